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
//! # Tiles and the disk cache
//!
//! Each open frame is cut into [`FILM_TILE`]×[`FILM_TILE`] pixel tiles (edge tiles
//! clipped), 28 bytes per pixel (Σ value·weight, Σ weight, Σ splat). Tiles are created on
//! first touch, so a frame only costs memory where contributions landed. With a memory
//! budget ([`WindowFilm::with_budget`]), the least recently used tiles are written to one
//! file per frame in a cache directory when a new tile would exceed the budget, and read
//! back when touched again. The directory is created on the first spill (a film that never
//! spills touches no disk) and removed with the film.
//!
//! **Memory bound**: the accumulation tiles held in memory never exceed
//! `max(budget, one tile)`, plus one tile while [`WindowFilm::finish`] reads a spilled tile
//! back — so at most `budget + 64·64·28 B` (114 688 B) for a budget of at least one tile,
//! whatever the resolution, the window and the number of frames. Not counted: the per-frame tile tables (a few bytes per tile), the
//! caller's batch, and the two full-frame vectors `finish` returns (16 B per pixel, owned
//! by the caller).
//!
//! **Determinism**: [`WindowFilm::add_batch`] processes a batch grouped by (frame, tile)
//! for locality, keeping the order of the batch within each group. Contributions to one
//! pixel are therefore summed in batch order, exactly as a one-by-one loop would, and the
//! result is bit-identical for every budget (spilled tiles round-trip through their exact
//! f32 bit patterns).
//!
//! I/O errors on the cache directory (disk full) panic: the API has no error path, and a
//! silently dropped tile would be a wrong image.

use chronolux_core::color::Rgb;
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Tile edge in pixels of the film's accumulation tiles.
pub const FILM_TILE: u32 = 64;

/// Bytes per pixel of the accumulators: Σ value·weight (3 × f32), Σ weight (f32),
/// Σ splat (3 × f32).
const BYTES_PER_PIXEL: u64 = 28;

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
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FilmStats {
    /// Largest number of bytes of accumulation tiles held in memory at once.
    pub peak_bytes: u64,
    /// Tile accesses served from memory / that had to read a tile back from disk. One
    /// access per (frame, tile) group of a batch and per tile taken out by `finish`; the
    /// first touch of a tile (created empty) counts as neither.
    pub tile_hits: u64,
    pub tile_misses: u64,
    /// Tiles written to the disk cache (evictions).
    pub tiles_written: u64,
    /// Bytes written to and read from the disk cache.
    pub bytes_written: u64,
    pub bytes_read: u64,
    /// Wall time spent in disk I/O (s).
    pub io_seconds: f64,
    /// Memory budget of the accumulation tiles (bytes; `u64::MAX` = unbounded).
    pub budget_bytes: u64,
}

/// Accumulators of one tile: per pixel 7 floats, Σ value·weight (x, y, z), Σ weight,
/// Σ splat (x, y, z) — one pixel's accumulators in one cache line, and a tile's bytes on
/// disk are the floats' exact little-endian bit patterns in this order.
struct TileBuf {
    data: Vec<f32>,
}

const FLOATS: usize = 7;

impl TileBuf {
    fn zeros(n: usize) -> Self {
        TileBuf {
            data: vec![0.0; FLOATS * n],
        }
    }

    #[inline]
    fn add(&mut self, k: usize, c: &Contribution) {
        let d = &mut self.data[FLOATS * k..FLOATS * k + FLOATS];
        if c.splat {
            d[4] += c.value.x;
            d[5] += c.value.y;
            d[6] += c.value.z;
        } else {
            // The same f32 operations as `sum += value * weight; weight += weight` on Rgb.
            let v = c.value * c.weight;
            d[0] += v.x;
            d[1] += v.y;
            d[2] += v.z;
            d[3] += c.weight;
        }
    }

    /// (Σ value·weight, Σ weight, Σ splat) of pixel `k`.
    #[inline]
    fn get(&self, k: usize) -> (Rgb, f32, Rgb) {
        let d = &self.data[FLOATS * k..FLOATS * k + FLOATS];
        (Rgb::new(d[0], d[1], d[2]), d[3], Rgb::new(d[4], d[5], d[6]))
    }

    fn write_bytes(&self, out: &mut Vec<u8>) {
        out.resize(4 * self.data.len(), 0);
        for (b, v) in out.chunks_exact_mut(4).zip(&self.data) {
            b.copy_from_slice(&v.to_le_bytes());
        }
    }

    fn read_bytes(n: usize, bytes: &[u8]) -> Self {
        let data = bytes[..4 * FLOATS * n]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        TileBuf { data }
    }
}

enum Slot {
    /// Never touched: all zero.
    Absent,
    /// In memory; `stamp` is its key in the LRU list.
    Resident { buf: Box<TileBuf>, stamp: u64 },
    /// Written to the frame's cache file at `tile index × tile stride`.
    OnDisk,
}

/// Tiles of one open frame.
struct FrameTiles {
    slots: Vec<Slot>,
    /// Cache file, created on the frame's first spill.
    file: Option<File>,
}

/// Per-pixel accumulators for the open frames of a window.
pub struct WindowFilm {
    width: u32,
    height: u32,
    tiles_x: u32,
    tiles_y: u32,
    budget: u64,
    frames: BTreeMap<u32, FrameTiles>,
    /// Resident tiles by last use (smallest stamp = least recently used).
    lru: BTreeMap<u64, (u32, u32)>,
    clock: u64,
    resident_bytes: u64,
    /// Where the cache directory is made (`None`: the system temp dir).
    cache_parent: Option<PathBuf>,
    /// The cache directory, once created; removed on drop.
    cache_dir: Option<PathBuf>,
    scratch: Vec<u8>,
    /// Scratch of [`Self::add_batch_where`], kept between batches: batch indices in
    /// (frame, tile) order, each contribution's slot, slot starts, and the groups (start
    /// and end in `order`, frame, tile).
    order: Vec<u32>,
    slot_of: Vec<u32>,
    start: Vec<u32>,
    groups: Vec<(u32, u32, u32, u32)>,
    /// Direction of the next batch's walk over its (frame, tile) groups.
    reverse: bool,
    stats: FilmStats,
}

/// Distinguishes the cache directories of several films of one process.
static FILM_COUNTER: AtomicU64 = AtomicU64::new(0);

impl WindowFilm {
    /// A film that keeps every tile in memory (no disk cache).
    pub fn new(width: u32, height: u32) -> Self {
        Self::build(width, height, u64::MAX, None)
    }

    /// A film holding at most `budget_bytes` of accumulation tiles in memory (see the
    /// module doc for the exact bound); least recently used tiles spill to a fresh
    /// directory inside `dir` (the system temp dir when `None`), removed on drop.
    pub fn with_budget(width: u32, height: u32, budget_bytes: u64, dir: Option<&Path>) -> Self {
        Self::build(width, height, budget_bytes, dir.map(Path::to_path_buf))
    }

    fn build(width: u32, height: u32, budget: u64, cache_parent: Option<PathBuf>) -> Self {
        WindowFilm {
            width,
            height,
            tiles_x: width.div_ceil(FILM_TILE),
            tiles_y: height.div_ceil(FILM_TILE),
            budget,
            frames: BTreeMap::new(),
            lru: BTreeMap::new(),
            clock: 0,
            resident_bytes: 0,
            cache_parent,
            cache_dir: None,
            scratch: Vec::new(),
            order: Vec::new(),
            slot_of: Vec::new(),
            start: Vec::new(),
            groups: Vec::new(),
            reverse: false,
            stats: FilmStats {
                budget_bytes: budget,
                ..Default::default()
            },
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Bytes of a full tile (the stride of the cache files).
    pub fn tile_bytes() -> u64 {
        (FILM_TILE as u64) * (FILM_TILE as u64) * BYTES_PER_PIXEL
    }

    /// The cache directory, if the film has spilled.
    pub fn cache_dir(&self) -> Option<&Path> {
        self.cache_dir.as_deref()
    }

    /// Pixel rectangle (x0, y0, w, h) of tile `t`.
    fn tile_rect(&self, t: u32) -> (u32, u32, u32, u32) {
        crate::framework::integrator::tile_rect(t, self.tiles_x, FILM_TILE, self.width, self.height)
    }

    fn tile_pixels(&self, t: u32) -> usize {
        let (_, _, w, h) = self.tile_rect(t);
        (w * h) as usize
    }

    /// Tile of pixel `p`.
    #[inline]
    fn tile_of(&self, p: u32) -> u32 {
        let (x, y) = (p % self.width, p / self.width);
        (y / FILM_TILE) * self.tiles_x + x / FILM_TILE
    }

    /// Adds a batch of contributions, in order (grouped by (frame, tile), batch order kept
    /// within a group: bit-identical to adding them one by one).
    pub fn add_batch(&mut self, batch: &[Contribution]) {
        self.add_batch_where(batch, |_| true);
    }

    /// [`Self::add_batch`] of the contributions whose frame `keep` accepts (the others
    /// are skipped, as if the batch had been filtered first).
    ///
    /// Grouping is a counting sort over the (frame, tile) slots the batch spans: stable,
    /// so each group keeps batch order, and linear in the batch (the comparison sort it
    /// replaced, with a filtered copy of every batch, was ≈ 4 % of a stbpt run in `perf`,
    /// BENCHMARKS.md). A batch spread thinly over many frames (more slots than
    /// contributions) is grouped by a sort instead.
    pub fn add_batch_where(&mut self, batch: &[Contribution], keep: impl Fn(u32) -> bool) {
        let n = self.width as u64 * self.height as u64;
        let n_tiles = (self.tiles_x * self.tiles_y) as usize;
        let (lo, hi) = batch.iter().fold((u32::MAX, 0u32), |(lo, hi), c| {
            debug_assert!((c.pixel as u64) < n, "pixel {} outside the film", c.pixel);
            (lo.min(c.frame), hi.max(c.frame))
        });
        if batch.is_empty() {
            return;
        }
        // `keep` once per frame of the batch's range, not once per contribution (unless
        // the range is far wider than the batch).
        let table = ((hi - lo) as usize) <= batch.len() + 1024;
        let kept_frames: Vec<bool> = if table {
            (lo..=hi).map(&keep).collect()
        } else {
            Vec::new()
        };
        let keep = |f: u32| {
            if table {
                kept_frames[(f - lo) as usize]
            } else {
                keep(f)
            }
        };
        let kept = batch.iter().filter(|c| keep(c.frame)).count();
        if kept == 0 {
            return;
        }
        // (frame, tile) slot of contribution i, or SKIP; slots ascend with (frame, tile).
        const SKIP: u32 = u32::MAX;
        let slots = (hi - lo) as usize * n_tiles + n_tiles;
        let mut order = std::mem::take(&mut self.order);
        let mut groups = std::mem::take(&mut self.groups);
        order.clear();
        groups.clear();
        if slots <= 4 * kept + 1024 {
            let mut slot_of = std::mem::take(&mut self.slot_of);
            let mut start = std::mem::take(&mut self.start);
            slot_of.clear();
            start.clear();
            start.resize(slots + 1, 0);
            for c in batch {
                if keep(c.frame) {
                    let s = (c.frame - lo) as usize * n_tiles + self.tile_of(c.pixel) as usize;
                    start[s + 1] += 1;
                    slot_of.push(s as u32);
                } else {
                    slot_of.push(SKIP);
                }
            }
            for s in 0..slots {
                start[s + 1] += start[s];
                if start[s + 1] > start[s] {
                    let frame = lo + (s / n_tiles) as u32;
                    groups.push((start[s], start[s + 1], frame, (s % n_tiles) as u32));
                }
            }
            order.resize(kept, 0);
            for (i, &s) in slot_of.iter().enumerate() {
                if s != SKIP {
                    let at = &mut start[s as usize];
                    order[*at as usize] = i as u32;
                    *at += 1;
                }
            }
            self.slot_of = slot_of;
            self.start = start;
        } else {
            // (key, index) pairs are distinct: sorting them is a stable sort by key.
            let mut keys: Vec<(u64, u32)> = batch
                .iter()
                .enumerate()
                .filter(|(_, c)| keep(c.frame))
                .map(|(i, c)| {
                    (
                        ((c.frame as u64) << 32) | self.tile_of(c.pixel) as u64,
                        i as u32,
                    )
                })
                .collect();
            keys.sort_unstable();
            let mut g = 0;
            while g < keys.len() {
                let end = g + keys[g..].iter().take_while(|k| k.0 == keys[g].0).count();
                let key = keys[g].0;
                groups.push((g as u32, end as u32, (key >> 32) as u32, key as u32));
                g = end;
            }
            order.extend(keys.iter().map(|k| k.1));
        }
        // Consecutive batches of a sweep touch nearly the same tiles in the same order: a
        // cyclic pattern on which LRU misses every time once the tiles do not all fit.
        // Alternating the direction makes the most recently used tiles the next ones used,
        // so hits degrade gracefully with the budget. Groups are disjoint pixel sets, so
        // the order of groups changes no sum.
        if self.reverse {
            groups.reverse();
        }
        self.reverse = !self.reverse;
        for &(g, end, frame, tile) in &groups {
            let (x0, y0, tw, _) = self.tile_rect(tile);
            let width = self.width;
            let buf = self.tile_mut(frame, tile);
            for &i in &order[g as usize..end as usize] {
                let c = &batch[i as usize];
                let (x, y) = (c.pixel % width, c.pixel / width);
                let k = ((y - y0) * tw + (x - x0)) as usize;
                buf.add(k, c);
            }
        }
        self.order = order;
        self.groups = groups;
    }

    /// The accumulators of (frame, tile), made resident (created, or read back from disk)
    /// and marked most recently used.
    fn tile_mut(&mut self, frame: u32, tile: u32) -> &mut TileBuf {
        let n_tiles = (self.tiles_x * self.tiles_y) as usize;
        let state = match self.frames.get(&frame).map(|f| &f.slots[tile as usize]) {
            None | Some(Slot::Absent) => 0,
            Some(Slot::Resident { .. }) => 1,
            Some(Slot::OnDisk) => 2,
        };
        let stamp = self.clock;
        self.clock += 1;
        if state == 1 {
            self.stats.tile_hits += 1;
        } else {
            let npx = self.tile_pixels(tile);
            let bytes = npx as u64 * BYTES_PER_PIXEL;
            self.make_room(bytes);
            let buf = if state == 2 {
                self.stats.tile_misses += 1;
                self.read_tile(frame, tile, npx)
            } else {
                TileBuf::zeros(npx)
            };
            self.resident_bytes += bytes;
            self.stats.peak_bytes = self.stats.peak_bytes.max(self.resident_bytes);
            let ft = self.frames.entry(frame).or_insert_with(|| FrameTiles {
                slots: (0..n_tiles).map(|_| Slot::Absent).collect(),
                file: None,
            });
            ft.slots[tile as usize] = Slot::Resident {
                buf: Box::new(buf),
                stamp,
            };
            self.lru.insert(stamp, (frame, tile));
        }
        let slot = &mut self.frames.get_mut(&frame).expect("frame open").slots[tile as usize];
        match slot {
            Slot::Resident { buf, stamp: s } => {
                if *s != stamp {
                    self.lru.remove(s);
                    *s = stamp;
                    self.lru.insert(stamp, (frame, tile));
                }
                buf
            }
            _ => unreachable!("tile made resident above"),
        }
    }

    /// Evicts least recently used tiles until `bytes` more fit in the budget (or nothing
    /// is left to evict).
    fn make_room(&mut self, bytes: u64) {
        while self.resident_bytes.saturating_add(bytes) > self.budget {
            let Some((_, (frame, tile))) = self.lru.pop_first() else {
                break;
            };
            let npx = self.tile_pixels(tile);
            let dir = self.ensure_cache_dir();
            let ft = self
                .frames
                .get_mut(&frame)
                .expect("resident tile of an open frame");
            let Slot::Resident { buf, .. } =
                std::mem::replace(&mut ft.slots[tile as usize], Slot::OnDisk)
            else {
                unreachable!("LRU lists resident tiles only");
            };
            let start = Instant::now();
            let file = ft.file.get_or_insert_with(|| {
                let path = dir.join(format!("frame_{frame}.bin"));
                OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(true)
                    .open(&path)
                    .unwrap_or_else(|e| panic!("film cache: cannot create {}: {e}", path.display()))
            });
            buf.write_bytes(&mut self.scratch);
            file.write_all_at(&self.scratch, tile as u64 * Self::tile_bytes())
                .unwrap_or_else(|e| {
                    panic!("film cache: cannot write a tile of frame {frame}: {e}")
                });
            self.stats.io_seconds += start.elapsed().as_secs_f64();
            self.stats.bytes_written += self.scratch.len() as u64;
            self.stats.tiles_written += 1;
            self.resident_bytes -= npx as u64 * BYTES_PER_PIXEL;
        }
    }

    fn read_tile(&mut self, frame: u32, tile: u32, npx: usize) -> TileBuf {
        let start = Instant::now();
        let len = npx * BYTES_PER_PIXEL as usize;
        self.scratch.resize(len, 0);
        let file = self.frames[&frame]
            .file
            .as_ref()
            .expect("a spilled tile has a cache file");
        file.read_exact_at(&mut self.scratch, tile as u64 * Self::tile_bytes())
            .unwrap_or_else(|e| panic!("film cache: cannot read a tile of frame {frame}: {e}"));
        self.stats.io_seconds += start.elapsed().as_secs_f64();
        self.stats.bytes_read += len as u64;
        TileBuf::read_bytes(npx, &self.scratch)
    }

    fn ensure_cache_dir(&mut self) -> PathBuf {
        if let Some(d) = &self.cache_dir {
            return d.clone();
        }
        let parent = self.cache_parent.clone().unwrap_or_else(std::env::temp_dir);
        for _ in 0..1000 {
            let d = parent.join(format!(
                "chronolux-film-{}-{}",
                std::process::id(),
                FILM_COUNTER.fetch_add(1, Ordering::Relaxed)
            ));
            match std::fs::create_dir_all(&parent).and_then(|_| std::fs::create_dir(&d)) {
                Ok(()) => {
                    self.cache_dir = Some(d.clone());
                    return d;
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => panic!("film cache: cannot create {}: {e}", d.display()),
            }
        }
        panic!("film cache: no free directory name in {}", parent.display());
    }

    /// Takes frame `frame` out: per pixel Σ value·weight / Σ weight (0 where no sample
    /// landed) plus `splat_scale` × the splats, and the per-pixel weight (so the caller can
    /// report pixels no sample reached). A frame that received nothing is all zero.
    pub fn finish(&mut self, frame: u32, splat_scale: f32) -> (Vec<Rgb>, Vec<f32>) {
        let n = (self.width * self.height) as usize;
        let mut px = vec![Rgb::ZERO; n];
        let mut wt = vec![0.0f32; n];
        let Some(ft) = self.frames.remove(&frame) else {
            return (px, wt);
        };
        let FrameTiles { slots, file } = ft;
        for (t, slot) in slots.into_iter().enumerate() {
            let t = t as u32;
            let npx = self.tile_pixels(t);
            let buf = match slot {
                Slot::Absent => continue,
                Slot::Resident { buf, stamp } => {
                    self.lru.remove(&stamp);
                    self.resident_bytes -= npx as u64 * BYTES_PER_PIXEL;
                    self.stats.tile_hits += 1;
                    *buf
                }
                Slot::OnDisk => {
                    let start = Instant::now();
                    let len = npx * BYTES_PER_PIXEL as usize;
                    self.scratch.resize(len, 0);
                    file.as_ref()
                        .expect("a spilled tile has a cache file")
                        .read_exact_at(&mut self.scratch, t as u64 * Self::tile_bytes())
                        .unwrap_or_else(|e| {
                            panic!("film cache: cannot read a tile of frame {frame}: {e}")
                        });
                    self.stats.io_seconds += start.elapsed().as_secs_f64();
                    self.stats.bytes_read += len as u64;
                    self.stats.tile_misses += 1;
                    // One tile over the resident set while it is read back.
                    let held = self.resident_bytes + npx as u64 * BYTES_PER_PIXEL;
                    self.stats.peak_bytes = self.stats.peak_bytes.max(held);
                    TileBuf::read_bytes(npx, &self.scratch)
                }
            };
            let (x0, y0, tw, th) = self.tile_rect(t);
            for y in 0..th {
                for x in 0..tw {
                    let k = (y * tw + x) as usize;
                    let i = ((y0 + y) * self.width + x0 + x) as usize;
                    let (sum, weight, splat) = buf.get(k);
                    let mean = if weight > 0.0 {
                        sum / weight
                    } else {
                        Rgb::ZERO
                    };
                    px[i] = mean + splat * splat_scale;
                    wt[i] = weight;
                }
            }
        }
        if file.is_some() {
            drop(file);
            if let Some(d) = &self.cache_dir {
                let _ = std::fs::remove_file(d.join(format!("frame_{frame}.bin")));
            }
        }
        (px, wt)
    }

    /// Frames currently open.
    pub fn open_frames(&self) -> Vec<u32> {
        self.frames.keys().copied().collect()
    }

    /// Bytes of accumulation tiles in memory now.
    pub fn resident_bytes(&self) -> u64 {
        self.resident_bytes
    }

    pub fn stats(&self) -> FilmStats {
        self.stats
    }
}

impl Drop for WindowFilm {
    fn drop(&mut self) {
        // Close the cache files before removing their directory.
        self.frames.clear();
        if let Some(d) = self.cache_dir.take() {
            let _ = std::fs::remove_dir_all(d);
        }
    }
}
