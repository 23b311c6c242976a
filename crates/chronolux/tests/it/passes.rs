//! `--passes` (render passes as EXR layers) and `--denoise`.

use crate::common::*;
use chronolux_io::image::{read_exr, read_exr_channel};

#[test]
fn passes_are_layers_of_the_exr_for_any_method() {
    for method in ["path", "stbpt"] {
        let dir = temp_dir(&format!("passes-{method}"));
        ok(&run([
            "render",
            "--method",
            method,
            "--passes",
            "all",
            "--frames",
            "3..5",
            "--resolution",
            "16x16",
            "--spp",
            "1",
            "--output",
            dir.to_str().unwrap(),
            "--no-preview",
        ]));
        let exr = dir.join("frame_0004.exr");
        // The beauty is still the image every reader sees.
        let beauty = read_exr(&exr).unwrap();
        assert_eq!((beauty.width, beauty.height), (16, 16));
        for name in [
            "ViewLayer.Denoising Albedo.R",
            "ViewLayer.Denoising Normal.Z",
            "ViewLayer.Depth.Z",
            "ViewLayer.Vector.X",
            "ViewLayer.Vector.W",
        ] {
            let c = read_exr_channel(&exr, name).unwrap();
            assert_eq!(c.map(|c| c.len()), Some(256), "{method}: {name}");
        }
        // Inside the demo's closed room every pixel sees a surface at a finite depth.
        let depth = read_exr_channel(&exr, "ViewLayer.Depth.Z")
            .unwrap()
            .unwrap();
        assert!(depth.iter().all(|d| *d > 0.0 && *d < 100.0), "{depth:?}");
        assert_eq!(manifest(&dir)["settings"]["passes"]["motion"], true);
    }
    let dir = temp_dir("passes-bad");
    fails(
        &run([
            "render",
            "--passes",
            "albedo,shadows",
            "--output",
            dir.to_str().unwrap(),
        ]),
        &["shadows", "albedo", "normal"],
    );
}

/// `direct` and `indirect` are layers that add up to the beauty exactly (f32 EXR);
/// a method that does not separate them refuses them before rendering.
#[test]
fn direct_and_indirect_add_up_to_the_beauty_and_are_refused_where_not_separated() {
    let dir = temp_dir("passes-light");
    ok(&run([
        "render",
        "--method",
        "path",
        "--passes",
        "light,depth",
        "--frames",
        "4",
        "--resolution",
        "16x16",
        "--spp",
        "2",
        "--output",
        dir.to_str().unwrap(),
        "--no-preview",
    ]));
    let exr = dir.join("frame_0004.exr");
    let beauty = read_exr(&exr).unwrap().pixels;
    let ch = |n: &str| read_exr_channel(&exr, n).unwrap().unwrap();
    let mut indirect_sum = 0.0f64;
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let d = ch(&format!("ViewLayer.Direct.{name}"));
        let i = ch(&format!("ViewLayer.Indirect.{name}"));
        for k in 0..beauty.len() {
            assert_eq!(d[k] + i[k], beauty[k][c], "pixel {k} channel {name}");
            indirect_sum += i[k] as f64;
        }
    }
    // The demo is a closed room: its walls light each other.
    assert!(indirect_sum > 0.0);
    // A method that does not separate them: an error naming it, before any frame.
    let dir = temp_dir("passes-light-bad");
    fails(
        &run([
            "render",
            "--method",
            "stbpt",
            "--passes",
            "direct",
            "--frames",
            "4",
            "--output",
            dir.to_str().unwrap(),
        ]),
        &["stbpt", "does not separate direct and indirect"],
    );
    assert!(!dir.join("frame_0004.exr").exists());
    // `all` writes them where the method separates them, and not where it does not.
    for (method, has) in [("path", true), ("stbpt", false)] {
        let dir = temp_dir(&format!("passes-all-{method}"));
        ok(&run([
            "render",
            "--method",
            method,
            "--passes",
            "all",
            "--frames",
            "4",
            "--resolution",
            "8x8",
            "--spp",
            "1",
            "--output",
            dir.to_str().unwrap(),
            "--no-preview",
        ]));
        let c = read_exr_channel(dir.join("frame_0004.exr"), "ViewLayer.Direct.G").unwrap();
        assert_eq!(c.is_some(), has, "{method}");
    }
}

/// Interpreter named by `CHRONOLUX_OPENEXR_PYTHON` (default `python3`) if it can
/// `import OpenEXR, numpy`, under the policy of `chronolux_core::testing::external`
/// otherwise (`.ci/run` installs both into `.venv-flip` and sets the variable).
fn openexr_python() -> Option<String> {
    let var = "CHRONOLUX_OPENEXR_PYTHON";
    let py = std::env::var(var).unwrap_or_else(|_| "python3".into());
    let found = std::process::Command::new(&py)
        .args(["-c", "import OpenEXR, numpy"])
        .output()
        .is_ok_and(|o| o.status.success())
        .then(|| py.clone());
    chronolux_core::testing::external::require_external(
        found,
        &format!("the Python package OpenEXR (`{py} -c \"import OpenEXR, numpy\"` fails)"),
        "`.ci/run` installs it with `.venv-flip/bin/pip install OpenEXR numpy` and sets \
         CHRONOLUX_OPENEXR_PYTHON=.venv-flip/bin/python; do the same by hand",
    )
}

/// An independent reader (the OpenEXR Python package, the reference implementation's
/// bindings) sees every layer under Blender's names, with the values our reader sees,
/// and direct + indirect equal to the beauty.
#[test]
fn an_independent_reader_sees_the_passes() {
    let Some(py) = openexr_python() else { return };
    let dir = temp_dir("passes-openexr");
    ok(&run([
        "render",
        "--method",
        "path",
        "--passes",
        "all",
        "--frames",
        "3..5",
        "--resolution",
        "12x10",
        "--spp",
        "2",
        "--output",
        dir.to_str().unwrap(),
        "--no-preview",
    ]));
    let exr = dir.join("frame_0004.exr");
    let script = r#"
import json, sys, OpenEXR, numpy as np
f = OpenEXR.File(sys.argv[1], separate_channels=True)
ch = {k: v.pixels for k, v in f.channels().items()}
out = {k: [float(x) for x in v.astype(np.float64).ravel()] for k, v in ch.items()}
out["shape"] = list(ch["R"].shape)
out["adds_up"] = all(bool(np.array_equal(ch["ViewLayer.Direct." + c] + ch["ViewLayer.Indirect." + c], ch[c])) for c in "RGB")
print(json.dumps(out))
"#;
    let o = std::process::Command::new(&py)
        .args(["-c", script, exr.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["shape"], serde_json::json!([10, 12]));
    assert_eq!(v["adds_up"], true);
    let names = [
        "R",
        "G",
        "B",
        "ViewLayer.Denoising Albedo.R",
        "ViewLayer.Denoising Albedo.G",
        "ViewLayer.Denoising Albedo.B",
        "ViewLayer.Denoising Normal.X",
        "ViewLayer.Denoising Normal.Y",
        "ViewLayer.Denoising Normal.Z",
        "ViewLayer.Depth.Z",
        "ViewLayer.Vector.X",
        "ViewLayer.Vector.Y",
        "ViewLayer.Vector.Z",
        "ViewLayer.Vector.W",
        "ViewLayer.Direct.R",
        "ViewLayer.Direct.G",
        "ViewLayer.Direct.B",
        "ViewLayer.Indirect.R",
        "ViewLayer.Indirect.G",
        "ViewLayer.Indirect.B",
    ];
    let obj = v.as_object().unwrap();
    assert_eq!(
        obj.len(),
        names.len() + 2,
        "{:?}",
        obj.keys().collect::<Vec<_>>()
    );
    for name in names {
        let theirs: Vec<f32> = obj[name]
            .as_array()
            .unwrap_or_else(|| panic!("{name} missing"))
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect();
        let ours = read_exr_channel(&exr, name).unwrap().unwrap();
        // f32 samples, printed as f64 and parsed back: exact.
        assert_eq!(theirs, ours, "{name}");
    }
}

/// A machine without Open Image Denoise (simulated: `CHRONOLUX_OIDN_LIB` names a file
/// that does not exist, and then nothing else is tried): the default render still
/// renders, undenoised (the same bits as `--no-denoise`), says once why, and run.json
/// records it; asking for `--denoise` there is a clear error.
#[test]
fn without_the_library_the_default_render_is_undenoised_and_says_why() {
    let missing = [(
        "CHRONOLUX_OIDN_LIB",
        "/nonexistent/libOpenImageDenoise.so.2",
    )];
    let dir = temp_dir("denoise-missing");
    let plain = temp_dir("denoise-missing-plain");
    let args = |out: &std::path::Path, extra: &[&str]| {
        let mut a = vec!["render", "--frames", "4", "--resolution", "24x24"];
        a.extend(["--spp", "2", "--no-preview", "--output"]);
        a.push(out.to_str().unwrap());
        a.extend(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let err = ok(&run_as_user(args(&dir, &[]), &missing));
    let said: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("without denoising"))
        .collect();
    assert_eq!(said.len(), 1, "{err}");
    assert!(said[0].starts_with("warning: "), "{err}");
    assert!(said[0].contains("CHRONOLUX_OIDN_LIB"), "{err}");
    let run_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).unwrap()).unwrap();
    assert_eq!(run_json["settings"]["denoise"], false, "{run_json}");
    assert!(
        run_json["settings"]["denoise_unavailable"]
            .as_str()
            .is_some_and(|w| w.contains("/nonexistent/")),
        "{run_json}"
    );
    let exr = dir.join("frame_0004.exr");
    assert!(
        read_exr_channel(&exr, "ViewLayer.Noisy Image.R")
            .unwrap()
            .is_none(),
        "an undenoised frame has no noisy layer"
    );
    ok(&run_as_user(args(&plain, &["--no-denoise"]), &missing));
    assert_eq!(
        read_exr(&exr).unwrap().pixels,
        read_exr(plain.join("frame_0004.exr")).unwrap().pixels
    );
    // Asked for, denoising that cannot be done is an error, before any rendering.
    let asked = temp_dir("denoise-missing-asked");
    fails(
        &run_as_user(args(&asked, &["--denoise"]), &missing),
        &["--denoise", "not available", "/nonexistent/"],
    );
    assert!(!asked.join("frame_0004.exr").exists());
    // The same for the equal-quality benchmark, before any reference is read.
    fails(
        &run_as_user(
            [
                "bench",
                "quality",
                "--frames",
                "0..2",
                "--reference",
                dir.to_str().unwrap(),
                "--target-flip",
                "0.1",
                "--denoise",
            ],
            &missing,
        ),
        &["--denoise", "not available"],
    );
}

/// Denoising really denoises, in the default build (CI runs this on a fresh clone: the
/// build fetched the library itself). Against a converged path-traced reference of the
/// same frame: the default render (no denoising flag at all) is denoised, its noisy
/// layer is bit for bit the `--no-denoise` render, and the denoised image has the lower
/// relMSE; and the denoised 4-spp stbpt image has less than half the noisy one's.
#[test]
fn denoise_lowers_the_error_and_keeps_the_noisy_image() {
    let dir = temp_dir("denoise-on");
    let reference = temp_dir("denoise-ref");
    let common = ["--frames", "4", "--resolution", "64x64", "--no-preview"];
    let mut args = vec![
        "render",
        "--method",
        "path",
        "--spp",
        "1024",
        "--output",
        reference.to_str().unwrap(),
    ];
    args.extend(common);
    ok(&run(&args));
    let r = read_exr(reference.join("frame_0004.exr")).unwrap().pixels;
    let noisy_layer = |exr: &std::path::Path| -> Vec<chronolux_core::color::Rgb> {
        let ch = |n: &str| {
            read_exr_channel(exr, &format!("ViewLayer.Noisy Image.{n}"))
                .unwrap()
                .unwrap_or_else(|| panic!("{}: no noisy layer: not denoised", exr.display()))
        };
        let (nr, ng, nb) = (ch("R"), ch("G"), ch("B"));
        (0..nr.len())
            .map(|k| chronolux_core::color::Rgb::new(nr[k], ng[k], nb[k]))
            .collect()
    };

    // The default, as a user runs it.
    let default_dir = temp_dir("denoise-default");
    let plain_dir = temp_dir("denoise-default-plain");
    let user = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["render", "--output", out.to_str().unwrap()];
        args.extend(common);
        args.extend(extra);
        run_as_user(&args, &[])
    };
    ok(&user(&default_dir, &[]));
    // The same settings undenoised: the default quality's are for a denoised render, so
    // they are replayed from its run.json.
    let default_json = default_dir.join("run.json");
    ok(&user(
        &plain_dir,
        &["--no-denoise", "--config", default_json.to_str().unwrap()],
    ));
    let default_exr = default_dir.join("frame_0004.exr");
    let run_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(default_dir.join("run.json")).unwrap())
            .unwrap();
    assert_eq!(run_json["settings"]["denoise"], true, "{run_json}");
    // The default quality's effort, from the registry's table.
    assert_eq!(run_json["settings"]["quality"], "preview", "{run_json}");
    assert_eq!(run_json["settings"]["technique"]["spp"], 4, "{run_json}");
    assert!(
        run_json["settings"]["denoise_library"].is_string(),
        "{run_json}"
    );
    let plain = read_exr(plain_dir.join("frame_0004.exr")).unwrap().pixels;
    assert_eq!(noisy_layer(&default_exr), plain);
    let e_default = chronolux_core::metrics::rel_mse(&read_exr(&default_exr).unwrap().pixels, &r);
    let e_plain = chronolux_core::metrics::rel_mse(&plain, &r);
    assert!(
        e_default < e_plain,
        "default denoised {e_default} vs --no-denoise {e_plain}"
    );

    // The README's route: stbpt at 4 spp, denoised (`extra`: more flags).
    let denoised = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["render", "--method", "stbpt", "--spp", "4", "--denoise"];
        args.extend(extra);
        args.extend(["--output", out.to_str().unwrap()]);
        args.extend(common);
        run(&args)
    };
    ok(&denoised(&dir, &[]));
    let exr = dir.join("frame_0004.exr");
    let clean = read_exr(&exr).unwrap().pixels;
    let ch = |n: &str| read_exr_channel(&exr, n).unwrap().unwrap();
    let (nr, ng, nb) = (
        ch("ViewLayer.Noisy Image.R"),
        ch("ViewLayer.Noisy Image.G"),
        ch("ViewLayer.Noisy Image.B"),
    );
    let noisy: Vec<_> = (0..clean.len())
        .map(|k| chronolux_core::color::Rgb::new(nr[k], ng[k], nb[k]))
        .collect();
    let e_noisy = chronolux_core::metrics::rel_mse(&noisy, &r);
    let e_clean = chronolux_core::metrics::rel_mse(&clean, &r);
    // OIDN on 4 spp of a diffuse-dominated scene removes most of the variance; a factor
    // 2 is a loose bound (the reference's own relMSE at 1024 spp is ~1e-3 here).
    assert!(
        e_clean < 0.5 * e_noisy,
        "denoised {e_clean} vs noisy {e_noisy}"
    );

    // `--denoise-quality fast`: the same noisy image (the quality is the filter's only),
    // filtered by another network (a different image), which denoises too (same bound),
    // and run.json says which.
    let fast_dir = temp_dir("denoise-fast");
    ok(&denoised(&fast_dir, &["--denoise-quality", "fast"]));
    let fast_exr = fast_dir.join("frame_0004.exr");
    let fast = read_exr(&fast_exr).unwrap().pixels;
    for name in ["R", "G", "B"] {
        let layer = format!("ViewLayer.Noisy Image.{name}");
        assert_eq!(
            read_exr_channel(&fast_exr, &layer).unwrap().unwrap(),
            ch(&layer),
            "{layer}"
        );
    }
    assert_ne!(fast, clean, "fast and high gave the same image");
    let e_fast = chronolux_core::metrics::rel_mse(&fast, &r);
    assert!(e_fast < 0.5 * e_noisy, "fast {e_fast} vs noisy {e_noisy}");
    let run_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fast_dir.join("run.json")).unwrap()).unwrap();
    assert_eq!(
        run_json["settings"]["denoise_quality"], "fast",
        "{run_json}"
    );
    // Resuming that folder with the other quality would mix two denoisers' frames.
    fails(
        &denoised(&fast_dir, &["--resume"]),
        &["--resume", "denoise_quality"],
    );
}
