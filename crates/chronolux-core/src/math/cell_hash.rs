//! A fast hasher for grid-cell keys, and the hash map that uses it.
//!
//! One multiply-rotate per word (the FxHash scheme of rustc). The standard SipHash was 3 %
//! of `spacetime-dept`'s CPU on a moving model (its element grid) and 3–4 % of
//! `ic-static-dynamic`'s (the irradiance cache's grid, looked up at every eye vertex and
//! cache point); cell keys come from the scene, not from an adversary, so a fast non-keyed
//! hash is enough. Nothing may depend on a map's iteration order (its users only look cells
//! up), so the hasher cannot change an image.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Hasher of small integer keys (grid cells).
#[derive(Default, Clone, Copy)]
pub struct CellHasher(u64);

impl Hasher for CellHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_i32(&mut self, i: i32) {
        self.write_u64(i as u32 as u64);
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

/// A hash map keyed by grid cells, hashed with [`CellHasher`].
pub type CellMap<K, V> = HashMap<K, V, BuildHasherDefault<CellHasher>>;
