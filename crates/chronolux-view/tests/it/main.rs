//! Integration tests of the live viewer (one binary for the crate).

mod engine;
mod server;

use chronolux_core::scene::desc::{AnimationId, SceneDesc};
use chronolux_core::scene::frame::{CameraChoice, FrameScene};
use chronolux_core::scene::stage;
use chronolux_view::{EditableScene, ViewOptions};
use std::time::Duration;

/// Small enough for a test: 32×32 pixels, 4000 photons, a few samples.
pub fn small_options() -> ViewOptions {
    ViewOptions {
        photons: 4000,
        max_spp: 4,
        slice: Duration::from_millis(20),
    }
}

/// The built-in demo (a Cornell box with a sliding cube, a metal and a glass sphere).
pub fn demo() -> (EditableScene, FrameScene) {
    EditableScene::new(
        stage::demo(),
        Some(AnimationId(0)),
        CameraChoice::First,
        32,
        32,
    )
    .expect("the demo builds")
}

pub fn node(desc: &SceneDesc, name: &str) -> u32 {
    desc.nodes
        .iter()
        .position(|n| n.name == name)
        .unwrap_or_else(|| panic!("the demo has a node {name}")) as u32
}
