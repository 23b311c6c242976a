//! Statistical tests of Monte Carlo images: quantiles, the Šidák correction, and block
//! z- and t-tests of an image against another estimate or a reference.
//!
//! The block tests follow the design of Mitsuba 3's `test_renders`: the image is cut into
//! square blocks; each block mean averages many pixels × samples and is close to normal,
//! so per block and channel a standardised difference is compared with the quantile
//! that keeps the family-wise false-alarm rate over all blocks × channels at the level the
//! test asks for (Šidák correction). The result ([`BlockTest`]) says which block is worst
//! and, when asked to assert ([`BlockTest::assert_passes`]), writes evidence images on
//! failure (see [`super::evidence`]).

use glam::Vec3;

/// Inverse of the standard normal cdf (Acklam's rational approximation, relative error
/// < 1.2e-9; checked against Python's `statistics.NormalDist` at 1e-9 ≤ p ≤ 0.024).
#[allow(clippy::excessive_precision)] // reason: the published coefficients, kept as printed
pub fn normal_quantile(p: f64) -> f64 {
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
        -2.549732539343734,
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

/// Upper `p` quantile of Student's t with `nu` degrees of freedom, Cornish–Fisher
/// expansion in 1/ν to third order (Abramowitz & Stegun 26.7.5; relative error below
/// 1 % for ν ≥ 10 at the quantiles used by the block tests).
pub fn t_quantile(p: f64, nu: f64) -> f64 {
    let z = normal_quantile(p);
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * nu)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * nu * nu)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * nu.powi(3))
}

/// Šidák-corrected per-test level for a family-wise false-alarm rate `alpha` over `tests`
/// independent tests: 1 − (1 − α)^(1/tests).
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

/// Critical |z| of a two-sided normal test at family-wise level `alpha` over `tests` tests
/// (Šidák).
pub fn sidak_z(alpha: f64, tests: usize) -> f64 {
    normal_quantile(1.0 - sidak(alpha, tests) / 2.0)
}

/// Critical |t| of a two-sided Student-t test with `nu` degrees of freedom at family-wise
/// level `alpha` over `tests` tests (Šidák).
pub fn sidak_t(alpha: f64, tests: usize, nu: f64) -> f64 {
    t_quantile(1.0 - sidak(alpha, tests) / 2.0, nu)
}

/// An image estimate: per pixel (rows top to bottom) and channel, the value and the
/// variance of that value (of the mean over the pixel's samples), in `f64` as the tests
/// sum them.
#[derive(Clone, Debug)]
pub struct Estimate {
    pub width: u32,
    pub height: u32,
    pub mean: Vec<[f64; 3]>,
    pub variance: Vec<[f64; 3]>,
}

fn to_f64(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

impl Estimate {
    /// From a film: pixel values and their per-pixel variances.
    pub fn new(width: u32, height: u32, pixels: &[Vec3], variance: &[Vec3]) -> Self {
        assert_eq!(pixels.len(), (width * height) as usize, "pixel count");
        assert_eq!(variance.len(), pixels.len(), "variance count");
        Estimate {
            width,
            height,
            mean: pixels.iter().map(|&p| to_f64(p)).collect(),
            variance: variance.iter().map(|&v| to_f64(v)).collect(),
        }
    }

    /// From pixel values whose variance is a function of the value (per channel), e.g. a
    /// reference whose relative noise is known.
    pub fn with_variance(
        width: u32,
        height: u32,
        pixels: &[Vec3],
        variance: impl Fn(f64) -> f64,
    ) -> Self {
        assert_eq!(pixels.len(), (width * height) as usize, "pixel count");
        let mean: Vec<[f64; 3]> = pixels.iter().map(|&p| to_f64(p)).collect();
        let variance = mean.iter().map(|m| m.map(&variance)).collect();
        Estimate {
            width,
            height,
            mean,
            variance,
        }
    }

    fn pixels_f32(&self) -> Vec<[f32; 3]> {
        self.mean.iter().map(|m| m.map(|v| v as f32)).collect()
    }
}

/// Per channel, the two image means (over pixels) and the standard error of their
/// difference, √(Σ var_a/n² + Σ var_b/n²) (pixels independent).
#[derive(Clone, Copy, Debug)]
pub struct MeanDiff {
    pub a: f64,
    pub b: f64,
    pub se: f64,
}

impl MeanDiff {
    /// |a − b| / se.
    pub fn z(&self) -> f64 {
        (self.a - self.b).abs() / self.se
    }
}

/// [`MeanDiff`] of `a` and `b` per channel.
pub fn channel_means(a: &Estimate, b: &Estimate) -> [MeanDiff; 3] {
    assert_eq!((a.width, a.height), (b.width, b.height), "image sizes");
    let n = (a.width * a.height) as f64;
    std::array::from_fn(|c| {
        let ma: f64 = a.mean.iter().map(|p| p[c]).sum::<f64>() / n;
        let mb: f64 = b.mean.iter().map(|p| p[c]).sum::<f64>() / n;
        let va: f64 = a.variance.iter().map(|v| v[c]).sum::<f64>() / (n * n);
        let vb: f64 = b.variance.iter().map(|v| v[c]).sum::<f64>() / (n * n);
        MeanDiff {
            a: ma,
            b: mb,
            se: (va + vb).sqrt(),
        }
    })
}

/// The worst block of a [`BlockTest`].
#[derive(Clone, Copy, Debug)]
pub struct Worst {
    /// The statistic (|z| or |t|); NaN if a block's difference was NaN.
    pub value: f64,
    pub bx: u32,
    pub by: u32,
    pub channel: usize,
    /// Block means of the tested image and of the reference there.
    pub test_mean: f64,
    pub reference_mean: f64,
}

/// Outcome of a block test: every block's statistic, the worst block and the critical
/// value, with the images compared (for evidence).
#[derive(Clone, Debug)]
pub struct BlockTest {
    /// `"z"` or `"t"`.
    pub statistic: &'static str,
    /// Block side in pixels.
    pub block: u32,
    pub blocks_x: u32,
    pub blocks_y: u32,
    /// Per block (rows top to bottom) and channel, the statistic; NaN where the block was
    /// not tested (no variance, see the test functions).
    pub values: Vec<[f64; 3]>,
    /// Number of tests the Šidák correction is over (blocks × channels).
    pub tests: usize,
    pub critical: f64,
    /// `None` when no block was tested.
    pub worst: Option<Worst>,
    width: u32,
    height: u32,
    test_image: Vec<[f32; 3]>,
    reference: Vec<[f32; 3]>,
}

impl BlockTest {
    fn new(
        statistic: &'static str,
        block: u32,
        width: u32,
        height: u32,
        critical: f64,
        test_image: Vec<[f32; 3]>,
        reference: Vec<[f32; 3]>,
    ) -> Self {
        let (blocks_x, blocks_y) = (width / block, height / block);
        BlockTest {
            statistic,
            block,
            blocks_x,
            blocks_y,
            values: vec![[f64::NAN; 3]; (blocks_x * blocks_y) as usize],
            tests: (blocks_x * blocks_y * 3) as usize,
            critical,
            worst: None,
            width,
            height,
            test_image,
            reference,
        }
    }

    fn record(&mut self, bx: u32, by: u32, c: usize, value: f64, test_mean: f64, ref_mean: f64) {
        self.values[(by * self.blocks_x + bx) as usize][c] = value;
        let replace = match self.worst {
            None => true,
            Some(w) => !w.value.is_nan() && (value.is_nan() || value > w.value),
        };
        if replace {
            self.worst = Some(Worst {
                value,
                bx,
                by,
                channel: c,
                test_mean,
                reference_mean: ref_mean,
            });
        }
    }

    /// Whether every tested block is below the critical value (a NaN statistic fails).
    pub fn passed(&self) -> bool {
        self.worst.is_none_or(|w| w.value < self.critical)
    }

    /// The largest statistic (0 when no block was tested).
    pub fn worst_value(&self) -> f64 {
        self.worst.map_or(0.0, |w| w.value)
    }

    /// One line: the worst block, its statistic and the critical value.
    pub fn summary(&self) -> String {
        let s = self.statistic;
        match self.worst {
            None => format!("no block tested (critical {s} {:.2})", self.critical),
            Some(w) => format!(
                "worst block {s} = {:.2} at block ({},{}) channel {} (test {:.5} vs reference \
                 {:.5}; critical {:.2}, {} tests of {}×{}-pixel blocks)",
                w.value,
                w.bx,
                w.by,
                w.channel,
                w.test_mean,
                w.reference_mean,
                self.critical,
                self.tests,
                self.block,
                self.block
            ),
        }
    }

    /// Writes the evidence of this test into [`super::evidence::dir`]`(what)`:
    /// `test.pfm` (the tested image; for a t-test the mean of the runs), `reference.pfm`,
    /// and `<statistic>_map.pfm` (one pixel per block, each channel that channel's
    /// statistic; NaN where untested) with `<statistic>_map_full.pfm` (the same at image
    /// resolution, to overlay). Returns the folder.
    pub fn write_evidence(&self, what: &str) -> std::io::Result<std::path::PathBuf> {
        use super::evidence::{dir, write_pfm};
        let d = dir(what)?;
        write_pfm(
            &d.join("test.pfm"),
            self.width,
            self.height,
            &self.test_image,
        )?;
        write_pfm(
            &d.join("reference.pfm"),
            self.width,
            self.height,
            &self.reference,
        )?;
        let map: Vec<[f32; 3]> = self.values.iter().map(|v| v.map(|x| x as f32)).collect();
        let s = self.statistic;
        write_pfm(
            &d.join(format!("{s}_map.pfm")),
            self.blocks_x,
            self.blocks_y,
            &map,
        )?;
        let mut full = vec![[f32::NAN; 3]; (self.width * self.height) as usize];
        for y in 0..(self.blocks_y * self.block) {
            for x in 0..(self.blocks_x * self.block) {
                full[(y * self.width + x) as usize] =
                    map[((y / self.block) * self.blocks_x + x / self.block) as usize];
            }
        }
        write_pfm(
            &d.join(format!("{s}_map_full.pfm")),
            self.width,
            self.height,
            &full,
        )?;
        std::fs::write(
            d.join("summary.txt"),
            format!("{what}: {}\n", self.summary()),
        )?;
        Ok(d)
    }

    /// Prints the summary (`what: worst block …`) when the test passed; otherwise writes
    /// the evidence ([`BlockTest::write_evidence`]) and panics with the summary and the
    /// evidence folder.
    pub fn assert_passes(&self, what: &str) {
        if self.passed() {
            eprintln!("{what}: {}", self.summary());
            return;
        }
        let evidence = match self.write_evidence(what) {
            Ok(d) => format!(
                "evidence (test, reference, per-block map) in {}",
                d.display()
            ),
            Err(e) => format!("could not write evidence images: {e}"),
        };
        panic!(
            "{what}: {} ≥ critical {:.2}: {}; {evidence}",
            self.statistic,
            self.critical,
            self.summary()
        );
    }
}

/// Block z-test of two independent unbiased estimates of the same image (or of an image
/// against a reference with known per-pixel variance): per `block`×`block` block and
/// channel, z = |Σ(a − b)| / √(Σ(var_a + var_b)), against the two-sided normal quantile
/// with Šidák correction at family-wise level `alpha` over blocks × channels. A block
/// whose summed variance is not positive is not tested (it still counts in the
/// correction). Pixels beyond the last whole block are ignored.
pub fn block_z_test(test: &Estimate, reference: &Estimate, block: u32, alpha: f64) -> BlockTest {
    let (w, h) = (test.width, test.height);
    assert_eq!((w, h), (reference.width, reference.height), "image sizes");
    let tests = ((w / block) * (h / block) * 3) as usize;
    let mut out = BlockTest::new(
        "z",
        block,
        w,
        h,
        sidak_z(alpha, tests),
        test.pixels_f32(),
        reference.pixels_f32(),
    );
    let n = (block * block) as f64;
    for by in 0..h / block {
        for bx in 0..w / block {
            for c in 0..3 {
                let (mut d, mut v) = (0.0f64, 0.0f64);
                let (mut st, mut sr) = (0.0f64, 0.0f64);
                for y in by * block..(by + 1) * block {
                    for x in bx * block..(bx + 1) * block {
                        let i = (y * w + x) as usize;
                        let r = reference.mean[i][c];
                        d += test.mean[i][c] - r;
                        v += test.variance[i][c] + reference.variance[i][c];
                        st += test.mean[i][c];
                        sr += r;
                    }
                }
                if v > 0.0 {
                    out.record(bx, by, c, d.abs() / v.sqrt(), st / n, sr / n);
                }
            }
        }
    }
    out
}

/// Block t-test of `runs`, independent renders of one image (pixel values, rows top to
/// bottom, the reference's size), against `reference`, an estimate with per-pixel
/// variances: per `block`×`block` block and channel, with m̄ and s² the mean and sample
/// variance of the R runs' block means and v_ref the variance of the reference's block
/// mean (Σ var / n²), T = |m̄ − m_ref| / √(s²/R + v_ref), Student-t with R − 1 degrees of
/// freedom under the null hypothesis (block means of independent renders iid and close to
/// normal); compared with the two-sided quantile with Šidák correction at family-wise level
/// `alpha` over blocks × channels. Use it when the renders' own per-pixel variances are
/// not trustworthy. A block with zero standard error fails unless m̄ equals m_ref exactly
/// (T = ∞), and is not tested if it does.
pub fn block_t_test(runs: &[&[Vec3]], reference: &Estimate, block: u32, alpha: f64) -> BlockTest {
    let (w, h) = (reference.width, reference.height);
    assert!(runs.len() >= 2, "a t-test needs at least two runs");
    for r in runs {
        assert_eq!(r.len(), (w * h) as usize, "run size");
    }
    let r = runs.len() as f64;
    let tests = ((w / block) * (h / block) * 3) as usize;
    let mean_image: Vec<[f32; 3]> = (0..(w * h) as usize)
        .map(|i| {
            let s = runs.iter().map(|p| p[i].as_dvec3()).sum::<glam::DVec3>() / r;
            [s.x as f32, s.y as f32, s.z as f32]
        })
        .collect();
    let mut out = BlockTest::new(
        "t",
        block,
        w,
        h,
        sidak_t(alpha, tests, r - 1.0),
        mean_image,
        reference.pixels_f32(),
    );
    let n = (block * block) as f64;
    let block_sum = |px: &dyn Fn(usize) -> f64, bx: u32, by: u32| {
        let mut s = 0.0f64;
        for y in by * block..(by + 1) * block {
            for x in bx * block..(bx + 1) * block {
                s += px((y * w + x) as usize);
            }
        }
        s
    };
    for by in 0..h / block {
        for bx in 0..w / block {
            for c in 0..3 {
                let means: Vec<f64> = runs
                    .iter()
                    .map(|p| block_sum(&|i| p[i][c] as f64, bx, by) / n)
                    .collect();
                let refm = block_sum(&|i| reference.mean[i][c], bx, by) / n;
                let refv = block_sum(&|i| reference.variance[i][c], bx, by) / (n * n);
                let m = means.iter().sum::<f64>() / r;
                let s2 = means.iter().map(|b| (b - m).powi(2)).sum::<f64>() / (r - 1.0);
                let se = (s2 / r + refv).sqrt();
                if se == 0.0 {
                    if m != refm {
                        out.record(bx, by, c, f64::INFINITY, m, refm);
                    }
                    continue;
                }
                out.record(bx, by, c, (m - refm).abs() / se, m, refm);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_match_tables() {
        // Standard normal and Student-t tables (Abramowitz & Stegun 26.2, 26.7).
        // Reference values from Python's statistics.NormalDist().inv_cdf, to 1e-8 (the
        // approximation's 1.2e-9 relative error plus the digits printed here).
        assert!((normal_quantile(0.975) - 1.959_963_985).abs() < 1e-8);
        assert!((normal_quantile(0.5)).abs() < 1e-12);
        assert!((normal_quantile(0.001) + 3.090_232_306).abs() < 1e-8);
        assert!((normal_quantile(1.0 - 1e-6) - 4.753_424_309).abs() < 1e-8);
        assert!((t_quantile(0.975, 30.0) - 2.042_272).abs() < 2e-3);
        assert!((t_quantile(0.995, 11.0) - 3.105_807).abs() < 0.03);
        // Šidák over one test is the level itself.
        assert!((sidak(0.01, 1) - 0.01).abs() < 1e-15);
        assert!((sidak_z(0.05, 1) - 1.959_964).abs() < 1e-6);
    }

    fn img(w: u32, h: u32, v: f32, var: f32) -> Estimate {
        let n = (w * h) as usize;
        Estimate::new(w, h, &vec![Vec3::splat(v); n], &vec![Vec3::splat(var); n])
    }

    #[test]
    fn block_z_test_finds_the_shifted_block() {
        let a = img(16, 16, 1.0, 0.01);
        let mut b = a.clone();
        // Shift block (1, 0) channel 2 by 0.2 per pixel: z = 64·0.2 / √(64·0.02) ≈ 11.3.
        for y in 0..8 {
            for x in 8..16 {
                b.mean[y * 16 + x][2] += 0.2;
            }
        }
        let t = block_z_test(&a, &a, 8, 0.01);
        assert!(t.passed() && t.worst_value() == 0.0, "{}", t.summary());
        let t = block_z_test(&b, &a, 8, 0.01);
        assert!(!t.passed());
        let w = t.worst.unwrap();
        assert_eq!((w.bx, w.by, w.channel), (1, 0, 2));
        // f32 inputs (0.01 is not exact): 1e-6 relative.
        assert!((w.value / (12.8 / 1.28f64.sqrt()) - 1.0).abs() < 1e-6);
        assert_eq!(t.tests, 12);
        // NaN fails.
        b.mean[0][0] = f64::NAN;
        assert!(!block_z_test(&b, &a, 8, 0.01).passed());
    }

    #[test]
    fn block_t_test_detects_bias_and_accepts_noise() {
        let reference = img(8, 8, 1.0, 1e-6);
        let noisy: Vec<Vec<Vec3>> = (0..8)
            .map(|k| vec![Vec3::splat(1.0 + 0.01 * ((k % 3) as f32 - 1.0)); 64])
            .collect();
        let runs: Vec<&[Vec3]> = noisy.iter().map(|v| v.as_slice()).collect();
        let t = block_t_test(&runs, &reference, 8, 0.01);
        assert!(t.passed(), "{}", t.summary());
        let biased: Vec<Vec<Vec3>> = noisy
            .iter()
            .map(|v| v.iter().map(|p| *p + Vec3::splat(0.1)).collect())
            .collect();
        let runs: Vec<&[Vec3]> = biased.iter().map(|v| v.as_slice()).collect();
        assert!(!block_t_test(&runs, &reference, 8, 0.01).passed());
        // Noiseless and different: fails; noiseless and equal: passes.
        let exact = img(8, 8, 1.0, 0.0);
        let same = [vec![Vec3::ONE; 64], vec![Vec3::ONE; 64]];
        let runs: Vec<&[Vec3]> = same.iter().map(|v| v.as_slice()).collect();
        assert!(block_t_test(&runs, &exact, 8, 0.01).passed());
        let off = [vec![Vec3::splat(2.0); 64], vec![Vec3::splat(2.0); 64]];
        let runs: Vec<&[Vec3]> = off.iter().map(|v| v.as_slice()).collect();
        assert!(!block_t_test(&runs, &exact, 8, 0.01).passed());
    }

    #[test]
    fn failing_test_writes_evidence_and_names_it() {
        let a = img(16, 8, 1.0, 0.01);
        let mut b = a.clone();
        b.mean[3][1] += 50.0;
        let t = block_z_test(&b, &a, 8, 0.01);
        let msg = std::panic::catch_unwind(|| t.assert_passes("evidence self-test"))
            .unwrap_err()
            .downcast::<String>()
            .unwrap();
        assert!(msg.contains("block (0,0) channel 1"), "{msg}");
        let d = t.write_evidence("evidence self-test").unwrap();
        assert!(msg.contains(&d.display().to_string()), "{msg}");
        assert!(d.to_string_lossy().contains("test-evidence"));
        let (w, h, px) = super::super::evidence::read_pfm(&d.join("test.pfm")).unwrap();
        assert_eq!((w, h), (16, 8));
        assert_eq!(px[3], [1.0, 51.0, 1.0]);
        let (bw, bh, map) = super::super::evidence::read_pfm(&d.join("z_map.pfm")).unwrap();
        assert_eq!((bw, bh), (2, 1));
        assert!(map[0][1] > 10.0 && map[1][1] == 0.0);
        let _ = std::fs::remove_dir_all(d);
    }
}
