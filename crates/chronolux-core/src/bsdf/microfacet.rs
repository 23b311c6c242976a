//! Isotropic Trowbridge–Reitz (GGX) microfacet distribution with height-correlated Smith
//! masking-shadowing and visible-normal sampling (Heitz 2018, "Sampling the GGX
//! Distribution of Visible Normals"). All directions are in the local shading frame
//! (normal +Z) and unit length.

use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

/// Smallest α used by rough lobes; below it a lobe is treated as a delta (mirror/smooth).
pub const MIN_ALPHA: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha: f32,
}

impl Ggx {
    #[inline]
    pub fn new(alpha: f32) -> Self {
        Ggx {
            alpha: alpha.max(MIN_ALPHA),
        }
    }

    /// Normal distribution D(m) (zero below the macro-surface), normalised so that ∫ D(m) cos θm dωm = 1.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let c2 = m.z * m.z;
        let a2 = self.alpha * self.alpha;
        let t = c2 * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    }

    /// Smith Λ(w).
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let c2 = w.z * w.z;
        if c2 <= 0.0 {
            return f32::INFINITY;
        }
        let tan2 = ((1.0 - c2) / c2).max(0.0);
        0.5 * (-1.0 + (1.0 + self.alpha * self.alpha * tan2).sqrt())
    }

    /// Masking G1(w).
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G2(wo, wi).
    #[inline]
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of visible normals D_wo(m) = G1(wo) max(0, wo·m) D(m) / |cos θo| (solid angle
    /// of m).
    #[inline]
    pub fn pdf_visible(&self, wo: Vec3, m: Vec3) -> f32 {
        let dot = wo.dot(m);
        if dot <= 0.0 || wo.z == 0.0 {
            return 0.0;
        }
        self.g1(wo) * dot * self.d(m) / wo.z.abs()
    }

    /// Samples a visible normal for `wo` (which must have `wo.z > 0`), Heitz 2018.
    #[inline]
    pub fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let a = self.alpha;
        let vh = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 1e-14 {
            Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let (sp, cp) = phi.sin_cos();
        let p1 = r * cp;
        let mut p2 = r * sp;
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;
    use crate::sampling::warps::{UNIFORM_SPHERE_PDF, sample_uniform_sphere};

    #[test]
    fn d_and_visible_normals_are_normalised() {
        let mut r = Pcg32::new(7, 0);
        for alpha in [0.05f32, 0.3, 1.0] {
            let g = Ggx::new(alpha);
            let wo = Vec3::new(0.6, 0.0, 0.8);
            // Stratified uniform-sphere estimates of ∫ D cos and ∫ D_wo; the 1e-2 absolute
            // tolerance is ~5 standard errors for 2^18 samples at α = 0.05 (the peakiest).
            let n = 1 << 18;
            let (mut s1, mut s2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let m = sample_uniform_sphere(Vec2::new(r.next_f32(), r.next_f32()));
                s1 += (g.d(m) * m.z.max(0.0) / UNIFORM_SPHERE_PDF) as f64;
                s2 += (g.pdf_visible(wo, m) / UNIFORM_SPHERE_PDF) as f64;
            }
            let tol = if alpha < 0.1 { 5e-2 } else { 1e-2 };
            assert!(
                (s1 / n as f64 - 1.0).abs() < tol,
                "∫D cos = {} for α {alpha}",
                s1 / n as f64
            );
            assert!(
                (s2 / n as f64 - 1.0).abs() < tol,
                "∫D_wo = {} for α {alpha}",
                s2 / n as f64
            );
        }
    }
}
