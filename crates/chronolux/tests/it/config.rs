//! Settings from the command line and from files: `--set`, `--config`, replay of a
//! `run.json`, methods and their checks from the registry, `bench quality --measure`.

use crate::common::*;
use std::path::Path;

fn exrs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn set_then_replay_of_run_json_is_bit_identical() {
    let first = temp_dir("config-first");
    ok(&run([
        "render",
        "--output",
        first.to_str().unwrap(),
        "--method",
        "stbpt",
        "--set",
        "window=2",
        "--set",
        "film_budget_mb=64",
        "--frames",
        "0..4",
        "--resolution",
        "16x16",
        "--spp",
        "1",
        "--seed",
        "7",
        "--no-preview",
    ]));
    let m = manifest(&first);
    assert_eq!(m["settings"]["method"], "stbpt");
    assert_eq!(m["settings"]["technique"]["window"], 2);
    assert_eq!(m["settings"]["technique"]["film_budget_mb"], 64);
    assert_eq!(m["settings"]["technique"]["bdpt"]["spp"], 1);
    assert_eq!(m["settings"]["technique"]["bdpt"]["seed"], 7);
    let again = temp_dir("config-again");
    let run_json = first.join("run.json");
    ok(&run([
        "render",
        "--config",
        run_json.to_str().unwrap(),
        "--output",
        again.to_str().unwrap(),
        "--no-preview",
    ]));
    let (a, b) = (exrs(&first), exrs(&again));
    assert_eq!(a.len(), 4);
    assert!(
        a == b,
        "a --config replay of run.json must give the same EXRs"
    );
    assert_eq!(manifest(&again)["settings"], {
        let mut s = m["settings"].clone();
        s["threads"] = manifest(&again)["settings"]["threads"].clone();
        s
    });
    // A flag overrides the file: another seed, other pixels.
    let other = temp_dir("config-other");
    ok(&run([
        "render",
        "--config",
        run_json.to_str().unwrap(),
        "--seed",
        "8",
        "--frames",
        "1",
        "--output",
        other.to_str().unwrap(),
    ]));
    assert_eq!(manifest(&other)["settings"]["technique"]["window"], 2);
    assert_ne!(exrs(&other)[0].1, a[1].1);
}

#[test]
fn a_settings_file_sets_keys_of_the_chosen_method() {
    let dir = temp_dir("config-settings");
    let file = dir.join("settings.json");
    std::fs::write(&file, r#"{"rr_depth": 3, "max_depth": 4}"#).unwrap();
    let out = dir.join("out");
    ok(&run([
        "render",
        "--method",
        "path",
        "--config",
        file.to_str().unwrap(),
        "--frames",
        "0",
        "--resolution",
        "8x8",
        "--spp",
        "1",
        "--output",
        out.to_str().unwrap(),
    ]));
    let t = &manifest(&out)["settings"]["technique"];
    assert_eq!(
        (t["rr_depth"].clone(), t["max_depth"].clone()),
        (3.into(), 4.into())
    );
    std::fs::write(&file, r#"{"rr_dpth": 3}"#).unwrap();
    fails(
        &run([
            "render",
            "--method",
            "path",
            "--config",
            file.to_str().unwrap(),
            "--output",
            out.to_str().unwrap(),
        ]),
        &["rr_dpth", "rr_depth", "max_depth"],
    );
}

#[test]
fn bad_settings_are_one_line_errors_naming_the_keys() {
    let dir = temp_dir("config-bad");
    let render = |extra: &[&str]| {
        let mut args = vec!["render", "--output", dir.to_str().unwrap()];
        args.extend(FAST);
        args.extend(extra);
        run(&args)
    };
    fails(
        &render(&["--method", "stbpt", "--set", "windw=2"]),
        &["windw", "window", "film_budget_mb"],
    );
    fails(
        &render(&["--method", "stbpt", "--set", "window=two"]),
        &["window", "two"],
    );
    fails(
        &render(&["--method", "stbpt", "--set", "interleave=3"]),
        &["interleave must be 1, 2, 4, 8 or 16", "not 3"],
    );
    fails(&render(&["--set", "window"]), &["key=value"]);
    fails(
        &render(&["--method", "path", "--window", "2"]),
        &["--window", "path", "spp"],
    );
    fails(
        &render(&["--method", "bdpt", "--photons", "1000"]),
        &["--photons", "dept"],
    );
    assert!(!dir.join("frame_0000.exr").exists());
}

#[test]
fn photons_set_the_pool_of_spt_which_has_no_stopping_rule() {
    // `--photons N` also clears the `auto` stopping rule of the DEPT methods; `spt` has
    // none, and a fixed count must still reach its pool (bench quality sets effort so).
    let dir = temp_dir("config-spt-photons");
    ok(&run([
        "render",
        "--method",
        "spt",
        "--photons",
        "3000",
        "--frames",
        "0",
        "--resolution",
        "8x8",
        "--spp",
        "1",
        "--no-preview",
        "--output",
        dir.to_str().unwrap(),
    ]));
    assert_eq!(manifest(&dir)["settings"]["technique"]["photons"], 3000);
    fails(
        &run([
            "render",
            "--method",
            "spt",
            "--photons",
            "auto",
            "--output",
            dir.to_str().unwrap(),
        ]),
        &["auto", "photons"],
    );
}

#[test]
fn help_lists_every_technique_of_the_registry() {
    let help = stdout(&run(["render", "--help"]));
    for t in chronolux_render::registry::TECHNIQUES {
        assert!(help.contains(t.name()), "{} missing from --help", t.name());
        assert!(help.contains(t.summary()), "{} summary missing", t.name());
    }
}

#[test]
fn bench_quality_measures_a_subset_of_the_rendered_frames() {
    let refs = temp_dir("measure-refs");
    ok(&run([
        "render",
        "--output",
        refs.to_str().unwrap(),
        "--frames",
        "0..4",
        "--resolution",
        "12x12",
        "--spp",
        "8",
        "--no-preview",
    ]));
    // Only the measured frames need references.
    std::fs::remove_file(refs.join("frame_0000.exr")).unwrap();
    let out = run([
        "bench",
        "quality",
        "--method",
        "stbpt",
        "--set",
        "window=1",
        "--frames",
        "0..4",
        "--measure",
        "1..=2",
        "--reference",
        refs.to_str().unwrap(),
        "--target-flip",
        "0.9",
        "--max-effort",
        "1",
        "--json",
    ]);
    ok(&out);
    let j: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(j["frames"], serde_json::json!([0, 1, 2, 3]));
    assert_eq!(j["measured"], serde_json::json!([1, 2]));
    // Frames 1 and 2 are consecutive in the render: one flicker pair.
    assert!(j["results"][0]["levels"][0]["flicker"].is_number(), "{j}");
    // Times are compared per measured frame: 2 of the 4 rendered.
    let l = &j["results"][0]["levels"][0];
    assert_eq!(l["frames_rendered"], 4);
    assert_eq!(l["frames_scored"], 2);
    assert_eq!(
        j["method_time_s"].as_f64().unwrap(),
        l["wall_s"].as_f64().unwrap() * 0.5,
        "{j}"
    );
    fails(
        &run([
            "bench",
            "quality",
            "--frames",
            "0..4",
            "--measure",
            "7",
            "--reference",
            refs.to_str().unwrap(),
            "--target-flip",
            "0.5",
        ]),
        &["--measure", "7"],
    );
}

/// `bench update --change CHANGE` on a 20k-photon pool (reference of the same size, 2
/// threads), its JSON report.
fn bench_update_json(change: &str) -> serde_json::Value {
    let out = run([
        "bench",
        "update",
        "--change",
        change,
        "--photons",
        "20000",
        "--ref-factor",
        "1",
        "--threads",
        "2",
        "--json",
    ]);
    ok(&out);
    serde_json::from_str(&stdout(&out)).unwrap()
}

/// `bench update --change occluder`: the block that appears under the lamp is its own
/// instance in both configurations, so the update invalidates only the photon groups whose
/// paths meet it (found by the pilots and the path scan), not the whole pool. The block
/// covers part of the lamp's downward hemisphere only, so some groups must stay valid:
/// with the block read as static geometry (the bug this guards) every group is invalid.
#[test]
fn bench_update_occluder_invalidates_only_the_groups_it_touches() {
    let j = bench_update_json("occluder");
    let groups = j["groups"].as_u64().unwrap();
    let p = &j["orders"]["priority"];
    let invalid = p["groups_invalidated"].as_u64().unwrap();
    assert!(
        invalid > 0 && invalid < groups,
        "{invalid} of {groups}: {j}"
    );
    assert_eq!(
        j["orders"]["scratch"]["groups_invalidated"].as_u64(),
        Some(groups)
    );
}

/// `bench update --change nudge`: a small block slides a short way on the floor. Derivable
/// from the design, not from timings: the path scan flags the same photons whatever the
/// order, so priority and random order (single photons, no pilots: the defaults) trace
/// exactly the same number of photons, fewer than a quarter of the pool that scratch
/// re-shoots (the block is 0.3 wide in a room 2 wide and 2 high: it meets a few percent
/// of the paths; a quarter is far above that and far below the pool). Both end on the
/// paths of the fresh pool of B (the converged state of the `stale` and `visible`
/// measures), so their final stale error is the `f32` rounding of the sums (relative
/// ~10⁻⁷ per side; bound 10⁻⁵), nothing is visibly different, and the area and view
/// errors of the two orders agree to 10⁻⁵ relative.
#[test]
fn bench_update_nudge_reshoots_only_the_flagged_photons_in_either_order() {
    let j = bench_update_json("nudge");
    let o = &j["orders"];
    let photons = |n: &str| o[n]["photons_total"].as_u64().unwrap();
    assert_eq!(photons("priority"), photons("random"), "{j}");
    assert_eq!(o["priority"]["pilots_traced"].as_u64(), Some(0));
    let z = j["pool_photons"].as_u64().unwrap();
    assert!(photons("scratch") >= z);
    assert!(
        photons("priority") > 0 && 4 * photons("priority") < z,
        "{j}"
    );
    for n in ["priority", "random"] {
        let f = &o[n]["final_error"];
        assert!(f["stale"].as_f64().unwrap() <= 1e-5, "{n}: {f}");
        assert_eq!(f["visible"].as_f64(), Some(0.0), "{n}: {f}");
    }
    for m in ["view", "area"] {
        let (p, r) = (
            o["priority"]["final_error"][m].as_f64().unwrap(),
            o["random"]["final_error"][m].as_f64().unwrap(),
        );
        assert!((p - r).abs() <= 1e-5 * r, "{m}: {p} vs {r}");
        assert!(
            j["measures"][m]["steady_state_error"].as_f64().unwrap() > 0.0,
            "{j}"
        );
    }
}
