//! Which strategies the per-sample estimator uses (module doc, "BDPT or the path
//! strategies"): all of BDPT's, or only those of path tracing (s ≤ 1, MIS over those
//! only, no light subpath: [`BdptSettings::path_strategies`]). A frame generated with all
//! strategies also evaluates, on the same camera subpaths and light samples, the estimate
//! the path strategies would have given, and counts what each part cost; [`decide`]
//! compares the two estimators' efficiency (1 / (variance × cost)) and, on a grid frame
//! ([`super::adapt::GRID`]), chooses the strategies of the frames up to the next. Counts and sample values only, never timings,
//! so images stay bit-identical across thread counts and runs.
//!
//! [`BdptSettings::path_strategies`]: crate::kernels::bdpt::BdptSettings::path_strategies

use chronolux_core::color::Rgb;

/// Cost of a shadow-ray query (standing for its whole connection or light sample: BSDF
/// evaluations, the MIS weight over the path, the query) relative to a closest-hit query
/// (a walk's segment with its surface interaction and BSDF sampling). Fitted (least
/// squares, CPU = a·closest-hit + b·shadow) to `path` and `bdpt` at 8 spp on RiggedSimple
/// `--stage cornell`, cornell-moving and the demo (64×64, frames 0–7, `--threads 1`, CPU s
/// from `bench quality`, query counts from `render`'s `run.json`; one run each, load
/// 3–4; `bench-results/2026-12-02-stbpt2/cost-calibration/`): a = 0.25 µs, b = 0.95 µs,
/// b / a = 3.9. With it the query counts give BDPT / path cost ratios of 4.10, 2.63 and
/// 3.91 against the measured 4.22, 2.63 and 3.71.
pub const SHADOW_QUERY_COST: f64 = 3.9;

/// In a pilot frame, one pixel pair in `PILOT_EVERY` uses all strategies ([`pilot_pixel`]).
pub const PILOT_EVERY: u32 = 4;

/// How a generated frame's samples are made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// All strategies, every sample (with the pilot's measurements when adaptive).
    Bdpt,
    /// The path strategies, every sample.
    Path,
    /// All strategies (and the measurements) at the [`pilot_pixel`]s, the path
    /// strategies elsewhere: what the comparison needs at a quarter of its cost.
    Pilot,
    /// All strategies, every sample, no measurements: the frames after a grid frame that
    /// chose BDPT, until the next grid frame ([`super::adapt::GRID`]).
    BdptQuiet,
}

impl Mode {
    pub(super) fn name(self) -> String {
        match self {
            Mode::Bdpt | Mode::BdptQuiet => "bdpt",
            Mode::Path => "path",
            Mode::Pilot => "pilot",
        }
        .to_string()
    }
}

/// The pixels of a pilot frame whose samples use all strategies: horizontal pairs (x, x ^ 1),
/// one pair in [`PILOT_EVERY`] along each row, shifted by one pair per row. Pairs, so that
/// a pixel's neighbour sample (one sample per pixel, [`Pilot::variances`]) is a pilot
/// sample too.
pub fn pilot_pixel(x: u32, y: u32) -> bool {
    ((x >> 1) + y).is_multiple_of(PILOT_EVERY)
}

/// Floor of a pixel's luminance in the relative variance, as a fraction of the frame's
/// mean: keeps black pixels from dominating the comparison.
const DARK_FLOOR: f64 = 0.1;

/// How much more efficient the path strategies must measure (BDPT's variance × cost over
/// theirs) for the next frame to use them. The variances come from 1–16 samples per
/// pixel and miss heavy tails that more samples meet: on the dolly (moving camera, so no
/// light tracing; the glass caustic seen directly), BDPT's measured per-sample variance
/// grew from 0.34 to 1.48 between 2 and 8 spp, and the ratio reached 1.1 where all
/// strategies were in fact the better choice (stbpt FLIP 0.122 with them against 0.148
/// with the path strategies at 8 spp). On RiggedSimple it is 2.1–2.4 at 1–16 spp, on
/// cornell-moving 1.0–1.5. A margin chosen between these measurements, not derived.
pub const SWITCH_MARGIN: f64 = 1.5;

/// Largest share of the image's light (luminance of BDPT's contributions) that may come
/// from paths the path strategies cannot make for them to be chosen: the path strategies
/// would miss it (a bias, not a variance).
pub const UNREACHABLE_MAX: f64 = 1e-3;

/// The pilot statistics of one generated frame: per pixel of f, its own samples' values
/// under both estimators and the light-tracing splats it received.
#[derive(Clone, Debug, Default)]
pub struct Pilot {
    pub width: u32,
    pub height: u32,
    /// Per pixel: Σ x_bdpt, Σ x_bdpt², Σ x_path, Σ x_path², samples (luminance of the
    /// camera part: all t ≥ 2 strategies with BDPT's weights / s ≤ 1 with path weights).
    pub pixels: Vec<[f64; 5]>,
    /// Per pixel: Σ (luminance of a light-tracing splat)², unscaled.
    pub splat_sq: Vec<f64>,
    /// Per pixel: the correction of the path strategies' sampled second moment Σ x_path²,
    /// i.e. the diagonal terms (each strategy's own second moment, Σ_A w'² f² / p_{s'})
    /// importance-sampled from every BDPT contribution landing there (camera part and
    /// splats) minus the same terms as the path samples themselves gave (Σ c_path²). The
    /// cross terms between path lengths of one camera subpath stay sampled (module doc).
    pub moment: Vec<f64>,
    /// Luminance of the contributions whose paths no path strategy can make, and of all.
    pub unreachable: f64,
    pub reachable: f64,
    /// Luminance of the contributions by strategy group: s ≤ 1 (the path strategies),
    /// s ≥ 2 with t ≥ 2 (connections to light subpaths), t = 1 (light tracing).
    pub shares: [f64; 3],
    /// Ray-query cost of the pilot samples' own-frame work in closest-hit units: all of
    /// it / only the path strategies' part (camera subpaths and s ≤ 1 light samples), and
    /// the number of pilot samples.
    pub cost_bdpt: f64,
    pub cost_path: f64,
    pub samples: u64,
    /// The same cost and count for the frame's other samples.
    pub other_cost: f64,
    pub other_samples: u64,
}

/// Luminance (Rec. 709).
pub fn luminance(c: Rgb) -> f64 {
    0.2126 * c.x as f64 + 0.7152 * c.y as f64 + 0.0722 * c.z as f64
}

impl Pilot {
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        Pilot {
            width,
            height,
            pixels: vec![[0.0; 5]; n],
            splat_sq: vec![0.0; n],
            moment: vec![0.0; n],
            ..Default::default()
        }
    }

    /// One sample of f in `pixel`: its camera part's luminance with all strategies and with
    /// the path strategies, and the correction of the path strategies' second moment
    /// (importance-sampled diagonal terms minus the sample's own: see [`Pilot::moment`]).
    pub fn add_sample(&mut self, pixel: u32, bdpt: f64, path: f64, moment: f64) {
        self.moment[pixel as usize] += moment;
        let p = &mut self.pixels[pixel as usize];
        p[0] += bdpt;
        p[1] += bdpt * bdpt;
        p[2] += path;
        p[3] += path * path;
        p[4] += 1.0;
    }

    /// Relative variance per sample of the two estimators, (bdpt, path from the
    /// importance-sampled second moment, path from its own samples), averaged over the
    /// measured pixels with a common weight per pixel 1 / (μ̂² + (0.1·L̄)²) (μ̂: the mean
    /// of the path estimate over the measured pixels of the 5×5 neighbourhood, the pixel
    /// included; L̄: the image mean). Per pixel: the sample variance of its samples
    /// (n ≥ 2), or with one sample x² − x·m(q), m(q) the mean of its pair partner (an
    /// independent sample of a neighbouring mean: unbiased where the image is locally
    /// flat). BDPT's light tracing adds Σ c² / spp per pixel (the splat sum S/spp over
    /// independent light subpaths has variance ≈ Σ c² / spp², i.e. Σ c² / spp per
    /// sample; in a pilot frame the splats come from a share of the samples and are scaled
    /// up by it). The importance-sampled path variance is `(Σ x_path² + moment) / n − μ̂²`,
    /// μ̂² from the path samples' products of distinct samples (n ≥ 2) or with the
    /// partner's mean.
    pub fn variances(&self, spp: u32) -> (f64, f64, f64) {
        let (w, h) = (self.width as usize, self.height as usize);
        let mean = |i: usize, k: usize| {
            let p = &self.pixels[i];
            if p[4] > 0.0 { p[k] / p[4] } else { 0.0 }
        };
        let var = |i: usize, q: usize, k: usize| {
            let p = &self.pixels[i];
            let n = p[4];
            if n >= 2.0 {
                (p[k + 1] - p[k] * p[k] / n) / (n - 1.0)
            } else if n == 1.0 {
                p[k + 1] - p[k] * mean(q, k)
            } else {
                0.0
            }
        };
        let square = |i: usize, q: usize| {
            let p = &self.pixels[i];
            let n = p[4];
            if n >= 2.0 {
                (p[2] * p[2] - p[3]) / (n * (n - 1.0))
            } else if n == 1.0 {
                p[2] * mean(q, 2)
            } else {
                0.0
            }
        };
        let measured = (0..w * h).filter(|&i| self.pixels[i][4] > 0.0).count();
        let total: f64 = (0..w * h).map(|i| mean(i, 2)).sum();
        let floor = (DARK_FLOOR * total / measured.max(1) as f64).powi(2);
        let (mut vb, mut vp, mut vs) = (0.0, 0.0, 0.0);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if self.pixels[i][4] == 0.0 {
                    continue;
                }
                // The pair partner (a pilot pixel too), else the previous pixel.
                let q = if (x ^ 1) < w {
                    y * w + (x ^ 1)
                } else {
                    i.saturating_sub(1)
                };
                // The local mean over the measured pixels around, the pixel included
                // (without it, a pixel on an emitter's edge next to a dark partner would
                // get a weight for the dark).
                let mut s = 0.0;
                let mut c = 0.0;
                for yy in y.saturating_sub(2)..(y + 3).min(h) {
                    for xx in x.saturating_sub(2)..(x + 3).min(w) {
                        if self.pixels[yy * w + xx][4] > 0.0 {
                            s += mean(yy * w + xx, 2);
                            c += 1.0;
                        }
                    }
                }
                let mu = if c > 0.0 { (s / c).max(0.0) } else { 0.0 };
                let weight = 1.0 / (mu * mu + floor).max(f64::MIN_POSITIVE);
                vb += weight * (var(i, q, 0) + self.splat_sq[i] / spp.max(1) as f64);
                vs += weight * var(i, q, 2);
                let n = self.pixels[i][4];
                if n > 0.0 {
                    let p = &self.pixels[i];
                    vp += weight * ((p[3] + self.moment[i]) / n - square(i, q));
                }
            }
        }
        let n = measured.max(1) as f64;
        (vb.max(0.0) / n, vp.max(0.0) / n, vs.max(0.0) / n)
    }
}

/// The choice of strategies after one generated frame (`strategy_decision` in its
/// `run.json` record).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StrategyDecision {
    /// Strategies the frame's samples were generated with: `bdpt`, `path` or `pilot`
    /// (all strategies at a quarter of the pixels, [`pilot_pixel`], the path strategies
    /// elsewhere).
    pub strategies: String,
    /// Strategies of the frames up to the next grid frame ([`super::adapt::GRID`]).
    pub next: String,
    /// Why: `bdpt` / `path` (on a grid frame: the comparison below chose them), `grid`
    /// (another frame: its grid frame's choice), `fixed` (no adaptation).
    pub decision: String,
    /// Relative variance per sample of the camera-part estimate plus light tracing, with
    /// all strategies (measured only on frames generated with them) and with the path
    /// strategies.
    pub variance_bdpt: Option<f64>,
    pub variance_path: Option<f64>,
    /// The path strategies' variance from their own samples (the pilot's values under
    /// their weights): what `variance_path` would be without importance sampling; it
    /// misses the rare high-valued paths (caustics) that few samples do not meet.
    pub variance_path_sampled: Option<f64>,
    /// Share of the luminance of BDPT's contributions on paths no path strategy can make
    /// (e.g. caustics of point lights); above `UNREACHABLE_MAX` BDPT is kept.
    pub unreachable_share: Option<f64>,
    /// Share of the image's light (luminance of BDPT's contributions in f) that came from
    /// the strategies s ≤ 1, from connections s ≥ 2 (t ≥ 2) and from light tracing (t = 1)
    /// (frames with all strategies).
    pub contribution_shares: Option<[f64; 3]>,
    /// Cost per sample in closest-hit ray queries (shadow queries count
    /// `SHADOW_QUERY_COST`) of the frame's own samples: all strategies (measured only on
    /// frames generated with them) / the path strategies' part (0 in a frame with all
    /// strategies and no measurements, whose own cost is `cost_bdpt` then).
    pub cost_bdpt: Option<f64>,
    pub cost_path: f64,
    /// (variance × cost) of BDPT over that of the path strategies: above 1, the path
    /// strategies reach a given variance for less work.
    pub bdpt_over_path: Option<f64>,
}

/// Decides how the frames after a grid frame are made from `pilot` (f's own samples,
/// `spp` per pixel; `mode`: how f was made). Without `adaptive`, or after a frame without
/// measurements, the mode stays (`fixed`, `grid`).
///
/// Rule: after a frame with measurements (all strategies or pilot), the next frames use the
/// path strategies iff `SWITCH_MARGIN` × variance_path × cost_path < variance_bdpt ×
/// cost_bdpt and the share of light they cannot reach is at most `UNREACHABLE_MAX`, else
/// all strategies without measurements.
pub fn decide(pilot: &Pilot, spp: u32, mode: Mode, adaptive: bool) -> (Mode, StrategyDecision) {
    let (vb, vp, vs) = pilot.variances(spp);
    let measured = matches!(mode, Mode::Bdpt | Mode::Pilot) && pilot.samples > 0;
    let cost_path = if measured {
        pilot.cost_path / pilot.samples as f64
    } else if mode == Mode::BdptQuiet {
        0.0
    } else {
        pilot.other_cost / pilot.other_samples.max(1) as f64
    };
    let cost_bdpt = pilot.cost_bdpt / pilot.samples.max(1) as f64;
    let mut d = StrategyDecision {
        strategies: mode.name(),
        variance_path: measured.then_some(vp),
        variance_path_sampled: measured.then_some(vs),
        cost_path,
        ..Default::default()
    };
    let unreachable = pilot.unreachable / pilot.reachable.max(f64::MIN_POSITIVE);
    if mode == Mode::BdptQuiet {
        d.cost_bdpt = Some(pilot.other_cost / pilot.other_samples.max(1) as f64);
    }
    if measured {
        d.unreachable_share = Some(unreachable);
        let total: f64 = pilot.shares.iter().sum();
        d.contribution_shares = Some(pilot.shares.map(|x| x / total.max(f64::MIN_POSITIVE)));
        d.variance_bdpt = Some(vb);
        d.cost_bdpt = Some(cost_bdpt);
        d.bdpt_over_path = Some(vb * cost_bdpt / (vp * cost_path).max(f64::MIN_POSITIVE));
    }
    let (next, why) = if !adaptive {
        (mode, "fixed")
    } else if !measured {
        (mode, "grid")
    } else if unreachable <= UNREACHABLE_MAX && SWITCH_MARGIN * vp * cost_path < vb * cost_bdpt {
        (Mode::Path, "path")
    } else {
        (Mode::BdptQuiet, "bdpt")
    };
    d.next = next.name();
    d.decision = why.to_string();
    (next, d)
}
