//! Evidence of a failed image test: the images it compared and its per-block statistic,
//! written as PFM (portable float map: linear RGB, 32-bit floats; tev, GIMP, ImageMagick
//! and `imageio` read it) into `target/test-evidence/<test name>/<what>/`.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The folder for the evidence of the running test's check `what`:
/// `<target>/test-evidence/<test name>/<what>/`, created empty. `<target>` is found from
/// the test executable (`<target>/<profile>/deps/<binary>`), so it follows
/// `CARGO_TARGET_DIR`; the test name is the test thread's name (what libtest names it).
pub fn dir(what: &str) -> std::io::Result<PathBuf> {
    let target = std::env::current_exe()
        .ok()
        .and_then(|exe| {
            exe.ancestors()
                .find(|a| a.file_name().is_some_and(|n| n == "deps"))
                .and_then(|deps| deps.parent()?.parent().map(Path::to_path_buf))
        })
        .unwrap_or_else(std::env::temp_dir);
    let test = std::thread::current()
        .name()
        .filter(|n| *n != "main")
        .unwrap_or("unnamed-test")
        .to_string();
    let d = target
        .join("test-evidence")
        .join(sanitize(&test))
        .join(sanitize(what));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d)?;
    Ok(d)
}

/// `s` as one file-name component: letters, digits, `-`, `_` and `.` kept, anything else
/// (`::`, spaces, `/`) becomes `_`.
fn sanitize(s: &str) -> String {
    let t: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if t.is_empty() { "_".into() } else { t }
}

/// Writes a `width`×`height` RGB image (rows top to bottom) as a little-endian PFM.
pub fn write_pfm(path: &Path, width: u32, height: u32, px: &[[f32; 3]]) -> std::io::Result<()> {
    assert_eq!(px.len(), (width * height) as usize, "pixel count");
    let mut out = Vec::with_capacity(px.len() * 12 + 32);
    write!(out, "PF\n{width} {height}\n-1.0\n")?;
    // PFM stores rows bottom to top.
    for row in px.chunks(width as usize).rev() {
        for p in row {
            for v in p {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, out)
}

/// Reads a PFM written by [`write_pfm`] (little-endian RGB): width, height, pixels top to
/// bottom.
pub fn read_pfm(path: &Path) -> std::io::Result<(u32, u32, Vec<[f32; 3]>)> {
    let bytes = std::fs::read(path)?;
    let bad = |m: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, m.to_string());
    let mut fields = Vec::new();
    let mut start = 0;
    let mut pos = 0;
    while fields.len() < 4 && pos < bytes.len() {
        if bytes[pos].is_ascii_whitespace() {
            if pos > start {
                fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
            }
            start = pos + 1;
        }
        pos += 1;
    }
    if fields.len() < 4 || fields[0] != "PF" {
        return Err(bad("not an RGB PFM"));
    }
    let w: u32 = fields[1].parse().map_err(|_| bad("width"))?;
    let h: u32 = fields[2].parse().map_err(|_| bad("height"))?;
    let scale: f32 = fields[3].parse().map_err(|_| bad("scale"))?;
    if scale >= 0.0 {
        return Err(bad("big-endian PFM not supported"));
    }
    let data = &bytes[start..];
    if data.len() != (w * h * 12) as usize {
        return Err(bad("size"));
    }
    let mut rows: Vec<Vec<[f32; 3]>> = data
        .chunks(w as usize * 12)
        .map(|row| {
            row.chunks(12)
                .map(|p| {
                    let f = |k: usize| f32::from_le_bytes(p[4 * k..4 * k + 4].try_into().unwrap());
                    [f(0), f(1), f(2)]
                })
                .collect()
        })
        .collect();
    rows.reverse();
    Ok((w, h, rows.concat()))
}
