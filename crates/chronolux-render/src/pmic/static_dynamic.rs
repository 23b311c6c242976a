//! `ic-static-dynamic`: photon mapping with an irradiance cache split into a **static**
//! part, computed once per segment of frames without the objects that move, and a
//! **dynamic** part per frame (Tawara, Myszkowski, Seidel, VMV 2002 and TPCG 2004;
//! summarised in Tawara et al., SCCG 2004, §3–3.1).
//!
//! ## Method
//! The render list is cut into segments of `segment` frames (0: automatic, one second of
//! animation, `round(fps)` frames). For a segment:
//! - the **dynamic instances** are those that move or deform anywhere in the segment
//!   ([`FrameDelta::over`]); the **static scene** `S` is the
//!   segment's first frame with them emptied
//!   ([`FrameScene::without_instances`]: ids, lights and bounds kept, so photon `i` makes
//!   the same decisions in `S` and in every frame until it meets a dynamic object);
//! - the **static photons** (the global stream's photons `0..N`) are traced once in `S`
//!   and kept per photon index; they make the **static map**, and the **static cache**
//!   is made from gathers in `S` reading the static map. It is reused by every frame of
//!   the segment, extended only where a frame's cache points are not covered yet (a
//!   moving camera uncovering new surfaces; records are still gathered in `S`).
//!
//! Per frame `F` of the segment:
//! - the same photons `0..N` are traced in `F`; a photon whose hits in `F` differ from its
//!   hits in `S` is **dynamic**: its hits in `F` enter the **dynamic map** with their flux
//!   and its hits in `S` with negated flux (**negative photons**: light a dynamic object
//!   now takes away, e.g. indirect shadows); the common prefix of the two paths (hits
//!   before the photon met a dynamic object) cancels exactly ([`cancel_twins`]). So the
//!   static map plus the dynamic map hold exactly the photons `pm-ic` (with
//!   `fixed_photons`) uses in `F`.
//! - **influence** at a cache point x: `m(x) = |E_D(x)| / E_S(x)`, luminance of the
//!   dynamic map's irradiance (all its photons) over the static map's; `m = ∞` on a
//!   dynamic instance. The **blend weight** `β = smoothstep(influence_low,
//!   influence_high, m)`.
//! - the **dynamic cache** (per frame, records gathered in `F` reading static + dynamic
//!   maps) gets records at the cache points with `β > 0`.
//! - indirect irradiance at an eye vertex:
//!   `E = (1 − β)(E_static cache + E_D,ind) + β E_dynamic cache`, where `E_D,ind` is the
//!   dynamic map's density estimate of its photons that the gather would have seen (at
//!   least one non-delta bounce: not direct, not caustic). The blend is continuous in `m`,
//!   so there is no seam where the dynamic cache starts.
//! - the caustic map is traced per frame in `F` from the caustic stream's photons `0..N`
//!   (the same photons every frame, so static caustics do not flicker).
//!
//! **Lights and materials**: if any light differs between frames of the segment (a moving
//! or changing light, or the scene bounds change while a directional or environment light
//! depends on them; [`FrameDelta::lights_changed`]) or a material changes, every photon of
//! the segment is dynamic: the static scene has no photons, and
//! the dynamic cache serves every point (`β = 1`) — frame by frame within that segment.
//! This is coarser than the papers' per-light split (only the moving light's photons
//! dynamic), because the kernel chooses a photon's light from its own Halton dimension.
//!
//! ## Bias
//! Where `β = 1` this is `pm-ic`'s estimator on the same photons (same bias, see
//! [`super`]). Where `β = 0` the static cache's interpolation bias (same bound) is
//! joined by the density-estimation bias of `E_D,ind` (the kernel blur at the maps'
//! radius, applied to the *change* of irradiance only, instead of a final gather over
//! it) — small where the change is small relative to the static irradiance, which is
//! exactly where `β = 0` (`m < influence_low`): at most `influence_low` of `E` is so
//! estimated. In between, a convex combination of the two.
//!
//! ## Deviations
//! - The papers detect dynamic photons by marking the photon paths that hit dynamic
//!   objects; here a photon is dynamic when its hits differ, which also catches paths
//!   that only pass through where an object now is (the negative photons) without a
//!   separate shadow-photon pass.

use super::cache::IrradianceCache;
use super::photon_map::{PhotonMap, StoredPhoton, cancel_twins};
use super::view::{CacheQuery, EyeView, IndirectSource, NoIndirect};
use super::{
    PmIcSettings, base_cell, caustic_photons, extend_cache, gather_at, point_key, probe_points,
    world_radius,
};
use crate::integrator::{RenderedFrame, render_camera_rays};
use crate::kernels::photon::trace_photons;
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::sampling::hash_words;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Settings of `ic-static-dynamic`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IcStaticDynamicSettings {
    /// The photon mapping and cache settings (as `pm-ic`; `fixed_photons` is implied).
    pub pmic: PmIcSettings,
    /// Frames per segment; 0: one second of animation (`round(fps)` frames). Default 0.
    pub segment: u32,
    /// Influence `m` below which the static cache alone (corrected) is used. Default 0.05.
    pub influence_low: f32,
    /// Influence above which the dynamic cache alone is used. Default 0.25.
    pub influence_high: f32,
}

impl Default for IcStaticDynamicSettings {
    fn default() -> Self {
        IcStaticDynamicSettings {
            pmic: PmIcSettings {
                fixed_photons: true,
                ..Default::default()
            },
            segment: 0,
            influence_low: 0.05,
            influence_high: 0.25,
        }
    }
}

/// A photon of the global stream with what the maps need to know of it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Tagged {
    index: u64,
    photon: StoredPhoton,
    /// At least one non-delta bounce before this hit (what a gather sees).
    gathered: bool,
}

fn trace_tagged(scene: &FrameScene, n: u64, seed: u64) -> Vec<Tagged> {
    trace_photons(scene, 0..n, seed, |h| {
        Some(Tagged {
            index: h.index,
            photon: StoredPhoton::from_hit(h, n),
            gathered: h.bounces > 0 && !h.caustic,
        })
    })
    .0
}

/// Hits grouped by photon index: `start[i]..start[i + 1]` (indices `0..n`).
fn offsets(hits: &[Tagged], n: u64) -> Vec<usize> {
    let mut start = vec![0usize; n as usize + 1];
    for h in hits {
        start[h.index as usize + 1] += 1;
    }
    for i in 0..n as usize {
        start[i + 1] += start[i];
    }
    start
}

/// Everything computed once for a segment.
struct Segment {
    /// Index range in the render list.
    first: usize,
    end: usize,
    dynamic: Vec<bool>,
    lights_static: bool,
    scene: FrameScene,
    hits: Vec<Tagged>,
    start: Vec<usize>,
    map: PhotonMap,
    cache: IrradianceCache,
    dynamic_count: usize,
}

/// The technique.
pub struct IcStaticDynamic {
    pub settings: IcStaticDynamicSettings,
    pub name: &'static str,
    segment: Option<Segment>,
}

impl IcStaticDynamic {
    pub fn new(settings: IcStaticDynamicSettings, name: &'static str) -> Self {
        IcStaticDynamic {
            settings,
            name,
            segment: None,
        }
    }

    fn segment_len(&self, source: &FrameSource) -> usize {
        if self.settings.segment > 0 {
            self.settings.segment as usize
        } else {
            (source.fps().round() as usize).max(1)
        }
    }

    fn make_segment(&self, source: &mut FrameSource, first: usize, end: usize) -> Segment {
        let s = &self.settings.pmic;
        let list: Vec<u32> = source.frames()[first..end].to_vec();
        let frames: Vec<Arc<FrameScene>> = list.iter().map(|&f| source.frame(f)).collect();
        let refs: Vec<&FrameScene> = frames.iter().map(|f| &**f).collect();
        let delta = FrameDelta::over(&refs);
        let dynamic = delta.dynamic_instances();
        let lights_static = !delta.lights_changed() && !delta.materials_changed();
        let scene = frames[0].without_instances(&dynamic);
        let hits = if lights_static {
            trace_tagged(&scene, s.photons, s.seed)
        } else {
            Vec::new()
        };
        let start = offsets(&hits, s.photons);
        let map = PhotonMap::build(hits.iter().map(|t| t.photon).collect());
        Segment {
            first,
            end,
            dynamic_count: dynamic.iter().filter(|d| **d).count(),
            dynamic,
            lights_static,
            cache: IrradianceCache::new(s.cache.accuracy, base_cell(&scene)),
            scene,
            hits,
            start,
            map,
        }
    }

    /// Renders frame `frame` (scenes from `source`).
    pub fn render(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let t0 = std::time::Instant::now();
        let idx = source
            .frames()
            .iter()
            .position(|&f| f == frame)
            .unwrap_or(0);
        let len = self.segment_len(source);
        let first = idx / len * len;
        let end = (first + len).min(source.frames().len().max(first + 1));
        let mut new_segment = false;
        if self
            .segment
            .as_ref()
            .is_none_or(|g| g.first != first || g.end != end)
        {
            self.segment = Some(self.make_segment(source, first, end));
            new_segment = true;
        }
        let t_segment = t0.elapsed().as_secs_f64();
        let scene = source.frame(frame);
        let scene = &*scene;
        let s = self.settings.pmic.clone();
        let (low, high) = (self.settings.influence_low, self.settings.influence_high);
        let seg = self.segment.as_mut().expect("segment made");

        // Dynamic photons: those whose hits differ from the static ones.
        let frame_hits = trace_tagged(scene, s.photons, s.seed);
        let fstart = offsets(&frame_hits, s.photons);
        let mut dyn_photons = Vec::new();
        let mut dyn_gathered = Vec::new();
        let mut dynamic_paths = 0u64;
        for i in 0..s.photons as usize {
            let a = &frame_hits[fstart[i]..fstart[i + 1]];
            let b = if seg.lights_static {
                &seg.hits[seg.start[i]..seg.start[i + 1]]
            } else {
                &[][..]
            };
            if a == b {
                continue;
            }
            dynamic_paths += 1;
            for t in a {
                dyn_photons.push(t.photon);
                if t.gathered {
                    dyn_gathered.push(t.photon);
                }
            }
            for t in b {
                dyn_photons.push(t.photon.negated());
                if t.gathered {
                    dyn_gathered.push(t.photon.negated());
                }
            }
        }
        let dyn_photons = cancel_twins(dyn_photons);
        let negative = dyn_photons
            .iter()
            .filter(|p| p.flux.x < 0.0 || p.flux.y < 0.0 || p.flux.z < 0.0)
            .count();
        let dyn_map = PhotonMap::build(dyn_photons);
        let dyn_gathered = PhotonMap::build(cancel_twins(dyn_gathered));
        let (caustic, caustic_rays) = caustic_photons(scene, 0..s.photons, s.seed, s.photons);
        let caustic = PhotonMap::build(caustic);
        let t_photons = t0.elapsed().as_secs_f64() - t_segment;

        // Cache points of this frame, their blend weights, and the caches.
        let key = hash_words(&[s.seed, 0, 0x6963]);
        let probe_src = NoIndirect;
        let probe_view = EyeView::new(&s, scene, &caustic, &probe_src);
        let points = probe_points(&probe_view, scene, key);
        let blend = Blend {
            settings: &s,
            static_map: &seg.map,
            dynamic_map: &dyn_map,
            dynamic_instances: &seg.dynamic,
            all_dynamic: !seg.lights_static,
            low,
            high,
        };
        // β of every cache point, once, in parallel (the record passes only read it).
        let betas: Vec<f32> = chronolux_core::parallel::map_chunks(points.len(), 256, |r| {
            points[r]
                .iter()
                .map(|(_, q)| blend.beta(scene, q))
                .collect::<Vec<_>>()
        })
        .concat();
        let static_before = seg.cache.len();
        let static_scene = &seg.scene;
        let static_map = &seg.map;
        extend_cache(
            &mut seg.cache,
            &points,
            &s.cache,
            |i| betas[i] < 1.0,
            |q, k| gather_at(static_scene, &s, &[static_map], q.p, q.n, k),
        );
        let static_added = seg.cache.len() - static_before;
        let mut dyn_cache = IrradianceCache::new(s.cache.accuracy, base_cell(scene));
        let dyn_records = extend_cache(
            &mut dyn_cache,
            &points,
            &s.cache,
            |i| betas[i] > 0.0,
            |q, k| gather_at(scene, &s, &[static_map, &dyn_map], q.p, q.n, k),
        );
        let blended_points = betas.iter().filter(|b| **b > 0.0).count();
        let t_cache = t0.elapsed().as_secs_f64() - t_segment - t_photons;

        let src = StaticDynamicSource {
            blend: &blend,
            static_scene,
            static_cache: &seg.cache,
            dynamic_cache: &dyn_cache,
            dyn_gathered: &dyn_gathered,
            unstored: AtomicU64::new(0),
        };
        let eye = EyeView::new(&s, scene, &caustic, &src);
        let mut out = render_camera_rays(&eye, scene, frame, s.spp, s.seed, progress);
        out.stats.rays += caustic_rays;
        let r = &mut out.report;
        r.insert("photons".into(), s.photons.into());
        r.insert("new_segment".into(), new_segment.into());
        r.insert("dynamic_instances".into(), seg.dynamic_count.into());
        r.insert("lights_static".into(), seg.lights_static.into());
        r.insert("dynamic_photon_paths".into(), dynamic_paths.into());
        r.insert("dynamic_map_photons".into(), dyn_map.len().into());
        r.insert("negative_photons".into(), negative.into());
        r.insert("static_records".into(), seg.cache.len().into());
        r.insert("static_records_added".into(), static_added.into());
        r.insert("dynamic_records".into(), dyn_records.into());
        r.insert(
            "blended_point_fraction".into(),
            (blended_points as f64 / points.len().max(1) as f64).into(),
        );
        r.insert("unstored_gathers".into(), src.unstored.into_inner().into());
        r.insert("seconds_segment".into(), t_segment.into());
        r.insert("seconds_photons".into(), t_photons.into());
        r.insert("seconds_cache".into(), t_cache.into());
        out
    }
}

/// The blend between the corrected static cache and the dynamic cache.
struct Blend<'a> {
    settings: &'a PmIcSettings,
    static_map: &'a PhotonMap,
    dynamic_map: &'a PhotonMap,
    dynamic_instances: &'a [bool],
    all_dynamic: bool,
    low: f32,
    high: f32,
}

impl Blend<'_> {
    /// β ∈ [0, 1] at a cache point (see the module doc).
    fn beta(&self, scene: &FrameScene, q: &CacheQuery) -> f32 {
        if self.all_dynamic
            || self
                .dynamic_instances
                .get(q.instance as usize)
                .copied()
                .unwrap_or(true)
        {
            return 1.0;
        }
        if self.dynamic_map.is_empty() {
            return 0.0;
        }
        let r = world_radius(scene, &self.settings.global);
        let d = luminance(
            self.dynamic_map
                .irradiance(q.p, q.n, &self.settings.global, r),
        )
        .abs();
        if d == 0.0 {
            return 0.0;
        }
        let st = luminance(
            self.static_map
                .irradiance(q.p, q.n, &self.settings.global, r),
        );
        let m = if st > 0.0 { d / st } else { f32::INFINITY };
        smoothstep(self.low, self.high, m)
    }
}

/// 0 below `a`, 1 above `b`, C¹ in between.
pub fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    if x <= a {
        return 0.0;
    }
    if x >= b || b <= a {
        return 1.0;
    }
    let t = (x - a) / (b - a);
    t * t * (3.0 - 2.0 * t)
}

struct StaticDynamicSource<'a> {
    blend: &'a Blend<'a>,
    static_scene: &'a FrameScene,
    static_cache: &'a IrradianceCache,
    dynamic_cache: &'a IrradianceCache,
    dyn_gathered: &'a PhotonMap,
    unstored: AtomicU64,
}

impl StaticDynamicSource<'_> {
    fn cached(
        &self,
        cache: &IrradianceCache,
        scene: &FrameScene,
        maps: &[&PhotonMap],
        q: &CacheQuery,
    ) -> Rgb {
        if let Some((e, _)) = cache.interpolate(q.p, q.n) {
            return e;
        }
        self.unstored.fetch_add(1, Ordering::Relaxed);
        gather_at(
            scene,
            self.blend.settings,
            maps,
            q.p,
            q.n,
            point_key(q.p, q.n),
        )
        .e
    }
}

impl IndirectSource for StaticDynamicSource<'_> {
    fn irradiance(&self, scene: &FrameScene, q: &CacheQuery) -> Rgb {
        let b = self.blend;
        let beta = b.beta(scene, q);
        let mut e = Rgb::ZERO;
        if beta < 1.0 {
            let mut st = self.cached(self.static_cache, self.static_scene, &[b.static_map], q);
            if !self.dyn_gathered.is_empty() {
                let r = world_radius(scene, &b.settings.global);
                st += self
                    .dyn_gathered
                    .irradiance(q.p, q.n, &b.settings.global, r);
            }
            e = st.max(Rgb::ZERO);
            if beta == 0.0 {
                return e;
            }
            e *= 1.0 - beta;
        }
        let dy = self.cached(self.dynamic_cache, scene, &[b.static_map, b.dynamic_map], q);
        e + dy * beta
    }
}

impl crate::sequence::SequenceRenderer for IcStaticDynamic {
    fn name(&self) -> &'static str {
        self.name
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        self.render(source, frame, progress)
    }
}

/// Registry entry of `ic-static-dynamic`.
pub static TECHNIQUE: crate::registry::Preset<IcStaticDynamicSettings> = crate::registry::Preset {
    name: "ic-static-dynamic",
    summary: "photon mapping with a static irradiance cache per segment of frames (dynamic objects removed) and per-frame dynamic photons (negative ones included) and a dynamic cache where they matter, blended",
    capabilities: crate::registry::Capabilities {
        motion_blur: false,
        photons: false,
        window: false,
        stateless: false,
        effort: crate::registry::Effort {
            key: "photons",
            per_unit: 1000,
            unit: "thousand photons per map",
        },
    },
    defaults: IcStaticDynamicSettings::default,
    build: |s, _, name| Box::new(IcStaticDynamic::new(s, name)),
};
