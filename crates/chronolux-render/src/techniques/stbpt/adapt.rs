//! Self-assessment (module doc, "Choosing K"): from what the samples of a generated frame
//! gave the frames around it, [`assess`] decides whether serving each distance paid for
//! itself and, on a grid frame ([`GRID`]), chooses the window half-width K of the frames
//! up to the next grid frame — down to K = 0, frame-by-frame BDPT, when reuse does not
//! pay at all. The decision and the
//! statistics it came from are reported per frame ([`WindowDecision`], `reuse_decision` in
//! `run.json`). Everything here is computed from counts (landings, ray queries), never
//! from timings, so images stay bit-identical across thread counts and runs.

use chronolux_core::stats::Stats;

/// What a reused sample is worth relative to a fresh sample of the frame it serves.
/// Measured (BENCHMARKS.md, issue 4, "Why not 10×"): stbpt at 1 spp matched BDPT at
/// 4.7–5.5 spp with 6.5 frames served per sample, i.e. 0.72–0.85 of a fresh sample per
/// landing; the lower end, rounded.
pub const REUSE_WORTH: f64 = 0.7;

/// Work per landed sample other than ray queries (BSDF re-evaluation at x1, two film
/// writes), in BDPT samples. Measured on the static Cornell box (`CornellBox.glb`, 64×64,
/// frames 0–7, 2 spp, `--threads 1`, one run), where every landing is a reuse and serving
/// costs no ray: stbpt K = 4 took 1.07 CPU s against 0.86 for K = 0, with 6.43 landings
/// per sample in other frames: (1.07 / 0.86 − 1) / 6.43 ≈ 0.04 (one run at load 6–10, so
/// rounded up).
pub const LANDING_COST: f64 = 0.05;

/// Period of the measuring frames: frame f is a **grid frame** when f is a multiple of
/// `GRID` (a global frame index, whatever the render list or the farm segment). Grid
/// frames are generated at the cap K with all strategies and the pilot's measurements;
/// every decision for the frames f + 1 .. f + GRID − 1 (their K and their strategies) is
/// a function of that grid frame's measurement alone (module doc, "Choosing K").
pub const GRID: u32 = 4;

/// What the samples of one generated frame gave the frames at one distance (one frame
/// before and one after, when both are in the render list). Per generated sample.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DistanceStats {
    /// |g − f| in frames.
    pub distance: u32,
    /// Samples that landed there, served by reuse (fully or partially) and by re-tracing.
    pub landed: f64,
    pub reused: f64,
    pub retraced: f64,
    /// What reuse gave, in fresh samples: `REUSE_WORTH × reused`. A re-traced landing is
    /// a fresh sample of that frame bought at a fresh sample's price (its own ray queries
    /// are left out of `cost`), so it counts neither way; its landing does.
    pub value: f64,
    /// What serving cost beyond the re-traces, in BDPT samples: the ray queries (closest-
    /// hit and shadow) spent on those frames other than the re-traces' camera subpaths and
    /// connections — landing rays, regenerated light subpaths, light tracing, the partial
    /// reuses' recomputed strategies — over the ray queries of the generated frame's own
    /// samples (≈ a BDPT sample each), plus `LANDING_COST` per landing.
    pub cost: f64,
}

impl DistanceStats {
    /// Serving this distance paid for itself: the same work spent on fresh samples of
    /// those frames would have given fewer samples than the landings' worth.
    pub fn pays(&self) -> bool {
        self.value > self.cost
    }
}

/// The self-assessment of one generated frame (`reuse_decision` in its `run.json` record).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WindowDecision {
    /// K the frame's samples were generated with (its window [f − K, f + K]).
    pub k: u32,
    /// The largest K allowed (the `window` setting).
    pub k_max: u32,
    /// K of the frames up to the next grid frame ([`GRID`]): chosen on a grid frame, its
    /// grid frame's choice on the others.
    pub k_next: u32,
    /// Why, in words (on a grid frame): `keep` (every distance paid), `shrink`,
    /// `frame-by-frame` (reuse did not pay at distance 1: the effort goes into fresh BDPT
    /// samples as frame-by-frame `bdpt` would spend it), `minimum` (reuse did not pay but
    /// motion blur needs K ≥ 1); `grid` on the other frames (their grid frame's choice);
    /// `fixed` (adaptation off or nothing to choose).
    pub decision: String,
    /// Frames served per generated sample, its own included.
    pub served_per_sample: f64,
    /// Cost of a generated sample in BDPT samples (own ray queries count 1).
    pub cost_per_sample: f64,
    /// Per distance 1..=K present in the render list.
    pub distances: Vec<DistanceStats>,
}

/// One window frame of a generated frame: its distance from f, its landings and the ray
/// queries spent serving it.
pub struct Served {
    pub distance: u32,
    pub landed: u64,
    pub reused: u64,
    pub retraced: u64,
    /// All ray queries spent on the frame.
    pub stats: Stats,
    /// Of those, the re-traced landings' (camera subpaths and connections).
    pub retrace_queries: u64,
}

/// The decision after generating a frame with window half-width `k` (`frames`: its window
/// frames, the generated frame itself at distance 0; `generated`: samples generated).
/// K stays within `k_min..=k_max` (`k_min` = 1 with motion blur, which needs the
/// neighbouring frames). A function of these statistics alone: on a grid frame (`k` =
/// `k_max`, its window every frame within `k_max`, in the render list or not), of the
/// grid frame's index and the scene only.
///
/// Rule: serving distance d pays when the landings' value exceeds their cost
/// ([`DistanceStats::pays`]). K_next is the largest d such that every distance 1..=d
/// present paid (`k` when all did).
pub fn assess(
    frames: &[Served],
    generated: u64,
    k: u32,
    k_min: u32,
    k_max: u32,
    adaptive: bool,
) -> WindowDecision {
    let g = generated.max(1) as f64;
    let queries = |s: &Stats| (s.rays + s.shadow_rays) as f64;
    let own = frames
        .iter()
        .filter(|s| s.distance == 0)
        .map(|s| queries(&s.stats))
        .sum::<f64>()
        .max(1.0);
    let mut distances: Vec<DistanceStats> = Vec::new();
    for s in frames.iter().filter(|s| s.distance > 0) {
        let i = match distances.iter().position(|d| d.distance == s.distance) {
            Some(i) => i,
            None => {
                distances.push(DistanceStats {
                    distance: s.distance,
                    ..Default::default()
                });
                distances.len() - 1
            }
        };
        let d = &mut distances[i];
        d.landed += s.landed as f64 / g;
        d.reused += s.reused as f64 / g;
        d.retraced += s.retraced as f64 / g;
        d.value += REUSE_WORTH * s.reused as f64 / g;
        d.cost += (queries(&s.stats) - s.retrace_queries as f64) / own
            + LANDING_COST * s.landed as f64 / g;
    }
    distances.sort_by_key(|d| d.distance);
    let served_per_sample = frames.iter().map(|s| s.landed as f64).sum::<f64>() / g;
    let retrace_cost: f64 = frames
        .iter()
        .filter(|s| s.distance > 0)
        .map(|s| s.retrace_queries as f64 / own)
        .sum();
    let cost_per_sample = 1.0 + retrace_cost + distances.iter().map(|d| d.cost).sum::<f64>();
    let (k_next, decision) = if !adaptive || k_max <= k_min {
        (k_max, "fixed")
    } else {
        // Distances without a frame (before frame 0) count as paying: no evidence
        // against them.
        let paying = (1..=k)
            .take_while(|&d| distances.iter().all(|s| s.distance != d || s.pays()))
            .count() as u32;
        if paying == k && k > 0 {
            (k, "keep")
        } else if paying < k_min {
            (k_min, "minimum")
        } else if paying == 0 {
            (0, "frame-by-frame")
        } else {
            (paying, "shrink")
        }
    };
    WindowDecision {
        k,
        k_max,
        k_next,
        decision: decision.to_string(),
        served_per_sample,
        cost_per_sample,
        distances,
    }
}
