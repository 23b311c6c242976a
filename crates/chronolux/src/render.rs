//! `chronolux render`: load → frame builder → technique → frames on disk.

use crate::args::{RenderArgs, SceneArgs};
use crate::config::{
    CommonFlags, ConfigFile, FlagSetting, PartialRun, RunConfig, parse_sets, technique_settings,
};
use crate::info;
use crate::scene_input;
use anyhow::{Context, Result, bail};
use chronolux_core::scene::desc::{Projection, SceneDesc};
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
use chronolux_core::scene::source::FrameSource;
use chronolux_io::image::Image;
use chronolux_io::output::{FrameRecord, FrameSink, Manifest};
use chronolux_render::framework::aov::PassSet;
use chronolux_render::framework::run;
use chronolux_render::framework::technique::Technique;
use chronolux_render::registry::{self, BuildContext};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::sync::Arc;

/// Largest accepted image side and sample count: beyond these a render is almost surely
/// a typo (and would need more memory or time than any machine of ours has).
const MAX_SIDE: u32 = 16384;
const MAX_SPP: u32 = 1 << 20;

/// Sets the size of the global thread pool (`None`: all cores).
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        if t == 0 {
            bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("cannot set up the thread pool")?;
    }
    Ok(())
}

/// Checks `--fps` and `--max-depth`, shared by every command that renders.
pub fn check_fps_and_depth(fps: f32, max_depth: Option<u32>) -> Result<()> {
    if !(fps > 0.0 && fps <= 1000.0) {
        bail!("--fps {fps} out of range (0 < fps ≤ 1000)");
    }
    if max_depth == Some(0) {
        bail!("--max-depth 0 renders nothing (1 shows emitters only, 2 adds direct lighting)");
    }
    Ok(())
}

/// Parses `A..B`, `A..=B` or `N` into a list of frames.
pub fn parse_frames(s: &str) -> Result<Vec<u32>> {
    let s = s.trim();
    let num = |t: &str| -> Result<u32> {
        t.trim().parse::<u32>().with_context(|| {
            format!("invalid frame number '{t}' in --frames '{s}' (expected A..B, A..=B or N)")
        })
    };
    let frames: Vec<u32> = if let Some((a, b)) = s.split_once("..=") {
        (num(a)?..=num(b)?).collect()
    } else if let Some((a, b)) = s.split_once("..") {
        (num(a)?..num(b)?).collect()
    } else {
        vec![num(s)?]
    };
    if frames.is_empty() {
        bail!("--frames '{s}' is empty (A..B is half-open: use A..=B to include B)");
    }
    Ok(frames)
}

/// Parses `WxH`.
pub fn parse_resolution(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s.split_once(['x', 'X']).with_context(|| {
        format!("invalid --resolution '{s}' (expected WIDTHxHEIGHT, e.g. 640x360)")
    })?;
    let p = |t: &str| {
        t.trim()
            .parse::<u32>()
            .with_context(|| format!("invalid --resolution '{s}' (expected WIDTHxHEIGHT)"))
    };
    let (w, h) = (p(w)?, p(h)?);
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        bail!("--resolution {w}x{h} out of range (each side 1 to {MAX_SIDE})");
    }
    Ok((w, h))
}

/// Last frame of the clip at `fps`: the frame on (or just before) its last key.
pub fn last_frame(
    desc: &SceneDesc,
    anim: Option<chronolux_core::scene::desc::AnimationId>,
    fps: f32,
) -> Option<u32> {
    let a = anim?;
    // 1e-3 frames of slack so a last key at exactly 47/24 s maps to frame 47.
    Some((desc.animations[a.index()].duration() * fps + 1e-3).floor() as u32)
}

pub fn default_resolution(desc: &SceneDesc, camera: &CameraChoice) -> (u32, u32) {
    let cam = scene_input::chosen_camera(desc, camera);
    let aspect = match cam.map(|c| c.projection) {
        Some(Projection::Perspective {
            aspect: Some(a), ..
        }) if a > 0.0 && a.is_finite() => a,
        Some(Projection::Orthographic { xmag, ymag }) if xmag > 0.0 && ymag > 0.0 => xmag / ymag,
        _ => 1.0,
    };
    (512, ((512.0 / aspect).round() as u32).clamp(1, MAX_SIDE))
}

pub fn run(args: RenderArgs) -> Result<()> {
    let (config, input, denoise_skipped) = resolve(&args)?;
    execute(
        &config,
        input,
        &Exec {
            output: args.output.clone(),
            resume: args.resume,
            no_preview: args.no_preview,
            threads: args.threads,
            segment: None,
            denoise_skipped,
        },
    )
}

/// How to carry out a resolved configuration (nothing here changes the pixels).
pub struct Exec {
    pub output: std::path::PathBuf,
    pub resume: bool,
    pub no_preview: bool,
    pub threads: Option<usize>,
    /// A farm segment: only its own frames are written, with its own manifest.
    pub segment: Option<crate::segment::SegmentRun>,
    /// Why the frames are not denoised although nothing said not to (the denoiser
    /// cannot be had here): said once and recorded in run.json.
    pub denoise_skipped: Option<String>,
}

/// The configuration the flags (and `--config`) give, checked, and the scene loaded; and
/// why the default denoising cannot be done, when it cannot.
pub fn resolve(args: &RenderArgs) -> Result<(RunConfig, scene_input::SceneInput, Option<String>)> {
    // Everything that can be checked without the scene is checked before loading it.
    let file = args.config.as_deref().map(ConfigFile::read).transpose()?;
    let prev = file.as_ref().map(ConfigFile::run).unwrap_or_default();
    let (method, tech, base) = method_of(args, file.as_ref(), &prev)?;
    if let Some(spp) = args.spp
        && (spp == 0 || spp > MAX_SPP)
    {
        bail!("--spp {spp} out of range (1 to {MAX_SPP})");
    }
    let fps = args.fps.or(prev.fps).unwrap_or(24.0);
    check_fps_and_depth(fps, args.max_depth)?;
    let exposure = args.exposure.or(prev.exposure);
    if exposure.is_some_and(|e| !e.is_finite()) {
        bail!("--exposure must be a finite number of stops");
    }
    let view = args.view.or(prev.view).unwrap_or_default();
    let environment = environment_of(args, &prev)?;
    let shutter = args.shutter.or(prev.shutter).unwrap_or(0.0);
    chronolux_render::framework::technique::check_shutter(shutter).map_err(anyhow::Error::msg)?;
    let mut flags = Vec::new();
    if let Some(window) = args.window {
        flags.push(FlagSetting {
            flag: "--window",
            key: "window",
            value: window.into(),
        });
    }
    let sources = SettingSources {
        tech,
        base,
        common: CommonFlags {
            spp: args.spp,
            seed: args.seed,
            max_depth: args.max_depth,
        },
        flags,
        sets: parse_sets(&args.set)?,
    };
    let passes = match &args.passes {
        Some(p) => PassSet::parse(p).map_err(anyhow::Error::msg)?,
        None => prev.passes.unwrap_or_default(),
    };
    let (denoise, denoise_skipped) = denoising(args, &prev)?;
    let requested_frames = match args.frames.as_deref() {
        Some(f) => Some(parse_frames(f)?),
        None => prev.frames.clone(),
    };
    let requested_resolution = match args.resolution.as_deref() {
        Some(r) => Some(parse_resolution(r)?),
        None => prev.resolution.map(|[w, h]| (w, h)),
    };
    let scene_args = scene_args_of(args, &prev);
    // The quality level's effort settings under the config file's and the flags'. A
    // config file's own level is not asked again: its technique settings carry it. The
    // level's entry is the one measured nearest the image's pixel count: known now when
    // the resolution is given (or the demo's 256²), else settled again below once the
    // scene's camera gives it.
    let known_pixels = match requested_resolution {
        Some((w, h)) => Some(u64::from(w) * u64::from(h)),
        None if scene_args.scene.is_none() => {
            Some(u64::from(DEMO_RESOLUTION.0) * u64::from(DEMO_RESOLUTION.1))
        }
        None => None,
    };
    let mut settled = sources.settle(args, &prev, denoise, known_pixels)?;
    // Built once here so that a bad combination fails before the scene is loaded.
    let built = tech
        .build(&settled.settings, &BuildContext { shutter })
        .map_err(anyhow::Error::msg)?;
    // Direct/indirect asked of a method that does not separate them: said now.
    passes
        .resolve(&method, built.separates_light())
        .map_err(anyhow::Error::msg)?;
    let input = scene_input::load(&scene_args)?;
    if let Some(e) = &environment
        && input
            .desc
            .warnings
            .iter()
            .any(|w| w.starts_with(chronolux_core::scene::desc::DEFAULT_ENVIRONMENT_WARNING))
    {
        // The loader's warning above names the default sky; the map replaces it.
        log::warn!(
            "--environment {}: lights the scene instead of that default environment",
            e.file
        );
    }
    let frames = frames_of(requested_frames, &input, fps)?;
    let (w, h) = match requested_resolution {
        Some(r) => r,
        None if scene_args.scene.is_none() => DEMO_RESOLUTION,
        None => default_resolution(&input.desc, &input.camera),
    };
    if known_pixels.is_none() {
        settled = sources.settle(args, &prev, denoise, Some(u64::from(w) * u64::from(h)))?;
    }
    let Settled {
        level,
        denoise_quality,
        settings,
    } = settled;
    let config = RunConfig {
        method: method.clone(),
        technique: settings,
        scene: scene_args.scene.as_ref().map(|p| p.display().to_string()),
        stage: scene_args.stage.clone(),
        animation: input.animation.map(|a| {
            let name = &input.desc.animations[a.index()].name;
            if name.trim().is_empty() {
                a.index().to_string()
            } else {
                name.clone()
            }
        }),
        camera: match &input.camera {
            CameraChoice::First => None,
            CameraChoice::Named(n) => Some(n.clone()),
        },
        resolution: [w, h],
        fps,
        frames,
        shutter,
        exposure,
        passes,
        denoise,
        denoise_quality,
        quality: match (&level, &args.quality) {
            (Some(l), _) => Some(l.name.to_string()),
            (None, None) => prev.quality.clone(),
            (None, Some(_)) => None,
        },
        view,
        environment,
    };
    Ok((config, input, denoise_skipped))
}

/// The method (`--method`, else the config file's, else the default), its technique, and
/// the config file's technique settings when they are that method's.
fn method_of(
    args: &RenderArgs,
    file: Option<&ConfigFile>,
    prev: &PartialRun,
) -> Result<(String, &'static dyn Technique, Option<serde_json::Value>)> {
    let method = args
        .method
        .clone()
        .or_else(|| prev.method.clone())
        .unwrap_or_else(|| registry::DEFAULT_METHOD.into());
    let tech = registry::find(&method).map_err(anyhow::Error::msg)?;
    // A config file's technique settings apply to its own method only.
    let base = match file {
        Some(ConfigFile::Settings(v)) => Some(v.clone()),
        Some(f) if f.method() == Some(method.as_str()) => prev.technique.clone(),
        Some(f) => {
            log::warn!(
                "--config names --method {}, overridden by --method {method}: its technique settings are not used",
                f.method().unwrap_or("?")
            );
            None
        }
        None => None,
    };
    Ok((method, tech, base))
}

/// The environment map (`--environment` and its strength and rotation, checked; else the
/// config file's).
fn environment_of(
    args: &RenderArgs,
    prev: &PartialRun,
) -> Result<Option<crate::config::EnvironmentConfig>> {
    let Some(file) = &args.environment else {
        return Ok(prev.environment.clone());
    };
    let strength = args.environment_strength.unwrap_or(1.0);
    if !(strength.is_finite() && strength >= 0.0) {
        bail!("--environment-strength must be a finite number ≥ 0, not {strength}");
    }
    let rotation_deg = args.environment_rotation.unwrap_or(0.0);
    if !rotation_deg.is_finite() {
        bail!("--environment-rotation must be a finite number of degrees");
    }
    if !file.is_file() {
        bail!(
            "--environment {}: no such file (an .exr or .hdr equirectangular map)",
            file.display()
        );
    }
    let file = std::fs::canonicalize(file).unwrap_or_else(|_| file.clone());
    Ok(Some(crate::config::EnvironmentConfig {
        file: file.display().to_string(),
        strength,
        rotation_deg,
        hidden: args.environment_hidden,
    }))
}

/// Whether the frames are denoised, and why not when by default they cannot be.
/// Denoised unless told not to: asked (--denoise, or a --config that denoised) it must
/// be done; by default it is done where the denoiser can be had.
fn denoising(args: &RenderArgs, prev: &PartialRun) -> Result<(bool, Option<String>)> {
    let asked = if args.no_denoise {
        Some(false)
    } else if args.denoise || args.denoise_quality.is_some() {
        Some(true)
    } else {
        prev.denoise
    };
    Ok(match asked {
        Some(true) => match crate::denoise::unavailable() {
            Some(why) if args.denoise || args.denoise_quality.is_some() => {
                bail!("--denoise: {why} (--no-denoise renders without)")
            }
            Some(why) => bail!("--config asks for denoising: {why} (--no-denoise renders without)"),
            None => (true, None),
        },
        Some(false) => (false, None),
        None => match crate::denoise::unavailable() {
            Some(why) => (false, Some(why)),
            None => (true, None),
        },
    })
}

/// The scene, clip, camera and stage: the flags', else the config file's.
fn scene_args_of(args: &RenderArgs, prev: &PartialRun) -> SceneArgs {
    SceneArgs {
        scene: args
            .scene
            .scene
            .clone()
            .or_else(|| prev.scene.clone().map(Into::into)),
        animation: args.scene.animation.clone().or(prev.animation.clone()),
        camera: args.scene.camera.clone().or(prev.camera.clone()),
        stage: args.scene.stage.clone().or(prev.stage.clone()),
    }
}

/// The frames asked for (default: the whole clip), checked against the clip's end.
fn frames_of(
    requested: Option<Vec<u32>>,
    input: &scene_input::SceneInput,
    fps: f32,
) -> Result<Vec<u32>> {
    let last = last_frame(&input.desc, input.animation, fps);
    let frames = match requested {
        Some(f) => f,
        None => (0..=last.unwrap_or(0)).collect(),
    };
    if let Some(last) = last {
        let max = *frames.iter().max().unwrap();
        if max > last {
            bail!(
                "--frames goes to frame {max}, but the animation ends at frame {last} ({:.3} s at {} fps)",
                last as f32 / fps,
                fps
            );
        }
    }
    if input.animation.is_none() && frames.len() > 1 {
        log::warn!(
            "{} has no animation: the {} frames will be identical",
            input.source,
            frames.len()
        );
    }
    Ok(frames)
}

/// The built-in demo's resolution when none is given: meant to finish in a few minutes on
/// a laptop.
const DEMO_RESOLUTION: (u32, u32) = (256, 256);

/// Where a technique's settings come from, below the quality level: the config file's
/// settings of the method, `--spp`/`--seed`/`--max-depth`, the flags that name settings
/// and the `--set`s.
struct SettingSources {
    tech: &'static dyn Technique,
    base: Option<serde_json::Value>,
    common: CommonFlags,
    flags: Vec<FlagSetting>,
    sets: Vec<(String, serde_json::Value)>,
}

/// What [`resolve`] takes from the quality level for one pixel count.
struct Settled {
    level: Option<registry::QualityLevel>,
    denoise_quality: crate::denoise::DenoiseQuality,
    settings: serde_json::Value,
}

impl SettingSources {
    /// The settings for an image of `pixels` pixels (`None`: not known yet): the quality
    /// level's entry for it, then the sources above.
    fn settle(
        &self,
        args: &RenderArgs,
        prev: &PartialRun,
        denoise: bool,
        pixels: Option<u64>,
    ) -> Result<Settled> {
        let tech = self.tech;
        let level = registry::quality_settings(tech, args.quality.as_deref(), denoise, pixels)
            .map_err(anyhow::Error::msg)?;
        let base = match (&level, &self.base) {
            (Some((q, _)), Some(b)) => {
                let mut q = q.clone();
                registry::merge(&mut q, b);
                Some(q)
            }
            (Some((q, _)), None) => Some(q.clone()),
            (None, b) => b.clone(),
        };
        let denoise_quality = args
            .denoise_quality
            .or(prev.denoise_quality)
            .or(level.as_ref().and_then(|(_, l)| {
                <crate::denoise::DenoiseQuality as clap::ValueEnum>::from_str(l.denoiser, false)
                    .ok()
            }))
            .unwrap_or_default();
        let settings = technique_settings(
            tech,
            base.as_ref(),
            self.common,
            &self.flags,
            args.photons.as_deref(),
            &self.sets,
        )?;
        Ok(Settled {
            level: level.map(|(_, l)| l),
            denoise_quality,
            settings,
        })
    }
}

/// Renders `config` (its scene already loaded as `input`) into `exec.output`.
pub fn execute(config: &RunConfig, input: scene_input::SceneInput, exec: &Exec) -> Result<()> {
    let mut input = input;
    if let Some(e) = &config.environment {
        input.desc.environment = Some(e.load()?);
    }
    let tech = registry::find(&config.method).map_err(anyhow::Error::msg)?;
    let mut renderer = tech
        .build(
            &config.technique,
            &BuildContext {
                shutter: config.shutter,
            },
        )
        .map_err(anyhow::Error::msg)?;
    set_threads(exec.threads)?;
    let summary = info::summarize(&input);
    let [w, h] = config.resolution;
    let fps = config.fps;
    // A segment computes its warm-up and cool-down frames too, and writes only its own.
    let (source_frames, run_frames) = match &exec.segment {
        Some(seg) => (seg.compute.clone(), seg.run_frames()),
        None => (config.frames.clone(), config.frames.clone()),
    };
    let frames = run_frames;
    let mut sink = FrameSink::create(&exec.output)?;
    if let Some(seg) = &exec.segment {
        sink = sink.with_manifest_name(&seg.manifest_name());
    }
    let desc = Arc::new(input.desc);
    let builder = FrameBuilder::new(desc.clone(), input.animation, input.camera.clone(), w, h)?;
    let mut source = FrameSource::new(builder, fps, source_frames);

    let exposure = match config.exposure {
        Some(e) => e,
        None => crate::exposure::first_frame_exposure(
            desc.clone(),
            input.animation,
            input.camera.clone(),
            (w, h),
            fps,
            *config.frames.first().context("no frame to render")?,
        )?,
    };
    let manifest = manifest_of(config, exec, exposure, &summary, &sink)?;

    let (options, asked) = run_options(config, tech, renderer.separates_light())?;
    let progress = Progress::new(w, h, frames.len(), tech.capabilities().stateless);
    progress.say(format!(
        "rendering {} frame(s) of {} at {w}x{h}, method {}, {} thread(s) into {}",
        frames.len(),
        input.source,
        renderer.name(),
        rayon::current_num_threads(),
        exec.output.display()
    ));
    // A frame is done when complete and recorded (`DiskSink::needs`'s own test). A
    // stateful technique resumed renders its history again, as a farm segment does, so
    // that a resumed render equals an uninterrupted one bit for bit.
    let done = |f| sink.is_complete(f) && manifest.frame(f).is_some();
    let warm_up_until = rebuild_history_until(
        exec,
        tech,
        config,
        &frames,
        done,
        &progress,
        renderer.name(),
    );
    let mut disk = DiskSink {
        sink: &sink,
        manifest,
        exposure,
        view: config.view,
        resume: exec.resume,
        denoise: config.denoise.then_some(config.denoise_quality),
        keep_passes: asked,
        owned: exec.segment.as_ref().map(|s| s.owned.clone()),
        warm_up_until,
    };
    let mut progress = progress;
    let result = chronolux_render::framework::run::run_with(
        renderer.as_mut(),
        &mut source,
        &frames,
        &mut [&mut disk, &mut progress],
        None,
        options,
    );
    // The bars are cleared whatever happens, so that an error line is not drawn over.
    progress.clear();
    let summary = result.map_err(|e| anyhow::anyhow!("{e}"))?;
    let written = written_frames(&frames, &summary, exec.segment.as_ref());
    // A segment's frames are previewed when the farm's frames are assembled.
    if !exec.no_preview && exec.segment.is_none() && written.len() > 1 {
        match chronolux_io::output::write_preview(&exec.output, &written, fps) {
            Ok(p) => progress.say(format!("preview: {}", p.display())),
            Err(e) => eprintln!("warning: no preview written: {e}"),
        }
    }
    progress.say(format!(
        "done: {} frame(s) in {:.1} s, {:.2} Mrays/s → {}",
        written.len(),
        summary.wall_s,
        progress.rays as f64 / summary.wall_s.max(1e-9) / 1e6,
        exec.output.display()
    ));
    Ok(())
}

/// The frame before which a stateful technique renders complete frames again (to
/// rebuild its history: a segment's warm-up, or a resumed run's), said when a resumed
/// run does.
fn rebuild_history_until(
    exec: &Exec,
    tech: &dyn Technique,
    config: &RunConfig,
    frames: &[u32],
    done: impl Fn(u32) -> bool + Copy,
    progress: &Progress,
    name: &str,
) -> Option<u32> {
    let (owned, render_before) = match &exec.segment {
        Some(s) => (&s.owned[..], s.render_before),
        None => (
            frames,
            registry::frame_context(tech, &config.technique).render_before,
        ),
    };
    let until = crate::segment::warm_up_until(owned, render_before, done, exec.resume);
    if exec.resume
        && exec.segment.is_none()
        && let Some(u) = until
    {
        let again = frames.iter().filter(|&&f| f < u && done(f)).count();
        if again > 0 {
            progress.say(format!(
                "resuming {}, which carries light from frame to frame: the {again} complete \
                 frame(s) before frame {u} are rendered again (the same bits) to rebuild its history",
                name
            ));
        }
    }
    until
}

/// `run.json` for a run of `config`: its settings, and what this machine adds to them
/// (threads, the exposure chosen, where the denoiser and the ray queries came from, why
/// a default run is not denoised); a segment's own part; and when resuming, the earlier
/// run's frames once it is checked to be the same run.
fn manifest_of(
    config: &RunConfig,
    exec: &Exec,
    exposure: f32,
    summary: &info::SceneSummary,
    sink: &FrameSink,
) -> Result<Manifest> {
    let mut settings_json = serde_json::to_value(config)?;
    settings_json["threads"] = rayon::current_num_threads().into();
    if config.exposure.is_none() {
        settings_json["auto_exposure"] = exposure.into();
    }
    // Where the denoiser came from, or why a default run is not denoised (recorded, not
    // settings: `--config` reads past them).
    if config.denoise {
        settings_json["denoise_library"] = crate::denoise::library()
            .map(|p| p.display().to_string())
            .into();
    }
    // Which kernel answered the ray queries (Embree, or the own BVH and why).
    settings_json["ray_backend"] = chronolux_core::accel::embree::backend_name().into();
    if let chronolux_core::accel::embree::Backend::Own(why) =
        chronolux_core::accel::embree::backend()
    {
        settings_json["ray_backend_note"] = why.clone().into();
    }
    if let Some(why) = &exec.denoise_skipped {
        log::warn!("rendering without denoising: {why}");
        settings_json["denoise_unavailable"] = why.clone().into();
    }
    let mut manifest = Manifest::new(
        std::env::args().collect(),
        settings_json,
        serde_json::to_value(summary)?,
    );
    if let Some(seg) = &exec.segment {
        settings_json_segment(&mut manifest.settings, seg);
    }
    if exec.resume
        && let Some(earlier) = sink.read_manifest()?
    {
        check_resumable(&earlier.settings, &manifest.settings, &exec.output)?;
        manifest.merge_earlier(&earlier);
    }
    Ok(manifest)
}

/// The passes the run computes and its seed; and the passes asked for (what is kept):
/// direct and indirect where the method separates them (`all`), an error where they were
/// named and it does not.
fn run_options(
    config: &RunConfig,
    tech: &dyn Technique,
    separates_light: bool,
) -> Result<(run::RunOptions, PassSet)> {
    let asked = config
        .passes
        .resolve(&config.method, separates_light)
        .map_err(anyhow::Error::msg)?;
    // A denoised frame needs its albedo and normal.
    let passes = if config.denoise {
        asked.with(PassSet::parse("denoise").expect("preset"))
    } else {
        asked
    };
    let options = run::RunOptions {
        passes,
        seed: tech
            .common(&config.technique)
            .map_err(anyhow::Error::msg)?
            .seed,
    };
    Ok((options, asked))
}

/// The frames of `frames` this run wrote (rendered or skipped as already done); of a
/// segment's, only its own.
fn written_frames(
    frames: &[u32],
    summary: &run::RunSummary,
    segment: Option<&crate::segment::SegmentRun>,
) -> Vec<u32> {
    let mut written: Vec<u32> = frames
        .iter()
        .copied()
        .filter(|f| summary.rendered.contains(f) || summary.skipped.contains(f))
        .collect();
    written.dedup();
    match segment {
        Some(seg) => written
            .into_iter()
            .filter(|f| seg.owned.contains(f))
            .collect(),
        None => written,
    }
}

/// Writes finished frames (EXR + PNG) and keeps `run.json` current after each.
pub struct DiskSink<'a> {
    pub sink: &'a FrameSink,
    pub manifest: Manifest,
    pub exposure: f32,
    pub view: chronolux_io::image::View,
    /// Frames already complete in the folder are not needed again.
    pub resume: bool,
    /// A farm segment's own frames (the others are computed, not written).
    pub owned: Option<Vec<u32>>,
    /// A stateful technique renders every frame before this one, its history (a segment's
    /// frames not its own are not written; its own and a resumed render's are, again).
    pub warm_up_until: Option<u32>,
    /// Denoise the beauty with this quality (the noisy one becomes a layer).
    pub denoise: Option<crate::denoise::DenoiseQuality>,
    /// The passes the user asked for (a denoised render computes albedo and normal even
    /// when they were not asked for, and does not write them then).
    pub keep_passes: PassSet,
}

impl run::FrameSink for DiskSink<'_> {
    fn needs(&self, frame: u32) -> bool {
        // A stateful technique (a farm segment, or a whole resumed render) renders every
        // frame before the last one it must render, in order, its own complete frames included (written again, the same
        // bits), so that the history is that of an uninterrupted run.
        if self.warm_up_until.is_some_and(|u| frame < u) {
            return true;
        }
        if self.owned.as_ref().is_some_and(|o| !o.contains(&frame)) {
            return false;
        }
        // Complete files without a record in run.json were written by a run killed before
        // it recorded them: rendered again (the same bits), so that run.json lists every
        // frame, as `chronolux reference --resume` does.
        !(self.resume && self.sink.is_complete(frame) && self.manifest.frame(frame).is_some())
    }

    fn frame(&mut self, f: &run::FinishedFrame) -> Result<(), run::SinkError> {
        if self.owned.as_ref().is_some_and(|o| !o.contains(&f.frame)) {
            return Ok(()); // a warm-up frame: computed for its history only
        }
        let out = f.output;
        let mut image = Image {
            width: out.width,
            height: out.height,
            pixels: out.pixels.clone(),
        };
        let light = if self.keep_passes.direct || self.keep_passes.indirect {
            Some(out.light.as_ref().ok_or_else(|| {
                format!(
                    "frame {}: the method made no direct/indirect split",
                    f.frame
                )
            })?)
        } else {
            None
        };
        if f.aovs.is_none() && light.is_none() {
            self.sink
                .write_frame_view(f.frame, &image, self.exposure, self.view)
                .map_err(|e| format!("writing frame {}: {e}", f.frame))?;
        } else {
            let mut layers = Vec::new();
            if let Some(aovs) = f.aovs {
                let mut kept = aovs.clone();
                if !self.keep_passes.albedo {
                    kept.albedo.clear();
                }
                if !self.keep_passes.normal {
                    kept.normal.clear();
                }
                layers = crate::denoise::pass_channels(&kept);
            }
            if let Some(l) = light {
                layers.extend(crate::denoise::light_channels(
                    l,
                    self.keep_passes.direct,
                    self.keep_passes.indirect,
                ));
            }
            if let Some(quality) = self.denoise {
                let aovs = f.aovs.ok_or_else(|| {
                    format!("frame {}: no albedo/normal to denoise with", f.frame)
                })?;
                let clean = crate::denoise::denoise(&image.pixels, aovs, quality)
                    .map_err(|e| format!("frame {}: {e}", f.frame))?;
                for (c, name) in ["R", "G", "B"].iter().enumerate() {
                    layers.push((
                        format!("ViewLayer.Noisy Image.{name}"),
                        image.pixels.iter().map(|p| p[c]).collect(),
                    ));
                }
                image.pixels = clean;
            }
            chronolux_io::image::write_exr_layers(self.sink.exr_path(f.frame), &image, &layers)
                .map_err(|e| format!("writing frame {}: {e}", f.frame))?;
            chronolux_io::image::write_png_view(
                self.sink.png_path(f.frame),
                &image,
                self.exposure,
                self.view,
            )
            .map_err(|e| format!("writing frame {}: {e}", f.frame))?;
        }
        self.manifest
            .upsert_frame(FrameRecord::new(f.frame, f.time_s, f.wall_s, f.record()));
        self.sink.write_manifest(&self.manifest)?;
        Ok(())
    }

    fn finish(&mut self, summary: &run::RunSummary) -> Result<(), run::SinkError> {
        self.manifest.finish(summary.wall_s);
        self.sink.write_manifest(&self.manifest)?;
        Ok(())
    }
}

/// Progress on the terminal: bars of frames and of the current frame's pixels when
/// stderr is a terminal, one line per frame otherwise (logs, CI, tests).
pub struct Progress {
    interactive: bool,
    mp: MultiProgress,
    frames: ProgressBar,
    pixels: ProgressBar,
    /// Whether each frame's rays are traced while it is rendered (a frame-by-frame method),
    /// so that its ray rate is its rays over its time. A temporal method traces samples for
    /// the frames after the one it outputs (and serves a frame from samples made while
    /// rendering earlier ones): its per-frame rate would be meaningless (a frame served
    /// entirely from earlier steps takes no time), so only the run's rate is printed.
    per_frame_rate: bool,
    /// Ray queries of the frames finished so far.
    rays: u64,
}

impl Progress {
    pub fn new(w: u32, h: u32, n: usize, per_frame_rate: bool) -> Self {
        let interactive = std::io::IsTerminal::is_terminal(&std::io::stderr());
        let mp = MultiProgress::with_draw_target(if interactive {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        });
        let style =
            ProgressStyle::with_template("{prefix:>7} [{bar:40}] {pos}/{len} {msg} ETA {eta}")
                .expect("valid progress template")
                .progress_chars("=> ");
        let frames = mp.add(ProgressBar::new(n as u64));
        frames.set_style(style.clone());
        frames.set_prefix("frames");
        let pixels = mp.add(ProgressBar::new(u64::from(w) * u64::from(h)));
        pixels.set_style(style);
        pixels.set_prefix("pixels");
        Progress {
            interactive,
            mp,
            frames,
            pixels,
            per_frame_rate,
            rays: 0,
        }
    }

    /// A line above the bars (plain stderr when not on a terminal).
    pub fn say(&self, s: String) {
        if self.interactive {
            if self.mp.println(&s).is_err() {
                eprintln!("{s}");
            }
        } else {
            eprintln!("{s}");
        }
    }

    pub fn clear(&self) {
        self.pixels.finish_and_clear();
        self.frames.finish_and_clear();
    }
}

impl run::FrameSink for Progress {
    /// Progress reporting wants no frame of its own: the writers decide what is rendered.
    fn needs(&self, _: u32) -> bool {
        false
    }

    fn begin_frame(&mut self, _: u32, _: usize, _: usize) {
        self.pixels.reset();
    }

    fn pixels(&self, n: u64) {
        self.pixels.inc(n);
    }

    fn skipped(&mut self, frame: u32, k: usize, n: usize) {
        let width = n.to_string().len();
        self.say(format!(
            "frame {frame} [{:>width$}/{n}]: already complete, skipped (--resume)",
            k + 1
        ));
        self.frames.inc(1);
    }

    fn frame(&mut self, f: &run::FinishedFrame) -> Result<(), run::SinkError> {
        let out = f.output;
        let width = f.n.to_string().len();
        self.frames.inc(1);
        let rays = out.stats.rays + out.stats.shadow_rays;
        self.rays += rays;
        let work = if self.per_frame_rate {
            format!("{:.2} Mrays/s", rays as f64 / f.wall_s.max(1e-9) / 1e6)
        } else {
            format!("{:.2} M rays", rays as f64 / 1e6)
        };
        // A frame the technique rendered as its baseline (its path probe found nothing
        // to gain: `spacetime-dept`, module doc "When it renders as `path`").
        let probe = &out.report.get("path_probe");
        let as_path = match probe {
            Some(p) if p["rendered_as"] == "path" => format!(
                ", rendered as path: nothing to reuse (indirect light adds {:.0} % noise)",
                100.0 * (p["variance_ratio"].as_f64().unwrap_or(1.0) - 1.0).max(0.0)
            ),
            _ => String::new(),
        };
        self.say(format!(
            "frame {} [{:>width$}/{}] t={:.3} s: {:.2} s, {work}{as_path}{}",
            f.frame,
            f.k + 1,
            f.n,
            f.time_s,
            f.wall_s,
            if out.invalid_samples > 0 {
                format!(", {} NaN/Inf samples dropped", out.invalid_samples)
            } else {
                String::new()
            }
        ));
        Ok(())
    }
}

/// Records in a segment's manifest which segment it is.
fn settings_json_segment(settings: &mut serde_json::Value, seg: &crate::segment::SegmentRun) {
    settings["segment"] = serde_json::json!({
        "index": seg.index,
        "owned": seg.owned,
        "compute": seg.compute,
    });
}

/// `--resume` continues a run only with the settings that made its frames: mixing frames of
/// different sample counts, sizes or cameras in one sequence would be silently wrong.
fn check_resumable(
    earlier: &serde_json::Value,
    now: &serde_json::Value,
    dir: &std::path::Path,
) -> Result<()> {
    let keys = [
        "method",
        "technique",
        "resolution",
        "fps",
        "shutter",
        "exposure",
        "passes",
        "denoise",
        "denoise_quality",
        "view",
        "animation",
        "camera",
        "stage",
        "scene",
        "environment",
    ];
    let differ: Vec<String> = keys
        .iter()
        .filter(|k| earlier.get(**k).is_some() && earlier.get(**k) != now.get(**k))
        .map(|k| {
            format!(
                "{k} was {} and is now {}",
                earlier[*k],
                now.get(*k).unwrap_or(&serde_json::Value::Null)
            )
        })
        .collect();
    if !differ.is_empty() {
        bail!(
            "--resume: {} holds frames rendered with other settings ({}); use the same settings or another --output",
            dir.display(),
            differ.join("; ")
        );
    }
    Ok(())
}
