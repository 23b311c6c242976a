//! `chronolux bench quality`: the equal-quality benchmark every temporal technique's
//! speed-up is quoted from.
//!
//! For a method (and its baseline), the effort (samples per pixel; thousands of photons
//! per frame for the photon methods) is doubled from `--start-effort` until the sequence reaches each target error
//! against converged references (HDR-ꟻLIP, mean over frames by default, or the worst
//! frame with `--criterion max`). Each effort level is a complete, independent render of
//! every frame, timed in wall-clock and CPU seconds (frame construction included, FLIP
//! excluded); the time to a target is the time of the first level that reaches it. The
//! flicker of that level (frame-to-frame differences against the reference's, see
//! `chronolux_core::metrics`) is reported beside it. The ratio baseline time / method time
//! is the speed-up.

use crate::args::SceneArgs;
use crate::config::{CommonFlags, FlagSetting, parse_sets, technique_settings};
use crate::render::{parse_frames, parse_resolution};
use crate::scene_input;
use anyhow::{Context, Result, bail};
use chronolux_core::metrics::{self, flip};
use chronolux_core::scene::frame::FrameBuilder;
use chronolux_core::scene::source::FrameSource;
use chronolux_io::image::read_exr;
use chronolux_render::framework::aov::PassSet;
use chronolux_render::framework::run::{FinishedFrame, FrameSink, RunOptions};
use chronolux_render::registry::{self, BuildContext, Technique};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Args, Debug)]
pub struct QualityArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Frames to render: `A..B`, `A..=B` or `N`.
    #[arg(long, value_name = "RANGE")]
    pub frames: String,
    /// Frames to score, a subset of --frames: comma-separated ranges or frames, e.g.
    /// `0..8,24,47`. Default: every rendered frame. Render more than you score so that a
    /// temporal technique's windows are whole where it is measured (not truncated by the
    /// ends of a short clip). Flicker is taken over consecutive measured frames. A
    /// frame-by-frame (stateless) method renders only the measured frames, since the
    /// others cannot change its images. Times are compared per measured frames: a run's
    /// time × measured / rendered frames (what that many frames of a long animation cost),
    /// so a temporal method that renders more frames than it scores is not charged for them.
    #[arg(long, value_name = "FRAMES")]
    pub measure: Option<String>,
    /// Folder of converged reference frames (frame_NNNN.exr), e.g. made by
    /// `chronolux reference`.
    #[arg(long, value_name = "DIR")]
    pub reference: PathBuf,
    /// The method measured.
    #[arg(long, default_value = "path", value_name = "METHOD")]
    pub method: String,
    /// The frame-by-frame baseline it must beat (default: none, only the method).
    #[arg(long, value_name = "METHOD")]
    pub baseline: Option<String>,
    /// Target HDR-FLIP errors, comma-separated (e.g. 0.12,0.09,0.07).
    #[arg(long, value_name = "F[,F...]", value_delimiter = ',', required = true)]
    pub target_flip: Vec<f64>,
    /// Which frames must reach the target: `mean` (the mean over frames) or `max` (every frame).
    #[arg(long, default_value = "mean", value_parser = ["mean", "max"])]
    pub criterion: String,
    /// First effort level tried (spp; thousands of photons per frame for photon methods);
    /// it doubles from there.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub start_effort: u32,
    /// Largest effort level tried; a target not met by then is reported as not reached.
    #[arg(long, default_value_t = 4096, value_name = "N")]
    pub max_effort: u32,
    /// Image size; must match the references. Default: the references' size.
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<String>,
    /// Longest path in segments (Mitsuba's max_depth). Default: unlimited.
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u32>,
    #[arg(long, default_value_t = 24.0, value_name = "FPS")]
    pub fps: f32,
    #[arg(long, default_value_t = 0, value_name = "S")]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// The `window` setting (stbpt's K: samples serve [f − K, f + K]; spacetime-dept's
    /// frames pooled on each side) of the methods that have one. Default: each method's.
    /// Recorded in the JSON.
    #[arg(long, value_name = "K")]
    pub window: Option<u32>,
    /// Set any setting of --method, `KEY=VALUE` (repeatable; as `render --set`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Set any setting of --baseline, `KEY=VALUE` (repeatable).
    #[arg(long = "baseline-set", value_name = "KEY=VALUE")]
    pub baseline_set: Vec<String>,
    /// Write a Markdown report (tables of every effort level) to this file.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Denoise every frame of every method with Open Image Denoise before scoring it
    /// (as `render --denoise`: the RT filter with the albedo and normal passes, which the
    /// run makes). The passes and the denoiser run inside the timed run, so their CPU
    /// seconds are counted. Needs a build with the `oidn` feature.
    #[arg(long)]
    pub denoise: bool,
    /// Open Image Denoise's quality with --denoise (as `render --denoise-quality`).
    #[arg(long, value_enum, value_name = "QUALITY", requires = "denoise")]
    pub denoise_quality: Option<crate::denoise::DenoiseQuality>,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Keeps each frame's image, denoised first when asked. The denoising happens in
/// [`FrameSink::frame`], inside the run loop's timing (its CPU seconds are the run's).
struct ScoredSink {
    denoise: Option<crate::denoise::DenoiseQuality>,
    frames: Vec<(u32, Vec<chronolux_core::color::Rgb>)>,
}

impl FrameSink for ScoredSink {
    fn frame(
        &mut self,
        f: &FinishedFrame,
    ) -> Result<(), chronolux_render::framework::run::SinkError> {
        let pixels = if let Some(quality) = self.denoise {
            let aovs = f
                .aovs
                .ok_or("bench quality --denoise: the run made no albedo/normal passes")?;
            crate::denoise::denoise(&f.output.pixels, aovs, quality)?
        } else {
            f.output.pixels.clone()
        };
        self.frames.push((f.frame, pixels));
        Ok(())
    }
}

/// One complete render of the sequence at one effort.
#[derive(Clone, Debug, Serialize)]
pub struct Level {
    pub effort: u32,
    /// Wall and process CPU seconds of the whole render (every frame rendered).
    pub wall_s: f64,
    pub cpu_s: f64,
    /// Frames this level rendered and scored. A temporal method renders more than it scores
    /// (`--measure`, whole windows), a frame-by-frame one only the scored frames; every
    /// comparison (times to a target, speed-ups) takes [`Level::scored_wall_s`] and
    /// [`Level::scored_cpu_s`], the time of as many frames of the run as were scored.
    pub frames_rendered: usize,
    pub frames_scored: usize,
    pub flip_mean: f64,
    pub flip_max: f64,
    pub relmse_mean: f64,
    /// Mean over pairs of measured frames consecutive in the render (None if no pair).
    pub flicker: Option<f64>,
}

impl Level {
    fn scored_share(&self) -> f64 {
        self.frames_scored as f64 / self.frames_rendered.max(1) as f64
    }

    /// Wall seconds of as many frames as were scored: the run's × scored / rendered, the
    /// cost of that many frames of a long animation (every frame of a temporal method pays
    /// for one frame's photons, samples and reconstruction, its window's or not).
    pub fn scored_wall_s(&self) -> f64 {
        self.wall_s * self.scored_share()
    }

    /// Process CPU seconds, scaled as [`Level::scored_wall_s`].
    pub fn scored_cpu_s(&self) -> f64 {
        self.cpu_s * self.scored_share()
    }
}

/// A method's curve and its times to each target.
#[derive(Clone, Debug, Serialize)]
pub struct MethodResult {
    pub method: String,
    pub levels: Vec<Level>,
    /// Per target: the first level reaching it (None: not reached up to max effort).
    pub reached: Vec<Option<Level>>,
    /// Per target: wall time interpolated to exactly the target, log-log between the two
    /// effort levels that bracket it (error falls as a power of effort, time rises
    /// linearly, so both are straight in log-log). The first-level rule above overstates a
    /// method's time by up to a whole doubling, depending only on where the grid falls;
    /// this removes that. `None` when the target is not bracketed. Per scored frames
    /// ([`Level::scored_wall_s`]).
    pub interpolated_time_s: Vec<Option<f64>>,
    /// The same in process CPU seconds (the comparison to use on a shared, loaded machine).
    pub interpolated_cpu_s: Vec<Option<f64>>,
    /// Two consecutive levels gave the same errors to the bit, so the effort does not change
    /// this method's images here; the levels stopped there.
    pub effort_has_no_effect: bool,
}

/// Wall time (per scored frames) at which `levels` (in increasing effort) reach `target`,
/// log-log interpolated.
pub fn interpolate_time(levels: &[Level], target: f64, criterion: &str) -> Option<f64> {
    interpolate_by(levels, target, criterion, Level::scored_wall_s)
}

/// CPU seconds at which `levels` reach `target`, interpolated as [`interpolate_time`].
pub fn interpolate_cpu(levels: &[Level], target: f64, criterion: &str) -> Option<f64> {
    interpolate_by(levels, target, criterion, Level::scored_cpu_s)
}

fn interpolate_by(
    levels: &[Level],
    target: f64,
    criterion: &str,
    time: impl Fn(&Level) -> f64,
) -> Option<f64> {
    let err = |l: &Level| {
        if criterion == "max" {
            l.flip_max
        } else {
            l.flip_mean
        }
    };
    let k = levels.iter().position(|l| err(l) <= target)?;
    if k == 0 {
        return (err(&levels[0]) == target).then_some(time(&levels[0]));
    }
    let (lo, hi) = (&levels[k - 1], &levels[k]);
    let (e0, e1) = (err(lo), err(hi));
    let (t0, t1) = (time(lo), time(hi));
    if !(e0 > e1 && e1 > 0.0 && t0 > 0.0 && t1 > 0.0) {
        return Some(t1);
    }
    let s = (e0 / target).ln() / (e0 / e1).ln();
    Some(t0 * (t1 / t0).powf(s))
}

/// The whole result; the flat fields are for the first target.
#[derive(Debug, Serialize)]
pub struct QualityResult {
    pub method: String,
    pub baseline: Option<String>,
    pub criterion: String,
    /// Whether every frame was denoised (Open Image Denoise) before scoring.
    pub denoise: bool,
    /// The denoiser's quality, when denoised.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub denoise_quality: Option<crate::denoise::DenoiseQuality>,
    /// Frames rendered at each level.
    pub frames: Vec<u32>,
    /// Frames scored (`--measure`; all rendered frames by default); flicker is over
    /// the pairs of them that are consecutive in `frames`.
    pub measured: Vec<u32>,
    pub target_flip: f64,
    pub method_time_s: Option<f64>,
    pub baseline_time_s: Option<f64>,
    /// baseline time / method time.
    pub speedup: Option<f64>,
    /// The same from times interpolated to exactly the target (see
    /// [`MethodResult::interpolated_time_s`]).
    pub method_time_interp_s: Option<f64>,
    pub baseline_time_interp_s: Option<f64>,
    pub speedup_interp: Option<f64>,
    /// The same in process CPU seconds.
    pub method_cpu_interp_s: Option<f64>,
    pub baseline_cpu_interp_s: Option<f64>,
    pub speedup_cpu_interp: Option<f64>,
    /// `--window` (stbpt's K), when given.
    pub window: Option<u32>,
    pub method_flicker: Option<f64>,
    pub baseline_flicker: Option<f64>,
    pub targets: Vec<f64>,
    pub results: Vec<MethodResult>,
}

/// The settings of `method` at `effort` (the unit its registry entry gives: samples per
/// pixel, or thousands of photons per frame). `seed` applies to every method (its common
/// settings); `max_depth` and `window` to the methods that have them (they are given for
/// the pair of methods); the flags given that did not apply are returned last.
pub fn config_for(
    method: &str,
    effort: u32,
    max_depth: Option<u32>,
    seed: u64,
    window: Option<u32>,
    sets: &[(String, serde_json::Value)],
) -> Result<(&'static dyn Technique, serde_json::Value, Vec<&'static str>)> {
    let tech = registry::find(method).map_err(anyhow::Error::msg)?;
    let e = tech.capabilities().effort;
    let amount = u64::from(effort) * e.per_unit;
    let defaults = tech.defaults();
    let mut flags = Vec::new();
    let mut photons = None;
    let mut ignored = Vec::new();
    let mut common = CommonFlags {
        seed: Some(seed),
        ..CommonFlags::default()
    };
    if max_depth.is_some() {
        if tech.capabilities().max_depth {
            common.max_depth = max_depth;
        } else {
            ignored.push("--max-depth");
        }
    }
    if tech.capabilities().photons && e.key == "photons" {
        photons = Some(amount.to_string());
    } else if e.key == "spp" {
        // Camera samples are the common block's, wherever the technique keeps it.
        common.spp = Some(u32::try_from(amount).context("effort beyond u32 samples")?);
    } else {
        flags.push(FlagSetting {
            flag: "the effort",
            key: e.key,
            value: amount.into(),
        });
    }
    if let Some(k) = window {
        if registry::find_key(&defaults, "window").is_some() {
            flags.push(FlagSetting {
                flag: "--window",
                key: "window",
                value: k.into(),
            });
        } else {
            ignored.push("--window");
        }
    }
    let s = technique_settings(tech, None, common, &flags, photons.as_deref(), sets)?;
    Ok((tech, s, ignored))
}

/// Parses `--measure`: comma-separated `A..B`, `A..=B` or `N`.
pub fn parse_measure(s: &str) -> Result<Vec<u32>> {
    let mut v = Vec::new();
    for part in s.split(',') {
        v.extend(parse_frames(part)?);
    }
    v.sort_unstable();
    v.dedup();
    Ok(v)
}

fn meets(level: &Level, target: f64, criterion: &str) -> bool {
    let v = if criterion == "max" {
        level.flip_max
    } else {
        level.flip_mean
    };
    v <= target
}

pub fn run(args: QualityArgs) -> Result<()> {
    let denoise = check(&args)?;
    let frames = parse_frames(&args.frames)?;
    let measured = match &args.measure {
        Some(m) => parse_measure(m)?,
        None => frames.clone(),
    };
    if let Some(f) = measured.iter().find(|f| !frames.contains(f)) {
        bail!("--measure names frame {f}, which --frames does not render");
    }
    let method_sets = parse_sets(&args.set)?;
    let baseline_sets = parse_sets(&args.baseline_set)?;
    let (refs, w, h) = load_references(&args, &measured)?;
    let mut targets = args.target_flip.clone();
    targets.sort_by(|a, b| b.partial_cmp(a).unwrap());
    let input = scene_input::load(&args.scene)?;
    let mut methods = vec![args.method.clone()];
    methods.extend(args.baseline.clone());
    let sets_of = |k: usize| if k == 0 { &method_sets } else { &baseline_sets };
    for (k, m) in methods.iter().enumerate() {
        warn_if_depth_ignored(&args, m, sets_of(k))?;
    }
    let bench = Bench {
        args: &args,
        desc: Arc::new(input.desc),
        animation: input.animation,
        camera: input.camera,
        size: (w, h),
        frames: &frames,
        measured: &measured,
        refs: &refs,
        denoise,
        hdr: flip::HdrSettings::default(),
        targets: &targets,
    };
    let mut results = Vec::new();
    for (mk, m) in methods.iter().enumerate() {
        results.push(bench.climb(m, sets_of(mk))?);
    }
    let result = summarize(&args, denoise, &frames, &measured, &targets, results);
    let md = markdown(&result);
    if let Some(p) = &args.report {
        chronolux_io::output::write_atomic(p, |w| std::io::Write::write_all(w, md.as_bytes()))
            .with_context(|| format!("writing report {}", p.display()))?;
    }
    if args.json {
        println!("{}", serde_json::to_string(&result)?);
    } else {
        print!("{md}");
    }
    Ok(())
}

/// The arguments checked (and the thread pool sized); the denoiser's quality when every
/// frame is denoised.
fn check(args: &QualityArgs) -> Result<Option<crate::denoise::DenoiseQuality>> {
    if args.start_effort == 0 || args.max_effort < args.start_effort {
        bail!("--start-effort must be ≥ 1 and ≤ --max-effort");
    }
    if args.target_flip.iter().any(|t| !(*t > 0.0 && *t < 1.0)) {
        bail!("--target-flip values must lie in (0, 1)");
    }
    if args.denoise
        && let Some(why) = crate::denoise::unavailable()
    {
        bail!("--denoise: {why}");
    }
    let denoise = args
        .denoise
        .then(|| args.denoise_quality.unwrap_or_default());
    crate::render::set_threads(args.threads)?;
    crate::render::check_fps_and_depth(args.fps, args.max_depth)?;
    Ok(denoise)
}

/// The reference frames of the measured frames, and the size rendered (`--resolution`,
/// else the references'), which every reference must have.
fn load_references(
    args: &QualityArgs,
    measured: &[u32],
) -> Result<(Vec<chronolux_io::image::Image>, u32, u32)> {
    let mut refs = Vec::new();
    for &f in measured {
        let p = args
            .reference
            .join(format!("{}.exr", chronolux_io::output::frame_stem(f)));
        let img = read_exr(&p).with_context(|| {
            format!("reference frame {f} missing or unreadable (make references with `chronolux reference ... --output {}`)", args.reference.display())
        })?;
        refs.push(img);
    }
    let (w, h) = match &args.resolution {
        Some(r) => parse_resolution(r)?,
        None => (refs[0].width, refs[0].height),
    };
    if refs.iter().any(|r| r.width != w || r.height != h) {
        bail!(
            "references are not all {w}x{h} (the size rendered); pass --resolution to match them"
        );
    }
    Ok((refs, w, h))
}

/// Says (not drops silently) that `--max-depth` does not apply to method `m`: its error
/// then includes the light of longer paths than a depth-limited reference has.
fn warn_if_depth_ignored(
    args: &QualityArgs,
    m: &str,
    sets: &[(String, serde_json::Value)],
) -> Result<()> {
    let (_, _, ignored) = config_for(m, 1, args.max_depth, args.seed, args.window, sets)?;
    if let Some(d) = args.max_depth
        && ignored.contains(&"--max-depth")
    {
        log::warn!(
            "--max-depth {d} does not apply to --method {m}, which renders paths of every depth: its error against a reference limited to depth {d} includes the longer paths' light"
        );
    }
    Ok(())
}

/// What every level of every method is rendered and scored with.
struct Bench<'a> {
    args: &'a QualityArgs,
    desc: Arc<chronolux_core::scene::desc::SceneDesc>,
    animation: Option<chronolux_core::scene::desc::AnimationId>,
    camera: chronolux_core::scene::frame::CameraChoice,
    size: (u32, u32),
    frames: &'a [u32],
    measured: &'a [u32],
    refs: &'a [chronolux_io::image::Image],
    denoise: Option<crate::denoise::DenoiseQuality>,
    hdr: flip::HdrSettings,
    /// The targets, highest (easiest) first.
    targets: &'a [f64],
}

impl Bench<'_> {
    /// Method `m`'s levels: the effort doubled from `--start-effort` until every target is
    /// reached, `--max-effort`, or a level that gives the images of the one before.
    fn climb(&self, m: &str, sets: &[(String, serde_json::Value)]) -> Result<MethodResult> {
        let args = self.args;
        let targets = self.targets;
        let mut levels: Vec<Level> = Vec::new();
        let mut reached: Vec<Option<Level>> = vec![None; targets.len()];
        let mut effort = args.start_effort;
        let mut no_effect = false;
        loop {
            let level = self.level(m, effort, sets)?;
            eprintln!(
                "{m} effort {effort}: {:.2} s wall, {:.2} s CPU ({:.2} s per {} measured of {} rendered frames), FLIP mean {:.4} max {:.4}, flicker {}",
                level.wall_s,
                level.cpu_s,
                level.scored_cpu_s(),
                level.frames_scored,
                level.frames_rendered,
                level.flip_mean,
                level.flip_max,
                level.flicker.map_or("-".into(), |f| format!("{f:.4}"))
            );
            for (k, t) in targets.iter().enumerate() {
                if reached[k].is_none() && meets(&level, *t, &args.criterion) {
                    reached[k] = Some(level.clone());
                }
            }
            levels.push(level);
            if reached.iter().all(Option::is_some) || effort >= args.max_effort {
                break;
            }
            // The same error to the bit as the level before: the effort does not reach the
            // images (e.g. `spacetime-dept` rendering every frame as `path`, whose samples
            // are its `spp`, not its photons). Higher levels would only cost time.
            if let [.., a, b] = levels.as_slice()
                && a.flip_mean == b.flip_mean
                && a.flip_max == b.flip_max
                && a.relmse_mean == b.relmse_mean
            {
                eprintln!(
                    "{m}: effort {effort} gives the images of effort {}: here its effort does not change its images (see its run.json from `render`, e.g. frames rendered as path); stopped",
                    a.effort
                );
                no_effect = true;
                break;
            }
            effort = (effort * 2).min(args.max_effort);
        }
        let interpolated_time_s = targets
            .iter()
            .map(|t| interpolate_time(&levels, *t, &args.criterion))
            .collect();
        let interpolated_cpu_s = targets
            .iter()
            .map(|t| interpolate_cpu(&levels, *t, &args.criterion))
            .collect();
        Ok(MethodResult {
            method: m.to_string(),
            levels,
            reached,
            interpolated_time_s,
            interpolated_cpu_s,
            effort_has_no_effect: no_effect,
        })
    }

    /// One level: method `m` at `effort`, a complete independent render of the frames
    /// (only the measured ones for a stateless method), timed and scored.
    fn level(&self, m: &str, effort: u32, sets: &[(String, serde_json::Value)]) -> Result<Level> {
        let args = self.args;
        let (w, h) = self.size;
        let (tech, settings, _) =
            config_for(m, effort, args.max_depth, args.seed, args.window, sets)?;
        let mut renderer = tech
            .build(&settings, &BuildContext::default())
            .map_err(anyhow::Error::msg)?;
        // A stateless method's frames do not depend on the frames rendered before them,
        // so it renders only the measured ones (same images, less CPU on the clock).
        let rendered = if tech.capabilities().stateless {
            self.measured
        } else {
            self.frames
        };
        let builder =
            FrameBuilder::new(self.desc.clone(), self.animation, self.camera.clone(), w, h)?;
        let mut source = FrameSource::new(builder, args.fps, rendered.to_vec());
        let mut sink = ScoredSink {
            denoise: self.denoise,
            frames: Vec::new(),
        };
        // A denoised run makes the albedo and normal passes the denoiser takes.
        let options = RunOptions {
            passes: if args.denoise {
                PassSet::parse("denoise").expect("preset")
            } else {
                PassSet::default()
            },
            seed: args.seed,
        };
        let run = chronolux_render::framework::run::run_with(
            renderer.as_mut(),
            &mut source,
            rendered,
            &mut [&mut sink],
            None,
            options,
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        let images: Vec<Vec<chronolux_core::color::Rgb>> = sink
            .frames
            .into_iter()
            .filter(|(f, _)| self.measured.contains(f))
            .map(|(_, px)| px)
            .collect();
        let (flips, relmse, flicker) = self.score(&images);
        Ok(Level {
            effort,
            wall_s: run.wall_s,
            cpu_s: run.cpu_s,
            frames_rendered: rendered.len(),
            frames_scored: self.measured.len(),
            flip_mean: flips.iter().sum::<f64>() / flips.len() as f64,
            flip_max: flips.iter().copied().fold(0.0, f64::max),
            relmse_mean: relmse.iter().sum::<f64>() / relmse.len() as f64,
            flicker,
        })
    }

    /// Per measured frame its HDR-FLIP and relMSE against the reference, and the mean
    /// flicker over pairs of measured frames that follow each other in the render.
    fn score(
        &self,
        images: &[Vec<chronolux_core::color::Rgb>],
    ) -> (Vec<f64>, Vec<f64>, Option<f64>) {
        let (w, h) = self.size;
        let (refs, frames, measured) = (self.refs, self.frames, self.measured);
        let flips: Vec<f64> = images
            .iter()
            .zip(refs)
            .map(|(i, r)| flip::flip_hdr(&r.pixels, i, w as usize, h as usize, &self.hdr).mean())
            .collect();
        let relmse: Vec<f64> = images
            .iter()
            .zip(refs)
            .map(|(i, r)| metrics::rel_mse(i, &r.pixels))
            .collect();
        let pairs: Vec<usize> = (1..measured.len())
            .filter(|&k| {
                let p = frames.iter().position(|&f| f == measured[k - 1]);
                p.is_some_and(|p| frames.get(p + 1) == Some(&measured[k]))
            })
            .collect();
        let flicker = (!pairs.is_empty()).then(|| {
            let v: Vec<f64> = pairs
                .iter()
                .map(|&k| {
                    metrics::flicker(
                        &images[k - 1],
                        &images[k],
                        &refs[k - 1].pixels,
                        &refs[k].pixels,
                    )
                })
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        });
        (flips, relmse, flicker)
    }
}

/// The result: every method's levels, and the flat fields of the first target as given on
/// the command line (times to it, speed-ups, flicker there).
fn summarize(
    args: &QualityArgs,
    denoise: Option<crate::denoise::DenoiseQuality>,
    frames: &[u32],
    measured: &[u32],
    targets: &[f64],
    results: Vec<MethodResult>,
) -> QualityResult {
    // The flat fields speak of the first target as given on the command line.
    let first = args.target_flip[0];
    let k0 = targets.iter().position(|t| *t == first).unwrap();
    let time = |r: &MethodResult, k: usize| r.reached[k].as_ref().map(Level::scored_wall_s);
    let flick = |r: &MethodResult, k: usize| r.reached[k].as_ref().and_then(|l| l.flicker);
    let interp = |r: &MethodResult, k: usize| r.interpolated_time_s[k];
    let cpu = |r: &MethodResult, k: usize| r.interpolated_cpu_s[k];
    let method_cpu_interp_s = cpu(&results[0], k0);
    let baseline_cpu_interp_s = results.get(1).and_then(|r| cpu(r, k0));
    let method_time_interp_s = interp(&results[0], k0);
    let baseline_time_interp_s = results.get(1).and_then(|r| interp(r, k0));
    let method_time_s = time(&results[0], k0);
    let baseline_time_s = results.get(1).and_then(|r| time(r, k0));
    QualityResult {
        method: args.method.clone(),
        baseline: args.baseline.clone(),
        criterion: args.criterion.clone(),
        denoise: args.denoise,
        denoise_quality: denoise,
        frames: frames.to_vec(),
        measured: measured.to_vec(),
        target_flip: first,
        method_time_s,
        baseline_time_s,
        speedup: match (method_time_s, baseline_time_s) {
            (Some(a), Some(b)) if a > 0.0 => Some(b / a),
            _ => None,
        },
        method_time_interp_s,
        baseline_time_interp_s,
        speedup_interp: match (method_time_interp_s, baseline_time_interp_s) {
            (Some(a), Some(b)) if a > 0.0 => Some(b / a),
            _ => None,
        },
        method_cpu_interp_s,
        baseline_cpu_interp_s,
        speedup_cpu_interp: match (method_cpu_interp_s, baseline_cpu_interp_s) {
            (Some(a), Some(b)) if a > 0.0 => Some(b / a),
            _ => None,
        },
        window: args.window,
        method_flicker: flick(&results[0], k0),
        baseline_flicker: results.get(1).and_then(|r| flick(r, k0)),
        targets: targets.to_vec(),
        results,
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("not reached".into(), |x| format!("{x:.digits$}"))
}

/// The report: times to each target side by side, then every level of every method.
pub fn markdown(r: &QualityResult) -> String {
    let mut s = String::new();
    s += &format!(
        "# Equal-quality benchmark: {}{}{}\n\nFrames rendered {:?} (frame-by-frame methods: only the measured ones), measured {:?}, criterion: {} HDR-FLIP over frames. Times are per measured frames: a run's × measured / rendered frames.\n\n",
        r.method,
        r.baseline
            .as_ref()
            .map_or(String::new(), |b| format!(" vs {b}")),
        r.denoise_quality.map_or(String::new(), |q| format!(
            ", every frame denoised (OIDN, quality {q:?})"
        )),
        r.frames,
        r.measured,
        r.criterion
    );
    s += "| target FLIP |";
    for m in &r.results {
        s += &format!(
            " {} time (s) | {} interpolated (s) | {} effort | {} flicker |",
            m.method, m.method, m.method, m.method
        );
    }
    if r.results.len() == 2 {
        s += " speed-up | speed-up interpolated | speed-up CPU interpolated |";
    }
    s += "\n|---|";
    for _ in &r.results {
        s += "---|---|---|---|";
    }
    if r.results.len() == 2 {
        s += "---|---|---|";
    }
    s += "\n";
    for (k, t) in r.targets.iter().enumerate() {
        s += &format!("| {t} |");
        for m in &r.results {
            let l = m.reached[k].as_ref();
            s += &format!(
                " {} | {} | {} | {} |",
                opt(l.map(Level::scored_wall_s), 2),
                opt(m.interpolated_time_s[k], 2),
                l.map_or("-".into(), |l| l.effort.to_string()),
                opt(l.and_then(|l| l.flicker), 4)
            );
        }
        if r.results.len() == 2 {
            let (a, b) = (
                r.results[0].reached[k].as_ref(),
                r.results[1].reached[k].as_ref(),
            );
            s += &format!(
                " {} |",
                match (a, b) {
                    (Some(a), Some(b)) if a.wall_s > 0.0 => {
                        format!("{:.2}×", b.scored_wall_s() / a.scored_wall_s())
                    }
                    _ => "-".into(),
                }
            );
            s += &format!(
                " {} |",
                match (
                    r.results[0].interpolated_time_s[k],
                    r.results[1].interpolated_time_s[k]
                ) {
                    (Some(a), Some(b)) if a > 0.0 => format!("{:.2}×", b / a),
                    _ => "-".into(),
                }
            );
            s += &format!(
                " {} |",
                match (
                    r.results[0].interpolated_cpu_s[k],
                    r.results[1].interpolated_cpu_s[k]
                ) {
                    (Some(a), Some(b)) if a > 0.0 => format!("{:.2}×", b / a),
                    _ => "-".into(),
                }
            );
        }
        s += "\n";
    }
    for m in &r.results {
        if m.effort_has_no_effect {
            s += &format!(
                "\n**{}: two efforts gave the same images; its effort does not change them here, so the levels stopped.**\n",
                m.method
            );
        }
    }
    for m in &r.results {
        s += &format!(
            "\n## {}: every effort level\n\n| effort | wall (s) | CPU (s) | frames rendered | CPU per scored frames (s) | FLIP mean | FLIP max | relMSE | flicker |\n|---|---|---|---|---|---|---|---|---|\n",
            m.method
        );
        for l in &m.levels {
            s += &format!(
                "| {} | {:.2} | {:.2} | {} | {:.2} | {:.4} | {:.4} | {:.5} | {} |\n",
                l.effort,
                l.wall_s,
                l.cpu_s,
                l.frames_rendered,
                l.scored_cpu_s(),
                l.flip_mean,
                l.flip_max,
                l.relmse_mean,
                opt(l.flicker, 4)
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(effort: u32, wall_s: f64, flip: f64) -> Level {
        Level {
            effort,
            wall_s,
            cpu_s: wall_s,
            frames_rendered: 8,
            frames_scored: 8,
            flip_mean: flip,
            flip_max: flip,
            relmse_mean: 0.0,
            flicker: None,
        }
    }

    #[test]
    fn interpolation_is_exact_on_a_power_law() {
        // FLIP = 0.4 / sqrt(effort), time = effort / 10: target 0.1 is reached at effort 16,
        // time 1.6, between the levels 8 and 32 of a grid that skips 16.
        let levels: Vec<Level> = [2u32, 8, 32]
            .iter()
            .map(|&e| level(e, e as f64 / 10.0, 0.4 / (e as f64).sqrt()))
            .collect();
        let t = interpolate_time(&levels, 0.1, "mean").unwrap();
        assert!((t - 1.6).abs() < 1e-9, "{t}");
        assert_eq!(interpolate_time(&levels, 0.01, "mean"), None);
    }

    #[test]
    fn times_are_compared_per_measured_frame() {
        // A temporal method renders 24 frames to score 8 with whole windows: the same
        // curve as above at three times the run's time costs the same per measured frame.
        let whole: Vec<Level> = [2u32, 8, 32]
            .iter()
            .map(|&e| Level {
                frames_rendered: 24,
                ..level(e, 3.0 * e as f64 / 10.0, 0.4 / (e as f64).sqrt())
            })
            .collect();
        let t = interpolate_cpu(&whole, 0.1, "mean").unwrap();
        assert!((t - 1.6).abs() < 1e-9, "{t}");
        assert!((whole[1].scored_wall_s() - 0.8).abs() < 1e-12);
    }
}
