//! Fresnel reflectance: exact unpolarised dielectric and Schlick's approximation.

use crate::color::Rgb;
use crate::math::safe_sqrt;

/// Unpolarised Fresnel reflectance of a dielectric interface (pbrt-v4 `FrDielectric`).
/// `cos_i` is the cosine of the incident direction with the normal on the *outside*
/// (negative: the direction is inside), `eta` = n_inside / n_outside. Returns 1 on total
/// internal reflection.
#[inline]
pub fn dielectric(cos_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (r_parl * r_parl + r_perp * r_perp) * 0.5
}

/// Schlick's weight (1 − cos)^5 for `cos` in [0, 1].
#[inline]
pub fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos.abs()).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's approximation with reflectance `f0` at normal incidence and 1 at grazing.
#[inline]
pub fn schlick(f0: Rgb, cos: f32) -> Rgb {
    f0 + (Rgb::ONE - f0) * schlick_weight(cos)
}

/// Normal-incidence reflectance of a dielectric of index `ior` against vacuum.
#[inline]
pub fn f0_from_ior(ior: f32) -> f32 {
    let r = (ior - 1.0) / (ior + 1.0);
    r * r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_limits() {
        // Normal incidence: ((η−1)/(η+1))²; f32 rounding only.
        assert!((dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
        // Total internal reflection from inside beyond the critical angle asin(1/1.5).
        assert_eq!(dielectric(-0.5, 1.5), 1.0);
        assert!(dielectric(-0.9, 1.5) < 1.0);
        assert!((schlick(Rgb::splat(0.04), 1.0).x - 0.04).abs() < 1e-7);
        assert!((f0_from_ior(1.5) - 0.04).abs() < 1e-7);
    }
}
