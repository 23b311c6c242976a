//! Scenes built in code with answers that can be derived by hand.

use super::desc::{
    CameraDesc, CameraId, Material, MaterialId, Mesh, MeshId, Node, NodeId, Primitive, Projection,
    SceneDesc, Trs,
};
use crate::color::Rgb;
use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

/// A UV sphere of `radius` around the origin with `seg` segments and `rings` rings,
/// normals outward (or inward, with the winding reversed, when `inward`).
pub fn uv_sphere(radius: f32, seg: u32, rings: u32, inward: bool) -> Primitive {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=seg {
            let phi = 2.0 * PI * s as f32 / seg as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            positions.push(n * radius);
            normals.push(if inward { -n } else { n });
            uvs.push(Vec2::new(s as f32 / seg as f32, r as f32 / rings as f32));
        }
    }
    let mut indices = Vec::new();
    let w = seg + 1;
    for r in 0..rings {
        for s in 0..seg {
            let (a, b, c, d) = (
                r * w + s,
                r * w + s + 1,
                (r + 1) * w + s,
                (r + 1) * w + s + 1,
            );
            // Outward-facing counter-clockwise order; the pole rows lose a degenerate triangle.
            let mut tris = vec![];
            if r != 0 {
                tris.push([a, c, b]);
            }
            if r != rings - 1 {
                tris.push([b, c, d]);
            }
            for mut t in tris {
                if inward {
                    t.swap(1, 2);
                }
                indices.push(t);
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

/// A scene with one mesh node and one camera node.
pub fn single_mesh_scene(
    name: &str,
    prim: Primitive,
    material: Material,
    camera: Trs,
    yfov: f32,
) -> SceneDesc {
    let mut prim = prim;
    prim.material = Some(MaterialId(0));
    SceneDesc {
        name: name.into(),
        nodes: vec![
            Node {
                name: "mesh".into(),
                mesh: Some(MeshId(0)),
                ..Default::default()
            },
            Node {
                name: "camera".into(),
                camera: Some(CameraId(0)),
                transform: camera,
                ..Default::default()
            },
        ],
        roots: vec![NodeId(0), NodeId(1)],
        meshes: vec![Mesh {
            name: "mesh".into(),
            primitives: vec![prim],
            weights: vec![],
        }],
        materials: vec![material],
        cameras: vec![CameraDesc {
            name: "camera".into(),
            projection: Projection::Perspective {
                yfov,
                aspect: None,
                znear: 0.01,
            },
        }],
        ..Default::default()
    }
}

/// White furnace: the inside of a closed sphere with diffuse albedo `albedo` emitting
/// `le` everywhere. Every surface point sees radiance L = Le + a·L, so L = Le / (1 − a)
/// in every pixel (for unlimited path depth).
pub fn furnace(albedo: f32, le: f32) -> SceneDesc {
    let mut m = Material::diffuse("furnace", Rgb::splat(albedo));
    m.emissive = Rgb::splat(le);
    single_mesh_scene(
        "furnace",
        uv_sphere(1.0, 48, 24, true),
        m,
        Trs::default(),
        1.2,
    )
}
