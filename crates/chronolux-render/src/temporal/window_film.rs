//! Accumulation of the frames of a sliding window: a temporal technique adds samples made
//! in one frame to every frame of its window, and takes a frame out once no later sample
//! can reach it.
//!
//! Two kinds of contribution per pixel of a frame:
//! - **weighted samples** (`add`): the pixel value is Σ value / Σ weight over the samples
//!   that landed in it (a reprojected camera sample lands wherever its point is seen);
//! - **splats** (`splat`): light-tracing contributions, summed and scaled once at
//!   [`WindowFilm::finish`] by a factor the technique knows (one over the number of light
//!   subpaths per pixel that served the frame), then added to the weighted mean.
//!
//! Contributions arrive in batches ([`WindowFilm::add_batch`]) built in parallel by the
//! technique and merged in a fixed order, so the result does not depend on thread count.
//!
//! This implementation keeps every open frame in memory; see the module's
//! [`WindowFilm::stats`] for what it reports.

use chronolux_core::color::Rgb;
use std::collections::BTreeMap;

/// One contribution to one pixel of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contribution {
    pub frame: u32,
    /// Pixel index `y · width + x`.
    pub pixel: u32,
    pub value: Rgb,
    /// Weight of a weighted sample; ignored for splats.
    pub weight: f32,
    /// True for a light-tracing splat.
    pub splat: bool,
}

/// What the film did so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FilmStats {
    /// Largest number of bytes of accumulation buffers held in memory at once.
    pub peak_bytes: u64,
    /// Tile accesses served from memory / that had to read a tile back from disk.
    pub tile_hits: u64,
    pub tile_misses: u64,
    /// Bytes written to and read from the disk cache.
    pub bytes_written: u64,
    pub bytes_read: u64,
    /// Wall time spent in disk I/O (s).
    pub io_seconds: f64,
}

/// Buffers of one open frame.
struct FrameBuf {
    sum: Vec<Rgb>,
    weight: Vec<f32>,
    splat: Vec<Rgb>,
}

/// Per-pixel accumulators for the open frames of a window.
pub struct WindowFilm {
    width: u32,
    height: u32,
    frames: BTreeMap<u32, FrameBuf>,
    stats: FilmStats,
}

impl WindowFilm {
    pub fn new(width: u32, height: u32) -> Self {
        WindowFilm {
            width,
            height,
            frames: BTreeMap::new(),
            stats: FilmStats::default(),
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    fn bytes_per_frame(&self) -> u64 {
        (self.width as u64) * (self.height as u64) * (12 + 4 + 12)
    }

    /// Adds a batch of contributions, in order.
    pub fn add_batch(&mut self, batch: &[Contribution]) {
        let n = (self.width * self.height) as usize;
        for c in batch {
            debug_assert!((c.pixel as usize) < n);
            let buf = self.frames.entry(c.frame).or_insert_with(|| FrameBuf {
                sum: vec![Rgb::ZERO; n],
                weight: vec![0.0; n],
                splat: vec![Rgb::ZERO; n],
            });
            let i = c.pixel as usize;
            if c.splat {
                buf.splat[i] += c.value;
            } else {
                buf.sum[i] += c.value * c.weight;
                buf.weight[i] += c.weight;
            }
        }
        let bytes = self.frames.len() as u64 * self.bytes_per_frame();
        self.stats.peak_bytes = self.stats.peak_bytes.max(bytes);
    }

    /// Takes frame `frame` out: per pixel Σ value·weight / Σ weight (0 where no sample
    /// landed) plus `splat_scale` × the splats, and the per-pixel weight (so the caller can
    /// report pixels no sample reached). A frame that received nothing is all zero.
    pub fn finish(&mut self, frame: u32, splat_scale: f32) -> (Vec<Rgb>, Vec<f32>) {
        let n = (self.width * self.height) as usize;
        let Some(buf) = self.frames.remove(&frame) else {
            return (vec![Rgb::ZERO; n], vec![0.0; n]);
        };
        let px = (0..n)
            .map(|i| {
                let mean = if buf.weight[i] > 0.0 {
                    buf.sum[i] / buf.weight[i]
                } else {
                    Rgb::ZERO
                };
                mean + buf.splat[i] * splat_scale
            })
            .collect();
        (px, buf.weight)
    }

    /// Frames currently open.
    pub fn open_frames(&self) -> Vec<u32> {
        self.frames.keys().copied().collect()
    }

    pub fn stats(&self) -> FilmStats {
        self.stats
    }
}
