//! Photon maps (Jensen 1996): photons stored at their surface hits, looked up by the k
//! nearest within a maximum radius in a k-d tree (`kiddo`'s `ImmutableKdTree<f32, 3>`,
//! the fastest k-NN-within-radius measured in ../shared/DEPENDENCIES.md §5), and turned
//! into irradiance or reflected-radiance estimates with a cone or Epanechnikov filter.
//!
//! ## Estimate
//! For a query at `x` with (side-oriented) normal `n`, the `k` nearest photons within
//! `r_max` are found; photons that arrived from the other side (`wi·n ≤ 0`) or lie on a
//! surface whose normal differs by more than 60° (`n_p·n < ½`, Jensen's test against
//! leaking across corners) are discarded. The disc radius `r` is the distance of the
//! k-th photon when `k` were found, else `r_max`. With per-photon flux `Φ_p` (power / photons
//! emitted) and kernel weights normalised over the disc:
//!
//! - cone filter (Jensen 2001 eq. 7.40), `w = 1 − d/(κ r)`:
//!   `L ≈ Σ f(wo, wi_p) Φ_p w_p / ((1 − 2/(3κ)) π r²)`;
//! - Epanechnikov, `w = 1 − d²/r²`: `L ≈ Σ f Φ_p w_p / (½ π r²)`.
//!
//! Irradiance is the same sum with `f = 1`. The bias is the kernel's blur over `r` (of
//! order `r²·∇²E`), plus the boundary bias where the disc leaves the surface.
//!
//! ## Negative photons
//! Flux may be negative (the dynamic map of `ic-static-dynamic` holds photons removed by a
//! moving object, [`cancel_twins`]); the estimates are linear in the flux, so a negative
//! photon at the same place as its positive twin cancels it. To make that cancellation
//! exact rather than up to rounding, twins are removed before the tree is built.

use chronolux_core::bsdf::{Bsdf, TransportMode};
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::math::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZero;

/// One stored photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StoredPhoton {
    pub p: Vec3,
    /// Unit direction towards where the photon came from.
    pub wi: Vec3,
    /// Geometric normal at the hit, turned to the side the photon arrived on.
    pub n: Vec3,
    /// Flux of this photon (already divided by the photons emitted; negative for a
    /// negative photon).
    pub flux: Rgb,
}

impl StoredPhoton {
    /// The photon of a kernel hit, with `flux = power / emitted`.
    pub fn from_hit(h: &crate::kernels::photon::PhotonHit, emitted: u64) -> Self {
        let n = if h.wi.dot(h.ng) >= 0.0 { h.ng } else { -h.ng };
        StoredPhoton {
            p: h.p,
            wi: h.wi,
            n,
            flux: h.power / emitted.max(1) as f32,
        }
    }

    /// The same photon with its flux negated.
    pub fn negated(self) -> Self {
        StoredPhoton {
            flux: -self.flux,
            ..self
        }
    }

    /// Bitwise identity (twins of a negative photon are found by it).
    fn key(&self) -> [u32; 12] {
        let v = [
            self.p.x,
            self.p.y,
            self.p.z,
            self.wi.x,
            self.wi.y,
            self.wi.z,
            self.n.x,
            self.n.y,
            self.n.z,
            self.flux.x,
            self.flux.y,
            self.flux.z,
        ];
        v.map(f32::to_bits)
    }
}

/// Removes every pair (positive photon, negative photon with exactly the negated flux at
/// exactly the same position, direction and normal), keeping the order of the rest. The
/// map of the rest gives bit-identical estimates to a map that never held the pair.
pub fn cancel_twins(photons: Vec<StoredPhoton>) -> Vec<StoredPhoton> {
    use std::collections::HashMap;
    let mut negatives: HashMap<[u32; 12], Vec<usize>> = HashMap::new();
    for (i, p) in photons.iter().enumerate() {
        if p.flux.x < 0.0 || p.flux.y < 0.0 || p.flux.z < 0.0 {
            negatives.entry(p.negated().key()).or_default().push(i);
        }
    }
    if negatives.is_empty() {
        return photons;
    }
    let mut dead = vec![false; photons.len()];
    for (i, p) in photons.iter().enumerate() {
        if dead[i] || p.flux.x < 0.0 || p.flux.y < 0.0 || p.flux.z < 0.0 {
            continue;
        }
        if let Some(list) = negatives.get_mut(&p.key())
            && let Some(j) = list.pop()
        {
            dead[i] = true;
            dead[j] = true;
        }
    }
    photons
        .into_iter()
        .zip(dead)
        .filter_map(|(p, d)| (!d).then_some(p))
        .collect()
}

/// The density-estimation kernel.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, tag = "kind", rename_all = "lowercase")]
pub enum MapFilter {
    /// Jensen's cone filter `w = 1 − d/(κ r)`, κ ≥ 1.
    Cone { k: f32 },
    /// `w = 1 − d²/r²`.
    Epanechnikov,
}

impl MapFilter {
    #[inline]
    fn weight(&self, d2: f32, r2: f32) -> f32 {
        match *self {
            MapFilter::Cone { k } => (1.0 - (d2 / r2).sqrt() / k).max(0.0),
            MapFilter::Epanechnikov => (1.0 - d2 / r2).max(0.0),
        }
    }

    /// ∫ w dA over the disc of radius r, divided by r².
    #[inline]
    fn norm(&self) -> f32 {
        match *self {
            MapFilter::Cone { k } => (1.0 - 2.0 / (3.0 * k)) * std::f32::consts::PI,
            MapFilter::Epanechnikov => 0.5 * std::f32::consts::PI,
        }
    }
}

/// How a map is queried.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lookup {
    /// Photons per estimate.
    pub k: u32,
    /// Largest disc radius, as a fraction of the scene's bounding-sphere radius.
    pub max_radius: f32,
    pub filter: MapFilter,
}

/// A photon map.
pub struct PhotonMap {
    photons: Vec<StoredPhoton>,
    tree: Option<ImmutableKdTree<f32, 3>>,
}

impl PhotonMap {
    /// A map of `photons` (built once; queries are read-only and thread-safe).
    pub fn build(photons: Vec<StoredPhoton>) -> Self {
        let pts: Vec<[f32; 3]> = photons.iter().map(|p| p.p.to_array()).collect();
        let tree = if pts.is_empty() {
            None
        } else {
            Some(ImmutableKdTree::new_from_slice(&pts).expect("finite photon positions"))
        };
        PhotonMap { photons, tree }
    }

    pub fn empty() -> Self {
        PhotonMap {
            photons: Vec::new(),
            tree: None,
        }
    }

    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    pub fn photons(&self) -> &[StoredPhoton] {
        &self.photons
    }

    /// The k-nearest gather shared by the estimates: visits every photon within `r_max`
    /// of `x` among the `lookup.k` nearest that arrived on the side of `n` (`wi · n > 0`)
    /// on a surface facing the same way (`n_photon · n ≥ 0.5`) with its filter weight, and
    /// returns the kernel's area `norm · r²` (r² the k-th distance², or `r_max²` when
    /// fewer than k were found); `None` when nothing was found.
    fn gather(
        &self,
        x: Vec3,
        n: Vec3,
        lookup: &Lookup,
        r_max: f32,
        mut visit: impl FnMut(&StoredPhoton, f32),
    ) -> Option<f32> {
        let tree = self.tree.as_ref()?;
        let k = NonZero::new(lookup.k.max(1) as usize).expect("k ≥ 1");
        let found = tree
            .query(&x.to_array())
            .nearest_n::<SquaredEuclidean<f32>>(k)
            .within(r_max * r_max)
            .execute();
        if found.is_empty() {
            return None;
        }
        let r2 = if found.len() >= k.get() {
            found
                .iter()
                .map(|f| f.distance)
                .fold(0.0f32, f32::max)
                .max(1e-12)
        } else {
            r_max * r_max
        };
        for f in &found {
            let ph = &self.photons[f.item as usize];
            if ph.wi.dot(n) <= 0.0 || ph.n.dot(n) < 0.5 {
                continue;
            }
            visit(ph, lookup.filter.weight(f.distance, r2));
        }
        Some(lookup.filter.norm() * r2)
    }

    /// `Σ g(photon) w / (norm r²)` over the accepted photons around `x` (normal `n`),
    /// `r_max` in world units.
    pub fn estimate(
        &self,
        x: Vec3,
        n: Vec3,
        lookup: &Lookup,
        r_max: f32,
        g: impl Fn(&StoredPhoton) -> Rgb,
    ) -> Rgb {
        let mut sum = Rgb::ZERO;
        let area = self.gather(x, n, lookup, r_max, |ph, w| {
            if w > 0.0 {
                sum += g(ph) * (ph.flux * w);
            }
        });
        area.map_or(Rgb::ZERO, |a| sum / a)
    }

    /// Luminance of the (signed) irradiance estimate at `x` and an upper bound of its
    /// standard deviation: with `w ≤ 1` (both filters), `Var Ê = Σ (Φ_i w_i)² / (norm r²)²
    /// ≤ Σ Φ_i² w_i / (norm r²)²` for independent photons, luminances `Φ_i`.
    pub fn irradiance_with_noise(
        &self,
        x: Vec3,
        n: Vec3,
        lookup: &Lookup,
        r_max: f32,
    ) -> (f32, f32) {
        let (mut sum, mut sq) = (0.0f32, 0.0f32);
        let area = self.gather(x, n, lookup, r_max, |ph, w| {
            let l = luminance(ph.flux);
            sum += l * w;
            sq += l * l * w;
        });
        area.map_or((0.0, 0.0), |a| (sum / a, sq.sqrt() / a))
    }

    /// Irradiance at `x` (side normal `n`).
    pub fn irradiance(&self, x: Vec3, n: Vec3, lookup: &Lookup, r_max: f32) -> Rgb {
        self.estimate(x, n, lookup, r_max, |_| Rgb::ONE)
    }

    /// Radiance reflected towards `wo` by `bsdf` at `x` (side normal `n`).
    pub fn radiance(
        &self,
        x: Vec3,
        n: Vec3,
        wo: Vec3,
        bsdf: &Bsdf,
        lookup: &Lookup,
        r_max: f32,
    ) -> Rgb {
        self.estimate(x, n, lookup, r_max, |ph| {
            bsdf.f(wo, ph.wi, TransportMode::Radiance)
        })
    }
}
