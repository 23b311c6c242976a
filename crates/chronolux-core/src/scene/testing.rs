//! Scenes built in code with answers that can be derived by hand.

use super::desc::{
    CameraDesc, CameraId, Material, MaterialId, Mesh, MeshId, Node, NodeId, Primitive, Projection,
    SceneDesc, Trs,
};
use super::stage;
use crate::color::Rgb;

/// A UV sphere (see [`stage::uv_sphere`]) with normals outward, or inward with the winding
/// reversed when `inward`.
pub fn uv_sphere(radius: f32, seg: u32, rings: u32, inward: bool) -> Primitive {
    let mut p = stage::uv_sphere(radius, seg, rings);
    if inward {
        p.indices.iter_mut().for_each(|t| t.swap(1, 2));
        if let Some(n) = p.normals.as_mut() {
            n.iter_mut().for_each(|v| *v = -*v);
        }
    }
    p
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
