//! What `chronolux info` and the first frame of `render` run on a file: the glTF/GLB
//! loader, then the frame builder at the start, middle and end of the first clip.
//! External URIs resolve in `../shared/scenes` (the seed corpus's own folder), so the
//! `.gltf` seeds with `.bin` files load as they do for a user.
#![no_main]

use chronolux_core::scene::desc::AnimationId;
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
use libfuzzer_sys::fuzz_target;
use std::path::Path;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let base = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/scenes"));
    let Ok(desc) = chronolux_io::gltf::load_slice(data, Some(base), "fuzz.gltf") else {
        return;
    };
    let anim = (!desc.animations.is_empty()).then_some(AnimationId(0));
    let duration = anim.map_or(0.0, |a| desc.animations[a.index()].duration());
    if let Ok(mut b) = FrameBuilder::new(Arc::new(desc), anim, CameraChoice::First, 8, 8) {
        for t in [0.0, 0.5 * duration, duration] {
            let _ = b.build(t);
        }
    }
});
