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
//! The camera-ray driver ([`chronolux_render::integrator::render_camera_rays`]) always
//! starts at sample index 0 of the stream keyed by (seed, frame, pixel), so disjoint
//! sample-index ranges of one stream are not reachable through the `Integrator` API.
//! Instead every (half, round) pair gets its own seed, `hash(--seed, round, half)`: each
//! seed is a different Owen scrambling of the Sobol sequence, i.e. an independent
//! randomisation, so batches are independent of each other (and stratified within a
//! batch). A and B are therefore independent, as the estimate requires.
//!
//! Output: `frame_NNNN.exr` (the average) + `.png`, the halves `frame_NNNN_A.exr` and
//! `frame_NNNN_B.exr` (for noise floors), and `run.json`, whose per-frame `stats` record
//! `spp` (total over both halves), `rounds`, `error_estimate`, `target_error` and
//! `converged`.

use crate::cli::SceneArgs;
use crate::render::{last_frame, parse_frames, parse_resolution};
use crate::scene_input;
use anyhow::{Context, Result, bail};
use chronolux_core::color::Rgb;
use chronolux_core::metrics::REL_MSE_EPS;
use chronolux_core::sampling::hash_words;
use chronolux_core::scene::frame::{FrameBuilder, FrameScene};
use chronolux_io::image::{Image, write_exr};
use chronolux_io::output::{FrameRecord, FrameSink, Manifest, frame_stem};
use chronolux_render::integrator::Integrator;
use chronolux_render::pt::{PathSettings, PathTracer};
use clap::Args;
use std::sync::Arc;
use std::time::Instant;

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

/// Result of one progressively rendered frame.
pub struct Converged {
    pub mean: Vec<Rgb>,
    pub half_a: Vec<Rgb>,
    pub half_b: Vec<Rgb>,
    /// Total samples per pixel (both halves).
    pub spp: u32,
    pub rounds: u32,
    pub error_estimate: f64,
    pub rays: u64,
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

/// Seed of the batch of `half` (0 = A, 1 = B) in `round`.
pub fn batch_seed(seed: u64, round: u32, half: u32) -> u64 {
    hash_words(&[seed, 0x7265_6665_7265_6e63, round as u64, half as u64])
}

/// Renders `frame` of `scene` progressively until the error estimate is ≤ `target` or
/// `max_spp` is reached; `on_round(spp, estimate)` reports each round.
pub fn render_converged(
    scene: &FrameScene,
    frame: u32,
    settings: &PathSettings,
    target: f64,
    start_spp: u32,
    max_spp: u32,
    mut on_round: impl FnMut(u32, f64),
) -> Converged {
    let mut sums: [Vec<Rgb>; 2] = [Vec::new(), Vec::new()];
    let mut n_half = 0u32;
    let mut batch = (start_spp / 2).max(1);
    let mut round = 0u32;
    let mut rays = 0u64;
    loop {
        for (h, sum) in sums.iter_mut().enumerate() {
            let pt = PathTracer::new(PathSettings {
                spp: batch,
                seed: batch_seed(settings.seed, round, h as u32),
                ..settings.clone()
            });
            let out = pt.render(scene, frame, &|_| {});
            rays += out.stats.rays + out.stats.shadow_rays;
            if sum.is_empty() {
                *sum = vec![Rgb::ZERO; out.pixels.len()];
            }
            for (s, p) in sum.iter_mut().zip(&out.pixels) {
                *s += *p * batch as f32;
            }
        }
        n_half += batch;
        round += 1;
        let inv = 1.0 / n_half as f32;
        let a: Vec<Rgb> = sums[0].iter().map(|s| *s * inv).collect();
        let b: Vec<Rgb> = sums[1].iter().map(|s| *s * inv).collect();
        let est = half_error_estimate(&a, &b);
        on_round(2 * n_half, est);
        let room = (max_spp / 2).saturating_sub(n_half);
        if est <= target || room == 0 {
            let mean = a.iter().zip(&b).map(|(x, y)| (*x + *y) * 0.5).collect();
            return Converged {
                mean,
                half_a: a,
                half_b: b,
                spp: 2 * n_half,
                rounds: round,
                error_estimate: est,
                rays,
            };
        }
        batch = n_half.min(room);
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
    let settings = PathSettings {
        spp: args.start_spp,
        max_depth: args.max_depth,
        rr_depth: 5,
        seed: args.seed,
    };
    let desc = Arc::new(input.desc);
    let mut builder = FrameBuilder::new(desc.clone(), input.animation, input.camera.clone(), w, h)?;
    let run_settings = serde_json::json!({
        "kind": "reference",
        "technique": {"method": "path", "max_depth": args.max_depth, "rr_depth": 5, "seed": args.seed},
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
    let total = Instant::now();
    for &f in &frames {
        if args.resume && sink.is_complete(f) && manifest.frame(f).is_some() {
            eprintln!("frame {f}: already complete, skipped (--resume)");
            continue;
        }
        let t = f as f32 / args.fps;
        let start = Instant::now();
        let scene = builder.build(t);
        let c = render_converged(
            &scene,
            f,
            &settings,
            args.target_error,
            args.start_spp,
            args.max_spp,
            |spp, est| eprintln!("frame {f}: {spp:>7} spp, estimated relMSE {est:.3e}"),
        );
        let img = |p: Vec<Rgb>| Image::from_pixels(w, h, p);
        sink.write_frame(f, &img(c.mean), 0.0)
            .with_context(|| format!("writing frame {f}"))?;
        for (suffix, half) in [("A", c.half_a), ("B", c.half_b)] {
            let p = sink.dir().join(format!("{}_{suffix}.exr", frame_stem(f)));
            write_exr(&p, &img(half)).with_context(|| format!("writing {}", p.display()))?;
        }
        let converged = c.error_estimate <= args.target_error;
        let wall = start.elapsed().as_secs_f64();
        manifest.upsert_frame(FrameRecord::new(
            f,
            t,
            wall,
            serde_json::json!({
                "spp": c.spp,
                "rounds": c.rounds,
                "error_estimate": c.error_estimate,
                "target_error": args.target_error,
                "converged": converged,
                "rays": c.rays,
            }),
        ));
        sink.write_manifest(&manifest)?;
        eprintln!(
            "frame {f}: {} spp, estimated relMSE {:.3e}{} in {wall:.1} s",
            c.spp,
            c.error_estimate,
            if converged {
                ""
            } else {
                " (NOT converged: --max-spp reached)"
            }
        );
    }
    manifest.finish(total.elapsed().as_secs_f64());
    sink.write_manifest(&manifest)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
