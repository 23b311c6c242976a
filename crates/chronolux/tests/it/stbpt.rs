//! `--method stbpt` records its sample reuse in run.json.

use crate::common::*;

#[test]
fn stbpt_writes_reuse_statistics_into_run_json() {
    let dir = temp_dir("stbpt-reuse");
    ok(&run([
        "render",
        "--output",
        dir.to_str().unwrap(),
        "--method",
        "stbpt",
        "--window",
        "1",
        "--frames",
        "0..3",
        "--resolution",
        "16x16",
        "--spp",
        "1",
        // K and the strategies fixed (all of BDPT's): the counts below are exact.
        "--set",
        "adaptive=false",
        "--no-preview",
    ]));
    let m = manifest(&dir);
    let frames = m["frames"].as_array().expect("frames in run.json");
    assert_eq!(frames.len(), 3);
    for rec in frames {
        let reuse = &rec["stats"]["reuse"];
        let f = rec["frame"].as_u64().unwrap();
        // Window [f − 1, f + 1] clipped to the render list 0..3.
        let window = if f == 1 { 3 } else { 2 };
        assert_eq!(reuse["window"], window, "frame {f}: {reuse}");
        // Own samples (256) plus those landed from the neighbours.
        let eff = reuse["effective_spp"].as_f64().unwrap();
        assert!(
            eff > 1.0 && eff <= window as f64 + 1e-9,
            "frame {f}: {reuse}"
        );
        let served = reuse["reused"].as_u64().unwrap() + reuse["retraced"].as_u64().unwrap();
        assert!(served > 0, "frame {f}: {reuse}");
        let factor = reuse["reuse_factor"].as_f64().unwrap();
        assert!(factor > 1.0 && factor <= 3.0 + 1e-9, "frame {f}: {reuse}");
        assert_eq!(reuse["light_subpaths_per_pixel"], window as f64);
        let strategies = &rec["stats"]["strategy_decision"];
        assert_eq!(strategies["decision"], "fixed", "frame {f}: {strategies}");
    }
}

/// `interleave` above the frames a window holds (here the 2-frame clip) leaves pixels that
/// no frame generates: the render says so on stderr (it still renders: those pixels are
/// filled, `reuse.filled`), and an `interleave` within the window says nothing.
#[test]
fn stbpt_warns_when_interleave_exceeds_the_window() {
    let dir = temp_dir("stbpt-interleave-warn");
    let render = |n: &str| {
        run([
            "render",
            "--output",
            dir.to_str().unwrap(),
            "--method",
            "stbpt",
            "--set",
            &format!("interleave={n}"),
            "--frames",
            "0..2",
            "--resolution",
            "16x16",
            "--spp",
            "1",
            "--no-preview",
        ])
    };
    let err = ok(&render("4"));
    assert!(
        err.contains("warning") && err.contains("interleave=4 is more than the 2 frames"),
        "{err}"
    );
    let filled: u64 = manifest(&dir)["frames"]
        .as_array()
        .expect("frames")
        .iter()
        .map(|f| f["stats"]["reuse"]["filled"].as_u64().unwrap_or(0))
        .sum();
    assert!(filled > 0, "no pixel was filled");
    let err = ok(&render("2"));
    assert!(!err.contains("interleave="), "{err}");
}
