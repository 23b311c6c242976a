//! `chronolux info`: text and JSON summaries of shared scenes.

use crate::common::*;
use serde_json::Value;

/// `chronolux info --json` of a shared scene; `None` when it is missing (see
/// `common::scene`).
fn info_json(name: &str, extra: &[&str]) -> Option<Value> {
    let p = scene(name)?;
    let mut args = vec!["info", p.to_str().unwrap(), "--json"];
    args.extend(extra);
    let out = run(&args);
    ok(&out);
    Some(serde_json::from_str(&stdout(&out)).expect("info --json prints JSON"))
}

#[test]
fn animated_morph_cube_json() {
    let Some(v) = info_json("AnimatedMorphCube.glb", &[]) else {
        return;
    };
    assert!(v["triangles"].as_u64().unwrap() > 0);
    let anims = v["animations"].as_array().unwrap();
    assert!(!anims.is_empty());
    assert!(anims[0]["duration_s"].as_f64().unwrap() > 0.0);
    assert!(
        anims[0]["targets"]
            .as_array()
            .unwrap()
            .contains(&"weights".into()),
        "{v}"
    );
    assert!(!v["dynamic_nodes"].as_array().unwrap().is_empty(), "{v}");
}

#[test]
fn interpolation_test_json_and_clip_choice() {
    let Some(v) = info_json("InterpolationTest.glb", &[]) else {
        return;
    };
    assert_eq!(v["triangles"], 110);
    let anims = v["animations"].as_array().unwrap();
    assert!(anims.len() > 1);
    for (i, a) in anims.iter().enumerate() {
        assert_eq!(a["index"], i);
        assert!(a["duration_s"].as_f64().unwrap() > 0.0, "{a}");
        assert!(a["channels"].as_u64().unwrap() > 0);
    }
    // The first clip animates one node; another clip, another node.
    let first = v["dynamic_nodes"].as_array().unwrap().clone();
    assert_eq!(first.len(), 1, "{v}");
    let Some(other) = info_json("InterpolationTest.glb", &["--animation", "Linear Scale"]) else {
        return;
    };
    let second = other["dynamic_nodes"].as_array().unwrap().clone();
    assert_eq!(second.len(), 1, "{other}");
    assert_ne!(first, second);
}

#[test]
fn info_text() {
    for name in ["AnimatedMorphCube.glb", "InterpolationTest.glb"] {
        let Some(p) = scene(name) else {
            return;
        };
        let out = run(["info", p.to_str().unwrap()]);
        ok(&out);
        let text = stdout(&out);
        for key in [
            "triangles",
            "materials",
            "lights",
            "cameras",
            "animation",
            "dynamic",
        ] {
            assert!(text.contains(key), "{name}: no '{key}' in\n{text}");
        }
    }
}

#[test]
fn info_lists_unnamed_cameras_by_their_cli_name() {
    let Some(v) = info_json("Cameras.gltf", &[]) else {
        return;
    };
    let cams: Vec<&str> = v["cameras"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert_eq!(cams.len(), 2);
    assert!(cams[0].starts_with("camera0 (perspective"), "{cams:?}");
    assert!(cams[1].starts_with("camera1 (orthographic"), "{cams:?}");
}

#[test]
fn long_lists_are_wrapped_and_summarised_and_warnings_print_once_on_stderr() {
    // 40 animated nodes (a rig's joints in miniature): `info` shows a wrapped, shortened
    // list; `--json` keeps all 40. An unsupported optional extension warns once, on stderr.
    let dir = temp_dir("info-long-lists");
    let (mut v, mut bytes) = tiny(&TRI, &[0, 1, 2]);
    let times = bytes.len();
    bytes.extend([0.0f32, 1.0].iter().flat_map(|f| f.to_le_bytes()));
    let moves = bytes.len();
    bytes.extend(
        [0.0f32, 0.0, 0.0, 0.0, 1.0, 0.0]
            .iter()
            .flat_map(|f| f.to_le_bytes()),
    );
    v["buffers"][0]["byteLength"] = bytes.len().into();
    v["bufferViews"].as_array_mut().unwrap().extend([
        serde_json::json!({"buffer": 0, "byteOffset": times, "byteLength": 8}),
        serde_json::json!({"buffer": 0, "byteOffset": moves, "byteLength": 24}),
    ]);
    v["accessors"].as_array_mut().unwrap().extend([
        serde_json::json!({"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR",
                           "min": [0.0], "max": [1.0]}),
        serde_json::json!({"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}),
    ]);
    let n = 40;
    let nodes: Vec<Value> = (0..n)
        .map(|i| serde_json::json!({"name": format!("a_rather_long_joint_name_{i:03}"), "mesh": 0}))
        .collect();
    v["nodes"] = nodes.into();
    v["scenes"][0]["nodes"] = (0..n).collect::<Vec<_>>().into();
    v["animations"] = serde_json::json!([{
        "samplers": [{"input": 2, "output": 3}],
        "channels": (0..n).map(|i| serde_json::json!({"sampler": 0, "target": {"node": i, "path": "translation"}})).collect::<Vec<_>>()
    }]);
    v["extensionsUsed"] = serde_json::json!(["EXT_made_up_for_this_test"]);
    let p = write_gltf(&dir, &v, Some(&bytes));
    let out = run(["info", p.to_str().unwrap()]);
    ok(&out);
    let text = stdout(&out);
    assert!(text.lines().all(|l| l.chars().count() <= 100), "{text}");
    assert!(
        text.contains("… and 28 more (40 in all; --json lists them)"),
        "{text}"
    );
    assert!(
        !text.contains("EXT_made_up_for_this_test"),
        "warnings go to stderr: {text}"
    );
    assert_eq!(
        stderr(&out).matches("EXT_made_up_for_this_test").count(),
        1,
        "{}",
        stderr(&out)
    );
    let json = run(["info", p.to_str().unwrap(), "--json"]);
    let j: Value = serde_json::from_str(&stdout(&json)).unwrap();
    assert_eq!(j["dynamic_nodes"].as_array().unwrap().len(), n);
}
