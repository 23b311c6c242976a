//! The path probe: whether frame-by-frame path tracing renders a frame as well as a
//! reuse technique would, measured, so that a technique that cannot gain renders the
//! frame as its baseline would and says so (issue 17: "a technique that cannot gain must
//! notice it and spend its effort as the baseline would").
//!
//! A photon technique such as `spacetime-dept` gains over path tracing in two ways only:
//! it **reuses per-pixel light** over frames where the animation leaves a pixel's paths
//! unchanged ([`crate::kernels::elements::reuse`]), and it reads **indirect light** from smooth element
//! estimates where path tracing samples it. Where the first is impossible (decided from
//! the animation: [`crate::kernels::elements::reuse::Validity`] refuses every pixel against every other
//! frame within the light history, as under a sky while anything moves, or under a moving camera), what is left is
//! the second, and its worth is what the indirect light adds to path tracing's noise.
//! [`probe`] measures that on every [`PROBE_ROW_STEP`]-th row of the frame, at
//! [`PROBE_SPP`] samples per pixel: the path
//! tracer's per-pixel variance of the whole sample against that of its direct part alone
//! (the same samples, [`crate::framework::integrator::LightSplit`]'s convention), each relative to
//! the pixel's direct light (mean² + 0.01, as relMSE's), summed over the pixels. The
//! direct part, not the whole sample, sets a pixel's weight because it is the less noisy
//! one: with the whole sample's mean, a firefly lowered its own pixel's weight, which at
//! 4 samples per pixel under-counted noisy indirect light (`LightsPunctualLamp` of
//! `../shared/scenes`, 96²: 1.09 at 4 samples, 1.18 at 16; with the direct mean 1.42). Their
//! ratio `R` bounds what the elements can gain at equal camera samples: with noise-free
//! elements and no light reuse, the technique's variance is at best the direct part's,
//! i.e. `1 / R` of path tracing's. It costs its photons, its reconstruction and its eye
//! pass besides, which on the sky-lit glTF models measured was 1.10–1.21× `path`'s CPU at
//! the same samples (BENCHMARKS.md, "Sky-lit models at 256²"), so at `R ≤`
//! [`MAX_PATH_RATIO`] = 1.1 path tracing is at least as efficient, and unbiased.
//!
//! Everything here is a function of the scene, the frame and the seed (sample streams,
//! not timings), so a run is deterministic and a farm segment decides as a single run
//! does: the probe of frame f is made at [`probe_frame`], the first frame of the render
//! list in f's block of `period` frames, within a segment's context when `period` is at
//! most the technique's window.

use crate::framework::integrator::RadianceEstimator;
use crate::kernels::path::{PathSettings, PathTracer};
use chronolux_core::color::luminance;
use chronolux_core::math::Vec2;
use chronolux_core::parallel;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use chronolux_core::stats::Stats;

/// The probe traces every `PROBE_ROW_STEP`-th row (1/8 of the pixels: 8k at 256²).
pub const PROBE_ROW_STEP: u32 = 8;

/// Samples per pixel of the probe (at most; at least 2 for a variance). The ratio is one
/// of per-sample variances, whatever the samples per pixel, so the probe takes no more
/// than these: at 16 samples per pixel it costs 1/32 of a `path` frame per block.
pub const PROBE_SPP: u32 = 4;

/// Largest ratio `R` (see the module documentation) at which path tracing renders the
/// frame: the photon technique's own cost over path's at equal samples, measured 1.10–1.21
/// where nothing is reused.
pub const MAX_PATH_RATIO: f64 = 1.1;

/// Offset added to a pixel's squared direct mean in its relative variance (as relMSE's
/// 0.01), so that black pixels do not dominate.
const REL_EPS: f64 = 0.01;

/// What the probe of one frame measured.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Probe {
    /// The frame probed.
    pub frame: u32,
    /// Σ over the probed pixels of var(whole sample) / (direct mean² + 0.01), over the
    /// same sum of var(direct part) (luminance): `R` of the module documentation; infinite
    /// when the direct part has no variance and the whole sample has.
    pub variance_ratio: f64,
    /// Pixels probed.
    pub pixels: u64,
}

impl Probe {
    /// Whether path tracing renders the frame ([`MAX_PATH_RATIO`]).
    pub fn path_suffices(&self) -> bool {
        self.variance_ratio <= MAX_PATH_RATIO
    }
}

/// The path tracer a probe and a frame rendered as `path` use: `path`'s defaults with
/// these samples, depth limit and seed (so the frame is `path`'s frame bit for bit).
pub fn path_tracer(spp: u32, max_depth: Option<u32>, seed: u64) -> PathTracer {
    PathTracer::new(PathSettings {
        common: crate::framework::technique::CommonSettings {
            spp,
            max_depth,
            seed,
        },
        ..PathSettings::default()
    })
}

/// The frame whose probe decides for `frame`: the first frame of `source`'s render list in
/// `frame`'s block `[period · ⌊frame / period⌋, frame]`.
pub fn probe_frame(source: &FrameSource, frame: u32, period: u32) -> u32 {
    let period = period.max(1);
    source
        .window(frame, frame % period, 0)
        .first()
        .copied()
        .unwrap_or(frame)
}

/// Probes `frame` of `scene` with `pt` at `spp` samples per pixel (clamped to
/// 2..=[`PROBE_SPP`]), from the streams of (`seed`, `frame`, pixel) as
/// [`crate::framework::integrator::render_camera_rays`] draws them.
pub fn probe(scene: &FrameScene, frame: u32, pt: &PathTracer, spp: u32, seed: u64) -> Probe {
    let spp = spp.clamp(2, PROBE_SPP);
    let (w, h) = (scene.camera.width, scene.camera.height);
    let rows: Vec<u32> = if h < PROBE_ROW_STEP {
        vec![h / 2]
    } else {
        (PROBE_ROW_STEP / 2..h)
            .step_by(PROBE_ROW_STEP as usize)
            .collect()
    };
    let n = spp as f64;
    let sums = parallel::map_chunks(rows.len(), 1, |range| {
        let mut stats = Stats::default();
        let (mut whole, mut direct, mut pixels) = (0.0f64, 0.0f64, 0u64);
        for &py in &rows[range] {
            for px in 0..w {
                let mut sampler = PixelSampler::new(seed, frame, px, py);
                // Σ, Σ² of the whole sample's and the direct part's luminance.
                let mut m = [0.0f64; 4];
                for s in 0..spp {
                    sampler.start_sample(s);
                    let raster = Vec2::new(px as f32, py as f32) + sampler.next_2d();
                    let ray = scene.camera.generate_ray(raster);
                    let [d, i] = pt.li_split(scene, &ray, &mut sampler, &mut stats);
                    let (t, d) = (luminance(d + i) as f64, luminance(d) as f64);
                    if !(t.is_finite() && d.is_finite()) {
                        continue;
                    }
                    m[0] += t;
                    m[1] += t * t;
                    m[2] += d;
                    m[3] += d * d;
                }
                let mean = m[2] / n; // the direct part's: see the module documentation
                let var = |s: f64, s2: f64| ((s2 - s * s / n) / (n - 1.0)).max(0.0);
                let k = 1.0 / (mean * mean + REL_EPS);
                whole += var(m[0], m[1]) * k;
                direct += var(m[2], m[3]) * k;
                pixels += 1;
            }
        }
        (whole, direct, pixels)
    });
    let (whole, direct, pixels) = sums
        .into_iter()
        .fold((0.0, 0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
    let variance_ratio = if direct > 0.0 {
        whole / direct
    } else if whole > 0.0 {
        f64::INFINITY
    } else {
        1.0
    };
    Probe {
        frame,
        variance_ratio,
        pixels,
    }
}
