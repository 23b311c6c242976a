//! Per-direction storage of the selective irradiance cache (`ic-selective`, see
//! [`super`]): for every record a fixed-size block of [`Stratum`]s (one per
//! stratum of its M×N gather), addressed by the record's **slot**.
//!
//! Two implementations of [`StrataStore`] give identical contents for the same sequence of
//! reads and writes (the paged one round-trips every value bit for bit):
//! - [`MemoryStore`]: one `Vec`, growing with the highest slot used;
//! - [`PagedStore`]: a file of fixed-size **pages** (each holding `records_per_page` whole
//!   records, [`Stratum::BYTES`] bytes per stratum, little-endian 32-bit words) and an in-memory LRU
//!   cache of at most `cache_pages` pages, read and written with
//!   [`FileExt::read_at`]/[`FileExt::write_at`]. A page is read on its first use after
//!   eviction and written back only when dirty. **Memory bound**: `cache_pages × page
//!   bytes` (plus one page index entry per cached page), whatever the number of records
//!   and frames; the file grows with the highest slot in use (slots are reused, see
//!   [`super`]). The file is unlinked as soon as it is created (Unix), so it
//!   disappears with the process.

use crate::kernels::gather::precomputed::MAX_GROUPS;
use chronolux_core::color::Rgb;
use chronolux_core::math::Vec3;
use std::collections::HashMap;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::PathBuf;

/// What one gather direction of a record keeps between frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stratum {
    /// Incident radiance along the stratum's direction (with per-group terms: their sum).
    pub l: Rgb,
    /// Distance to the first hit (`f32::INFINITY`: nothing hit).
    pub dist: f32,
    /// Instance of the first hit ([`Stratum::NO_HIT`]: nothing hit).
    pub hit: u32,
    /// Frame in which it was cast (its age is the current frame minus this; its direction
    /// is jittered from numbers hashed from it).
    pub cast: u32,
    /// With per-group terms ([`super::IcSelectiveSettings::light_terms`]): the vertex whose
    /// radiance the ray reads, its side normal and weight
    /// ([`crate::kernels::gather::precomputed::GatherHit`]), and each light group's term
    /// `w · E_g(x)` (zero otherwise, and past the frame's groups).
    pub x: Vec3,
    pub ns: Vec3,
    pub w: Rgb,
    pub terms: [Rgb; MAX_GROUPS],
}

impl Stratum {
    pub const NO_HIT: u32 = u32::MAX;
    /// 32-bit words of one stratum on disk.
    const WORDS: usize = 15 + 3 * MAX_GROUPS;
    /// Bytes of one stratum on disk.
    pub const BYTES: usize = 4 * Self::WORDS;
    pub const EMPTY: Stratum = Stratum {
        l: Rgb::ZERO,
        dist: f32::INFINITY,
        hit: Stratum::NO_HIT,
        cast: 0,
        x: Vec3::ZERO,
        ns: Vec3::ZERO,
        w: Rgb::ZERO,
        terms: [Rgb::ZERO; MAX_GROUPS],
    };

    fn encode(&self, out: &mut [u8]) {
        let mut w = [0u32; Self::WORDS];
        let mut i = 0;
        let mut put = |v: u32| {
            w[i] = v;
            i += 1;
        };
        for c in [self.l, self.x, self.ns, self.w]
            .into_iter()
            .chain(self.terms)
        {
            put(c.x.to_bits());
            put(c.y.to_bits());
            put(c.z.to_bits());
        }
        put(self.dist.to_bits());
        put(self.hit);
        put(self.cast);
        for (c, v) in out.chunks_exact_mut(4).zip(w) {
            c.copy_from_slice(&v.to_le_bytes());
        }
    }

    fn decode(b: &[u8]) -> Stratum {
        let w = |i: usize| u32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
        let v = |i: usize| {
            Vec3::new(
                f32::from_bits(w(3 * i)),
                f32::from_bits(w(3 * i + 1)),
                f32::from_bits(w(3 * i + 2)),
            )
        };
        let t = 3 * (4 + MAX_GROUPS);
        Stratum {
            l: v(0),
            x: v(1),
            ns: v(2),
            w: v(3),
            terms: std::array::from_fn(|g| v(4 + g)),
            dist: f32::from_bits(w(t)),
            hit: w(t + 1),
            cast: w(t + 2),
        }
    }
}

/// Traffic of a store (cumulative).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StoreStats {
    /// Record blocks read / written by the technique.
    pub record_reads: u64,
    pub record_writes: u64,
    /// Pages read from / written to the file (0 for the memory store).
    pub page_reads: u64,
    pub page_writes: u64,
    /// Record accesses served by a cached page.
    pub page_hits: u64,
    /// Bytes of pages held in memory now and at most so far.
    pub resident_bytes: u64,
    pub peak_resident_bytes: u64,
    /// Size of the backing file (bytes).
    pub file_bytes: u64,
}

/// Where the strata of the records live; `read`/`write` move one record's whole block
/// (`strata_per_record` strata). A slot never written reads as [`Stratum::EMPTY`].
pub trait StrataStore: Send {
    fn strata_per_record(&self) -> usize;
    fn read(&mut self, slot: u32, out: &mut [Stratum]);
    fn write(&mut self, slot: u32, data: &[Stratum]);
    fn stats(&self) -> StoreStats;
}

/// All strata in memory.
pub struct MemoryStore {
    spr: usize,
    data: Vec<Stratum>,
    stats: StoreStats,
}

impl MemoryStore {
    pub fn new(strata_per_record: usize) -> Self {
        MemoryStore {
            spr: strata_per_record.max(1),
            data: Vec::new(),
            stats: StoreStats::default(),
        }
    }
}

impl StrataStore for MemoryStore {
    fn strata_per_record(&self) -> usize {
        self.spr
    }

    fn read(&mut self, slot: u32, out: &mut [Stratum]) {
        self.stats.record_reads += 1;
        let at = slot as usize * self.spr;
        if at + self.spr <= self.data.len() {
            out.copy_from_slice(&self.data[at..at + self.spr]);
        } else {
            out.fill(Stratum::EMPTY);
        }
    }

    fn write(&mut self, slot: u32, data: &[Stratum]) {
        self.stats.record_writes += 1;
        let at = slot as usize * self.spr;
        if self.data.len() < at + self.spr {
            self.data.resize(at + self.spr, Stratum::EMPTY);
        }
        self.data[at..at + self.spr].copy_from_slice(data);
        let bytes = (self.data.len() * Stratum::BYTES) as u64;
        self.stats.resident_bytes = bytes;
        self.stats.peak_resident_bytes = self.stats.peak_resident_bytes.max(bytes);
    }

    fn stats(&self) -> StoreStats {
        self.stats
    }
}

struct Page {
    index: u64,
    data: Vec<u8>,
    dirty: bool,
    last_use: u64,
}

/// Strata in a file of fixed-size pages with an LRU cache of pages (see the module doc).
pub struct PagedStore {
    spr: usize,
    record_bytes: usize,
    records_per_page: usize,
    page_bytes: usize,
    capacity: usize,
    file: File,
    pages: Vec<Page>,
    where_: HashMap<u64, usize>,
    clock: u64,
    file_len: u64,
    stats: StoreStats,
}

impl PagedStore {
    /// A store in a new unlinked file under `dir` (the system's temporary directory when
    /// `None`), pages of about `page_bytes` bytes (rounded down to whole records, at least
    /// one), at most `cache_pages` (≥ 1) of them in memory.
    pub fn new(
        strata_per_record: usize,
        page_bytes: usize,
        cache_pages: usize,
        dir: Option<PathBuf>,
    ) -> std::io::Result<Self> {
        let spr = strata_per_record.max(1);
        let record_bytes = spr * Stratum::BYTES;
        let records_per_page = (page_bytes / record_bytes).max(1);
        let dir = dir.unwrap_or_else(std::env::temp_dir);
        static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path = dir.join(format!(
            "chronolux-icsel-{}-{n}-{}.pages",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_nanos())
                .unwrap_or(0)
        ));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)?;
        // The open handle keeps the data; nothing is left behind when the process ends.
        std::fs::remove_file(&path)?;
        Ok(PagedStore {
            spr,
            record_bytes,
            records_per_page,
            page_bytes: records_per_page * record_bytes,
            capacity: cache_pages.max(1),
            file,
            pages: Vec::new(),
            where_: HashMap::new(),
            clock: 0,
            file_len: 0,
            stats: StoreStats::default(),
        })
    }

    /// Bytes of one page.
    pub fn page_bytes(&self) -> usize {
        self.page_bytes
    }

    /// The cached page holding `slot` (read or made, evicting the least recently used
    /// page when the cache is full) and the record's byte offset in it.
    fn page_of(&mut self, slot: u32) -> (usize, usize) {
        self.clock += 1;
        let index = slot as u64 / self.records_per_page as u64;
        let offset = (slot as usize % self.records_per_page) * self.record_bytes;
        if let Some(&i) = self.where_.get(&index) {
            self.stats.page_hits += 1;
            self.pages[i].last_use = self.clock;
            return (i, offset);
        }
        let at = if self.pages.len() < self.capacity {
            self.pages.push(Page {
                index,
                data: vec![0; self.page_bytes],
                dirty: false,
                last_use: 0,
            });
            self.pages.len() - 1
        } else {
            let victim = (0..self.pages.len())
                .min_by_key(|&i| self.pages[i].last_use)
                .expect("capacity ≥ 1");
            self.flush_page(victim);
            self.where_.remove(&self.pages[victim].index);
            victim
        };
        let pos = index * self.page_bytes as u64;
        let page = &mut self.pages[at];
        page.index = index;
        page.dirty = false;
        page.last_use = self.clock;
        // Bytes past the end of the file were never written: empty strata.
        let have = self
            .file_len
            .saturating_sub(pos)
            .min(self.page_bytes as u64) as usize;
        if have > 0 {
            self.file
                .read_exact_at(&mut page.data[..have], pos)
                .expect("ic-selective: reading the strata file");
            self.stats.page_reads += 1;
        }
        if have < self.page_bytes {
            let empty = {
                let mut b = [0u8; Stratum::BYTES];
                Stratum::EMPTY.encode(&mut b);
                b
            };
            for c in page.data[have..].chunks_exact_mut(Stratum::BYTES) {
                c.copy_from_slice(&empty);
            }
        }
        self.where_.insert(index, at);
        let resident = (self.pages.len() * self.page_bytes) as u64;
        self.stats.resident_bytes = resident;
        self.stats.peak_resident_bytes = self.stats.peak_resident_bytes.max(resident);
        (at, offset)
    }

    fn flush_page(&mut self, i: usize) {
        let page = &mut self.pages[i];
        if !page.dirty {
            return;
        }
        let pos = page.index * self.page_bytes as u64;
        self.file
            .write_all_at(&page.data, pos)
            .expect("ic-selective: writing the strata file");
        page.dirty = false;
        self.stats.page_writes += 1;
        self.file_len = self.file_len.max(pos + self.page_bytes as u64);
        self.stats.file_bytes = self.file_len;
    }
}

impl StrataStore for PagedStore {
    fn strata_per_record(&self) -> usize {
        self.spr
    }

    fn read(&mut self, slot: u32, out: &mut [Stratum]) {
        self.stats.record_reads += 1;
        let (i, off) = self.page_of(slot);
        let bytes = &self.pages[i].data[off..off + self.record_bytes];
        for (o, b) in out.iter_mut().zip(bytes.chunks_exact(Stratum::BYTES)) {
            *o = Stratum::decode(b);
        }
    }

    fn write(&mut self, slot: u32, data: &[Stratum]) {
        self.stats.record_writes += 1;
        let (i, off) = self.page_of(slot);
        let page = &mut self.pages[i];
        for (s, b) in data
            .iter()
            .zip(page.data[off..off + self.record_bytes].chunks_exact_mut(Stratum::BYTES))
        {
            s.encode(b);
        }
        page.dirty = true;
    }

    fn stats(&self) -> StoreStats {
        self.stats
    }
}
