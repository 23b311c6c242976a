//! Rendering across machines: plans of segments with overlap, farm job files (Slurm job
//! arrays, Open Job Description templates for Deadline Cloud), and assembling the result.
//!
//! ## The contract
//! A farm cuts a frame range into segments; a temporal technique then needs frames around
//! a segment's own (its window, or its history), or it flickers where segments meet. Here
//! the overlap is part of the plan: the technique's registry entry says which neighbouring
//! frames it needs ([`registry::frame_context`]), and each segment computes them and writes
//! only its own frames. For techniques whose samples depend only on (seed, frame, pixel,
//! sample index), with their window in the frame list, a frame rendered by a segment is
//! bit-identical to the same frame of a single run over the whole range (tested for every
//! such technique). Stateful ones get a warm-up history and their seams are measured by
//! `assemble`.
//!
//! A plan fixes the complete configuration ([`RunConfig`]: method, settings, seed,
//! resolution, frames, scene by absolute path), so no segment can run with other
//! settings: `render --plan P --segment I` accepts no setting flag.
//!
//! ## Files in a farm folder
//! `plan.json`, the frames (`frame_NNNN.exr/.png`, written atomically by the segment that
//! owns them), one manifest per segment (`run.segment-NNNN.json`: segments sharing a folder
//! never write the same file), and, after `assemble`, `run.json` and the preview. Slurm:
//! `render.sbatch`, `assemble.sbatch`, `logs/`. Open Job Description: `job.template.yaml`.

use crate::args::{RenderArgs, SceneArgs};
use crate::config::RunConfig;
use crate::render::{Exec, execute, resolve};
use crate::scene_input;
use crate::segment::SegmentRun;
use anyhow::{Context, Result, bail};
use chronolux_core::color::Rgb;
use chronolux_core::metrics;
use chronolux_io::output::{FrameRecord, FrameSink, Manifest};
use chronolux_render::registry::{self, FrameContext};
use clap::{Args, Subcommand};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Version of the plan format.
const PLAN_VERSION: u32 = 1;

#[derive(Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    #[command(flatten)]
    pub cut: CutArgs,
    /// Print the plan as JSON (default: a table).
    #[arg(long)]
    pub json: bool,
}

/// How to cut the frames into segments.
#[derive(Args, Debug, Clone)]
pub struct CutArgs {
    /// Number of segments (frames split as evenly as possible).
    #[arg(long, value_name = "N", conflicts_with = "segment_length")]
    pub segments: Option<u32>,
    /// Frames owned by each segment (the last may own fewer).
    #[arg(long, value_name = "L")]
    pub segment_length: Option<u32>,
}

#[derive(Args, Debug)]
pub struct FarmArgs {
    #[command(subcommand)]
    pub kind: FarmKind,
}

#[derive(Subcommand, Debug)]
pub enum FarmKind {
    /// A Slurm job array (one task per segment, throttled to --max-parallel) and an
    /// assemble job that runs after every task succeeded (`afterok`).
    Slurm(SlurmArgs),
    /// An Open Job Description (Deadline Cloud) job template: a Render step with one task
    /// per segment, and an Assemble step after it.
    Openjd(OpenjdArgs),
}

#[derive(Args, Debug)]
pub struct SlurmArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    #[command(flatten)]
    pub cut: CutArgs,
    /// Most array tasks running at once (Slurm's `%N` throttle). Default: no limit.
    #[arg(long, value_name = "N")]
    pub max_parallel: Option<u32>,
    /// Submit the jobs with `sbatch` and print their ids.
    #[arg(long)]
    pub submit: bool,
}

#[derive(Args, Debug)]
pub struct OpenjdArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    #[command(flatten)]
    pub cut: CutArgs,
}

#[derive(Args, Debug)]
pub struct AssembleArgs {
    /// The farm folder (with plan.json).
    pub dir: PathBuf,
    /// Do not write the animated preview.
    #[arg(long)]
    pub no_preview: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// A render cut into segments.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    pub chronolux_plan: u32,
    pub config: RunConfig,
    /// What the technique needs around a frame (from the registry).
    pub context: FrameContext,
    pub segments: Vec<Segment>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    pub index: u32,
    /// Frames this segment writes.
    pub owned: Vec<u32>,
    /// Frames it computes (owned plus the context the technique needs, within the range).
    pub compute: Vec<u32>,
}

/// Cuts `frames` into segments and adds each one's context.
pub fn cut(frames: &[u32], cut: &CutArgs, ctx: &FrameContext) -> Result<Vec<Segment>> {
    let n = frames.len() as u32;
    let len = match (cut.segments, cut.segment_length) {
        (Some(0), _) => bail!("--segments must be at least 1"),
        (_, Some(0)) => bail!("--segment-length must be at least 1"),
        (Some(s), None) => n.div_ceil(s.min(n)),
        (None, Some(l)) => l,
        (None, None) => bail!("give --segments N or --segment-length L"),
        (Some(_), Some(_)) => bail!("give --segments or --segment-length, not both"),
    };
    Ok(frames
        .chunks(len as usize)
        .enumerate()
        .map(|(i, owned)| {
            let lo = owned[0].saturating_sub(ctx.before);
            let hi = owned[owned.len() - 1].saturating_add(ctx.after);
            Segment {
                index: i as u32,
                owned: owned.to_vec(),
                compute: frames
                    .iter()
                    .copied()
                    .filter(|&f| f >= lo && f <= hi)
                    .collect(),
            }
        })
        .collect())
}

/// The plan of a render's flags cut as asked; the scene by absolute path so the plan
/// runs from any working directory.
pub fn make_plan(render: &RenderArgs, cut_args: &CutArgs) -> Result<Plan> {
    if render.plan.is_some() {
        bail!("--plan belongs to `render`; plan from the render's own flags");
    }
    let (mut config, _, _) = resolve(render)?;
    if let Some(s) = &config.scene
        && !s.starts_with("builtin:")
    {
        config.scene = Some(
            std::fs::canonicalize(s)
                .with_context(|| format!("cannot resolve scene path {s}"))?
                .display()
                .to_string(),
        );
    }
    let tech = registry::find(&config.method).map_err(anyhow::Error::msg)?;
    let context = registry::frame_context(tech, &config.technique);
    let segments = cut(&config.frames, cut_args, &context)?;
    Ok(Plan {
        chronolux_plan: PLAN_VERSION,
        config,
        context,
        segments,
    })
}

/// `chronolux plan`.
pub fn plan(args: PlanArgs) -> Result<()> {
    let plan = make_plan(&args.render, &args.cut)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&plan)?);
        return Ok(());
    }
    let owned: usize = plan.segments.iter().map(|s| s.owned.len()).sum();
    let computed: usize = plan.segments.iter().map(|s| s.compute.len()).sum();
    println!(
        "{} frame(s) of --method {} in {} segment(s); context {} before, {} after{}; computed / owned frames = {:.2}",
        owned,
        plan.config.method,
        plan.segments.len(),
        plan.context.before,
        plan.context.after,
        if plan.context.exact {
            " (frames bit-identical to a single run)"
        } else {
            " (stateful: warm-up history, seams measured by `assemble`)"
        },
        computed as f64 / owned.max(1) as f64
    );
    for s in &plan.segments {
        println!(
            "  segment {:>3}: owns {}..={} ({} frames), computes {}..={}",
            s.index,
            s.owned[0],
            s.owned[s.owned.len() - 1],
            s.owned.len(),
            s.compute[0],
            s.compute[s.compute.len() - 1]
        );
    }
    Ok(())
}

fn read_plan(path: &Path) -> Result<Plan> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let plan: Plan = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a chronolux plan", path.display()))?;
    if plan.chronolux_plan != PLAN_VERSION {
        bail!(
            "{}: plan format {} (this chronolux reads {PLAN_VERSION})",
            path.display(),
            plan.chronolux_plan
        );
    }
    Ok(plan)
}

/// `chronolux render --plan P --segment I`.
pub fn render_segment(args: RenderArgs) -> Result<()> {
    let (Some(plan_path), Some(index)) = (&args.plan, args.segment) else {
        bail!("--plan and --segment go together");
    };
    let given: Vec<&str> = [
        ("SCENE", args.scene.scene.is_some()),
        ("--animation", args.scene.animation.is_some()),
        ("--camera", args.scene.camera.is_some()),
        ("--stage", args.scene.stage.is_some()),
        ("--frames", args.frames.is_some()),
        ("--fps", args.fps.is_some()),
        ("--spp", args.spp.is_some()),
        ("--resolution", args.resolution.is_some()),
        ("--max-depth", args.max_depth.is_some()),
        ("--method", args.method.is_some()),
        ("--set", !args.set.is_empty()),
        ("--config", args.config.is_some()),
        ("--shutter", args.shutter.is_some()),
        ("--window", args.window.is_some()),
        ("--photons", args.photons.is_some()),
        ("--seed", args.seed.is_some()),
        ("--exposure", args.exposure.is_some()),
        ("--passes", args.passes.is_some()),
        ("--denoise", args.denoise),
        ("--no-denoise", args.no_denoise),
        ("--quality", args.quality.is_some()),
        ("--denoise-quality", args.denoise_quality.is_some()),
        ("--view", args.view.is_some()),
        ("--environment", args.environment.is_some()),
    ]
    .into_iter()
    .filter(|(_, g)| *g)
    .map(|(n, _)| n)
    .collect();
    if !given.is_empty() {
        bail!(
            "--plan fixes every setting of the render: remove {} (only --segment, --output, --threads, --resume and --no-preview go with it)",
            given.join(", ")
        );
    }
    let plan = read_plan(plan_path)?;
    let seg = plan
        .segments
        .iter()
        .find(|s| s.index == index)
        .with_context(|| {
            format!(
                "--segment {index}: the plan has segments 0..{}",
                plan.segments.len()
            )
        })?;
    let c = &plan.config;
    let input = scene_input::load(&SceneArgs {
        scene: c.scene.clone().map(Into::into),
        animation: c.animation.clone(),
        camera: c.camera.clone(),
        stage: c.stage.clone(),
    })?;
    execute(
        c,
        input,
        &Exec {
            output: args.output.clone(),
            resume: args.resume,
            no_preview: true,
            threads: args.threads,
            segment: Some(SegmentRun {
                index,
                owned: seg.owned.clone(),
                compute: seg.compute.clone(),
                render_before: plan.context.render_before,
            }),
            // The plan fixed denoising: on where the machine that planned had it.
            denoise_skipped: None,
        },
    )
}

/// Quotes `s` for a POSIX shell.
fn sh(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// Writes `plan.json` into the render's output folder (absolute) and returns both.
fn write_plan(render: &RenderArgs, cut_args: &CutArgs) -> Result<(Plan, PathBuf)> {
    let plan = make_plan(render, cut_args)?;
    std::fs::create_dir_all(&render.output)
        .with_context(|| format!("cannot create {}", render.output.display()))?;
    let dir = std::fs::canonicalize(&render.output)?;
    let path = dir.join("plan.json");
    let text = serde_json::to_string_pretty(&plan)? + "\n";
    chronolux_io::output::write_atomic(&path, |w| std::io::Write::write_all(w, text.as_bytes()))
        .with_context(|| format!("writing {}", path.display()))?;
    Ok((plan, dir))
}

/// `chronolux farm slurm|openjd`. The OpenJD template's paths default to the template's
/// own folder (the farm folder, where `plan.json` is), as the specification requires of
/// default paths; the executable is a string parameter for the workers.
pub fn farm(args: FarmArgs) -> Result<()> {
    match args.kind {
        FarmKind::Slurm(a) => slurm(a),
        FarmKind::Openjd(a) => openjd(a),
    }
}

fn exe() -> Result<String> {
    Ok(std::env::current_exe()
        .context("cannot locate the chronolux executable")?
        .display()
        .to_string())
}

fn slurm(a: SlurmArgs) -> Result<()> {
    if a.max_parallel == Some(0) {
        bail!("--max-parallel must be at least 1");
    }
    let (plan, dir) = write_plan(&a.render, &a.cut)?;
    let n = plan.segments.len();
    let exe = exe()?;
    std::fs::create_dir_all(dir.join("logs"))?;
    let d = dir.display().to_string();
    let throttle = a.max_parallel.map_or(String::new(), |m| format!("%{m}"));
    let threads = a
        .render
        .threads
        .map_or(String::new(), |t| format!(" --threads {t}"));
    let render = format!(
        "#!/bin/sh\n\
         # One array task per segment of {plan}; written by `chronolux farm slurm`.\n\
         #SBATCH --job-name=chronolux-render\n\
         #SBATCH --array=0-{last}{throttle}\n\
         #SBATCH --output={logs}/segment-%a.log\n\
         exec {exe} render --plan {plan} --segment \"$SLURM_ARRAY_TASK_ID\" --output {dir} --resume{threads}\n",
        plan = sh(&format!("{d}/plan.json")),
        last = n - 1,
        logs = d,
        exe = sh(&exe),
        dir = sh(&d),
    );
    let assemble = format!(
        "#!/bin/sh\n\
         # Runs after every segment succeeded (afterok); written by `chronolux farm slurm`.\n\
         #SBATCH --job-name=chronolux-assemble\n\
         #SBATCH --output={d}/logs/assemble.log\n\
         exec {exe} assemble {dir}\n",
        exe = sh(&exe),
        dir = sh(&d),
    );
    for (name, text) in [("render.sbatch", &render), ("assemble.sbatch", &assemble)] {
        let p = dir.join(name);
        chronolux_io::output::write_atomic(&p, |w| std::io::Write::write_all(w, text.as_bytes()))
            .with_context(|| format!("writing {}", p.display()))?;
    }
    eprintln!(
        "{n} segment(s) of {} frame(s): {d}/render.sbatch, {d}/assemble.sbatch, {d}/plan.json",
        plan.config.frames.len()
    );
    if a.submit {
        let sbatch = |args: &[&str]| -> Result<String> {
            let out = std::process::Command::new("sbatch")
                .args(args)
                .output()
                .context("cannot run sbatch (is Slurm installed and on PATH?)")?;
            if !out.status.success() {
                bail!(
                    "sbatch {} failed: {}",
                    args.join(" "),
                    String::from_utf8_lossy(&out.stderr).trim()
                );
            }
            let id = String::from_utf8_lossy(&out.stdout).trim().to_string();
            Ok(id.split(';').next().unwrap_or_default().to_string())
        };
        let r = sbatch(&["--parsable", &format!("{d}/render.sbatch")])?;
        let s = sbatch(&[
            "--parsable",
            &format!("--dependency=afterok:{r}"),
            &format!("{d}/assemble.sbatch"),
        ])?;
        println!("render job {r}");
        println!("assemble job {s}");
    }
    Ok(())
}

fn openjd(a: OpenjdArgs) -> Result<()> {
    let (plan, dir) = write_plan(&a.render, &a.cut)?;
    let n = plan.segments.len();
    let exe = exe()?;
    // YAML strings quoted with single quotes (a quote inside is doubled).
    let q = |s: &str| format!("'{}'", s.replace('\'', "''"));
    let template = format!(
        "specificationVersion: 'jobtemplate-2023-09'\n\
         name: 'chronolux {method}, {frames} frames in {n} segments'\n\
         parameterDefinitions:\n\
         - name: Chronolux\n  type: STRING\n  description: 'chronolux executable on the workers'\n  default: {exe}\n\
         - name: PlanFile\n  type: PATH\n  objectType: FILE\n  dataFlow: IN\n  default: 'plan.json'\n\
         - name: OutputDir\n  type: PATH\n  objectType: DIRECTORY\n  dataFlow: OUT\n  default: '.'\n\
         steps:\n\
         - name: Render\n\
         \x20 parameterSpace:\n\
         \x20   taskParameterDefinitions:\n\
         \x20   - name: Segment\n\
         \x20     type: INT\n\
         \x20     range: '0-{last}'\n\
         \x20 script:\n\
         \x20   actions:\n\
         \x20     onRun:\n\
         \x20       command: '{{{{Param.Chronolux}}}}'\n\
         \x20       args: ['render', '--plan', '{{{{Param.PlanFile}}}}', '--segment', '{{{{Task.Param.Segment}}}}', '--output', '{{{{Param.OutputDir}}}}', '--resume']\n\
         - name: Assemble\n\
         \x20 dependencies:\n\
         \x20 - dependsOn: Render\n\
         \x20 script:\n\
         \x20   actions:\n\
         \x20     onRun:\n\
         \x20       command: '{{{{Param.Chronolux}}}}'\n\
         \x20       args: ['assemble', '{{{{Param.OutputDir}}}}']\n",
        method = plan.config.method,
        frames = plan.config.frames.len(),
        exe = q(&exe),
        last = n - 1,
    );
    let p = dir.join("job.template.yaml");
    chronolux_io::output::write_atomic(&p, |w| std::io::Write::write_all(w, template.as_bytes()))
        .with_context(|| format!("writing {}", p.display()))?;
    eprintln!(
        "{n} segment(s): {} (submit with `deadline bundle submit` or run locally with `openjd run`)",
        p.display()
    );
    Ok(())
}

/// One boundary between two segments.
#[derive(Debug, Serialize)]
pub struct Seam {
    /// The segment starting at the boundary.
    pub segment: u32,
    /// Last frame of the previous segment, first of this one.
    pub frames: [u32; 2],
    /// Mean |I_b − I_{b−1}| across the boundary (flicker without a reference).
    pub flicker: f64,
}

#[derive(Debug, Serialize)]
pub struct AssembleReport {
    pub frames: usize,
    pub segments: usize,
    pub seams: Vec<Seam>,
    /// Mean of the same flicker over consecutive frames inside the segments.
    pub inside_flicker: Option<f64>,
    /// Largest seam flicker / inside flicker (≤ 1: no seam stands out).
    pub worst_seam_ratio: Option<f64>,
}

/// `chronolux assemble DIR`.
pub fn assemble(a: AssembleArgs) -> Result<()> {
    let plan = read_plan(&a.dir.join("plan.json"))?;
    let sink = FrameSink::create(&a.dir)?;
    let c = &plan.config;
    let missing: Vec<u32> = c
        .frames
        .iter()
        .copied()
        .filter(|&f| !sink.is_complete(f))
        .collect();
    if !missing.is_empty() {
        bail!(
            "{}: {} of {} frame(s) missing or incomplete: {:?} (re-run their segments with --resume)",
            a.dir.display(),
            missing.len(),
            c.frames.len(),
            missing
        );
    }
    let mut images: std::collections::BTreeMap<u32, Vec<Rgb>> = Default::default();
    for &f in &c.frames {
        let img = chronolux_io::image::read_exr(sink.exr_path(f))
            .with_context(|| format!("frame {f} does not decode"))?;
        if [img.width, img.height] != c.resolution {
            bail!(
                "frame {f} is {}x{}, the plan says {}x{}",
                img.width,
                img.height,
                c.resolution[0],
                c.resolution[1]
            );
        }
        images.insert(f, img.pixels);
    }
    // One run.json from the segments' manifests.
    let mut records: Vec<FrameRecord> = Vec::new();
    let mut started: Option<String> = None;
    let mut wall = 0.0;
    for s in &plan.segments {
        let name = SegmentRun {
            index: s.index,
            owned: s.owned.clone(),
            compute: s.compute.clone(),
            render_before: plan.context.render_before,
        }
        .manifest_name();
        let seg_sink = FrameSink::create(&a.dir)?.with_manifest_name(&name);
        let m = seg_sink
            .read_manifest()?
            .with_context(|| format!("segment {}: {name} missing", s.index))?;
        started = Some(match started {
            Some(x) if x <= m.started => x,
            _ => m.started.clone(),
        });
        wall += m.total_wall_s;
        records.extend(m.frames.into_iter().filter(|r| s.owned.contains(&r.frame)));
    }
    records.sort_by_key(|r| r.frame);
    // Complete files without a record: a segment killed between writing a frame and
    // recording it (its `--resume` renders such a frame again).
    let unrecorded: Vec<u32> = c
        .frames
        .iter()
        .copied()
        .filter(|f| records.binary_search_by_key(f, |r| r.frame).is_err())
        .collect();
    if !unrecorded.is_empty() {
        bail!(
            "{}: {} frame(s) have their files but no record in their segment's run.segment-NNNN.json (the segment was stopped before recording them): {:?} (re-run their segments with --resume)",
            a.dir.display(),
            unrecorded.len(),
            unrecorded
        );
    }
    let mut settings = serde_json::to_value(c)?;
    settings["farm"] = serde_json::json!({
        "segments": plan.segments,
        "context": plan.context,
    });
    let mut manifest = Manifest::new(
        std::env::args().collect(),
        settings,
        serde_json::json!({ "assembled_from": plan.segments.len() }),
    );
    if let Some(s) = started {
        manifest.started = s;
    }
    for r in records {
        manifest.upsert_frame(r);
    }
    manifest.finish(wall);
    sink.write_manifest(&manifest)?;
    // Seams: flicker across each boundary against flicker inside the segments.
    let fl = |a: u32, b: u32| metrics::flicker_no_reference(&images[&a], &images[&b]);
    let mut inside = Vec::new();
    let mut seams = Vec::new();
    for (k, s) in plan.segments.iter().enumerate() {
        for w in s.owned.windows(2) {
            inside.push(fl(w[0], w[1]));
        }
        if k > 0 {
            let prev = *plan.segments[k - 1].owned.last().expect("owned");
            let first = s.owned[0];
            seams.push(Seam {
                segment: s.index,
                frames: [prev, first],
                flicker: fl(prev, first),
            });
        }
    }
    let inside_flicker =
        (!inside.is_empty()).then(|| inside.iter().sum::<f64>() / inside.len() as f64);
    let worst = seams
        .iter()
        .map(|s| s.flicker)
        .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))));
    let report = AssembleReport {
        frames: c.frames.len(),
        segments: plan.segments.len(),
        worst_seam_ratio: match (worst, inside_flicker) {
            (Some(w), Some(i)) if i > 0.0 => Some(w / i),
            _ => None,
        },
        seams,
        inside_flicker,
    };
    if !a.no_preview && c.frames.len() > 1 {
        match chronolux_io::output::write_preview(&a.dir, &c.frames, c.fps) {
            Ok(p) => eprintln!("preview: {}", p.display()),
            Err(e) => eprintln!("warning: no preview written: {e}"),
        }
    }
    if a.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!(
            "{} frame(s) from {} segment(s), all present and readable; run.json written",
            report.frames, report.segments
        );
        for s in &report.seams {
            println!(
                "  seam before segment {} (frames {}→{}): flicker {:.5}",
                s.segment, s.frames[0], s.frames[1], s.flicker
            );
        }
        if let (Some(i), Some(r)) = (report.inside_flicker, report.worst_seam_ratio) {
            println!("  inside the segments: flicker {i:.5}; worst seam / inside = {r:.2}");
        }
    }
    Ok(())
}
