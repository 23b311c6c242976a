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
pub fn radical_inverse(dim: usize, index: u64) -> f32 {
    let base = PRIMES[dim] as u64;
    if base == 2 {
        return ((index.reverse_bits() >> 40) as f32 * (1.0 / (1u64 << 24) as f32))
            .min(super::rng::ONE_MINUS_EPSILON);
    }
    // One copy of the digit loop per base, so that each division is by a constant (a
    // multiply and a shift instead of a 64-bit `div`, which made `halton` 2 % of the
    // default route's CPU); the arithmetic, and so every value, is that of the loop with
    // the base read at run time.
    macro_rules! by_base {
        ($($b:literal)*) => {
            match base {
                $($b => digits::<$b>(index),)*
                _ => digits_dyn(base, index),
            }
        };
    }
    let (rev, inv_n) = by_base!(3 5 7 11 13 17 19 23 29 31 37 41 43 47 53 59 61 67 71 73 79 83
        89 97 101 103 107 109 113 127 131 137 139 149 151 157 163 167 173 179 181 191 193 197
        199 211 223 227 229 233 239 241 251 257 263 269 271 277 281 283 293 307 311);
    ((rev as f64 * inv_n) as f32).min(super::rng::ONE_MINUS_EPSILON)
}

/// [`digits_dyn`] with the base a constant, so that inlined its divisions are by a
/// constant.
#[inline(always)]
fn digits<const B: u64>(index: u64) -> (u64, f64) {
    digits_dyn(B, index)
}

/// The digits of `index` in base `base` reversed (as an integer) and `base^-digits`.
#[inline(always)]
fn digits_dyn(base: u64, mut index: u64) -> (u64, f64) {
    let inv = 1.0 / base as f64;
    let mut inv_n = 1.0f64;
    let mut rev = 0u64;
    while index > 0 {
        let next = index / base;
        rev = rev * base + (index - next * base);
        inv_n *= inv;
        index = next;
    }
    (rev, inv_n)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The per-base constant-divisor loops give exactly the run-time-base loop's digits and
    /// scale, for every base and indices from 0 to beyond 2^40 (so photon streams replay
    /// the same points as before the specialisation).
    #[test]
    fn constant_base_digits_equal_runtime_base() {
        for (dim, &prime) in PRIMES.iter().enumerate().skip(1) {
            let base = prime as u64;
            let mut index = 0u64;
            while index < 1 << 42 {
                let want = digits_dyn(base, index);
                let x = radical_inverse(dim, index);
                let w =
                    ((want.0 as f64 * want.1) as f32).min(crate::sampling::rng::ONE_MINUS_EPSILON);
                assert_eq!(x.to_bits(), w.to_bits(), "base {base}, index {index}");
                index = index * 3 + 1 + (index & 7);
            }
        }
    }
}
