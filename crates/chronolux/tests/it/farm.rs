//! Farm segments: plans with the overlap each technique needs, segments that write only
//! their own frames, bit-identical to a single run for every technique whose frames depend
//! only on (seed, frame, pixel, index), `assemble` and its seam report.

use crate::common::*;
use std::path::Path;

fn exr(dir: &Path, f: u32) -> Vec<u8> {
    std::fs::read(dir.join(format!("frame_{f:04}.exr"))).unwrap()
}

/// Every technique of the registry, cut into 3 segments, against one run of the range.
#[test]
fn segments_equal_a_single_run_for_every_exact_technique() {
    for t in chronolux_render::registry::TECHNIQUES {
        let name = t.name();
        let e = t.capabilities().effort;
        // The smallest effort: 1 sample per pixel, or 1000 photons per frame.
        let effort = format!("{}={}", e.key, e.per_unit);
        let common = [
            "--method",
            name,
            "--set",
            effort.as_str(),
            "--frames",
            "0..6",
            "--resolution",
            "16x16",
            "--no-preview",
        ];
        let single = temp_dir(&format!("farm-single-{name}"));
        let mut args = vec!["render", "--output", single.to_str().unwrap()];
        args.extend(common);
        ok(&run(&args));

        let farm = temp_dir(&format!("farm-seg-{name}"));
        let plan = farm.join("plan.json");
        let mut args = vec!["plan", "--segments", "3", "--json"];
        args.extend(common);
        let out = run(&args);
        ok(&out);
        std::fs::write(&plan, stdout(&out)).unwrap();
        let p: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(p["segments"].as_array().unwrap().len(), 3, "{name}");
        // Segments run in reverse order (nothing depends on another segment's output), the
        // middle one on one thread (a farm's machines differ).
        for i in (0..3).rev() {
            let threads = if i == 1 { "1" } else { "2" };
            ok(&run([
                "render",
                "--plan",
                plan.to_str().unwrap(),
                "--segment",
                &i.to_string(),
                "--threads",
                threads,
                "--output",
                farm.to_str().unwrap(),
            ]));
            assert!(farm.join(format!("run.segment-{i:04}.json")).is_file());
        }
        let out = run(["assemble", farm.to_str().unwrap(), "--json", "--no-preview"]);
        ok(&out);
        let report: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(report["frames"], 6, "{name}: {report}");
        assert_eq!(manifest(&farm)["frames"].as_array().unwrap().len(), 6);
        if p["context"]["exact"] == true {
            for f in 0..6 {
                assert!(
                    exr(&single, f) == exr(&farm, f),
                    "{name}: frame {f} of the segments differs from the single run"
                );
            }
        } else {
            // Stateful: the seam is measured, and must not stand out from the flicker
            // inside the segments. Single frame pairs at these tiny sizes and photon counts
            // differ by tens of percent from their mean (measured with the warm-up: worst
            // seam / mean inside = 1.02 for spt, ≤ 1 for ic-static-dynamic), so a seam
            // "stands out" only beyond 1.25 times the inside mean; a cold start without
            // history shows the difference of two independent solutions instead.
            let r = report["worst_seam_ratio"].as_f64().unwrap();
            assert!(r <= 1.25, "{name}: seam flicker / inside flicker = {r}");
        }
    }
}

#[test]
fn a_plan_fixes_the_settings_and_assemble_finds_missing_frames() {
    let farm = temp_dir("farm-fixed");
    let out = run([
        "plan",
        "--method",
        "stbpt",
        "--window",
        "2",
        "--frames",
        "0..10",
        "--segment-length",
        "4",
        "--resolution",
        "8x8",
        "--spp",
        "1",
        "--json",
    ]);
    ok(&out);
    let p: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    // Owned 4-7 with K = 2 computes 2..=9.
    assert_eq!(p["segments"][1]["owned"], serde_json::json!([4, 5, 6, 7]));
    assert_eq!(
        p["segments"][1]["compute"],
        serde_json::json!([2, 3, 4, 5, 6, 7, 8, 9])
    );
    assert_eq!(p["segments"][2]["owned"], serde_json::json!([8, 9]));
    let plan = farm.join("plan.json");
    std::fs::write(&plan, stdout(&out)).unwrap();
    fails(
        &run([
            "render",
            "--plan",
            plan.to_str().unwrap(),
            "--segment",
            "0",
            "--spp",
            "4",
        ]),
        &["--plan", "--spp"],
    );
    fails(
        &run([
            "render",
            "--plan",
            plan.to_str().unwrap(),
            "--segment",
            "3",
            "--output",
            farm.to_str().unwrap(),
        ]),
        &["--segment 3"],
    );
    ok(&run([
        "render",
        "--plan",
        plan.to_str().unwrap(),
        "--segment",
        "0",
        "--output",
        farm.to_str().unwrap(),
    ]));
    // Segment 0 writes only its own frames.
    assert!(farm.join("frame_0003.exr").is_file());
    assert!(!farm.join("frame_0004.exr").exists());
    fails(
        &run(["assemble", farm.to_str().unwrap()]),
        &["missing", "[4, 5, 6, 7, 8, 9]"],
    );
}

/// A stateful technique's segment stopped between writing a frame and recording it:
/// `assemble` names the frame instead of writing a run.json without it, and the
/// segment's `--resume` renders it again from the same history (the frames before it,
/// warm-up and its own complete ones, in order), so the frame comes out bit for bit as
/// the uninterrupted segment made it.
#[test]
fn an_unrecorded_frame_of_a_stateful_segment_is_found_and_resumed_bit_for_bit() {
    let farm = temp_dir("farm-unrecorded");
    let plan = farm.join("plan.json");
    // ic-selective: its cache ages frame by frame, so a frame rendered without the
    // frames before it differs (measured: a resume that skipped frame 3 changed frame 4).
    let out = run([
        "plan",
        "--method",
        "ic-selective",
        "--frames",
        "0..6",
        "--segments",
        "2",
        "--resolution",
        "8x8",
        "--set",
        "photons=1000",
        "--set",
        "spp=1",
        "--json",
    ]);
    ok(&out);
    std::fs::write(&plan, stdout(&out)).unwrap();
    let segment = |i: &str, resume: bool| {
        let mut args = vec![
            "render",
            "--plan",
            plan.to_str().unwrap(),
            "--segment",
            i,
            "--output",
            farm.to_str().unwrap(),
        ];
        if resume {
            args.push("--resume");
        }
        ok(&run(args));
    };
    segment("0", false);
    segment("1", false);
    let before = exr(&farm, 4);
    // Segment 1 owns 3..=5; frame 4's record is lost.
    let m = farm.join("run.segment-0001.json");
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
    doc["frames"]
        .as_array_mut()
        .unwrap()
        .retain(|r| r["frame"] != 4);
    std::fs::write(&m, doc.to_string()).unwrap();
    fails(
        &run(["assemble", farm.to_str().unwrap(), "--no-preview"]),
        &["no record", "[4]", "--resume"],
    );
    segment("1", true);
    assert!(exr(&farm, 4) == before, "frame 4 resumed differs");
    ok(&run(["assemble", farm.to_str().unwrap(), "--no-preview"]));
    assert_eq!(manifest(&farm)["frames"].as_array().unwrap().len(), 6);
}

/// `spacetime-dept`'s segments equal a single run on a model whose animation changes the
/// scene's bounds (InterpolationTest scales and moves its cubes): the elements are built
/// from frame 0's scene whatever frame a segment starts at. Built from the segment's own
/// first frame, every frame of the last segment (16–23) differed.
#[test]
fn spacetime_segments_equal_a_single_run_when_the_bounds_change() {
    let Some(model) = scene("InterpolationTest.glb") else {
        return;
    };
    let model = model.to_str().unwrap();
    let common = [
        model,
        "--frames",
        "0..24",
        "--resolution",
        "16x16",
        "--photons",
        "2000",
        "--spp",
        "2",
        "--no-preview",
    ];
    let single = temp_dir("farm-bounds-single");
    let mut args = vec!["render", "--output", single.to_str().unwrap()];
    args.extend(common);
    ok(&run(&args));
    let farm = temp_dir("farm-bounds-seg");
    let plan = farm.join("plan.json");
    let mut args = vec!["plan", "--segments", "3", "--json"];
    args.extend(common);
    let out = run(&args);
    ok(&out);
    std::fs::write(&plan, stdout(&out)).unwrap();
    for i in ["2", "0", "1"] {
        ok(&run([
            "render",
            "--plan",
            plan.to_str().unwrap(),
            "--segment",
            i,
            "--output",
            farm.to_str().unwrap(),
        ]));
    }
    for f in 0..24 {
        assert!(
            exr(&single, f) == exr(&farm, f),
            "frame {f} of the segments differs from the single run"
        );
    }
}
