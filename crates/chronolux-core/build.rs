//! Finds Intel Embree 4 for the default build, so that ray queries run on it on a fresh
//! machine without a variable set by hand (`src/accel/embree.rs`).
//!
//! Nothing is linked: the library is loaded at run time, so a build without it still
//! builds and renders (on the own BVH, saying why). This script only bakes in the path of
//! the library found or put (`CHRONOLUX_EMBREE_BUILD_LIB`), or why there is none
//! (`CHRONOLUX_EMBREE_BUILD_NOTE`), in this order:
//!
//! 1. `pkg-config embree4` (a system or Homebrew install);
//! 2. the libraries of the `embreex` wheel (Embree 4.4.0's release build with its TBB, as
//!    PyPI ships it for trimesh), fetched by `python3 -m pip download` with its sha256
//!    pinned and unpacked into the cache shared by every profile and checkout
//!    (`$CHRONOLUX_EMBREE_CACHE`, else `$XDG_CACHE_HOME/chronolux`, else
//!    `~/.cache/chronolux`). `CHRONOLUX_EMBREE_FETCH=0` turns the download off; a failed
//!    download is a build warning, not an error.

#[path = "../../build-support/wheel.rs"]
mod wheel;

use std::path::PathBuf;
use std::process::Command;

const WHEEL: &str = "embreex==4.4.0.post1";
const WHEEL_SHA256: &str = "2cd0f7d5c6342e6247e31f700761689cae7829454d8c6de0c41e62124a023e1f";
const CACHE_NAME: &str = "embree-4.4.0";
/// The wheel's Embree, renamed by auditwheel (its TBB beside it, found through `$ORIGIN`).
const WHEEL_LIB: &str = "libembree4-4aef3270.so.4";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../build-support/wheel.rs");
    for var in [
        "CHRONOLUX_EMBREE_FETCH",
        "CHRONOLUX_EMBREE_CACHE",
        "XDG_CACHE_HOME",
        "HOME",
    ] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    let (lib, note) = match find() {
        Ok(path) => (path.display().to_string(), String::new()),
        Err(why) => {
            println!(
                "cargo:warning=Embree not found: {why}; ray queries will use the built-in BVH unless the library is found at run time"
            );
            (String::new(), why)
        }
    };
    println!("cargo:rustc-env=CHRONOLUX_EMBREE_BUILD_LIB={lib}");
    println!("cargo:rustc-env=CHRONOLUX_EMBREE_BUILD_NOTE={note}");
}

fn find() -> Result<PathBuf, String> {
    if let Ok(out) = Command::new("pkg-config")
        .args(["--variable=libdir", "embree4"])
        .output()
        && out.status.success()
    {
        let lib =
            PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()).join("libembree4.so.4");
        if lib.is_file() {
            return Ok(lib);
        }
    }
    if std::env::var("CHRONOLUX_EMBREE_FETCH").as_deref() == Ok("0") {
        return Err("no pkg-config entry for embree4, and CHRONOLUX_EMBREE_FETCH=0".into());
    }
    let target = (
        std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default(),
        std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default(),
    );
    if target != ("linux".into(), "x86_64".into()) {
        return Err(format!(
            "the pinned embreex wheel is for Linux x86-64, not {}-{}: install Embree 4 (pkg-config embree4) or set CHRONOLUX_EMBREE_LIB at run time",
            target.1, target.0
        ));
    }
    let cache = wheel::cache_dir("CHRONOLUX_EMBREE_CACHE")
        .ok_or("no cache folder (set CHRONOLUX_EMBREE_CACHE)")?;
    // The wheel is tagged for CPython 3.11; only its native libraries are used, so the
    // selection names the tag instead of the interpreter that runs pip.
    let dir = wheel::fetch(
        &wheel::Wheel {
            spec: WHEEL,
            sha256: WHEEL_SHA256,
            select: &[
                "--platform",
                "manylinux_2_28_x86_64",
                "--python-version",
                "3.11",
                "--implementation",
                "cp",
                "--abi",
                "cp311",
            ],
            cache_name: CACHE_NAME,
            keep: r"embreex\.libs/lib(embree4|tbb)-[0-9a-f]+\.so[.0-9]*$",
            lib: WHEEL_LIB,
        },
        &cache,
    )?;
    Ok(dir.join(WHEEL_LIB))
}
