//! Finds Intel Open Image Denoise for the default build, so that `cargo run --release --
//! render` denoises on a fresh machine without a variable set by hand (README,
//! "Render passes and denoising").
//!
//! Nothing is linked: the binary loads the library at run time (`src/denoise.rs`), so a
//! build without it still builds and renders, undenoised, saying why. This script only
//! bakes into the binary the folder where the library was found or put
//! (`CHRONOLUX_OIDN_BUILD_LIB`), or why there is none (`CHRONOLUX_OIDN_BUILD_NOTE`), in
//! this order:
//!
//! 1. `OIDN_DIR` (an OIDN install or release package: `$OIDN_DIR/lib`);
//! 2. `pkg-config OpenImageDenoise` (a system or Homebrew install);
//! 3. the CPU part of the `pyoidn` wheel (OIDN 2.5.1's own release build, as PyPI ships
//!    it), fetched by `python3 -m pip download` with its sha256 pinned and unpacked into
//!    a cache shared by every profile and checkout (`$CHRONOLUX_OIDN_CACHE`, else
//!    `$XDG_CACHE_HOME/chronolux`, else `~/.cache/chronolux`). `CHRONOLUX_OIDN_FETCH=0`
//!    turns the download off (an offline or hermetic build); a failed download is a
//!    build warning, not an error.

#[path = "../../build-support/wheel.rs"]
mod wheel;

use std::path::{Path, PathBuf};
use std::process::Command;

/// The wheel fetched in step 3 and its sha256 (PyPI's file for Linux x86-64).
const WHEEL: &str = "pyoidn==2.5.1.0";
const WHEEL_SHA256: &str = "32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e";
/// The folder name of the unpacked library in the cache (one per OIDN version).
const CACHE_NAME: &str = "oidn-2.5.1";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../build-support/wheel.rs");
    for var in [
        "OIDN_DIR",
        "CHRONOLUX_OIDN_FETCH",
        "CHRONOLUX_OIDN_CACHE",
        "XDG_CACHE_HOME",
        "HOME",
    ] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    let (lib, note) = match find() {
        Ok(dir) => (dir.display().to_string(), String::new()),
        Err(why) => {
            println!(
                "cargo:warning=Open Image Denoise not found: {why}; chronolux will render undenoised unless it finds the library at run time"
            );
            (String::new(), why)
        }
    };
    println!("cargo:rustc-env=CHRONOLUX_OIDN_BUILD_LIB={lib}");
    println!("cargo:rustc-env=CHRONOLUX_OIDN_BUILD_NOTE={note}");
}

/// The name of OIDN's main library on this target.
fn lib_name() -> &'static str {
    match std::env::var("CARGO_CFG_TARGET_OS").as_deref() {
        Ok("macos") => "libOpenImageDenoise.2.dylib",
        Ok("windows") => "OpenImageDenoise.dll",
        _ => "libOpenImageDenoise.so.2",
    }
}

fn has_lib(dir: &Path) -> bool {
    dir.join(lib_name()).is_file()
}

fn find() -> Result<PathBuf, String> {
    if let Some(dir) = std::env::var_os("OIDN_DIR") {
        let lib = PathBuf::from(dir).join("lib");
        return if has_lib(&lib) {
            Ok(lib)
        } else {
            Err(format!(
                "OIDN_DIR is set but {} has no {}",
                lib.display(),
                lib_name()
            ))
        };
    }
    if let Ok(out) = Command::new("pkg-config")
        .args(["--variable=libdir", "OpenImageDenoise"])
        .output()
        && out.status.success()
    {
        let lib = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
        if has_lib(&lib) {
            return Ok(lib);
        }
    }
    if std::env::var("CHRONOLUX_OIDN_FETCH").as_deref() == Ok("0") {
        return Err("no OIDN_DIR, no pkg-config entry, and CHRONOLUX_OIDN_FETCH=0".into());
    }
    fetch()
}

/// Step 3: the pyoidn wheel's CPU libraries, in the shared cache.
fn fetch() -> Result<PathBuf, String> {
    let target = (
        std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default(),
        std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default(),
    );
    if target != ("linux".into(), "x86_64".into()) {
        return Err(format!(
            "the pinned pyoidn wheel is for Linux x86-64, not {}-{}: set OIDN_DIR to an OIDN release",
            target.1, target.0
        ));
    }
    let cache = wheel::cache_dir("CHRONOLUX_OIDN_CACHE")
        .ok_or("no cache folder (set CHRONOLUX_OIDN_CACHE)")?;
    // The CPU device's libraries only (not CUDA, HIP, SYCL: 40 MB more for devices this
    // renderer does not create).
    wheel::fetch(
        &wheel::Wheel {
            spec: WHEEL,
            sha256: WHEEL_SHA256,
            select: &["--platform", "manylinux2014_x86_64"],
            cache_name: CACHE_NAME,
            keep: r"pyoidn/oidn/lib/(libOpenImageDenoise(_core|_device_cpu)?|libtbb|libtbbbind[_0-9]*)\.so[.0-9]*$",
            lib: lib_name(),
        },
        &cache,
    )
}
