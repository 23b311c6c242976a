//! `chronolux render`: load → frame builder → technique → frames on disk.

use crate::cli::RenderArgs;
use crate::info;
use crate::scene_input;
use anyhow::{Context, Result, bail};
use chronolux_core::scene::desc::{Projection, SceneDesc};
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
use chronolux_core::scene::source::FrameSource;
use chronolux_io::image::Image;
use chronolux_io::output::{FrameRecord, FrameSink, Manifest};
use chronolux_render::dept::budget::PhotonCount;
use chronolux_render::pt::PathSettings;
use chronolux_render::registry::TechniqueConfig;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::sync::Arc;
use std::time::Instant;

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
    if args.spp == 0 || args.spp > MAX_SPP {
        bail!("--spp {} out of range (1 to {MAX_SPP})", args.spp);
    }
    check_fps_and_depth(args.fps, args.max_depth)?;
    if !args.exposure.is_finite() {
        bail!("--exposure must be a finite number of stops");
    }
    chronolux_render::motion_blur::check_shutter(args.shutter).map_err(anyhow::Error::msg)?;
    if args.shutter > 0.0 && !["path", "bdpt", "stbpt"].contains(&args.method.as_str()) {
        bail!(
            "--shutter (motion blur) is implemented for --method path, bdpt and stbpt, not {}",
            args.method
        );
    }
    set_threads(args.threads)?;
    // Everything that can be checked without the scene is checked before loading it.
    let requested_frames = args.frames.as_deref().map(parse_frames).transpose()?;
    let requested_resolution = args
        .resolution
        .as_deref()
        .map(parse_resolution)
        .transpose()?;
    let input = scene_input::load(&args.scene)?;
    let summary = info::summarize(&input);
    let last = last_frame(&input.desc, input.animation, args.fps);
    let frames = match requested_frames {
        Some(f) => f,
        None => (0..=last.unwrap_or(0)).collect(),
    };
    if let Some(last) = last {
        let max = *frames.iter().max().unwrap();
        if max > last {
            bail!(
                "--frames goes to frame {max}, but the animation ends at frame {last} ({:.3} s at {} fps)",
                last as f32 / args.fps,
                args.fps
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
    let (w, h) = match requested_resolution {
        Some(r) => r,
        // The built-in demo is meant to finish in a few minutes on a laptop: 256² by default.
        None if args.scene.scene.is_none() => (256, 256),
        None => default_resolution(&input.desc, &input.camera),
    };
    let photons: Option<PhotonCount> = match &args.photons {
        None => None,
        Some(_) if !args.method.contains("dept") => {
            bail!("--photons applies to the photon methods (dept*, spacetime-dept) only")
        }
        Some(p) => Some(p.parse().map_err(anyhow::Error::msg)?),
    };
    if args.window.is_some() && args.method != "stbpt" {
        bail!("--window applies to --method stbpt only");
    }
    let sink = FrameSink::create(&args.output)?;
    let config = match args.method.as_str() {
        "path" => TechniqueConfig::Path(PathSettings {
            spp: args.spp,
            max_depth: args.max_depth,
            rr_depth: 5,
            seed: args.seed,
        }),
        "bdpt" => TechniqueConfig::Bdpt(chronolux_render::bdpt::BdptSettings {
            spp: args.spp,
            max_depth: args.max_depth,
            seed: args.seed,
            ..Default::default()
        }),
        "stbpt" => TechniqueConfig::Stbpt(chronolux_render::temporal::stbpt::StbptSettings {
            bdpt: chronolux_render::bdpt::BdptSettings {
                spp: args.spp,
                max_depth: args.max_depth,
                seed: args.seed,
                ..Default::default()
            },
            window: args.window.unwrap_or(4),
            shutter: args.shutter,
            ..Default::default()
        }),
        "dept" => TechniqueConfig::Dept(
            chronolux_render::dept::DeptSettings {
                spp: args.spp,
                seed: args.seed,
                ..Default::default()
            }
            .with_photons(photons),
        ),
        "dept-spatial" => TechniqueConfig::DeptSpatial(
            chronolux_render::dept::DeptSettings {
                spp: args.spp,
                seed: args.seed,
                ..chronolux_render::dept::DeptSettings::spatial()
            }
            .with_photons(photons),
        ),
        "dept-bilateral" => TechniqueConfig::DeptBilateral(
            chronolux_render::dept::DeptSettings {
                spp: args.spp,
                seed: args.seed,
                ..chronolux_render::dept::DeptSettings::bilateral()
            }
            .with_photons(photons),
        ),
        "spacetime-dept" => TechniqueConfig::SpacetimeDept(
            chronolux_render::temporal::spacetime_dept::SpacetimeSettings {
                spp: args.spp,
                seed: args.seed,
                ..Default::default()
            }
            .with_photons(photons),
        ),
        m => bail!("unknown --method '{m}'"),
    };
    let mut renderer: Box<dyn chronolux_render::sequence::SequenceRenderer + Send> = match &config {
        TechniqueConfig::Path(s) if args.shutter > 0.0 => {
            Box::new(chronolux_render::motion_blur::MotionBlur::new(
                chronolux_render::pt::PathTracer::new(s.clone()),
                args.shutter,
            ))
        }
        TechniqueConfig::Bdpt(s) if args.shutter > 0.0 => {
            Box::new(chronolux_render::motion_blur::MotionBlur::new(
                chronolux_render::bdpt::Bdpt::new(s.clone()),
                args.shutter,
            ))
        }
        _ => config.build(),
    };
    let desc = Arc::new(input.desc);
    let builder = FrameBuilder::new(desc.clone(), input.animation, input.camera.clone(), w, h)?;
    let mut source = FrameSource::new(builder, args.fps, frames.clone());

    let settings = serde_json::json!({
        "technique": config,
        "resolution": [w, h],
        "fps": args.fps,
        "shutter": args.shutter,
        "frames": frames,
        "exposure": args.exposure,
        "threads": rayon::current_num_threads(),
        "animation": input.animation.map(|a| desc.animations[a.index()].name.clone()),
        "camera": match &input.camera {
            CameraChoice::First => None,
            CameraChoice::Named(n) => Some(n.clone()),
        },
        "stage": args.scene.stage,
        "scene": input.source,
    });
    let mut manifest = Manifest::new(
        std::env::args().collect(),
        settings,
        serde_json::to_value(&summary)?,
    );
    if args.resume
        && let Some(earlier) = sink.read_manifest()?
    {
        check_resumable(&earlier.settings, &manifest.settings, &args.output)?;
        manifest.merge_earlier(&earlier);
    }

    // Progress bars only on a terminal; otherwise (logs, CI, tests) one line per frame.
    let interactive = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mp = MultiProgress::with_draw_target(if interactive {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    });
    let style = ProgressStyle::with_template("{prefix:>7} [{bar:40}] {pos}/{len} {msg} ETA {eta}")
        .expect("valid progress template")
        .progress_chars("=> ");
    let frame_bar = mp.add(ProgressBar::new(frames.len() as u64));
    frame_bar.set_style(style.clone());
    frame_bar.set_prefix("frames");
    let pixel_bar = mp.add(ProgressBar::new(u64::from(w) * u64::from(h)));
    pixel_bar.set_style(style);
    pixel_bar.set_prefix("pixels");
    let say = |s: String| {
        if interactive {
            // Prints above the bars; falls back to plain stderr if that fails.
            if mp.println(&s).is_err() {
                eprintln!("{s}");
            }
        } else {
            eprintln!("{s}");
        }
    };

    say(format!(
        "rendering {} frame(s) of {} at {w}x{h}, {} spp, method {}, {} thread(s) into {}",
        frames.len(),
        input.source,
        args.spp,
        renderer.name(),
        rayon::current_num_threads(),
        args.output.display()
    ));
    let total = Instant::now();
    let mut rendered_frames = Vec::new();
    let n = frames.len();
    let width = n.to_string().len();
    // The bars are cleared whatever happens, so that an error line is not drawn over.
    let result = (|| -> Result<()> {
        for (k, &f) in frames.iter().enumerate() {
            if args.resume && sink.is_complete(f) {
                say(format!(
                    "frame {f} [{:>width$}/{n}]: already complete, skipped (--resume)",
                    k + 1
                ));
                frame_bar.inc(1);
                rendered_frames.push(f);
                continue;
            }
            let t = f as f32 / args.fps;
            let start = Instant::now();
            pixel_bar.reset();
            let out = renderer.render_frame(&mut source, f, &|n| pixel_bar.inc(n));
            let image = Image {
                width: out.width,
                height: out.height,
                pixels: out.pixels,
            };
            sink.write_frame(f, &image, args.exposure)
                .with_context(|| format!("writing frame {f}"))?;
            let wall = start.elapsed().as_secs_f64();
            let rec = FrameRecord::new(
                f,
                t,
                wall,
                serde_json::json!({
                    "rays": out.stats.rays,
                    "shadow_rays": out.stats.shadow_rays,
                    "samples": out.stats.samples,
                    "invalid_samples": out.invalid_samples,
                    "photons": renderer.photons_last_frame(),
                    "reuse": renderer.reuse_last_frame(),
                    "build": source.last_build,
                }),
            );
            manifest.upsert_frame(rec);
            sink.write_manifest(&manifest)?;
            frame_bar.inc(1);
            say(format!(
                "frame {f} [{:>width$}/{n}] t={t:.3} s: {wall:.2} s, {:.2} Mrays/s{}",
                k + 1,
                (out.stats.rays + out.stats.shadow_rays) as f64 / wall.max(1e-9) / 1e6,
                if out.invalid_samples > 0 {
                    format!(", {} NaN/Inf samples dropped", out.invalid_samples)
                } else {
                    String::new()
                }
            ));
            rendered_frames.push(f);
        }
        Ok(())
    })();
    pixel_bar.finish_and_clear();
    frame_bar.finish_and_clear();
    result?;
    manifest.finish(total.elapsed().as_secs_f64());
    sink.write_manifest(&manifest)?;
    if !args.no_preview && rendered_frames.len() > 1 {
        match chronolux_io::output::write_preview(&args.output, &rendered_frames, args.fps) {
            Ok(p) => say(format!("preview: {}", p.display())),
            Err(e) => eprintln!("warning: no preview written: {e}"),
        }
    }
    say(format!(
        "done: {} frame(s) in {:.1} s → {}",
        rendered_frames.len(),
        total.elapsed().as_secs_f64(),
        args.output.display()
    ));
    Ok(())
}

/// `--resume` continues a run only with the settings that made its frames: mixing frames of
/// different sample counts, sizes or cameras in one sequence would be silently wrong.
fn check_resumable(
    earlier: &serde_json::Value,
    now: &serde_json::Value,
    dir: &std::path::Path,
) -> Result<()> {
    let keys = [
        "technique",
        "resolution",
        "fps",
        "shutter",
        "exposure",
        "animation",
        "camera",
        "stage",
        "scene",
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
