//! `FrameDelta` on the shared glTF scenes (chronolux-core's own tests cannot load glTF):
//! a skinned mesh is deformed, a morphed one too, a rigid animation moves its instances
//! without deforming them, and the static room around them never changes.

use chronolux_core::scene::delta::{FrameDelta, dynamic_instances};
use chronolux_core::scene::desc::{AnimationId, SceneDesc};
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder, FrameScene};
use chronolux_core::scene::stage;
use std::path::PathBuf;
use std::sync::Arc;

fn shared(name: &str) -> SceneDesc {
    let path = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/"
    ))
    .join(name);
    stage::cornell_stage(chronolux_io::gltf::load(&path).unwrap())
}

/// Frames at `times` (s) of the first clip.
fn frames(desc: &SceneDesc, times: &[f32]) -> Vec<FrameScene> {
    let mut b = FrameBuilder::new(
        Arc::new(desc.clone()),
        Some(AnimationId(0)),
        CameraChoice::First,
        16,
        16,
    )
    .unwrap();
    times.iter().map(|&t| b.build(t)).collect()
}

/// Instances carrying a geometry whose node satisfies `pred`.
fn instances_where(
    scene: &FrameScene,
    desc: &SceneDesc,
    pred: impl Fn(&chronolux_core::scene::desc::Node) -> bool,
) -> Vec<usize> {
    let mut v: Vec<usize> = scene
        .geometry
        .iter()
        .enumerate()
        .filter(|(_, g)| pred(&desc.nodes[g.node.index()]))
        .map(|(g, _)| scene.geometry_instance[g] as usize)
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
fn shared_scenes_report_deformation_and_motion() {
    for (name, deforms) in [
        ("RiggedSimple.glb", true),
        ("AnimatedMorphCube.glb", true),
        ("BoxAnimated.glb", false),
    ] {
        let desc = shared(name);
        let fr = frames(&desc, &[0.0, 0.3, 0.6]);
        let d = FrameDelta::between(&fr[0], &fr[1]);
        let room = instances_where(&fr[0], &desc, |n| n.name == "ceiling_light");
        assert_eq!(room.len(), 1);
        assert!(!d.instance_changed(room[0]), "{name}: the room is static");
        assert!(!d.camera_changed(), "{name}: the stage camera is static");
        let changed: Vec<usize> = (0..d.instance_count())
            .filter(|&i| d.instance_changed(i))
            .collect();
        assert!(!changed.is_empty(), "{name}: something changes");
        if deforms {
            assert!(changed.iter().any(|&i| d.instance_deformed(i)), "{name}");
            // Deformed geometry lives in world space: its instance never moves.
            for i in instances_where(&fr[0], &desc, |n| n.skin.is_some()) {
                assert!(d.instance_deformed(i) && !d.instance_moved(i), "{name}");
            }
        } else {
            assert!(changed.iter().all(|&i| d.instance_moved(i)), "{name}");
            assert!(
                (0..d.instance_count()).all(|i| !d.instance_deformed(i)),
                "{name}: rigid motion deforms nothing"
            );
        }
        // The segment's dynamic set: the union of the pairwise changes.
        let refs: Vec<&FrameScene> = fr.iter().collect();
        let mut union = FrameDelta::between(&fr[0], &fr[1]).dynamic_instances();
        for (u, c) in union
            .iter_mut()
            .zip(FrameDelta::between(&fr[1], &fr[2]).dynamic_instances())
        {
            *u |= c;
        }
        assert_eq!(dynamic_instances(&refs), union, "{name}");
        // Built twice at one time: identical, though deformed data was rebuilt.
        let again = frames(&desc, &[0.3]);
        assert!(FrameDelta::between(&fr[1], &again[0]).is_static(), "{name}");
    }
}

/// RiggedSimple's clip turns only its second bone: the 30 of its 188 triangles whose
/// vertices are weighted to the root bone alone (counted from the file's JOINTS_0 and
/// WEIGHTS_0) are the same surface in every frame, though the mesh deforms; the others
/// change.
#[test]
fn rigged_simple_keeps_the_triangles_of_its_still_bone() {
    let desc = shared("RiggedSimple.glb");
    let fr = frames(&desc, &[0.0, 0.3]);
    let d = FrameDelta::between(&fr[0], &fr[1]);
    let g = fr[0]
        .geometry
        .iter()
        .position(|g| desc.nodes[g.node.index()].skin.is_some())
        .expect("a skinned geometry") as u32;
    assert!(d.geometry_changed(&fr[0], g));
    let n = fr[0].geometry[g as usize].indices.len() as u32;
    let still = (0..n)
        .filter(|&triangle| {
            let tri = chronolux_core::accel::TriRef {
                geometry: g,
                triangle,
            };
            !d.triangle_changed(&fr[0], &fr[1], tri)
        })
        .count();
    assert_eq!((still, n), (30, 188));
}
