//! Metrics with known answers, and ꟻLIP against the reference implementation
//! (`flip-evaluator`, run through Python when available).

use chronolux_core::color::Rgb;
use chronolux_core::metrics::flip::{self, HdrSettings};
use chronolux_core::metrics::{
    REL_MSE_EPS, flicker, flicker_no_reference, mean_value, mse, psnr, rel_mse, rmse,
};
use chronolux_core::sampling::rng::Pcg32;

/// A smooth HDR "scene": a gradient room with a bright patch (values up to ~18).
fn scene(w: usize, h: usize) -> Vec<Rgb> {
    let mut v = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (u, t) = (x as f32 / w as f32, y as f32 / h as f32);
            let mut c = Rgb::new(0.6 * u + 0.05, 0.3 + 0.2 * t, 0.1 + 0.4 * u * t);
            if (u - 0.5).abs() < 0.15 && t < 0.1 {
                c = Rgb::new(18.4, 14.0, 6.75);
            }
            if ((u - 0.3).powi(2) + (t - 0.7).powi(2)).sqrt() < 0.12 {
                c *= 0.2;
            }
            v.push(c);
        }
    }
    v
}

/// `img` with deterministic multiplicative noise of relative amplitude `amp`.
fn noisy(img: &[Rgb], amp: f32, seed: u64) -> Vec<Rgb> {
    let mut rng = Pcg32::new(seed, 7);
    img.iter()
        .map(|c| {
            let n = Rgb::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Rgb::ONE;
            (*c * (Rgb::ONE + n * amp)).max(Rgb::ZERO)
        })
        .collect()
}

#[test]
fn identical_images_give_zero() {
    let r = scene(40, 30);
    assert_eq!(rel_mse(&r, &r), 0.0);
    assert_eq!(mse(&r, &r), 0.0);
    assert_eq!(rmse(&r, &r), 0.0);
    assert_eq!(psnr(&r, &r), f64::INFINITY);
    assert_eq!(flicker(&r, &r, &r, &r), 0.0);
    assert_eq!(flicker_no_reference(&r, &r), 0.0);
    assert_eq!(
        flip::flip_ldr(&r, &r, 40, 30, flip::default_ppd()).mean(),
        0.0
    );
    assert_eq!(
        flip::flip_hdr(&r, &r, 40, 30, &HdrSettings::default()).mean(),
        0.0
    );
}

#[test]
fn constant_offset_gives_computed_values() {
    // Reference: half the pixels 0.5, half 1.0; test = reference + 0.25 everywhere.
    let r: Vec<Rgb> = (0..100usize)
        .map(|i| Rgb::splat(if i.is_multiple_of(2) { 0.5 } else { 1.0 }))
        .collect();
    let t: Vec<Rgb> = r.iter().map(|c| *c + Rgb::splat(0.25)).collect();
    let d2 = 0.0625f64;
    let expect_rel = 0.5 * d2 / (0.25 + REL_MSE_EPS) + 0.5 * d2 / (1.0 + REL_MSE_EPS);
    assert!((rel_mse(&t, &r) - expect_rel).abs() < 1e-12);
    assert!((mse(&t, &r) - d2).abs() < 1e-12);
    assert!((rmse(&t, &r) - 0.25).abs() < 1e-12);
    assert!((psnr(&t, &r) - 10.0 * (1.0 / d2).log10()).abs() < 1e-9);
    assert!((mean_value(&r) - 0.75).abs() < 1e-12);
}

#[test]
fn flicker_of_static_noisy_sequence_against_static_reference() {
    // Reference constant 0.5 in both frames; the test alternates ±0.1 about it per pixel:
    // frame 0 = 0.5 + 0.1 s, frame 1 = 0.5 − 0.1 s with s = ±1, so |ΔI − ΔR| = 0.2 and
    // flicker = 0.2 / 0.5 = 0.4; without reference mean |ΔI| = 0.2.
    let r = vec![Rgb::splat(0.5); 64];
    let s = |i: usize| if i.is_multiple_of(3) { 1.0 } else { -1.0 };
    let i0: Vec<Rgb> = (0..64).map(|i| Rgb::splat(0.5 + 0.1 * s(i))).collect();
    let i1: Vec<Rgb> = (0..64).map(|i| Rgb::splat(0.5 - 0.1 * s(i))).collect();
    assert!((flicker(&i0, &i1, &r, &r) - 0.4).abs() < 1e-6);
    assert!((flicker_no_reference(&i0, &i1) - 0.2).abs() < 1e-6);
    // A test that changes exactly as the reference does has no flicker.
    let r1: Vec<Rgb> = r.iter().map(|c| *c * 2.0).collect();
    let j1: Vec<Rgb> = i0.iter().zip(&r).map(|(a, b)| *a + *b).collect();
    assert!(flicker(&i0, &j1, &r, &r1).abs() < 1e-6);
}

#[test]
fn flip_grows_with_noise_and_stays_in_unit_range() {
    let (w, h) = (48, 40);
    let r = scene(w, h);
    let a = flip::flip_hdr(&r, &noisy(&r, 0.05, 1), w, h, &HdrSettings::default());
    let b = flip::flip_hdr(&r, &noisy(&r, 0.3, 1), w, h, &HdrSettings::default());
    assert!(
        a.mean() > 0.0 && a.mean() < b.mean(),
        "{} {}",
        a.mean(),
        b.mean()
    );
    assert!(b.errors.iter().all(|e| (0.0..=1.0).contains(e)));
    let (s, e, n) = b.exposures.unwrap();
    assert!(s < e && n >= 2);
}

#[test]
fn default_ppd_matches_flip() {
    assert!((flip::default_ppd() - 67.020_645).abs() < 1e-4);
}

fn write_raw(path: &std::path::Path, img: &[Rgb]) {
    let mut bytes = Vec::with_capacity(img.len() * 12);
    for c in img {
        for v in [c.x, c.y, c.z] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// Mean FLIP by `flip-evaluator` in `mode` ("HDR" or "LDR") of raw f32 RGB images, with
/// the peers' preprocessing (negatives to 0; LDR: clipped to [0, 1], linear input).
fn python_flip(py: &str, r: &[Rgb], t: &[Rgb], w: usize, h: usize, mode: &str) -> f64 {
    let dir = std::env::temp_dir().join(format!("chronolux-flip-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (rp, tp) = (
        dir.join(format!("r_{mode}.f32")),
        dir.join(format!("t_{mode}.f32")),
    );
    write_raw(&rp, r);
    write_raw(&tp, t);
    let script = format!(
        "import numpy as np, flip_evaluator as fl\n\
         r=np.fromfile('{}',dtype=np.float32).reshape({h},{w},3)\n\
         t=np.fromfile('{}',dtype=np.float32).reshape({h},{w},3)\n\
         r=np.ascontiguousarray(np.maximum(r,0));t=np.ascontiguousarray(np.maximum(t,0))\n\
         if '{mode}'=='LDR': r,t=np.minimum(r,1),np.minimum(t,1)\n\
         print(repr(float(fl.evaluate(r,t,'{mode}',inputsRGB=False,applyMagma=False,computeMeanError=True)[1])))\n",
        rp.display(),
        tp.display()
    );
    let out = std::process::Command::new(py)
        .args(["-c", &script])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
    String::from_utf8_lossy(&out.stdout).trim().parse().unwrap()
}

#[test]
fn flip_agrees_with_flip_evaluator() {
    let Some(py) = chronolux_core::testing::flip_python() else {
        return;
    };
    let (w, h) = (96, 80);
    let r = scene(w, h);
    let pairs = [
        ("noise 5%", noisy(&r, 0.05, 3)),
        ("noise 40%", noisy(&r, 0.4, 4)),
        ("darker", r.iter().map(|c| *c * 0.8).collect::<Vec<_>>()),
        (
            "other scene",
            noisy(&scene(w, h).into_iter().rev().collect::<Vec<_>>(), 0.1, 5),
        ),
    ];
    for (name, t) in &pairs {
        let ours_hdr = flip::flip_hdr(&r, t, w, h, &HdrSettings::default()).mean();
        let theirs_hdr = python_flip(&py, &r, t, w, h, "HDR");
        let ours_ldr = flip::flip_ldr(&r, t, w, h, flip::default_ppd()).mean();
        let theirs_ldr = python_flip(&py, &r, t, w, h, "LDR");
        eprintln!(
            "{name}: HDR {ours_hdr:.6} vs {theirs_hdr:.6}, LDR {ours_ldr:.6} vs {theirs_ldr:.6}"
        );
        assert!(
            (ours_hdr - theirs_hdr).abs() < 1e-3,
            "{name}: HDR-FLIP {ours_hdr} vs flip-evaluator {theirs_hdr}"
        );
        assert!(
            (ours_ldr - theirs_ldr).abs() < 1e-3,
            "{name}: LDR-FLIP {ours_ldr} vs flip-evaluator {theirs_ldr}"
        );
    }
}
