//! `chronolux reference`: converged references, rendered progressively to a target error.
//!
//! ## How the error is estimated
//! Each frame is rendered as two independent half images A and B, in rounds: round 0 adds
//! `--start-spp`/2 samples per pixel to each half, every later round as many as the half
//! already has, so the total doubles each round. After each round the remaining error of
//! the average M = (A + B)/2 is estimated as
//!
//! ê = mean over pixels and channels of (A − B)² / (M² + 0.01) / 4
//!   = relMSE-style mean of ((A − B)/2)² / (M² + 0.01),
//!
//! and rendering stops when ê ≤ `--target-error` or the total reaches `--max-spp`.
//! Derivation: A and B are unbiased and independent with (per pixel and channel) variance
//! σ² each, so E[(A − B)²] = Var A + Var B = 2σ², while the average has
//! Var M = σ²/2 = E[(A − B)²]/4. Dividing by (R² + 0.01) with the (unknown) converged R
//! replaced by M turns this into an estimate of relMSE(M, R), the figure `compare` reports.
//! (It is the same quantity as the peers' "relMSE of the reference's own noise".)
//!
//! ## Independence of the samples
//! The frames are rendered by the registry's `path` technique as successive passes
//! through the progressive run loop (`chronolux_render::framework::run::run_progressive`,
//! `FrameByFrame::render_passes`): pass 2r + h is round r of half h (even passes make A,
//! odd ones B) and draws from its own seed, `batch_seed(--seed, round, half)`: each seed
//! is a different Owen scrambling of the Sobol sequence, i.e. an independent
//! randomisation, so batches are independent of each other (and stratified within a
//! batch). A and B are therefore independent, as the estimate requires. This sink stops a
//! frame after a pair of passes whose estimate is at most the target.
//!
//! Output: `frame_NNNN.exr` (the average) + `.png`, the halves `frame_NNNN_A.exr` and
//! `frame_NNNN_B.exr` (for noise floors), and `run.json`, whose per-frame `stats` record
//! `spp` (total over both halves), `rounds`, `error_estimate`, `target_error` and
//! `converged`.

use crate::args::SceneArgs;
use crate::render::{last_frame, parse_frames, parse_resolution};
use crate::scene_input;
use anyhow::{Result, bail};
use chronolux_core::color::Rgb;
use chronolux_core::metrics::REL_MSE_EPS;
use chronolux_core::scene::frame::FrameBuilder;
use chronolux_core::scene::source::FrameSource;
use chronolux_io::image::{Image, write_exr};
use chronolux_io::output::{FrameRecord, FrameSink, Manifest, frame_stem};
use chronolux_render::framework::run;
use chronolux_render::framework::sequence::{Flow, Pass, PassPlan};
use chronolux_render::registry::{self, BuildContext};
use clap::Args;
use std::sync::Arc;

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Frames to render: `A..B` (half-open), `A..=B` or `N`. Default: every frame of the clip.
    #[arg(long, value_name = "RANGE")]
    pub frames: Option<String>,
    /// Frames per second of the animation timeline.
    #[arg(long, default_value_t = 24.0, value_name = "FPS")]
    pub fps: f32,
    /// Stop a frame when its estimated remaining relMSE is at most this. The estimate is
    /// mean ((A − B)/2)² / (M² + 0.01) over the two independent half images A, B and their
    /// average M (the expected relMSE of M, since Var M = E[(A − B)²]/4).
    #[arg(long, default_value_t = 1e-4, value_name = "E")]
    pub target_error: f64,
    /// Most samples per pixel per frame (both halves together); a frame that reaches it
    /// is written with `converged: false` in run.json.
    #[arg(long, default_value_t = 65536, value_name = "N")]
    pub max_spp: u32,
    /// Samples per pixel of the first round (both halves together, at least 2); each
    /// later round doubles the total.
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub start_spp: u32,
    /// Image size in pixels, WIDTHxHEIGHT. Default: 512 wide, height from the camera's
    /// aspect ratio.
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<String>,
    /// Longest light path in segments from the camera (Mitsuba's max_depth). Default:
    /// unlimited (Russian roulette ends paths).
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u32>,
    /// Base seed; the seeds of the halves and rounds are derived from it.
    #[arg(long, default_value_t = 0, value_name = "S")]
    pub seed: u64,
    /// Worker threads (default: all cores). Images do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Output folder.
    #[arg(long, short, default_value = "reference", value_name = "DIR")]
    pub output: std::path::PathBuf,
    /// Skip frames already complete in the output folder (EXR and PNG present and whole).
    #[arg(long)]
    pub resume: bool,
}

/// Estimated remaining relMSE of (A + B)/2: mean of ((A − B)/2)² / (M² + 0.01).
pub fn half_error_estimate(a: &[Rgb], b: &[Rgb]) -> f64 {
    assert_eq!(a.len(), b.len());
    if a.is_empty() {
        return 0.0;
    }
    let mut s = 0.0f64;
    for (p, q) in a.iter().zip(b) {
        for c in 0..3 {
            let (x, y) = (f64::from(p[c]), f64::from(q[c]));
            let m = 0.5 * (x + y);
            let d = 0.5 * (x - y);
            s += d * d / (m * m + REL_MSE_EPS);
        }
    }
    s / (3 * a.len()) as f64
}

/// Accumulates the passes of a frame into the halves A (even passes) and B (odd passes)
/// and stops the frame once the error estimate of their mean is at most the target.
struct Converge {
    target: f64,
    sums: [Vec<Rgb>; 2],
    n_half: [u32; 2],
    rounds: u32,
    estimate: f64,
    rays: u64,
    frame: u32,
}

impl Converge {
    fn halves(&self) -> [Vec<Rgb>; 2] {
        let half = |h: usize| {
            let inv = 1.0 / self.n_half[h].max(1) as f32;
            self.sums[h].iter().map(|s| *s * inv).collect()
        };
        [half(0), half(1)]
    }
}

/// Writes the converged frames, their halves and run.json.
struct ReferenceSink<'a> {
    sink: &'a FrameSink,
    manifest: Manifest,
    resume: bool,
    c: Converge,
    w: u32,
    h: u32,
}

impl run::FrameSink for ReferenceSink<'_> {
    fn needs(&self, frame: u32) -> bool {
        !(self.resume && self.sink.is_complete(frame) && self.manifest.frame(frame).is_some())
    }

    fn skipped(&mut self, frame: u32, _: usize, _: usize) {
        eprintln!("frame {frame}: already complete, skipped (--resume)");
    }

    fn begin_frame(&mut self, frame: u32, _: usize, _: usize) {
        self.c = Converge {
            target: self.c.target,
            sums: [Vec::new(), Vec::new()],
            n_half: [0, 0],
            rounds: 0,
            estimate: f64::INFINITY,
            rays: 0,
            frame,
        };
    }

    fn pass(&mut self, pass: &Pass) -> Flow {
        let c = &mut self.c;
        let h = (pass.index % 2) as usize;
        let out = pass.image;
        c.rays += out.stats.rays + out.stats.shadow_rays;
        if c.sums[h].is_empty() {
            c.sums[h] = vec![Rgb::ZERO; out.pixels.len()];
        }
        for (s, p) in c.sums[h].iter_mut().zip(&out.pixels) {
            *s += *p * pass.spp as f32;
        }
        c.n_half[h] += pass.spp;
        if h == 0 {
            return Flow::Continue;
        }
        c.rounds += 1;
        let [a, b] = c.halves();
        c.estimate = half_error_estimate(&a, &b);
        eprintln!(
            "frame {}: {:>7} spp, estimated relMSE {:.3e}",
            c.frame, pass.total_spp, c.estimate
        );
        if c.estimate <= c.target {
            Flow::Stop
        } else {
            Flow::Continue
        }
    }

    fn frame(&mut self, f: &run::FinishedFrame) -> Result<(), run::SinkError> {
        let c = &self.c;
        let [a, b] = c.halves();
        let mean: Vec<Rgb> = a.iter().zip(&b).map(|(x, y)| (*x + *y) * 0.5).collect();
        let img = |p: Vec<Rgb>| Image::from_pixels(self.w, self.h, p);
        self.sink
            .write_frame(f.frame, &img(mean), 0.0)
            .map_err(|e| format!("writing frame {}: {e}", f.frame))?;
        for (suffix, half) in [("A", a), ("B", b)] {
            let p = self
                .sink
                .dir()
                .join(format!("{}_{suffix}.exr", frame_stem(f.frame)));
            write_exr(&p, &img(half)).map_err(|e| format!("writing {}: {e}", p.display()))?;
        }
        let converged = c.estimate <= c.target;
        let spp = c.n_half[0] + c.n_half[1];
        self.manifest.upsert_frame(FrameRecord::new(
            f.frame,
            f.time_s,
            f.wall_s,
            serde_json::json!({
                "spp": spp,
                "rounds": c.rounds,
                "error_estimate": c.estimate,
                "target_error": c.target,
                "converged": converged,
                "rays": c.rays,
            }),
        ));
        self.sink.write_manifest(&self.manifest)?;
        eprintln!(
            "frame {}: {} spp, estimated relMSE {:.3e}{} in {:.1} s",
            f.frame,
            spp,
            c.estimate,
            if converged {
                ""
            } else {
                " (NOT converged: --max-spp reached)"
            },
            f.wall_s
        );
        Ok(())
    }

    fn finish(&mut self, summary: &run::RunSummary) -> Result<(), run::SinkError> {
        self.manifest.finish(summary.wall_s);
        self.sink.write_manifest(&self.manifest)?;
        Ok(())
    }
}

pub fn run(args: ReferenceArgs) -> Result<()> {
    if !(args.target_error > 0.0 && args.target_error.is_finite()) {
        bail!("--target-error must be a positive relMSE, e.g. 1e-4");
    }
    if args.start_spp < 2 || args.max_spp < args.start_spp || args.max_spp > 1 << 24 {
        bail!(
            "need 2 ≤ --start-spp ({}) ≤ --max-spp ({}) ≤ {}",
            args.start_spp,
            args.max_spp,
            1 << 24
        );
    }
    crate::render::check_fps_and_depth(args.fps, args.max_depth)?;
    crate::render::set_threads(args.threads)?;
    let input = scene_input::load(&args.scene)?;
    let last = last_frame(&input.desc, input.animation, args.fps);
    let frames = match &args.frames {
        Some(s) => parse_frames(s)?,
        None => (0..=last.unwrap_or(0)).collect(),
    };
    if let Some(last) = last {
        let max = *frames.iter().max().unwrap();
        if max > last {
            bail!("--frames goes to frame {max}, but the animation ends at frame {last}");
        }
    }
    let (w, h) = match &args.resolution {
        Some(r) => parse_resolution(r)?,
        None => crate::render::default_resolution(&input.desc, &input.camera),
    };
    let sink = FrameSink::create(&args.output)?;
    // The path tracer of the registry, in passes of the paired-doubling schedule
    // (`FrameByFrame::render_passes`): pass 2r + h is round r of half h, with its own seed.
    let tech = registry::find("path").map_err(anyhow::Error::msg)?;
    let mut technique =
        serde_json::json!({"spp": args.start_spp, "rr_depth": 5, "seed": args.seed});
    if let Some(d) = args.max_depth {
        technique["max_depth"] = d.into();
    }
    let technique = registry::resolve(tech, Some(&technique), &[]).map_err(anyhow::Error::msg)?;
    let mut renderer = tech
        .build(&technique, &BuildContext::default())
        .map_err(anyhow::Error::msg)?;
    let desc = Arc::new(input.desc);
    let builder = FrameBuilder::new(desc.clone(), input.animation, input.camera.clone(), w, h)?;
    let mut source = FrameSource::new(builder, args.fps, frames.clone());
    let run_settings = serde_json::json!({
        "kind": "reference",
        "method": "path",
        "technique": technique,
        "target_error": args.target_error,
        "error_estimate": "mean ((A - B)/2)^2 / (M^2 + 0.01) of two independent halves A, B; M = (A + B)/2",
        "start_spp": args.start_spp,
        "max_spp": args.max_spp,
        "resolution": [w, h],
        "fps": args.fps,
        "frames": frames,
        "animation": input.animation.map(|a| desc.animations[a.index()].name.clone()),
    });
    let mut manifest = Manifest::new(
        std::env::args().collect(),
        run_settings,
        serde_json::json!({ "source": input.source }),
    );
    if args.resume
        && let Some(earlier) = sink.read_manifest()?
    {
        manifest.merge_earlier(&earlier);
    }
    eprintln!(
        "reference: {} frame(s) of {} at {w}x{h}, target relMSE {:e}, {}..{} spp, into {}",
        frames.len(),
        input.source,
        args.target_error,
        args.start_spp,
        args.max_spp,
        args.output.display()
    );
    let mut out = ReferenceSink {
        sink: &sink,
        manifest,
        resume: args.resume,
        c: Converge {
            target: args.target_error,
            sums: [Vec::new(), Vec::new()],
            n_half: [0, 0],
            rounds: 0,
            estimate: f64::INFINITY,
            rays: 0,
            frame: 0,
        },
        w,
        h,
    };
    run::run_progressive(
        renderer.as_mut(),
        &mut source,
        &frames,
        PassPlan {
            first_spp: args.start_spp,
            max_spp: args.max_spp,
        },
        &mut [&mut out],
        None,
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use chronolux_render::framework::sequence::batch_seed;

    #[test]
    fn estimate_of_identical_halves_is_zero_and_of_known_halves_is_computed() {
        let a = vec![Rgb::splat(0.5); 10];
        assert_eq!(half_error_estimate(&a, &a), 0.0);
        let b = vec![Rgb::splat(0.3); 10];
        // M = 0.4, (A − B)/2 = 0.1 → 0.01 / (0.16 + 0.01).
        assert!((half_error_estimate(&a, &b) - 0.01 / 0.17).abs() < 1e-7);
    }

    #[test]
    fn batch_seeds_differ_between_halves_and_rounds() {
        let mut seen = std::collections::HashSet::new();
        for r in 0..20 {
            for h in 0..2 {
                assert!(seen.insert(batch_seed(0, r, h)));
            }
        }
    }
}
