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

/// Sets of four dimensions served by Sobol points.
const SOBOL_SETS: usize = (SOBOL_DIMS / 4) as usize;

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
    /// Burley's shuffled (Owen-scrambled, bit-reversed) index of the current sample: the
    /// same for every dimension set of the sample, so computed once in `start_sample`.
    shuffled_rev: u32,
    /// Per dimension set, the hashed Owen-scramble seeds of the pixel (the same for every
    /// sample of the pixel), filled on first use; bit `k` of `scrambles_set` marks set `k`.
    scrambles: [[u32; 4]; SOBOL_SETS],
    scrambles_set: u32,
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
            shuffled_rev: 0,
            scrambles: [[0; 4]; SOBOL_SETS],
            scrambles_set: 0,
        }
    }

    /// Starts sample `index` of this pixel.
    pub fn start_sample(&mut self, index: u32) {
        self.index = index;
        self.dim = 0;
        self.cached_set = u32::MAX;
        self.shuffled_rev = sobol4::shuffle(index, self.seed);
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
                let bit = 1u32 << set;
                if self.scrambles_set & bit == 0 {
                    self.scrambles[set as usize] = sobol4::scramble(set, self.seed);
                    self.scrambles_set |= bit;
                }
                self.cache = sobol4::sample(self.shuffled_rev, set, self.scrambles[set as usize]);
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

/// `sobol_burley::sample_4d` (Burley 2020: shuffled, Owen-scrambled Sobol points, four
/// dimensions at a time), bit for bit, in three parts so that a pixel's sampler computes
/// each only as often as its inputs change: the index shuffle once per sample
/// ([`shuffle`]), the scramble seeds once per pixel and set ([`scramble`]), and the Sobol
/// matrix product per sample and set ([`sample`]), which reads the XOR of the direction
/// vectors for each 4-bit digit of the index from a table (four loads instead of a loop
/// over the index's set bits; 32 KiB for the 32 sets). Profiled on `path` (cornell-moving),
/// the crate's `sample_4d` was 7.7 % of the CPU.
mod sobol4 {
    use super::SOBOL_SETS;
    use sobol_burley::parts::{
        Int4, hash, hash_int4, owen_scramble_int4_rev, owen_scramble_rev, sobol_int4_rev,
    };
    use std::sync::OnceLock;

    /// `DIGITS[set][k][v]`: XOR of the direction vectors of `set` selected by the 4-bit
    /// digit `v` at position `k` (from the top) of the 16 used bits of a reversed index.
    type Digits = [[[[u32; 4]; 16]; 4]; SOBOL_SETS];

    fn digits() -> &'static Digits {
        static T: OnceLock<Box<Digits>> = OnceLock::new();
        T.get_or_init(|| {
            let mut t = Box::new([[[[0u32; 4]; 16]; 4]; SOBOL_SETS]);
            for (set, table) in t.iter_mut().enumerate() {
                for (k, digit) in table.iter_mut().enumerate() {
                    for (v, entry) in digit.iter_mut().enumerate() {
                        // The digit's bits as a reversed index (its top 16 bits are used);
                        // the crate's own product gives the XOR of their vectors.
                        let rev = (v as u32) << (28 - 4 * k);
                        *entry = sobol_int4_rev(rev, set as u32).into();
                    }
                }
            }
            t
        })
    }

    /// The shuffled, bit-reversed index of sample `index` under `seed`.
    #[inline]
    pub fn shuffle(index: u32, seed: u32) -> u32 {
        owen_scramble_rev(index.reverse_bits(), hash(seed ^ 0x79c68e4a))
    }

    /// The hashed Owen-scramble seeds of dimension set `set` under `seed`.
    #[inline]
    pub fn scramble(set: u32, seed: u32) -> [u32; 4] {
        let s = seed.wrapping_mul(0x9c8f2d3b) ^ set;
        let raw: Int4 = [
            s ^ 0x912f69ba,
            s ^ 0x174f18ab,
            s ^ 0x691e72ca,
            s ^ 0xb40cc1b8,
        ]
        .into();
        hash_int4(raw).into()
    }

    /// The four values of dimension set `set` at the shuffled index `shuffled_rev`, with the
    /// set's scramble seeds `scramble` (from [`scramble`]).
    #[inline]
    pub fn sample(shuffled_rev: u32, set: u32, scramble: [u32; 4]) -> [f32; 4] {
        let t = &digits()[set as usize];
        let d = |k: usize| t[k][((shuffled_rev >> (28 - 4 * k)) & 0xf) as usize];
        let (a, b, c, e) = (d(0), d(1), d(2), d(3));
        let sobol: [u32; 4] = std::array::from_fn(|i| a[i] ^ b[i] ^ c[i] ^ e[i]);
        owen_scramble_int4_rev(sobol.into(), scramble.into())
            .reverse_bits()
            .to_f32_norm()
    }

    #[cfg(test)]
    mod tests {
        /// The split form equals the crate's `sample_4d` exactly, over sample indices up to
        /// the sampler's limit's low end, every set it serves, and several seeds.
        #[test]
        fn equals_sample_4d() {
            for seed in [0u32, 1, 0x9e3779b9, 0xdeadbeef, 12345] {
                for set in 0..super::SOBOL_SETS as u32 {
                    let sc = super::scramble(set, seed);
                    for index in (0..1024).chain([4095, 65535]) {
                        let got = super::sample(super::shuffle(index, seed), set, sc);
                        let want = sobol_burley::sample_4d(index, set, seed);
                        assert_eq!(
                            got.map(f32::to_bits),
                            want.map(f32::to_bits),
                            "index {index}, set {set}, seed {seed}"
                        );
                    }
                }
            }
        }
    }
}
