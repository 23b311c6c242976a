//! Photon mapping with final gathering and an irradiance cache, frame by frame
//! (`pm-ic`, Jensen 1996/2001 with Ward's cache), and its temporal variant with static and
//! dynamic photons and caches ([`crate::techniques::ic_static_dynamic`], `ic-static-dynamic`, Tawara,
//! Myszkowski, Seidel 2002/2004).
//!
//! ## Method (per frame)
//! 1. **Photons** ([`photon_map`]): `photons` photons of the replayable kernel
//!    ([`crate::kernels::photon`]) build the **global map** (every diffuse hit, direct ones
//!    included: the full outgoing light at a gather hit), and `photons` more, from an
//!    independent Halton scrambling, keep their caustic hits (light → specular⁺ → here)
//!    for the **caustic map**. Frame `f` uses photons `f·N ..` (a frame-by-frame baseline
//!    decorrelates frames) unless `fixed_photons` is set (then `0..N` every frame).
//! 2. **Eye paths** ([`view`], a reader of the shared eye walk [`crate::kernels::eye`]):
//!    emission seen directly or through delta chains; at every vertex with a non-delta
//!    lobe, direct light by next-event estimation (the shared kernel,
//!    [`crate::kernels::direct`], weight 1: emission is not picked up after a non-delta
//!    bounce) and caustics from the caustic map (`Σ f(wo, wi_p) Φ_p w_p / area`). A
//!    **glossy** vertex ([`view::follows_glossy`]: GGX α below `glossy_alpha`, metal or
//!    transmitting or without a diffuse base) continues the path by BSDF sampling (up to
//!    `max_glossy_depth`); a delta lobe continues the chain; at the first other non-delta
//!    vertex the indirect diffuse light is `β · f_sample · E(x)/π`, with `E` from the
//!    irradiance cache.
//! 3. **Irradiance cache** ([`irradiance_cache`]): records made by **final gathering** (M×N
//!    stratified cosine-weighted hemisphere; each gather ray follows delta chains without
//!    counting emission, and reads the global map's radiance estimate at its first
//!    non-delta hit), with harmonic mean distance and Ward–Heckbert gradients,
//!    interpolated with Ward's weights.
//!
//! ## Determinism (records in a fixed order)
//! Records are made lazily but not during the parallel eye pass: first a **probe pass**
//! finds the cache point of each pixel centre (the eye walk above with numbers hashed from
//! the pixel), on a coarse-to-fine grid (pixel strides 16, 8, 4, 2, 1; each level only the
//! pixels not on a coarser one), in row-major order, and last at the four quarter points
//! of every pixel. Those points are taken in batches of
//! [`BATCH`]: each batch drops the points some existing record already covers
//! (sequentially), gathers the rest in parallel and inserts them in point order. The
//! records therefore depend only on the batch size, not on the thread count. The eye pass
//! then only reads the cache; a sample point no record covers (sub-pixel jitter, rare)
//! gets its own gather, made from numbers hashed from the point and **not stored**
//! (counted in the frame report as `unstored_gathers`). Images are bit-identical for any
//! thread count.
//!
//! ## Bias and its bound
//! Relative to the path tracer the method is consistent except for:
//! - **interpolation** (first-order Taylor with Ward–Heckbert gradients over the validity
//!   radius `aR`): the error of a record is the second-order remainder
//!   `½ |∇²E| (aR)²`; where `E` varies on the scale `R` itself (an irradiance `∝ 1/d²`
//!   from a surface at distance `R`, the worst regular case, the plane test's
//!   `E = I h/(h²+r²)^{3/2}` with `R = h`) that is `≤ 1.5 a² E` (6 % of E at a = 0.2);
//!   the interpolation is a convex combination of such extrapolations, so it is bounded
//!   by the same. `R` is clamped (see [`irradiance_cache`]): the lower clamp (validity radius at
//!   least one pixel) enlarges records in corners, where `E` varies fastest — the
//!   bound then holds with `R` the clamped radius, i.e. at pixel scale.
//! - **density estimation at gather hits**: the global map's kernel blurs the outgoing
//!   radiance over the disc radius `r ≤ max_radius`; the gather averages many such
//!   estimates, so the error in `E` is the blur of the *incident* field, second order in
//!   `r` (`O(r²∇²L)`), and its noise is averaged over M·N hits.
//! - **caustic map** blur at the eye vertex, `O(r_c²∇²E_c)`.
//! - **non-Lambertian, non-glossy lobes** (the specular coating of a plastic) see indirect
//!   light as uniform `E/π`; bounded by the coating's albedo (a few % for glTF's
//!   dielectric F0 = 0.04) times the anisotropy of the incident indirect light.
//! - the **gather's** own first-order noise is frozen in each record (not a bias of the
//!   mean over seeds, but it does not average out over pixels within a record).
//!
//! On the diffuse Cornell box indirect light is about a third of the image's radiance,
//! so the interpolation bound (6 % of `E`) is ≈ 2 % of a block's value; the test adds the
//! reference's own noise and the map blur measured in `tests/it/pmic.rs`.
//!
//! ## Deviations from the papers
//! - Caustic photons are not aimed at specular objects (the kernel is replayable by index
//!   and cannot aim); the caustic map keeps the caustic hits of a separate photon stream.
//! - Direct light at gather hits comes from the global map (as Jensen), not from shadow
//!   rays.
//! - Records live on the first diffuse-class vertex of eye paths, including behind delta
//!   and glossy chains.

pub mod irradiance_cache;
pub mod photon_map;
pub mod precomputed;
pub mod view;

use crate::kernels::photon::trace_photons;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::spawn_ray;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::hash_words;
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::scene::frame::FrameScene;
use irradiance_cache::{CacheParams, Gather, IrradianceCache, gather, make_record};
use photon_map::{Lookup, MapFilter, PhotonMap, StoredPhoton};
use view::{CacheQuery, EyeView, IndirectSource};

/// Points gathered per batch of the record-making pass (results depend on it, not on
/// the thread count).
pub const BATCH: usize = 16;

/// Pixel strides of the probe pass, coarse to fine.
pub const PROBE_STRIDES: [u32; 5] = [16, 8, 4, 2, 1];

/// Settings of `pm-ic`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PmIcSettings {
    /// Camera samples, path depth and seed ([`crate::framework::technique::CommonSettings`]). `spp`:
    /// Camera samples per pixel (direct light, caustics, anti-aliasing). Default 16.
    /// `seed`: Seed of the photon, gather and camera streams. Default 0. `max_depth`: not
    /// implemented (must stay `None`: the eye walk ends at `max_specular_depth`)
    #[serde(flatten)]
    pub common: crate::framework::technique::CommonSettings,
    /// Photons per frame for the global map, and as many for the caustic map. Default 100 000.
    pub photons: u64,
    /// Global-map lookups at gather hits.
    pub global: Lookup,
    /// Caustic-map lookups at eye vertices.
    pub caustic: Lookup,
    /// Gather strata in θ (M) and φ (N). Defaults 12 × 36 (432 rays).
    pub gather_m: u32,
    pub gather_n: u32,
    /// The irradiance cache (accuracy a, radius clamps).
    pub cache: CacheParams,
    /// Longest chain of delta bounces followed by eye and gather rays. Default 8.
    pub max_specular_depth: u32,
    /// GGX α below which a metal, transmitting or base-less lobe is traced as glossy.
    /// Default 0.1 (roughness ≈ 0.32).
    pub glossy_alpha: f32,
    /// Glossy bounces followed by an eye path. Default 3.
    pub max_glossy_depth: u32,
    /// Use photons `0..N` in every frame instead of `f·N ..`. Default false.
    pub fixed_photons: bool,
    /// The estimator of a gather ray's radiance. 0: the k-NN radiance estimate of the
    /// global map ([`PhotonMap::radiance`]). N > 0: Christensen's precomputed irradiance
    /// at every N-th photon of each light group's map, read by one nearest-neighbour
    /// lookup ([`precomputed`]: the estimator `ic-selective` keeps its strata with, so that
    /// `pm-ic` with it is that method frame by frame). `pm-ic`'s technique defaults set 4
    /// (`techniques::pm_ic::pm_ic_defaults`), and so do `ic-static-dynamic`'s, which
    /// reads its static, frame and dynamic maps so (one precomputed map per map, not per
    /// light group); this struct's default is 0 (the tests that build the methods from it
    /// keep the k-NN estimate). `ic-selective` refuses a value (its own `light_terms` and
    /// `precompute_stride` choose).
    pub precompute_stride: u32,
}

impl Default for PmIcSettings {
    fn default() -> Self {
        PmIcSettings {
            common: crate::framework::technique::CommonSettings {
                spp: 16,
                max_depth: None,
                seed: 0,
            },
            photons: 100_000,
            global: Lookup {
                k: 64,
                max_radius: 0.1,
                filter: MapFilter::Cone { k: 1.1 },
            },
            caustic: Lookup {
                k: 64,
                max_radius: 0.03,
                filter: MapFilter::Cone { k: 1.1 },
            },
            gather_m: 12,
            gather_n: 36,
            cache: CacheParams::default(),
            max_specular_depth: 8,
            glossy_alpha: 0.1,
            max_glossy_depth: 3,
            fixed_photons: false,
            precompute_stride: 0,
        }
    }
}

/// Salt of the caustic photon stream's scrambling.
const CAUSTIC_SALT: u64 = 0x6361_7573_7469_6373;

/// First photon index of frame `frame`.
pub fn photon_base(s: &PmIcSettings, frame: u32) -> u64 {
    if s.fixed_photons {
        0
    } else {
        frame as u64 * s.photons
    }
}

/// Seed of the caustic stream.
pub fn caustic_seed(seed: u64) -> u64 {
    hash_words(&[seed, CAUSTIC_SALT])
}

/// The photons of the global stream (every diffuse hit) of `indices`, with their photon
/// index, in index then path order.
pub fn global_photons(
    scene: &FrameScene,
    indices: std::ops::Range<u64>,
    seed: u64,
    emitted: u64,
) -> (Vec<(u64, StoredPhoton)>, u64) {
    let (v, st) = trace_photons(scene, indices, seed, |h| {
        Some((h.index, StoredPhoton::from_hit(h, emitted)))
    });
    (v, st.rays)
}

/// The caustic hits of the caustic stream's photons `indices`.
pub fn caustic_photons(
    scene: &FrameScene,
    indices: std::ops::Range<u64>,
    seed: u64,
    emitted: u64,
) -> (Vec<StoredPhoton>, u64) {
    let (v, st) = trace_photons(scene, indices, caustic_seed(seed), |h| {
        h.caustic.then(|| StoredPhoton::from_hit(h, emitted))
    });
    (v, st.rays)
}

/// World size of a lookup's maximum radius.
pub fn world_radius(scene: &FrameScene, l: &Lookup) -> f32 {
    l.max_radius * scene.scene_radius.max(1e-6)
}

/// What a gather ray reads at the first non-delta vertex of its chain: a photon map's k-NN
/// radiance estimate ([`PhotonMap::radiance`]) or precomputed irradiance
/// ([`precomputed::PrecomputedMap`]); `&dyn RadianceMap` when the choice is made at run
/// time. Read from the parallel gathers, hence `Sync`.
pub trait RadianceMap: Sync {
    /// Radiance reflected towards `wo` by `bsdf` at `x` (side normal `n`).
    fn gather_radiance(
        &self,
        x: Vec3,
        n: Vec3,
        wo: Vec3,
        bsdf: &chronolux_core::bsdf::Bsdf,
        lookup: &Lookup,
        r_max: f32,
    ) -> Rgb;
}

impl RadianceMap for PhotonMap {
    #[inline]
    fn gather_radiance(
        &self,
        x: Vec3,
        n: Vec3,
        wo: Vec3,
        bsdf: &chronolux_core::bsdf::Bsdf,
        lookup: &Lookup,
        r_max: f32,
    ) -> Rgb {
        self.radiance(x, n, wo, bsdf, lookup, r_max)
    }
}

/// Radiance arriving at `x` from direction `dir` for a final gather: delta chains are
/// followed (emission not counted: direct light and caustics are estimated elsewhere) and
/// the first non-delta hit reads `maps` (summed). Returns (radiance, distance to the
/// first hit); `None` when nothing is hit.
pub fn gather_ray<M: RadianceMap + ?Sized>(
    scene: &FrameScene,
    s: &PmIcSettings,
    maps: &[&M],
    x: Vec3,
    n: Vec3,
    dir: Vec3,
    rng: &mut Pcg32,
) -> Option<(Rgb, f32)> {
    gather_ray_hit(scene, s, maps, x, n, dir, rng).map(|(l, d, _)| (l, d))
}

/// [`gather_ray`] with the instance of the first hit.
pub fn gather_ray_hit<M: RadianceMap + ?Sized>(
    scene: &FrameScene,
    s: &PmIcSettings,
    maps: &[&M],
    x: Vec3,
    n: Vec3,
    dir: Vec3,
    rng: &mut Pcg32,
) -> Option<(Rgb, f32, u32)> {
    gather_ray_visiting(scene, s, maps, x, n, dir, rng, |_| {})
}

/// [`gather_ray_hit`], calling `visit` with the instance of every vertex of the ray's
/// chain (the delta vertices and the one whose radiance is read), in order.
#[allow(clippy::too_many_arguments)]
pub fn gather_ray_visiting<M: RadianceMap + ?Sized>(
    scene: &FrameScene,
    s: &PmIcSettings,
    maps: &[&M],
    x: Vec3,
    n: Vec3,
    dir: Vec3,
    rng: &mut Pcg32,
    visit: impl FnMut(u32),
) -> Option<(Rgb, f32, u32)> {
    let end = gather_chain(scene, s, x, n, dir, rng, visit)?;
    let l = match &end.read {
        Some(v) => {
            let r_max = world_radius(scene, &s.global);
            let mut l = Rgb::ZERO;
            for m in maps {
                l += m.gather_radiance(end.last.0, end.last.1, v.wo, &v.bsdf, &s.global, r_max);
            }
            v.beta * l
        }
        None => Rgb::ZERO,
    };
    Some((l, end.dist, end.instance))
}

/// Where a gather ray's chain ended ([`gather_chain`]).
pub struct ChainEnd {
    /// The first non-delta vertex, whose radiance the gather reads; `None` when the chain
    /// was cut (depth limit or zero throughput) before one.
    pub read: Option<ChainVertex>,
    /// Point and side normal (turned towards the ray) of the chain's last vertex: the
    /// vertex read, or the last delta vertex of a cut chain.
    pub last: (Vec3, Vec3),
    /// Distance to the chain's first hit, and its instance.
    pub dist: f32,
    pub instance: u32,
}

/// The vertex a gather ray reads ([`ChainEnd::read`]).
pub struct ChainVertex {
    /// Direction back along the ray.
    pub wo: Vec3,
    pub bsdf: chronolux_core::bsdf::Bsdf,
    /// Throughput of the delta chain before it.
    pub beta: Rgb,
}

/// The delta chain of a gather ray from (x, n) along `dir`, followed up to
/// `max_specular_depth` bounces with numbers from `rng` (three per vertex), calling
/// `visit` with every vertex's instance; `None` when nothing is hit, the chain leaves
/// the scene or its sampling fails. What every gather reads at its end is chosen by the
/// caller ([`gather_ray_visiting`], [`precomputed::gather_hit`]).
pub fn gather_chain(
    scene: &FrameScene,
    s: &PmIcSettings,
    x: Vec3,
    n: Vec3,
    dir: Vec3,
    rng: &mut Pcg32,
    mut visit: impl FnMut(u32),
) -> Option<ChainEnd> {
    let mut ray = spawn_ray(x, n, dir);
    let mut beta = Rgb::ONE;
    let mut first: Option<(f32, u32)> = None;
    let mut last = (x, n);
    for _ in 0..=s.max_specular_depth {
        let hit = scene.intersect(&ray)?;
        let si = scene.interaction(&hit, &ray);
        visit(si.instance);
        let (dist, instance) = *first.get_or_insert(((si.p - x).length(), si.instance));
        let wo = -ray.d.normalize();
        let bsdf = scene.bsdf(&si);
        let (u_lobe, u_dir) = (rng.next_f32(), Vec2::new(rng.next_f32(), rng.next_f32()));
        let ns = if wo.dot(si.ng) >= 0.0 { si.ng } else { -si.ng };
        last = (si.p, ns);
        if bsdf.has_non_delta() {
            return Some(ChainEnd {
                read: Some(ChainVertex { wo, bsdf, beta }),
                last,
                dist,
                instance,
            });
        }
        let bs = bsdf.sample(
            wo,
            u_lobe,
            u_dir,
            chronolux_core::bsdf::TransportMode::Radiance,
        )?;
        beta *= bs.weight;
        if beta == Rgb::ZERO {
            break;
        }
        ray = spawn_ray(si.p, si.ng, bs.wi);
    }
    first.map(|(dist, instance)| ChainEnd {
        read: None,
        last,
        dist,
        instance,
    })
}

/// A final gather at (x, n) reading `maps`, its strata jittered from `key`.
pub fn gather_at<M: RadianceMap + ?Sized>(
    scene: &FrameScene,
    s: &PmIcSettings,
    maps: &[&M],
    x: Vec3,
    n: Vec3,
    key: u64,
) -> Gather {
    let mut rng = Pcg32::new(hash_words(&[s.common.seed, key]), 0x6761_7468);
    let mut jr = Pcg32::new(hash_words(&[s.common.seed, key, 1]), 0x6a69_7474);
    gather(
        n,
        s.gather_m,
        s.gather_n,
        |_, _| (jr.next_f32(), jr.next_f32()),
        |d| gather_ray(scene, s, maps, x, n, d, &mut rng),
    )
}

/// Key of an unstored gather at a point (hash of its bits).
pub fn point_key(x: Vec3, n: Vec3) -> u64 {
    hash_words(&[
        x.x.to_bits() as u64,
        x.y.to_bits() as u64,
        x.z.to_bits() as u64,
        n.x.to_bits() as u64,
        n.y.to_bits() as u64,
        n.z.to_bits() as u64,
    ])
}

/// The probe pass: the cache point of each pixel centre of the coarse-to-fine grid
/// ([`PROBE_STRIDES`]), in level then row-major order, then of the four quarter points of
/// every pixel (so pixels straddling an edge get records on both surfaces), with a key
/// per point.
pub fn probe_points<S: IndirectSource>(
    view: &EyeView<'_, S>,
    scene: &FrameScene,
    key: u64,
) -> Vec<(u64, CacheQuery)> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    // (pixel x, pixel y, sub-position): 0 is the centre, 1..=4 the quarter points.
    let mut pixels = Vec::new();
    for (li, &stride) in PROBE_STRIDES.iter().enumerate() {
        for y in (0..h).step_by(stride as usize) {
            for x in (0..w).step_by(stride as usize) {
                let coarser = PROBE_STRIDES[..li]
                    .iter()
                    .any(|&c| x % c == 0 && y % c == 0);
                if !coarser {
                    pixels.push((x, y, 0u32));
                }
            }
        }
    }
    for y in 0..h {
        for x in 0..w {
            for sub in 1..=4 {
                pixels.push((x, y, sub));
            }
        }
    }
    const SUB: [(f32, f32); 5] = [
        (0.5, 0.5),
        (0.25, 0.25),
        (0.75, 0.25),
        (0.25, 0.75),
        (0.75, 0.75),
    ];
    let found = parallel::map_chunks(pixels.len(), 64, |r| {
        let mut out = Vec::new();
        for &(x, y, sub) in &pixels[r] {
            let k = hash_words(&[key, x as u64, y as u64, sub as u64]);
            let mut rng = Pcg32::new(k, 0x7072_6f62);
            let (dx, dy) = SUB[sub as usize];
            let ray = scene
                .camera
                .generate_ray(Vec2::new(x as f32 + dx, y as f32 + dy));
            if let Some(q) = view.probe(scene, &ray, &mut rng) {
                out.push((k, q));
            }
        }
        out
    });
    found.into_iter().flatten().collect()
}

/// Adds records to `cache` for the points `want` accepts (by index in `points`) that no
/// record covers yet, in batches of [`BATCH`] (see the module doc); `gather_fn(point,
/// key)` makes a gather. Returns the records added.
pub fn extend_cache(
    cache: &mut IrradianceCache,
    points: &[(u64, CacheQuery)],
    params: &CacheParams,
    want: impl Fn(usize) -> bool + Sync,
    gather_fn: impl Fn(&CacheQuery, u64) -> Gather + Sync,
) -> u64 {
    let mut added = 0;
    for (b, batch) in points.chunks(BATCH).enumerate() {
        let need: Vec<&(u64, CacheQuery)> = batch
            .iter()
            .enumerate()
            .filter(|(i, (_, q))| want(b * BATCH + i) && !cache.covers(q.p, q.n))
            .map(|(_, p)| p)
            .collect();
        if need.is_empty() {
            continue;
        }
        let made = parallel::map_chunks(need.len(), 1, |r| {
            let (k, q) = need[r.start];
            let g = gather_fn(q, *k);
            let a = params.accuracy.max(1e-6);
            make_record(
                q.p,
                q.n,
                &g,
                params.r_min_px * q.footprint / a,
                params.r_max_px * q.footprint / a,
            )
        });
        for rec in made {
            cache.insert(rec);
            added += 1;
        }
    }
    added
}

/// Smallest grid cell of a cache for `scene`.
pub fn base_cell(scene: &FrameScene) -> f32 {
    scene.scene_radius.max(1e-6) * 1e-4
}

/// The maps of one frame.
pub struct FrameMaps {
    pub global: PhotonMap,
    pub caustic: PhotonMap,
    /// Photon rays traced.
    pub rays: u64,
}

/// Traces the global and caustic photons of photon indices `base .. base + n`.
pub fn frame_maps(scene: &FrameScene, s: &PmIcSettings, base: u64) -> FrameMaps {
    let n = s.photons;
    let (g, r1) = global_photons(scene, base..base + n, s.common.seed, n);
    let (c, r2) = caustic_photons(scene, base..base + n, s.common.seed, n);
    FrameMaps {
        global: PhotonMap::build(g.into_iter().map(|(_, p)| p).collect()),
        caustic: PhotonMap::build(c),
        rays: r1 + r2,
    }
}

/// The irradiance source of `pm-ic`: one cache; the gathers where it has no record read
/// `maps` (summed), as the cache's own gathers do.
pub struct CacheSource<'a> {
    pub settings: &'a PmIcSettings,
    pub cache: &'a IrradianceCache,
    pub maps: &'a [&'a dyn RadianceMap],
    pub unstored: std::sync::atomic::AtomicU64,
}

impl IndirectSource for CacheSource<'_> {
    fn irradiance(&self, scene: &FrameScene, q: &CacheQuery) -> Rgb {
        if let Some((e, _)) = self.cache.interpolate(q.p, q.n) {
            return e;
        }
        self.unstored
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        gather_at(
            scene,
            self.settings,
            self.maps,
            q.p,
            q.n,
            point_key(q.p, q.n),
        )
        .e
    }
}
