//! The environment map ([`EnvMap`]): χ² goodness of fit of its direction sampling against
//! its pdf, the pdf's normalisation over the sphere, the pdf's proportionality to
//! luminance (importance sampling as pbrt-v3's InfiniteAreaLight), the orientation the
//! docs state, and the light built on it (`sample_li` against `pdf_li`).

use crate::chi2::pooled_p_value;
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::light::{EnvMap, Environment, Light};
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::sampling::rng::Pcg32;
use std::f64::consts::PI;

const W: usize = 32;
const H: usize = 16;

/// A map with structure: a sky gradient, a dark ground, a bright "sun" of a few texels
/// (40× the sky: the sampling must follow it), a black band (zero density), coloured texels.
pub fn test_map(rotation_deg: f32) -> EnvMap {
    let mut t = Vec::with_capacity(W * H);
    for row in 0..H {
        for col in 0..W {
            let c = if (3..5).contains(&row) && (20..23).contains(&col) {
                Rgb::new(40.0, 36.0, 30.0)
            } else if row == 9 {
                Rgb::ZERO
            } else if row < H / 2 {
                Rgb::new(0.3, 0.5, 1.0) * (1.0 + row as f32 * 0.2)
            } else {
                Rgb::new(0.2, 0.15, 0.1) * (1.0 + (col % 5) as f32 * 0.3)
            };
            t.push(c);
        }
    }
    EnvMap::new(W, H, t, 1.5, rotation_deg).unwrap()
}

/// Map coordinates (row, column) of world direction `w`, computed here from the documented
/// convention (module doc of `light::envmap`), independently of the map's own lookup:
/// turned by `rot` about +Y, θ from +Y, the centre column along +X, u = ¼ along −Z.
fn cell(w: Vec3, rot_deg: f64) -> (usize, usize, f64, f64) {
    let (s, c) = rot_deg.to_radians().sin_cos();
    let w = w.as_dvec3().normalize();
    let (x, y, z) = (w.x * c + w.z * s, w.y, -w.x * s + w.z * c);
    let theta = y.clamp(-1.0, 1.0).acos();
    let u = (0.5 + z.atan2(x) / (2.0 * PI)).rem_euclid(1.0);
    let row = ((theta / PI * H as f64) as usize).min(H - 1);
    let col = ((u * W as f64) as usize).min(W - 1);
    (row, col, theta, u)
}

/// World direction at map coordinates (θ, u), inverse of [`cell`].
fn dir(theta: f64, u: f64, rot_deg: f64) -> Vec3 {
    let phi = 2.0 * PI * (u - 0.5);
    let (x, y, z) = (
        theta.sin() * phi.cos(),
        theta.cos(),
        theta.sin() * phi.sin(),
    );
    let (s, c) = rot_deg.to_radians().sin_cos();
    Vec3::new((x * c - z * s) as f32, y as f32, (x * s + z * c) as f32)
}

/// ∫ pdf dω over texel (row, col), by the midpoint rule on 8×8 sub-cells in (θ, u), all
/// strictly inside the texel: there pdf·sin θ is constant (density constant per texel in
/// (u, v)), so the rule is exact up to f32 rounding.
fn texel_integral(m: &EnvMap, row: usize, col: usize, rot: f64) -> f64 {
    let n = 8;
    let (dt, du) = (PI / H as f64, 1.0 / W as f64);
    let mut s = 0.0;
    for a in 0..n {
        let theta = (row as f64 + (a as f64 + 0.5) / n as f64) * dt;
        for b in 0..n {
            let u = (col as f64 + (b as f64 + 0.5) / n as f64) * du;
            s += m.pdf(dir(theta, u, rot)) as f64 * theta.sin();
        }
    }
    // dω = sin θ dθ dφ, dφ = 2π du.
    s * (dt / n as f64) * (2.0 * PI * du / n as f64)
}

#[test]
fn chi2_map_sampling_matches_its_pdf_and_the_pdf_integrates_to_one() {
    for rot in [0.0f32, 37.5] {
        let m = test_map(rot);
        let exp_p: Vec<f64> = (0..H * W)
            .map(|i| texel_integral(&m, i / W, i % W, rot as f64))
            .collect();
        let integral: f64 = exp_p.iter().sum();
        // Exact quadrature (see texel_integral); 1e-5 covers f32 rounding of the pdf.
        assert!(
            (integral - 1.0).abs() < 1e-5,
            "rotation {rot}: ∫ pdf dω = {integral}"
        );
        let n = 200_000;
        let mut obs = vec![0.0f64; H * W];
        let mut rng = Pcg32::new(42, rot.to_bits() as u64);
        let mut lost = 0usize;
        for _ in 0..n {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            // `sample` gives up only where f32 rounding puts the direction on a pole or
            // across the edge of a black texel (density 0 there): measure zero.
            let Some((w, pdf)) = m.sample(u) else {
                lost += 1;
                continue;
            };
            assert!((w.length() - 1.0).abs() < 1e-5);
            assert_eq!(pdf, m.pdf(w), "sample's pdf is pdf() of its direction");
            let (row, col, _, _) = cell(w, rot as f64);
            obs[row * W + col] += 1.0;
        }
        assert!(lost <= 2, "rotation {rot}: {lost} of {n} samples lost");
        let exp: Vec<f64> = exp_p.iter().map(|p| p * (n - lost) as f64).collect();
        // The black row has density 0 and gets no samples.
        assert!((0..W).all(|c| obs[9 * W + c] == 0.0 && exp[9 * W + c] == 0.0));
        let p = pooled_p_value(&obs, &exp, None);
        eprintln!("rotation {rot}: χ² p = {p:.4}, ∫pdf = {integral:.7}");
        // Two configurations, family-wise false alarm 1 % (Šidák).
        let threshold = chronolux_core::testing::stats::sidak(0.01, 2);
        assert!(
            p >= threshold,
            "rotation {rot}: χ² p-value {p} < {threshold}"
        );
    }
}

#[test]
fn map_density_follows_luminance_and_lookup_follows_the_stated_orientation() {
    let rot = 37.5f64;
    let m = test_map(rot as f32);
    let mut ratio: Option<f64> = None;
    for row in 0..H {
        for col in 0..W {
            let theta = (row as f64 + 0.5) * PI / H as f64;
            let u = (col as f64 + 0.5) / W as f64;
            let w = dir(theta, u, rot);
            let (r2, c2, _, _) = cell(w, rot);
            assert_eq!((r2, c2), (row, col));
            let l = m.eval(w);
            // pdf ∝ luminance at the texel centre (the sin θ of the weights cancels the
            // sin θ of dω there): one ratio for every lit texel, to f32 rounding.
            let lum = luminance(l) as f64;
            let pdf = m.pdf(w) as f64;
            if lum == 0.0 {
                assert_eq!(pdf, 0.0);
                continue;
            }
            let q = pdf / lum;
            match ratio {
                None => ratio = Some(q),
                Some(r) => assert!((q - r).abs() <= 1e-4 * r, "texel {row},{col}: {q} vs {r}"),
            }
        }
    }
    // The sun (rows 3-4, columns 20-22, strength 1.5) is where the convention says.
    let sun = m.eval(dir(3.5 * PI / H as f64, 21.5 / W as f64, rot));
    assert_eq!(sun, Rgb::new(40.0, 36.0, 30.0) * 1.5);
    // Unrotated: straight up is the top row, +X the centre column, −Z a quarter across.
    let m0 = test_map(0.0);
    assert_eq!(cell(Vec3::Y, 0.0).0, 0);
    assert_eq!(cell(Vec3::X, 0.0).1, W / 2);
    assert_eq!(cell(-Vec3::Z, 0.0).1, W / 4);
    assert_eq!(
        m0.eval(Vec3::new(1.0, 0.001, 0.0)),
        m0.eval(dir(PI / 2.0 - 1e-3, 0.5 + 1e-4, 0.0))
    );
    // The mean is the exact solid-angle average of the texels.
    let mut s = 0.0f64;
    for row in 0..H {
        let (t0, t1) = (row as f64 * PI / H as f64, (row + 1) as f64 * PI / H as f64);
        for col in 0..W {
            let w = dir(
                (row as f64 + 0.5) * PI / H as f64,
                (col as f64 + 0.5) / W as f64,
                0.0,
            );
            s += m0.eval(w).x as f64 * (t0.cos() - t1.cos()) * 2.0 * PI / W as f64;
        }
    }
    let mean = s / (4.0 * PI);
    assert!(
        (m0.mean().x as f64 - mean).abs() <= 1e-5 * mean,
        "{} vs {mean}",
        m0.mean().x
    );
}

#[test]
fn map_light_samples_agree_with_pdf_li_and_bad_maps_are_errors() {
    let l = Light::Environment {
        env: Environment::from_map(test_map(10.0), true),
    };
    let mut rng = Pcg32::new(1, 2);
    let p = Vec3::new(0.3, -0.2, 1.0);
    for _ in 0..10_000 {
        let s = l
            .sample_li(p, Vec2::new(rng.next_f32(), rng.next_f32()), 10.0)
            .unwrap();
        let q = l.pdf_li(p, s.p);
        assert!((s.pdf - q).abs() <= 1e-3 * q, "{} vs {q}", s.pdf);
        let Light::Environment { env } = &l else {
            unreachable!()
        };
        assert_eq!(s.li, env.radiance(s.wi));
    }
    let ok = vec![Rgb::ONE; 8];
    assert!(EnvMap::new(0, 0, vec![], 1.0, 0.0).is_err());
    assert!(EnvMap::new(4, 3, ok.clone(), 1.0, 0.0).is_err());
    assert!(EnvMap::new(4, 2, ok.clone(), f32::NAN, 0.0).is_err());
    assert!(EnvMap::new(4, 2, ok.clone(), -1.0, 0.0).is_err());
    assert!(EnvMap::new(4, 2, ok.clone(), 1.0, f32::INFINITY).is_err());
    let mut bad = ok.clone();
    bad[3] = Rgb::new(f32::NAN, 0.0, 0.0);
    assert!(EnvMap::new(4, 2, bad, 1.0, 0.0).is_err());
    // A black map is valid and lights nothing.
    let black = EnvMap::new(4, 2, vec![Rgb::ZERO; 8], 1.0, 0.0).unwrap();
    assert!(black.sample(Vec2::new(0.5, 0.5)).is_none());
    assert_eq!(black.pdf(Vec3::Y), 0.0);
}
