//! Agreement with a peer: Mitsuba 3's `path` integrator (max_depth 8, 4096 spp) rendered
//! frame 12 of ../shared/peers/cornell-moving.glb (a Blender-exported animated Cornell
//! box); our path tracer on the same glTF, camera, frame and depth must converge to it.

use chronolux_core::scene::desc::AnimationId;
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
use chronolux_render::integrator::Integrator;
use chronolux_render::pt::{PathSettings, PathTracer};
use std::path::PathBuf;
use std::sync::Arc;

fn shared(rel: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/")).join(rel)
}

/// Relative noise of the Mitsuba reference itself, from ../shared/peers/README.md:
/// relMSE ≈ 6.5e-5 for the 4096-spp frames, relMSE = mean (I−R)²/(R²+0.01).
const REF_RELMSE: f64 = 6.5e-5;

#[test]
fn path_tracer_converges_to_the_mitsuba_reference() {
    let desc = chronolux_io::gltf::load(&shared("peers/cornell-moving.glb")).unwrap();
    let reference =
        chronolux_io::image::read_exr(shared("peers/mitsuba-refs/mitsuba_f12.exr")).unwrap();
    let (w, h) = (reference.width, reference.height);
    let mut builder = FrameBuilder::new(
        Arc::new(desc),
        Some(AnimationId(0)),
        CameraChoice::First,
        w,
        h,
    )
    .unwrap();
    let scene = builder.build(12.0 / 24.0);
    let spp = 32;
    let pt = PathTracer::new(PathSettings {
        spp,
        max_depth: Some(8),
        ..Default::default()
    });
    let img = pt.render(&scene, 12, &|_| {});
    assert_eq!(img.invalid_samples, 0);

    // 1. Image means per channel: the difference must be within 5 standard errors of the
    //    two estimates (ours from our per-pixel variances; the reference's from REF_RELMSE).
    let n = (w * h) as f64;
    for c in 0..3 {
        let ours: f64 = img.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        let theirs: f64 = reference.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        let var_ours: f64 = img.variance.iter().map(|v| v[c] as f64).sum::<f64>() / (n * n);
        let var_ref: f64 = reference
            .pixels
            .iter()
            .map(|p| REF_RELMSE * ((p[c] as f64).powi(2) + 0.01))
            .sum::<f64>()
            / (n * n);
        let se = (var_ours + var_ref).sqrt();
        let rel = (ours - theirs).abs() / theirs;
        assert!(
            (ours - theirs).abs() < 5.0 * se,
            "channel {c}: mean {ours:.5} vs Mitsuba {theirs:.5} (rel {rel:.4}, se {se:.2e})"
        );
    }

    // 2. Per-block z-test (Mitsuba's test_renders design with Šidák correction): 16×16-pixel
    //    blocks, so each block mean averages 256 pixels × spp samples and is close to normal.
    let b = 16u32;
    let blocks = (w / b) * (h / b) * 3;
    // Šidák: per-test level 1 − (1 − 0.01)^(1/blocks); two-sided normal quantile of it.
    let alpha = 1.0 - (1.0f64 - 0.01).powf(1.0 / blocks as f64);
    let z_crit = normal_quantile(1.0 - alpha / 2.0);
    let mut worst = 0.0f64;
    for by in 0..h / b {
        for bx in 0..w / b {
            for c in 0..3 {
                let (mut d, mut v) = (0.0f64, 0.0f64);
                for y in by * b..(by + 1) * b {
                    for x in bx * b..(bx + 1) * b {
                        let i = (y * w + x) as usize;
                        let r = reference.pixels[i][c] as f64;
                        d += img.pixels[i][c] as f64 - r;
                        v += img.variance[i][c] as f64 + REF_RELMSE * (r * r + 0.01);
                    }
                }
                if v > 0.0 {
                    let z = d.abs() / v.sqrt();
                    worst = worst.max(z);
                    assert!(
                        z < z_crit,
                        "block ({bx},{by}) channel {c}: z = {z:.2} ≥ {z_crit:.2}"
                    );
                }
            }
        }
    }
    eprintln!("peer agreement: worst block z = {worst:.2} (critical {z_crit:.2})");
}

#[allow(clippy::excessive_precision)] // reason: the published coefficients, kept as printed
/// Inverse of the standard normal cdf (Acklam's rational approximation, |error| < 1.2e-9).
pub(crate) fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383577518672690e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549671236853500,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let plow = 0.02425;
    if p < plow {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - plow {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        -normal_quantile(1.0 - p)
    }
}
