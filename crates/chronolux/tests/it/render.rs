//! `chronolux render`: output layout, manifest, resume, shared scenes, determinism, UX.

use crate::common::*;
use std::path::Path;
use std::time::SystemTime;

fn frame_files(dir: &Path, frames: &[u32]) {
    for f in frames {
        for ext in ["exr", "png"] {
            let p = dir.join(format!("frame_{f:04}.{ext}"));
            assert!(p.is_file(), "missing {}", p.display());
        }
    }
}

fn mtimes(dir: &Path, frames: &[u32]) -> Vec<SystemTime> {
    frames
        .iter()
        .flat_map(|f| {
            ["exr", "png"].map(|ext| {
                std::fs::metadata(dir.join(format!("frame_{f:04}.{ext}")))
                    .unwrap()
                    .modified()
                    .unwrap()
            })
        })
        .collect()
}

fn render_demo(dir: &Path, extra: &[&str]) -> String {
    let mut args = vec!["render", "--output", dir.to_str().unwrap()];
    args.extend(FAST);
    args.extend(extra);
    ok(&run(&args))
}

#[test]
fn demo_three_frames_manifest_preview_and_resume() {
    let dir = temp_dir("demo3");
    let err = render_demo(&dir, &["--frames", "0..3"]);
    frame_files(&dir, &[0, 1, 2]);
    assert!(!dir.join("frame_0003.exr").exists());
    assert!(dir.join("preview.gif").is_file());
    let m = manifest(&dir);
    let frames = m["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    for (i, r) in frames.iter().enumerate() {
        assert_eq!(r["frame"], i as u64);
        assert!(r["wall_s"].as_f64().unwrap() > 0.0);
        assert!(r["stats"]["rays"].as_u64().unwrap() > 0);
        assert_eq!(r["stats"]["samples"].as_u64().unwrap(), 24 * 24 * 2);
        let t = r["time_s"].as_f64().unwrap();
        assert!((t - i as f64 / 24.0).abs() < 1e-6, "{t}");
    }
    assert_eq!(m["settings"]["resolution"], serde_json::json!([24, 24]));
    // Without --method, `render` uses the registry's default technique (spacetime-dept,
    // whose `spp` is its eye pass's camera samples).
    assert_eq!(m["settings"]["method"], "spacetime-dept");
    assert_eq!(m["settings"]["technique"]["spp"], 2);
    assert_eq!(m["settings"]["fps"], 24.0);
    assert!(m["finished"].is_string());
    assert!(m["scene"]["triangles"].as_u64().unwrap() > 0);
    // Off a terminal: no progress bar, one line per frame.
    assert!(!err.contains('\r') && !err.contains("ETA"), "{err}");
    for f in 0..3 {
        assert!(err.contains(&format!("frame {f} [{}/3]", f + 1)), "{err}");
    }
    assert!(
        !err.contains("warning"),
        "the demo renders without warnings:\n{err}"
    );

    // --resume: every frame complete, nothing re-rendered.
    let before = mtimes(&dir, &[0, 1, 2]);
    std::thread::sleep(std::time::Duration::from_millis(20));
    let err = render_demo(&dir, &["--frames", "0..3", "--resume"]);
    assert_eq!(err.matches("skipped").count(), 3, "{err}");
    assert_eq!(mtimes(&dir, &[0, 1, 2]), before);
    assert_eq!(manifest(&dir)["frames"].as_array().unwrap().len(), 3);

    // A deleted frame is rendered again, the others are kept.
    std::fs::remove_file(dir.join("frame_0001.png")).unwrap();
    let err = render_demo(&dir, &["--frames", "0..3", "--resume"]);
    assert_eq!(err.matches("skipped").count(), 2, "{err}");
    frame_files(&dir, &[0, 1, 2]);
    let after = mtimes(&dir, &[0, 1, 2]);
    assert_eq!(after[0..2], before[0..2]);
    assert_eq!(after[4..6], before[4..6]);
    assert_ne!(after[2..4], before[2..4]);

    // Resuming with other settings would mix sequences: refused.
    let out = run([
        "render",
        "--output",
        dir.to_str().unwrap(),
        "--resolution",
        "24x24",
        "--spp",
        "3",
        "--frames",
        "0..3",
        "--resume",
    ]);
    fails(&out, &["--resume", "spp"]);
}

#[test]
fn inclusive_range_gives_the_same_frames() {
    let a = temp_dir("excl");
    let b = temp_dir("incl");
    render_demo(&a, &["--frames", "0..3", "--no-preview"]);
    render_demo(&b, &["--frames", "0..=2", "--no-preview"]);
    frame_files(&b, &[0, 1, 2]);
    assert!(!b.join("frame_0003.exr").exists());
    assert!(!b.join("preview.gif").exists());
    assert_eq!(
        manifest(&a)["settings"]["frames"],
        manifest(&b)["settings"]["frames"]
    );
    for f in 0..3 {
        let name = format!("frame_{f:04}.exr");
        assert_eq!(
            std::fs::read(a.join(&name)).unwrap(),
            std::fs::read(b.join(&name)).unwrap(),
            "{name}"
        );
    }
}

#[test]
fn same_seed_gives_identical_exr_bytes() {
    let a = temp_dir("seed-a");
    let b = temp_dir("seed-b");
    let c = temp_dir("seed-c");
    render_demo(&a, &["--frames", "5", "--seed", "7"]);
    render_demo(&b, &["--frames", "5", "--seed", "7"]);
    render_demo(&c, &["--frames", "5", "--seed", "8"]);
    let read = |d: &Path| std::fs::read(d.join("frame_0005.exr")).unwrap();
    assert_eq!(read(&a), read(&b));
    assert_ne!(read(&a), read(&c), "the seed must change the noise");
}

#[test]
fn thread_count_does_not_change_pixels() {
    let a = temp_dir("threads1");
    let b = temp_dir("threads2");
    render_demo(&a, &["--frames", "3", "--threads", "1"]);
    render_demo(&b, &["--frames", "3", "--threads", "2"]);
    assert_eq!(manifest(&a)["settings"]["threads"], 1);
    assert_eq!(manifest(&b)["settings"]["threads"], 2);
    let ia = chronolux_io::image::read_exr(a.join("frame_0003.exr")).unwrap();
    let ib = chronolux_io::image::read_exr(b.join("frame_0003.exr")).unwrap();
    assert_eq!((ia.width, ia.height), (24, 24));
    assert!(ia.mean_value() > 0.0);
    let bits = |i: &chronolux_io::image::Image| -> Vec<[u32; 3]> {
        i.pixels
            .iter()
            .map(|p| [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()])
            .collect()
    };
    assert_eq!(bits(&ia), bits(&ib));
}

#[test]
fn box_animated_renders_with_default_light_message() {
    let dir = temp_dir("box");
    let Some(p) = scene("BoxAnimated.glb") else {
        return;
    };
    let mut args = vec![
        "render",
        p.to_str().unwrap(),
        "--frames",
        "10..12",
        "--output",
        dir.to_str().unwrap(),
    ];
    args.extend(FAST);
    let err = ok(&run(&args));
    frame_files(&dir, &[10, 11]);
    // No light in the file: the default environment, said once.
    assert_eq!(err.matches("no light").count(), 1, "{err}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("warning: ") && l.contains("environment"))
    );
    assert_eq!(manifest(&dir)["scene"]["environment_light"], true);
}

#[test]
fn rigged_simple_in_cornell_stage() {
    let dir = temp_dir("rigged");
    let Some(p) = scene("RiggedSimple.glb") else {
        return;
    };
    let mut args = vec![
        "render",
        p.to_str().unwrap(),
        "--stage",
        "cornell",
        "--frames",
        "0..=1",
        "--output",
        dir.to_str().unwrap(),
    ];
    args.extend(FAST);
    let err = ok(&run(&args));
    frame_files(&dir, &[0, 1]);
    let m = manifest(&dir);
    assert_eq!(m["settings"]["stage"], "cornell");
    // The stage brings its own light: no default environment.
    assert_eq!(m["scene"]["environment_light"], false, "{err}");
    let img = chronolux_io::image::read_exr(dir.join("frame_0001.exr")).unwrap();
    assert!(img.mean_value() > 0.0);
}

#[test]
fn animation_by_index_and_name() {
    let Some(p) = scene("InterpolationTest.glb") else {
        return;
    };
    let render = |anim: &str| {
        let dir = temp_dir("anim");
        let mut args = vec![
            "render",
            p.to_str().unwrap(),
            "--animation",
            anim,
            "--frames",
            "0",
            "--output",
            dir.to_str().unwrap(),
        ];
        args.extend(FAST);
        ok(&run(&args));
        let m = manifest(&dir);
        (
            m["settings"]["animation"].as_str().unwrap().to_string(),
            std::fs::read(dir.join("frame_0000.exr")).unwrap(),
        )
    };
    let (by_index, img_i) = render("1");
    let (by_name, img_n) = render("Linear Scale");
    assert_eq!(by_index, "Linear Scale");
    assert_eq!(by_name, "Linear Scale");
    assert_eq!(img_i, img_n);
}

#[test]
fn camera_by_name_and_index_orthographic_renders() {
    let Some(p) = scene("Cameras.gltf") else {
        return;
    };
    let render = |cam: &str| {
        let dir = temp_dir("cam");
        let mut args = vec![
            "render",
            p.to_str().unwrap(),
            "--camera",
            cam,
            "--output",
            dir.to_str().unwrap(),
        ];
        args.extend(FAST);
        ok(&run(&args));
        chronolux_io::image::read_exr(dir.join("frame_0000.exr")).unwrap()
    };
    let persp = render("camera0");
    let ortho = render("camera1");
    let ortho_by_index = render("1");
    assert_eq!(ortho.pixels, ortho_by_index.pixels);
    assert_ne!(
        persp.pixels, ortho.pixels,
        "the two cameras see differently"
    );
    // The orthographic view shows the quad in front of the environment: not uniform.
    let lum: Vec<f32> = ortho.pixels.iter().map(|p| p[0] + p[1] + p[2]).collect();
    let (lo, hi) = lum
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(lo.is_finite() && hi > lo + 1e-3, "uniform image {lo}..{hi}");
}

#[test]
fn degenerate_triangles_are_counted_and_skipped() {
    let dir = temp_dir("degenerate");
    let (v, buf) = tiny(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0],
        ],
        &[0, 1, 2, 0, 0, 1, 0, 1, 3],
    );
    let p = write_gltf(&dir, &v, Some(&buf));
    let out = dir.join("out");
    let mut args = vec![
        "render",
        p.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ];
    args.extend(FAST);
    let err = ok(&run(&args));
    assert!(
        err.lines()
            .any(|l| l.starts_with("warning: ") && l.contains("2 degenerate triangle")),
        "{err}"
    );
    frame_files(&out, &[0]);
}

#[test]
fn render_help_mentions_every_flag() {
    let out = run(["render", "--help"]);
    assert!(out.status.success());
    let help = stdout(&out);
    for flag in [
        "--frames",
        "--fps",
        "--spp",
        "--resolution",
        "--max-depth",
        "--method",
        "--seed",
        "--threads",
        "--output",
        "--stage",
        "--resume",
        "--animation",
        "--camera",
        "--exposure",
        "--no-preview",
        "[SCENE]",
    ] {
        assert!(help.contains(flag), "--help lacks {flag}:\n{help}");
    }
    // Explains, not just lists: the half-open range and Mitsuba's depth convention.
    assert!(
        help.contains("A..=B") && help.contains("max_depth"),
        "{help}"
    );
}

/// The lists in `--help` come from the registry's capabilities, so none can miss a
/// technique (the hand-written `--photons` list once omitted `spt`): each flag's section
/// names exactly the techniques that take it, with the default `render` would use.
#[test]
fn render_help_lists_the_techniques_from_the_registry() {
    use chronolux_render::registry::{self, TECHNIQUES};
    let out = run(["render", "--help"]);
    let help = stdout(&out);
    let section = |flag: &str| -> String {
        let start = help
            .find(&format!("      {flag} "))
            .unwrap_or_else(|| panic!("{flag} missing:\n{help}"));
        let rest = &help[start + flag.len() + 6..];
        let end = rest.find("\n      --").unwrap_or(rest.len());
        rest[..end].to_string()
    };
    let listed = |text: &str, name: &str| {
        text.lines()
            .any(|l| l.split_whitespace().next() == Some(name))
    };
    let (spp, photons, window) = (section("--spp"), section("--photons"), section("--window"));
    for t in TECHNIQUES {
        let c = t.capabilities();
        let start = registry::quality_settings(*t, None, true, None)
            .unwrap()
            .map_or_else(|| t.defaults(), |(s, _)| s);
        let n = t.common(&start).unwrap().spp;
        assert!(
            spp.lines()
                .any(|l| l.split_whitespace().take(2).eq([t.name(), &n.to_string()])),
            "--spp: {} {n}:\n{spp}",
            t.name()
        );
        assert_eq!(
            listed(&photons, t.name()),
            c.photons,
            "--photons {}",
            t.name()
        );
        assert_eq!(listed(&window, t.name()), c.window, "--window {}", t.name());
        let names = |f: fn(&registry::Capabilities) -> bool| registry::names_where(f).join(", ");
        assert!(section("--shutter").contains(&names(|c| c.motion_blur)));
        assert!(section("--max-depth").contains(&names(|c| c.max_depth)));
    }
}

/// A 2×2 quad facing +Z (no material: white) lit head-on by a directional light of
/// 5000 lux, as engines and Blender export a sun; no camera.
fn sun_lit_quad(dir: &Path) -> std::path::PathBuf {
    let quad = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let (mut v, buf) = tiny(&quad, &[0, 1, 2, 0, 2, 3]);
    v["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual"]);
    v["extensions"] = serde_json::json!({"KHR_lights_punctual": {"lights": [
        {"type": "directional", "intensity": 5000.0}]}});
    v["nodes"] =
        serde_json::json!([{"mesh": 0}, {"extensions": {"KHR_lights_punctual": {"light": 0}}}]);
    v["scenes"] = serde_json::json!([{"nodes": [0, 1]}]);
    write_gltf(dir, &v, Some(&buf))
}

#[test]
fn sun_lit_scene_is_exposed_automatically_and_replays_identically() {
    let dir = temp_dir("sun");
    let p = sun_lit_quad(&dir);
    let render = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "render",
            p.to_str().unwrap(),
            "--frames",
            "0",
            "--resolution",
            "32x32",
            "--spp",
            "4",
            "--output",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        ok(&run(&args))
    };
    let centre = |out: &Path| {
        let png = chronolux_io::image::read_png_rgb8(out.join("frame_0000.png")).unwrap();
        png.pixels[16 * 32 + 16]
    };
    // Default: automatic exposure + AgX. The quad's radiance is about 5000/π ≈ 1600; the
    // exposure brings the 90th percentile (the quad) to the key 0.8 (log2(0.8/1600) ≈ −11),
    // shown at about 0.75 × 255 ≈ 190 by AgX, not clipped.
    let auto = dir.join("auto");
    render(&auto, &[]);
    let c = centre(&auto);
    assert!(c.iter().all(|&v| (100..250).contains(&v)), "{c:?}");
    let m = manifest(&auto);
    let ev = m["settings"]["auto_exposure"]
        .as_f64()
        .expect("auto_exposure recorded");
    assert!((-12.5..-9.5).contains(&ev), "{ev}");
    assert!(m["settings"]["exposure"].is_null());
    assert_eq!(m["settings"]["view"], "agx");
    // What the issue saw: the old default (exposure 0, clamp) is solid white.
    let old = dir.join("standard");
    render(&old, &["--view", "standard", "--exposure", "0"]);
    assert_eq!(centre(&old), [255, 255, 255]);
    assert_eq!(manifest(&old)["settings"]["view"], "standard");
    assert!(manifest(&old)["settings"].get("auto_exposure").is_none());
    // The EXR is the same linear image whatever the view and exposure.
    assert_eq!(
        std::fs::read(auto.join("frame_0000.exr")).unwrap(),
        std::fs::read(old.join("frame_0000.exr")).unwrap()
    );
    // Replaying run.json measures the same exposure: identical PNG.
    let again = dir.join("again");
    let cfg = auto.join("run.json");
    ok(&run([
        "render",
        "--config",
        cfg.to_str().unwrap(),
        "--output",
        again.to_str().unwrap(),
    ]));
    assert_eq!(
        std::fs::read(auto.join("frame_0000.png")).unwrap(),
        std::fs::read(again.join("frame_0000.png")).unwrap()
    );
    assert_eq!(manifest(&again)["settings"]["auto_exposure"], ev);
    // A bad view is a one-line error.
    fails(
        &run([
            "render",
            "--view",
            "filmic",
            "--output",
            dir.to_str().unwrap(),
        ]),
        &["filmic"],
    );
}

#[test]
fn unlit_white_model_stands_out_from_the_fallback_backdrop() {
    // AnimatedTriangle.gltf: one white triangle, no light, no camera. It used to render
    // white on the white of the uniform environment.
    let dir = temp_dir("unlit");
    let Some(p) = scene("AnimatedTriangle.gltf") else {
        return;
    };
    let mut args = vec![
        "render",
        p.to_str().unwrap(),
        "--frames",
        "0",
        "--output",
        dir.to_str().unwrap(),
    ];
    args.extend(FAST);
    let err = ok(&run(&args));
    assert!(err.contains("no light"), "{err}");
    let img = chronolux_io::image::read_exr(dir.join("frame_0000.exr")).unwrap();
    // Camera rays that miss show the backdrop, 0.05 exactly (every sample of a corner
    // pixel misses).
    let backdrop = img.pixels[0];
    assert!(
        (backdrop - glam::Vec3::splat(0.05)).abs().max_element() < 1e-6,
        "{backdrop}"
    );
    let model: Vec<_> = img
        .pixels
        .iter()
        .filter(|p| (**p - backdrop).abs().max_element() > 1e-3)
        .collect();
    // The triangle covers a part of the automatic framing and is lit: a vertical
    // white face under the gradient receives E/π = 0.6 (see `default_environment`), over
    // ten times the backdrop.
    assert!(
        model.len() > img.pixels.len() / 20,
        "{} pixels",
        model.len()
    );
    let mean = model.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / (3.0 * model.len() as f32);
    assert!(mean > 0.2, "mean of the model {mean}");
    // And in the PNG the model is clearly lighter than the backdrop.
    let png = chronolux_io::image::read_png_rgb8(dir.join("frame_0000.png")).unwrap();
    let max = png.pixels.iter().map(|p| p[1]).max().unwrap();
    assert!(
        max as i32 - png.pixels[0][1] as i32 > 80,
        "{max} vs {:?}",
        png.pixels[0]
    );
}

/// The default technique on a model lit only by the sky whose every part moves (a skinned
/// one) cannot share light between frames, and its indirect light adds nothing to path
/// tracing's noise: every frame is rendered as `path` (bit for bit `--method path` at the
/// same samples), the progress line says so and each `run.json` record carries the
/// probe's figures.
#[test]
fn a_sky_lit_skinned_model_renders_as_path_and_says_so() {
    let Some(model) = scene("RiggedSimple.glb") else {
        return;
    };
    let model = model.to_str().unwrap();
    let common = ["--frames", "0..3", "--resolution", "24x24", "--no-preview"];
    let ours = temp_dir("sky-default");
    let mut args = vec![
        "render",
        model,
        "--spp",
        "4",
        "--output",
        ours.to_str().unwrap(),
    ];
    args.extend(common);
    let out = ok(&run(&args));
    assert_eq!(out.matches("rendered as path").count(), 3, "{out}");
    for r in manifest(&ours)["frames"].as_array().unwrap() {
        assert_eq!(r["stats"]["path_probe"]["rendered_as"], "path", "{r}");
    }
    let path = temp_dir("sky-path");
    let mut args = vec![
        "render",
        model,
        "--method",
        "path",
        "--spp",
        "4",
        "--output",
        path.to_str().unwrap(),
    ];
    args.extend(common);
    ok(&run(&args));
    for f in 0..3 {
        let name = format!("frame_{f:04}.exr");
        assert!(
            std::fs::read(ours.join(&name)).unwrap() == std::fs::read(path.join(&name)).unwrap(),
            "frame {f} differs from path's"
        );
    }
    // `bench quality` steps spacetime-dept's photons, which do not reach these images: it
    // stops at the second level (the same errors to the bit) instead of rendering on to
    // --max-effort, and says so.
    let out = run([
        "bench",
        "quality",
        model,
        "--method",
        "spacetime-dept",
        "--frames",
        "0..3",
        "--resolution",
        "24x24",
        "--set",
        "spp=4",
        // Not the reference's own samples (it is `path` at this seed, 4 spp).
        "--seed",
        "1",
        "--reference",
        path.to_str().unwrap(),
        "--target-flip",
        "0.00001",
        "--start-effort",
        "1",
        "--max-effort",
        "64",
        "--json",
    ]);
    ok(&out);
    let j: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let r = &j["results"][0];
    assert_eq!(r["effort_has_no_effect"], true, "{j}");
    assert_eq!(r["levels"].as_array().unwrap().len(), 2, "{j}");
    assert!(
        stderr(&out).contains("does not change its images"),
        "{}",
        stderr(&out)
    );
}
