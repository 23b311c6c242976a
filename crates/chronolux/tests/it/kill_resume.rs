//! Kill and resume, proven: a render killed with SIGKILL at random moments (while a frame
//! is traced, while files are written) and resumed each time ends with a folder equal, bit
//! for bit, to an uninterrupted render; between kills every frame file present decodes and
//! no temporary file carries a frame's name.
//!
//! The kill moments are drawn uniformly over the duration of an uninterrupted render from a
//! seed printed on failure (`CHRONOLUX_KILL_SEED=N` replays it).

use crate::common::*;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

const FRAMES: &str = "0..8";

fn args(dir: &Path) -> Vec<String> {
    [
        "render",
        "--no-denoise",
        "--frames",
        FRAMES,
        "--resolution",
        "40x40",
        "--spp",
        "8",
        "--resume",
        "--output",
        dir.to_str().unwrap(),
    ]
    .map(String::from)
    .to_vec()
}

/// Starts a render into `dir`, waits `delay` and kills it if it is still running; true
/// when it was killed. `Child::kill` is SIGKILL on Unix: no destructor, no temporary-file
/// clean-up runs.
fn kill_after(dir: &Path, delay: std::time::Duration) -> bool {
    let mut child = Command::new(env!("CARGO_BIN_EXE_chronolux"))
        .args(args(dir))
        .env_remove("RUST_LOG")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chronolux");
    std::thread::sleep(delay);
    let running = child.try_wait().unwrap().is_none();
    if running {
        child.kill().unwrap();
    }
    child.wait().unwrap();
    running
}

/// Every file of `dir` (name → bytes), except `run.json`, whose timings differ.
fn contents(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap() != "run.json")
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

/// Keeps in `dir`'s run.json only the records of the frames `keep` accepts (what a run
/// killed before recording the others leaves).
fn keep_records(dir: &Path, keep: impl Fn(u64) -> bool) {
    let path = dir.join("run.json");
    let mut m: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    m["frames"]
        .as_array_mut()
        .unwrap()
        .retain(|r| keep(r["frame"].as_u64().unwrap()));
    std::fs::write(&path, serde_json::to_vec_pretty(&m).unwrap()).unwrap();
}

/// Frame files are whole (they decode) and only finished files carry a frame's name.
fn check_consistent(dir: &Path, why: &str) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".tmp") {
            // A write cut short: under its temporary name, never taken as a frame.
            assert!(
                name.starts_with("frame_")
                    || name.starts_with("run")
                    || name.starts_with("preview"),
                "{why}: unexpected temporary file {name}"
            );
            continue;
        }
        if name.starts_with("frame_") {
            if name.ends_with(".exr") {
                chronolux_io::image::read_exr(&p)
                    .unwrap_or_else(|e| panic!("{why}: {name} does not decode: {e}"));
            } else if name.ends_with(".png") {
                chronolux_io::image::read_png_rgb8(&p)
                    .unwrap_or_else(|e| panic!("{why}: {name} does not decode: {e}"));
            } else {
                panic!("{why}: unexpected file {name}");
            }
        }
        if name == "run.json" {
            let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&p).unwrap())
                .unwrap_or_else(|e| panic!("{why}: run.json is not JSON: {e}"));
            assert!(v["settings"].is_object(), "{why}");
        }
    }
}

#[test]
fn sigkill_at_random_moments_then_resume_equals_an_uninterrupted_render() {
    let whole = temp_dir("kill-whole");
    let start = Instant::now();
    ok(&run(args(&whole)));
    let full = start.elapsed();

    let seed: u64 = std::env::var("CHRONOLUX_KILL_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap()
                .as_nanos() as u64
        });
    let mut state = seed | 1;
    let mut uniform = move || {
        // xorshift64*
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    };

    let cut = temp_dir("kill-cut");
    let mut killed = 0;
    let mut progress = Vec::new();
    for attempt in 0..6 {
        let delay = full.mul_f64(uniform());
        killed += u32::from(kill_after(&cut, delay));
        let why = format!(
            "seed {seed}, attempt {attempt}, killed after {:.3} s of {:.3} s",
            delay.as_secs_f64(),
            full.as_secs_f64()
        );
        check_consistent(&cut, &why);
        progress.push(
            (0..8)
                .filter(|f| cut.join(format!("frame_{f:04}.png")).is_file())
                .count(),
        );
    }
    // Every child may have finished before its moment (the machine ran faster than during
    // the measured render, or the resumed runs had little left): then again from an empty
    // folder with ever earlier moments, so that the test always proves a kill.
    let mut again = 0;
    while killed == 0 && again < 10 {
        again += 1;
        std::fs::remove_dir_all(&cut).unwrap();
        let delay = full.mul_f64(uniform() / f64::from(1u32 << again));
        killed += u32::from(kill_after(&cut, delay));
        check_consistent(&cut, &format!("seed {seed}, again {again}"));
    }
    // The last resume runs to the end.
    ok(&run(args(&cut)));
    check_consistent(&cut, &format!("seed {seed}, final"));
    assert!(
        killed > 0,
        "seed {seed}: no run was killed (full run {full:?})"
    );

    let (a, b) = (contents(&whole), contents(&cut));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "seed {seed}: file sets differ (frames done after each kill: {progress:?})"
    );
    for (name, bytes) in &a {
        assert!(
            &b[name] == bytes,
            "seed {seed}: {name} differs from the uninterrupted render"
        );
    }
    let (ma, mb) = (manifest(&whole), manifest(&cut));
    let frames = |m: &serde_json::Value| {
        m["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["frame"].as_u64().unwrap())
            .collect::<Vec<_>>()
    };
    assert_eq!(frames(&ma), (0..8).collect::<Vec<_>>());
    assert_eq!(frames(&mb), frames(&ma), "seed {seed}");
    let mut sa = ma["settings"].clone();
    let mut sb = mb["settings"].clone();
    sa["threads"] = serde_json::Value::Null;
    sb["threads"] = serde_json::Value::Null;
    assert_eq!(sa, sb, "seed {seed}");
}

/// A kill between a frame's files and its record in run.json (the files are written
/// first) leaves complete files without a record: `--resume` renders that frame again,
/// so that run.json lists every frame (found by the test above under load: run.json
/// lacked frame 6). Simulated here by deleting a record.
#[test]
fn resume_renders_a_frame_again_whose_record_is_missing() {
    let dir = temp_dir("kill-record");
    ok(&run(args(&dir)));
    keep_records(&dir, |f| f != 3);
    let before = contents(&dir);
    let out = ok(&run(args(&dir)));
    // Frame 3 rendered again, the others skipped.
    assert!(!out.contains("frame 3 [4/8]: already complete"), "{out}");
    assert!(out.contains("frame 2 [3/8]: already complete"), "{out}");
    let frames: Vec<u64> = manifest(&dir)["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["frame"].as_u64().unwrap())
        .collect();
    assert_eq!(frames, (0..8).collect::<Vec<_>>());
    assert!(contents(&dir) == before, "the same bits again");
}

/// A stateful technique without a window (`ic-selective`: its cache ages frame by frame)
/// resumed after a stop at frame 3 renders frames 0–2 again for its history, so the
/// resumed frames equal an uninterrupted render's bit for bit; before, it started frame 3
/// from an empty history and wrote different bits without a word.
#[test]
fn a_resumed_stateful_render_rebuilds_its_history_and_equals_an_uninterrupted_one() {
    let dir = temp_dir("resume-stateful");
    let args = |dir: &Path| {
        let mut a = args(dir);
        a.extend(
            [
                "--method",
                "ic-selective",
                "--set",
                "photons=1000",
                "--set",
                "spp=1",
            ]
            .map(String::from),
        );
        a
    };
    ok(&run(args(&dir)));
    let whole = contents(&dir);
    // A render stopped after frame 2: frames 3–7 have neither files nor records.
    for f in 3..8 {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with(&format!("frame_{f:04}"))
            {
                std::fs::remove_file(p).unwrap();
            }
        }
    }
    keep_records(&dir, |f| f < 3);
    let out = ok(&run(args(&dir)));
    assert!(out.contains("rendered again"), "{out}");
    assert!(
        contents(&dir) == whole,
        "the resumed frames differ from an uninterrupted run's"
    );
    assert_eq!(manifest(&dir)["frames"].as_array().unwrap().len(), 8);
}

/// A probe file (the output folder's writability check) left by a run killed before it
/// removed it is removed by the next run when its writer is gone, never when it is alive
/// (this test process stands for a live writer).
#[test]
fn a_dead_runs_probe_file_is_removed_and_a_live_ones_kept() {
    let dir = temp_dir("kill-probe");
    std::fs::create_dir_all(&dir).unwrap();
    // Above Linux's largest process id (2^22): no such process.
    let dead = dir.join(".chronolux-probe-4294967294");
    let live = dir.join(format!(".chronolux-probe-{}", std::process::id()));
    std::fs::write(&dead, b"probe").unwrap();
    std::fs::write(&live, b"probe").unwrap();
    ok(&run(args(&dir)));
    assert!(!dead.exists(), "a dead run's probe is left");
    assert!(live.exists(), "a live run's probe was removed");
}
