//! `chronolux bench`: speed measurements (rays/s, BVH builds, samples/s).
//!
//! - `bench rays`: incoherent closest-hit and any-hit (shadow) rays through the renderer's
//!   own two-level acceleration structure (`FrameScene::intersect` / `occluded`, the calls
//!   the path tracer makes), on ray sets as in ../shared/DEPENDENCIES.md §4: *hemi* (a
//!   uniformly chosen triangle, a uniform point on it, offset along the geometric normal,
//!   direction uniform over that hemisphere) and *box* (origin uniform in the scene bounds,
//!   direction uniform on the sphere). PCG32-seeded, so every run traces the same rays;
//!   `--dump-rays` writes them for other renderers (scripts/peer/mitsuba_rays.py). Each
//!   set is traced twice: one call per ray (how the kernels trace today) and in packets of
//!   16 (`intersect_many` / `occluded_many`: Embree's packet kernels, the way Mitsuba's
//!   wavefront traces the same rays). The backend (Embree or the own BVH,
//!   `CHRONOLUX_ACCEL=bvh`) is named in the output. Each query is timed in wall and in
//!   process CPU seconds, after one untimed pass; compare CPU seconds on a shared machine.
//! - `bench build`: BVH build seconds (the frame builder's persistent BLASes, one frame,
//!   and one flat BLAS over all world-space triangles).
//! - `bench pt`: path-traced samples per second, excluding scene loading and frame building.
//!
//! Rounds are interleaved (every measurement once per round) and medians reported, because
//! the machines we measure on are shared.

use crate::args::SceneArgs;
use crate::render::{parse_frames, parse_resolution};
use crate::scene_input;
use anyhow::{Context, Result, bail};
use chronolux_core::accel::{Blas, TriRef};
use chronolux_core::geometry::Ray;
use chronolux_core::math::{Affine3A, Vec2, Vec3};
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::sampling::warps::{sample_uniform_sphere, sample_uniform_triangle};
use chronolux_core::scene::desc::SceneDesc;
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder, FrameScene};
use chronolux_core::scene::generated::TerrainSpheres;
use chronolux_core::scene::source::FrameSource;
use chronolux_render::framework::run::MemorySink;
use chronolux_render::registry::{self, BuildContext};
use clap::{Args, Subcommand};
use rayon::prelude::*;
use serde_json::{Value, json};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use update::process_cpu_seconds;

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub what: BenchCommand,
}

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Incoherent closest-hit and shadow (any-hit) rays per second, and BVH build time.
    /// Without SCENE or --generated: the built-in demo and a 1,024,000-triangle generated
    /// scene (terrain + icospheres).
    Rays(RaysArgs),
    /// BVH build seconds. Same scene choice as `rays`.
    Build(BuildArgs),
    /// Path-traced samples per second (scene loading and frame building excluded).
    Pt(PtArgs),
    /// Equal-quality benchmark: time (and flicker) for a method and its baseline to reach
    /// target HDR-FLIP errors against converged references.
    Quality(Box<crate::quality::QualityArgs>),
    /// Time to a clean image after a change: selective photon tracing (`spt`) in priority
    /// order against random order and recomputation from scratch. Without arguments: the
    /// demo, its block jumping across the room.
    Update(Box<update::UpdateArgs>),
}

#[path = "bench_update.rs"]
mod update;

/// Scene choice and common settings of `rays` and `build`.
#[derive(Args, Debug)]
pub struct TargetArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Use a generated terrain-and-spheres scene of about N triangles (95360 and 1024000
    /// give the two scenes of DEPENDENCIES.md §4 exactly). Replaces SCENE.
    #[arg(long, value_name = "N_TRIANGLES")]
    pub generated: Option<u64>,
    /// Frame of the animation to measure (time frame/fps).
    #[arg(long, default_value_t = 0, value_name = "F")]
    pub frame: u32,
    /// Frames per second of the animation timeline.
    #[arg(long, default_value_t = 24.0, value_name = "FPS")]
    pub fps: f32,
    /// Worker threads.
    #[arg(long, default_value_t = 2, value_name = "N")]
    pub threads: usize,
    /// Measurement rounds (interleaved; medians and best reported).
    #[arg(long, default_value_t = 3, value_name = "R")]
    pub rounds: usize,
    /// Print one JSON document instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct RaysArgs {
    #[command(flatten)]
    pub target: TargetArgs,
    /// Rays per set (hemi and box).
    #[arg(long, default_value_t = 1_000_000, value_name = "N")]
    pub rays: usize,
    /// Write each ray set to `DIR/<scene>_<set>.rays` (little-endian f32 ox oy oz dx dy dz
    /// per ray) with `DIR/<scene>_<set>.json` (our hit count and Σt), for other renderers.
    #[arg(long, value_name = "DIR")]
    pub dump_rays: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct BuildArgs {
    #[command(flatten)]
    pub target: TargetArgs,
}

#[derive(Args, Debug)]
pub struct PtArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Samples per pixel.
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub spp: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256", value_name = "WxH")]
    pub resolution: String,
    /// Longest path in segments from the camera (Mitsuba's max_depth); 0 = unlimited.
    #[arg(long, default_value_t = 8, value_name = "N")]
    pub max_depth: u32,
    /// Frames to render: `A..B`, `A..=B` or `N`.
    #[arg(long, default_value = "0", value_name = "RANGE")]
    pub frames: String,
    /// Frames per second of the animation timeline.
    #[arg(long, default_value_t = 24.0, value_name = "FPS")]
    pub fps: f32,
    /// Worker threads.
    #[arg(long, default_value_t = 2, value_name = "N")]
    pub threads: usize,
    /// Rounds over the frames (interleaved; medians reported).
    #[arg(long, default_value_t = 1, value_name = "R")]
    pub rounds: usize,
    /// Print one JSON document instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: BenchArgs) -> Result<()> {
    match args.what {
        BenchCommand::Rays(a) => rays(a),
        BenchCommand::Build(a) => build(a),
        BenchCommand::Pt(a) => pt(a),
        BenchCommand::Quality(a) => crate::quality::run(*a),
        BenchCommand::Update(a) => update::run(*a),
    }
}

fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    if threads == 0 {
        bail!("--threads must be at least 1");
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot set up the thread pool")
}

fn machine() -> Value {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_default();
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_default();
    json!({
        "cpu": cpu,
        "nproc": std::thread::available_parallelism().map_or(0, |n| n.get()),
        "loadavg1": load,
    })
}

fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn best(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// A scene to measure: its description, how to make it, and a short label.
struct Target {
    label: String,
    source: String,
    desc: Arc<SceneDesc>,
    animation: Option<chronolux_core::scene::desc::AnimationId>,
    camera: CameraChoice,
    load_s: f64,
}

fn targets(t: &TargetArgs) -> Result<Vec<Target>> {
    let generated = |n: u64| -> Result<Target> {
        if n == 0 {
            bail!("--generated needs at least 1 triangle");
        }
        let start = Instant::now();
        let p = TerrainSpheres::with_triangles(n);
        let desc = p.scene();
        Ok(Target {
            label: format!("generated{}", p.triangle_count()),
            source: desc.name.clone(),
            desc: Arc::new(desc),
            animation: None,
            camera: CameraChoice::First,
            load_s: start.elapsed().as_secs_f64(),
        })
    };
    let loaded = |args: &SceneArgs| -> Result<Target> {
        let start = Instant::now();
        let input = scene_input::load(args)?;
        let label = match &args.scene {
            Some(p) => p
                .file_stem()
                .map_or("scene".into(), |s| s.to_string_lossy().into_owned()),
            None => "demo".into(),
        };
        Ok(Target {
            label,
            source: input.source,
            desc: Arc::new(input.desc),
            animation: input.animation,
            camera: input.camera,
            load_s: start.elapsed().as_secs_f64(),
        })
    };
    Ok(match (t.generated, &t.scene.scene) {
        (Some(n), None) => vec![generated(n)?],
        (Some(n), Some(_)) => vec![loaded(&t.scene)?, generated(n)?],
        (None, Some(_)) => vec![loaded(&t.scene)?],
        (None, None) => vec![loaded(&t.scene)?, generated(1_024_000)?],
    })
}

/// Triangles with their ids, in world space.
type WorldTriangles = Vec<(TriRef, [Vec3; 3])>;

/// World-space triangles of a frame (through each geometry's instance transform).
fn world_triangles(scene: &FrameScene) -> WorldTriangles {
    let insts = scene.accel.instances();
    let mut out = Vec::new();
    for (gid, g) in scene.geometry.iter().enumerate() {
        let m = if g.world_space {
            Affine3A::IDENTITY
        } else {
            // Rigid geometry: the object-space instance with the largest base ≤ gid.
            insts
                .iter()
                .filter(|i| {
                    (i.geometry_base as usize) <= gid
                        && !scene.geometry[i.geometry_base as usize].world_space
                })
                .max_by_key(|i| i.geometry_base)
                .map_or(Affine3A::IDENTITY, |i| i.world_from_object)
        };
        for (k, t) in g.indices.iter().enumerate() {
            out.push((
                TriRef {
                    geometry: gid as u32,
                    triangle: k as u32,
                },
                t.map(|i| m.transform_point3(g.positions[i as usize])),
            ));
        }
    }
    out
}

/// `n` hemi rays (from surface points) and `n` box rays (from points in the bounds).
fn ray_sets(scene: &FrameScene, tris: &[(TriRef, [Vec3; 3])], n: usize) -> [Vec<Ray>; 2] {
    let b = scene.bounds;
    // Offset along the normal: 1e-5 of the scene's diagonal (≈1e-3 on the 100-unit
    // terrain of DEPENDENCIES.md §4, which used 1e-3).
    let offset = 1e-5 * b.diagonal().length();
    let mut r = Pcg32::new(0x5eed, 1);
    let mut hemi = Vec::with_capacity(n);
    while hemi.len() < n && !tris.is_empty() {
        let k = ((r.next_f32() * tris.len() as f32) as usize).min(tris.len() - 1);
        let [a, b1, c] = tris[k].1;
        let ng = (b1 - a).cross(c - a).normalize_or_zero();
        let (u, v) = sample_uniform_triangle(Vec2::new(r.next_f32(), r.next_f32()));
        let mut d = sample_uniform_sphere(Vec2::new(r.next_f32(), r.next_f32()));
        if ng == Vec3::ZERO {
            continue;
        }
        if d.dot(ng) < 0.0 {
            d = -d;
        }
        let p = (1.0 - u - v) * a + u * b1 + v * c;
        hemi.push(Ray::new(p + offset * ng, d));
    }
    let mut r = Pcg32::new(0x5eed, 2);
    let boxed = (0..n)
        .map(|_| {
            let u = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
            let o = b.min + u * (b.max - b.min);
            let d = sample_uniform_sphere(Vec2::new(r.next_f32(), r.next_f32()));
            Ray::new(o, d)
        })
        .collect();
    [hemi, boxed]
}

/// One traced set: wall and process CPU seconds, hits, Σt over hits.
struct Traced {
    wall_s: f64,
    cpu_s: f64,
    hits: u64,
    sum_t: f64,
}

/// Traces all rays. `packets`: through `FrameScene::intersect_many` / `occluded_many`
/// (16-ray packets on Embree), as a wavefront kernel would issue them, instead of one call
/// per ray. The timed part is the queries and the per-ray conversions of our interface
/// (ray to Embree's layout, hit back), as a kernel pays them; the rays are made before.
/// CPU seconds come from [`process_cpu_seconds`] (`CLOCK_PROCESS_CPUTIME_ID`), the clock
/// of Mitsuba's side too (`time.process_time` in `scripts/peer/mitsuba_rays.py`): on a
/// shared machine wall time counts the other sessions' load.
fn trace(scene: &FrameScene, rays: &[Ray], shadow: bool, packets: bool) -> Traced {
    let cpu0 = process_cpu_seconds();
    let start = Instant::now();
    let (hits, sum_t) = rays
        .par_chunks(4096)
        .map(|chunk| {
            let mut hits = 0u64;
            let mut sum_t = 0f64;
            if packets && shadow {
                let mut out = vec![false; chunk.len()];
                scene.occluded_many(chunk, &mut out);
                hits += out.iter().filter(|&&b| b).count() as u64;
            } else if packets {
                let mut out = vec![None; chunk.len()];
                scene.intersect_many(chunk, &mut out);
                for h in out.iter().flatten() {
                    hits += 1;
                    sum_t += h.t as f64;
                }
            } else {
                for ray in chunk {
                    if shadow {
                        hits += scene.occluded(ray) as u64;
                    } else if let Some(h) = scene.intersect(ray) {
                        hits += 1;
                        sum_t += h.t as f64;
                    }
                }
            }
            (hits, sum_t)
        })
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    Traced {
        wall_s: start.elapsed().as_secs_f64(),
        cpu_s: process_cpu_seconds() - cpu0,
        hits,
        sum_t,
    }
}

/// Build timings of one target: the frame builder's persistent structures (static BLAS,
/// rigid BLASes), one frame (TLAS, deformed BLASes, lights), and one flat BLAS over every
/// world-space triangle. Returns the JSON record, the builder and a frame.
fn build_times(
    t: &Target,
    frame_time: f32,
    rounds: usize,
) -> Result<(Value, FrameScene, WorldTriangles)> {
    let (mut new_s, mut frame_s, mut flat_s) = (vec![], vec![], vec![]);
    let mut last = None;
    for _ in 0..rounds.max(1) {
        let start = Instant::now();
        let mut builder =
            FrameBuilder::new(t.desc.clone(), t.animation, t.camera.clone(), 256, 256)?;
        new_s.push(start.elapsed().as_secs_f64());
        let start = Instant::now();
        let scene = builder.build(frame_time);
        frame_s.push(start.elapsed().as_secs_f64());
        let tris = world_triangles(&scene);
        let start = Instant::now();
        let blas = Blas::build(&tris, false);
        flat_s.push(start.elapsed().as_secs_f64());
        drop(blas);
        last = Some((scene, tris));
    }
    let (scene, tris) = last.unwrap();
    let rec = json!({
        "triangles": tris.len(),
        "instances": scene.accel.instances().len(),
        "builder_new_s": {"median": median(&new_s), "best": best(&new_s)},
        "frame_build_s": {"median": median(&frame_s), "best": best(&frame_s)},
        "flat_blas_build_s": {"median": median(&flat_s), "best": best(&flat_s)},
    });
    Ok((rec, scene, tris))
}

fn rays(a: RaysArgs) -> Result<()> {
    let tg = &a.target;
    if a.rays == 0 {
        bail!("--rays must be at least 1");
    }
    let pool = pool(tg.threads)?;
    let mut out = Vec::new();
    for t in targets(tg)? {
        let time = chronolux_core::scene::source::frame_time(tg.frame, tg.fps);
        let (build, scene, tris) = pool.install(|| build_times(&t, time, tg.rounds))?;
        let sets = ray_sets(&scene, &tris, a.rays);
        let names = ["hemi", "box"];
        // Per (set, kind): seconds of each round, hits, Σt.
        // Kinds: closest, shadow, closest in packets, shadow in packets.
        let mut secs: [[Vec<f64>; 4]; 2] = Default::default();
        let mut cpu: [[Vec<f64>; 4]; 2] = Default::default();
        let mut counts = [[(0u64, 0f64); 4]; 2];
        // One untimed pass over every set and kind first (page faults of the outputs,
        // thread-pool start-up), as Mitsuba's side makes one untimed call per query.
        for rays in &sets {
            for kind in 0..4 {
                pool.install(|| trace(&scene, rays, kind % 2 == 1, kind >= 2));
            }
        }
        for _ in 0..tg.rounds.max(1) {
            for (s, rays) in sets.iter().enumerate() {
                for kind in 0..4 {
                    let r = pool.install(|| trace(&scene, rays, kind % 2 == 1, kind >= 2));
                    secs[s][kind].push(r.wall_s);
                    cpu[s][kind].push(r.cpu_s);
                    counts[s][kind] = (r.hits, r.sum_t);
                }
            }
        }
        let mut sets_json = serde_json::Map::new();
        for (s, name) in names.iter().enumerate() {
            let n = sets[s].len() as f64;
            let rec = |kind: usize| {
                let (hits, sum_t) = counts[s][kind];
                json!({
                    "mrays_per_s_median": n / median(&secs[s][kind]) / 1e6,
                    "mrays_per_s_best": n / best(&secs[s][kind]) / 1e6,
                    "mrays_per_cpu_s_median": n / median(&cpu[s][kind]) / 1e6,
                    "seconds": secs[s][kind],
                    "cpu_seconds": cpu[s][kind],
                    "hits": hits,
                    "hit_fraction": hits as f64 / n,
                    "sum_t": if kind.is_multiple_of(2) { json!(sum_t) } else { Value::Null },
                })
            };
            sets_json.insert(
                name.to_string(),
                json!({"rays": sets[s].len(), "closest": rec(0), "shadow": rec(1),
                       "closest_packets": rec(2), "shadow_packets": rec(3)}),
            );
            if let Some(dir) = &a.dump_rays {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("cannot create {}", dir.display()))?;
                let mut bytes = Vec::with_capacity(sets[s].len() * 24);
                for r in &sets[s] {
                    for x in [r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z] {
                        bytes.extend_from_slice(&x.to_le_bytes());
                    }
                }
                let stem = dir.join(format!("{}_{name}", t.label));
                std::fs::write(stem.with_extension("rays"), bytes)?;
                std::fs::write(
                    stem.with_extension("json"),
                    serde_json::to_string_pretty(&json!({
                        "scene": t.source, "frame": tg.frame, "set": name, "rays": sets[s].len(),
                        "closest_hits": counts[s][0].0, "closest_sum_t": counts[s][0].1,
                        "shadow_hits": counts[s][1].0,
                    }))?,
                )?;
            }
        }
        out.push(json!({
            "scene": t.label,
            "source": t.source,
            "frame": tg.frame,
            "load_s": t.load_s,
            "build": build,
            "sets": sets_json,
        }));
    }
    let doc = json!({
        "bench": "rays",
        "accel": chronolux_core::accel::embree::backend_name(),
        "threads": tg.threads,
        "rounds": tg.rounds,
        "rays_per_set": a.rays,
        "machine": machine(),
        "scenes": out,
    });
    if tg.json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(());
    }
    println!(
        "rays on {} thread(s), {} rays per set, median (best) of {} rounds, {} backend; {}",
        tg.threads,
        a.rays,
        tg.rounds,
        doc["accel"].as_str().unwrap_or(""),
        doc["machine"]
    );
    for s in &out {
        let b = &s["build"];
        println!(
            "{} ({} triangles, {} instances): builder {:.3} s, frame {:.3} s, flat BLAS {:.3} s (median)",
            s["scene"].as_str().unwrap_or(""),
            b["triangles"],
            b["instances"],
            b["builder_new_s"]["median"].as_f64().unwrap_or(f64::NAN),
            b["frame_build_s"]["median"].as_f64().unwrap_or(f64::NAN),
            b["flat_blas_build_s"]["median"]
                .as_f64()
                .unwrap_or(f64::NAN),
        );
        for name in ["hemi", "box"] {
            for kind in ["closest", "shadow", "closest_packets", "shadow_packets"] {
                let r = &s["sets"][name][kind];
                println!(
                    "  {name:>4} {kind:<15} {:7.3} Mrays/s ({:.3}), {:7.3} M per CPU s  hits {:.1}%",
                    r["mrays_per_s_median"].as_f64().unwrap_or(f64::NAN),
                    r["mrays_per_s_best"].as_f64().unwrap_or(f64::NAN),
                    r["mrays_per_cpu_s_median"].as_f64().unwrap_or(f64::NAN),
                    100.0 * r["hit_fraction"].as_f64().unwrap_or(f64::NAN),
                );
            }
        }
    }
    Ok(())
}

fn build(a: BuildArgs) -> Result<()> {
    let tg = &a.target;
    let pool = pool(tg.threads)?;
    let mut out = Vec::new();
    for t in targets(tg)? {
        let time = chronolux_core::scene::source::frame_time(tg.frame, tg.fps);
        let (rec, _, _) = pool.install(|| build_times(&t, time, tg.rounds))?;
        out.push(json!({"scene": t.label, "source": t.source, "load_s": t.load_s, "build": rec}));
    }
    let doc = json!({
        "bench": "build",
        "threads": tg.threads,
        "rounds": tg.rounds,
        "machine": machine(),
        "scenes": out,
    });
    if tg.json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
    } else {
        for s in &out {
            let b = &s["build"];
            println!(
                "{} ({} triangles): builder {:.3} s, frame {:.3} s, flat BLAS {:.3} s (median of {}, {} threads)",
                s["scene"].as_str().unwrap_or(""),
                b["triangles"],
                b["builder_new_s"]["median"].as_f64().unwrap_or(f64::NAN),
                b["frame_build_s"]["median"].as_f64().unwrap_or(f64::NAN),
                b["flat_blas_build_s"]["median"]
                    .as_f64()
                    .unwrap_or(f64::NAN),
                tg.rounds,
                tg.threads
            );
        }
    }
    Ok(())
}

fn pt(a: PtArgs) -> Result<()> {
    if a.spp == 0 {
        bail!("--spp must be at least 1");
    }
    let (w, h) = parse_resolution(&a.resolution)?;
    let frames = parse_frames(&a.frames)?;
    let pool = pool(a.threads)?;
    let start = Instant::now();
    let input = scene_input::load(&a.scene)?;
    let load_s = start.elapsed().as_secs_f64();
    let desc = Arc::new(input.desc);
    // The registry's path tracer through the one run loop; each frame's scene is built
    // (and timed) first, so the loop's time is the rendering alone.
    let tech = registry::find("path").map_err(anyhow::Error::msg)?;
    let mut settings = serde_json::json!({ "spp": a.spp });
    if a.max_depth > 0 {
        settings["max_depth"] = a.max_depth.into();
    }
    let settings = registry::resolve(tech, Some(&settings), &[]).map_err(anyhow::Error::msg)?;
    let mut per_frame: Vec<(Vec<f64>, Vec<f64>, u64, u64)> =
        vec![(vec![], vec![], 0, 0); frames.len()];
    for _ in 0..a.rounds.max(1) {
        let builder = FrameBuilder::new(desc.clone(), input.animation, input.camera.clone(), w, h)?;
        let mut source = FrameSource::new(builder, a.fps, frames.clone());
        let mut tracer = tech
            .build(&settings, &BuildContext::default())
            .map_err(anyhow::Error::msg)?;
        for (k, &f) in frames.iter().enumerate() {
            let t0 = Instant::now();
            pool.install(|| source.frame(f));
            let build_s = t0.elapsed().as_secs_f64();
            let mut sink = MemorySink::new();
            let run = pool
                .install(|| {
                    chronolux_render::framework::run::run(
                        tracer.as_mut(),
                        &mut source,
                        &[f],
                        &mut [&mut sink],
                        None,
                    )
                })
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            let out = &sink.frames[0].1;
            per_frame[k].0.push(build_s);
            per_frame[k].1.push(run.wall_s);
            per_frame[k].2 = out.stats.samples;
            per_frame[k].3 = out.stats.rays + out.stats.shadow_rays;
        }
    }
    let recs: Vec<Value> = frames
        .iter()
        .zip(&per_frame)
        .map(|(f, (b, r, samples, rays))| {
            let m = median(r);
            json!({
                "frame": f,
                "build_s": median(b),
                "render_s": r,
                "render_s_median": m,
                "samples": samples,
                "rays": rays,
                "msamples_per_s": *samples as f64 / m / 1e6,
                "mrays_per_s": *rays as f64 / m / 1e6,
            })
        })
        .collect();
    let total_s: f64 = per_frame.iter().map(|p| median(&p.1)).sum();
    let total_samples: u64 = per_frame.iter().map(|p| p.2).sum();
    let total_rays: u64 = per_frame.iter().map(|p| p.3).sum();
    let doc = json!({
        "bench": "pt",
        "scene": input.source,
        "resolution": [w, h],
        "spp": a.spp,
        "max_depth": a.max_depth,
        "threads": a.threads,
        "rounds": a.rounds,
        "load_s": load_s,
        "machine": machine(),
        "frames": recs,
        "msamples_per_s": total_samples as f64 / total_s / 1e6,
        "mrays_per_s": total_rays as f64 / total_s / 1e6,
        "seconds_per_frame": total_s / frames.len() as f64,
    });
    if a.json {
        println!("{}", serde_json::to_string_pretty(&doc)?);
    } else {
        println!(
            "path tracing {} at {w}x{h}, {} spp, max depth {}, {} thread(s); {}",
            input.source, a.spp, a.max_depth, a.threads, doc["machine"]
        );
        for r in &recs {
            println!(
                "  frame {:>4}: {:.3} s render (median), {:.3} M samples/s, {:.2} M rays/s (frame build {:.3} s)",
                r["frame"],
                r["render_s_median"].as_f64().unwrap_or(f64::NAN),
                r["msamples_per_s"].as_f64().unwrap_or(f64::NAN),
                r["mrays_per_s"].as_f64().unwrap_or(f64::NAN),
                r["build_s"].as_f64().unwrap_or(f64::NAN),
            );
        }
        println!(
            "  all: {:.3} s/frame, {:.3} M samples/s, {:.2} M rays/s",
            doc["seconds_per_frame"].as_f64().unwrap_or(f64::NAN),
            doc["msamples_per_s"].as_f64().unwrap_or(f64::NAN),
            doc["mrays_per_s"].as_f64().unwrap_or(f64::NAN),
        );
    }
    Ok(())
}
