//! Per-pixel sample streams.
//!
//! A [`PixelSampler`] is keyed by (seed, frame, pixel) and a sample index, so the numbers a
//! pixel receives never depend on tiling or thread count. Dimensions are consumed in a fixed
//! order by the integrator. The first [`SOBOL_DIMS`] dimensions come from Owen-scrambled
//! Sobol points (Burley 2020) — low discrepancy per pixel — and later ones from PCG32, since
//! deep bounces gain little from stratification.

use super::rng::{ONE_MINUS_EPSILON, Pcg32};

/// Dimensions served by the scrambled Sobol sequence before switching to PCG32.
pub const SOBOL_DIMS: u32 = 128;

/// Largest sample count per pixel for which the Sobol sequence is used (sobol_burley limit);
/// beyond it samples come from PCG32.
pub const SOBOL_MAX_SAMPLES: u32 = 1 << 16;

#[derive(Clone, Debug)]
pub struct PixelSampler {
    seed: u32,
    index: u32,
    dim: u32,
    rng: Pcg32,
    /// Sobol values of the 4-dimension set `cached_set` for the current sample: the
    /// sequence is evaluated four dimensions at a time (one SIMD call instead of four).
    cache: [f32; 4],
    cached_set: u32,
}

impl PixelSampler {
    /// Stream for pixel `(x, y)` of `frame`; `seed` is the user's seed.
    pub fn new(seed: u64, frame: u32, x: u32, y: u32) -> Self {
        let key = super::hash_words(&[seed, frame as u64, x as u64, y as u64]);
        PixelSampler {
            seed: key as u32,
            index: 0,
            dim: 0,
            rng: Pcg32::new(key, 0),
            cache: [0.0; 4],
            cached_set: u32::MAX,
        }
    }

    /// Starts sample `index` of this pixel.
    pub fn start_sample(&mut self, index: u32) {
        self.index = index;
        self.dim = 0;
        self.cached_set = u32::MAX;
        self.rng = Pcg32::new(
            super::mix64(self.seed as u64 ^ ((index as u64) << 32)),
            self.seed as u64,
        );
    }

    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        self.dim += 1;
        if d < SOBOL_DIMS && self.index < SOBOL_MAX_SAMPLES {
            let set = d / 4;
            if set != self.cached_set {
                self.cache = sobol_burley::sample_4d(self.index, set, self.seed);
                self.cached_set = set;
            }
            self.cache[(d % 4) as usize].min(ONE_MINUS_EPSILON)
        } else {
            self.rng.next_f32()
        }
    }

    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        glam::Vec2::new(self.next_1d(), self.next_1d())
    }
}
