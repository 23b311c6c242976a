//! Helpers: running the binary, temporary folders, shared scenes, crafted glTF files.

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A shared scene from `shared/scenes` beside the repository; `None` (the test returns)
/// when it is missing outside CI, a failure under CI (the policy of
/// `chronolux_core::testing::external`).
pub fn scene(name: &str) -> Option<PathBuf> {
    chronolux_core::testing::shared_file(&format!("scenes/{name}"))
}

/// A fresh, empty folder unique to this process and call.
pub fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let d = std::env::temp_dir().join(format!("chronolux-cli-{}-{n}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `chronolux ARGS` (stdin closed, logging at its default level). A `render`,
/// `plan` or `farm` that says nothing of denoising gets `--no-denoise`: the tests of
/// the renderer's own images (bit-identity, statistics) are about its estimate, and the
/// default denoising has its own tests ([`run_as_user`]).
pub fn run<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let mut args: Vec<std::ffi::OsString> =
        args.into_iter().map(|a| a.as_ref().to_owned()).collect();
    let has = |flag: &str| args.iter().any(|a| a == flag);
    let renders = args
        .first()
        .is_some_and(|a| a == "render" || a == "plan" || a == "farm");
    if renders
        && !has("--denoise")
        && !has("--no-denoise")
        && !has("--denoise-quality")
        && !has("--plan")
        && !has("--help")
    {
        args.push("--no-denoise".into());
    }
    run_as_user(args, &[])
}

/// Runs `chronolux ARGS` exactly as given, with the environment variables `env` set
/// (stdin closed, logging at its default level).
pub fn run_as_user<I, S>(args: I, env: &[(&str, &str)]) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_chronolux"))
        .args(args)
        .envs(env.iter().copied())
        .env_remove("RUST_LOG")
        .env_remove("RUST_BACKTRACE")
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run chronolux")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Asserts success and returns stderr.
pub fn ok(o: &Output) -> String {
    let err = stderr(o);
    assert!(
        o.status.success(),
        "chronolux failed ({}):\n{err}",
        o.status
    );
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// Asserts the bad-input contract: non-zero exit, no panic, exactly one `error:` line on
/// stderr (besides `warning:` lines about the scene), naming the problem with every
/// `needles` (case-insensitive). Returns the error line.
pub fn fails(o: &Output, needles: &[&str]) -> String {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure, got success:\n{err}");
    assert!(!err.contains("panicked"), "panic:\n{err}");
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| !l.starts_with("warning: "))
        .collect();
    assert_eq!(lines.len(), 1, "expected one error line:\n{err}");
    let line = lines[0];
    assert!(line.starts_with("error: "), "{err}");
    for n in needles {
        assert!(
            line.to_lowercase().contains(&n.to_lowercase()),
            "error line does not mention '{n}': {line}"
        );
    }
    line.to_string()
}

/// Common fast render arguments.
pub const FAST: [&str; 4] = ["--resolution", "24x24", "--spp", "2"];

/// `run.json` of an output folder.
pub fn manifest(dir: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(dir.join("run.json")).expect("run.json")).unwrap()
}

/// A minimal glTF with one node and one mesh (POSITION + u16 indices), its buffer in
/// `buffer.bin` next to it. Returns the JSON and the buffer bytes.
pub fn tiny(positions: &[[f32; 3]], indices: &[u16]) -> (Value, Vec<u8>) {
    let mut bytes: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let pos_len = bytes.len();
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let idx_len = bytes.len() - pos_len;
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
    let v = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bytes.len(), "uri": "buffer.bin"}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos_len},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": idx_len}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}
        ]
    });
    (v, bytes)
}

pub const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// Writes `scene.gltf` (and `buffer.bin`) into `dir`; returns the glTF path.
pub fn write_gltf(dir: &Path, v: &Value, buffer: Option<&[u8]>) -> PathBuf {
    if let Some(b) = buffer {
        std::fs::write(dir.join("buffer.bin"), b).unwrap();
    }
    let p = dir.join("scene.gltf");
    std::fs::write(&p, serde_json::to_vec_pretty(v).unwrap()).unwrap();
    p
}
