//! The render loop's state: edits reach the image at once, the queue drains to 0, and the
//! drained pool is the one a fresh pool of the edited scene would be.

use crate::{demo, node, small_options};
use chronolux_core::scene::desc::{ChannelTarget, SceneDesc};
use chronolux_core::scene::stage;
use chronolux_view::{Edit, Viewer};

fn moved_sphere(desc: &SceneDesc) -> Edit {
    Edit::Node {
        node: node(desc, "metal_sphere"),
        translate: [0.3, 0.0, 0.0],
        rotate: [0.0, 0.0, 0.0],
    }
}

/// Steps until nothing is queued; every step re-shoots at least one group (a time
/// slice always takes its first batch), so the group count bounds the steps.
fn drain(v: &mut Viewer) -> usize {
    let bound = v.queued() + 1;
    let mut steps = 0;
    while v.queued() > 0 {
        v.step()
            .expect("a step while groups are queued gives an image");
        steps += 1;
        assert!(steps <= bound, "the queue did not shrink");
    }
    steps
}

#[test]
fn moving_a_node_changes_the_image_at_once_and_the_queue_drains_to_zero() {
    let (scene, frame) = demo();
    let edit = moved_sphere(&stage::demo());
    let mut v = Viewer::from_scene(scene, frame, small_options());
    let before = v.frame_after_pass();
    assert_eq!(before.status.queued, 0, "a fresh pool has nothing queued");
    let (after, errors) = v.edit(&[(1, edit)]);
    assert!(errors.is_empty(), "{errors:?}");
    assert_eq!(after.status.edit, 1);
    assert!(
        after.status.queued > 0 && after.status.invalidated > 0,
        "photons hit the sphere, so moving it must queue their groups: {:?}",
        after.status
    );
    assert_ne!(
        before.rgb8, after.rgb8,
        "the first image after the move (direct light) already differs"
    );
    drain(&mut v);
    let f = v.frame();
    assert_eq!(f.status.queued, 0);
    assert!(f.status.settled_after.is_some());
    assert_ne!(before.rgb8, f.rgb8);
}

#[test]
fn the_drained_pool_renders_as_a_fresh_pool_of_the_edited_scene() {
    let edit = moved_sphere(&stage::demo());
    let (scene, frame) = demo();
    let mut updated = Viewer::from_scene(scene, frame, small_options());
    updated.frame_after_pass();
    updated.edit(&[(1, edit.clone())]);
    drain(&mut updated);
    let (mut scene, _) = demo();
    scene.apply(&edit).unwrap();
    let frame = scene.build().unwrap();
    let mut fresh = Viewer::from_scene(scene, frame, small_options());
    fresh.frame_after_pass();
    // Both images are the first sample per pixel (same sample stream) over pools that
    // hold the same photon paths; the sums differ only in the order of the signed f64
    // deposits, i.e. by rounding, which f32 pixels show at most in the last few bits.
    let (a, b) = (updated.linear(), fresh.linear());
    let mut worst = 0.0f32;
    for (x, y) in a.iter().zip(&b) {
        let d = (*x - *y).abs().max_element() / x.max_element().max(y.max_element()).max(1e-3);
        worst = worst.max(d);
    }
    assert!(worst < 1e-3, "largest relative pixel difference {worst}");
}

#[test]
fn the_timeline_edit_moves_the_animation_and_settles() {
    let (scene, frame) = demo();
    let duration = scene.duration;
    assert!(duration > 0.0);
    let mut v = Viewer::from_scene(scene, frame, small_options());
    let before = v.frame_after_pass();
    let (after, _) = v.edit(&[(3, Edit::Time { t: 1e6 })]);
    assert_eq!(after.status.t, duration, "time is clamped to the clip");
    assert!(after.status.queued > 0, "the cube slid across the room");
    assert_ne!(before.rgb8, after.rgb8);
    drain(&mut v);
    assert_eq!(v.frame().status.queued, 0);
}

#[test]
fn light_and_material_edits_change_the_image() {
    let desc = stage::demo();
    let light = node(&desc, "ceiling_light");
    let white = desc
        .materials
        .iter()
        .position(|m| m.name == "white")
        .expect("the demo has a white material") as u32;
    let (scene, frame) = demo();
    assert!(scene.is_light(light as usize));
    let mut v = Viewer::from_scene(scene, frame, small_options());
    v.frame_after_pass();
    let base = v.linear();
    let (_, e) = v.edit(&[(
        1,
        Edit::Light {
            node: light,
            intensity: 2.0,
        },
    )]);
    assert!(e.is_empty(), "{e:?}");
    drain(&mut v);
    // Twice the emission: every pixel lit only through the light doubles; the image mean
    // grows (the light itself is shown twice as bright too).
    let brighter = mean(&v.linear());
    assert!(
        brighter > 1.5 * mean(&base),
        "{brighter} vs {}",
        mean(&base)
    );
    let (_, e) = v.edit(&[(
        2,
        Edit::Material {
            material: white,
            base_color: [0.0, 0.0, 0.0],
        },
    )]);
    assert!(e.is_empty(), "{e:?}");
    drain(&mut v);
    let black = mean(&v.linear());
    assert!(
        black < brighter,
        "black walls reflect less: {black} vs {brighter}"
    );
}

fn mean(p: &[chronolux_core::color::Rgb]) -> f32 {
    p.iter().map(|c| c.element_sum()).sum::<f32>() / p.len() as f32
}

#[test]
fn a_node_offset_holds_at_every_key_of_its_channels() {
    let desc = stage::demo();
    let cube = node(&desc, "sliding_cube");
    let (mut scene, _) = demo();
    scene
        .apply(&Edit::Node {
            node: cube,
            translate: [0.0, 0.25, 0.0],
            rotate: [0.0, 0.0, 0.0],
        })
        .unwrap();
    let edited = scene.desc();
    let c = cube as usize;
    assert_eq!(
        edited.nodes[c].transform.translation.y,
        desc.nodes[c].transform.translation.y + 0.25
    );
    let ch = |d: &SceneDesc| {
        d.animations[0]
            .channels
            .iter()
            .find(|ch| ch.node.index() == c && ch.target == ChannelTarget::Translation)
            .expect("the cube slides")
            .values
            .clone()
    };
    for (k, (a, b)) in ch(&desc).iter().zip(ch(&edited)).enumerate() {
        let expect = if k % 3 == 1 { a + 0.25 } else { *a };
        assert_eq!(b, expect, "key value {k}");
    }
}

#[test]
fn bad_edits_are_refused_with_a_reason() {
    let (mut scene, _) = demo();
    let desc = stage::demo();
    let n = desc.nodes.len() as u32;
    let floor = node(&desc, "floor");
    for (e, why) in [
        (
            Edit::Node {
                node: n,
                translate: [0.0; 3],
                rotate: [0.0; 3],
            },
            "no node",
        ),
        (
            Edit::Node {
                node: 0,
                translate: [f32::NAN, 0.0, 0.0],
                rotate: [0.0; 3],
            },
            "finite",
        ),
        (
            Edit::Node {
                node: 0,
                translate: [1e9, 0.0, 0.0],
                rotate: [0.0; 3],
            },
            "beyond",
        ),
        (
            Edit::Light {
                node: floor,
                intensity: 1.0,
            },
            "not a light",
        ),
        (
            Edit::Material {
                material: 0,
                base_color: [2.0, 0.0, 0.0],
            },
            "[0, 1]",
        ),
        (Edit::Time { t: f32::INFINITY }, "finite"),
    ] {
        let err = scene.apply(&e).expect_err(why);
        assert!(err.contains(why), "{err} should say {why}");
    }
}
