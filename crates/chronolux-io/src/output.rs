//! Frame sequences on disk: `frame_NNNN.exr` + `frame_NNNN.png` per frame, a `run.json`
//! manifest, and an animated preview (`preview.gif`, plus `preview.mp4` when `ffmpeg` is on
//! PATH).
//!
//! Every file is written atomically through [`write_atomic`] (`<name>.tmp` in the same folder,
//! then a rename), so an interrupted run never leaves a truncated file under a final name;
//! [`FrameSink::is_complete`] is what `--resume` asks.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

pub use crate::atomic::{tmp_path, write_atomic};
use crate::image::{Image, ImageError, Rgb8Image, read_png_rgb8, write_exr};

/// Name of the manifest file in the output folder.
pub const MANIFEST_NAME: &str = "run.json";
/// Name of the animated GIF preview in the output folder.
pub const PREVIEW_GIF_NAME: &str = "preview.gif";
/// Name of the MP4 preview in the output folder (written only when `ffmpeg` is available).
pub const PREVIEW_MP4_NAME: &str = "preview.mp4";
/// Longest side of the GIF preview, in pixels.
pub const PREVIEW_MAX_SIDE: u32 = 512;

/// Errors of the output folder.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output folder cannot be created or written to.
    #[error("output folder {path} is not writable: {source}")]
    Unwritable {
        /// The folder.
        path: PathBuf,
        /// OS error.
        source: io::Error,
    },
    /// Writing or reading an image failed.
    #[error(transparent)]
    Image(#[from] ImageError),
    /// Any other file could not be written or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// OS error.
        source: io::Error,
    },
    /// The manifest could not be parsed.
    #[error("cannot parse manifest {path}: {source}")]
    Manifest {
        /// The manifest file.
        path: PathBuf,
        /// Parser error.
        source: serde_json::Error,
    },
    /// A preview could not be made (no frames, frames of different sizes, encoder error).
    #[error("cannot write preview in {path}: {reason}")]
    Preview {
        /// The output folder.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
}

// ---------------------------------------------------------------------------------------------
// File names

/// `frame_0000` for frame 0 (at least four digits; frame 12345 is `frame_12345`).
pub fn frame_stem(frame: u32) -> String {
    format!("frame_{frame:04}")
}

/// `frame_0000.exr`.
pub fn frame_exr_name(frame: u32) -> String {
    format!("{}.exr", frame_stem(frame))
}

/// `frame_0000.png`.
pub fn frame_png_name(frame: u32) -> String {
    format!("{}.png", frame_stem(frame))
}

// ---------------------------------------------------------------------------------------------
// Timestamps

/// Seconds since the Unix epoch, as f64 (0 for times before it).
pub fn unix_seconds(t: SystemTime) -> f64 {
    t.duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// RFC 3339 UTC timestamp with whole seconds, e.g. `2026-11-22T01:27:00Z`.
pub fn timestamp_utc(t: SystemTime) -> String {
    let secs = t
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// [`timestamp_utc`] of now.
pub fn now_utc() -> String {
    timestamp_utc(SystemTime::now())
}

// ---------------------------------------------------------------------------------------------
// Manifest

/// What was rendered, how, and how long it took: `run.json` in the output folder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Version of the renderer that wrote the manifest.
    pub chronolux_version: String,
    /// Command line (program name first).
    pub command: Vec<String>,
    /// Render settings, as the caller serialises them.
    #[serde(default)]
    pub settings: serde_json::Value,
    /// Scene summary, as the caller serialises it.
    #[serde(default)]
    pub scene: serde_json::Value,
    /// One record per finished frame, sorted by frame number.
    #[serde(default)]
    pub frames: Vec<FrameRecord>,
    /// Start of the run ([`timestamp_utc`]).
    pub started: String,
    /// End of the run; `None` while the run is in progress or was interrupted.
    #[serde(default)]
    pub finished: Option<String>,
    /// Wall-clock seconds of the run so far.
    #[serde(default)]
    pub total_wall_s: f64,
}

/// One finished frame in the [`Manifest`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// Frame number.
    pub frame: u32,
    /// Scene time of the frame, seconds.
    pub time_s: f32,
    /// Wall-clock seconds spent on the frame.
    pub wall_s: f64,
    /// Render statistics, as the caller serialises them.
    #[serde(default)]
    pub stats: serde_json::Value,
    /// EXR file name, relative to the output folder.
    pub file_exr: String,
    /// PNG file name, relative to the output folder.
    pub file_png: String,
}

impl FrameRecord {
    /// A record with the standard file names of `frame`.
    pub fn new(frame: u32, time_s: f32, wall_s: f64, stats: serde_json::Value) -> Self {
        Self {
            frame,
            time_s,
            wall_s,
            stats,
            file_exr: frame_exr_name(frame),
            file_png: frame_png_name(frame),
        }
    }
}

impl Manifest {
    /// A manifest for a run starting now, with this crate's version and no frames.
    pub fn new(
        command: Vec<String>,
        settings: serde_json::Value,
        scene: serde_json::Value,
    ) -> Self {
        Self {
            chronolux_version: env!("CARGO_PKG_VERSION").to_owned(),
            command,
            settings,
            scene,
            frames: Vec::new(),
            started: now_utc(),
            finished: None,
            total_wall_s: 0.0,
        }
    }

    /// Inserts `record`, replacing any record with the same frame number; keeps frames sorted.
    pub fn upsert_frame(&mut self, record: FrameRecord) {
        match self.frames.binary_search_by_key(&record.frame, |r| r.frame) {
            Ok(i) => self.frames[i] = record,
            Err(i) => self.frames.insert(i, record),
        }
    }

    /// Merges the records of an earlier run (from [`FrameSink::read_manifest`] on `--resume`):
    /// frames this manifest already has win, the others are kept. Frames end up sorted.
    pub fn merge_earlier(&mut self, earlier: &Manifest) {
        for r in &earlier.frames {
            if self.frame(r.frame).is_none() {
                self.upsert_frame(r.clone());
            }
        }
        self.frames.sort_by_key(|r| r.frame);
    }

    /// The record of `frame`, if any.
    pub fn frame(&self, frame: u32) -> Option<&FrameRecord> {
        self.frames.iter().find(|r| r.frame == frame)
    }

    /// Sets `finished` to now and `total_wall_s`.
    pub fn finish(&mut self, total_wall_s: f64) {
        self.finished = Some(now_utc());
        self.total_wall_s = total_wall_s;
    }
}

// ---------------------------------------------------------------------------------------------
// Frame sink

/// An output folder receiving frames (`frame_NNNN.exr` + `.png`) and `run.json`.
#[derive(Clone, Debug)]
pub struct FrameSink {
    dir: PathBuf,
    /// File name of the manifest (`run.json`; a farm segment writes its own).
    manifest: String,
}

/// Name of a writability probe file, followed by the process id of its writer.
pub const PROBE_PREFIX: &str = ".chronolux-probe-";

/// Removes the probe files in `dir` whose writer is gone: a run killed (SIGKILL runs no
/// clean-up) between writing and removing its probe leaves it. Where process ids cannot be
/// checked (no `/proc`), nothing is removed; a live writer's probe is never touched.
pub fn remove_stale_probes(dir: &Path) {
    let proc_fs = Path::new("/proc");
    if !proc_fs.join("self").exists() {
        return;
    }
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let pid = name
            .to_str()
            .and_then(|n| n.strip_prefix(PROBE_PREFIX))
            .and_then(|p| p.parse::<u32>().ok());
        if let Some(pid) = pid
            && !proc_fs.join(pid.to_string()).exists()
        {
            let _ = fs::remove_file(e.path());
        }
    }
}

impl FrameSink {
    /// Creates `dir` (and parents) if needed and checks it is writable by writing and removing
    /// a probe file. The error names the folder and the OS error on one line. Probe files
    /// of runs killed before they removed theirs are removed ([`remove_stale_probes`]).
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        let unwritable = |source| OutputError::Unwritable {
            path: dir.to_owned(),
            source,
        };
        fs::create_dir_all(dir).map_err(unwritable)?;
        if !dir.is_dir() {
            return Err(unwritable(io::Error::new(
                io::ErrorKind::NotADirectory,
                "not a directory",
            )));
        }
        remove_stale_probes(dir);
        let probe = dir.join(format!("{PROBE_PREFIX}{}", std::process::id()));
        let written = File::create(&probe).and_then(|mut f| {
            f.write_all(b"probe")?;
            f.sync_all()
        });
        let removed = fs::remove_file(&probe);
        written.map_err(unwritable)?;
        removed.map_err(unwritable)?;
        Ok(Self {
            dir: dir.to_owned(),
            manifest: MANIFEST_NAME.to_string(),
        })
    }

    /// The same folder with the manifest written as `name` instead of `run.json` (farm
    /// segments sharing one folder each keep their own, so none overwrites another's).
    pub fn with_manifest_name(mut self, name: &str) -> Self {
        self.manifest = name.to_string();
        self
    }

    /// The output folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// `dir/frame_NNNN.exr`.
    pub fn exr_path(&self, frame: u32) -> PathBuf {
        self.dir.join(frame_exr_name(frame))
    }

    /// `dir/frame_NNNN.png`.
    pub fn png_path(&self, frame: u32) -> PathBuf {
        self.dir.join(frame_png_name(frame))
    }

    /// `dir/run.json` (or the name given to [`FrameSink::with_manifest_name`]).
    pub fn manifest_path(&self) -> PathBuf {
        self.dir.join(&self.manifest)
    }

    /// True when both files of `frame` exist, the PNG ends with its `IEND` chunk, and the EXR
    /// parses with a nonzero size and all its chunks present (compressed chunks are read, not
    /// decoded), so a truncated file counts as incomplete. Used by `--resume`.
    pub fn is_complete(&self, frame: u32) -> bool {
        png_is_complete(&self.png_path(frame)) && exr_is_complete(&self.exr_path(frame))
    }

    /// Writes `frame_NNNN.exr` (linear) then `frame_NNNN.png` (sRGB, `exposure` stops), each
    /// atomically.
    pub fn write_frame(&self, frame: u32, image: &Image, exposure: f32) -> Result<(), OutputError> {
        self.write_frame_view(frame, image, exposure, crate::image::View::Standard)
    }

    /// [`FrameSink::write_frame`] with the PNG made through `view` (the EXR is unaffected).
    pub fn write_frame_view(
        &self,
        frame: u32,
        image: &Image,
        exposure: f32,
        view: crate::image::View,
    ) -> Result<(), OutputError> {
        write_exr(self.exr_path(frame), image)?;
        crate::image::write_png_view(self.png_path(frame), image, exposure, view)?;
        Ok(())
    }

    /// Writes `run.json` (pretty JSON) atomically.
    pub fn write_manifest(&self, manifest: &Manifest) -> Result<(), OutputError> {
        let path = self.manifest_path();
        write_atomic(&path, |w| {
            serde_json::to_writer_pretty(&mut *w, manifest).map_err(io::Error::other)?;
            w.write_all(b"\n")
        })
        .map_err(|source| OutputError::Io { path, source })
    }

    /// Reads `run.json`; `Ok(None)` when there is none.
    pub fn read_manifest(&self) -> Result<Option<Manifest>, OutputError> {
        let path = self.manifest_path();
        let text = match fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
            Err(source) => return Err(OutputError::Io { path, source }),
        };
        serde_json::from_str(&text)
            .map(Some)
            .map_err(|source| OutputError::Manifest { path, source })
    }
}

/// PNG signature at the start and the `IEND` chunk (with its fixed CRC) at the end.
fn png_is_complete(path: &Path) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    const IEND: [u8; 12] = [0, 0, 0, 0, b'I', b'E', b'N', b'D', 0xae, 0x42, 0x60, 0x82];
    let check = || -> io::Result<bool> {
        let mut f = File::open(path)?;
        let mut head = [0u8; 8];
        f.read_exact(&mut head)?;
        f.seek(SeekFrom::End(-12))?;
        let mut tail = [0u8; 12];
        f.read_exact(&mut tail)?;
        Ok(head == SIGNATURE && tail == IEND)
    };
    check().unwrap_or(false)
}

/// Header parses, every layer has a nonzero size, and every chunk is present and readable.
fn exr_is_complete(path: &Path) -> bool {
    use exr::block::reader::Reader;
    let Ok(file) = File::open(path) else {
        return false;
    };
    let Ok(reader) = Reader::read_from_buffered(io::BufReader::new(file), false) else {
        return false;
    };
    let sized = !reader.headers().is_empty()
        && reader
            .headers()
            .iter()
            .all(|h| h.layer_size.width() > 0 && h.layer_size.height() > 0);
    if !sized {
        return false;
    }
    match reader.all_chunks(false) {
        Ok(mut chunks) => chunks.all(|c| c.is_ok()),
        Err(_) => false,
    }
}

// ---------------------------------------------------------------------------------------------
// Preview

/// Reads back the PNGs of `frames` (in the order given) from `dir` and writes `preview.gif`
/// there: animated, looping forever, `fps` frames per second (GIF delays are whole
/// centiseconds, at least 2), downscaled (area average in linear light) so the long side is
/// ≤ [`PREVIEW_MAX_SIDE`], quantised per frame with `gif::Frame::from_rgb_speed` (speed 10).
/// Returns the GIF's path.
///
/// When an `ffmpeg` binary is on PATH and the frame numbers are contiguous and increasing, it
/// also writes `preview.mp4` (H.264, yuv420p, full resolution padded to even size) from the
/// PNG sequence. Non-contiguous frames skip the MP4 (logged); a missing or failing `ffmpeg`
/// is logged as a warning and does not fail the call.
pub fn write_preview(dir: &Path, frames: &[u32], fps: f32) -> Result<PathBuf, OutputError> {
    let preview_err = |reason: String| OutputError::Preview {
        path: dir.to_owned(),
        reason,
    };
    if frames.is_empty() {
        return Err(preview_err("no frames".to_owned()));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(preview_err(format!("invalid fps {fps}")));
    }
    let gif_path = dir.join(PREVIEW_GIF_NAME);
    write_gif(dir, &gif_path, frames, fps)?;
    write_mp4(dir, frames, fps);
    Ok(gif_path)
}

fn write_gif(dir: &Path, gif_path: &Path, frames: &[u32], fps: f32) -> Result<(), OutputError> {
    let preview_err = |reason: String| OutputError::Preview {
        path: dir.to_owned(),
        reason,
    };
    let first = read_png_rgb8(dir.join(frame_png_name(frames[0])))?;
    let (src_w, src_h) = (first.width, first.height);
    let (dst_w, dst_h) = preview_size(src_w, src_h);
    if dst_w > u32::from(u16::MAX) || dst_h > u32::from(u16::MAX) {
        return Err(preview_err(format!(
            "preview size {dst_w}x{dst_h} too large"
        )));
    }
    let delay = ((100.0 / fps).round() as u16).max(2);
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(8);

    let mut first = Some(first);
    write_atomic(gif_path, |w| {
        let mut enc =
            gif::Encoder::new(w, dst_w as u16, dst_h as u16, &[]).map_err(io::Error::other)?;
        enc.set_repeat(gif::Repeat::Infinite)
            .map_err(io::Error::other)?;
        for batch in frames.chunks(threads) {
            // Read + downscale + quantise a batch of frames in parallel, write them in order.
            let results: Vec<Result<gif::Frame<'static>, OutputError>> = std::thread::scope(|s| {
                let handles: Vec<_> = batch
                    .iter()
                    .map(|&f| {
                        let pre = if f == frames[0] { first.take() } else { None };
                        s.spawn(move || -> Result<gif::Frame<'static>, OutputError> {
                            let img = match pre {
                                Some(img) => img,
                                None => read_png_rgb8(dir.join(frame_png_name(f)))?,
                            };
                            if (img.width, img.height) != (src_w, src_h) {
                                return Err(OutputError::Preview {
                                    path: dir.to_owned(),
                                    reason: format!(
                                        "{} is {}x{}, first frame is {src_w}x{src_h}",
                                        frame_png_name(f),
                                        img.width,
                                        img.height
                                    ),
                                });
                            }
                            let small = downscale_srgb8(&img, dst_w, dst_h);
                            let mut frame = gif::Frame::from_rgb_speed(
                                dst_w as u16,
                                dst_h as u16,
                                small.pixels.as_flattened(),
                                10,
                            );
                            frame.delay = delay;
                            Ok(frame)
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().expect("GIF worker panicked"))
                    .collect()
            });
            for r in results {
                let frame = r.map_err(io::Error::other)?;
                enc.write_frame(&frame).map_err(io::Error::other)?;
            }
        }
        enc.into_inner().map_err(io::Error::other)?;
        Ok(())
    })
    .map_err(|source| match source.downcast::<OutputError>() {
        Ok(e) => e,
        Err(source) => OutputError::Io {
            path: gif_path.to_owned(),
            source,
        },
    })
}

/// Size with the long side ≤ [`PREVIEW_MAX_SIDE`], aspect kept, at least 1×1.
fn preview_size(w: u32, h: u32) -> (u32, u32) {
    let long = w.max(h);
    if long <= PREVIEW_MAX_SIDE {
        return (w, h);
    }
    let scale = f64::from(PREVIEW_MAX_SIDE) / f64::from(long);
    let s = |v: u32| ((f64::from(v) * scale).round() as u32).clamp(1, PREVIEW_MAX_SIDE);
    (s(w), s(h))
}

/// Area-average resampling of an sRGB image, averaged in linear light.
fn downscale_srgb8(img: &Rgb8Image, dst_w: u32, dst_h: u32) -> Rgb8Image {
    if (img.width, img.height) == (dst_w, dst_h) {
        return img.clone();
    }
    let lin = img.to_linear();
    let wx = box_weights(img.width, dst_w);
    let wy = box_weights(img.height, dst_h);
    let (sw, dw) = (img.width as usize, dst_w as usize);
    // Horizontal pass: src_h rows of dst_w.
    let mut tmp = vec![glam::Vec3::ZERO; dw * img.height as usize];
    for y in 0..img.height as usize {
        let row = &lin.pixels[y * sw..(y + 1) * sw];
        for (x, taps) in wx.iter().enumerate() {
            tmp[y * dw + x] = taps.iter().map(|&(i, w)| row[i] * w).sum();
        }
    }
    // Vertical pass.
    let mut out = Vec::with_capacity(dw * dst_h as usize);
    for taps in &wy {
        for x in 0..dw {
            let c: glam::Vec3 = taps.iter().map(|&(j, w)| tmp[j * dw + x] * w).sum();
            let enc = |v: f32| (chronolux_core::color::linear_to_srgb(v) * 255.0).round() as u8;
            out.push([enc(c.x), enc(c.y), enc(c.z)]);
        }
    }
    Rgb8Image {
        width: dst_w,
        height: dst_h,
        pixels: out,
    }
}

/// For each destination index, the source indices and weights (summing to 1) of a box filter.
fn box_weights(src: u32, dst: u32) -> Vec<Vec<(usize, f32)>> {
    let ratio = f64::from(src) / f64::from(dst);
    (0..dst)
        .map(|i| {
            let (a, b) = (f64::from(i) * ratio, f64::from(i + 1) * ratio);
            let mut taps = Vec::new();
            let mut j = a.floor() as usize;
            while (j as f64) < b && j < src as usize {
                let cover = (b.min(j as f64 + 1.0) - a.max(j as f64)).max(0.0);
                if cover > 0.0 {
                    taps.push((j, (cover / ratio) as f32));
                }
                j += 1;
            }
            taps
        })
        .collect()
}

/// `preview.mp4` through `ffmpeg`, best effort: every failure is a warning.
fn write_mp4(dir: &Path, frames: &[u32], fps: f32) {
    let contiguous = frames.windows(2).all(|w| w[1] == w[0].wrapping_add(1));
    if !contiguous {
        log::warn!(
            "preview.mp4 skipped: frame numbers are not contiguous ({} frames from {} to {})",
            frames.len(),
            frames[0],
            frames[frames.len() - 1]
        );
        return;
    }
    let tmp_name = format!("{PREVIEW_MP4_NAME}.tmp");
    let fps_arg = format!("{fps}");
    let output = Command::new("ffmpeg")
        .current_dir(dir)
        .args(["-y", "-loglevel", "error", "-framerate", &fps_arg])
        .args([
            "-start_number",
            &frames[0].to_string(),
            "-i",
            "frame_%04d.png",
        ])
        .args(["-frames:v", &frames.len().to_string()])
        .args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
        .args([
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-f",
            "mp4",
            &tmp_name,
        ])
        .stdin(Stdio::null())
        .output();
    let tmp = dir.join(&tmp_name);
    match output {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            log::info!("preview.mp4 skipped: no ffmpeg on PATH (the GIF preview was written)");
        }
        Err(e) => log::warn!("preview.mp4 skipped: cannot run ffmpeg: {e}"),
        Ok(out) if !out.status.success() => {
            let _ = fs::remove_file(&tmp);
            log::warn!(
                "preview.mp4 skipped: ffmpeg failed ({}): {}",
                out.status,
                String::from_utf8_lossy(&out.stderr).trim()
            );
        }
        Ok(_) => match fs::rename(&tmp, dir.join(PREVIEW_MP4_NAME)) {
            Ok(()) => log::info!("wrote {}", dir.join(PREVIEW_MP4_NAME).display()),
            Err(e) => {
                let _ = fs::remove_file(&tmp);
                log::warn!("preview.mp4 skipped: cannot rename {}: {e}", tmp.display());
            }
        },
    }
}
