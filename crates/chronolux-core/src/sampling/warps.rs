//! Warps from the unit square, in `sample_*` / `*_pdf` triples with the measure stated.

use crate::math::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

/// Uniform point on the unit disk (Shirley–Chiu concentric map).
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction on the +Z hemisphere.
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// pdf of [`sample_cosine_hemisphere`] w.r.t. solid angle.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the unit sphere.
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// pdf of [`sample_uniform_sphere`] w.r.t. solid angle.
pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// Uniform direction in the cone around +Z with cos half-angle `cos_max`.
pub fn sample_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = (1.0 - u.x) + u.x * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(phi.cos() * sin_t, phi.sin() * sin_t, cos_t)
}

/// pdf of [`sample_uniform_cone`] w.r.t. solid angle.
#[inline]
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentric coordinates (b0, b1) on a triangle (Heitz 2019 low-distortion map);
/// b2 = 1 − b0 − b1. pdf w.r.t. area is 1 / area.
pub fn sample_uniform_triangle(u: Vec2) -> (f32, f32) {
    let (b0, b1);
    if u.x < u.y {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    (b0, b1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    #[test]
    fn warps_land_in_their_domain() {
        let mut r = Pcg32::new(1, 2);
        for _ in 0..10_000 {
            let u = Vec2::new(r.next_f32(), r.next_f32());
            assert!(sample_concentric_disk(u).length() <= 1.0 + 1e-6);
            let d = sample_cosine_hemisphere(u);
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
            assert!((sample_uniform_sphere(u).length() - 1.0).abs() < 1e-5);
            let c = sample_uniform_cone(u, 0.8);
            assert!(c.z >= 0.8 - 1e-6);
            let (b0, b1) = sample_uniform_triangle(u);
            assert!(b0 >= 0.0 && b1 >= 0.0 && b0 + b1 <= 1.0 + 1e-6);
        }
    }
}
