//! Image error and temporal flicker: the yardstick every technique is measured with.
//!
//! All images are linear, scene-referred RGB ([`Rgb`]) given as pixel slices of equal
//! length (row-major; the layout only matters for FLIP, which takes width and height).
//! Sums are accumulated in `f64`. "Mean" is over all pixels **and** channels (N = 3 ×
//! pixels). `I` is the image under test, `R` the reference.
//!
//! | metric | definition |
//! | --- | --- |
//! | relMSE | mean of (I − R)² / (R² + 0.01) ([`rel_mse`]; ε = [`REL_MSE_EPS`]) |
//! | MSE / RMSE | mean of (I − R)²; RMSE = √MSE ([`mse`], [`rmse`]) |
//! | PSNR | 10 · log10(1 / MSE) dB, peak 1 on the linear values; +∞ when MSE = 0 ([`psnr`]) |
//! | flicker | for consecutive frames t−1, t: mean \|(I_t − I_{t−1}) − (R_t − R_{t−1})\| / mean(R_t) ([`flicker`]) |
//! | flicker without reference | mean \|I_t − I_{t−1}\| ([`flicker_no_reference`]); on a static scene the truth is 0 |
//! | HDR-FLIP | NVIDIA ꟻLIP in HDR mode on the linear images (negatives set to 0), exposure range chosen from the reference as `flip-evaluator` does ([`flip::flip_hdr`]) |
//! | LDR-FLIP | both linear images clipped to [0, 1] and compared with LDR-ꟻLIP ([`flip::flip_ldr`]) |
//!
//! These are exactly the definitions of the peer measurements
//! (`../shared/peers/harness/metrics.py`): relMSE with ε = 0.01, flicker normalised by the
//! mean of the reference frame t, FLIP at 67.02 pixels per degree (0.7 m from a 0.7 m wide
//! 3840-pixel monitor). A sequence's summary is the mean of its per-frame values; flicker is
//! defined for every frame t whose predecessor t−1 is also compared.
//!
//! All functions here are deterministic and independent of the number of threads.

pub mod flip;
pub mod magma;

use crate::color::Rgb;

/// ε of relMSE's denominator (R² + ε), as in the peers' `metrics.py`.
pub const REL_MSE_EPS: f64 = 0.01;

fn check_len(a: &[Rgb], b: &[Rgb]) {
    assert_eq!(
        a.len(),
        b.len(),
        "metrics: images of different sizes ({} vs {} pixels)",
        a.len(),
        b.len()
    );
}

/// Mean over pixels and channels of `f(test channel, reference channel)`; 0 for no pixels.
fn mean_channels(test: &[Rgb], reference: &[Rgb], f: impl Fn(f64, f64) -> f64) -> f64 {
    check_len(test, reference);
    if test.is_empty() {
        return 0.0;
    }
    let mut s = 0.0f64;
    for (i, r) in test.iter().zip(reference) {
        for c in 0..3 {
            s += f(f64::from(i[c]), f64::from(r[c]));
        }
    }
    s / (3 * test.len()) as f64
}

/// relMSE = mean over pixels and channels of (I − R)² / (R² + 0.01).
///
/// # Panics
/// When the images differ in size.
pub fn rel_mse(test: &[Rgb], reference: &[Rgb]) -> f64 {
    mean_channels(test, reference, |i, r| {
        (i - r) * (i - r) / (r * r + REL_MSE_EPS)
    })
}

/// MSE = mean over pixels and channels of (I − R)².
pub fn mse(test: &[Rgb], reference: &[Rgb]) -> f64 {
    mean_channels(test, reference, |i, r| (i - r) * (i - r))
}

/// RMSE = √MSE.
pub fn rmse(test: &[Rgb], reference: &[Rgb]) -> f64 {
    mse(test, reference).sqrt()
}

/// PSNR = 10 · log10(1 / MSE) in dB with peak value 1 on the linear values (so it is not
/// bounded by the image's own maximum); +∞ for identical images.
pub fn psnr(test: &[Rgb], reference: &[Rgb]) -> f64 {
    let m = mse(test, reference);
    if m == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * m.log10()
    }
}

/// Mean over pixels and channels.
pub fn mean_value(pixels: &[Rgb]) -> f64 {
    if pixels.is_empty() {
        return 0.0;
    }
    let s: f64 = pixels
        .iter()
        .map(|p| f64::from(p.x) + f64::from(p.y) + f64::from(p.z))
        .sum();
    s / (3 * pixels.len()) as f64
}

/// Flicker of frame t against a reference sequence:
/// mean over pixels and channels of |(I_t − I_{t−1}) − (R_t − R_{t−1})|, divided by the
/// mean of R_t (over pixels and channels). 0 when the test changes exactly as the reference
/// does; a reference frame of mean 0 gives +∞ unless the numerator is 0 too (then 0).
///
/// # Panics
/// When the four images differ in size.
pub fn flicker(test_prev: &[Rgb], test: &[Rgb], ref_prev: &[Rgb], reference: &[Rgb]) -> f64 {
    check_len(test_prev, test);
    check_len(ref_prev, reference);
    check_len(test, reference);
    if test.is_empty() {
        return 0.0;
    }
    let mut s = 0.0f64;
    for k in 0..test.len() {
        for c in 0..3 {
            let di = f64::from(test[k][c]) - f64::from(test_prev[k][c]);
            let dr = f64::from(reference[k][c]) - f64::from(ref_prev[k][c]);
            s += (di - dr).abs();
        }
    }
    let num = s / (3 * test.len()) as f64;
    if num == 0.0 {
        return 0.0;
    }
    num / mean_value(reference)
}

/// Flicker without a reference: mean over pixels and channels of |I_t − I_{t−1}|
/// (absolute, not normalised). Meaningful on a static scene, where the truth is 0.
pub fn flicker_no_reference(prev: &[Rgb], current: &[Rgb]) -> f64 {
    mean_channels(current, prev, |a, b| (a - b).abs())
}
