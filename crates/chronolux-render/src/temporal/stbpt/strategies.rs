//! Which strategies the per-sample estimator uses (module doc, "BDPT or the path
//! strategies"): all of BDPT's, or only those of path tracing (s ≤ 1, MIS over those
//! only, no light subpath: [`BdptSettings::path_strategies`]). A frame generated with all
//! strategies also evaluates, on the same camera subpaths and light samples, the estimate
//! the path strategies would have given, and counts what each part cost; [`decide`]
//! compares the two estimators' efficiency (1 / (variance × cost)) and chooses the
//! strategies of the next generated frame. Counts and sample values only, never timings,
//! so images stay bit-identical across thread counts and runs.
//!
//! [`BdptSettings::path_strategies`]: crate::bdpt::BdptSettings::path_strategies

use chronolux_core::color::Rgb;

/// Cost of a shadow-ray query (a connection or light sample with its MIS weight and BSDF
/// evaluations) relative to a closest-hit query (a walk's segment with its surface
/// interaction and BSDF sampling). Measured: `path` and `bdpt` at 8 spp on RiggedSimple
/// `--stage cornell`, 64×64, frames 0–3, `--threads 1`, one run each (load 2.3):
/// path 0.71 CPU s for 0.488 M closest-hit and 0.321 M shadow queries, bdpt 1.67 CPU s
/// for 0.945 M and 1.587 M; the two equations a·rays + b·shadow = CPU give a = 1.25 µs,
/// b = 0.31 µs, b / a = 0.25.
pub const SHADOW_QUERY_COST: f64 = 0.16;

/// Generated frames with the path strategies after which one frame is generated with all
/// of BDPT's to measure both again (the comparison needs the light subpaths).
pub const PROBE_EVERY: u32 = 4;

/// Floor of a pixel's luminance in the relative variance, as a fraction of the frame's
/// mean: keeps black pixels from dominating the comparison.
const DARK_FLOOR: f64 = 0.1;

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
    /// Ray-query cost of the frame's own samples in closest-hit units: all of them / only
    /// the path strategies' part (camera subpaths and s ≤ 1 light samples).
    pub cost_bdpt: f64,
    pub cost_path: f64,
    pub samples: u64,
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
    /// importance-sampled second moment, path from its own samples), summed over the
    /// pixels with a common weight per pixel 1 / (μ̂² + (0.1·L̄)²) (μ̂: the 3×3 mean of
    /// the path estimate, L̄: its image mean). Per pixel: the sample variance of its
    /// samples (n ≥ 2), or with one sample x² − x·m(q), m(q) the mean of the next pixel
    /// of the row (an independent sample of a neighbouring mean: unbiased where the image
    /// is locally flat). BDPT's light tracing adds Σ c² / spp per pixel (the splat sum
    /// S/spp over independent light subpaths has variance ≈ Σ c² / spp², i.e. Σ c² / spp
    /// per sample). The importance-sampled path variance is `(Σ x_path² + moment) / n − μ̂²`, μ̂² from
    /// the path samples' products of distinct samples (n ≥ 2) or with the neighbour's mean.
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
        let total: f64 = (0..w * h).map(|i| mean(i, 2)).sum();
        let floor = (DARK_FLOOR * total / (w * h).max(1) as f64).powi(2);
        let (mut vb, mut vp, mut vs) = (0.0, 0.0, 0.0);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let q = if x + 1 < w {
                    i + 1
                } else {
                    i.saturating_sub(1)
                };
                let mut s = 0.0;
                let mut c = 0.0;
                for yy in y.saturating_sub(1)..(y + 2).min(h) {
                    for xx in x.saturating_sub(1)..(x + 2).min(w) {
                        s += mean(yy * w + xx, 2);
                        c += 1.0;
                    }
                }
                let mu = (s / c).max(0.0);
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
        let n = (w * h).max(1) as f64;
        (vb.max(0.0) / n, vp.max(0.0) / n, vs.max(0.0) / n)
    }
}

/// The choice of strategies after one generated frame (`strategy_decision` in its
/// `run.json` record).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StrategyDecision {
    /// Strategies the frame's samples were generated with: `bdpt` or `path`.
    pub strategies: String,
    /// Strategies of the next generated frame.
    pub next: String,
    /// Why: `bdpt` / `path` (the comparison below chose them), `probe` (all strategies
    /// after `PROBE_EVERY` frames with the path strategies, to measure again), `path`
    /// kept between probes, `fixed` (no adaptation).
    pub decision: String,
    /// Relative variance per sample of the camera-part estimate plus light tracing, with
    /// all strategies (measured only on frames generated with them) and with the path
    /// strategies.
    pub variance_bdpt: Option<f64>,
    pub variance_path: f64,
    /// The path strategies' variance from their own samples (the pilot's values under
    /// their weights): what `variance_path` would be without importance sampling; it
    /// misses the rare high-valued paths (caustics) that few samples do not meet.
    pub variance_path_sampled: f64,
    /// Share of the luminance of BDPT's contributions on paths no path strategy can make
    /// (e.g. caustics of point lights); above `UNREACHABLE_MAX` BDPT is kept.
    pub unreachable_share: Option<f64>,
    /// Share of the image's light (luminance of BDPT's contributions in f) that came from
    /// the strategies s ≤ 1, from connections s ≥ 2 (t ≥ 2) and from light tracing (t = 1)
    /// (frames with all strategies).
    pub contribution_shares: Option<[f64; 3]>,
    /// Cost per sample in closest-hit ray queries (shadow queries count
    /// `SHADOW_QUERY_COST`) of the frame's own samples: all strategies (measured only on
    /// frames generated with them) / the path strategies' part.
    pub cost_bdpt: Option<f64>,
    pub cost_path: f64,
    /// (variance × cost) of BDPT over that of the path strategies: above 1, the path
    /// strategies reach a given variance for less work.
    pub bdpt_over_path: Option<f64>,
}

/// Decides the strategies of the next generated frame from `pilot` (f's own samples, `spp`
/// per pixel), which were generated with the path strategies iff `path`. `path_run` counts
/// the consecutive generated frames with the path strategies (updated here). Without
/// `adaptive` the strategies stay those of the settings (`fixed`).
///
/// Rule: after a frame with all strategies, the next uses the path strategies iff
/// variance_path × cost_path < variance_bdpt × cost_bdpt (equal efficiency keeps BDPT).
/// After a frame with the path strategies nothing can be compared: the path strategies
/// are kept, and after `PROBE_EVERY` such frames one frame is generated with all
/// strategies to measure again.
pub fn decide(
    pilot: &Pilot,
    spp: u32,
    path: bool,
    adaptive: bool,
    path_run: &mut u32,
) -> (bool, StrategyDecision) {
    let samples = pilot.samples.max(1) as f64;
    let (vb, vp, vs) = pilot.variances(spp);
    let cost_path = pilot.cost_path / samples;
    let cost_bdpt = pilot.cost_bdpt / samples;
    let name = |p: bool| if p { "path" } else { "bdpt" }.to_string();
    let mut d = StrategyDecision {
        strategies: name(path),
        variance_path: if path { vs } else { vp },
        variance_path_sampled: vs,
        cost_path,
        ..Default::default()
    };
    let unreachable = pilot.unreachable / pilot.reachable.max(f64::MIN_POSITIVE);
    if !path {
        d.unreachable_share = Some(unreachable);
        let total: f64 = pilot.shares.iter().sum();
        d.contribution_shares = Some(pilot.shares.map(|x| x / total.max(f64::MIN_POSITIVE)));
        d.variance_bdpt = Some(vb);
        d.cost_bdpt = Some(cost_bdpt);
        d.bdpt_over_path = Some(vb * cost_bdpt / (vp * cost_path).max(f64::MIN_POSITIVE));
    }
    let (next, why) = if !adaptive {
        (path, "fixed")
    } else if path {
        *path_run += 1;
        if *path_run >= PROBE_EVERY {
            (false, "probe")
        } else {
            (true, "path")
        }
    } else if unreachable <= UNREACHABLE_MAX && vp * cost_path < vb * cost_bdpt {
        (true, "path")
    } else {
        (false, "bdpt")
    };
    if !next {
        *path_run = 0;
    }
    d.next = name(next);
    d.decision = why.to_string();
    (next, d)
}
