//! `FrameDelta`: what changed between two frames, exactly, on the built-in demo and
//! caustic scenes and on skinned and morphed meshes built in code (the shared glTF scenes
//! are checked in chronolux-render's tests, which can load glTF), plus segments and
//! light/material/camera changes made by modifying the scene description.

use chronolux_core::accel::TriRef;
use chronolux_core::color::Rgb;
use chronolux_core::math::{Mat4, Vec3, Vec4};
use chronolux_core::scene::delta::{FrameDelta, dynamic_instances};
use chronolux_core::scene::desc::{
    Animation, AnimationId, Channel, ChannelTarget, Interpolation, LightKind, Material, MaterialId,
    Mesh, MeshId, MorphTarget, Node, NodeId, SceneDesc, Skin, SkinId, Trs,
};
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder, FrameScene};
use chronolux_core::scene::source::FrameSource;
use chronolux_core::scene::stage;
use std::sync::Arc;

const FPS: f32 = 24.0;

fn builder(desc: SceneDesc) -> FrameBuilder {
    let anim = (!desc.animations.is_empty()).then_some(AnimationId(0));
    FrameBuilder::new(Arc::new(desc), anim, CameraChoice::First, 16, 16).unwrap()
}

fn frames(desc: SceneDesc, fs: &[u32]) -> Vec<FrameScene> {
    let mut b = builder(desc);
    fs.iter().map(|&f| b.build(f as f32 / FPS)).collect()
}

/// On the Cornell stage: a quad skinned to two joints (the second one animated: the
/// quad's top-left corner, vertex 3, moves), a quad with one morph target (its weight
/// animated, the target moving vertex 3 only), and a static quad; one clip of 2 s. In
/// both deformed quads triangle 0 (vertices 0, 1, 2) stays still and triangle 1 moves.
fn skinned_and_morphed() -> SceneDesc {
    let quad = |x: f32| chronolux_core::scene::desc::Primitive {
        positions: vec![
            Vec3::new(x - 0.5, 0.0, 0.0),
            Vec3::new(x + 0.5, 0.0, 0.0),
            Vec3::new(x + 0.5, 1.0, 0.0),
            Vec3::new(x - 0.5, 1.0, 0.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material: Some(MaterialId(0)),
        ..Default::default()
    };
    let mut skinned = quad(-1.5);
    skinned.joints = Some(vec![[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0], [1, 0, 0, 0]]);
    skinned.joint_weights = Some(vec![Vec4::X; 4]);
    let mut morphed = quad(0.0);
    morphed.morph_targets.push(MorphTarget {
        positions: Some(vec![Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::Z]),
        ..Default::default()
    });
    let node = |name: &str, mesh: Option<u32>| Node {
        name: name.into(),
        mesh: mesh.map(MeshId),
        ..Default::default()
    };
    let mut nodes = vec![
        node("skinned", Some(0)),
        node("joint_a", None),
        node("joint_b", None),
        node("morphed", Some(1)),
        node("still", Some(2)),
    ];
    nodes[0].skin = Some(SkinId(0));
    nodes[4].transform.translation = Vec3::new(1.5, 0.0, 0.0);
    let mesh = |p| Mesh {
        name: String::new(),
        primitives: vec![p],
        weights: vec![],
    };
    let mut morph_mesh = mesh(morphed);
    morph_mesh.weights = vec![0.0];
    let linear = |node: u32, target, values: Vec<f32>, components| Channel {
        node: NodeId(node),
        target,
        interpolation: Interpolation::Linear,
        times: vec![0.0, 2.0],
        values,
        components,
    };
    stage::cornell_stage(SceneDesc {
        name: "skinned_and_morphed".into(),
        nodes,
        roots: (0..5).map(NodeId).collect(),
        meshes: vec![mesh(skinned), morph_mesh, mesh(quad(0.0))],
        materials: vec![Material::diffuse("grey", Rgb::splat(0.5))],
        skins: vec![Skin {
            name: "skin".into(),
            joints: vec![NodeId(1), NodeId(2)],
            inverse_bind_matrices: vec![Mat4::IDENTITY; 2],
        }],
        animations: vec![Animation {
            name: "bend".into(),
            channels: vec![
                linear(
                    2,
                    ChannelTarget::Translation,
                    vec![0., 0., 0., 0., 0., 0.5],
                    3,
                ),
                linear(3, ChannelTarget::Weights, vec![0.0, 1.0], 1),
            ],
        }],
        ..Default::default()
    })
}

/// Instance carrying the geometry of the node named `name`.
fn instance_of(scene: &FrameScene, desc: &SceneDesc, name: &str) -> usize {
    scene.geometry_instance[geometry_of(scene, desc, name) as usize] as usize
}

/// Geometry id of the node named `name`.
fn geometry_of(scene: &FrameScene, desc: &SceneDesc, name: &str) -> u32 {
    scene
        .geometry
        .iter()
        .position(|g| desc.nodes[g.node.index()].name == name)
        .unwrap_or_else(|| panic!("no geometry on node {name}")) as u32
}

/// World positions of the vertices instance `i` carries in `scene`.
fn instance_points(scene: &FrameScene, i: usize) -> Vec<Vec3> {
    let xf = scene.geometry_transforms();
    scene
        .geometry
        .iter()
        .enumerate()
        .filter(|(g, _)| scene.geometry_instance[*g] as usize == i)
        .flat_map(|(g, gd)| {
            let m = xf[g];
            gd.positions.iter().map(move |p| m.transform_point3(*p))
        })
        .collect::<Vec<_>>()
}

/// World positions (in `scene`, one of the delta's frames `a`, `b`) of the vertices of
/// instance `i`'s triangles that are not the same surface in `a` and `b`
/// ([`FrameDelta::triangle_changed`], brute force over the triangles): all its vertices
/// when it moved.
fn changed_points(
    d: &FrameDelta,
    a: &FrameScene,
    b: &FrameScene,
    scene: &FrameScene,
    i: usize,
) -> Vec<Vec3> {
    if d.instance_moved(i) {
        return instance_points(scene, i);
    }
    let xf = scene.geometry_transforms();
    let mut out = Vec::new();
    for (g, gd) in scene.geometry.iter().enumerate() {
        if scene.geometry_instance[g] as usize != i {
            continue;
        }
        for (t, ix) in gd.indices.iter().enumerate() {
            let t = TriRef {
                geometry: g as u32,
                triangle: t as u32,
            };
            if d.triangle_changed(a, b, t) {
                out.extend(
                    ix.iter()
                        .map(|&v| xf[g].transform_point3(gd.positions[v as usize])),
                );
            }
        }
    }
    out
}

fn inside(b: &chronolux_core::geometry::Bounds3, p: Vec3) -> bool {
    p.cmpge(b.min).all() && p.cmple(b.max).all()
}

/// `d = between(a, b)` has one region per changed instance (that carries vertices) in
/// each frame, bounding exactly (brute force over the vertices) every vertex it has there
/// when it moved, and when it only deformed every vertex of its changed triangles
/// ([`changed_points`]; no region when none changed), within a padding of 1e-4 of the
/// box's diagonal (FrameScene::instance_world_bounds' pad, at least 1e-7); none for an
/// unchanged instance.
fn regions_bound_exactly_the_changed_instances(d: &FrameDelta, a: &FrameScene, b: &FrameScene) {
    for (k, scene) in [a, b].into_iter().enumerate() {
        let mut expect = Vec::new();
        for i in 0..scene.accel.instances().len() {
            let pts = changed_points(d, a, b, scene, i);
            if !d.instance_changed(i) || pts.is_empty() {
                continue;
            }
            expect.push(i as u32);
            let r = d
                .regions()
                .iter()
                .find(|r| r.frame == k as u32 && r.instance == i as u32)
                .unwrap_or_else(|| panic!("no region of instance {i} in frame {k}"));
            assert!(
                pts.iter().all(|&p| inside(&r.bounds, p)),
                "instance {i} frame {k}"
            );
            let (lo, hi) = pts
                .iter()
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), &p| {
                    (l.min(p), h.max(p))
                });
            let pad = 1e-4 * (hi - lo).length().max(1e-3) * 1.001;
            assert!(
                (r.bounds.min - lo).abs().max_element() <= pad
                    && (r.bounds.max - hi).abs().max_element() <= pad,
                "instance {i} frame {k}: {:?} vs {lo}..{hi}",
                r.bounds
            );
        }
        let got: Vec<u32> = d
            .regions()
            .iter()
            .filter(|r| r.frame == k as u32)
            .map(|r| r.instance)
            .collect();
        assert_eq!(
            got, expect,
            "frame {k}: one region per changed instance, in order"
        );
    }
}

fn changed_instances(d: &FrameDelta) -> Vec<usize> {
    (0..d.instance_count())
        .filter(|&i| d.instance_changed(i))
        .collect()
}

#[test]
fn identical_frames_report_nothing_changed() {
    let mut b = builder(stage::demo());
    let (a, a2) = (b.build(0.5), b.build(0.5));
    for d in [FrameDelta::between(&a, &a), FrameDelta::between(&a, &a2)] {
        assert!(d.is_static(), "{d:?}");
        assert!(!d.camera_changed() && !d.lights_changed() && !d.materials_changed());
        assert!(changed_instances(&d).is_empty());
    }
    // The demo's clip ends at 2 s: later instants are the same frame.
    let (c, e) = (b.build(2.5), b.build(3.0));
    assert!(FrameDelta::between(&c, &e).is_static());
}

#[test]
fn demo_cube_moves_walls_and_camera_stay() {
    let desc = stage::demo();
    let fr = frames(desc.clone(), &[0, 6]);
    let d = FrameDelta::between(&fr[0], &fr[1]);
    let cube = instance_of(&fr[0], &desc, "sliding_cube");
    let walls = instance_of(&fr[0], &desc, "ceiling_light");
    assert_eq!(
        instance_of(&fr[1], &desc, "sliding_cube"),
        cube,
        "instance ids are stable across frames"
    );
    assert!(d.instance_moved(cube));
    assert!(!d.instance_deformed(cube), "a rigid cube is not deformed");
    assert!(!d.instance_changed(walls));
    assert_eq!(changed_instances(&d), vec![cube]);
    assert!(!d.camera_changed(), "the demo's camera is static");
    assert!(!d.lights_changed() && !d.materials_changed());
    assert!(!d.is_static());
    // Symmetric in what changed; the regions name the frames in the order given.
    let back = FrameDelta::between(&fr[1], &fr[0]);
    assert_eq!(changed_instances(&back), changed_instances(&d), "symmetric");
    assert_eq!(back.changed_bounds_in(0), d.changed_bounds_in(1));
    assert_eq!(back.changed_bounds_in(1), d.changed_bounds_in(0));
    regions_bound_exactly_the_changed_instances(&d, &fr[0], &fr[1]);
    // Geometry-level view: every primitive of the cube changed, nothing else did.
    for (g, gd) in fr[0].geometry.iter().enumerate() {
        let is_cube = desc.nodes[gd.node.index()].name == "sliding_cube";
        assert_eq!(d.geometry_changed(&fr[0], g as u32), is_cube);
    }
}

#[test]
fn skinned_and_morphed_meshes_are_deformed_not_moved() {
    let desc = skinned_and_morphed();
    let fr = frames(desc.clone(), &[0, 12]);
    let d = FrameDelta::between(&fr[0], &fr[1]);
    let (skinned, morphed, still) = (
        instance_of(&fr[0], &desc, "skinned"),
        instance_of(&fr[0], &desc, "morphed"),
        instance_of(&fr[0], &desc, "still"),
    );
    assert!(skinned != morphed && morphed != still);
    for i in [skinned, morphed] {
        assert!(d.instance_deformed(i), "instance {i}");
        assert!(
            !d.instance_moved(i),
            "deformed data is in world space under an identity instance"
        );
    }
    assert!(!d.instance_changed(still));
    assert!(!d.instance_changed(instance_of(&fr[0], &desc, "ceiling_light")));
    regions_bound_exactly_the_changed_instances(&d, &fr[0], &fr[1]);
    assert!(!d.camera_changed() && !d.lights_changed() && !d.materials_changed());
    // The builder rebuilds deformed geometry for every build: at the same time the data
    // is new (other buffers, other BLAS) but equal, so nothing is deformed.
    let mut b = builder(desc.clone());
    let (x, y) = (b.build(0.5), b.build(0.5));
    let g = geometry_of(&fr[0], &desc, "skinned") as usize;
    assert!(!Arc::ptr_eq(
        &x.geometry[g].positions,
        &y.geometry[g].positions
    ));
    assert!(FrameDelta::between(&x, &y).is_static());
    // After the clip's end the pose holds: deformed geometry is unchanged.
    assert!(FrameDelta::between(&b.build(2.0), &b.build(2.5)).is_static());
}

/// A deformed mesh changes only where its vertices move: a triangle whose three vertices
/// are bound to a still joint (or untouched by the morph target) is the same surface in
/// both frames, the others are not; a rigidly moved object changes every triangle, a
/// static one none. Both orders of the frames give the same answers.
#[test]
fn deformed_meshes_change_only_the_triangles_whose_vertices_move() {
    let tri = |geometry, triangle| TriRef { geometry, triangle };
    let desc = skinned_and_morphed();
    let fr = frames(desc.clone(), &[0, 12]);
    let d = FrameDelta::between(&fr[0], &fr[1]);
    for name in ["skinned", "morphed"] {
        let g = geometry_of(&fr[0], &desc, name);
        assert!(d.geometry_changed(&fr[0], g), "{name}: the mesh deforms");
        for (a, b) in [(&fr[0], &fr[1]), (&fr[1], &fr[0])] {
            assert!(
                !d.triangle_changed(a, b, tri(g, 0)),
                "{name}: vertices 0, 1, 2 stay"
            );
            assert!(
                d.triangle_changed(a, b, tri(g, 1)),
                "{name}: vertex 3 moves"
            );
        }
    }
    let still = geometry_of(&fr[0], &desc, "still");
    assert!(!d.triangle_changed(&fr[0], &fr[1], tri(still, 0)));
    // Identical frames: nothing changes, deformed or not.
    let same = FrameDelta::between(&fr[1], &fr[1]);
    let skinned = geometry_of(&fr[0], &desc, "skinned");
    assert!(!same.triangle_changed(&fr[1], &fr[1], tri(skinned, 1)));

    let demo = stage::demo();
    let fr = frames(demo.clone(), &[0, 12]);
    let d = FrameDelta::between(&fr[0], &fr[1]);
    let cube = geometry_of(&fr[0], &demo, "sliding_cube");
    let n = fr[0].geometry[cube as usize].indices.len() as u32;
    assert!((0..n).all(|t| d.triangle_changed(&fr[0], &fr[1], tri(cube, t))));
    let floor = geometry_of(&fr[0], &demo, "floor");
    assert!(!d.triangle_changed(&fr[0], &fr[1], tri(floor, 0)));

    // The built-in banner: the upper half of its rows is bound to the still joint only.
    let banner = stage::banner();
    let fr = frames(banner.clone(), &[0, 7]);
    let d = FrameDelta::between(&fr[0], &fr[1]);
    let g = geometry_of(&fr[0], &banner, "banner");
    let per_row = 2 * stage::BANNER_COLUMNS;
    for t in 0..per_row * stage::BANNER_ROWS {
        let row = t / per_row;
        assert_eq!(
            d.triangle_changed(&fr[0], &fr[1], tri(g, t)),
            row >= stage::BANNER_ROWS / 2,
            "banner triangle {t} (row {row})"
        );
    }
    // Where: the swinging lower half only, not the whole banner.
    regions_bound_exactly_the_changed_instances(&d, &fr[0], &fr[1]);
    let i = fr[0].geometry_instance[g as usize] as usize;
    for (k, scene) in fr.iter().enumerate() {
        let r = d
            .regions()
            .iter()
            .find(|r| r.instance == i as u32 && r.frame == k as u32)
            .expect("the banner changed");
        assert!(
            instance_points(scene, i)
                .iter()
                .any(|&p| !inside(&r.bounds, p)),
            "frame {k}: the region is smaller than the banner"
        );
    }
}

#[test]
fn segment_dynamic_set_is_the_union_of_pairwise_changes() {
    for (what, desc) in [
        ("demo", stage::demo()),
        ("caustic", stage::caustic()),
        ("skinned and morphed", skinned_and_morphed()),
        ("banner", stage::banner()),
    ] {
        let fs: Vec<u32> = (0..8).collect();
        let fr = frames(desc.clone(), &fs);
        let refs: Vec<&FrameScene> = fr.iter().collect();
        let seg = dynamic_instances(&refs);
        let mut union = vec![false; seg.len()];
        for a in &fr {
            for b in &fr {
                let d = FrameDelta::between(a, b);
                for (u, c) in union.iter_mut().zip(d.dynamic_instances()) {
                    *u |= c;
                }
            }
        }
        assert_eq!(seg, union, "{what}");
        assert!(
            seg.iter().any(|&c| c),
            "{what}: something moves in frames 0..8"
        );
        // Static instances of the segment are the same surfaces in every frame.
        let seg_delta = FrameDelta::over(&refs);
        for (i, _) in seg.iter().enumerate().filter(|(_, c)| !**c) {
            let (a, b) = (&fr[0].accel.instances()[i], &fr[7].accel.instances()[i]);
            assert_eq!(a.world_from_object, b.world_from_object, "{what}");
            assert!(!seg_delta.instance_changed(i));
        }
        // Where: every vertex of a dynamic instance's triangles that change between a
        // frame of the segment and the next (or the one before) lies in one of its
        // regions; each region names a frame of the segment.
        for (f, scene) in fr.iter().enumerate() {
            for (i, _) in seg.iter().enumerate().filter(|(_, c)| **c) {
                let mine: Vec<_> = seg_delta
                    .regions()
                    .iter()
                    .filter(|r| r.instance == i as u32)
                    .collect();
                let mut pts = Vec::new();
                for (x, y) in [(f.wrapping_sub(1), f), (f, f + 1)] {
                    if let (Some(a), Some(b)) = (fr.get(x), fr.get(y)) {
                        pts.extend(changed_points(&FrameDelta::between(a, b), a, b, scene, i));
                    }
                }
                for p in pts {
                    assert!(
                        mine.iter().any(|r| inside(&r.bounds, p)),
                        "{what}: instance {i}, frame {f}: {p} outside its regions"
                    );
                }
            }
        }
        assert!(
            seg_delta
                .regions()
                .iter()
                .all(|r| (r.frame as usize) < fr.len())
        );
        // Through the frame source (built two at a time).
        let mut src = FrameSource::new(builder(desc), FPS, fs.clone());
        assert_eq!(src.delta_over(&fs), seg_delta, "{what}");
    }
    // The caustic occluder enters between frames 3 and 4 (a STEP key): it is dynamic in a
    // segment across the step and static in segments before and after it.
    let desc = stage::caustic();
    let fr = frames(desc.clone(), &[0, 1, 2, 3, 4, 5]);
    let occluder = instance_of(&fr[0], &desc, "occluder");
    let seg = |r: std::ops::Range<usize>| dynamic_instances(&fr[r].iter().collect::<Vec<_>>());
    assert!(!seg(0..4)[occluder] && !seg(4..6)[occluder] && seg(3..5)[occluder]);
}

/// The demo with an animated point light, with a brighter lamp material, and with an
/// animated camera: each change is reported, and only it.
#[test]
fn light_material_and_camera_changes_are_detected() {
    // An animated point light on the demo's clip.
    let mut desc = stage::demo();
    let node = desc.add_light("bulb", 3.0, LightKind::Point, Trs::default());
    desc.animations[0].channels.push(Channel {
        node,
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Linear,
        times: vec![0.0, 2.0],
        values: vec![0.0, 0.5, 0.0, 0.0, 0.8, 0.0],
        components: 3,
    });
    let fr = frames(desc, &[0, 6]);
    let d = FrameDelta::between(&fr[0], &fr[1]);
    let bulb = fr[0]
        .lights
        .iter()
        .position(|l| matches!(l, chronolux_core::light::Light::Point { .. }))
        .unwrap();
    assert!(d.light_changed(bulb) && d.lights_changed());
    assert_eq!(
        (0..fr[0].lights.len())
            .filter(|&l| d.light_changed(l))
            .collect::<Vec<_>>(),
        vec![bulb],
        "the lamp's triangles are unchanged"
    );
    assert!(!d.camera_changed());

    // A material changed: same scene, brighter lamp (two builders: no shared data).
    let base = stage::demo();
    let mut brighter = base.clone();
    let lamp = brighter
        .materials
        .iter()
        .position(|m| m.name == "light")
        .unwrap();
    brighter.materials[lamp].emissive *= 2.0;
    let (a, b) = (&frames(base.clone(), &[3])[0], &frames(brighter, &[3])[0]);
    let d = FrameDelta::between(a, b);
    assert_eq!(
        (0..a.materials.len())
            .filter(|&m| d.material_changed(m))
            .collect::<Vec<_>>(),
        vec![lamp]
    );
    // Every lamp triangle's radiance changed; nothing moved.
    assert!(!a.lights.is_empty());
    assert!((0..a.lights.len()).all(|l| d.light_changed(l)));
    assert!(changed_instances(&d).is_empty() && !d.camera_changed());
    // Same description built twice: equal by value.
    let c = &frames(base.clone(), &[3])[0];
    assert!(FrameDelta::between(a, c).is_static());

    // A moving camera.
    let mut moving = base;
    let cam = moving
        .nodes
        .iter()
        .position(|n| n.camera.is_some())
        .unwrap();
    let z = moving.nodes[cam].transform.translation;
    moving.animations[0].channels.push(Channel {
        node: NodeId(cam as u32),
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Linear,
        times: vec![0.0, 2.0],
        values: vec![z.x, z.y, z.z, z.x + 0.3, z.y, z.z],
        components: 3,
    });
    let fr = frames(moving, &[0, 6, 60]);
    assert!(FrameDelta::between(&fr[0], &fr[1]).camera_changed());
    let end = frames(stage::demo(), &[60]);
    assert!(!FrameDelta::between(&fr[0], &fr[0]).camera_changed());
    assert!(FrameDelta::between(&fr[2], &end[0]).camera_changed());
}

#[test]
fn movable_nodes_get_their_own_instance_and_a_moved_one_is_all_that_changes() {
    let desc = stage::demo();
    let anim = Some(AnimationId(0));
    let movable = vec![true; desc.nodes.len()];
    let build = |d: SceneDesc| {
        FrameBuilder::with_movable(Arc::new(d), anim, CameraChoice::First, 16, 16, &movable)
            .unwrap()
            .build(0.5)
    };
    let a = build(desc.clone());
    // Every mesh node is an instance of its own: no static instance holds the walls.
    let meshes = desc.nodes.iter().filter(|n| n.mesh.is_some()).count();
    assert_eq!(a.accel.instances().len(), meshes);
    let mut moved = desc.clone();
    let sphere = moved
        .nodes
        .iter()
        .position(|n| n.name == "metal_sphere")
        .unwrap();
    moved.nodes[sphere].transform.translation.x += 0.25;
    let b = build(moved);
    let d = FrameDelta::between(&a, &b);
    assert_eq!(
        changed_instances(&d),
        vec![instance_of(&a, &desc, "metal_sphere")],
        "another builder over the edited scene: only the moved sphere changed"
    );
    assert!(!d.lights_changed() && !d.materials_changed() && !d.camera_changed());
    // Same pixels' worth of scene as `new`: an empty mask is `new`.
    let plain = FrameBuilder::with_movable(
        Arc::new(desc.clone()),
        anim,
        CameraChoice::First,
        16,
        16,
        &[],
    )
    .unwrap()
    .build(0.5);
    assert!(FrameDelta::between(&plain, &builder(desc).build(0.5)).is_static());
}

/// `only_camera_changed`: under the fly-through (the dolly's camera, nothing else moving)
/// every pair of frames differs in the camera alone; under the dolly the cube moves too.
#[test]
fn only_the_camera_changes_in_the_flythrough() {
    let fs: Vec<u32> = (0..6).collect();
    let fly = frames(stage::flythrough(), &fs);
    for w in fly.windows(2) {
        let d = FrameDelta::between(&w[0], &w[1]);
        assert!(d.only_camera_changed() && d.camera_changed() && !d.is_static());
    }
    let dolly = frames(stage::dolly(), &fs);
    let d = FrameDelta::between(&dolly[0], &dolly[5]);
    assert!(d.camera_changed() && !d.only_camera_changed());
    let same = FrameDelta::between(&dolly[2], &dolly[2]);
    assert!(same.only_camera_changed() && same.is_static());
}
