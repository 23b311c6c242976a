//! Shared by the build scripts that fetch a native library from a PyPI wheel
//! (`crates/chronolux/build.rs`: Open Image Denoise from `pyoidn`;
//! `crates/chronolux-core/build.rs`: Embree from `embreex`). Included with `#[path]`.
//!
//! The wheel is downloaded by `python3 -m pip download` with its sha256 pinned, the files
//! matching `keep` are unpacked into a fresh folder of the cache, which is then moved into
//! place, so that two builds at once never see half a folder.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A pinned wheel and what to take from it.
pub struct Wheel<'a> {
    /// `name==version` for pip.
    pub spec: &'a str,
    pub sha256: &'a str,
    /// pip's selection of the file (`--platform`, `--python-version`, …).
    pub select: &'a [&'a str],
    /// Folder of the unpacked libraries in the cache (one per version).
    pub cache_name: &'a str,
    /// Python regex over the wheel's member names: the files to unpack (flat).
    pub keep: &'a str,
    /// The file whose presence says the folder is complete.
    pub lib: &'a str,
}

/// The cache folder: `$var`, else `$XDG_CACHE_HOME/chronolux`, else `~/.cache/chronolux`.
pub fn cache_dir(var: &str) -> Option<PathBuf> {
    let dir = if let Some(d) = std::env::var_os(var) {
        PathBuf::from(d)
    } else if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        PathBuf::from(d).join("chronolux")
    } else {
        PathBuf::from(std::env::var_os("HOME")?)
            .join(".cache")
            .join("chronolux")
    };
    std::fs::create_dir_all(&dir).ok()?;
    Some(dir)
}

/// The folder holding `w.lib` in `cache`, fetched and unpacked if it is not there yet.
pub fn fetch(w: &Wheel, cache: &Path) -> Result<PathBuf, String> {
    let lib = cache.join(w.cache_name).join("lib");
    if lib.join(w.lib).is_file() {
        return Ok(lib);
    }
    let name = w.spec.split("==").next().unwrap_or(w.spec);
    let out = PathBuf::from(std::env::var("OUT_DIR").map_err(|e| e.to_string())?);
    let download = out.join(format!("{name}-wheel"));
    let _ = std::fs::remove_dir_all(&download);
    std::fs::create_dir_all(&download).map_err(|e| e.to_string())?;
    let req = download.join("requirements.txt");
    std::fs::write(&req, format!("{} --hash=sha256:{}\n", w.spec, w.sha256))
        .map_err(|e| e.to_string())?;
    let pip = Command::new("python3")
        .args(["-m", "pip", "download", "--no-deps", "--only-binary=:all:"])
        .args(w.select)
        .args(["--require-hashes", "-q"])
        .arg("-r")
        .arg(&req)
        .arg("-d")
        .arg(&download)
        .output()
        .map_err(|e| format!("cannot run python3 -m pip: {e}"))?;
    if !pip.status.success() {
        return Err(format!(
            "python3 -m pip download {} failed: {}",
            w.spec,
            String::from_utf8_lossy(&pip.stderr)
                .lines()
                .rfind(|l| !l.trim().is_empty())
                .unwrap_or("no message")
        ));
    }
    let staging = cache.join(format!("{}.part-{}", w.cache_name, std::process::id()));
    let _ = std::fs::remove_dir_all(&staging);
    let script = r#"
import glob, os, re, sys, zipfile
wheel = glob.glob(os.path.join(sys.argv[1], "*.whl"))[0]
dest = os.path.join(sys.argv[2], "lib")
os.makedirs(dest)
keep = re.compile(sys.argv[3])
with zipfile.ZipFile(wheel) as z:
    for m in z.namelist():
        if keep.match(m):
            with z.open(m) as src, open(os.path.join(dest, os.path.basename(m)), "wb") as dst:
                dst.write(src.read())
"#;
    let unpack = Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(&download)
        .arg(&staging)
        .arg(w.keep)
        .output()
        .map_err(|e| format!("cannot run python3: {e}"))?;
    let _ = std::fs::remove_dir_all(&download);
    if !unpack.status.success() {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(format!(
            "unpacking the {name} wheel failed: {}",
            String::from_utf8_lossy(&unpack.stderr).trim()
        ));
    }
    if std::fs::rename(&staging, cache.join(w.cache_name)).is_err() {
        // Another build put it there first.
        let _ = std::fs::remove_dir_all(&staging);
    }
    if lib.join(w.lib).is_file() {
        Ok(lib)
    } else {
        Err(format!(
            "{} has no {} after unpacking",
            lib.display(),
            w.lib
        ))
    }
}
