//! How many photons a frame gets: a fixed count, or the **stopping rule** (issue 5, item 5)
//! that shoots photons in batches until the remaining noise of the reconstruction is
//! below a perceptual threshold.
//!
//! ## The rule
//! After each batch the frame's reconstruction (the method's own: unfiltered, Gaussian,
//! bilateral or space-time) is formed together with its noise: for every element side the
//! standard error `σ_e` of its reconstructed luminance irradiance, propagated through the
//! reconstruction's weights from the photons' Σφ² (`Var Σφ ≈ Σφ²`, photon counts being
//! ~Poisson): `σ_e = √(Σ_j w_j² Σφ²_j) / (N Σ_j w_j A_j)`.
//!
//! The threshold is a **luminance contrast (Weber fraction)**: the indirect estimate's
//! noise is visible where it exceeds `weber` (default 2 %) of the element's *total*
//! irradiance, direct included — `σ_e > weber · (E_direct + E_indirect)` (the reflectance
//! multiplies both, so the ratio is the contrast of the reflected luminance on a diffuse
//! surface). Direct light is rendered per pixel, but its per-element irradiance is
//! estimated from the same photons' first hits (they cost nothing extra), which is what
//! lets bright directly-lit surfaces mask indirect noise, as in Myszkowski's
//! perception-guided stopping condition.
//!
//! The frame stops when the **luminance-weighted fraction** of element sides above
//! threshold (weight: area × total irradiance, i.e. reflected power, so dark unseen
//! corners do not dominate) is at most `max_fraction` (default 5 %), or at `max_photons`.
//! The next total is predicted from the relative errors (`σ ∝ 1/√N`): the smallest N at
//! which the weighted fraction above threshold would reach `max_fraction`, clamped to
//! `[total + batch, 2 · total]` so a bad prediction costs at most one doubling.
//!
//! The threshold is on the photon noise only: the eye pass's own noise (direct light and
//! anti-aliasing with `spp` samples) is a separate budget. Elements are not weighted by
//! visibility from the camera (every surface counts, by power).
//!
//! Photon indices: frame `f` uses photons `f·max_photons ..` of the Halton stream, the
//! first `n` of them, so frames never share photons and any photon stays replayable.

use chronolux_core::color::Rgb;
use chronolux_core::color::luminance;

/// Settings of the stopping rule.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AutoPhotons {
    /// Visible luminance contrast (Weber fraction) of the indirect estimate's noise
    /// (one standard error) against the total irradiance. Default 0.02.
    pub weber: f32,
    /// Largest luminance-weighted fraction of element sides allowed above threshold.
    /// Default 0.05.
    pub max_fraction: f32,
    /// First batch, and the smallest increment. Default 25 000.
    pub batch: u64,
    /// Most photons per frame. Default 4 000 000.
    pub max_photons: u64,
}

impl Default for AutoPhotons {
    fn default() -> Self {
        AutoPhotons {
            weber: 0.02,
            max_fraction: 0.05,
            batch: 25_000,
            max_photons: 4_000_000,
        }
    }
}

/// `--photons N` or `--photons auto`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhotonCount {
    Fixed(u64),
    Auto(AutoPhotons),
}

impl std::str::FromStr for PhotonCount {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(PhotonCount::Auto(AutoPhotons::default()));
        }
        let n: u64 = s
            .replace('_', "")
            .parse()
            .map_err(|_| format!("--photons takes a count or `auto`, not '{s}'"))?;
        if n == 0 {
            return Err("--photons must be at least 1".into());
        }
        Ok(PhotonCount::Fixed(n))
    }
}

/// The verdict on one reconstruction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseAssessment {
    /// Luminance-weighted fraction of element sides whose noise is above threshold.
    pub fraction_above: f32,
    /// Predicted photon total at which the fraction would reach `max_fraction`.
    pub predicted_photons: u64,
}

/// Assesses a reconstruction with `photons` photons: per element side its indirect
/// luminance irradiance `ind`, that estimate's standard error `sigma`, the direct
/// luminance irradiance `direct`, and the side's `area`.
pub fn assess(
    rule: &AutoPhotons,
    photons: u64,
    ind: &[f32],
    sigma: &[f32],
    direct: &[f32],
    area: impl Fn(usize) -> f32,
) -> NoiseAssessment {
    // (weight, photons needed) per side with any light.
    let mut need: Vec<(f32, f64)> = Vec::with_capacity(ind.len());
    let mut total_w = 0.0f64;
    for s in 0..ind.len() {
        let e = (direct[s] + ind[s]).max(0.0);
        let w = area(s) * e;
        if !(w > 0.0) {
            continue;
        }
        total_w += w as f64;
        let rel = sigma[s] / (rule.weber * e);
        // σ ∝ 1/√N: below threshold from N · rel².
        need.push((w, photons as f64 * (rel as f64).powi(2)));
    }
    if total_w <= 0.0 {
        return NoiseAssessment {
            fraction_above: 0.0,
            predicted_photons: photons,
        };
    }
    let above: f64 = need
        .iter()
        .filter(|(_, n)| *n > photons as f64)
        .map(|(w, _)| *w as f64)
        .sum();
    // Weighted (1 − max_fraction) quantile of the photons needed.
    need.sort_by(|a, b| a.1.total_cmp(&b.1));
    let keep = (1.0 - rule.max_fraction as f64).clamp(0.0, 1.0) * total_w;
    let mut acc = 0.0f64;
    let mut predicted = photons as f64;
    for (w, n) in &need {
        acc += *w as f64;
        predicted = *n;
        if acc >= keep {
            break;
        }
    }
    NoiseAssessment {
        fraction_above: (above / total_w) as f32,
        predicted_photons: predicted.ceil().min(u64::MAX as f64 / 2.0) as u64,
    }
}

/// Photon total of the next batch after `total` given an assessment, or `None` to stop.
pub fn next_total(rule: &AutoPhotons, total: u64, a: &NoiseAssessment) -> Option<u64> {
    if a.fraction_above <= rule.max_fraction || total >= rule.max_photons {
        return None;
    }
    let lo = total + rule.batch.max(1);
    let hi = (2 * total).max(lo);
    Some(a.predicted_photons.clamp(lo, hi).min(rule.max_photons))
}

/// Luminance of each entry.
pub fn luminances(v: &[Rgb]) -> Vec<f32> {
    v.iter().map(|c| luminance(*c)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_counts_and_auto() {
        assert_eq!("250000".parse(), Ok(PhotonCount::Fixed(250_000)));
        assert_eq!("1_000".parse(), Ok(PhotonCount::Fixed(1000)));
        assert!(matches!("auto".parse(), Ok(PhotonCount::Auto(_))));
        assert!("0".parse::<PhotonCount>().is_err());
        assert!("lots".parse::<PhotonCount>().is_err());
    }

    #[test]
    fn stops_when_noise_is_below_threshold_and_predicts_otherwise() {
        let rule = AutoPhotons::default();
        // Relative error 1 % of total: below 2 %.
        let a = assess(&rule, 1000, &[1.0; 4], &[0.01; 4], &[0.0; 4], |_| 1.0);
        assert_eq!(a.fraction_above, 0.0);
        assert_eq!(next_total(&rule, 1000, &a), None);
        // 4 % everywhere: needs 4× the photons; the next total doubles (clamp).
        let a = assess(&rule, 100_000, &[1.0; 4], &[0.04; 4], &[0.0; 4], |_| 1.0);
        assert_eq!(a.fraction_above, 1.0);
        assert_eq!(a.predicted_photons, 400_000);
        assert_eq!(next_total(&rule, 100_000, &a), Some(200_000));
        // Direct light masks the same noise: 0.04 / (1 + 3) = 1 %.
        let a = assess(&rule, 100_000, &[1.0; 4], &[0.04; 4], &[3.0; 4], |_| 1.0);
        assert_eq!(a.fraction_above, 0.0);
    }
}
