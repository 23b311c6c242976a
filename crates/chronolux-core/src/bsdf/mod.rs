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
//!
//! ## The model (glTF 2.0 appendix B with KHR_materials_specular / _transmission / _ior)
//! `material = mix(dielectric, metal, metallic)`, with one GGX roughness α = roughness²
//! shared by every specular lobe (α < [`microfacet::MIN_ALPHA`] makes them deltas):
//! - **metal**: GGX reflection with Schlick Fresnel, F0 = base colour.
//! - **opaque dielectric** (weight 1 − transmission): a GGX reflection layer with Schlick
//!   Fresnel (F0 = min(f0(ior)·specularColor, 1), F90 = 1) scaled by specularFactor `s`,
//!   over a Lambertian base. Instead of glTF's `1 − s·F(cos θo)` layering weight (which can
//!   exceed energy 1 for rough layers) the base receives exactly what the layer does not
//!   reflect, in a reciprocal form (Kulla–Conty style):
//!   `f_base = ρ/π · (1 − E(μo))(1 − E(μi)) / (1 − E_avg)`, where `E(μ) = s·E_spec(μ)` is the
//!   layer's directional albedo ([`albedo`]) for the largest F0 channel. Then
//!   `∫ f cos = ρ(1 − E(μo)) + E(μo) ≤ 1`, and `s = 0` gives pure Lambert.
//! - **transmitting dielectric** (weight transmission): one rough (Walter et al. 2007) or
//!   smooth dielectric interface of index `ior`; reflection uses the exact dielectric
//!   Fresnel tinted by `s·specularColor`, transmission (1 − F) is tinted by the base colour.
//!
//! All GGX reflection lobes share one microfacet distribution, so they are evaluated and
//! sampled as a single reflection lobe whose Fresnel term is the weighted sum. Sampling
//! chooses among diffuse (cosine), reflection (visible normals, Heitz 2018) and transmission
//! (visible normals, refracted) with probabilities proportional to each lobe's approximate
//! albedo at `wo`; [`Bsdf::pdf`] is the matching mixture.
//!
//! ## Sides, shading normals, adjoint
//! Lobes are evaluated in the shading frame (`frame.n` = shading normal). Opaque lobes are
//! two-sided: when `wo` is below the shading normal both directions are mirrored to the
//! upper side; for the transmitting dielectric this side is "inside" (relative index
//! 1/ior). Whether a pair (wo, wi) is a reflection or a transmission is decided by the
//! **geometric** normal `ng`; a pair the shading frame classifies differently gets f = 0
//! (no light leaks), and sampling such a direction fails.
//! - `TransportMode::Importance` multiplies f (and sample weights) by Veach's adjoint
//!   correction `|wo·ns||wi·ng| / (|wo·ng||wi·ns|)` — here and nowhere else.
//! - Refraction in `Radiance` mode carries the `1/η²` radiance scaling (η = n_t/n_i along
//!   the transmitted direction); `Importance` mode does not (pbrt-v4 convention).

pub mod albedo;
pub mod fresnel;
pub mod microfacet;

use crate::color::Rgb;
use crate::math::{Frame, Vec2, Vec3, refract};
use microfacet::{Ggx, MIN_ALPHA};
use std::f32::consts::FRAC_1_PI;

/// GGX α below which a specular lobe is *near-specular* ([`Bsdf::near_specular`]).
pub const NEAR_SPECULAR_ALPHA: f32 = 0.1;

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

/// The closed set of lobes of the glTF metallic-roughness model (see the module doc).
/// Weights are already multiplied in (textures evaluated); a lobe with zero weight is
/// absent. Build it with [`Lobes::gltf`] or fill the fields directly.
#[derive(Clone, Debug, Default)]
pub struct Lobes {
    /// Lambertian albedo of the opaque dielectric base:
    /// base colour · (1 − metallic) · (1 − transmission).
    pub diffuse: Rgb,
    /// Weight of the opaque dielectric's specular layer:
    /// (1 − metallic) · (1 − transmission) · specularFactor.
    pub specular_weight: f32,
    /// Schlick F0 of that layer: min(f0(ior) · specularColor, 1).
    pub specular_f0: Rgb,
    /// specularFactor: the fraction of the layer's albedo taken from the diffuse base.
    pub specular: f32,
    /// Metallic reflection's Schlick F0 (the base colour).
    pub metal: Rgb,
    /// Weight of the metal lobe (metallic).
    pub metal_weight: f32,
    /// Tint of the light transmitted through the dielectric interface (base colour).
    pub transmission: Rgb,
    /// Weight of the transmitting dielectric: (1 − metallic) · transmission.
    pub transmission_weight: f32,
    /// Tint of the transmitting dielectric's reflection (specularFactor · specularColor).
    pub transmission_specular: Rgb,
    /// GGX roughness α (= perceptual roughness²), shared by the specular lobes; below
    /// [`microfacet::MIN_ALPHA`] they are deltas.
    pub alpha: f32,
    /// Index of refraction of the dielectric (inside / outside).
    pub ior: f32,
    /// Transmittance of the medium segment that ended here (a volume's Beer–Lambert
    /// factor), multiplying every value and sample weight; `None`: 1.
    pub attenuation: Option<Rgb>,
}

impl Lobes {
    /// Lobes of the glTF metallic-roughness model from (texture-multiplied) parameters.
    pub fn gltf(
        base_color: Rgb,
        metallic: f32,
        roughness: f32,
        ior: f32,
        specular: f32,
        specular_color: Rgb,
        transmission: f32,
    ) -> Lobes {
        let m = metallic.clamp(0.0, 1.0);
        let t = transmission.clamp(0.0, 1.0);
        let s = specular.clamp(0.0, 1.0);
        let base = base_color.clamp(Rgb::ZERO, Rgb::ONE);
        let spec_color = specular_color.max(Rgb::ZERO);
        // KHR_materials_ior allows 1 ≤ ior; keep refraction away from the degenerate η = 1.
        let ior = if ior.is_finite() {
            ior.clamp(1.0 + 1e-3, 10.0)
        } else {
            1.5
        };
        let r = roughness.clamp(0.0, 1.0);
        let opaque = (1.0 - m) * (1.0 - t);
        Lobes {
            diffuse: base * opaque,
            specular_weight: opaque * s,
            specular_f0: (fresnel::f0_from_ior(ior) * spec_color).min(Rgb::ONE),
            specular: s,
            metal: base,
            metal_weight: m,
            transmission: base,
            transmission_weight: (1.0 - m) * t,
            transmission_specular: (s * spec_color).min(Rgb::ONE),
            alpha: r * r,
            ior,
            attenuation: None,
        }
    }

    #[inline]
    fn is_delta(&self) -> bool {
        self.alpha < MIN_ALPHA
    }

    #[inline]
    fn has_diffuse(&self) -> bool {
        self.diffuse != Rgb::ZERO
    }

    #[inline]
    fn has_reflection(&self) -> bool {
        self.specular_weight > 0.0
            || self.metal_weight > 0.0
            || (self.transmission_weight > 0.0 && self.transmission_specular != Rgb::ZERO)
    }

    #[inline]
    fn has_transmission(&self) -> bool {
        self.transmission_weight > 0.0 && self.transmission != Rgb::ZERO
    }

    /// Directional albedo of the specular layer over the diffuse base (scaled by `s`).
    #[inline]
    fn layer_albedo(&self, mu: f32) -> f32 {
        if self.specular <= 0.0 {
            return 0.0;
        }
        let a = if self.is_delta() { 0.0 } else { self.alpha };
        let [ea, eb] = albedo::albedo_ab(mu, a);
        let f0 = self.specular_f0.max_element();
        self.specular * (eb + f0 * (ea - eb))
    }

    #[inline]
    fn layer_albedo_avg(&self) -> f32 {
        if self.specular <= 0.0 {
            return 0.0;
        }
        let a = if self.is_delta() { 0.0 } else { self.alpha };
        let [ea, eb] = albedo::albedo_avg_ab(a);
        let f0 = self.specular_f0.max_element();
        self.specular * (eb + f0 * (ea - eb))
    }

    /// Sum of the reflection lobes' Fresnel terms at microfacet cosine `c`; `eta` is the
    /// relative index across the interface seen from the `wo` side.
    #[inline]
    fn fresnel_reflect(&self, c: f32, eta: f32) -> Rgb {
        let mut f = Rgb::ZERO;
        if self.specular_weight > 0.0 {
            f += self.specular_weight * fresnel::schlick(self.specular_f0, c);
        }
        if self.metal_weight > 0.0 {
            f += self.metal_weight * fresnel::schlick(self.metal, c);
        }
        if self.transmission_weight > 0.0 && self.transmission_specular != Rgb::ZERO {
            f +=
                self.transmission_weight * self.transmission_specular * fresnel::dielectric(c, eta);
        }
        f
    }

    /// What depends on `wo` alone (local, upper side), computed once per query and shared
    /// by the value and the pdf: the specular layer's albedo at `wo` (the diffuse base's
    /// `1 − E(μo)`) and the lobe selection probabilities. Only evaluated where it is used
    /// (the layer albedo only with a diffuse base), so the numbers are those each part
    /// computed on its own before.
    #[inline]
    fn wo_terms(&self, wo: Vec3, eta: f32) -> WoTerms {
        let layer_wo = self.layer_wo(wo);
        WoTerms {
            layer_wo,
            p: self.probabilities(wo, eta, layer_wo),
        }
    }

    /// [`WoTerms::layer_wo`]: the layer albedo at `wo` where a diffuse base uses it, else 0.
    #[inline]
    fn layer_wo(&self, wo: Vec3) -> f32 {
        if self.has_diffuse() {
            self.layer_albedo(wo.z)
        } else {
            0.0
        }
    }

    /// Lobe selection probabilities (diffuse, reflection, transmission) at `wo` (local,
    /// upper side); `layer_wo` = [`Lobes::layer_albedo`] at `wo.z` (used with a diffuse
    /// base only).
    fn probabilities(&self, wo: Vec3, eta: f32, layer_wo: f32) -> [f32; 3] {
        let avg = |c: Rgb| (c.x + c.y + c.z) / 3.0;
        let c = wo.z;
        let delta = self.is_delta();
        let mut w = [0.0f32; 3];
        if self.has_diffuse() {
            // Floor: a non-delta lobe that f() can return must keep a non-zero probability.
            w[0] = (avg(self.diffuse) * (1.0 - layer_wo)).max(1e-4);
        }
        if self.has_reflection() {
            w[1] = avg(self.fresnel_reflect(c, eta));
            if !delta {
                w[1] = w[1].max(1e-4);
            }
        }
        if self.has_transmission() {
            w[2] = self.transmission_weight
                * avg(self.transmission)
                * (1.0 - fresnel::dielectric(c, eta));
            if !delta {
                // Rough interfaces transmit through tilted microfacets even past the
                // critical angle of the macro-surface.
                w[2] = w[2].max(1e-4);
            }
        }
        let sum = w[0] + w[1] + w[2];
        if sum.is_nan() || sum <= 0.0 {
            return [0.0; 3];
        }
        w.map(|x| x / sum)
    }

    /// Value of the non-delta lobes (local frame, `wo.z > 0`), without cosine; `t` =
    /// [`Lobes::wo_terms`] at `wo`.
    fn f_local(&self, t: &WoTerms, wo: Vec3, wi: Vec3, eta: f32, radiance: bool) -> Rgb {
        let mut f = Rgb::ZERO;
        if wi.z > 0.0 {
            if self.has_diffuse() {
                let denom = 1.0 - self.layer_albedo_avg();
                if denom > 1e-6 {
                    let k = (1.0 - t.layer_wo) * (1.0 - self.layer_albedo(wi.z)) / denom;
                    f += self.diffuse * (FRAC_1_PI * k.max(0.0));
                }
            }
            if !self.is_delta() && self.has_reflection() {
                let m = wo + wi;
                if m.length_squared() > 0.0 {
                    let m = m.normalize();
                    let g = Ggx::new(self.alpha);
                    let fr = self.fresnel_reflect(wo.dot(m), eta);
                    f += fr * (g.d(m) * g.g(wo, wi) / (4.0 * wo.z * wi.z));
                }
            }
        } else if wi.z < 0.0
            && !self.is_delta()
            && self.has_transmission()
            && let Some((m, _)) = self.half_vector_t(wo, wi, eta)
        {
            let g = Ggx::new(self.alpha);
            let (dwm, dom) = (wi.dot(m), wo.dot(m));
            let denom = (dwm + dom / eta) * (dwm + dom / eta);
            let fr = fresnel::dielectric(dom, eta);
            let mut ft =
                (1.0 - fr) * g.d(m) * g.g(wo, wi) * (dwm * dom / (wi.z * wo.z * denom)).abs();
            if radiance {
                ft /= eta * eta;
            }
            f += self.transmission * (self.transmission_weight * ft);
        }
        f
    }

    /// Generalised half vector of a refraction pair, facing +Z, if the pair is valid (not
    /// through a back-facing microfacet). Also returns the Jacobian dωm/dωi.
    #[inline]
    fn half_vector_t(&self, wo: Vec3, wi: Vec3, eta: f32) -> Option<(Vec3, f32)> {
        let m = wo + wi * eta;
        if m.length_squared().is_nan() || m.length_squared() <= 0.0 {
            return None;
        }
        let mut m = m.normalize();
        if m.z < 0.0 {
            m = -m;
        }
        let (dwm, dom) = (wi.dot(m), wo.dot(m));
        if dwm >= 0.0 || dom <= 0.0 {
            return None;
        }
        let denom = (dwm + dom / eta) * (dwm + dom / eta);
        Some((m, dwm.abs() / denom))
    }

    /// Combined solid-angle pdf of the non-delta lobes (local frame, `wo.z > 0`); `t` =
    /// [`Lobes::wo_terms`] at `wo`.
    fn pdf_local(&self, t: &WoTerms, wo: Vec3, wi: Vec3, eta: f32) -> f32 {
        let p = t.p;
        let delta = self.is_delta();
        let mut pdf = 0.0;
        if wi.z > 0.0 {
            if p[0] > 0.0 {
                pdf += p[0] * wi.z * FRAC_1_PI;
            }
            if !delta && p[1] > 0.0 {
                let m = (wo + wi).normalize();
                let g = Ggx::new(self.alpha);
                pdf += p[1] * g.pdf_visible(wo, m) / (4.0 * wo.dot(m));
            }
        } else if wi.z < 0.0
            && !delta
            && p[2] > 0.0
            && let Some((m, jac)) = self.half_vector_t(wo, wi, eta)
        {
            pdf += p[2] * Ggx::new(self.alpha).pdf_visible(wo, m) * jac;
        }
        pdf
    }
}

/// [`Lobes::wo_terms`]: the parts of a query that depend on `wo` only.
struct WoTerms {
    layer_wo: f32,
    p: [f32; 3],
}

/// `wo`, `wi` in the local frame mirrored so that `wo.z > 0`, and the relative index seen
/// from `wo`'s side.
struct Local {
    wo: Vec3,
    flip: bool,
    eta: f32,
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

    /// True when the BSDF has a specular lobe (the dielectric's specular layer, metal or
    /// transmission, with non-zero weight) whose GGX α is below [`NEAR_SPECULAR_ALPHA`]
    /// (deltas, α < [`MIN_ALPHA`], included). Such a lobe is narrow: a direction sampled
    /// from it for one view direction `wo` is where `f(wo, ·)` peaks, and for another view
    /// `wo'` the weight `f(wo', wi)/pdf(wo, wi)` has a huge variance. Techniques that reuse
    /// a direction sampled for one view with another view (stbpt's reuse when the camera
    /// moves) must not do it at such a surface. A property of the lobes only: independent
    /// of the shading frame and of any direction.
    pub fn near_specular(&self) -> bool {
        let lo = &self.lobes;
        (lo.specular_weight > 0.0 || lo.metal_weight > 0.0 || lo.transmission_weight > 0.0)
            && lo.alpha < NEAR_SPECULAR_ALPHA
    }

    /// True when the BSDF has a *glossy* specular lobe: the dielectric's specular layer,
    /// metal or transmission with non-zero weight, rough enough not to be a delta
    /// (α ≥ [`MIN_ALPHA`]) and with GGX α below `max_alpha` (`f32::INFINITY`: every rough
    /// one). Light reflected by such a lobe is far from the uniform reading a diffuse
    /// surface allows, so eye paths continue through it by sampling it. A property of the
    /// lobes only, as [`Self::near_specular`].
    pub fn is_glossy(&self, max_alpha: f32) -> bool {
        let lo = &self.lobes;
        (lo.specular_weight > 0.0 || lo.metal_weight > 0.0 || lo.transmission_weight > 0.0)
            && lo.alpha >= MIN_ALPHA
            && lo.alpha < max_alpha
    }

    /// True if some lobe is not a delta distribution (light sampling can help).
    pub fn has_non_delta(&self) -> bool {
        let l = &self.lobes;
        l.has_diffuse() || (!l.is_delta() && (l.has_reflection() || l.has_transmission()))
    }

    #[inline]
    fn local(&self, lo: Vec3) -> Local {
        let flip = lo.z < 0.0;
        let ior = if self.lobes.ior > 0.0 {
            self.lobes.ior
        } else {
            1.5
        };
        Local {
            wo: if flip { mirror(lo) } else { lo },
            flip,
            eta: if flip { 1.0 / ior } else { ior },
        }
    }

    /// Veach's adjoint correction for shading normals, |wo·ns||wi·ng| / (|wo·ng||wi·ns|).
    #[inline]
    fn adjoint(&self, wo: Vec3, wi: Vec3, lo: Vec3, li: Vec3) -> f32 {
        let d = wo.dot(self.ng).abs() * li.z.abs();
        if d == 0.0 {
            0.0
        } else {
            lo.z.abs() * wi.dot(self.ng).abs() / d
        }
    }

    /// True when the geometric normal agrees with the shading frame on whether (wo, wi) is
    /// a reflection or a transmission.
    #[inline]
    fn sides_agree(&self, wo: Vec3, wi: Vec3, lo: Vec3, li: Vec3) -> bool {
        let g = wo.dot(self.ng) * wi.dot(self.ng);
        let s = lo.z * li.z;
        (g > 0.0 && s > 0.0) || (g < 0.0 && s < 0.0)
    }

    /// BSDF value without the cosine factor; zero for delta lobes.
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        let (lo, li) = (self.frame.to_local(wo), self.frame.to_local(wi));
        if lo.z == 0.0 || li.z == 0.0 || !self.sides_agree(wo, wi, lo, li) {
            return Rgb::ZERO;
        }
        let l = self.local(lo);
        let li_l = if l.flip { mirror(li) } else { li };
        // The value needs the layer albedo at `wo`, not the selection probabilities.
        let t = WoTerms {
            layer_wo: self.lobes.layer_wo(l.wo),
            p: [0.0; 3],
        };
        self.f_mode(&t, &l, li_l, wo, wi, lo, li, mode)
    }

    /// [`Bsdf::f`] from the local directions: the lobes' value, the medium's attenuation
    /// and, for importance, the adjoint correction.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn f_mode(
        &self,
        t: &WoTerms,
        l: &Local,
        li_l: Vec3,
        wo: Vec3,
        wi: Vec3,
        lo: Vec3,
        li: Vec3,
        mode: TransportMode,
    ) -> Rgb {
        let mut f = self
            .lobes
            .f_local(t, l.wo, li_l, l.eta, mode == TransportMode::Radiance);
        if let Some(t) = self.lobes.attenuation {
            f *= t;
        }
        match mode {
            TransportMode::Radiance => f,
            TransportMode::Importance => f * self.adjoint(wo, wi, lo, li),
        }
    }

    /// Solid-angle pdf of sampling `wi` given `wo`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (lo, li) = (self.frame.to_local(wo), self.frame.to_local(wi));
        if lo.z == 0.0 || li.z == 0.0 {
            return 0.0;
        }
        let l = self.local(lo);
        let li_l = if l.flip { mirror(li) } else { li };
        let t = self.lobes.wo_terms(l.wo, l.eta);
        self.lobes.pdf_local(&t, l.wo, li_l, l.eta)
    }

    /// [`Bsdf::f`] and [`Bsdf::pdf`] of one pair in one pass (the frame change and what
    /// depends on `wo` computed once), equal to the two calls' values bit for bit. For
    /// next-event estimation, which needs both for its MIS weight.
    pub fn f_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (Rgb, f32) {
        let (lo, li) = (self.frame.to_local(wo), self.frame.to_local(wi));
        if lo.z == 0.0 || li.z == 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let l = self.local(lo);
        let li_l = if l.flip { mirror(li) } else { li };
        let t = self.lobes.wo_terms(l.wo, l.eta);
        let pdf = self.lobes.pdf_local(&t, l.wo, li_l, l.eta);
        if !self.sides_agree(wo, wi, lo, li) {
            return (Rgb::ZERO, pdf);
        }
        (self.f_mode(&t, &l, li_l, wo, wi, lo, li, mode), pdf)
    }

    /// Samples `wi` given `wo`; `u_lobe` chooses the lobe, `u` the direction.
    pub fn sample(
        &self,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        let lo = self.frame.to_local(wo);
        if lo.z == 0.0 || !lo.is_finite() {
            return None;
        }
        let l = self.local(lo);
        let lobes = &self.lobes;
        let t = lobes.wo_terms(l.wo, l.eta);
        let p = t.p;
        let lobe = if u_lobe < p[0] {
            0
        } else if u_lobe < p[0] + p[1] || p[2] == 0.0 {
            if p[1] > 0.0 { 1 } else { 0 }
        } else {
            2
        };
        if p[lobe] <= 0.0 {
            return None;
        }
        let delta = lobe != 0 && lobes.is_delta();
        let radiance = mode == TransportMode::Radiance;
        // Direction in the mirrored local frame, and for deltas the value f·|cos θi|.
        let (li_l, delta_value) = match lobe {
            0 => (
                crate::sampling::warps::sample_cosine_hemisphere(u),
                Rgb::ZERO,
            ),
            1 if delta => {
                let wi = Vec3::new(-l.wo.x, -l.wo.y, l.wo.z);
                (wi, lobes.fresnel_reflect(l.wo.z, l.eta))
            }
            1 => {
                let m = Ggx::new(lobes.alpha).sample_visible(l.wo, u);
                let wi = 2.0 * l.wo.dot(m) * m - l.wo;
                if wi.z <= 0.0 {
                    return None;
                }
                (wi, Rgb::ZERO)
            }
            _ if delta => {
                let wi = refract(l.wo, Vec3::Z, l.eta)?;
                let mut t = lobes.transmission_weight * (1.0 - fresnel::dielectric(l.wo.z, l.eta));
                if radiance {
                    t /= l.eta * l.eta;
                }
                (wi, lobes.transmission * t)
            }
            _ => {
                let m = Ggx::new(lobes.alpha).sample_visible(l.wo, u);
                let wi = refract(l.wo, m, l.eta)?;
                if wi.z >= 0.0 {
                    return None;
                }
                (wi, Rgb::ZERO)
            }
        };
        let is_transmission = li_l.z < 0.0;
        let wi = self
            .frame
            .from_local(if l.flip { mirror(li_l) } else { li_l })
            .normalize();
        // Evaluate f and pdf on the direction handed out, exactly as `f()`/`pdf()` will (near
        // the critical angle the Fresnel term is ill-conditioned under rounding).
        let li = self.frame.to_local(wi);
        let li_l = if l.flip { mirror(li) } else { li };
        if li.z == 0.0 || (li_l.z < 0.0) != is_transmission || !self.sides_agree(wo, wi, lo, li) {
            return None;
        }
        let eta = if is_transmission { l.eta } else { 1.0 };
        if delta {
            let mut weight = delta_value / p[lobe];
            if let Some(t) = lobes.attenuation {
                weight *= t;
            }
            if mode == TransportMode::Importance {
                weight *= self.adjoint(wo, wi, lo, li);
            }
            return Some(BsdfSample {
                wi,
                weight,
                pdf: p[lobe],
                is_delta: true,
                is_transmission,
                eta,
            });
        }
        let pdf = lobes.pdf_local(&t, l.wo, li_l, l.eta);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let mut f = lobes.f_local(&t, l.wo, li_l, l.eta, radiance);
        if let Some(t) = lobes.attenuation {
            f *= t;
        }
        if mode == TransportMode::Importance {
            f *= self.adjoint(wo, wi, lo, li);
        }
        Some(BsdfSample {
            wi,
            weight: f * (li.z.abs() / pdf),
            pdf,
            is_delta: false,
            is_transmission,
            eta,
        })
    }
}

#[inline]
fn mirror(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}
