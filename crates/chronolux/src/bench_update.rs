//! `chronolux bench update`: time to a clean image after a change, for selective photon
//! tracing (`spt`) in priority order, in random order (the paper's baseline) and
//! recomputed from scratch.
//!
//! A pool of `Z` photons is shot in configuration A (not timed); the scene then changes
//! to configuration B and each order updates the pool, in steps of a growing photon
//! budget, until its queue is empty. After every step the **error** of the displayed
//! indirect solution (indirect + caustic element irradiance, Gaussian-filtered as
//! `spt`/`dept-spatial` filter it, luminance) against a converged solution of B is
//! measured: `Σ_s A_s |E_s − E*_s| / Σ_s A_s E*_s` over element sides (A_s: area), where
//! `E*` comes from an independent pool of `ref_factor · Z` photons (another seed) on the
//! same elements. The **steady-state level** is the error of a fresh pool of the same `Z`
//! photons shot in B (what every order converges to: `spt` ends exactly there); an
//! order is done when its error is back under `(1 + margin) ·` that level (default
//! margin 5 %). `speedup_vs_random` and `speedup_vs_scratch` are ratios of the process
//! CPU seconds (user + system, `/proc/self/stat`) spent in the updates up to that point
//! (pilots and path scan included; the error measurements excluded), interpolated
//! linearly between steps.
//!
//! Changes (`--change`): `jump` (default): the animation's first pose (t = 0) → its last
//! key (for the demo, the block jumps from the left to the right of the room); `occluder`:
//! a white block (0.5 × 0.1 × 0.5) appears 0.45 below the stage's ceiling light (it waits
//! under the floor in A); `light`: the stage's ceiling light moves 0.3 along x. The
//! occluder and the moved light are built as movable nodes in both configurations
//! ([`FrameBuilder::with_movable`]: their own instances, not the static geometry), so A
//! and B have the same instances and elements and [`FrameDelta`] reports only them.

use crate::args::SceneArgs;
use crate::scene_input;
use anyhow::{Context, Result, bail};
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::math::Vec3;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::desc::{AnimationId, Material, MaterialId, SceneDesc, Trs};
use chronolux_core::scene::frame::{FrameBuilder, FrameScene};
use chronolux_core::scene::stage::{ROOM_HALF, cube_primitive};
use chronolux_render::framework::run::cpu_seconds;
use chronolux_render::kernels::elements::element_map::{
    ElementAccumulators, ElementMesh, FrameElements,
};
use chronolux_render::kernels::elements::reconstruct::{Filter, Neighbours, filter_with};
use chronolux_render::registry;
use chronolux_render::techniques::spt::pool::{Budget, SptState};
use chronolux_render::techniques::spt::{Order, SptSettings};
use clap::Args;
use serde_json::{Value, json};
use std::sync::Arc;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct UpdateArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The change: `jump` (first pose → last key of the animation; the demo's block jumps
    /// across the room), `occluder` (a block appears under the stage's ceiling light) or
    /// `light` (the stage's ceiling light moves 0.3 along x).
    #[arg(long, default_value = "jump", value_parser = ["jump", "occluder", "light"])]
    pub change: String,
    /// Photons in the pool (`spt`'s `photons`).
    #[arg(long, default_value_t = 300_000, value_name = "Z")]
    pub photons: u64,
    /// Reference pool size in multiples of Z (independent seed).
    #[arg(long, default_value_t = 8, value_name = "K")]
    pub ref_factor: u64,
    /// Relative margin over the steady-state error that counts as clean again.
    #[arg(long, default_value_t = 0.05, value_name = "M")]
    pub margin: f64,
    /// Any other `spt` setting, KEY=VALUE (repeatable), e.g. `--set scan_paths=false
    /// --set reshoot=group` for the paper's pilots-only detection.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Worker threads.
    #[arg(long, default_value_t = 2, value_name = "N")]
    pub threads: usize,
    /// Print one JSON document instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Configurations A and B of `change` at the camera and animation of `input`.
fn configurations(
    input: &scene_input::SceneInput,
    change: &str,
) -> Result<(FrameScene, FrameScene, String)> {
    // Nodes named in `movable` are their own instances in both configurations (a node
    // the clip leaves still would otherwise join the static geometry, and the change
    // would read as a change of everything).
    let build = |desc: SceneDesc, t: f32, movable: &[&str]| -> Result<FrameScene> {
        let anim =
            (!desc.animations.is_empty()).then_some(input.animation.unwrap_or(AnimationId(0)));
        let mask: Vec<bool> = desc
            .nodes
            .iter()
            .map(|n| movable.contains(&n.name.as_str()))
            .collect();
        let mut b =
            FrameBuilder::with_movable(Arc::new(desc), anim, input.camera.clone(), 64, 64, &mask)?;
        Ok(b.build(t))
    };
    match change {
        "jump" => {
            let Some(id) = input.animation else {
                bail!(
                    "--change jump needs an animated scene (it jumps from the first pose to the last key)"
                );
            };
            let t1 = input.desc.animations[id.0 as usize].duration();
            if t1 <= 0.0 {
                bail!("--change jump: the animation has no extent");
            }
            Ok((
                build(input.desc.clone(), 0.0, &[])?,
                build(input.desc.clone(), t1, &[])?,
                format!("first pose (t = 0) → last key (t = {t1} s)"),
            ))
        }
        "occluder" => {
            let with = |y: f32| {
                let mut d = input.desc.clone();
                d.materials
                    .push(Material::diffuse("bench_occluder", Rgb::splat(0.73)));
                let m = MaterialId(d.materials.len() as u32 - 1);
                d.add_mesh(
                    "bench_occluder",
                    cube_primitive(0.25 * ROOM_HALF),
                    m,
                    Trs {
                        translation: Vec3::new(0.0, y, 0.0),
                        scale: Vec3::new(1.0, 0.2, 1.0),
                        ..Default::default()
                    },
                );
                d
            };
            Ok((
                build(with(-0.5 * ROOM_HALF), 0.0, &["bench_occluder"])?,
                build(with(1.45 * ROOM_HALF), 0.0, &["bench_occluder"])?,
                "a 0.5 × 0.1 × 0.5 block appears 0.45 below the ceiling light".into(),
            ))
        }
        "light" => {
            let with = |dx: f32| -> Result<SceneDesc> {
                let mut d = input.desc.clone();
                let n = d
                    .nodes
                    .iter()
                    .position(|n| n.name == "ceiling_light")
                    .context("--change light needs the stage's `ceiling_light` (the demo, or --stage cornell)")?;
                d.nodes[n].transform.translation.x += dx;
                Ok(d)
            };
            Ok((
                build(with(0.0)?, 0.0, &["ceiling_light"])?,
                build(with(0.3 * ROOM_HALF)?, 0.0, &["ceiling_light"])?,
                "the ceiling light moves 0.3 along x".into(),
            ))
        }
        other => bail!("unknown change '{other}'"),
    }
}

/// The error measure of the module doc.
struct ErrorMeasure {
    fe: FrameElements,
    nb: Neighbours,
    inv2s2: f32,
    reference: Vec<f32>,
}

impl ErrorMeasure {
    fn displayed(&self, ind: &ElementAccumulators, cau: &ElementAccumulators) -> Vec<f32> {
        let w = |_: usize, _: usize, d2: f32| (-d2 * self.inv2s2).exp();
        let a = filter_with(ind, &self.fe, &self.nb, w);
        let b = filter_with(cau, &self.fe, &self.nb, w);
        a.iter().zip(&b).map(|(x, y)| luminance(*x + *y)).collect()
    }

    fn of_state(&self, st: &SptState) -> f64 {
        let (_, ind, cau) = st.accumulators();
        self.error(&self.displayed(&ind, &cau))
    }

    fn error(&self, e: &[f32]) -> f64 {
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (s, (&x, &r)) in e.iter().zip(&self.reference).enumerate() {
            let a = self.fe.area[s / 2] as f64;
            num += a * (x as f64 - r as f64).abs();
            den += a * r as f64;
        }
        num / den.max(1e-30)
    }
}

/// One point of an error curve.
#[derive(Clone, Copy, Debug, serde::Serialize)]
struct Point {
    photons: u64,
    cpu_s: f64,
    wall_s: f64,
    error: f64,
}

/// First (interpolated) CPU seconds and photons at which `curve` gets under `threshold`.
fn crossing(curve: &[Point], threshold: f64) -> Option<(f64, f64)> {
    let k = curve.iter().position(|p| p.error <= threshold)?;
    if k == 0 {
        return Some((curve[0].cpu_s, curve[0].photons as f64));
    }
    let (a, b) = (curve[k - 1], curve[k]);
    let f = ((a.error - threshold) / (a.error - b.error)).clamp(0.0, 1.0);
    Some((
        a.cpu_s + f * (b.cpu_s - a.cpu_s),
        a.photons as f64 + f * (b.photons as f64 - a.photons as f64),
    ))
}

pub fn run(a: UpdateArgs) -> Result<()> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.max(1))
        .build()
        .context("cannot set up the thread pool")?;
    pool.install(|| run_in_pool(a))
}

fn run_in_pool(a: UpdateArgs) -> Result<()> {
    let input = scene_input::load(&a.scene)?;
    let (sa, sb, what) = configurations(&input, &a.change)?;
    let (sa, sb) = (Arc::new(sa), Arc::new(sb));
    let (settings_json, base) = spt_settings(&a)?;
    let mesh = ElementMesh::build(&sa, base.elements_per_diagonal());
    if !mesh.matches(&sb) || sa.lights.len() != sb.lights.len() {
        bail!("the change alters the scene's topology; spt cannot update across it");
    }
    let changes = FrameDelta::between(&sa, &sb);
    let radius = match base.filter {
        Filter::Gaussian { radius } => radius,
        _ => 2.5,
    };
    let fe = FrameElements::new(&sb, &mesh);
    let r = radius * mesh.element_size;
    let mut m = ErrorMeasure {
        nb: Neighbours::new(&fe, r),
        fe,
        inv2s2: 1.0 / (2.0 * (0.5 * r) * (0.5 * r)),
        reference: Vec::new(),
    };
    let t_ref = Instant::now();
    let refst = SptState::new_on_mesh(
        sb.clone(),
        SptSettings {
            photons: a.photons * a.ref_factor.max(1),
            common: chronolux_render::registry::CommonSettings {
                seed: base.common.seed.wrapping_add(0x5eed),
                ..base.common
            },
            ..base.clone()
        },
        mesh.clone(),
    );
    let (_, ri, rc) = refst.accumulators();
    m.reference = m.displayed(&ri, &rc);
    drop(refst);
    let fresh = SptState::new_on_mesh(sb.clone(), base.clone(), mesh.clone());
    let steady = m.of_state(&fresh);
    let z = fresh.layout.photons();
    let groups = fresh.layout.groups;
    drop(fresh);
    let threshold = steady * (1.0 + a.margin);
    log::info!(
        "reference and steady state in {:.1} s",
        t_ref.elapsed().as_secs_f64()
    );
    let mut results = serde_json::Map::new();
    let mut to_threshold = std::collections::BTreeMap::new();
    for (name, order) in [
        ("priority", Order::Priority),
        ("random", Order::Random),
        ("scratch", Order::Scratch),
    ] {
        let (rec, cross) = measure_order(
            &m,
            (&sa, &sb),
            &changes,
            SptSettings {
                order,
                ..base.clone()
            },
            &mesh,
            (z, threshold),
        );
        to_threshold.insert(name, cross);
        results.insert(name.into(), rec);
    }
    let ratio = |x: &str, y: &str, k: usize| -> Value {
        match (to_threshold[x], to_threshold[y]) {
            (Some(p), Some(q)) => {
                let (p, q) = if k == 0 { (p.0, q.0) } else { (p.1, q.1) };
                if p > 0.0 { json!(q / p) } else { Value::Null }
            }
            _ => Value::Null,
        }
    };
    let out = json!({
        "scene": input.source,
        "change": a.change,
        "what": what,
        "pool_photons": z,
        "groups": groups,
        "settings": settings_json,
        "reference_photons": a.photons * a.ref_factor.max(1),
        "steady_state_error": steady,
        "margin": a.margin,
        "threshold": threshold,
        "threads": a.threads,
        "speedup_vs_random": ratio("priority", "random", 0),
        "speedup_vs_scratch": ratio("priority", "scratch", 0),
        "photon_ratio_vs_random": ratio("priority", "random", 1),
        "photon_ratio_vs_scratch": ratio("priority", "scratch", 1),
        "orders": results,
    });
    if a.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_text(&out, &input.source, &what, z, groups, steady, threshold);
    }
    Ok(())
}

/// spt's settings for the bench (`--photons`, then every `--set`), as JSON and typed.
fn spt_settings(a: &UpdateArgs) -> Result<(Value, SptSettings)> {
    let tech = registry::find("spt").map_err(anyhow::Error::msg)?;
    let mut sets: Vec<(String, Value)> = vec![("photons".into(), Value::from(a.photons))];
    for s in &a.sets {
        let (k, v) = s
            .split_once('=')
            .with_context(|| format!("--set takes KEY=VALUE, not '{s}'"))?;
        sets.push((k.into(), registry::parse_value(v)));
    }
    let settings_json = registry::resolve(tech, None, &sets).map_err(anyhow::Error::msg)?;
    let base: SptSettings = serde_json::from_value(settings_json.clone())?;
    Ok((settings_json, base))
}

/// One update order: the state converged on `sa`, invalidated by the change to `sb`, then
/// drained in growing steps while the error is measured. Returns its record and where it
/// first falls below `threshold` (CPU s, photons). `(z, threshold)`: the pool's photons
/// and the clean threshold.
fn measure_order(
    m: &ErrorMeasure,
    (sa, sb): (&Arc<FrameScene>, &Arc<FrameScene>),
    changes: &FrameDelta,
    s: SptSettings,
    mesh: &ElementMesh,
    (z, threshold): (u64, f64),
) -> (Value, Option<(f64, f64)>) {
    let mut st = SptState::new_on_mesh(sa.clone(), s, mesh.clone());
    let before = m.of_state(&st);
    let (c0, w0) = (cpu_seconds().unwrap_or(f64::NAN), Instant::now());
    let inv = st.invalidate(sb.clone(), changes);
    let (mut cpu, mut wall) = (
        cpu_seconds().unwrap_or(f64::NAN) - c0,
        w0.elapsed().as_secs_f64(),
    );
    let mut photons = inv.photons_traced;
    let mut curve = vec![Point {
        photons,
        cpu_s: cpu,
        wall_s: wall,
        error: m.of_state(&st),
    }];
    let mut step = (z / 1000).max(1);
    while st.queue_len() > 0 {
        let (c0, w0) = (cpu_seconds().unwrap_or(f64::NAN), Instant::now());
        let d = st.drain(Budget {
            photons: step,
            time: None,
        });
        cpu += cpu_seconds().unwrap_or(f64::NAN) - c0;
        wall += w0.elapsed().as_secs_f64();
        photons += d.photons_traced;
        if d.groups_reshot == 0 {
            // A group larger than the step: widen it.
            step *= 2;
            continue;
        }
        curve.push(Point {
            photons,
            cpu_s: cpu,
            wall_s: wall,
            error: m.of_state(&st),
        });
        step = (step as f64 * 1.3).ceil() as u64;
    }
    let cross = crossing(&curve, threshold);
    let rec = json!({
        "error_before_change": before,
        "groups_invalidated": inv.groups_invalidated,
        "groups_by_pilots": inv.groups_by_pilots,
        "groups_by_scan": inv.groups_by_scan,
        "pilots_traced": inv.pilots_traced,
        "photons_total": photons,
        "cpu_s_total": cpu,
        "wall_s_total": wall,
        "final_error": curve.last().map(|p| p.error),
        "cpu_s_to_clean": cross.map(|c| c.0),
        "photons_to_clean": cross.map(|c| c.1),
        "curve": curve,
    });
    (rec, cross)
}

/// The text report of `run_in_pool`'s JSON document.
fn print_text(
    out: &Value,
    source: &str,
    what: &str,
    z: u64,
    groups: u64,
    steady: f64,
    threshold: f64,
) {
    println!(
        "bench update: {} — {} ({} photons in {} groups)",
        source, what, z, groups
    );
    println!(
        "steady-state error {:.4}, clean below {:.4}",
        steady, threshold
    );
    for name in ["priority", "random", "scratch"] {
        let r = &out["orders"][name];
        println!(
            "  {name:9} invalidated {:>6} groups; clean after {} CPU s / {} photons; total {:.3} CPU s, {} photons, final error {:.4}",
            r["groups_invalidated"],
            r["cpu_s_to_clean"],
            r["photons_to_clean"],
            r["cpu_s_total"].as_f64().unwrap_or(f64::NAN),
            r["photons_total"],
            r["final_error"].as_f64().unwrap_or(f64::NAN)
        );
    }
    println!(
        "speedup_vs_random {}, speedup_vs_scratch {}",
        out["speedup_vs_random"], out["speedup_vs_scratch"]
    );
}
