//! Loading the scene a command names (or the built-in demo), with the stage applied.

use crate::cli::SceneArgs;
use anyhow::{Context, Result, bail};
use chronolux_core::scene::desc::{AnimationId, SceneDesc};
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
        Some(path) => (chronolux_io::gltf::load(path)?, path.display().to_string()),
        None => (stage::demo(), "built-in demo".to_string()),
    };
    if let Some(s) = &args.stage {
        match s.as_str() {
            "cornell" => desc = stage::cornell_stage(desc),
            other => bail!("unknown stage '{other}' (available: cornell)"),
        }
    }
    for w in &desc.warnings {
        log::warn!("{w}");
        eprintln!("warning: {w}");
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
        Some(n) => CameraChoice::Named(n.clone()),
        None => CameraChoice::First,
    };
    Ok(SceneInput {
        desc,
        animation,
        camera,
        source,
    })
}
