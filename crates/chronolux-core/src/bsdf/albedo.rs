//! Directional albedo of the GGX specular layer, used to give the diffuse base exactly the
//! energy the layer does not reflect.
//!
//! With Schlick's Fresnel F = f0 + (1 − f0)(1 − cos)^5 the single-scattering albedo of a
//! GGX reflection lobe is linear in f0: E(μ) = B(μ, α) + f0 (A(μ, α) − B(μ, α)), where
//! A is the albedo with F = 1 and B the albedo weighted by (1 − wo·m)^5. Both are
//! tabulated once (deterministic stratified quadrature over visible normals, where the
//! integrand is G2/G1) on a grid over μ = cos θo and r = √α, with the mirror limit (α = 0:
//! A = 1, B = (1 − μ)^5) as the first column, and read with bilinear interpolation. The
//! cosine-weighted hemispherical averages 2∫E(μ)μ dμ are tabulated per r.

use super::fresnel::schlick_weight;
use super::microfacet::Ggx;
use crate::math::{Vec2, Vec3};
use std::sync::OnceLock;

const N_MU: usize = 32;
const N_R: usize = 32;
/// Stratified samples per axis per table entry.
const STRATA: usize = 24;

struct Tables {
    /// [r][mu] → (A, B)
    e: Vec<[f32; 2]>,
    /// [r] → (A_avg, B_avg)
    avg: Vec<[f32; 2]>,
}

fn mu_at(i: usize) -> f32 {
    (i as f32 / (N_MU - 1) as f32).max(1e-4)
}

fn compute() -> Tables {
    let mut e = vec![[0.0f32; 2]; N_MU * N_R];
    for j in 0..N_R {
        let r = j as f32 / (N_R - 1) as f32;
        for i in 0..N_MU {
            let mu = mu_at(i);
            if j == 0 {
                e[j * N_MU + i] = [1.0, schlick_weight(mu)];
                continue;
            }
            let g = Ggx::new(r * r);
            let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            let g1o = g.g1(wo);
            let (mut a, mut b) = (0.0f64, 0.0f64);
            for sy in 0..STRATA {
                for sx in 0..STRATA {
                    let u = Vec2::new(
                        (sx as f32 + 0.5) / STRATA as f32,
                        (sy as f32 + 0.5) / STRATA as f32,
                    );
                    let m = g.sample_visible(wo, u);
                    let wi = 2.0 * wo.dot(m) * m - wo;
                    if wi.z <= 0.0 {
                        continue;
                    }
                    let w = (g.g(wo, wi) / g1o) as f64;
                    a += w;
                    b += w * schlick_weight(wo.dot(m)) as f64;
                }
            }
            let n = (STRATA * STRATA) as f64;
            e[j * N_MU + i] = [(a / n) as f32, (b / n) as f32];
        }
    }
    // 2∫ E(μ) μ dμ of the piecewise-linear interpolant, exactly (trapezoid on E·μ is not
    // exact; integrate the linear pieces analytically).
    let avg = (0..N_R)
        .map(|j| {
            let mut s = [0.0f64; 2];
            for i in 0..N_MU - 1 {
                let (m0, m1) = (
                    i as f64 / (N_MU - 1) as f64,
                    (i + 1) as f64 / (N_MU - 1) as f64,
                );
                let h = m1 - m0;
                for (k, sk) in s.iter_mut().enumerate() {
                    let (e0, e1) = (e[j * N_MU + i][k] as f64, e[j * N_MU + i + 1][k] as f64);
                    // ∫ (e0 + (e1−e0)(μ−m0)/h) μ dμ over [m0, m1]
                    *sk += h * (e0 * (2.0 * m0 + m1) + e1 * (m0 + 2.0 * m1)) / 6.0;
                }
            }
            [(2.0 * s[0]) as f32, (2.0 * s[1]) as f32]
        })
        .collect();
    Tables { e, avg }
}

fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(compute)
}

#[inline]
fn lerp_index(x: f32, n: usize) -> (usize, f32) {
    let x = x.clamp(0.0, 1.0) * (n - 1) as f32;
    let i = (x as usize).min(n - 2);
    (i, x - i as f32)
}

/// (A, B) at `mu` = |cos θo| for GGX roughness `alpha` (α < MIN_ALPHA reads the mirror
/// column).
pub fn albedo_ab(mu: f32, alpha: f32) -> [f32; 2] {
    let t = tables();
    let (i, fi) = lerp_index(mu, N_MU);
    let (j, fj) = lerp_index(alpha.max(0.0).sqrt(), N_R);
    let at = |j: usize, i: usize, k: usize| t.e[j * N_MU + i][k];
    std::array::from_fn(|k| {
        let lo = at(j, i, k) * (1.0 - fi) + at(j, i + 1, k) * fi;
        let hi = at(j + 1, i, k) * (1.0 - fi) + at(j + 1, i + 1, k) * fi;
        lo * (1.0 - fj) + hi * fj
    })
}

/// Cosine-weighted hemispherical average of [`albedo_ab`] (consistent with its μ
/// interpolation).
pub fn albedo_avg_ab(alpha: f32) -> [f32; 2] {
    let t = tables();
    let (j, fj) = lerp_index(alpha.max(0.0).sqrt(), N_R);
    std::array::from_fn(|k| t.avg[j][k] * (1.0 - fj) + t.avg[j + 1][k] * fj)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn albedo_tables_are_sane() {
        // Mirror limit: A = 1, B = (1 − μ)^5; hemispherical average of (1−μ)^5 is 2/42
        // (piecewise-linear interpolation on 32 nodes overestimates a convex function by
        // at most h²/8·max|f''| ≈ 2e-2·... → 2e-3 observed bound is generous).
        assert!((albedo_avg_ab(0.0)[0] - 1.0).abs() < 1e-5);
        assert!((albedo_avg_ab(0.0)[1] - 2.0 / 42.0).abs() < 2e-3);
        for j in 0..=10 {
            let a = j as f32 / 10.0;
            for i in 0..=10 {
                let [ea, eb] = albedo_ab(i as f32 / 10.0, a);
                assert!(
                    (0.0..=1.0 + 1e-6).contains(&ea) && (0.0..=ea + 1e-6).contains(&eb),
                    "{a} {i} {ea} {eb}"
                );
            }
        }
        // Single-scattering GGX loses energy with roughness.
        assert!(albedo_ab(0.8, 1.0)[0] < 0.9 && albedo_ab(0.8, 0.01)[0] > 0.99);
    }
}
