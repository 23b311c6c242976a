//! The one photon-tracing kernel, shared by every photon method (density estimation on
//! elements, selective photon tracing, photon maps).
//!
//! ## Replayable, quasi-random photons
//! Photon `index` is generated from Halton point `index` (scrambled per dimension by
//! `seed`, [`chronolux_core::sampling::qmc::halton`]) with one dimension per decision, in
//! this fixed order:
//!
//! | dimension (base) | decision |
//! | --- | --- |
//! | 0 (2) | light choice *and* first coordinate of the point on the light (see below) |
//! | 1 (3) | second coordinate of the point on the light ([`Light::sample_le`](chronolux_core::light::Light::sample_le) `u_pos.y`) |
//! | 2, 3 (5, 7) | emitted direction ([`Light::sample_le`](chronolux_core::light::Light::sample_le) `u_dir`) |
//! | 4 + 4b, 5 + 4b | bounce b: BSDF direction (bounce 0: bases 11, 13) |
//! | 6 + 4b | bounce b: BSDF lobe |
//! | 7 + 4b | bounce b: Russian roulette |
//!
//! The coordinates that decide where a photon goes — emission (point, direction) and the
//! first bounce's direction — take the six lowest prime bases, so that the periodicity of
//! the Halton sequence (points `i` and `i + m·N_g` agree in dimension `j` to within
//! `b_j^-k_j` when `b_j^k_j` divides `N_g`, Dmitriev et al. 2002, Eq. 1) makes groups of
//! photons `i ≡ r (mod N_g)` coherent with a small `N_g` (selective photon tracing,
//! [`crate::techniques::spt`]). The light choice is folded into dimension 0: the power-proportional
//! [`LightSampler`](chronolux_core::light::LightSampler) inverts its CDF at `u₀` and the
//! remainder `(u₀ − cdf_l)/pmf_l`, again uniform in [0, 1), is the first coordinate of the
//! point on the chosen light — the emitters are sampled as one surface, so photons that
//! agree in dimension 0 leave the same light from nearby points (a separate light-choice
//! dimension in front, as before, pushed emission to bases 3–11 and the first bounce to
//! bases 17/19, where the group count needed for coherence explodes).
//!
//! Every dimension is consumed whether or not it is used, so photon `index` follows the
//! same path in any scene where the same decisions lead to the same surfaces: re-tracing
//! photon `i` in another frame is exactly `trace_photon(scene', i, seed, ..)`. (Dimensions
//! beyond the 64 prime bases wrap around; that happens after 14 bounces only.)
//!
//! ## Power
//! A photon starts with flux `le·|cos|/(pdf_pos·pdf_dir·pmf(light))` (an unbiased estimate
//! of the total emitted power, so the power of `N` photons is their sum divided by `N`).
//! Bounces sample the BSDF in [`TransportMode::Importance`] (the adjoint shading-normal
//! correction is applied inside [`chronolux_core::bsdf::Bsdf`]); Russian roulette keeps the
//! photon with probability `q = min(1, max(β·w)/max(β))` and divides by `q`, so the carried
//! power stays roughly constant (Jensen's photon map rule).
//!
//! ## What is reported
//! Every hit on a surface with a non-delta lobe ("diffuse hit") is reported to the
//! callback with the power arriving there, before the photon scatters on. Hits on purely
//! specular (delta) surfaces are not reported by [`trace_photon`]; [`trace_photon_path`]
//! reports every vertex (delta ones flagged) and the emitting light, for methods that must
//! know everything a path touched (selective photon tracing's pilots).

use super::direct::light_radiance_at;
use chronolux_core::accel::TriRef;
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::{Rgb, max_component};
use chronolux_core::geometry::{Bounds3, Ray, spawn_ray};
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::qmc::halton;
use chronolux_core::scene::frame::FrameScene;

/// Hard cap on the number of bounces of one photon (Russian roulette ends paths long
/// before it except in pathological all-white scenes).
pub const MAX_BOUNCES: u32 = 64;

/// First Halton dimension of bounce `b` (its two direction coordinates; the lobe choice
/// is `bounce_dim(b) + 2`, Russian roulette `bounce_dim(b) + 3`).
#[inline]
pub const fn bounce_dim(b: u32) -> usize {
    4 + 4 * b as usize
}

/// Dimension of the light choice (and the first coordinate of the point on the light).
pub const LIGHT_DIM: usize = 0;
/// Dimensions of the point on the light (`LIGHT_DIM` reused after the choice, then this).
pub const POSITION_DIMS: [usize; 2] = [0, 1];
/// Dimensions of the emitted direction.
pub const DIRECTION_DIMS: [usize; 2] = [2, 3];
/// Dimensions of the first bounce's BSDF direction.
pub const FIRST_BOUNCE_DIMS: [usize; 2] = [bounce_dim(0), bounce_dim(0) + 1];

/// A photon arriving at a surface with a non-delta lobe.
#[derive(Clone, Copy, Debug)]
pub struct PhotonHit {
    /// Index of the photon (its Halton point).
    pub index: u64,
    /// World-space hit point.
    pub p: Vec3,
    /// Geometric normal (world, unit, front per winding).
    pub ng: Vec3,
    /// Triangle hit (stable [`GeometryId`](chronolux_core::scene::frame::GeometryId) and
    /// triangle index) and the instance it was hit through.
    pub tri: TriRef,
    pub instance: u32,
    /// Barycentrics of the hit point on the triangle (vertices 1 and 2).
    pub b1: f32,
    pub b2: f32,
    /// Unit direction from the hit point back towards where the photon came from.
    pub wi: Vec3,
    /// Flux carried (per emitted photon: the flux estimate of `N` photons is Σ power / N).
    pub power: Rgb,
    /// Scattering events before this hit: 0 = straight from the light.
    pub bounces: u32,
    /// All of the (at least one) scattering events before this hit were specular (delta):
    /// a caustic photon (light → specular⁺ → here).
    pub caustic: bool,
}

impl PhotonHit {
    /// True when the photon did at least one bounce (indirect illumination, caustics included).
    #[inline]
    pub fn is_indirect(&self) -> bool {
        self.bounces > 0
    }
}

/// What tracing one photon cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhotonStats {
    /// Closest-hit rays cast.
    pub rays: u64,
    /// Hits reported.
    pub hits: u64,
}

impl std::ops::AddAssign for PhotonStats {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.hits += o.hits;
    }
}

/// One vertex of a photon path as [`trace_photon_path`] reports it.
#[derive(Clone, Copy, Debug)]
pub struct PathVertex {
    /// The hit, with the power arriving there.
    pub hit: PhotonHit,
    /// The surface has a non-delta lobe: [`trace_photon`] reports (deposits) this hit.
    pub deposited: bool,
    /// Material of the surface hit (index into [`FrameScene::materials`]).
    pub material: u32,
}

/// Traces photon `index` of the stream keyed by `seed` through `scene`, reporting every
/// diffuse hit to `callback` in path order. Deterministic: the same (scene, index, seed)
/// always gives the same hits.
pub fn trace_photon(
    scene: &FrameScene,
    index: u64,
    seed: u64,
    callback: impl FnMut(&PhotonHit),
) -> PhotonStats {
    trace_photon_within(scene, index, seed, MAX_BOUNCES, callback)
}

/// [`trace_photon`] ending the path after its hit with `max_bounces` scattering events
/// (at most [`MAX_BOUNCES`]): the same hits as [`trace_photon`]'s with
/// [`PhotonHit::bounces`] ≤ `max_bounces`, without tracing the rest of the path (a
/// depth-limited render's photons, [`crate::kernels::elements::element_map::max_photon_bounces`]).
pub fn trace_photon_within(
    scene: &FrameScene,
    index: u64,
    seed: u64,
    max_bounces: u32,
    mut callback: impl FnMut(&PhotonHit),
) -> PhotonStats {
    walk(
        scene,
        index,
        seed,
        false,
        max_bounces.min(MAX_BOUNCES),
        |_, _| {},
        |v| {
            if v.deposited {
                callback(&v.hit)
            }
        },
        |_| {},
    )
}

/// [`trace_photon`] reporting everything the path touches: the emitting light (index into
/// [`FrameScene::lights`]) with the emitted ray, before the first vertex (not called when
/// nothing is emitted); every vertex, delta (purely specular) ones included; and the ray
/// that left the scene, if the path ended by missing every surface (`on_escape`). Same
/// path, same stats.
pub fn trace_photon_path(
    scene: &FrameScene,
    index: u64,
    seed: u64,
    on_light: impl FnMut(usize, &Ray),
    on_vertex: impl FnMut(&PathVertex),
    on_escape: impl FnMut(&Ray),
) -> PhotonStats {
    walk(
        scene,
        index,
        seed,
        false,
        MAX_BOUNCES,
        on_light,
        on_vertex,
        on_escape,
    )
}

/// [`trace_photon`] restricted to caustic photons: the same photon `index` (same numbers,
/// same path as long as it lasts), reporting only its deposits with
/// [`PhotonHit::caustic`] set (light → specular⁺ → here), and ending the path at its first
/// non-delta bounce, after which no deposit can be a caustic one. A photon whose first hit
/// is on a surface without a delta lobe costs one ray.
pub fn trace_caustic_photon(
    scene: &FrameScene,
    index: u64,
    seed: u64,
    mut callback: impl FnMut(&PhotonHit),
) -> PhotonStats {
    walk(
        scene,
        index,
        seed,
        true,
        MAX_BOUNCES,
        |_, _| {},
        |v| {
            if v.deposited && v.hit.caustic {
                callback(&v.hit)
            }
        },
        |_| {},
    )
}

/// The photon walk of [`trace_photon_path`]; with `specular_only`, the walk ends at the
/// first bounce that samples a non-delta lobe, and in any case after the vertex reached by
/// `max_bounces` bounces (everything before either is unchanged).
#[allow(clippy::too_many_arguments)]
fn walk(
    scene: &FrameScene,
    index: u64,
    seed: u64,
    specular_only: bool,
    max_bounces: u32,
    mut on_light: impl FnMut(usize, &Ray),
    mut on_vertex: impl FnMut(&PathVertex),
    mut on_escape: impl FnMut(&Ray),
) -> PhotonStats {
    let mut stats = PhotonStats::default();
    let h = |dim: usize| halton(dim, index, seed);
    let Some((li, pmf, u_pos0)) = scene.light_sampler.sample(h(LIGHT_DIM)) else {
        return stats;
    };
    if pmf <= 0.0 {
        return stats;
    }
    let light = &scene.lights[li];
    let (center, radius) = scene.bounds.bounding_sphere();
    let Some(les) = light.sample_le(
        Vec2::new(u_pos0, h(POSITION_DIMS[1])),
        Vec2::new(h(DIRECTION_DIMS[0]), h(DIRECTION_DIMS[1])),
        center,
        radius,
    ) else {
        return stats;
    };
    if les.pdf_pos <= 0.0 || les.pdf_dir <= 0.0 {
        return stats;
    }
    let le = light_radiance_at(scene, light, les.le, les.ray.o);
    let mut beta = chronolux_core::light::emit::LeSample { le, ..les }.flux_weight() / pmf;
    if beta == Rgb::ZERO || !beta.is_finite() {
        return stats;
    }
    on_light(li, &les.ray);
    let mut ray = les.ray;
    let mut bounces = 0u32;
    let mut all_specular = true;
    loop {
        stats.rays += 1;
        let Some(hit) = scene.intersect(&ray) else {
            on_escape(&ray);
            break;
        };
        let si = scene.interaction(&hit, &ray);
        let wo = -ray.d.normalize();
        let bsdf = scene.bsdf(&si);
        let deposited = bsdf.has_non_delta();
        if deposited {
            stats.hits += 1;
        }
        on_vertex(&PathVertex {
            hit: PhotonHit {
                index,
                p: si.p,
                ng: si.ng,
                tri: hit.tri,
                instance: hit.instance,
                b1: hit.b1,
                b2: hit.b2,
                wi: wo,
                power: beta,
                bounces,
                caustic: bounces > 0 && all_specular,
            },
            deposited,
            material: si.material,
        });
        if bounces >= max_bounces {
            break;
        }
        let d = bounce_dim(bounces);
        let Some(bs) = bsdf.sample(
            wo,
            h(d + 2),
            Vec2::new(h(d), h(d + 1)),
            TransportMode::Importance,
        ) else {
            break;
        };
        if specular_only && !bs.is_delta {
            break;
        }
        let new_beta = beta * bs.weight;
        let q = (max_component(new_beta) / max_component(beta)).min(1.0);
        if !(q > 0.0) || h(d + 3) >= q {
            break;
        }
        beta = new_beta / q;
        all_specular &= bs.is_delta;
        bounces += 1;
        ray = spawn_ray(si.p, si.ng, bs.wi);
    }
    stats
}

/// Photons per parallel work item. Results do not depend on it.
pub const PHOTON_CHUNK: u64 = 2048;

/// Traces photons `indices` in parallel (chunks of [`PHOTON_CHUNK`]) and returns what
/// `map` keeps of their hits, in photon-index order then path order — bit-identical for
/// any thread count.
pub fn trace_photons<T: Send>(
    scene: &FrameScene,
    indices: std::ops::Range<u64>,
    seed: u64,
    map: impl Fn(&PhotonHit) -> Option<T> + Sync,
) -> (Vec<T>, PhotonStats) {
    trace_photons_within(scene, indices, seed, MAX_BOUNCES, map)
}

/// [`trace_photons`] with every path ended after `max_bounces` scattering events
/// ([`trace_photon_within`]).
pub fn trace_photons_within<T: Send>(
    scene: &FrameScene,
    indices: std::ops::Range<u64>,
    seed: u64,
    max_bounces: u32,
    map: impl Fn(&PhotonHit) -> Option<T> + Sync,
) -> (Vec<T>, PhotonStats) {
    let n = indices.end.saturating_sub(indices.start);
    let chunks = parallel::map_chunks(n.div_ceil(PHOTON_CHUNK) as usize, 1, |r| {
        let c = r.start as u64;
        let lo = indices.start + c * PHOTON_CHUNK;
        let hi = (lo + PHOTON_CHUNK).min(indices.end);
        let mut out = Vec::new();
        let mut stats = PhotonStats::default();
        for i in lo..hi {
            stats += trace_photon_within(scene, i, seed, max_bounces, |hit| {
                if let Some(t) = map(hit) {
                    out.push(t);
                }
            });
        }
        (out, stats)
    });
    let mut all = Vec::with_capacity(chunks.iter().map(|c| c.0.len()).sum());
    let mut stats = PhotonStats::default();
    for (v, s) in chunks {
        all.extend(v);
        stats += s;
    }
    (all, stats)
}

/// Slab test: does the segment `o + t·d`, `t ∈ [0, t_max]`, meet box `b`? (Which photon
/// paths a change reached: `spt`'s path scan, `ic-static-dynamic`'s sweep.)
#[inline]
pub fn segment_hits_box(o: Vec3, d: Vec3, t_max: f32, b: &Bounds3) -> bool {
    let (mut t0, mut t1) = (0.0f32, t_max);
    for k in 0..3 {
        let inv = 1.0 / d[k];
        let (mut a, mut c) = ((b.min[k] - o[k]) * inv, (b.max[k] - o[k]) * inv);
        if a > c {
            std::mem::swap(&mut a, &mut c);
        }
        // NaN (d = 0 and o on a slab plane) keeps the current interval.
        if a > t0 {
            t0 = a;
        }
        if c < t1 {
            t1 = c;
        }
        if t0 > t1 {
            return false;
        }
    }
    true
}
