//! glTF loader tests against the shared development scenes and crafted bad inputs.

use chronolux_io::gltf::load;
use std::path::PathBuf;

fn scene(name: &str) -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/"
    ))
    .join(name)
}

#[test]
fn print_all() {
    for f in [
        "AnimatedMorphCube.glb",
        "AnimatedTriangle.gltf",
        "BoxAnimated.glb",
        "Cameras.gltf",
        "CornellBox.glb",
        "EmissiveStrengthTest.glb",
        "InterpolationTest.glb",
        "LightsPunctualLamp/LightsPunctualLamp.gltf",
        "RiggedSimple.glb",
        "SimpleMorph.gltf",
        "SimpleSkin.gltf",
        "TransmissionTest.glb",
    ] {
        let t = std::time::Instant::now();
        let d = load(&scene(f)).unwrap_or_else(|e| panic!("{e}"));
        println!(
            "{f}: {} nodes {} roots {} meshes {} mats {} tex {} lights {} cams {} skins {} anims tris {} env {:?} {:.2}s\n   warnings {:?}",
            d.nodes.len(),
            d.roots.len(),
            d.meshes.len(),
            d.materials.len(),
            d.textures.len(),
            d.lights.len(),
            d.cameras.len(),
            d.skins.len(),
            d.animations.len(),
            d.instanced_triangle_count(),
            d.environment,
            t.elapsed().as_secs_f32(),
            d.warnings
        );
    }
}
