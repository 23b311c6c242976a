//! Photon maps per **light group** with **precomputed irradiance** (Christensen 1999,
//! "Faster photon map global illumination", JGT 4(3)), read by final gathering with one
//! nearest-neighbour query instead of a k-NN radiance estimate.
//!
//! ## Maps
//! The photons are `pm-ic`'s global stream (photons `base .. base + n`, the same Halton
//! points and paths as [`super::global_photons`], photon `i` always from stream `i`), each
//! tagged with the light it left ([`trace_photon_path`]'s `on_light`; the light is the
//! power-proportional light sampler's choice, so the total budget `n` is split between
//! the lights by their power exactly as in `pm-ic`'s one map). The lights are put into
//! **groups** ([`light_groups`]): the emissive triangles of one instance form a group
//! (they move with it, and a moving instance is a geometry change anyway), every other
//! light (point, spot, directional, environment) is a group of its own; groups past
//! [`MAX_GROUPS`] − 1 share the last one. Each group's photons make one map.
//!
//! ## Precomputed irradiance
//! At every `stride`-th photon of a group's map (in photon-index order) the irradiance
//! `E` is estimated once per frame from that map's `k` nearest photons with the photon's
//! own normal (`PhotonMap::irradiance`: the same filter, radius limit and normal tests as
//! `pm-ic`'s estimate; `k` is `pm-ic`'s unless set, in every group). Every group's
//! estimate then has the count bias of `pm-ic`'s `k`-photon estimate; a group with a share
//! `s` of the photons gets a disc `1/√s` times `pm-ic`'s radius (more blur, the noise of
//! `k` photons). A `k` scaled by the share instead (the group's photons inside `pm-ic`'s
//! disc, at least 16) was tried: it raised the image mean by 1.4 % against `pm-ic` on the
//! moving-light test scene (0.2 % with the same `k`): the `k`-nearest estimate's bias grows
//! as its photon count falls (measured 2026-12-08, the scene of `tests/it/icsel.rs`,
//! frame 0, 60k photons, 32²). A lookup at a
//! gather hit `x` with side normal `n` takes the nearest precomputed point within the
//! lookup's world radius whose normal agrees (`n_p · n ≥ ½`, Jensen's test; the nearest
//! [`NEAREST`], then [`NEAREST_WIDE`], are searched) and returns its `E`; the radiance is
//! `f(wo, n) · E` ([`GatherHit::w`]), exact for a Lambertian surface (`ρ/π · E`).
//!
//! ## Bias (what the tests bound)
//! - The estimate's blur is `pm-ic`'s for a group that has (nearly) all the photons and
//!   wider for the others (radius `r/√s`, above): second order in its radius `r`, as
//!   [`super`] states.
//! - The lookup reads `E` at a point `q` up to the distance to the nearest precomputed
//!   photon away (about `r·√(stride/k)`, the spacing of every `stride`-th of `k`
//!   photons in a disc of radius `r`; never more than the world radius): an extra blur of
//!   the same order, so the kernel's support grows from `r` to at most `2r` and the
//!   second-order blur term at most fourfold.
//! - The radiance treats the incident light at the hit as arriving along the normal:
//!   exact for Lambertian surfaces, off by the non-Lambertian lobe's share elsewhere
//!   (glTF's dielectric coating, F0 = 0.04: a few %), the class of bias [`super`] already
//!   names for non-Lambertian lobes at the eye vertex.
//!
//! Everything is deterministic: photons are traced in chunks merged in index order, the
//! estimates are made per point independently.

use super::PmIcSettings;
use super::photon_map::{Lookup, PhotonMap, StoredPhoton};
use super::world_radius;
use crate::kernels::photon::{PHOTON_CHUNK, trace_photon_path};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::light::Light;
use chronolux_core::math::Vec3;
use chronolux_core::parallel;
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::scene::frame::FrameScene;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZero;

/// Most light groups (and terms kept per gather direction); lights past the first
/// `MAX_GROUPS − 1` groups share the last.
pub const MAX_GROUPS: usize = 4;

/// Precomputed points searched first for one with an agreeing normal.
pub const NEAREST: usize = 4;
/// Searched when none of the first [`NEAREST`] agrees.
pub const NEAREST_WIDE: usize = 16;

/// The group of each of `scene`'s lights (see the module doc), and the number of groups.
pub fn light_groups(scene: &FrameScene) -> (Vec<u8>, usize) {
    let mut keys: Vec<(u8, u64)> = Vec::new();
    let mut out = Vec::with_capacity(scene.lights.len());
    for (i, l) in scene.lights.iter().enumerate() {
        let key = match l {
            Light::Triangle { instance, .. } => (0u8, *instance as u64),
            _ => (1u8, i as u64),
        };
        let g = match keys.iter().position(|k| *k == key) {
            Some(g) => g,
            None => {
                keys.push(key);
                keys.len() - 1
            }
        };
        out.push(g.min(MAX_GROUPS - 1) as u8);
    }
    let n = keys.len().min(MAX_GROUPS);
    (out, n)
}

/// One point with precomputed irradiance.
#[derive(Clone, Copy, Debug)]
struct Point {
    n: Vec3,
    e: Rgb,
}

/// A group's precomputed points (the photons' positions, normals and irradiance).
pub struct PrecomputedMap {
    points: Vec<Point>,
    tree: Option<ImmutableKdTree<f32, 3>>,
}

impl PrecomputedMap {
    /// The irradiance of `map` precomputed at every `stride`-th of its photons (in its
    /// order), each from `lookup.k` nearest photons with the photon's own normal
    /// ([`PhotonMap::irradiance`]: the same filter, radius limit and normal tests).
    pub fn from_map(map: &PhotonMap, lookup: &Lookup, r_max: f32, stride: u32) -> Self {
        let at: Vec<usize> = (0..map.len()).step_by(stride.max(1) as usize).collect();
        let est = parallel::map_chunks(at.len(), 256, |r| {
            at[r]
                .iter()
                .map(|&i| {
                    let p = map.photons()[i];
                    (p.p, p.n, map.irradiance(p.p, p.n, lookup, r_max))
                })
                .collect::<Vec<_>>()
        });
        let est: Vec<(Vec3, Vec3, Rgb)> = est.into_iter().flatten().collect();
        let pts: Vec<[f32; 3]> = est.iter().map(|e| e.0.to_array()).collect();
        let tree = (!pts.is_empty())
            .then(|| ImmutableKdTree::new_from_slice(&pts).expect("finite photon positions"));
        PrecomputedMap {
            points: est.iter().map(|&(_, n, e)| Point { n, e }).collect(),
            tree,
        }
    }

    /// Irradiance of the nearest precomputed point within `r_max` of `x` whose normal
    /// agrees with `n` (`n_p · n ≥ ½`); zero when there is none among the nearest
    /// [`NEAREST_WIDE`]. The nearest point is tried first (one exact nearest-neighbour
    /// query, the common case away from corners), then the nearest [`NEAREST`] and
    /// [`NEAREST_WIDE`].
    pub fn irradiance(&self, x: Vec3, n: Vec3, r_max: f32) -> Rgb {
        let Some(tree) = self.tree.as_ref() else {
            return Rgb::ZERO;
        };
        let q = x.to_array();
        let one = tree
            .query(&q)
            .nearest_one::<SquaredEuclidean<f32>>()
            .execute();
        if one.distance > r_max * r_max {
            return Rgb::ZERO;
        }
        let p = &self.points[one.item as usize];
        if p.n.dot(n) >= 0.5 {
            return p.e;
        }
        for k in [NEAREST, NEAREST_WIDE] {
            let found = tree
                .query(&q)
                .nearest_n::<SquaredEuclidean<f32>>(NonZero::new(k).expect("k ≥ 1"))
                .within(r_max * r_max)
                .execute();
            let mut best: Option<(f32, u64)> = None;
            for f in &found {
                let p = &self.points[f.item as usize];
                if p.n.dot(n) < 0.5 {
                    continue;
                }
                let c = (f.distance, f.item as u64);
                if best.is_none_or(|b| c < b) {
                    best = Some(c);
                }
            }
            if let Some((_, i)) = best {
                return self.points[i as usize].e;
            }
            if found.len() < k {
                // Everything within the radius was seen.
                break;
            }
        }
        Rgb::ZERO
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// The maps of one frame, one per light group.
pub struct GroupMaps {
    /// Group of each light of the frame.
    pub group_of: Vec<u8>,
    pub maps: Vec<PrecomputedMap>,
    /// Stored photons per group.
    pub photons: Vec<usize>,
    /// Photon rays traced.
    pub rays: u64,
    /// World radius of the lookups.
    pub r_max: f32,
}

impl GroupMaps {
    /// Traces the global photons `base .. base + s.photons` of `scene`, splits them by
    /// light group and precomputes the irradiance at every `stride`-th photon of each
    /// group from its `k` nearest photons (0: `s.global.k`, `pm-ic`'s).
    pub fn build(scene: &FrameScene, s: &PmIcSettings, base: u64, stride: u32, k: u32) -> Self {
        let n = s.photons;
        let (group_of, groups) = light_groups(scene);
        let seed = s.common.seed;
        let chunks = parallel::map_chunks(n.div_ceil(PHOTON_CHUNK) as usize, 1, |r| {
            let lo = base + r.start as u64 * PHOTON_CHUNK;
            let hi = (lo + PHOTON_CHUNK).min(base + n);
            let mut out: Vec<(u8, StoredPhoton)> = Vec::new();
            let mut rays = 0u64;
            for i in lo..hi {
                let g = std::cell::Cell::new(0u8);
                rays += trace_photon_path(
                    scene,
                    i,
                    seed,
                    |li, _| g.set(group_of[li]),
                    |v| {
                        if v.deposited {
                            out.push((g.get(), StoredPhoton::from_hit(&v.hit, n)));
                        }
                    },
                    |_| {},
                )
                .rays;
            }
            (out, rays)
        });
        let mut per: Vec<Vec<StoredPhoton>> = vec![Vec::new(); groups];
        let mut rays = 0;
        for (v, r) in chunks {
            rays += r;
            for (g, p) in v {
                per[g as usize].push(p);
            }
        }
        let r_max = world_radius(scene, &s.global);
        let photons: Vec<usize> = per.iter().map(Vec::len).collect();
        let stride = stride.max(1) as usize;
        let maps = per
            .into_iter()
            .map(|ph| {
                let lookup = Lookup {
                    k: if k == 0 { s.global.k } else { k },
                    ..s.global
                };
                PrecomputedMap::from_map(&PhotonMap::build(ph), &lookup, r_max, stride as u32)
            })
            .collect();
        GroupMaps {
            group_of,
            maps,
            photons,
            rays,
            r_max,
        }
    }

    /// Groups.
    pub fn groups(&self) -> usize {
        self.maps.len()
    }

    /// Precomputed points in all groups.
    pub fn points(&self) -> usize {
        self.maps.iter().map(PrecomputedMap::len).sum()
    }

    /// Group `g`'s term at a gather hit: `w · E_g(x)`.
    pub fn term(&self, g: usize, hit: &GatherHit) -> Rgb {
        if hit.w == Rgb::ZERO {
            return Rgb::ZERO;
        }
        hit.w * self.maps[g].irradiance(hit.x, hit.ns, self.r_max)
    }
}

/// Where a gather ray's radiance is read: the first non-delta vertex after the delta
/// chain, with the weight that turns irradiance there into the radiance arriving back at
/// the gather's origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherHit {
    /// The vertex read.
    pub x: Vec3,
    /// Its geometric normal turned towards the ray.
    pub ns: Vec3,
    /// Throughput of the delta chain times `f(wo, ns)` (zero when the chain ended without
    /// a non-delta vertex).
    pub w: Rgb,
    /// Distance to the first hit (of the chain).
    pub dist: f32,
    /// Instance of the first hit.
    pub instance: u32,
}

/// The gather ray of [`super::gather_ray_hit`] (its delta chain, [`super::gather_chain`]:
/// the same numbers drawn from `rng` at every vertex), at the vertex whose radiance it would
/// read: `None`
/// exactly where [`super::gather_ray_hit`] returns `None` (nothing hit, a chain that
/// leaves the scene or whose sampling fails); a chain cut by the depth limit or a zero
/// weight has `w = 0`.
pub fn gather_hit(
    scene: &FrameScene,
    s: &PmIcSettings,
    x: Vec3,
    n: Vec3,
    dir: Vec3,
    rng: &mut Pcg32,
) -> Option<GatherHit> {
    let end = super::gather_chain(scene, s, x, n, dir, rng, |_| {})?;
    let (x, ns) = end.last;
    Some(GatherHit {
        x,
        ns,
        w: end.read.map_or(Rgb::ZERO, |v| {
            v.beta * v.bsdf.f(v.wo, ns, TransportMode::Radiance)
        }),
        dist: end.dist,
        instance: end.instance,
    })
}

impl super::RadianceMap for PrecomputedMap {
    /// `f(wo, n) · E(x)`: the radiance [`GroupMaps::term`] reads (exact for a Lambertian
    /// surface, see the module doc).
    #[inline]
    fn gather_radiance(
        &self,
        x: Vec3,
        n: Vec3,
        wo: Vec3,
        bsdf: &chronolux_core::bsdf::Bsdf,
        _lookup: &Lookup,
        r_max: f32,
    ) -> Rgb {
        bsdf.f(wo, n, TransportMode::Radiance) * self.irradiance(x, n, r_max)
    }
}
