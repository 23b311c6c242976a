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

#[cfg(not(feature = "oidn"))]
#[test]
fn denoise_without_the_feature_is_a_clear_error() {
    let dir = temp_dir("denoise-off");
    fails(
        &run(["render", "--denoise", "--output", dir.to_str().unwrap()]),
        &["--denoise", "--features oidn"],
    );
}

/// Denoising really denoises: against a converged path-traced reference of the same
/// frame, the denoised 4-spp image has a lower relMSE than the noisy one it came from.
#[cfg(feature = "oidn")]
#[test]
fn denoise_lowers_the_error_and_keeps_the_noisy_image() {
    let dir = temp_dir("denoise-on");
    let reference = temp_dir("denoise-ref");
    let common = ["--frames", "4", "--resolution", "64x64", "--no-preview"];
    let mut args = vec![
        "render",
        "--spp",
        "1024",
        "--output",
        reference.to_str().unwrap(),
    ];
    args.extend(common);
    ok(&run(&args));
    let mut args = vec![
        "render",
        "--spp",
        "4",
        "--denoise",
        "--output",
        dir.to_str().unwrap(),
    ];
    args.extend(common);
    ok(&run(&args));
    let exr = dir.join("frame_0004.exr");
    let clean = read_exr(&exr).unwrap().pixels;
    let r = read_exr(reference.join("frame_0004.exr")).unwrap().pixels;
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
}
