//! `chronolux info`: what a scene contains.

use crate::args::SceneArgs;
use crate::scene_input::{self, SceneInput};
use anyhow::Result;
use chronolux_core::scene::anim;
use chronolux_core::scene::desc::{ChannelTarget, Projection};
use clap::Args;
use serde::Serialize;

/// `chronolux info`: the scene and the output format.
#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
pub struct AnimationSummary {
    pub index: usize,
    pub name: String,
    pub duration_s: f32,
    pub channels: usize,
    /// Target paths animated, e.g. ["translation", "rotation"].
    pub targets: Vec<&'static str>,
}

#[derive(Serialize)]
pub struct SceneSummary {
    pub source: String,
    pub name: String,
    /// Triangles after node instancing.
    pub triangles: usize,
    pub meshes: usize,
    pub mesh_instances: usize,
    pub materials: usize,
    pub textures: usize,
    /// Punctual lights (KHR_lights_punctual).
    pub punctual_lights: usize,
    /// Materials with emission (their triangles are area lights).
    pub emissive_materials: usize,
    pub environment_light: bool,
    /// Camera names with their projection.
    pub cameras: Vec<String>,
    pub skins: usize,
    pub animations: Vec<AnimationSummary>,
    /// Nodes that change under the selected clip (derived from its channels).
    pub dynamic_nodes: Vec<String>,
    pub warnings: Vec<String>,
}

pub fn summarize(s: &SceneInput) -> SceneSummary {
    let d = &s.desc;
    let dynamic = anim::dynamic_nodes(d, s.animation);
    SceneSummary {
        source: s.source.clone(),
        name: d.name.clone(),
        triangles: d.instanced_triangle_count(),
        meshes: d.meshes.len(),
        mesh_instances: d.nodes.iter().filter(|n| n.mesh.is_some()).count(),
        materials: d.materials.len(),
        textures: d.textures.len(),
        punctual_lights: d.nodes.iter().filter(|n| n.light.is_some()).count(),
        emissive_materials: d
            .materials
            .iter()
            .filter(|m| m.emissive != glam::Vec3::ZERO)
            .count(),
        environment_light: d.environment.is_some(),
        cameras: d
            .cameras
            .iter()
            .map(|c| match c.projection {
                Projection::Perspective { yfov, .. } => {
                    format!("{} (perspective, yfov {:.1}°)", c.name, yfov.to_degrees())
                }
                Projection::Orthographic { xmag, ymag } => {
                    format!("{} (orthographic, {xmag}×{ymag})", c.name)
                }
            })
            .collect(),
        skins: d.skins.len(),
        animations: d
            .animations
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let mut targets: Vec<&'static str> = Vec::new();
                for c in &a.channels {
                    let t = match c.target {
                        ChannelTarget::Translation => "translation",
                        ChannelTarget::Rotation => "rotation",
                        ChannelTarget::Scale => "scale",
                        ChannelTarget::Weights => "weights",
                    };
                    if !targets.contains(&t) {
                        targets.push(t);
                    }
                }
                AnimationSummary {
                    index: i,
                    name: a.name.clone(),
                    duration_s: a.duration(),
                    channels: a.channels.len(),
                    targets,
                }
            })
            .collect(),
        dynamic_nodes: d
            .nodes
            .iter()
            .zip(&dynamic)
            .enumerate()
            .filter(|(_, (_, dy))| **dy)
            .map(|(i, (n, _))| {
                if n.name.is_empty() {
                    format!("#{i}")
                } else {
                    n.name.clone()
                }
            })
            .collect(),
        warnings: d.warnings.clone(),
    }
}

pub fn run(args: InfoArgs) -> Result<()> {
    let input = scene_input::load(&args.scene)?;
    let s = summarize(&input);
    if args.json {
        return print_stdout(&format!("{}\n", serde_json::to_string_pretty(&s)?));
    }
    let mut out = String::new();
    macro_rules! outln {
        ($($t:tt)*) => {{
            use std::fmt::Write as _;
            let _ = writeln!(out, $($t)*);
        }};
    }
    outln!("scene        {} ({})", s.name, s.source);
    outln!(
        "triangles    {} in {} mesh instances of {} meshes",
        s.triangles,
        s.mesh_instances,
        s.meshes
    );
    outln!(
        "materials    {} ({} emissive), {} textures",
        s.materials,
        s.emissive_materials,
        s.textures
    );
    outln!(
        "lights       {} punctual, {} emissive materials{}",
        s.punctual_lights,
        s.emissive_materials,
        if s.environment_light {
            ", default environment"
        } else {
            ""
        }
    );
    outln!(
        "cameras      {}",
        if s.cameras.is_empty() {
            "none (automatic framing)".into()
        } else {
            wrap_list(&s.cameras)
        }
    );
    outln!("skins        {}", s.skins);
    if s.animations.is_empty() {
        outln!("animations   none (static scene)");
    }
    for a in &s.animations {
        outln!(
            "animation    {}: '{}' {:.3} s, {} channels ({})",
            a.index,
            a.name,
            a.duration_s,
            a.channels,
            wrap_list(&a.targets)
        );
    }
    outln!(
        "dynamic      {}",
        if s.dynamic_nodes.is_empty() {
            "no nodes".into()
        } else {
            wrap_list(&s.dynamic_nodes)
        }
    );
    // Warnings went to stderr once, as the scene loaded (`scene_input::load`).
    print_stdout(&out)
}

/// Names shown per list before `info` summarises the rest (`--json` lists them all).
pub const LIST_SHOWN: usize = 12;
/// Text width `info` wraps lists at.
const WIDTH: usize = 100;
/// Width of the label column (`"dynamic      "`).
const LABEL: usize = 13;

/// `a, b, c` wrapped at [`WIDTH`] under the label column, at most [`LIST_SHOWN`] names,
/// then `… and N more (--json lists all)`.
fn wrap_list<T: AsRef<str>>(items: &[T]) -> String {
    let mut words: Vec<String> = items
        .iter()
        .take(LIST_SHOWN)
        .enumerate()
        .map(|(i, w)| {
            let w = w.as_ref();
            if i + 1 < items.len() {
                format!("{w},")
            } else {
                w.to_string()
            }
        })
        .collect();
    if items.len() > LIST_SHOWN {
        words.push(format!(
            "… and {} more ({} in all; --json lists them)",
            items.len() - LIST_SHOWN,
            items.len()
        ));
    }
    let mut out = String::new();
    let mut col = LABEL;
    for w in words {
        let len = w.chars().count();
        if col > LABEL && col + 1 + len > WIDTH {
            out.push('\n');
            out.push_str(&" ".repeat(LABEL));
            col = LABEL;
        } else if col > LABEL {
            out.push(' ');
            col += 1;
        }
        out.push_str(&w);
        col += len;
    }
    out
}

/// Writes to stdout; a closed pipe (`chronolux info x.glb | head`) is not an error.
fn print_stdout(text: &str) -> Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(anyhow::Error::new(e).context("cannot write to stdout"))
        }
        _ => Ok(()),
    }
}
