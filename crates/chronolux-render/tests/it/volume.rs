//! KHR_materials_volume: Beer–Lambert absorption along the world-space path inside a
//! transmissive closed mesh.
//!
//! The glass has ior 1 and roughness 0, so its interfaces neither reflect (Fresnel is 0 at
//! η = 1) nor bend rays: an orthographic camera looking through a slab of thickness d at a
//! uniform environment of radiance 1 sees exactly exp(−σ·d) in every pixel, with no noise
//! (every path is the same delta path: camera, entry face, exit face, environment).

use crate::frame0;
use chronolux_core::color::Rgb;
use chronolux_core::light::Environment;
use chronolux_core::math::{Quat, Vec3};
use chronolux_core::scene::desc::{
    CameraDesc, CameraId, Material, MaterialId, Mesh, MeshId, Node, NodeId, Primitive, Projection,
    SceneDesc, Trs, Volume,
};
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::kernels::path::{PathSettings, PathTracer};

/// An axis-aligned box [−1, 1]² × [−hz, hz], outward-facing winding.
fn slab(hz: f32) -> Primitive {
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z * hz);
    let positions = vec![
        p(-1., -1., -1.),
        p(1., -1., -1.),
        p(1., 1., -1.),
        p(-1., 1., -1.),
        p(-1., -1., 1.),
        p(1., -1., 1.),
        p(1., 1., 1.),
        p(-1., 1., 1.),
    ];
    let quads: [[u32; 4]; 6] = [
        [4, 5, 6, 7], // +z
        [1, 0, 3, 2], // −z
        [5, 1, 2, 6], // +x
        [0, 4, 7, 3], // −x
        [7, 6, 2, 3], // +y
        [0, 1, 5, 4], // −y
    ];
    let indices = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    Primitive {
        positions,
        indices,
        material: Some(MaterialId(0)),
        ..Default::default()
    }
}

fn glass(volume: Option<Volume>) -> Material {
    Material {
        name: "coloured glass".into(),
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.0,
        volume,
        ..Default::default()
    }
}

/// The slab (half-thickness `hz`) on a node scaled by `scale`, seen head-on by an
/// orthographic camera whose view (±0.5) lies inside the slab's ±1 face.
fn scene(hz: f32, scale: Vec3, volume: Option<Volume>) -> SceneDesc {
    SceneDesc {
        name: "volume slab".into(),
        nodes: vec![
            Node {
                name: "slab".into(),
                mesh: Some(MeshId(0)),
                transform: Trs {
                    scale,
                    ..Default::default()
                },
                ..Default::default()
            },
            Node {
                name: "camera".into(),
                camera: Some(CameraId(0)),
                transform: Trs {
                    translation: Vec3::new(0.0, 0.0, 20.0),
                    rotation: Quat::IDENTITY,
                    ..Default::default()
                },
                ..Default::default()
            },
        ],
        roots: vec![NodeId(0), NodeId(1)],
        meshes: vec![Mesh {
            name: "slab".into(),
            primitives: vec![slab(hz)],
            weights: vec![],
        }],
        materials: vec![glass(volume)],
        cameras: vec![CameraDesc {
            name: "ortho".into(),
            projection: Projection::Orthographic {
                xmag: 0.5,
                ymag: 0.5,
            },
        }],
        environment: Some(Environment::uniform(Rgb::ONE)),
        ..Default::default()
    }
}

fn render(d: SceneDesc) -> Vec<Rgb> {
    let scene = frame0(d, 8, 8);
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 4,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let img = pt.render(&scene, 0, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    img.pixels
}

/// Every pixel equals `want` per channel. Tolerance 1e-4 relative: the only error is the
/// segment length inside, shortened by the ray-origin offset at the entry face (a few
/// 1e-6 of the coordinates here) and f32 rounding of exp; σ·d ≤ 3.
fn assert_all(px: &[Rgb], want: Rgb, what: &str) {
    for p in px {
        let err = (*p - want).abs().max_element();
        assert!(
            err <= 1e-4 * want.max_element().max(1e-3),
            "{what}: {p} vs {want}"
        );
    }
}

#[test]
fn beer_lambert_through_a_slab() {
    // attenuationColor (0.5, 0.8, 1.0) at attenuationDistance 1: after one unit white light
    // has that colour; σ = (ln 2, −ln 0.8, 0).
    let c = Rgb::new(0.5, 0.8, 1.0);
    let v = Volume::from_attenuation(c, 1.0);
    // No volume: clear glass, 1 exactly.
    assert_all(&render(scene(0.5, Vec3::ONE, None)), Rgb::ONE, "clear");
    for d in [0.5f32, 1.0, 2.0] {
        let want = Rgb::new(c.x.powf(d), c.y.powf(d), c.z.powf(d));
        assert_all(
            &render(scene(0.5 * d, Vec3::ONE, Some(v))),
            want,
            &format!("slab of thickness {d}"),
        );
    }
    // Attenuation distance 2: half the coefficient.
    let v2 = Volume::from_attenuation(c, 2.0);
    let want = Rgb::new(c.x.sqrt(), c.y.sqrt(), 1.0);
    assert_all(&render(scene(0.5, Vec3::ONE, Some(v2))), want, "distance 2");
}

#[test]
fn attenuation_follows_the_world_space_path_of_a_scaled_mesh() {
    // The same mesh (thickness 0.5) on a node scaled 3× along the view: the path inside is
    // 1.5 world units; scaled across the view only, it stays 0.5.
    let c = Rgb::new(0.5, 0.8, 1.0);
    let v = Volume::from_attenuation(c, 1.0);
    let want = |d: f32| Rgb::new(c.x.powf(d), c.y.powf(d), c.z.powf(d));
    assert_all(
        &render(scene(0.25, Vec3::new(1.0, 1.0, 3.0), Some(v))),
        want(1.5),
        "scaled along the view",
    );
    assert_all(
        &render(scene(0.25, Vec3::new(2.0, 2.0, 1.0), Some(v))),
        want(0.5),
        "scaled across the view",
    );
}
