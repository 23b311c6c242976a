//! Scenes built in code: a Cornell room ([`cornell_box`]), a way to place any scene inside
//! it ([`cornell_stage`]), the built-in demo animation ([`demo`]), a caustic scene with
//! an abrupt change ([`caustic`]), the demo under a moving camera ([`dolly`]) and a
//! partly deforming skinned banner ([`banner`]).
//!
//! The room spans x, z ∈ [-1, 1], y ∈ [0, 2] (y up); the front (z = +1) is open and the
//! camera looks down −Z into it from z ≈ 3.9. It is lit only by an emissive quad just below
//! the ceiling, so [`SceneDesc::environment`] is `None`.

use super::anim::{deform_primitive, pose_at};
use super::desc::{
    Animation, CameraDesc, CameraId, Channel, ChannelTarget, Interpolation, LightId, Material,
    MaterialId, MeshId, Node, NodeId, Primitive, Projection, SceneDesc, SkinId, TextureRef, Trs,
};
use crate::color::Rgb;
use crate::math::{Quat, Vec2, Vec3};

/// Half-extent of the room in x and z; the room is `2 * ROOM_HALF` tall.
pub const ROOM_HALF: f32 = 1.0;
/// Emitted radiance of the ceiling light (the classic Cornell box spectrum as RGB).
pub const LIGHT_RADIANCE: Rgb = Rgb::new(17.0, 12.0, 4.0);
/// Vertical field of view of the stage camera (radians).
pub const CAMERA_YFOV: f32 = 0.69;

/// A quad p0..p3 (in order around its boundary) as two triangles whose geometric normal and
/// shading normals equal `normal`.
fn quad(p: [Vec3; 4], normal: Vec3) -> Primitive {
    let geometric = (p[1] - p[0]).cross(p[2] - p[0]);
    let p = if geometric.dot(normal) < 0.0 {
        [p[0], p[3], p[2], p[1]]
    } else {
        p
    };
    Primitive {
        positions: p.to_vec(),
        normals: Some(vec![normal; 4]),
        uvs: Some(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ]),
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    }
}

fn push_material(desc: &mut SceneDesc, m: Material) -> MaterialId {
    desc.materials.push(m);
    MaterialId(desc.materials.len() as u32 - 1)
}

/// The Cornell room: white floor, ceiling and back wall, red left wall, green right wall,
/// an emissive ceiling quad facing down, and a perspective camera (camera 0) in front of the
/// open side looking in.
pub fn cornell_box() -> SceneDesc {
    let mut d = SceneDesc {
        name: "cornell_box".into(),
        ..Default::default()
    };
    let white = push_material(&mut d, Material::diffuse("white", Rgb::splat(0.73)));
    let red = push_material(
        &mut d,
        Material::diffuse("red", Rgb::new(0.63, 0.065, 0.05)),
    );
    let green = push_material(
        &mut d,
        Material::diffuse("green", Rgb::new(0.14, 0.45, 0.09)),
    );
    let light = push_material(
        &mut d,
        Material {
            emissive: LIGHT_RADIANCE,
            // One-sided: a lamp that also emitted upwards would light the thin gap under
            // the ceiling, a tiny bright region that paths find only by chance (fireflies).
            double_sided: false,
            ..Material::diffuse("light", Rgb::splat(0.78))
        },
    );
    let (h, top) = (ROOM_HALF, 2.0 * ROOM_HALF);
    let v = Vec3::new;
    let id = Trs::default();
    let floor = quad(
        [v(-h, 0.0, -h), v(h, 0.0, -h), v(h, 0.0, h), v(-h, 0.0, h)],
        Vec3::Y,
    );
    d.add_mesh("floor", floor, white, id);
    let ceiling = quad(
        [v(-h, top, -h), v(h, top, -h), v(h, top, h), v(-h, top, h)],
        -Vec3::Y,
    );
    d.add_mesh("ceiling", ceiling, white, id);
    let back = quad(
        [v(-h, 0.0, -h), v(h, 0.0, -h), v(h, top, -h), v(-h, top, -h)],
        Vec3::Z,
    );
    d.add_mesh("back_wall", back, white, id);
    let left = quad(
        [v(-h, 0.0, -h), v(-h, 0.0, h), v(-h, top, h), v(-h, top, -h)],
        Vec3::X,
    );
    d.add_mesh("left_wall", left, red, id);
    let right = quad(
        [v(h, 0.0, -h), v(h, 0.0, h), v(h, top, h), v(h, top, -h)],
        -Vec3::X,
    );
    d.add_mesh("right_wall", right, green, id);
    // Light: the classic 130 × 105 of a 556 room, 1 % of the height below the ceiling.
    let (lx, lz, ly) = (0.235 * h, 0.19 * h, top - 0.01 * top);
    let lamp = quad(
        [
            v(-lx, ly, -lz),
            v(lx, ly, -lz),
            v(lx, ly, lz),
            v(-lx, ly, lz),
        ],
        -Vec3::Y,
    );
    d.add_mesh("ceiling_light", lamp, light, id);
    d.cameras.push(CameraDesc {
        name: "stage_camera".into(),
        projection: Projection::Perspective {
            yfov: CAMERA_YFOV,
            aspect: Some(1.0),
            znear: 0.01,
        },
    });
    let cam = NodeId(d.nodes.len() as u32);
    d.nodes.push(Node {
        name: "stage_camera".into(),
        transform: Trs {
            translation: Vec3::new(0.0, h, h + 2.9 * h),
            ..Default::default()
        },
        camera: Some(CameraId(0)),
        ..Default::default()
    });
    d.roots.push(cam);
    d
}

/// Axis-aligned bounds of all mesh vertices of `desc` at its rest pose, in world space
/// (`None` when there is no vertex).
pub fn rest_bounds(desc: &SceneDesc) -> Option<(Vec3, Vec3)> {
    let pose = pose_at(desc, None, 0.0);
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for id in desc.topological_order() {
        let node = &desc.nodes[id.index()];
        let Some(m) = node.mesh else { continue };
        let world = pose.world[id.index()];
        for prim in &desc.meshes[m.index()].primitives {
            let skinned =
                node.skin.is_some() && prim.joints.is_some() && prim.joint_weights.is_some();
            let pts: Vec<Vec3> = match deform_primitive(desc, id, prim, &pose) {
                Some((p, _)) if skinned => p,
                Some((p, _)) => p.iter().map(|&q| world.transform_point3(q)).collect(),
                None => prim
                    .positions
                    .iter()
                    .map(|&q| world.transform_point3(q))
                    .collect(),
            };
            for p in pts.into_iter().filter(|p| p.is_finite()) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// Puts `content` inside the Cornell room: a new root node (`"stage"`) with a uniform scale
/// (largest extent → 60 % of the room size) and a translation (centred in x and z, standing
/// on the floor) parents the content's roots. All content ids are offset; its meshes,
/// materials, textures, lights, skins, animations (retargeted), cameras (after the stage
/// camera, which stays camera 0) and warnings are kept. The room's lighting replaces the
/// content's `environment` (the stage is lit by its ceiling quad and the content's lights).
pub fn cornell_stage(content: SceneDesc) -> SceneDesc {
    let mut d = cornell_box();
    d.name = content.name.clone();
    let (scale, translation) = match rest_bounds(&content) {
        Some((lo, hi)) => {
            let extent = (hi - lo).max_element();
            let s = if extent > 0.0 {
                0.6 * 2.0 * ROOM_HALF / extent
            } else {
                1.0
            };
            let c = 0.5 * (lo + hi);
            (
                s,
                Vec3::new(-c.x * s, -lo.y * s + 1e-3 * ROOM_HALF, -c.z * s),
            )
        }
        None => (1.0, Vec3::ZERO),
    };
    let stage = NodeId(d.nodes.len() as u32);
    let node_off = stage.0 + 1;
    let mesh_off = d.meshes.len() as u32;
    let mat_off = d.materials.len() as u32;
    let tex_off = d.textures.len() as u32;
    let light_off = d.lights.len() as u32;
    let cam_off = d.cameras.len() as u32;
    let skin_off = d.skins.len() as u32;
    let nid = |n: NodeId| NodeId(n.0 + node_off);
    d.nodes.push(Node {
        name: "stage".into(),
        transform: Trs {
            translation,
            rotation: Quat::IDENTITY,
            scale: Vec3::splat(scale),
        },
        children: content.roots.iter().map(|&r| nid(r)).collect(),
        ..Default::default()
    });
    d.roots.push(stage);
    for n in content.nodes {
        d.nodes.push(Node {
            parent: Some(n.parent.map_or(stage, nid)),
            children: n.children.iter().map(|&c| nid(c)).collect(),
            mesh: n.mesh.map(|m| MeshId(m.0 + mesh_off)),
            camera: n.camera.map(|c| CameraId(c.0 + cam_off)),
            light: n.light.map(|l| LightId(l.0 + light_off)),
            skin: n.skin.map(|s| SkinId(s.0 + skin_off)),
            ..n
        });
    }
    d.meshes.extend(content.meshes.into_iter().map(|mut m| {
        for p in &mut m.primitives {
            p.material = p.material.map(|x| MaterialId(x.0 + mat_off));
        }
        m
    }));
    let tex = |t: Option<TextureRef>| {
        t.map(|t| TextureRef {
            texture: super::desc::TextureId(t.texture.0 + tex_off),
            ..t
        })
    };
    d.materials
        .extend(content.materials.into_iter().map(|m| Material {
            base_color_texture: tex(m.base_color_texture),
            metallic_roughness_texture: tex(m.metallic_roughness_texture),
            emissive_texture: tex(m.emissive_texture),
            normal_texture: tex(m.normal_texture),
            transmission_texture: tex(m.transmission_texture),
            ..m
        }));
    d.textures.extend(content.textures);
    d.lights.extend(content.lights);
    d.cameras.extend(content.cameras);
    d.skins.extend(content.skins.into_iter().map(|mut s| {
        s.joints.iter_mut().for_each(|j| *j = nid(*j));
        s
    }));
    d.animations
        .extend(content.animations.into_iter().map(|mut a| {
            a.channels.iter_mut().for_each(|c| c.node = nid(c.node));
            a
        }));
    // The room lights the content: a default environment the loader added is gone.
    d.warnings.extend(
        content
            .warnings
            .into_iter()
            .filter(|w| w != super::desc::DEFAULT_ENVIRONMENT_WARNING),
    );
    d
}

/// A cube of half-size `h` centred at the origin, 24 vertices with face normals.
pub fn cube_primitive(h: f32) -> Primitive {
    let mut prim = Primitive::default();
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let (u, v) = (Vec3::new(n.y, n.z, n.x), Vec3::new(n.z, n.x, n.y));
            let c = n * h;
            let q = quad(
                [
                    c - (u + v) * h,
                    c + (u - v) * h,
                    c + (u + v) * h,
                    c + (v - u) * h,
                ],
                n,
            );
            let base = prim.positions.len() as u32;
            prim.positions.extend(q.positions);
            normals.extend(q.normals.unwrap_or_default());
            uvs.extend(q.uvs.unwrap_or_default());
            prim.indices
                .extend(q.indices.iter().map(|t| t.map(|i| i + base)));
        }
    }
    Primitive {
        normals: Some(normals),
        uvs: Some(uvs),
        ..prim
    }
}

/// A UV sphere of `radius` centred at the origin with `segments` longitudes and `rings`
/// latitudes (2·segments·(rings−1) triangles), unit normals and UVs.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> Primitive {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        let theta = v * std::f32::consts::PI;
        for s in 0..=segments {
            let u = s as f32 / segments as f32;
            let phi = u * std::f32::consts::TAU;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            positions.push(n * radius);
            normals.push(n);
            uvs.push(Vec2::new(u, v));
        }
    }
    let row = segments + 1;
    let mut indices = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, e) = (
                r * row + s,
                r * row + s + 1,
                (r + 1) * row + s + 1,
                (r + 1) * row + s,
            );
            // Counter-clockwise seen from outside; the pole rows have one triangle per quad.
            if r != 0 {
                indices.push([a, e, b]);
            }
            if r != rings - 1 {
                indices.push([b, e, c]);
            }
        }
    }
    Primitive {
        positions,
        normals: Some(normals),
        uvs: Some(uvs),
        indices,
        ..Default::default()
    }
}

/// Duration of the demo clip in seconds (48 frames at 24 fps).
pub const DEMO_DURATION: f32 = 2.0;

/// The built-in demo: the Cornell room with a glossy cube sliding and turning across the
/// floor (LINEAR keys over 2 s), a rough-metal sphere and a glass sphere; static camera; one
/// clip named `"demo"` lasting exactly [`DEMO_DURATION`].
pub fn demo() -> SceneDesc {
    let mut d = cornell_box();
    d.name = "demo".into();
    let glossy = push_material(
        &mut d,
        Material {
            name: "glossy_orange".into(),
            base_color: Rgb::new(0.8, 0.35, 0.08),
            metallic: 0.0,
            roughness: 0.35,
            double_sided: false,
            ..Default::default()
        },
    );
    let metal = push_material(
        &mut d,
        Material {
            name: "metal".into(),
            base_color: Rgb::new(0.95, 0.93, 0.88),
            metallic: 1.0,
            roughness: 0.3,
            ..Default::default()
        },
    );
    let glass = push_material(
        &mut d,
        Material {
            name: "glass".into(),
            base_color: Rgb::ONE,
            metallic: 0.0,
            roughness: 0.0,
            transmission: 1.0,
            ior: 1.5,
            ..Default::default()
        },
    );
    let r = 0.35 * ROOM_HALF;
    let at = |p: Vec3| Trs {
        translation: p,
        ..Default::default()
    };
    let half = 0.2 * ROOM_HALF;
    let y0 = half;
    let cube = d.add_mesh(
        "sliding_cube",
        cube_primitive(half),
        glossy,
        at(Vec3::new(-0.6, y0, 0.35) * ROOM_HALF),
    );
    d.add_mesh(
        "metal_sphere",
        uv_sphere(r, 32, 24),
        metal,
        at(Vec3::new(-0.45, 0.35, -0.4) * ROOM_HALF),
    );
    d.add_mesh(
        "glass_sphere",
        uv_sphere(r, 32, 24),
        glass,
        at(Vec3::new(0.45, 0.35, -0.35) * ROOM_HALF),
    );
    let times = vec![0.0, 0.5 * DEMO_DURATION, DEMO_DURATION];
    let xs = [-0.6f32, 0.0, 0.6];
    let translation: Vec<f32> = xs
        .iter()
        .flat_map(|&x| [x * ROOM_HALF, y0, 0.35 * ROOM_HALF])
        .collect();
    let rotation: Vec<f32> = [0.0f32, 0.25, 0.5]
        .iter()
        .flat_map(|&turn| {
            let q = Quat::from_rotation_y(turn * std::f32::consts::PI);
            [q.x, q.y, q.z, q.w]
        })
        .collect();
    d.animations.push(Animation {
        name: "demo".into(),
        channels: vec![
            Channel {
                node: cube,
                target: ChannelTarget::Translation,
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: translation,
                components: 3,
            },
            Channel {
                node: cube,
                target: ChannelTarget::Rotation,
                interpolation: Interpolation::Linear,
                times,
                values: rotation,
                components: 4,
            },
        ],
    });
    d
}

/// Duration of the caustic clip in seconds (48 frames at 24 fps).
pub const CAUSTIC_DURATION: f32 = 2.0;
/// Time (s) at which the caustic scene's occluder enters (between frames 3 and 4 at
/// 24 fps): a STEP key, so the lighting changes abruptly from one frame to the next.
pub const CAUSTIC_OCCLUDER_TIME: f32 = 0.15;

/// A caustic scene with an abrupt change: the Cornell room with a glass sphere (IOR 1.5,
/// radius 0.3) that rolls slowly across the floor under the lamp, focusing a caustic on
/// the floor, and a white diffuse block (0.5 × 0.1 × 0.5) that *enters* at
/// [`CAUSTIC_OCCLUDER_TIME`] (STEP keys: hidden under the floor before, hanging 0.45 below
/// the lamp after), shadowing the sphere and the middle of the floor from one frame to the
/// next. One clip named `"caustic"` lasting [`CAUSTIC_DURATION`]; static camera.
pub fn caustic() -> SceneDesc {
    let mut d = cornell_box();
    d.name = "caustic".into();
    let glass = push_material(
        &mut d,
        Material {
            name: "glass".into(),
            base_color: Rgb::ONE,
            metallic: 0.0,
            roughness: 0.0,
            transmission: 1.0,
            ior: 1.5,
            ..Default::default()
        },
    );
    let white = push_material(&mut d, Material::diffuse("occluder", Rgb::splat(0.73)));
    let r = 0.3 * ROOM_HALF;
    let at = |p: Vec3| Trs {
        translation: p,
        ..Default::default()
    };
    let (x0, x1, z) = (-0.25 * ROOM_HALF, 0.25 * ROOM_HALF, 0.05 * ROOM_HALF);
    let sphere = d.add_mesh(
        "glass_sphere",
        uv_sphere(r, 48, 32),
        glass,
        at(Vec3::new(x0, r, z)),
    );
    // The occluder: a flat block, hidden under the floor (fully below y = 0, where neither
    // the lamp nor the camera sees it) until it enters.
    let hidden = Vec3::new(0.0, -0.5 * ROOM_HALF, 0.0);
    let shown = Vec3::new(0.0, 1.45 * ROOM_HALF, 0.0);
    let occluder = d.add_mesh(
        "occluder",
        cube_primitive(0.25 * ROOM_HALF),
        white,
        Trs {
            translation: hidden,
            rotation: Quat::IDENTITY,
            scale: Vec3::new(1.0, 0.2, 1.0),
        },
    );
    d.animations.push(Animation {
        name: "caustic".into(),
        channels: vec![
            Channel {
                node: sphere,
                target: ChannelTarget::Translation,
                interpolation: Interpolation::Linear,
                times: vec![0.0, CAUSTIC_DURATION],
                values: vec![x0, r, z, x1, r, z],
                components: 3,
            },
            Channel {
                node: occluder,
                target: ChannelTarget::Translation,
                interpolation: Interpolation::Step,
                times: vec![0.0, CAUSTIC_OCCLUDER_TIME],
                values: vec![hidden.x, hidden.y, hidden.z, shown.x, shown.y, shown.z],
                components: 3,
            },
        ],
    });
    d
}

/// The node carrying the stage camera (camera 0) of a built-in scene.
fn stage_camera_node(d: &SceneDesc) -> NodeId {
    d.nodes
        .iter()
        .position(|n| n.camera == Some(CameraId(0)))
        .map(|i| NodeId(i as u32))
        .expect("the stage camera's node")
}

/// The demo ([`demo`]) filmed by a moving camera: over the clip the stage camera trucks
/// from x = −0.3 to +0.3 (room half-widths), dollies in from z = 3.9 to 3.3 and turns to
/// keep the room's centre (0, 1, 0) in the middle of the frame (LINEAR keys at 0, 1 and
/// 2 s, the yaw `atan2(x, z − 0)` at each key), while the cube slides and turns as in the
/// demo. Every surface is seen from a new place in every frame: view-dependent shading
/// (the metal and glass spheres, the glossy cube) changes everywhere, and reuse across
/// frames must re-shade, re-project and re-test visibility to the new eye. One clip named
/// `"dolly"` lasting [`DEMO_DURATION`].
pub fn dolly() -> SceneDesc {
    let mut d = demo();
    d.name = "dolly".into();
    d.animations[0].name = "dolly".into();
    let cam = stage_camera_node(&d);
    let h = ROOM_HALF;
    let times = vec![0.0, 0.5 * DEMO_DURATION, DEMO_DURATION];
    let keys = [(-0.3 * h, 3.9 * h), (0.0, 3.6 * h), (0.3 * h, 3.3 * h)];
    let translation: Vec<f32> = keys.iter().flat_map(|&(x, z)| [x, h, z]).collect();
    let rotation: Vec<f32> = keys
        .iter()
        .flat_map(|&(x, z)| {
            // −Z (the camera's view) turned by θ about +Y is (−sin θ, 0, −cos θ): towards
            // the centre (−x, 0, −z)/r when θ = atan2(x, z).
            let q = Quat::from_rotation_y(x.atan2(z));
            [q.x, q.y, q.z, q.w]
        })
        .collect();
    d.animations[0].channels.extend([
        Channel {
            node: cam,
            target: ChannelTarget::Translation,
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values: translation,
            components: 3,
        },
        Channel {
            node: cam,
            target: ChannelTarget::Rotation,
            interpolation: Interpolation::Linear,
            times,
            values: rotation,
            components: 4,
        },
    ]);
    d
}

/// A fly-through of a still interior: the [`dolly`]'s camera path through the demo's room,
/// with nothing else moving (the cube stays at its first pose). Every frame sees the room
/// from a new place while all its light stays the same: the case an irradiance-map
/// fly-through mode (V-Ray) or an ambient file (Radiance) serves by computing the light
/// once. One clip named `"flythrough"` lasting [`DEMO_DURATION`].
pub fn flythrough() -> SceneDesc {
    let mut d = dolly();
    d.name = "flythrough".into();
    let cam = stage_camera_node(&d);
    let clip = &mut d.animations[0];
    clip.name = "flythrough".into();
    clip.channels.retain(|c| c.node == cam);
    d
}

/// Quads across and down the [`banner`]; the upper half of the rows is still.
pub const BANNER_COLUMNS: u32 = 8;
pub const BANNER_ROWS: u32 = 12;

/// The Cornell room with a skinned red banner hanging in front of the back wall (x ∈
/// [−0.5, 0.5], y from 1.8 down to 0.4, z = −0.7), over [`DEMO_DURATION`]: its upper
/// half is bound to a joint that never moves, its lower half to a second joint that
/// turns about the banner's middle line, swinging the lower edge out towards the camera
/// (by up to 40°) and back, with weights growing linearly to 1 at the bottom edge, so the
/// cloth bends smoothly. The mesh deforms in every frame, yet its upper half is the same
/// surface in every frame ([`FrameDelta::triangle_changed`](super::delta::FrameDelta::triangle_changed)),
/// as the still parts of a character are while one limb moves: the scene for reuse on
/// the still part of a deforming mesh.
pub fn banner() -> SceneDesc {
    let mut d = cornell_box();
    d.name = "banner".into();
    let cloth = push_material(
        &mut d,
        Material {
            double_sided: true,
            ..Material::diffuse("banner", Rgb::new(0.7, 0.12, 0.1))
        },
    );
    let h = ROOM_HALF;
    let (cols, rows) = (BANNER_COLUMNS, BANNER_ROWS);
    let (x0, x1, top, bottom, z) = (-0.5 * h, 0.5 * h, 1.8 * h, 0.4 * h, -0.7 * h);
    let mid = 0.5 * (top + bottom);
    let mut positions = Vec::new();
    let mut weights = Vec::new();
    for r in 0..=rows {
        let y = top + (bottom - top) * r as f32 / rows as f32;
        // Joint 1's weight: 0 down to the middle row, then growing to 1.
        let w = ((r as f32 - 0.5 * rows as f32) / (0.5 * rows as f32)).max(0.0);
        for c in 0..=cols {
            positions.push(Vec3::new(x0 + (x1 - x0) * c as f32 / cols as f32, y, z));
            weights.push(crate::math::Vec4::new(1.0 - w, w, 0.0, 0.0));
        }
    }
    let at = |r: u32, c: u32| r * (cols + 1) + c;
    let mut indices = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let (a, b, e, f) = (at(r, c), at(r, c + 1), at(r + 1, c + 1), at(r + 1, c));
            // Wound so that the geometric normal faces +Z (the camera).
            indices.push([a, f, e]);
            indices.push([a, e, b]);
        }
    }
    let n = positions.len();
    let prim = Primitive {
        positions,
        normals: Some(vec![Vec3::Z; n]),
        indices,
        joints: Some(vec![[0, 1, 0, 0]; n]),
        joint_weights: Some(weights),
        ..Default::default()
    };
    let mesh_node = d.add_mesh("banner", prim, cloth, Trs::default());
    let still = d.add_root(Node {
        name: "banner_still_joint".into(),
        ..Default::default()
    });
    let pivot = Vec3::new(0.0, mid, z);
    let swing = d.add_root(Node {
        name: "banner_swing_joint".into(),
        transform: Trs {
            translation: pivot,
            ..Default::default()
        },
        ..Default::default()
    });
    d.skins.push(super::desc::Skin {
        name: "banner".into(),
        joints: vec![still, swing],
        inverse_bind_matrices: vec![
            crate::math::Mat4::IDENTITY,
            crate::math::Mat4::from_translation(-pivot),
        ],
    });
    d.nodes[mesh_node.index()].skin = Some(SkinId(d.skins.len() as u32 - 1));
    // A turn by −θ about +X moves points below the pivot towards +Z.
    let rotation: Vec<f32> = [0.0f32, -0.7, 0.0]
        .iter()
        .flat_map(|&a| {
            let q = Quat::from_rotation_x(a);
            [q.x, q.y, q.z, q.w]
        })
        .collect();
    d.animations.push(Animation {
        name: "banner".into(),
        channels: vec![Channel {
            node: swing,
            target: ChannelTarget::Rotation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 0.5 * DEMO_DURATION, DEMO_DURATION],
            values: rotation,
            components: 4,
        }],
    });
    d
}

/// Names of the built-in scenes ([`builtin`]).
pub const BUILTIN_SCENES: [&str; 5] = ["demo", "caustic", "dolly", "flythrough", "banner"];

/// A built-in scene by name (`demo`, `caustic`, `dolly`, `flythrough`, `banner`).
pub fn builtin(name: &str) -> Option<SceneDesc> {
    match name {
        "demo" => Some(demo()),
        "caustic" => Some(caustic()),
        "dolly" => Some(dolly()),
        "flythrough" => Some(flythrough()),
        "banner" => Some(banner()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::{AnimationId, Mesh, Skin};

    /// A small content scene: two nodes (parent translated far away, child with a mesh),
    /// a material, an animation on the child.
    fn content() -> SceneDesc {
        let mut c = SceneDesc {
            name: "content".into(),
            ..Default::default()
        };
        c.materials.push(Material::diffuse("m", Rgb::splat(0.5)));
        c.meshes.push(Mesh {
            name: "box".into(),
            primitives: vec![Primitive {
                material: Some(MaterialId(0)),
                ..cube_primitive(3.0)
            }],
            weights: vec![],
        });
        c.nodes.push(Node {
            name: "parent".into(),
            children: vec![NodeId(1)],
            transform: Trs {
                translation: Vec3::new(100.0, -50.0, 7.0),
                ..Default::default()
            },
            ..Default::default()
        });
        c.nodes.push(Node {
            name: "child".into(),
            parent: Some(NodeId(0)),
            mesh: Some(MeshId(0)),
            transform: Trs {
                scale: Vec3::new(1.0, 2.0, 1.0),
                ..Default::default()
            },
            ..Default::default()
        });
        c.roots.push(NodeId(0));
        c.skins.push(Skin {
            name: "s".into(),
            joints: vec![NodeId(1)],
            inverse_bind_matrices: vec![crate::math::Mat4::IDENTITY],
        });
        c.animations.push(Animation {
            name: "spin".into(),
            channels: vec![Channel {
                node: NodeId(1),
                target: ChannelTarget::Translation,
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
                components: 3,
            }],
        });
        c
    }

    #[test]
    fn stage_fits_content_inside_room() {
        let staged = cornell_stage(content());
        let room = cornell_box();
        let content_nodes = room.nodes.len() + 1..staged.nodes.len();
        let pose = pose_at(&staged, None, 0.0);
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in content_nodes {
            if let Some(m) = staged.nodes[i].mesh {
                for p in &staged.meshes[m.index()].primitives {
                    for &q in &p.positions {
                        let w = pose.world[i].transform_point3(q);
                        lo = lo.min(w);
                        hi = hi.max(w);
                    }
                }
            }
        }
        assert!(lo.x >= -1.0 && lo.z >= -1.0 && lo.y >= 0.0, "{lo}");
        assert!(hi.x <= 1.0 && hi.z <= 1.0 && hi.y <= 2.0, "{hi}");
        assert!((lo.y - 1e-3).abs() < 1e-4, "stands on the floor: {lo}");
        assert!(
            ((hi - lo).max_element() - 1.2).abs() < 1e-4,
            "60 % of the room: {}",
            (hi - lo).max_element()
        );
        assert!(
            (lo.x + hi.x).abs() < 1e-4 && (lo.z + hi.z).abs() < 1e-4,
            "centred"
        );
        assert!(matches!(
            staged.cameras[0].projection,
            Projection::Perspective { .. }
        ));
        assert_eq!(staged.cameras[0].name, "stage_camera");
    }

    #[test]
    fn stage_remaps_ids_consistently() {
        let staged = cornell_stage(content());
        let n = staged.nodes.len();
        for (i, node) in staged.nodes.iter().enumerate() {
            assert!(
                node.parent.is_none_or(|p| p.index() < n
                    && staged.nodes[p.index()].children.contains(&NodeId(i as u32)))
            );
            assert!(
                node.children
                    .iter()
                    .all(|c| c.index() < n
                        && staged.nodes[c.index()].parent == Some(NodeId(i as u32)))
            );
            assert!(node.mesh.is_none_or(|m| m.index() < staged.meshes.len()));
            assert!(node.camera.is_none_or(|c| c.index() < staged.cameras.len()));
            assert!(node.light.is_none_or(|l| l.index() < staged.lights.len()));
            assert!(node.skin.is_none_or(|s| s.index() < staged.skins.len()));
        }
        for m in &staged.meshes {
            for p in &m.primitives {
                assert!(
                    p.material
                        .is_none_or(|x| x.index() < staged.materials.len())
                );
            }
        }
        assert_eq!(
            staged.topological_order().len(),
            n,
            "every node reachable exactly once"
        );
        let child = staged.nodes.iter().position(|x| x.name == "child").unwrap();
        assert_eq!(staged.animations[0].channels[0].node, NodeId(child as u32));
        assert_eq!(staged.skins[0].joints, vec![NodeId(child as u32)]);
        assert_eq!(
            staged.meshes[staged.nodes[child].mesh.unwrap().index()].name,
            "box"
        );
        // The animation still moves the child (by the stage scale).
        let a = pose_at(&staged, Some(AnimationId(0)), 0.0).world[child].w_axis;
        let b = pose_at(&staged, Some(AnimationId(0)), 1.0).world[child].w_axis;
        assert!((b - a).length() > 0.01);
    }

    #[test]
    fn caustic_occluder_enters_between_frames_3_and_4() {
        let d = builtin("caustic").unwrap();
        assert_eq!(d.animations[0].duration(), CAUSTIC_DURATION);
        let node = |name: &str| d.nodes.iter().position(|n| n.name == name).unwrap();
        let (occ, sphere) = (node("occluder"), node("glass_sphere"));
        // (lowest, highest) world y of node n's vertices at time t.
        let span_y = |n: usize, t: f32| {
            let pose = pose_at(&d, Some(AnimationId(0)), t);
            d.meshes[d.nodes[n].mesh.unwrap().index()].primitives[0]
                .positions
                .iter()
                .map(|&p| pose.world[n].transform_point3(p).y)
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), y| {
                    (lo.min(y), hi.max(y))
                })
        };
        // Frames 0–3 (24 fps): entirely under the floor; frames 4+: between the sphere's
        // top and the lamp (y = 1.98).
        for f in 0..4 {
            assert!(span_y(occ, f as f32 / 24.0).1 < 0.0, "frame {f}");
        }
        for f in 4..48 {
            let t = f as f32 / 24.0;
            let (lo, hi) = span_y(occ, t);
            assert!(lo > span_y(sphere, t).1 && hi < 1.98, "frame {f}");
        }
    }

    #[test]
    fn demo_is_two_seconds_and_well_formed() {
        let d = demo();
        assert_eq!(d.animations.len(), 1);
        assert_eq!(d.animations[0].name, "demo");
        assert_eq!(d.animations[0].duration(), 2.0);
        assert_eq!(d.find_animation("demo"), Some(AnimationId(0)));
        let sphere = d.meshes.iter().find(|m| m.name == "glass_sphere").unwrap();
        let tris = sphere.primitives[0].indices.len();
        assert!((1000..=2000).contains(&tris), "{tris}");
        let (lo, hi) = rest_bounds(&d).unwrap();
        assert!(
            lo.cmpge(Vec3::new(-1.0, 0.0, -1.0) - 1e-5).all()
                && hi.cmple(Vec3::new(1.0, 2.0, 1.0) + 1e-5).all()
        );
        // The cube stays inside the room during the clip.
        for f in 0..=48 {
            let pose = pose_at(&d, Some(AnimationId(0)), f as f32 / 24.0);
            let cube = d
                .nodes
                .iter()
                .position(|n| n.name == "sliding_cube")
                .unwrap();
            for &p in &d.meshes[d.nodes[cube].mesh.unwrap().index()].primitives[0].positions {
                let w = pose.world[cube].transform_point3(p);
                assert!(w.x.abs() <= 1.0 && w.z.abs() <= 1.0 && w.y >= -1e-5, "{w}");
            }
        }
    }

    #[test]
    fn flythrough_moves_only_the_camera() {
        let d = flythrough();
        assert_eq!(d.animations[0].name, "flythrough");
        assert_eq!(d.animations[0].duration(), DEMO_DURATION);
        let cam = d.nodes.iter().position(|n| n.camera.is_some()).unwrap();
        let clip = &d.animations[0];
        assert!(!clip.channels.is_empty());
        assert!(clip.channels.iter().all(|c| c.node.index() == cam));
        // The camera's path is the dolly's.
        let dolly = dolly();
        for f in [0, 17, 48] {
            let t = f as f32 / 24.0;
            let a = pose_at(&d, Some(AnimationId(0)), t).world[cam];
            let b = pose_at(&dolly, Some(AnimationId(0)), t).world[cam];
            assert!(a.abs_diff_eq(b, 1e-6), "frame {f}");
        }
    }

    #[test]
    fn dolly_camera_moves_and_keeps_the_room_centre_in_view() {
        let d = dolly();
        assert_eq!(d.animations[0].name, "dolly");
        assert_eq!(d.animations[0].duration(), DEMO_DURATION);
        let cam = d.nodes.iter().position(|n| n.camera.is_some()).unwrap();
        let mut prev: Option<Vec3> = None;
        for f in 0..=48 {
            let pose = pose_at(&d, Some(AnimationId(0)), f as f32 / 24.0);
            let m = pose.world[cam];
            let eye = m.transform_point3(Vec3::ZERO);
            let view = m.transform_vector3(-Vec3::Z).normalize();
            // The view ray passes within 2 % of the room's half-width of its centre
            // (exact at the keys; between them the nlerp'd yaw lags the truck slightly).
            let to_centre = Vec3::new(0.0, 1.0, 0.0) - eye;
            let miss = (to_centre - view * to_centre.dot(view)).length();
            assert!(
                miss < 0.02,
                "frame {f}: the view misses the centre by {miss}"
            );
            // Outside the room's front (z = 1) and moving every frame.
            assert!(eye.z > 3.2 && eye.x.abs() <= 0.3 + 1e-5, "{eye}");
            if let Some(p) = prev {
                assert!((eye - p).length() > 0.01, "frame {f} did not move");
            }
            prev = Some(eye);
        }
        // The demo's two cube channels plus the camera's two.
        assert_eq!(d.animations[0].channels.len(), 4);
        assert!(
            d.animations[0].channels[2..]
                .iter()
                .all(|c| c.node.index() == cam)
        );
    }

    #[test]
    fn room_normals_face_inward() {
        let d = cornell_box();
        for m in &d.meshes {
            let p = &m.primitives[0];
            for t in &p.indices {
                let [a, b, c] = t.map(|i| p.positions[i as usize]);
                let n = (b - a).cross(c - a).normalize();
                assert!(
                    n.dot(p.normals.as_ref().unwrap()[t[0] as usize]) > 0.99,
                    "{}",
                    m.name
                );
                // Inward: towards the room centre.
                assert!(n.dot(Vec3::new(0.0, 1.0, 0.0) - a) > 0.0, "{}", m.name);
            }
        }
    }

    #[test]
    fn sphere_normals_point_outward_and_match_winding() {
        let s = uv_sphere(1.0, 16, 8);
        for t in &s.indices {
            let [a, b, c] = t.map(|i| s.positions[i as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.length() > 0.0);
            assert!(n.dot(a + b + c) > 0.0);
        }
    }
}
