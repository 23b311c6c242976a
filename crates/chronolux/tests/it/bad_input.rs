//! Bad input: a non-zero exit, one `error:` line naming the problem, never a panic.

use crate::common::*;
use serde_json::json;
use std::path::Path;

/// `chronolux render SCENE --frames 0` at a tiny size into a fresh folder.
fn render_scene(scene: &Path, extra: &[&str]) -> std::process::Output {
    let out = temp_dir("bad-out");
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ];
    args.extend(FAST);
    args.extend(extra);
    run(&args)
}

/// `chronolux render` of the demo with `extra` (expected to fail before rendering).
fn render_demo(extra: &[&str]) -> std::process::Output {
    let out = temp_dir("bad-demo");
    let mut args = vec!["render", "--output", out.to_str().unwrap()];
    args.extend(extra);
    run(&args)
}

#[test]
fn missing_file() {
    let dir = temp_dir("missing");
    let p = dir.join("nothing here.glb");
    fails(
        &render_scene(&p, &[]),
        &["nothing here.glb", "no such file"],
    );
    fails(&run(["info", p.to_str().unwrap()]), &["nothing here.glb"]);
}

#[test]
fn directory_as_scene() {
    let dir = temp_dir("dirscene");
    fails(
        &render_scene(&dir, &[]),
        &[dir.to_str().unwrap(), "directory"],
    );
}

#[test]
fn truncated_glb() {
    let Some(p) = scene("BoxAnimated.glb") else {
        return;
    };
    let bytes = std::fs::read(p).unwrap();
    let dir = temp_dir("truncated");
    for len in [bytes.len() / 2, 30, 6, 0] {
        let p = dir.join(format!("cut{len}.glb"));
        std::fs::write(&p, &bytes[..len]).unwrap();
        fails(&render_scene(&p, &[]), &[&format!("cut{len}.glb")]);
    }
}

#[test]
fn json_that_is_not_gltf() {
    let dir = temp_dir("notgltf");
    let p = dir.join("hello.gltf");
    std::fs::write(&p, br#"{"hello": "world"}"#).unwrap();
    fails(&render_scene(&p, &[]), &["hello.gltf", "asset"]);
    std::fs::write(&p, b"not json at all").unwrap();
    fails(&render_scene(&p, &[]), &["hello.gltf"]);
}

#[test]
fn accessor_out_of_range() {
    let dir = temp_dir("accessor");
    let (mut v, buf) = tiny(&TRI, &[0, 1, 2]);
    v["accessors"][0]["count"] = json!(4);
    let p = write_gltf(&dir, &v, Some(&buf));
    fails(&render_scene(&p, &[]), &["POSITION"]);
    let (v, buf) = tiny(&TRI, &[0, 1, 7]);
    let p = write_gltf(&dir, &v, Some(&buf));
    fails(&render_scene(&p, &[]), &["indices"]);
}

#[test]
fn nan_and_inf_vertices() {
    let dir = temp_dir("nan");
    let (v, buf) = tiny(
        &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[0, 1, 2],
    );
    let p = write_gltf(&dir, &v, Some(&buf));
    fails(&render_scene(&p, &[]), &["POSITION", "NaN"]);
    let (v, buf) = tiny(
        &[[0.0, f32::INFINITY, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[0, 1, 2],
    );
    let p = write_gltf(&dir, &v, Some(&buf));
    fails(&render_scene(&p, &[]), &["POSITION"]);
}

#[test]
fn missing_external_buffer() {
    let dir = temp_dir("nobuffer");
    let (v, _) = tiny(&TRI, &[0, 1, 2]);
    let p = write_gltf(&dir, &v, None);
    fails(&render_scene(&p, &[]), &["buffer.bin"]);
}

#[test]
fn missing_texture() {
    let dir = temp_dir("notexture");
    let (mut v, buf) = tiny(&TRI, &[0, 1, 2]);
    v["images"] = json!([{"uri": "missing.png"}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let p = write_gltf(&dir, &v, Some(&buf));
    fails(&render_scene(&p, &[]), &["missing.png"]);
    // A corrupt image too.
    std::fs::write(dir.join("missing.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    fails(&render_scene(&p, &[]), &["missing.png"]);
}

#[test]
fn bad_resolution() {
    for (r, needle) in [
        ("0x10", "0x10"),
        ("100000x10", "100000x10"),
        ("abc", "abc"),
        ("24x", "24x"),
        ("-3x4", "resolution"),
    ] {
        fails(
            &render_demo(&["--resolution", r]),
            &["--resolution", needle],
        );
    }
    // Checked before a scene is loaded.
    let Some(p) = scene("BoxAnimated.glb") else {
        return;
    };
    let out = render_scene(&p, &["--resolution", "0x10"]);
    let err = fails(&out, &["--resolution"]);
    assert!(!stderr(&out).contains("warning"), "{err}");
}

#[test]
fn bad_spp() {
    fails(&render_demo(&["--spp", "0"]), &["--spp", "0"]);
    fails(
        &render_demo(&["--spp", "100000000"]),
        &["--spp", "100000000"],
    );
    fails(&render_demo(&["--spp", "99999999999"]), &["--spp"]);
    fails(&render_demo(&["--spp", "many"]), &["--spp", "many"]);
}

#[test]
fn bad_fps() {
    fails(&render_demo(&["--fps", "0"]), &["--fps"]);
    fails(&render_demo(&["--fps", "-24"]), &["--fps"]);
    fails(&render_demo(&["--fps", "NaN"]), &["--fps"]);
}

#[test]
fn frames_outside_the_animation_or_empty() {
    let Some(p) = scene("BoxAnimated.glb") else {
        return;
    };
    fails(
        &render_scene(&p, &["--frames", "0..500"]),
        &["--frames", "499", "ends at frame"],
    );
    fails(&render_demo(&["--frames", "5..5"]), &["--frames", "empty"]);
    fails(&render_demo(&["--frames", "3..1"]), &["--frames", "empty"]);
    fails(&render_demo(&["--frames", "x..2"]), &["--frames", "'x'"]);
    fails(&render_demo(&["--frames", "-1..2"]), &["--frames", "'-1'"]);
}

#[test]
fn unknown_animation_and_camera() {
    fails(&render_demo(&["--animation", "walk"]), &["walk", "demo"]);
    fails(&render_demo(&["--animation", "7"]), &["'7'"]);
    let Some(p) = scene("Cameras.gltf") else {
        return;
    };
    fails(
        &render_scene(&p, &["--camera", "drone"]),
        &["drone", "camera0", "camera1"],
    );
    fails(&render_scene(&p, &["--camera", "5"]), &["'5'"]);
    fails(
        &render_demo(&["--camera", "drone"]),
        &["drone", "stage_camera"],
    );
}

#[test]
fn unwritable_output_folder() {
    let dir = temp_dir("unwritable");
    let file = dir.join("a file");
    std::fs::write(&file, b"x").unwrap();
    let below = file.join("frames");
    let out = run([
        "render",
        "--frames",
        "0",
        "--resolution",
        "8x8",
        "--spp",
        "1",
        "--output",
        below.to_str().unwrap(),
    ]);
    let line = fails(&out, &["not writable", below.to_str().unwrap()]);
    // The OS reason once, not repeated by the cause chain.
    assert_eq!(line.matches("os error").count(), 1, "{line}");
}

#[test]
fn usage_errors_are_one_line() {
    fails(&run(["render", "--bogus"]), &["--bogus"]);
    fails(&run(["render", "--method", "magic"]), &["magic"]);
    fails(&run(["render", "--stage", "moon"]), &["moon"]);
    fails(&run(["info", "a.glb", "b.glb"]), &["b.glb"]);
    fails(&render_demo(&["--threads", "0"]), &["--threads"]);
    fails(&render_demo(&["--max-depth", "0"]), &["--max-depth"]);
    // A depth limit asked of a method without one: refused, naming those with one.
    fails(
        &render_demo(&["--method", "spt", "--max-depth", "3"]),
        &["--max-depth 3", "spt", "path, bdpt"],
    );
    // ic-selective's paged store in a folder that does not exist: said before any frame
    // (it panicked in the first frame).
    let missing = temp_dir("no-store").join("absent");
    fails(
        &render_demo(&[
            "--method",
            "ic-selective",
            "--set",
            "paged=true",
            "--set",
            &format!("store_dir={}", missing.display()),
        ]),
        &["store_dir", "absent"],
    );
    // --quality: a method without a measured table, an undenoised level not measured.
    fails(
        &render_demo(&["--method", "bdpt", "--quality", "final"]),
        &[
            "--quality",
            "bdpt",
            "no measured quality table",
            "spacetime-dept",
        ],
    );
    fails(
        &render_demo(&["--no-denoise", "--quality", "final"]),
        &["--quality final", "denoised renders only"],
    );
    fails(
        &render_demo(&["--quality", "ultra"]),
        &["ultra", "--quality"],
    );
    fails(
        &render_demo(&["--no-denoise", "--denoise-quality", "fast"]),
        &["--no-denoise", "cannot be used with", "--denoise-quality"],
    );
    // A missing required argument is named on the line (clap puts it on the next one).
    fails(
        &render_demo(&["--plan", "plan.json"]),
        &["not provided", "--segment"],
    );
    fails(
        &render_demo(&["--denoise", "--denoise-quality", "fastest"]),
        &["fastest", "--denoise-quality"],
    );
}

/// An animation channel whose `target.node` is out of range used to panic inside the gltf
/// crate (`gltf-1.4.1/src/animation/mod.rs:211`) from both `info` and `render`.
#[test]
fn animation_target_node_out_of_range() {
    let dir = temp_dir("animnode");
    let (mut v, buf) = tiny(&TRI, &[0, 1, 2]);
    v["animations"] = json!([{
        "channels": [{"sampler": 0, "target": {"node": 7, "path": "translation"}}],
        "samplers": [{"input": 1, "output": 0}]
    }]);
    let p = write_gltf(&dir, &v, Some(&buf));
    let want = ["animations[0].channels[0].target.node", "out of bounds"];
    fails(&render_scene(&p, &[]), &want);
    fails(&run(["info", p.to_str().unwrap()]), &want);
}

#[test]
fn view_with_a_bad_scene_or_a_port_in_use() {
    let dir = temp_dir("view-missing");
    let p = dir.join("nothing here.glb");
    fails(
        &run(["view", p.to_str().unwrap(), "--port", "0"]),
        &["nothing here.glb", "no such file"],
    );
    fails(
        &run(["view", "builtin:nope", "--port", "0"]),
        &["builtin:demo"],
    );
    // A port taken by another listener: the viewer must not start (and so the test
    // cannot hang on a server that runs until killed).
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    fails(
        &run(["view", "--port", &port, "--photons", "1000"]),
        &["cannot listen on 127.0.0.1", &port],
    );
    fails(
        &run(["view", "--bind", "not-an-address"]),
        &["not-an-address"],
    );
}

/// `--environment`: a missing file, a file that is no map, a truncated .hdr and a bad
/// strength are one clear error each; a good .hdr renders and run.json records it.
#[test]
fn environment_maps() {
    let dir = temp_dir("envmap");
    let missing = dir.join("nowhere.hdr");
    fails(
        &render_demo(&["--environment", missing.to_str().unwrap()]),
        &["--environment", "nowhere.hdr", "no such file"],
    );
    let text = dir.join("sky.png");
    std::fs::write(&text, b"not an image").unwrap();
    fails(
        &render_demo(&["--environment", text.to_str().unwrap()]),
        &["--environment", "OpenEXR (.exr) or Radiance HDR (.hdr)"],
    );
    let img = chronolux_io::image::Image::from_pixels(
        4,
        2,
        (0..8)
            .map(|i| chronolux_core::color::Rgb::splat(0.5 + i as f32))
            .collect(),
    );
    let good = dir.join("sky.hdr");
    let bytes = chronolux_io::envmap::encode_hdr(&img);
    std::fs::write(&good, &bytes).unwrap();
    let cut = dir.join("cut.hdr");
    std::fs::write(&cut, &bytes[..bytes.len() - 5]).unwrap();
    fails(
        &render_demo(&["--environment", cut.to_str().unwrap(), "--frames", "0"]),
        &["cut.hdr", "pixel data ends early"],
    );
    fails(
        &render_demo(&[
            "--environment",
            good.to_str().unwrap(),
            "--environment-strength",
            "-2",
        ]),
        &["--environment-strength"],
    );
    fails(
        &render_demo(&["--environment-strength", "2"]),
        &["--environment"],
    );
    let out = temp_dir("envmap-out");
    let mut args = vec![
        "render",
        "--output",
        out.to_str().unwrap(),
        "--environment",
        good.to_str().unwrap(),
        "--environment-strength",
        "2",
        "--environment-rotation",
        "30",
        "--environment-hidden",
        "--frames",
        "0",
        "--no-preview",
    ];
    args.extend(FAST);
    ok(&run(&args));
    let m = manifest(&out);
    let e = &m["settings"]["environment"];
    assert!(e["file"].as_str().unwrap().ends_with("sky.hdr"), "{e}");
    assert_eq!(e["strength"], 2.0);
    assert_eq!(e["rotation_deg"], 30.0);
    assert_eq!(e["hidden"], true);
}
