//! glTF loader tests against the shared development scenes and crafted bad inputs.
//!
//! Expected values are recomputed here from the files' own JSON and binary data (read with
//! a small independent GLB reader below), never taken from the loader.

use base64::Engine as _;
use chronolux_core::math::{Mat4, Quat, Vec3};
use chronolux_core::scene::anim::{deform_primitive, pose_at};
use chronolux_core::scene::desc::{LightKind, NodeId, Projection, SceneDesc};
use chronolux_io::gltf::{LoadError, load, load_slice};
use serde_json::{Value, json};
use std::path::PathBuf;

/// Path of a shared scene (`shared/scenes/` beside the repository), whether or not it
/// exists.
fn scene_path(name: &str) -> PathBuf {
    chronolux_core::testing::external::shared_path(&format!("scenes/{name}"))
}

/// A shared scene's path; `None` (the test returns) when it is missing outside CI, see
/// `chronolux_core::testing::external`.
fn scene(name: &str) -> Option<PathBuf> {
    chronolux_core::testing::shared_file(&format!("scenes/{name}"))
}

/// A shared scene, loaded; `None` as [`scene`].
fn load_ok(name: &str) -> Option<SceneDesc> {
    scene(name).map(|p| load(&p).unwrap_or_else(|e| panic!("{e}")))
}

fn node_by_name(d: &SceneDesc, name: &str) -> NodeId {
    NodeId(
        d.nodes
            .iter()
            .position(|n| n.name == name)
            .unwrap_or_else(|| panic!("no node {name}")) as u32,
    )
}

/// Independent reader of a GLB's JSON and accessors (float and unsigned integer, strided).
struct Glb {
    json: Value,
    bin: Vec<u8>,
}

impl Glb {
    fn open(name: &str) -> Glb {
        let b = std::fs::read(scene_path(name)).unwrap();
        let u = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap()) as usize;
        let jlen = u(12);
        let json: Value = serde_json::from_slice(&b[20..20 + jlen]).unwrap();
        let bo = 20 + jlen.div_ceil(4) * 4;
        let blen = u(bo);
        Glb {
            json,
            bin: b[bo + 8..bo + 8 + blen].to_vec(),
        }
    }

    /// Accessor `i` as f32 components (no normalisation: these files use float data).
    fn acc(&self, i: usize) -> Vec<f32> {
        let a = &self.json["accessors"][i];
        let v = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let n = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            t => panic!("{t}"),
        };
        let ct = a["componentType"].as_u64().unwrap();
        let cs = match ct {
            5121 => 1,
            5123 => 2,
            _ => 4,
        };
        let stride = v["byteStride"].as_u64().map_or(n * cs, |s| s as usize);
        let base = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let count = a["count"].as_u64().unwrap() as usize;
        let mut out = Vec::new();
        for e in 0..count {
            for c in 0..n {
                let o = base + e * stride + c * cs;
                let b = &self.bin[o..o + cs];
                out.push(match ct {
                    5121 => b[0] as f32,
                    5123 => u16::from_le_bytes([b[0], b[1]]) as f32,
                    5125 => u32::from_le_bytes(b.try_into().unwrap()) as f32,
                    _ => f32::from_le_bytes(b.try_into().unwrap()),
                });
            }
        }
        out
    }
}

// ---------------------------------------------------------------------------------------
// Shared scenes

#[test]
fn every_shared_scene_loads() {
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
        let Some(d) = load_ok(f) else {
            return;
        };
        assert!(
            !d.nodes.is_empty() && !d.roots.is_empty() && !d.meshes.is_empty(),
            "{f}"
        );
        assert_eq!(
            d.name,
            PathBuf::from(f).file_stem().unwrap().to_str().unwrap()
        );
        assert_eq!(
            d.topological_order().len(),
            d.nodes.len(),
            "{f}: every node reachable once"
        );
        for t in &d.textures {
            assert_eq!(
                t.rgba8.len(),
                (t.width * t.height) as usize,
                "{f}: {}",
                t.name
            );
        }
    }
}

#[test]
fn lights_punctual_lamp_has_five_point_lights_and_textures() {
    let Some(d) = load_ok("LightsPunctualLamp/LightsPunctualLamp.gltf") else {
        return;
    };
    assert_eq!(d.lights.len(), 5);
    assert!(
        d.lights
            .iter()
            .all(|l| l.kind == LightKind::Point && l.intensity > 0.0)
    );
    assert_eq!(d.nodes.iter().filter(|n| n.light.is_some()).count(), 5);
    let (lo, hi) = d.lights.iter().fold((f32::MAX, 0.0f32), |(a, b), l| {
        (a.min(l.intensity), b.max(l.intensity))
    });
    assert_eq!((lo, hi), (1.5, 180.0));
    assert_eq!(d.textures.len(), 7);
    assert!(d.materials.iter().any(|m| m.transmission > 0.0));
    assert!(d.environment.is_none());
}

#[test]
fn transmission_test_triangles_camera_and_warning() {
    let Some(d) = load_ok("TransmissionTest.glb") else {
        return;
    };
    assert_eq!(d.instanced_triangle_count(), 128_775);
    assert_eq!(d.cameras.len(), 1);
    assert!(d.materials.iter().any(|m| m.transmission == 1.0));
    assert!(d.materials.iter().any(|m| m.transmission_texture.is_some()));
    assert!(
        d.warnings.iter().any(|w| w.contains("KHR_xmp")),
        "{:?}",
        d.warnings
    );
}

#[test]
fn cameras_perspective_and_orthographic() {
    let Some(d) = load_ok("Cameras.gltf") else {
        return;
    };
    assert_eq!(d.cameras.len(), 2);
    assert_eq!(
        d.cameras
            .iter()
            .filter(|c| matches!(c.projection, Projection::Perspective { .. }))
            .count(),
        1
    );
    assert_eq!(
        d.cameras
            .iter()
            .filter(|c| matches!(c.projection, Projection::Orthographic { .. }))
            .count(),
        1
    );
    assert_eq!(d.nodes.iter().filter(|n| n.camera.is_some()).count(), 2);
}

#[test]
fn cornell_box_emissive_strength_100() {
    let Some(d) = load_ok("CornellBox.glb") else {
        return;
    };
    let e: Vec<_> = d
        .materials
        .iter()
        .filter(|m| m.emissive.max_element() > 0.0)
        .collect();
    assert_eq!(e.len(), 1);
    assert_eq!(e[0].emissive, Vec3::splat(100.0));
    assert!(
        d.environment.is_none(),
        "emissive scene needs no default light"
    );
    assert_eq!(d.instanced_triangle_count(), 36);
}

#[test]
fn unlit_scene_gets_default_environment_with_warning() {
    let Some(d) = load_ok("BoxAnimated.glb") else {
        return;
    };
    // Was `Some(Vec3::splat(1.0))` (uniform white, also the background) before issue 15.
    let env = d.environment.expect("default light");
    assert_eq!(env, chronolux_core::scene::desc::default_environment());
    assert!(env.zenith.x > env.nadir.x && env.background.x < env.nadir.x);
    assert!(
        d.warnings
            .iter()
            .any(|w| w.contains("no light") && w.contains("default environment"))
    );
    // No material → material None.
    let Some(t) = load_ok("AnimatedTriangle.gltf") else {
        return;
    };
    assert!(t.meshes[0].primitives[0].material.is_none());
}

// ---------------------------------------------------------------------------------------
// Animation: InterpolationTest

fn hermite(v0: f64, out0: f64, v1: f64, in1: f64, dt: f64, s: f64) -> f64 {
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * v0
        + (s3 - 2.0 * s2 + s) * dt * out0
        + (-2.0 * s3 + 3.0 * s2) * v1
        + (s3 - s2) * dt * in1
}

/// Expected value of a sampler at `t`, computed in f64 from the raw key data.
fn expected(
    interp: &str,
    rotation: bool,
    times: &[f32],
    vals: &[f32],
    n: usize,
    t: f32,
) -> Vec<f64> {
    let cubic = interp == "CUBICSPLINE";
    let stride = if cubic { 3 * n } else { n };
    let off = if cubic { n } else { 0 };
    let value = |k: usize| -> Vec<f64> {
        vals[k * stride + off..k * stride + off + n]
            .iter()
            .map(|&x| x as f64)
            .collect()
    };
    let last = times.len() - 1;
    if t <= times[0] {
        return value(0);
    }
    if t >= times[last] {
        return value(last);
    }
    let k = times.iter().rposition(|&x| x <= t).unwrap();
    let (t0, t1) = (times[k] as f64, times[k + 1] as f64);
    let dt = t1 - t0;
    let s = (t as f64 - t0) / dt;
    let (a, b) = (value(k), value(k + 1));
    let mut v: Vec<f64> = match interp {
        "STEP" => a,
        "LINEAR" if rotation => {
            let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let b: Vec<f64> = if dot < 0.0 {
                b.iter().map(|x| -x).collect()
            } else {
                b
            };
            let theta = dot.abs().min(1.0).acos();
            let (wa, wb) = if theta < 1e-6 {
                (1.0 - s, s)
            } else {
                (
                    ((1.0 - s) * theta).sin() / theta.sin(),
                    (s * theta).sin() / theta.sin(),
                )
            };
            a.iter().zip(&b).map(|(x, y)| wa * x + wb * y).collect()
        }
        "LINEAR" => a.iter().zip(&b).map(|(x, y)| x + (y - x) * s).collect(),
        _ => (0..n)
            .map(|i| {
                let out0 = vals[k * stride + 2 * n + i] as f64;
                let in1 = vals[(k + 1) * stride + i] as f64;
                hermite(a[i], out0, b[i], in1, dt, s)
            })
            .collect(),
    };
    if rotation {
        let len = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.iter_mut().for_each(|x| *x /= len);
    }
    v
}

#[test]
fn interpolation_test_matches_hand_computed_keys() {
    let Some(d) = load_ok("InterpolationTest.glb") else {
        return;
    };
    let g = Glb::open("InterpolationTest.glb");
    let anims = g.json["animations"].as_array().unwrap();
    assert_eq!(anims.len(), 9);
    assert_eq!(d.animations.len(), 9);
    let mut checked = 0;
    for a in anims {
        let name = a["name"].as_str().unwrap();
        let id = d
            .find_animation(name)
            .unwrap_or_else(|| panic!("clip {name}"));
        let ch = &a["channels"][0];
        let smp = &a["samplers"][ch["sampler"].as_u64().unwrap() as usize];
        let interp = smp["interpolation"].as_str().unwrap();
        let path = ch["target"]["path"].as_str().unwrap();
        let node_name = g.json["nodes"][ch["target"]["node"].as_u64().unwrap() as usize]["name"]
            .as_str()
            .unwrap();
        let node = node_by_name(&d, node_name);
        let times = g.acc(smp["input"].as_u64().unwrap() as usize);
        let vals = g.acc(smp["output"].as_u64().unwrap() as usize);
        let n = if path == "rotation" { 4 } else { 3 };
        let mut probe: Vec<f32> = times.clone();
        probe.extend(
            times
                .windows(2)
                .flat_map(|w| [0.5 * (w[0] + w[1]), w[0] + 0.3 * (w[1] - w[0])]),
        );
        probe.extend([times[0] - 0.5, times[times.len() - 1] + 1.0]);
        for &t in &probe {
            let pose = pose_at(&d, Some(id), t);
            let l = pose.local[node.index()];
            let got: Vec<f32> = match path {
                "translation" => l.translation.to_array().to_vec(),
                "scale" => l.scale.to_array().to_vec(),
                _ => l.rotation.to_array().to_vec(),
            };
            let want = expected(interp, path == "rotation", &times, &vals, n, t);
            let sign = if path == "rotation"
                && got
                    .iter()
                    .zip(&want)
                    .map(|(a, b)| *a as f64 * b)
                    .sum::<f64>()
                    < 0.0
            {
                -1.0
            } else {
                1.0
            };
            for (g, w) in got.iter().zip(&want) {
                assert!(
                    (*g as f64 - sign * w).abs() < 2e-5,
                    "{name} t={t}: got {got:?} want {want:?}"
                );
            }
            // At key times translation/scale equal the key exactly.
            if path != "rotation" && times.contains(&t) {
                let want32: Vec<f32> = want.iter().map(|&x| x as f32).collect();
                assert_eq!(got, want32, "{name} at key t={t}");
            }
            checked += 1;
        }
    }
    assert!(checked > 80);
}

#[test]
fn negative_scale_keeps_negative_determinant() {
    let mut v = tiny(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[0, 1, 2],
    );
    v["nodes"] = json!([
        {"name": "mirrored", "mesh": 0, "scale": [-1.0, 1.0, 1.0], "children": [1]},
        {"name": "matrix", "mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,-2,0, 3,4,5,1]}
    ]);
    let d = load_json(&v).unwrap();
    let pose = pose_at(&d, None, 0.0);
    let m = node_by_name(&d, "mirrored");
    let x = node_by_name(&d, "matrix");
    assert!(pose.world[m.index()].determinant() < 0.0);
    assert!(d.nodes[x.index()].transform.matrix().determinant() < 0.0);
    let want = Mat4::from_cols_array(&[
        1., 0., 0., 0., 0., 1., 0., 0., 0., 0., -2., 0., 3., 4., 5., 1.,
    ]);
    assert!(
        d.nodes[x.index()]
            .transform
            .matrix()
            .abs_diff_eq(want, 1e-6)
    );
    assert!(pose.world[x.index()].determinant() > 0.0, "mirror × mirror");
}

// ---------------------------------------------------------------------------------------
// Skinning and morphing

#[test]
fn rigged_simple_lbs_matches_hand_computation() {
    let Some(d) = load_ok("RiggedSimple.glb") else {
        return;
    };
    let g = Glb::open("RiggedSimple.glb");
    let prim_json = &g.json["meshes"][0]["primitives"][0];
    let attr = |s: &str| prim_json["attributes"][s].as_u64().unwrap() as usize;
    let pos = g.acc(attr("POSITION"));
    let joints = g.acc(attr("JOINTS_0"));
    let weights = g.acc(attr("WEIGHTS_0"));
    let skin = &g.json["skins"][0];
    let ibm = g.acc(skin["inverseBindMatrices"].as_u64().unwrap() as usize);
    let joint_names: Vec<&str> = skin["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| {
            g.json["nodes"][j.as_u64().unwrap() as usize]["name"]
                .as_str()
                .unwrap()
        })
        .collect();
    let mesh_node = node_by_name(&d, "Cylinder");
    let prim = &d.meshes[d.nodes[mesh_node.index()].mesh.unwrap().index()].primitives[0];
    // Vertices with one and with two influencing joints.
    let two = (0..pos.len() / 3)
        .find(|&v| weights[4 * v + 1] > 0.1)
        .unwrap();
    let one = (0..pos.len() / 3)
        .find(|&v| weights[4 * v + 1] == 0.0)
        .unwrap();
    let anim = d.find_animation("0").unwrap();
    let mut moved = false;
    for t in [0.0, 1.0] {
        let pose = pose_at(&d, Some(anim), t);
        let (skinned, _) = deform_primitive(&d, mesh_node, prim, &pose).unwrap();
        for v in [one, two] {
            let p = Vec3::new(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
            let mut acc = Vec3::ZERO;
            for k in 0..4 {
                let w = weights[4 * v + k];
                if w == 0.0 {
                    continue;
                }
                let j = joints[4 * v + k] as usize;
                let jw = pose.world[node_by_name(&d, joint_names[j]).index()];
                let inv = Mat4::from_cols_slice(&ibm[16 * j..16 * j + 16]);
                acc += w * (jw * inv).transform_point3(p);
            }
            assert!(
                (skinned[v] - acc).length() < 1e-4,
                "t={t} v={v}: {} vs {acc}",
                skinned[v]
            );
            moved |= t > 0.0 && (acc - p).length() > 1e-3;
        }
    }
    assert!(moved);
}

#[test]
fn animated_morph_cube_weights_and_positions() {
    let Some(d) = load_ok("AnimatedMorphCube.glb") else {
        return;
    };
    let g = Glb::open("AnimatedMorphCube.glb");
    let smp = &g.json["animations"][0]["samplers"][0];
    let times = g.acc(smp["input"].as_u64().unwrap() as usize);
    let vals = g.acc(smp["output"].as_u64().unwrap() as usize);
    assert_eq!(vals.len(), 2 * times.len());
    let pj = &g.json["meshes"][0]["primitives"][0];
    let base = g.acc(pj["attributes"]["POSITION"].as_u64().unwrap() as usize);
    let deltas: Vec<Vec<f32>> = (0..2)
        .map(|k| g.acc(pj["targets"][k]["POSITION"].as_u64().unwrap() as usize))
        .collect();
    let node = NodeId(0);
    let prim = &d.meshes[0].primitives[0];
    assert_eq!(d.meshes[0].weights, vec![0.0, 0.0]);
    let anim = d.find_animation("Square").unwrap();
    let mid = 0.5 * (times[3] + times[4]);
    let cases = [
        (times[3], [vals[6], vals[7]]),
        (times[10], [vals[20], vals[21]]),
        (mid, [0.5 * (vals[6] + vals[8]), 0.5 * (vals[7] + vals[9])]),
    ];
    let mut nonzero = false;
    for (t, w) in cases {
        let pose = pose_at(&d, Some(anim), t);
        let got = &pose.weights[node.index()];
        assert!(
            (got[0] - w[0]).abs() < 1e-6 && (got[1] - w[1]).abs() < 1e-6,
            "t={t}: {got:?} vs {w:?}"
        );
        let Some((p, _)) = deform_primitive(&d, node, prim, &pose) else {
            assert!(w == [0.0, 0.0]);
            continue;
        };
        nonzero = true;
        for v in [0, 5, 13] {
            let want = Vec3::from_slice(&base[3 * v..])
                + w[0] * Vec3::from_slice(&deltas[0][3 * v..])
                + w[1] * Vec3::from_slice(&deltas[1][3 * v..]);
            assert!((p[v] - want).length() < 1e-5, "t={t} v={v}");
        }
    }
    assert!(nonzero);
}

// ---------------------------------------------------------------------------------------
// Crafted files and error cases

fn b64(bytes: &[u8]) -> String {
    format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    )
}

/// A minimal glTF: one node, one mesh with POSITION (+ u16 indices), buffer as data: URI.
fn tiny(positions: &[[f32; 3]], indices: &[u16]) -> Value {
    let mut bytes: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let pos_len = bytes.len();
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let idx_len = bytes.len() - pos_len;
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bytes.len(), "uri": b64(&bytes)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": idx_len}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}
        ]
    })
}

fn load_json(v: &Value) -> Result<SceneDesc, LoadError> {
    load_slice(&serde_json::to_vec(v).unwrap(), None, "tiny.gltf")
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("chronolux-gltf-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn single_line(e: &LoadError) -> String {
    let s = e.to_string();
    assert!(!s.contains('\n'), "{s}");
    s
}

#[test]
fn tiny_scene_loads() {
    let d = load_json(&tiny(&TRI, &[0, 1, 2])).unwrap();
    assert_eq!(d.name, "tiny.gltf");
    assert_eq!(d.meshes[0].primitives[0].indices, vec![[0, 1, 2]]);
    assert!(d.meshes[0].primitives[0].material.is_none());
}

#[test]
fn error_missing_file() {
    let e = load(&scene_path("DoesNotExist.glb")).unwrap_err();
    assert!(matches!(e, LoadError::Io { .. }));
    assert!(single_line(&e).contains("DoesNotExist.glb"));
}

#[test]
fn error_truncated_glb() {
    let Some(p) = scene("BoxAnimated.glb") else {
        return;
    };
    let bytes = std::fs::read(p).unwrap();
    let dir = temp_dir("trunc");
    for (i, len) in [bytes.len() / 2, 30, 14, 6].into_iter().enumerate() {
        let p = dir.join(format!("truncated{i}.glb"));
        std::fs::write(&p, &bytes[..len]).unwrap();
        let e = load(&p).unwrap_err();
        let msg = single_line(&e);
        assert!(matches!(e, LoadError::NotGltf { .. }), "{msg}");
        assert!(msg.contains(&format!("truncated{i}.glb")), "{msg}");
    }
    // A GLB whose header length is below the header size must not underflow.
    let mut bad = bytes[..20].to_vec();
    bad[8..12].copy_from_slice(&4u32.to_le_bytes());
    assert!(load_slice(&bad, None, "bad.glb").is_err());
}

#[test]
fn error_json_not_gltf() {
    let e = load_slice(br#"{"hello": "world"}"#, None, "hello.gltf").unwrap_err();
    let msg = single_line(&e);
    assert!(
        matches!(e, LoadError::NotGltf { .. })
            && msg.contains("hello.gltf")
            && msg.contains("asset"),
        "{msg}"
    );
    let e = load_slice(b"not json at all", None, "text.gltf").unwrap_err();
    assert!(matches!(e, LoadError::NotGltf { .. }));
    let e = load_slice(br#"{"asset": {"version": "1.0"}}"#, None, "old.gltf").unwrap_err();
    assert!(single_line(&e).contains("1.0"));
}

#[test]
fn error_accessor_out_of_range() {
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["accessors"][0]["count"] = json!(4);
    let e = load_json(&v).unwrap_err();
    let msg = single_line(&e);
    assert!(
        msg.contains("meshes[0].primitives[0].attributes.POSITION"),
        "{msg}"
    );
    // A data: URI buffer shorter than its byteLength.
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["buffers"][0]["uri"] = json!(b64(&[0u8; 8]));
    let msg = single_line(&load_json(&v).unwrap_err());
    assert!(msg.contains("buffers[0]"), "{msg}");
    // Index beyond the vertex count.
    let msg = single_line(&load_json(&tiny(&TRI, &[0, 1, 7])).unwrap_err());
    assert!(
        msg.contains("meshes[0].primitives[0].indices") && msg.contains('7'),
        "{msg}"
    );
    // Accessor offset beyond its view.
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["accessors"][1]["byteOffset"] = json!(1_000_000_000u64);
    assert!(load_json(&v).is_err());
}

#[test]
fn error_nan_vertex() {
    let e = load_json(&tiny(
        &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[0, 1, 2],
    ))
    .unwrap_err();
    let msg = single_line(&e);
    assert!(msg.contains("POSITION") && msg.contains("NaN"), "{msg}");
    let e = load_json(&tiny(
        &[[0.0, f32::INFINITY, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[0, 1, 2],
    ))
    .unwrap_err();
    assert!(matches!(e, LoadError::Invalid { .. }));
}

#[test]
fn error_missing_external_buffer() {
    let dir = temp_dir("nobuf");
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["buffers"][0]["uri"] = json!("missing%20data.bin");
    let p = dir.join("scene.gltf");
    std::fs::write(&p, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = load(&p).unwrap_err();
    let msg = single_line(&e);
    assert!(
        matches!(e, LoadError::Resource { .. })
            && msg.contains("missing%20data.bin")
            && msg.contains("buffers[0]"),
        "{msg}"
    );
    // Without a base directory an external file cannot be resolved.
    assert!(matches!(
        load_json(&v).unwrap_err(),
        LoadError::Resource { .. }
    ));
    // The same buffer next to the file loads (percent-decoded name).
    let raw = base64::engine::general_purpose::STANDARD
        .decode(
            tiny(&TRI, &[0, 1, 2])["buffers"][0]["uri"]
                .as_str()
                .unwrap()
                .split(',')
                .nth(1)
                .unwrap(),
        )
        .unwrap();
    std::fs::write(dir.join("missing data.bin"), raw).unwrap();
    assert_eq!(load(&p).unwrap().meshes[0].primitives[0].indices.len(), 1);
}

#[test]
fn error_missing_texture() {
    let dir = temp_dir("notex");
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["images"] = json!([{"uri": "missing.png"}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let p = dir.join("scene.gltf");
    std::fs::write(&p, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = load(&p).unwrap_err();
    let msg = single_line(&e);
    assert!(
        matches!(e, LoadError::Resource { .. })
            && msg.contains("missing.png")
            && msg.contains("images[0]"),
        "{msg}"
    );
    // A corrupt image is an error too, not a panic.
    std::fs::write(dir.join("missing.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    assert!(load(&p).is_err());
}

/// A 2×1 RGB PNG (red, blue) made with the png crate.
fn red_blue_png() -> Vec<u8> {
    let mut png_bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut png_bytes, 2, 1);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()
        .unwrap()
        .write_image_data(&[255, 0, 0, 0, 0, 255])
        .unwrap();
    png_bytes
}

#[test]
fn a_png_header_claiming_terabytes_is_refused_before_allocating() {
    // libFuzzer found a GLB whose PNG header claimed 841 TB of pixels (the fuzz build
    // skips the png crate's CRC checks); the allocation aborted the process. Here a valid
    // PNG whose IHDR (CRC recomputed) says 2^20 × 2^20: refused, naming the limit.
    let mut png_bytes = red_blue_png();
    // Signature (8), IHDR length (4), "IHDR" (4), width, height, …, CRC over type + data.
    png_bytes[16..20].copy_from_slice(&(1u32 << 20).to_be_bytes());
    png_bytes[20..24].copy_from_slice(&(1u32 << 20).to_be_bytes());
    let crc = {
        let mut c = !0u32;
        for &b in &png_bytes[12..29] {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    (c >> 1) ^ 0xEDB8_8320
                } else {
                    c >> 1
                };
            }
        }
        !c
    };
    png_bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["images"] = json!([{"uri": format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png_bytes))}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let e = load_json(&v).unwrap_err();
    let msg = single_line(&e);
    assert!(
        msg.contains("texture limit") && msg.contains("1048576"),
        "{msg}"
    );
}

#[test]
fn texture_decoded_with_sampler_and_transform() {
    let png_bytes = red_blue_png();
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["extensionsUsed"] = json!(["KHR_texture_transform", "EXT_fancy_thing"]);
    v["images"] = json!([{"uri": format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png_bytes))}]);
    v["samplers"] = json!([{"magFilter": 9728, "wrapS": 33071, "wrapT": 33648}]);
    v["textures"] = json!([{"source": 0, "sampler": 0}]);
    v["materials"] = json!([{
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 0,
            "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.25], "scale": [2.0, 3.0], "texCoord": 1}}}},
        "emissiveFactor": [0.0, 0.0, 0.0]
    }]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let d = load_json(&v).unwrap();
    let t = &d.textures[0];
    assert_eq!((t.width, t.height), (2, 1));
    assert_eq!(t.rgba8, vec![[255, 0, 0, 255], [0, 0, 255, 255]]);
    assert!(!t.bilinear);
    use chronolux_core::scene::desc::WrapMode;
    assert_eq!(
        (t.wrap_s, t.wrap_t),
        (WrapMode::ClampToEdge, WrapMode::MirroredRepeat)
    );
    let r = d.materials[0].base_color_texture.unwrap();
    assert_eq!(r.uv_set, 1);
    assert_eq!(r.transform[0].x, 2.0);
    assert_eq!(r.transform[1].y, 3.0);
    assert_eq!(r.transform[2].to_array(), [0.5, 0.25]);
    assert_eq!(
        d.warnings
            .iter()
            .filter(|w| w.contains("EXT_fancy_thing"))
            .count(),
        1
    );
}

#[test]
fn error_unsupported_required_extension() {
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    v["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = load_json(&v).unwrap_err();
    let msg = single_line(&e);
    assert!(
        matches!(e, LoadError::UnsupportedExtension { .. })
            && msg.contains("KHR_draco_mesh_compression"),
        "{msg}"
    );
    // Supported required extensions (including KHR_materials_specular) are accepted.
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["extensionsUsed"] = json!(["KHR_materials_specular", "KHR_lights_punctual"]);
    v["extensionsRequired"] = json!(["KHR_materials_specular"]);
    v["materials"] = json!([{"extensions": {"KHR_materials_specular": {"specularFactor": 0.25, "specularColorFactor": [1.0, 0.5, 0.0]}}}]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let d = load_json(&v).unwrap();
    assert_eq!(d.materials[0].specular, 0.25);
    assert_eq!(d.materials[0].specular_color, Vec3::new(1.0, 0.5, 0.0));
    assert!(
        d.warnings.iter().all(|w| !w.contains("KHR_")),
        "{:?}",
        d.warnings
    );
}

#[test]
fn degenerate_triangles_skipped_and_counted() {
    let pos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [2.0, 0.0, 0.0],
    ];
    // Good, repeated index, collinear (zero area), good.
    let d = load_json(&tiny(&pos, &[0, 1, 2, 0, 0, 1, 0, 1, 3, 2, 1, 3])).unwrap();
    assert_eq!(
        d.meshes[0].primitives[0].indices,
        vec![[0, 1, 2], [2, 1, 3]]
    );
    let w: Vec<_> = d
        .warnings
        .iter()
        .filter(|w| w.contains("degenerate"))
        .collect();
    assert_eq!(w.len(), 1);
    assert!(w[0].contains("skipped 2 degenerate"), "{}", w[0]);
}

#[test]
fn strips_fans_and_points() {
    let pos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let mut v = tiny(&pos, &[0, 1, 2, 3]);
    v["meshes"][0]["primitives"][0]["mode"] = json!(5); // strip
    let d = load_json(&v).unwrap();
    assert_eq!(
        d.meshes[0].primitives[0].indices,
        vec![[0, 1, 2], [2, 1, 3]]
    );
    v["meshes"][0]["primitives"][0]["mode"] = json!(6); // fan
    let d = load_json(&v).unwrap();
    assert_eq!(
        d.meshes[0].primitives[0].indices,
        vec![[1, 2, 0], [2, 3, 0]]
    );
    v["meshes"][0]["primitives"][0]["mode"] = json!(0); // points
    let d = load_json(&v).unwrap();
    assert!(d.meshes[0].primitives.is_empty());
    assert!(
        d.warnings.iter().any(|w| w.contains("Points")),
        "{:?}",
        d.warnings
    );
}

#[test]
fn normalized_rotation_output_and_weights() {
    // Rotation key as normalized i16 (quarter turn about y = (0, 0.7071, 0, 0.7071)).
    let q = (0.70710677f32 * 32767.0).round() as i16;
    let mut bytes: Vec<u8> = TRI.iter().flatten().flat_map(|f| f.to_le_bytes()).collect(); // 36
    bytes.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes())); // 6
    bytes.extend([0u8; 2]); // pad to 44
    bytes.extend([0.0f32].iter().flat_map(|f| f.to_le_bytes())); // time, 4 → 48
    bytes.extend([0i16, q, 0, q].iter().flat_map(|i| i.to_le_bytes())); // 8 → 56
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["buffers"] = json!([{"byteLength": bytes.len(), "uri": b64(&bytes)}]);
    v["bufferViews"] = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 36},
        {"buffer": 0, "byteOffset": 36, "byteLength": 6},
        {"buffer": 0, "byteOffset": 44, "byteLength": 4},
        {"buffer": 0, "byteOffset": 48, "byteLength": 8}
    ]);
    v["accessors"] = json!([
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
        {"bufferView": 2, "componentType": 5126, "count": 1, "type": "SCALAR"},
        {"bufferView": 3, "componentType": 5122, "normalized": true, "count": 1, "type": "VEC4"}
    ]);
    v["animations"] = json!([{"name": "turn", "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}],
        "samplers": [{"input": 2, "output": 3, "interpolation": "LINEAR"}]}]);
    let d = load_json(&v).unwrap();
    let ch = &d.animations[0].channels[0];
    assert_eq!(ch.components, 4);
    assert!(
        (ch.values[1] - 0.70710677).abs() < 1e-4 && ch.values[0] == 0.0,
        "{:?}",
        ch.values
    );
    let pose = pose_at(&d, d.find_animation("turn"), 0.0);
    assert!(
        pose.local[0]
            .rotation
            .angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2))
            < 1e-3
    );
}

#[test]
fn bad_indices_and_singular_matrix_do_not_panic() {
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    v["nodes"][0]["extensions"] = json!({"KHR_lights_punctual": {"light": 5}});
    assert!(load_json(&v).is_err());
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["nodes"][0]["children"] = json!([0]);
    let msg = single_line(&load_json(&v).unwrap_err());
    assert!(msg.contains("nodes[0]"), "{msg}");
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["nodes"][0]["matrix"] = json!([0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3, 1]);
    let d = load_json(&v).unwrap();
    assert!(d.nodes[0].transform.rotation.is_finite());
    assert_eq!(d.nodes[0].transform.translation, Vec3::new(1.0, 2.0, 3.0));
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["accessors"][0]["count"] = json!(4_000_000_000u64);
    assert!(load_json(&v).is_err());
    v["accessors"][0]["bufferView"] = Value::Null;
    assert!(load_json(&v).is_err());
}

#[test]
fn shared_scenes_fit_the_cornell_stage() {
    use chronolux_core::scene::stage::{cornell_stage, rest_bounds};
    for f in [
        "RiggedSimple.glb",
        "CornellBox.glb",
        "InterpolationTest.glb",
        "AnimatedMorphCube.glb",
    ] {
        let Some(content) = load_ok(f) else {
            return;
        };
        let staged = cornell_stage(content);
        let (lo, hi) = rest_bounds(&staged).unwrap();
        assert!(
            lo.cmpge(Vec3::new(-1.0, 0.0, -1.0) - 1e-4).all()
                && hi.cmple(Vec3::new(1.0, 2.0, 1.0) + 1e-4).all(),
            "{f}: {lo} {hi}"
        );
        assert_eq!(staged.cameras[0].name, "stage_camera");
        assert_eq!(staged.topological_order().len(), staged.nodes.len());
        for a in 0..staged.animations.len() {
            let _ = pose_at(
                &staged,
                Some(chronolux_core::scene::desc::AnimationId(a as u32)),
                0.5,
            );
        }
    }
}

/// `tiny` plus a translation clip: key times at accessor 2 (t = 0, 1), values at accessor 3
/// ((0,0,0), (1,2,3)); `channels` is written as given.
fn tiny_animated(channels: Value) -> Value {
    let mut bytes: Vec<u8> = TRI.iter().flatten().flat_map(|f| f.to_le_bytes()).collect(); // 36
    bytes.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes())); // 6
    bytes.extend([0u8; 2]); // pad to 44
    bytes.extend([0.0f32, 1.0].iter().flat_map(|f| f.to_le_bytes())); // 8 → 52
    bytes.extend(
        [0.0f32, 0.0, 0.0, 1.0, 2.0, 3.0]
            .iter()
            .flat_map(|f| f.to_le_bytes()),
    ); // 24 → 76
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["buffers"] = json!([{"byteLength": bytes.len(), "uri": b64(&bytes)}]);
    v["bufferViews"] = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 36},
        {"buffer": 0, "byteOffset": 36, "byteLength": 6},
        {"buffer": 0, "byteOffset": 44, "byteLength": 8},
        {"buffer": 0, "byteOffset": 52, "byteLength": 24}
    ]);
    v["accessors"] = json!([
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
        {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR"},
        {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}
    ]);
    v["animations"] = json!([{"name": "move", "channels": channels,
        "samplers": [{"input": 2, "output": 3, "interpolation": "LINEAR"}]}]);
    v
}

#[test]
fn animation_target_node_out_of_range_is_an_error_not_a_panic() {
    // Used to panic in gltf-1.4.1 (animation/mod.rs:211): its validation skips channel
    // targets and `Target::node` unwraps.
    let v = tiny_animated(json!([{"sampler": 0, "target": {"node": 3, "path": "translation"}}]));
    let e = load_json(&v).unwrap_err();
    let msg = single_line(&e);
    assert!(
        matches!(e, LoadError::Invalid { .. })
            && msg.contains("animations[0].channels[0].target.node")
            && msg.contains("out of bounds"),
        "{msg}"
    );
    // An unknown property name is refused the same way (`Target::property` unwraps too).
    let v = tiny_animated(json!([{"sampler": 0, "target": {"node": 0, "path": "colour"}}]));
    let msg = single_line(&load_json(&v).unwrap_err());
    assert!(
        msg.contains("animations[0].channels[0].target.path"),
        "{msg}"
    );
}

#[test]
fn animation_channel_without_node_is_ignored_with_a_warning() {
    // glTF 2.0, animation.channel.target.node: "When undefined, the animated object MAY be
    // defined by an extension" — valid, and without such an extension there is nothing to
    // animate. The second channel (original index 1) is kept and animates node 0.
    let v = tiny_animated(json!([
        {"sampler": 0, "target": {"path": "translation"}},
        {"sampler": 0, "target": {"node": 0, "path": "translation"}}
    ]));
    let d = load_json(&v).unwrap();
    let warned: Vec<_> = d
        .warnings
        .iter()
        .filter(|w| w.contains("animations[0].channels[0]") && w.contains("no target.node"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", d.warnings);
    assert_eq!(d.animations[0].channels.len(), 1);
    let pose = pose_at(&d, d.find_animation("move"), 0.5);
    // Linear key interpolation halfway between (0,0,0) and (1,2,3); f32 rounding only.
    assert!(
        (pose.local[0].translation - Vec3::new(0.5, 1.0, 1.5)).length() < 1e-6,
        "{:?}",
        pose.local[0].translation
    );
    // Every channel without a node: an animation with no channels, still no panic.
    let v = tiny_animated(json!([{"sampler": 0, "target": {"path": "rotation"}}]));
    let d = load_json(&v).unwrap();
    assert!(d.animations[0].channels.is_empty());
}

#[test]
fn materials_volume_is_read_as_an_absorption_coefficient() {
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_volume"]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let glass = |volume: Value| {
        json!({"name": "glass", "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": volume}})
    };
    v["materials"] = json!([glass(json!({
        "thicknessFactor": 0.2, "attenuationDistance": 0.5,
        "attenuationColor": [0.25, 1.0, 0.5]}))]);
    let d = load_json(&v).unwrap();
    assert!(
        !d.warnings
            .iter()
            .any(|w| w.contains("KHR_materials_volume")),
        "{:?}",
        d.warnings
    );
    let vol = d.materials[0].volume.expect("volume read");
    // σ = −ln(c)/distance: white light has colour c after 0.5 world units.
    let want = Vec3::new(-(0.25f32.ln()) / 0.5, 0.0, -(0.5f32.ln()) / 0.5);
    assert!((vol.sigma_a - want).abs().max_element() < 1e-6, "{vol:?}");
    let t = vol.transmittance(0.5);
    assert!(
        (t - Vec3::new(0.25, 1.0, 0.5)).abs().max_element() < 1e-6,
        "{t}"
    );
    // thicknessFactor 0 (the default) is thin-walled by the spec: no volume, one warning.
    v["materials"] = json!([glass(json!({
        "attenuationColor": [0.5, 0.5, 0.5], "attenuationDistance": 1.0}))]);
    let d = load_json(&v).unwrap();
    assert!(d.materials[0].volume.is_none());
    assert!(
        d.warnings.iter().any(|w| w.contains("thin-walled")),
        "{:?}",
        d.warnings
    );
    // No attenuation given (white, infinite distance): nothing to absorb, no warning.
    v["materials"] = json!([glass(json!({"thicknessFactor": 1.0}))]);
    let d = load_json(&v).unwrap();
    assert!(d.materials[0].volume.is_none());
    // A required volume extension is now supported.
    v["extensionsRequired"] = json!(["KHR_materials_volume"]);
    assert!(load_json(&v).is_ok());
}

#[test]
fn external_uri_to_a_device_or_directory_is_an_error_not_a_hang() {
    // Reading `/dev/zero` as a buffer never ends (and exhausts memory).
    let dir = temp_dir("devzero");
    for uri in ["/dev/zero", "."] {
        let mut v = tiny(&TRI, &[0, 1, 2]);
        v["buffers"][0]["uri"] = json!(uri);
        let e = load_slice(&serde_json::to_vec(&v).unwrap(), Some(&dir), "dev.gltf").unwrap_err();
        let msg = single_line(&e);
        assert!(
            msg.contains("not a regular file") && msg.contains("buffers[0]"),
            "{msg}"
        );
    }
}

#[test]
fn position_accessor_out_of_range_is_an_error_not_a_panic() {
    // Found by the mutation fuzzer (tests/it/fuzz.rs): gltf-json's validation itself indexes
    // `accessors` with the POSITION index (gltf-json-1.4.1/src/mesh.rs:151).
    let mut v = tiny(&TRI, &[0, 1, 2]);
    v["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9);
    let msg = single_line(&load_json(&v).unwrap_err());
    assert!(
        msg.contains("meshes[0].primitives[0].attributes.POSITION")
            && msg.contains("out of bounds"),
        "{msg}"
    );
}

#[test]
fn huge_vertex_coordinates_are_an_error() {
    // Found by the mutation fuzzer: a vertex at −1.7e38 broke the BVH build downstream.
    let msg = single_line(
        &load_json(&tiny(
            &[[0.0, 0.0, 0.0], [-1.7e38, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[0, 1, 2],
        ))
        .unwrap_err(),
    );
    assert!(msg.contains("POSITION") && msg.contains("beyond"), "{msg}");
}

#[test]
fn image_without_source_or_mime_type_is_an_error_not_a_panic() {
    // Found by the mutation fuzzer: gltf-1.4.1's `Image::source` unwraps both.
    for image in [json!({}), json!({"bufferView": 0})] {
        let mut v = tiny(&TRI, &[0, 1, 2]);
        v["images"] = json!([image]);
        v["textures"] = json!([{"source": 0}]);
        v["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
        v["meshes"][0]["primitives"][0]["material"] = json!(0);
        let msg = single_line(&load_json(&v).unwrap_err());
        assert!(msg.contains("images[0]"), "{msg}");
    }
}

/// A glTF whose camera node is animated (LINEAR translation and rotation keys at t = 0 and
/// 1 s): the loaded clip moves the camera exactly as the keys say, the frame builder knows
/// the camera may move (what the temporal techniques read to treat view-dependent reuse),
/// and consecutive frames report a camera change. Expected values from the keys: at
/// t = 0.5 the translation is the keys' midpoint, and the rotation the slerp midpoint of
/// identity and 45° about +y, i.e. 22.5°, so the view direction −z turns to
/// (−sin 22.5°, 0, −cos 22.5°).
#[test]
fn an_animated_camera_moves_as_its_keys_say() {
    use chronolux_core::scene::delta::FrameDelta;
    use chronolux_core::scene::desc::AnimationId;
    use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
    use std::sync::Arc;
    let half = std::f32::consts::FRAC_PI_8; // 22.5°, half of the key's 45°
    let f32s = |v: &[f32]| -> Vec<u8> { v.iter().flat_map(|f| f.to_le_bytes()).collect() };
    let mut bytes = f32s(&TRI.concat()); // 36 bytes
    bytes.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes())); // 6 + 2 padding
    let times = bytes.len();
    bytes.extend(f32s(&[0.0, 1.0]));
    let trans = bytes.len();
    bytes.extend(f32s(&[0.0, 0.0, 3.0, 1.0, 0.5, 2.0]));
    let rot = bytes.len();
    bytes.extend(f32s(&[
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        half.sin(),
        0.0,
        half.cos(),
    ]));
    let gltf = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "name": "cam", "translation": [0.0, 0.0, 3.0]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bytes.len(), "uri": b64(&bytes)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": times, "byteLength": 8},
            {"buffer": 0, "byteOffset": trans, "byteLength": 24},
            {"buffer": 0, "byteOffset": rot, "byteLength": 32}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR",
             "min": [0.0], "max": [1.0]},
            {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"},
            {"bufferView": 4, "componentType": 5126, "count": 2, "type": "VEC4"}
        ],
        "animations": [{
            "channels": [
                {"sampler": 0, "target": {"node": 1, "path": "translation"}},
                {"sampler": 1, "target": {"node": 1, "path": "rotation"}}
            ],
            "samplers": [
                {"input": 2, "output": 3, "interpolation": "LINEAR"},
                {"input": 2, "output": 4, "interpolation": "LINEAR"}
            ]
        }]
    });
    let desc = Arc::new(load_json(&gltf).unwrap());
    assert_eq!(desc.animations.len(), 1);
    let mut b = FrameBuilder::new(
        desc.clone(),
        Some(AnimationId(0)),
        CameraChoice::First,
        8,
        8,
    )
    .unwrap();
    assert!(b.camera_may_move());
    let (f0, f1) = (b.build(0.0), b.build(0.5));
    let w = f1.camera.world_from_camera();
    let p = Vec3::from(w.translation);
    assert!((p - Vec3::new(0.5, 0.25, 2.5)).length() < 1e-5, "{p:?}");
    let fwd = w.transform_vector3(Vec3::new(0.0, 0.0, -1.0));
    // The key's quaternion holds sin/cos of half its 45°; the midpoint turns by 22.5° = `half`.
    let want = Vec3::new(-half.sin(), 0.0, -half.cos());
    assert!((fwd - want).length() < 1e-5, "{fwd:?} vs {want:?}");
    assert!(FrameDelta::between(&f0, &f1).camera_changed());
    assert!(!FrameDelta::between(&f1, &b.build(0.5)).camera_changed());
    // Without the clip the camera stands still.
    let still = FrameBuilder::new(desc, None, CameraChoice::First, 8, 8).unwrap();
    assert!(!still.camera_may_move());
}
