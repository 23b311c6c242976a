//! Loading the scene a command names (or the built-in demo), with the stage applied.

use crate::args::SceneArgs;
use anyhow::{Context, Result, bail};
use chronolux_core::scene::desc::{AnimationId, CameraDesc, SceneDesc};
use chronolux_core::scene::frame::CameraChoice;
use chronolux_core::scene::stage;

/// A loaded scene and the user's choices about it.
pub struct SceneInput {
    pub desc: SceneDesc,
    pub animation: Option<AnimationId>,
    pub camera: CameraChoice,
    /// Where it came from (path or "built-in demo").
    pub source: String,
}

pub fn load(args: &SceneArgs) -> Result<SceneInput> {
    let (mut desc, source) = match &args.scene {
        Some(path) => match builtin_name(path) {
            Some(name) => (
                stage::builtin(name).with_context(|| {
                    format!(
                        "no built-in scene '{name}' (available: {})",
                        stage::BUILTIN_SCENES
                            .map(|n| format!("builtin:{n}"))
                            .join(", ")
                    )
                })?,
                format!("built-in {name}"),
            ),
            None => (chronolux_io::gltf::load(path)?, path.display().to_string()),
        },
        None => (stage::demo(), "built-in demo".to_string()),
    };
    if let Some(s) = &args.stage {
        match s.as_str() {
            "cornell" => desc = stage::cornell_stage(desc),
            other => bail!("unknown stage '{other}' (available: cornell)"),
        }
    }
    // Unnamed cameras get `cameraN` (N: their glTF index) so that `--camera` can name them
    // and `info` can list them.
    for (i, c) in desc.cameras.iter_mut().enumerate() {
        if c.name.trim().is_empty() {
            c.name = format!("camera{i}");
        }
    }
    // Each distinct warning once (a file can trigger the same one per primitive or
    // channel), with how often it occurred; `info --json` gets the same list.
    let mut counts: Vec<(String, usize)> = Vec::new();
    let mut index: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    for w in desc.warnings.drain(..) {
        match index.get(&w) {
            Some(&i) => counts[i].1 += 1,
            None => {
                index.insert(w.clone(), counts.len());
                counts.push((w, 1));
            }
        }
    }
    desc.warnings = counts
        .into_iter()
        .map(|(w, n)| if n > 1 { format!("{w} (×{n})") } else { w })
        .collect();
    for w in &desc.warnings {
        log::warn!("{w}");
    }
    let animation = match &args.animation {
        Some(key) => Some(desc.find_animation(key).with_context(|| {
            let names: Vec<String> = desc
                .animations
                .iter()
                .enumerate()
                .map(|(i, a)| format!("{i}:{}", a.name))
                .collect();
            format!(
                "no animation '{key}' in {source} (clips: {})",
                if names.is_empty() {
                    "none".into()
                } else {
                    names.join(", ")
                }
            )
        })?),
        None => (!desc.animations.is_empty()).then_some(AnimationId(0)),
    };
    let camera = match &args.camera {
        Some(key) => resolve_camera(&mut desc, key, &source)?,
        None => CameraChoice::First,
    };
    Ok(SceneInput {
        desc,
        animation,
        camera,
        source,
    })
}

/// `builtin:NAME` names a built-in scene ([`stage::builtin`]) instead of a file.
fn builtin_name(path: &std::path::Path) -> Option<&str> {
    path.to_str()?.strip_prefix("builtin:")
}

/// Cameras placed in the scene by a node, as (camera index, node name), in glTF order.
fn placed_cameras(desc: &SceneDesc) -> Vec<(usize, &str)> {
    desc.nodes
        .iter()
        .filter_map(|n| n.camera.map(|c| (c.index(), n.name.as_str())))
        .collect()
}

/// `--camera KEY`: a camera name, a camera node name, or a camera index.
fn resolve_camera(desc: &mut SceneDesc, key: &str, source: &str) -> Result<CameraChoice> {
    let placed = placed_cameras(desc);
    let by_name = placed
        .iter()
        .any(|&(c, node)| desc.cameras[c].name == key || (!node.is_empty() && node == key));
    if by_name {
        return Ok(CameraChoice::Named(key.to_string()));
    }
    if let Ok(i) = key.parse::<usize>()
        && placed.iter().any(|&(c, _)| c == i)
    {
        // Make the name unique, so that choosing by name picks exactly this camera.
        let name = desc.cameras[i].name.clone();
        let clashes = desc.cameras.iter().filter(|c| c.name == name).count() > 1
            || desc.nodes.iter().any(|n| n.name == name);
        if clashes {
            desc.cameras[i].name = format!("camera{i}");
        }
        return Ok(CameraChoice::Named(desc.cameras[i].name.clone()));
    }
    let names: Vec<String> = placed
        .iter()
        .map(|&(c, node)| {
            if node.is_empty() || node == desc.cameras[c].name {
                format!("{c}:{}", desc.cameras[c].name)
            } else {
                format!("{c}:{} (node {node})", desc.cameras[c].name)
            }
        })
        .collect();
    bail!(
        "no camera '{key}' in {source} (cameras: {})",
        if names.is_empty() {
            "none; the view is framed automatically".into()
        } else {
            names.join(", ")
        }
    )
}

/// The camera a choice designates (`None`: automatic framing).
pub fn chosen_camera<'a>(desc: &'a SceneDesc, choice: &CameraChoice) -> Option<&'a CameraDesc> {
    let order = desc.topological_order();
    let mut placed = order.into_iter().filter_map(|n| {
        let node = &desc.nodes[n.index()];
        node.camera
            .map(|c| (node.name.as_str(), &desc.cameras[c.index()]))
    });
    match choice {
        CameraChoice::First => placed.next().map(|(_, c)| c),
        CameraChoice::Named(key) => placed
            .find(|(node, c)| c.name == *key || node == key)
            .map(|(_, c)| c),
    }
}
