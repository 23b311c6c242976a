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
