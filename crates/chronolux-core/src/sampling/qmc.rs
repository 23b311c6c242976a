//! Radical inverses and scrambled Halton points, indexable by photon number so any photon
//! path can be replayed exactly (photon i always uses Halton point i).

/// The first 64 primes (Halton bases, one per dimension).
pub const PRIMES: [u32; 64] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97,
    101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193,
    197, 199, 211, 223, 227, 229, 233, 239, 241, 251, 257, 263, 269, 271, 277, 281, 283, 293, 307,
    311,
];

/// Radical inverse of `index` in base `PRIMES[dim]`, in [0, 1).
pub fn radical_inverse(dim: usize, mut index: u64) -> f32 {
    let base = PRIMES[dim] as u64;
    if base == 2 {
        return ((index.reverse_bits() >> 40) as f32 * (1.0 / (1u64 << 24) as f32))
            .min(super::rng::ONE_MINUS_EPSILON);
    }
    let inv = 1.0 / base as f64;
    let mut inv_n = 1.0f64;
    let mut rev = 0u64;
    while index > 0 {
        let next = index / base;
        rev = rev * base + (index - next * base);
        inv_n *= inv;
        index = next;
    }
    ((rev as f64 * inv_n) as f32).min(super::rng::ONE_MINUS_EPSILON)
}

/// Halton point `index` in dimension `dim`, decorrelated per dimension by a Cranley–Patterson
/// rotation derived from `seed` (keeps the stratification, removes the correlation between
/// low prime bases).
pub fn halton(dim: usize, index: u64, seed: u64) -> f32 {
    let x = radical_inverse(dim % PRIMES.len(), index);
    let shift = (super::mix64(seed ^ (dim as u64).wrapping_mul(0x9E37_79B9)) >> 40) as f32
        / (1u64 << 24) as f32;
    let v = x + shift;
    (if v >= 1.0 { v - 1.0 } else { v }).min(super::rng::ONE_MINUS_EPSILON)
}
