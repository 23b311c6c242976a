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
//! - the **static photons** (the global stream's photons `0..N`, and the caustic
//!   stream's) are traced once in `S` and kept per photon index with their paths'
//!   points; they make the **static map**, and the **static cache** is made from gathers
//!   in `S` reading the static map at the cache points not on a dynamic object. It is
//!   reused by every frame of the segment, extended only where a frame's cache points
//!   are not covered yet (a moving camera uncovering new surfaces, or surfaces a dynamic
//!   object hid; records are still gathered in `S`).
//! - the **candidates**: the photons whose static paths cross the bounds of a dynamic
//!   object in some frame of the segment (its sweep); no other photon can change.
//!
//! Per frame `F` of the segment:
//! - the candidates whose static paths cross a dynamic object's bounds *in `F`* are
//!   re-traced in `F` ([`retrace_set`]; every other photon's path in `F` is its static
//!   path, see there — a test re-traces all photons to check it). A re-traced photon
//!   whose hits in `F` differ from its hits in `S` is **dynamic**: its hits in `F` enter
//!   the **dynamic map** with their flux and its hits in `S` with negated flux
//!   (**negative photons**: light a dynamic object now takes away, e.g. indirect
//!   shadows); the common prefix of the two paths (hits before the photon met a dynamic
//!   object) cancels exactly ([`cancel_twins`]). So the static map plus the dynamic map
//!   hold exactly the photons `pm-ic` (with `fixed_photons`) uses in `F`.
//! - **influence** at a static record x: `m(x) = max(|E_D(x)| − z σ_D(x), 0) / E_S(x)`,
//!   luminance of the dynamic map's irradiance (all its photons, signed) less `z`
//!   (`influence_sigmas`, default 2) times an upper bound of its standard deviation
//!   ([`PhotonMap::irradiance_with_noise`]), over the static map's: the change of the
//!   local lighting by the dynamic objects where it stands out of the dynamic map's
//!   noise (a k-NN estimate from a few thousand signed photons is noisy, and without
//!   the allowance that noise alone made a third of the image "dynamic"). The **blend
//!   weight** of the record is `β = smoothstep(influence_low, influence_high, m)`, once
//!   per record and frame, and it is interpolated to any point with the record weights
//!   of the static cache (continuous like the cache itself); `β = 1` on a dynamic
//!   instance and where no static record is valid.
//! - the **dynamic cache** (per frame, records gathered in `F` reading the frame's global
//!   map — the static photons with the re-traced ones replaced by their paths in `F`,
//!   i.e. `pm-ic`'s map, with one lookup per gather ray) gets records at the cache
//!   points with `β > 0`.
//! - indirect irradiance at an eye vertex:
//!   `E = (1 − β)(E_static cache + E_D,ind) + β E_dynamic cache`, where `E_D,ind` is the
//!   dynamic map's density estimate of its photons that the gather would have seen (at
//!   least one non-delta bounce: not direct, not caustic), evaluated at the static
//!   records and interpolated with them. β and `E_D,ind` are interpolated with the
//!   weights `1/ε − 1/a`, which vanish where a record stops being valid, so they are
//!   continuous (Ward's `1/ε` jumps to `1/a` there); the blend is then continuous, so
//!   there is no seam where the dynamic cache starts (test on line profiles).
//! - the caustic map is the static caustic photons with the re-traced ones replaced by
//!   their paths in `F` (the same photons every frame, so static caustics do not
//!   flicker).
//!
//! **Lights and materials**: if any light differs between frames of the segment (a moving
//! or changing light, or the scene bounds change while a directional or environment light
//! depends on them; [`FrameDelta::lights_changed`]) or a material changes, every photon of
//! the segment is dynamic: the static scene has no photons, and
//! the dynamic cache serves every point (`β = 1`) — frame by frame within that segment.
//! This is coarser than the papers' per-light split (only the moving light's photons
//! dynamic), because the kernel chooses a photon's light from its own Halton dimension.
//!
//! ### The correction (issue 41)
//! `E_D,ind` is the change of a static record's indirect irradiance between `S` and the
//! frame. With `correction_m = 0` (the default until issue 41) it is the density estimate at the record of the
//! dynamic photons a gather would see: cheap (one lookup), but it is a raw density
//! estimate of a few thousand signed photons, noisy and blurred over the map's radius,
//! and at 256² its blotches span pixels where FLIP sees them (BENCHMARKS.md, "Which
//! holds": with β forced to 1 the whole FLIP gap to `pm-ic` disappears). With
//! `correction_m = m > 0` it is instead a **final gather of the change**: `m × 3m`
//! strata at the record, each ray traced in the frame through specular chains as
//! `pm-ic`'s gather rays are; where the chain meets only static instances its hit is the
//! same point in `S` (static instances do not move within a segment, and `S` has no other
//! geometry), so the stratum's change is the **dynamic map's** radiance there (the frame
//! map is the static map with the dynamic photons added and their static twins
//! subtracted); where it meets a dynamic instance, the change is the frame map's radiance
//! at the chain's end in the frame less the static map's at its end in `S` (one more ray
//! and two full lookups, on the few strata that see the moving object). The dynamic map
//! is small, so most lookups find no photon within the radius and end early: a record's
//! correction costs a fraction of a gather. Its jitter is hashed from the record's point,
//! so the same directions are used in every frame of the segment (coherent in time).
//! Measured (BENCHMARKS.md, issue 12, "The gathered correction"): at 256² over 8 frames,
//! 25k photons, FLIP 0.1106 → 0.0851 (`pm-ic` 0.0820 with 25k): `pm-ic`'s FLIP needs
//! ≈ 30k photons instead of ≈ 90k, and the photon gap to `pm-ic` is gone; at 64² (the
//! blur within a pixel) the density estimate was ≈ 7 % cheaper at equal FLIP, which is
//! why both stay.
//!
//! ### The gather estimator
//! With `pmic.precompute_stride = N > 0` the gather rays that read the static or the
//! frame's map (the static cache's, the dynamic cache's, the unstored ones and the
//! correction's strata that meet the moving object) read Christensen's precomputed
//! irradiance of that map instead of a k-NN radiance estimate
//! ([`crate::kernels::gather::precomputed::PrecomputedMap`], one nearest-neighbour read):
//! the static map's points are estimated once per segment, the frame map's once per frame
//! (a few thousand k-NN estimates, against one per gather ray). The correction's reads of
//! the **dynamic** map stay k-NN: that map is sparse, and the nearest precomputed point
//! hands a photon's density to any hit up to the lookup radius away, so the correction
//! spread into blotches (measured at 64², cornell-moving, 24k photons: FLIP 0.0998 and
//! 8.2 CPU s with it precomputed, 0.0844 and 4.6 s with k-NN, where most lookups find no
//! photon and end early). The influence test and the density correction
//! (`correction_m = 0`) stay k-NN estimates at the records.
//!
//! It is the default (`precompute_stride = 4`), as `pm-ic`'s (which keeps one map per
//! light group; here one per map). Measured (BENCHMARKS.md, issue 12, "Whole windows at
//! 256²"; cornell-moving, whole animation, 256²): 25k photons give FLIP 0.0785 for 11.2 CPU
//! s per 12 frames against the k-NN estimate's 0.0839 for 22 s, and 1.09–1.42× less CPU
//! than `pm-ic` with its precomputed estimator at equal FLIP (1.36–2.17× at 64² over one
//! segment; with the k-NN estimate against it: 0.48–0.49× at 256²).
//!
//! ## Bias
//! Where `β = 1` this is `pm-ic`'s estimator on the same photons (same bias, see
//! [`super`]). Where `β = 0` the static cache's interpolation bias (same bound) is
//! joined by the density-estimation bias of `E_D,ind` (the kernel blur at the maps'
//! radius, applied to the *change* of irradiance only, instead of a final gather over
//! it) — small where the change is small relative to the static irradiance, which is
//! exactly where `β = 0` (`m < influence_low`, i.e. `|E_D| < influence_low·E_S + z σ_D`):
//! at most `influence_low` of `E`, plus a change within the dynamic map's own noise, is
//! so estimated. In between, a convex combination of the two. Interpolating β and
//! `E_D,ind` from the records adds the cache's interpolation error to them (first order
//! over `aR`, as for `E`).
//!
//! ## Deviations
//! - The papers detect dynamic photons by marking the photon paths that hit dynamic
//!   objects; here a photon is dynamic when its hits differ, which also catches paths
//!   that only pass through where an object now is (the negative photons) without a
//!   separate shadow-photon pass.

use crate::framework::integrator::{RenderedFrame, render_camera_rays};
use crate::kernels::gather::irradiance_cache::IrradianceCache;
use crate::kernels::gather::irradiance_cache::stratum_direction;
use crate::kernels::gather::photon_map::{PhotonMap, StoredPhoton, cancel_twins};
use crate::kernels::gather::precomputed::PrecomputedMap;
use crate::kernels::gather::view::{CacheQuery, EyeView, IndirectSource, NoIndirect};
use crate::kernels::gather::{
    PmIcSettings, RadianceMap, base_cell, caustic_seed, extend_cache, gather_at, gather_ray_hit,
    gather_ray_visiting, point_key, probe_points, world_radius,
};
use crate::kernels::photon::segment_hits_box;
use crate::kernels::photon::{PhotonHit, trace_photon_path};
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::geometry::Bounds3;
use chronolux_core::math::{Frame, Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::hash_words;
use chronolux_core::sampling::rng::Pcg32;
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
    /// Noise allowance of the influence, in standard deviations of the dynamic map's
    /// estimate (`m = max(|E_D| − z σ_D, 0) / E_S`). Default 2.
    pub influence_sigmas: f32,
    /// Where no record of a cache is valid at an eye sample (sub-pixel jitter past the
    /// probe points, at edges), use its records valid under the accuracy
    /// `fallback_accuracy · a` instead of a gather that is not stored; 0: gather, as
    /// `pm-ic`. Default 2.
    pub fallback_accuracy: f32,
    /// How the change `E_D,ind` of a static record's indirect irradiance is estimated:
    /// 0, the dynamic map's density estimate at the record (blurred over the map's
    /// radius); `m > 0`, a final gather of `m × 3m` strata in the frame reading the
    /// dynamic map (see "The correction" in the module doc). Default 6 (108 strata).
    pub correction_m: u32,
}

impl Default for IcStaticDynamicSettings {
    fn default() -> Self {
        IcStaticDynamicSettings {
            pmic: PmIcSettings {
                fixed_photons: true,
                // The precomputed estimator, as `pm-ic`'s default (module doc, "The
                // gather estimator").
                precompute_stride: 4,
                ..Default::default()
            },
            segment: 0,
            influence_low: 0.05,
            influence_high: 0.25,
            influence_sigmas: 2.0,
            fallback_accuracy: 2.0,
            correction_m: 6,
        }
    }
}

/// A photon of the global stream with what the maps need to know of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tagged {
    pub index: u64,
    pub photon: StoredPhoton,
    /// At least one non-delta bounce before this hit (what a gather sees).
    pub gathered: bool,
}

/// Which deposited hits a stream keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Keep {
    /// Every diffuse-class hit (the global map).
    All,
    /// Caustic hits only (the caustic map).
    Caustic,
}

/// One photon's path: the hits it keeps, the points of its segments (emission point, then
/// every vertex, delta ones included) and the direction it left the scene in (zero if it
/// ended at a vertex).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Path {
    pub hits: Vec<Tagged>,
    pub points: Vec<Vec3>,
    pub escape: Vec3,
}

/// Traces photon `i` of the stream `seed` (`emitted` photons in the map).
pub fn trace_path(scene: &FrameScene, i: u64, seed: u64, emitted: u64, keep: Keep) -> Path {
    let mut path = Path::default();
    let mut escape = Vec3::ZERO;
    let mut origin = None;
    let mut points = Vec::new();
    let mut hits = Vec::new();
    trace_photon_path(
        scene,
        i,
        seed,
        |_, ray| origin = Some(ray.o),
        |v| {
            points.push(v.hit.p);
            let h: &PhotonHit = &v.hit;
            if v.deposited && (keep == Keep::All || h.caustic) {
                hits.push(Tagged {
                    index: h.index,
                    photon: StoredPhoton::from_hit(h, emitted),
                    gathered: h.bounces > 0 && !h.caustic,
                });
            }
        },
        |ray| escape = ray.d,
    );
    path.hits = hits;
    if let Some(o) = origin {
        points.insert(0, o);
    }
    path.points = points;
    path.escape = escape;
    path
}

/// Some segment of the path (emission point → vertices → escape ray) passes through one
/// of `boxes` (conservative).
pub fn path_crosses(points: &[Vec3], escape: Vec3, boxes: &[Bounds3]) -> bool {
    if points.is_empty() || boxes.is_empty() {
        return false;
    }
    for w in points.windows(2) {
        if boxes
            .iter()
            .any(|b| segment_hits_box(w[0], w[1] - w[0], 1.0, b))
        {
            return true;
        }
    }
    let last = points[points.len() - 1];
    escape != Vec3::ZERO
        && boxes
            .iter()
            .any(|b| segment_hits_box(last, escape, f32::INFINITY, b))
}

/// A photon stream traced once in the static scene: hits and path points per photon
/// (flat, `*_start[i]..*_start[i + 1]`).
pub struct Stream {
    pub hits: Vec<Tagged>,
    hit_start: Vec<usize>,
    points: Vec<Vec3>,
    point_start: Vec<usize>,
    escape: Vec<Vec3>,
}

/// Photons per parallel chunk.
const CHUNK: usize = 1024;

impl Stream {
    /// Traces photons `0..n` of stream `seed` in `scene`.
    pub fn trace(scene: &FrameScene, n: u64, seed: u64, keep: Keep) -> Stream {
        let chunks = parallel::map_chunks((n as usize).div_ceil(CHUNK), 1, |r| {
            let lo = r.start * CHUNK;
            let hi = (lo + CHUNK).min(n as usize);
            (lo..hi)
                .map(|i| trace_path(scene, i as u64, seed, n, keep))
                .collect::<Vec<_>>()
        });
        let mut st = Stream {
            hits: Vec::new(),
            hit_start: vec![0],
            points: Vec::new(),
            point_start: vec![0],
            escape: Vec::with_capacity(n as usize),
        };
        for p in chunks.into_iter().flatten() {
            st.hits.extend_from_slice(&p.hits);
            st.hit_start.push(st.hits.len());
            st.points.extend_from_slice(&p.points);
            st.point_start.push(st.points.len());
            st.escape.push(p.escape);
        }
        st
    }

    /// An empty stream of `n` photons (nothing traced).
    fn empty(n: u64) -> Stream {
        Stream {
            hits: Vec::new(),
            hit_start: vec![0; n as usize + 1],
            points: Vec::new(),
            point_start: vec![0; n as usize + 1],
            escape: vec![Vec3::ZERO; n as usize],
        }
    }

    pub fn hits_of(&self, i: usize) -> &[Tagged] {
        &self.hits[self.hit_start[i]..self.hit_start[i + 1]]
    }

    /// Photon `i`'s static path crosses one of `boxes`.
    pub fn crosses(&self, i: usize, boxes: &[Bounds3]) -> bool {
        path_crosses(
            &self.points[self.point_start[i]..self.point_start[i + 1]],
            self.escape[i],
            boxes,
        )
    }

    /// The photons (of `among`) whose static paths cross one of `boxes`.
    pub fn crossing(&self, among: &[u32], boxes: &[Bounds3]) -> Vec<u32> {
        parallel::map_chunks(among.len(), 4096, |r| {
            among[r]
                .iter()
                .copied()
                .filter(|&i| self.crosses(i as usize, boxes))
                .collect::<Vec<_>>()
        })
        .concat()
    }
}

/// Traces the photons `indices` of stream `seed` (in parallel, results in that order).
fn trace_list(
    scene: &FrameScene,
    indices: &[u32],
    seed: u64,
    emitted: u64,
    keep: Keep,
) -> Vec<Path> {
    parallel::map_chunks(indices.len(), 256, |r| {
        indices[r]
            .iter()
            .map(|&i| trace_path(scene, i as u64, seed, emitted, keep))
            .collect::<Vec<_>>()
    })
    .concat()
}

/// World bounds of the instances `dynamic` marks, in `scene` (slightly padded).
pub fn dynamic_bounds(scene: &FrameScene, dynamic: &[bool]) -> Vec<Bounds3> {
    scene.instance_world_bounds(dynamic.len(), |i| dynamic[i])
}

/// The photons of a frame that must be re-traced: those (of the segment's candidates)
/// whose static path crosses a dynamic object's bounds in `scene`. Every other photon's
/// path in `scene` is its static path: the scenes differ only by the dynamic instances
/// (lights, materials and bounds are those of the static scene), the path's light and
/// emission are the same, and at every vertex the closest hit along the segment is the
/// static one because no dynamic triangle lies on the segment (an escaping ray meets
/// none either); the vertices then make the same decisions from the same Halton
/// dimensions, by induction along the path.
pub fn retrace_set(stream: &Stream, candidates: &[u32], boxes: &[Bounds3]) -> Vec<u32> {
    stream.crossing(candidates, boxes)
}

/// Everything computed once for a segment.
struct Segment {
    /// Index range in the render list.
    first: usize,
    end: usize,
    dynamic: Vec<bool>,
    lights_static: bool,
    scene: FrameScene,
    global: Stream,
    caustic: Stream,
    /// Photons whose static paths cross a dynamic object's bounds in some frame of the
    /// segment (only these can change).
    global_candidates: Vec<u32>,
    caustic_candidates: Vec<u32>,
    map: PhotonMap,
    /// The static map's precomputed irradiance (`pmic.precompute_stride > 0`).
    map_pre: Option<PrecomputedMap>,
    cache: IrradianceCache,
    /// The static records again, valid under the fallback accuracy (same order).
    loose: Option<IrradianceCache>,
    dynamic_count: usize,
}

/// A frame's photons ([`IcStaticDynamic`]'s step 2): the static paths a dynamic object
/// can change re-traced in this frame, the dynamic maps (their new hits and the negated
/// static ones), the caustic map and the frame's global map.
struct FramePhotons {
    /// Photons re-traced (global and caustic), and of the global ones those whose hits
    /// changed.
    retraced: usize,
    dynamic_paths: u64,
    /// Photons of negative flux in the dynamic map.
    negative: usize,
    dyn_map: PhotonMap,
    /// The dynamic photons that a gather reads.
    dyn_gathered: PhotonMap,
    caustic: PhotonMap,
    /// The frame's global map (`None` when nothing changed: the static map is it).
    frame_map: Option<PhotonMap>,
    /// The frame's map's precomputed irradiance (`pmic.precompute_stride > 0`).
    frame_pre: Option<PrecomputedMap>,
    /// Rays traced: one per vertex, one per escape.
    photon_rays: u64,
}

/// The dynamic cache of a frame and the blend weights ([`IcStaticDynamic`]'s step 3).
struct DynamicPart {
    cache: IrradianceCache,
    loose: Option<IrradianceCache>,
    /// Records the dynamic cache gathered.
    records: u64,
    /// Cache points with β > 0.
    blended_points: usize,
    rec_beta: Vec<f32>,
    rec_corr: Vec<Rgb>,
}

/// The photons of frame `scene` in segment `seg` (see [`FramePhotons`]).
/// What the gathers of one map read: its precomputed irradiance `pre` when there is one
/// (`pmic.precompute_stride > 0`), else its k-NN estimate (the maps' other uses, the
/// influence and the density correction, stay k-NN estimates).
fn reader<'a>(knn: &'a PhotonMap, pre: Option<&'a PrecomputedMap>) -> &'a dyn RadianceMap {
    match pre {
        Some(p) => p,
        None => knn,
    }
}

/// What the gathers in a frame read: the frame's map (`None` when nothing changed: the
/// static map is it), as [`reader`] chooses.
fn frame_reader<'a>(
    seg: &'a Segment,
    frame_map: Option<&'a PhotonMap>,
    frame_pre: Option<&'a PrecomputedMap>,
) -> &'a dyn RadianceMap {
    match frame_map {
        Some(m) => reader(m, frame_pre),
        None => reader(&seg.map, seg.map_pre.as_ref()),
    }
}

/// `map`'s precomputed irradiance in `scene` when `s.precompute_stride > 0` (every that
/// many photons, from the global lookup's `k` nearest: [`PrecomputedMap::from_map`]).
fn precompute(scene: &FrameScene, s: &PmIcSettings, map: &PhotonMap) -> Option<PrecomputedMap> {
    (s.precompute_stride > 0).then(|| {
        PrecomputedMap::from_map(
            map,
            &s.global,
            world_radius(scene, &s.global),
            s.precompute_stride,
        )
    })
}

fn frame_photons(seg: &Segment, scene: &FrameScene, s: &PmIcSettings) -> FramePhotons {
    let n = s.photons;
    // Photons that can differ from their static paths, re-traced in this frame.
    let boxes = dynamic_bounds(scene, &seg.dynamic);
    let (g_idx, c_idx) = if seg.lights_static {
        (
            retrace_set(&seg.global, &seg.global_candidates, &boxes),
            retrace_set(&seg.caustic, &seg.caustic_candidates, &boxes),
        )
    } else {
        (
            seg.global_candidates.clone(),
            seg.caustic_candidates.clone(),
        )
    };
    let g_new = trace_list(scene, &g_idx, s.common.seed, n, Keep::All);
    let c_new = trace_list(scene, &c_idx, caustic_seed(s.common.seed), n, Keep::Caustic);
    // Rays traced: one per vertex, one per escape.
    let photon_rays = g_new
        .iter()
        .chain(&c_new)
        .map(|p| p.points.len().saturating_sub(1) as u64 + u64::from(p.escape != Vec3::ZERO))
        .sum::<u64>();

    // Dynamic photons: re-traced ones whose hits differ from the static ones.
    let mut dyn_photons = Vec::new();
    let mut dyn_gathered = Vec::new();
    let mut dynamic_paths = 0u64;
    for (&i, path) in g_idx.iter().zip(&g_new) {
        let a = &path.hits[..];
        let b = seg.global.hits_of(i as usize);
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
    // The caustic map in photon order: static hits, re-traced photons' new hits.
    let mut caustic = Vec::new();
    let mut next = 0;
    for i in 0..n as usize {
        if next < c_idx.len() && c_idx[next] as usize == i {
            caustic.extend(c_new[next].hits.iter().map(|t| t.photon));
            next += 1;
        } else {
            caustic.extend(seg.caustic.hits_of(i).iter().map(|t| t.photon));
        }
    }
    let caustic = PhotonMap::build(caustic);
    // The frame's global map, as `pm-ic` builds it: every photon's hits in `F` in
    // photon order (static hits for the photons not re-traced). The dynamic cache's
    // gathers read it (one lookup per gather ray instead of one in each of the
    // static and the dynamic map).
    let frame_map = if dyn_map.is_empty() {
        None
    } else {
        let mut all = Vec::with_capacity(seg.global.hits.len());
        let mut next = 0;
        for i in 0..n as usize {
            if next < g_idx.len() && g_idx[next] as usize == i {
                all.extend(g_new[next].hits.iter().map(|t| t.photon));
                next += 1;
            } else {
                all.extend(seg.global.hits_of(i).iter().map(|t| t.photon));
            }
        }
        Some(PhotonMap::build(all))
    };
    let pre = |m: &PhotonMap| precompute(scene, s, m);
    FramePhotons {
        retraced: g_idx.len() + c_idx.len(),
        dynamic_paths,
        negative,
        frame_pre: frame_map.as_ref().and_then(pre),
        dyn_map,
        dyn_gathered,
        caustic,
        frame_map,
        photon_rays,
    }
}

/// The per-frame state of `ic-static-dynamic` (see the module doc).
struct FrameState {
    scene: Arc<FrameScene>,
    dyn_map: PhotonMap,
    /// The frame's global map (`None`: no dynamic photons, it is the static map).
    frame_map: Option<PhotonMap>,
    frame_pre: Option<PrecomputedMap>,
    caustic: PhotonMap,
    dyn_cache: IrradianceCache,
    dyn_loose: Option<IrradianceCache>,
    /// β and the dynamic correction `E_D,ind` at every static record.
    rec_beta: Vec<f32>,
    rec_corr: Vec<Rgb>,
    report: serde_json::Map<String, serde_json::Value>,
    photon_rays: u64,
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
        let (global, caustic) = if lights_static {
            (
                Stream::trace(&scene, s.photons, s.common.seed, Keep::All),
                Stream::trace(
                    &scene,
                    s.photons,
                    caustic_seed(s.common.seed),
                    Keep::Caustic,
                ),
            )
        } else {
            (Stream::empty(s.photons), Stream::empty(s.photons))
        };
        // The dynamic objects' bounds in every frame of the segment (their sweep).
        let swept: Vec<Bounds3> = frames
            .iter()
            .flat_map(|f| dynamic_bounds(f, &dynamic))
            .collect();
        let all: Vec<u32> = (0..s.photons as u32).collect();
        let (global_candidates, caustic_candidates) = if lights_static {
            (
                global.crossing(&all, &swept),
                caustic.crossing(&all, &swept),
            )
        } else {
            (all.clone(), all)
        };
        let map = PhotonMap::build(global.hits.iter().map(|t| t.photon).collect());
        let map_pre = precompute(&scene, s, &map);
        Segment {
            map_pre,
            first,
            end,
            dynamic_count: dynamic.iter().filter(|d| **d).count(),
            dynamic,
            lights_static,
            cache: IrradianceCache::new(s.cache.accuracy, base_cell(&scene)),
            loose: (self.settings.fallback_accuracy > 0.0).then(|| {
                IrradianceCache::new(
                    s.cache.accuracy * self.settings.fallback_accuracy,
                    base_cell(&scene),
                )
            }),
            scene,
            global,
            caustic,
            global_candidates,
            caustic_candidates,
            map,
        }
    }

    /// Makes (or keeps) the segment of `frame` and computes the frame's photons, caches
    /// and blend weights: [`IcStaticDynamic::ensure_segment`], [`frame_photons`],
    /// [`IcStaticDynamic::extend_static_cache`], [`IcStaticDynamic::blend_and_dynamic_cache`].
    fn prepare(&mut self, source: &mut FrameSource, frame: u32) -> FrameState {
        let t0 = std::time::Instant::now();
        let new_segment = self.ensure_segment(source, frame);
        let t_segment = t0.elapsed().as_secs_f64();
        let scene_arc = source.frame(frame);
        let scene = &*scene_arc;
        let s = self.settings.pmic.clone();
        let seg = self.segment.as_ref().expect("segment made");
        let ph = frame_photons(seg, scene, &s);
        let t_photons = t0.elapsed().as_secs_f64() - t_segment;

        // Cache points of this frame; the static cache where it lacks records.
        let key = hash_words(&[s.common.seed, 0, 0x6963]);
        let probe_src = NoIndirect;
        let probe_view = EyeView::new(&s, scene, &ph.caustic, &probe_src);
        let points = probe_points(&probe_view, scene, key);
        let static_added = self.extend_static_cache(&s, &points);
        let dynamic = self.blend_and_dynamic_cache(&s, scene, &points, &ph);
        let t_cache = t0.elapsed().as_secs_f64() - t_segment - t_photons;

        let seg = self.segment.as_ref().expect("segment made");
        let mut r = serde_json::Map::new();
        r.insert("photons".into(), s.photons.into());
        r.insert("new_segment".into(), new_segment.into());
        r.insert("dynamic_instances".into(), seg.dynamic_count.into());
        r.insert("lights_static".into(), seg.lights_static.into());
        r.insert(
            "candidate_photons".into(),
            (seg.global_candidates.len() + seg.caustic_candidates.len()).into(),
        );
        r.insert("retraced_photons".into(), ph.retraced.into());
        r.insert("dynamic_photon_paths".into(), ph.dynamic_paths.into());
        r.insert("dynamic_map_photons".into(), ph.dyn_map.len().into());
        r.insert("negative_photons".into(), ph.negative.into());
        r.insert("static_records".into(), seg.cache.len().into());
        r.insert("static_records_added".into(), static_added.into());
        r.insert("dynamic_records".into(), dynamic.records.into());
        r.insert(
            "blended_point_fraction".into(),
            (dynamic.blended_points as f64 / points.len().max(1) as f64).into(),
        );
        r.insert("seconds_segment".into(), t_segment.into());
        r.insert("seconds_photons".into(), t_photons.into());
        r.insert("seconds_cache".into(), t_cache.into());
        FrameState {
            scene: scene_arc,
            dyn_map: ph.dyn_map,
            frame_map: ph.frame_map,
            frame_pre: ph.frame_pre,
            caustic: ph.caustic,
            dyn_cache: dynamic.cache,
            dyn_loose: dynamic.loose,
            rec_beta: dynamic.rec_beta,
            rec_corr: dynamic.rec_corr,
            report: r,
            photon_rays: ph.photon_rays,
        }
    }

    /// Makes the segment of `frame` unless the current one is it; true when made.
    fn ensure_segment(&mut self, source: &mut FrameSource, frame: u32) -> bool {
        let idx = source
            .frames()
            .iter()
            .position(|&f| f == frame)
            .unwrap_or(0);
        let len = self.segment_len(source);
        let first = idx / len * len;
        let end = (first + len).min(source.frames().len().max(first + 1));
        if self
            .segment
            .as_ref()
            .is_none_or(|g| g.first != first || g.end != end)
        {
            self.segment = Some(self.make_segment(source, first, end));
            return true;
        }
        false
    }

    /// Adds to the segment's static cache the records this frame's cache points on static
    /// objects lack (gathered in the static scene from the static map); returns how many.
    fn extend_static_cache(&mut self, s: &PmIcSettings, points: &[(u64, CacheQuery)]) -> usize {
        let seg = self.segment.as_mut().expect("segment made");
        let all_dynamic = !seg.lights_static;
        let static_before = seg.cache.len();
        {
            let (static_scene, static_map) = (&seg.scene, reader(&seg.map, seg.map_pre.as_ref()));
            let dynamic = &seg.dynamic;
            extend_cache(
                &mut seg.cache,
                points,
                &s.cache,
                |i| {
                    let q = &points[i].1;
                    !(all_dynamic || dynamic.get(q.instance as usize).copied().unwrap_or(true))
                },
                |q, k| gather_at(static_scene, s, &[static_map], q.p, q.n, k),
            );
        }
        if let Some(loose) = &mut seg.loose {
            for rec in &seg.cache.records()[static_before..] {
                loose.insert(*rec);
            }
        }
        seg.cache.len() - static_before
    }

    /// β and the correction at every static record (once), β at the cache points (1 on
    /// dynamic objects, else interpolated from the records), and the dynamic cache where
    /// β > 0, gathered in this frame.
    fn blend_and_dynamic_cache(
        &self,
        s: &PmIcSettings,
        scene: &FrameScene,
        points: &[(u64, CacheQuery)],
        ph: &FramePhotons,
    ) -> DynamicPart {
        let seg = self.segment.as_ref().expect("segment made");
        let all_dynamic = !seg.lights_static;
        let on_dynamic = |q: &CacheQuery| {
            all_dynamic
                || seg
                    .dynamic
                    .get(q.instance as usize)
                    .copied()
                    .unwrap_or(true)
        };

        // β and the correction at every static record, once.
        let blend = Blend {
            settings: s,
            static_map: &seg.map,
            dynamic_map: &ph.dyn_map,
            low: self.settings.influence_low,
            high: self.settings.influence_high,
            sigmas: self.settings.influence_sigmas,
        };
        let r_g = world_radius(scene, &s.global);
        let correction = Correction {
            settings: s,
            frame: scene,
            static_scene: &seg.scene,
            dynamic: &seg.dynamic,
            // The sparse signed dynamic map stays a k-NN estimate (module doc, "The gather
            // estimator").
            dyn_map: &ph.dyn_map,
            frame_map: frame_reader(seg, ph.frame_map.as_ref(), ph.frame_pre.as_ref()),
            static_map: reader(&seg.map, seg.map_pre.as_ref()),
        };
        let recs = seg.cache.records();
        let (rec_beta, rec_corr): (Vec<f32>, Vec<Rgb>) =
            parallel::map_chunks(recs.len(), 64, |r| {
                recs[r]
                    .iter()
                    .map(|rec| {
                        let corr = if ph.dyn_gathered.is_empty() && ph.dyn_map.is_empty() {
                            Rgb::ZERO
                        } else if self.settings.correction_m > 0 {
                            correction.gathered(rec.p, rec.n, self.settings.correction_m)
                        } else if ph.dyn_gathered.is_empty() {
                            Rgb::ZERO
                        } else {
                            ph.dyn_gathered.irradiance(rec.p, rec.n, &s.global, r_g)
                        };
                        (blend.beta(scene, rec.p, rec.n), corr)
                    })
                    .collect::<Vec<_>>()
            })
            .concat()
            .into_iter()
            .unzip();
        // β at the cache points: 1 on dynamic objects, else interpolated from the records.
        let point_beta: Vec<f32> = points
            .iter()
            .map(|(_, q)| {
                if on_dynamic(q) {
                    1.0
                } else {
                    interpolate_static(&seg.cache, &rec_beta, &rec_corr, q)
                        .or_else(|| {
                            interpolate_static(seg.loose.as_ref()?, &rec_beta, &rec_corr, q)
                        })
                        .map_or(1.0, |v| v.beta)
                }
            })
            .collect();
        let mut dyn_cache = IrradianceCache::new(s.cache.accuracy, base_cell(scene));
        let frame = frame_reader(seg, ph.frame_map.as_ref(), ph.frame_pre.as_ref());
        let dyn_records = extend_cache(
            &mut dyn_cache,
            points,
            &s.cache,
            |i| point_beta[i] > 0.0,
            |q, k| gather_at(scene, s, &[frame], q.p, q.n, k),
        );
        let dyn_loose = seg.loose.as_ref().map(|l| {
            let mut c = IrradianceCache::new(l.accuracy, base_cell(scene));
            for rec in dyn_cache.records() {
                c.insert(*rec);
            }
            c
        });
        let blended_points = point_beta.iter().filter(|b| **b > 0.0).count();
        DynamicPart {
            cache: dyn_cache,
            loose: dyn_loose,
            records: dyn_records,
            blended_points,
            rec_beta,
            rec_corr,
        }
    }
    fn source<'a>(&'a self, st: &'a FrameState) -> StaticDynamicSource<'a> {
        let seg = self.segment.as_ref().expect("segment made");
        StaticDynamicSource {
            settings: &self.settings.pmic,
            dynamic_map: &st.dyn_map,
            frame_reader: frame_reader(seg, st.frame_map.as_ref(), st.frame_pre.as_ref()),
            dynamic_instances: &seg.dynamic,
            all_dynamic: !seg.lights_static,
            static_cache: &seg.cache,
            static_loose: seg.loose.as_ref(),
            dynamic_loose: st.dyn_loose.as_ref(),
            fallbacks: AtomicU64::new(0),
            rec_beta: &st.rec_beta,
            rec_corr: &st.rec_corr,
            dynamic_cache: &st.dyn_cache,
            unstored: AtomicU64::new(0),
        }
    }

    /// Renders frame `frame` (scenes from `source`).
    pub fn render(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let st = self.prepare(source, frame);
        let s = &self.settings.pmic;
        let src = self.source(&st);
        let scene = &*st.scene;
        let eye = EyeView::new(s, scene, &st.caustic, &src);
        let mut out = render_camera_rays(&eye, scene, frame, s.common.spp, s.common.seed, progress);
        out.stats.rays += st.photon_rays;
        out.report.extend(st.report.clone());
        out.report
            .insert("unstored_gathers".into(), src.unstored.into_inner().into());
        out.report.insert(
            "fallback_interpolations".into(),
            src.fallbacks.into_inner().into(),
        );
        out
    }

    /// The blend weight β and the indirect irradiance `E` the eye pass of `frame` uses at
    /// the cache points seen through the image positions `raster` (pixel units; `None`
    /// where the eye path finds no cache point). For profiles across the blend.
    pub fn profile(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        raster: &[Vec2],
    ) -> Vec<Option<(CacheQuery, f32, Rgb)>> {
        let st = self.prepare(source, frame);
        let s = &self.settings.pmic;
        let src = self.source(&st);
        let scene = &*st.scene;
        let probe_src = NoIndirect;
        let view = EyeView::new(s, scene, &st.caustic, &probe_src);
        raster
            .iter()
            .map(|&x| {
                let mut rng = Pcg32::new(0, 0x7072_6f62);
                let q = view.probe(scene, &scene.camera.generate_ray(x), &mut rng)?;
                let (beta, e) = src.blended(scene, &q);
                Some((q, beta, e))
            })
            .collect()
    }
}

/// The gathered estimate of a static record's change of indirect irradiance (module doc,
/// "The correction").
struct Correction<'a> {
    settings: &'a PmIcSettings,
    frame: &'a FrameScene,
    static_scene: &'a FrameScene,
    dynamic: &'a [bool],
    dyn_map: &'a dyn RadianceMap,
    frame_map: &'a dyn RadianceMap,
    static_map: &'a dyn RadianceMap,
}

impl Correction<'_> {
    /// `E_F(x) − E_S(x)` by an `m × 3m` stratified gather at `(x, n)`: per stratum the
    /// dynamic map's radiance at the hit where the gather ray's chain meets only static
    /// instances (there the hit is the same in `S` and `F`), else the frame map's radiance
    /// at the chain's end in `F` less the static map's at its end in `S`. The strata's
    /// jitter is hashed from the record's point only, so a record gathers along the same
    /// directions in every frame of the segment.
    fn gathered(&self, x: Vec3, n: Vec3, m: u32) -> Rgb {
        let s = self.settings;
        let key = hash_words(&[s.common.seed, point_key(x, n), 0x636f_7272]);
        let mut jr = Pcg32::new(key, 0x6a69_7474);
        let mut rng = Pcg32::new(hash_words(&[key, 1]), 0x6761_7468);
        let np = 3 * m;
        let frame = Frame::from_normal(n);
        let mut sum = Rgb::ZERO;
        for j in 0..m {
            for k in 0..np {
                let (dir, _) = stratum_direction(&frame, m, np, j, k, jr.next_f32(), jr.next_f32());
                let start = rng.clone();
                let mut touched = false;
                let l = radiance(gather_ray_visiting(
                    self.frame,
                    s,
                    &[self.dyn_map],
                    x,
                    n,
                    dir,
                    &mut rng,
                    |i| touched |= self.dynamic.get(i as usize).copied().unwrap_or(true),
                ));
                sum += if touched {
                    let (mut a, mut b) = (start.clone(), start);
                    let lf = gather_ray_hit(self.frame, s, &[self.frame_map], x, n, dir, &mut a);
                    let ls =
                        gather_ray_hit(self.static_scene, s, &[self.static_map], x, n, dir, &mut b);
                    radiance(lf) - radiance(ls)
                } else {
                    l
                };
            }
        }
        sum * (std::f32::consts::PI / (m * np) as f32)
    }
}

/// The radiance of a gather ray's result (zero where it found nothing).
fn radiance(r: Option<(Rgb, f32, u32)>) -> Rgb {
    r.map_or(Rgb::ZERO, |(l, _, _)| l)
}

/// The influence measure and blend weight (see the module doc).
struct Blend<'a> {
    settings: &'a PmIcSettings,
    static_map: &'a PhotonMap,
    dynamic_map: &'a PhotonMap,
    low: f32,
    high: f32,
    sigmas: f32,
}

impl Blend<'_> {
    /// β ∈ [0, 1] at a static point (see the module doc).
    fn beta(&self, scene: &FrameScene, p: Vec3, n: Vec3) -> f32 {
        if self.dynamic_map.is_empty() {
            return 0.0;
        }
        let r = world_radius(scene, &self.settings.global);
        let (d, sigma) = self
            .dynamic_map
            .irradiance_with_noise(p, n, &self.settings.global, r);
        let excess = d.abs() - self.sigmas * sigma;
        if excess <= 0.0 {
            return 0.0;
        }
        let st = luminance(self.static_map.irradiance(p, n, &self.settings.global, r));
        let m = if st > 0.0 { excess / st } else { f32::INFINITY };
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

/// The static cache's interpolation at a point, with the records' β and correction
/// interpolated with weights continuous at the records' validity edges.
struct StaticValue {
    e: Rgb,
    beta: f32,
    corr: Rgb,
}

fn interpolate_static(
    cache: &IrradianceCache,
    rec_beta: &[f32],
    rec_corr: &[Rgb],
    q: &CacheQuery,
) -> Option<StaticValue> {
    let (mut sum, mut wsum, mut b, mut c) = (Rgb::ZERO, 0.0f32, 0.0f32, Rgb::ZERO);
    let (mut b0, mut c0, mut vsum) = (0.0f32, Rgb::ZERO, 0.0f32);
    let inv_a = 1.0 / cache.accuracy.max(1e-6);
    cache.for_valid_indexed(q.p, q.n, |i, rec, eps| {
        let w = 1.0 / eps.max(1e-6);
        sum += rec.extrapolate(q.p, q.n) * w;
        wsum += w;
        b0 += rec_beta[i] * w;
        c0 += rec_corr[i] * w;
        // β and the correction with weights that vanish at the edge of a record's
        // validity, so that they are continuous where records start to count (Ward's
        // weights jump there from 0 to 1/a: a step in β would show as a seam).
        let v = (w - inv_a).max(0.0);
        b += rec_beta[i] * v;
        c += rec_corr[i] * v;
        vsum += v;
    });
    let (beta, corr) = if vsum > 0.0 {
        (b / vsum, c / vsum)
    } else {
        (b0 / wsum, c0 / wsum)
    };
    (wsum > 0.0).then(|| StaticValue {
        e: (sum / wsum).max(Rgb::ZERO),
        beta: beta.clamp(0.0, 1.0),
        corr,
    })
}

struct StaticDynamicSource<'a> {
    settings: &'a PmIcSettings,
    dynamic_map: &'a PhotonMap,
    /// What the gathers not stored read (the frame map, or the static map).
    frame_reader: &'a dyn RadianceMap,
    dynamic_instances: &'a [bool],
    all_dynamic: bool,
    static_cache: &'a IrradianceCache,
    static_loose: Option<&'a IrradianceCache>,
    dynamic_loose: Option<&'a IrradianceCache>,
    fallbacks: AtomicU64,
    rec_beta: &'a [f32],
    rec_corr: &'a [Rgb],
    dynamic_cache: &'a IrradianceCache,
    unstored: AtomicU64,
}

impl StaticDynamicSource<'_> {
    /// The dynamic cache's irradiance (a gather in the frame, not stored, where it has no
    /// record).
    fn dynamic(&self, scene: &FrameScene, q: &CacheQuery) -> Rgb {
        if let Some((e, _)) = self.dynamic_cache.interpolate(q.p, q.n) {
            return e;
        }
        if let Some((e, _)) = self.dynamic_loose.and_then(|c| c.interpolate(q.p, q.n)) {
            self.fallbacks.fetch_add(1, Ordering::Relaxed);
            return e;
        }
        self.unstored.fetch_add(1, Ordering::Relaxed);
        gather_at(
            scene,
            self.settings,
            &[self.frame_reader],
            q.p,
            q.n,
            point_key(q.p, q.n),
        )
        .e
    }

    /// (β, E) at a cache point.
    fn blended(&self, scene: &FrameScene, q: &CacheQuery) -> (f32, Rgb) {
        if self.all_dynamic
            || self
                .dynamic_instances
                .get(q.instance as usize)
                .copied()
                .unwrap_or(true)
        {
            return (1.0, self.dynamic(scene, q));
        }
        let v =
            interpolate_static(self.static_cache, self.rec_beta, self.rec_corr, q).or_else(|| {
                let v = interpolate_static(self.static_loose?, self.rec_beta, self.rec_corr, q);
                self.fallbacks.fetch_add(1, Ordering::Relaxed);
                v
            });
        let Some(v) = v else {
            // No static record here (the cache points around it were on dynamic objects).
            return (1.0, self.dynamic(scene, q));
        };
        let st = if self.dynamic_map.is_empty() {
            v.e
        } else {
            (v.e + v.corr).max(Rgb::ZERO)
        };
        if v.beta <= 0.0 {
            return (0.0, st);
        }
        let dy = self.dynamic(scene, q);
        (v.beta, st * (1.0 - v.beta) + dy * v.beta)
    }
}

impl IndirectSource for StaticDynamicSource<'_> {
    fn irradiance(&self, scene: &FrameScene, q: &CacheQuery) -> Rgb {
        self.blended(scene, q).1
    }
}

impl crate::framework::sequence::SequenceRenderer for IcStaticDynamic {
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
pub static TECHNIQUE: crate::framework::technique::Preset<IcStaticDynamicSettings> =
    crate::framework::technique::Preset {
        name: "ic-static-dynamic",
        summary: "photon mapping with a static irradiance cache per segment of frames (dynamic objects removed) and per-frame dynamic photons (negative ones included) and a dynamic cache where they matter, blended",
        capabilities: crate::framework::technique::Capabilities {
            motion_blur: false,
            photons: false,
            window: false,
            max_depth: false,
            stateless: false,
            effort: crate::framework::technique::Effort {
                key: "photons",
                per_unit: 1000,
                unit: "thousand photons per map",
            },
        },
        quality: &[],
        defaults: IcStaticDynamicSettings::default,
        common: |s| &mut s.pmic.common,
        build: |s, _, name| Ok(Box::new(IcStaticDynamic::new(s, name))),
    };
