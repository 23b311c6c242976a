//! Atomic file writes: a reader (another segment, `--resume`, `assemble`) never sees a
//! half-written file under its final name. Below [`crate::image`] and [`crate::output`],
//! which both write through it.

use std::fs::{self, File};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

/// Writes `path` atomically: `write` fills `<path>.tmp` (same folder, so the rename stays on one
/// file system), which is flushed, synced and renamed over `path`. On error (or panic) the
/// temporary file is removed and `path` is left untouched.
///
/// The writer is a buffered [`File`], which is both [`Write`](io::Write) and [`io::Seek`] (the EXR encoder
/// needs to seek). Encoders' own errors should be wrapped with [`io::Error::other`].
pub fn write_atomic<T>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<T>,
) -> io::Result<T> {
    let tmp = tmp_path(path);
    let mut guard = TmpGuard {
        path: Some(tmp.clone()),
    };
    let mut w = BufWriter::new(File::create(&tmp)?);
    let value = write(&mut w)?;
    let file = w.into_inner().map_err(|e| e.into_error())?;
    file.sync_all()?;
    drop(file);
    fs::rename(&tmp, path)?;
    guard.path = None;
    Ok(value)
}

/// `<path>.tmp`: the temporary name [`write_atomic`] uses for `path`.
pub fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Removes the temporary file unless disarmed (`path = None`).
struct TmpGuard {
    path: Option<PathBuf>,
}

impl Drop for TmpGuard {
    fn drop(&mut self) {
        if let Some(p) = self.path.take() {
            let _ = fs::remove_file(p);
        }
    }
}
