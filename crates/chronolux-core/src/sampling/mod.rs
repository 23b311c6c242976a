//! Random and quasi-random numbers, warps from the unit square, discrete distributions, MIS.

pub mod distrib;
pub mod qmc;
pub mod rng;
pub mod sampler;
pub mod warps;

/// Power heuristic (β = 2) weight of strategy `f` against `g`, given sample counts × pdfs.
#[inline]
pub fn power_heuristic(nf: f32, f_pdf: f32, ng: f32, g_pdf: f32) -> f32 {
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    if f.is_infinite() {
        return 1.0;
    }
    let (f2, g2) = (f * f, g * g);
    if f2 + g2 == 0.0 { 0.0 } else { f2 / (f2 + g2) }
}

/// Hashes several words into one (a splitmix64-style finaliser over the sequence).
#[inline]
pub fn hash_words(words: &[u64]) -> u64 {
    let mut h = 0x9E37_79B9_7F4A_7C15u64;
    for &w in words {
        h ^= w
            .wrapping_add(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(h << 6)
            .wrapping_add(h >> 2);
        h = mix64(h);
    }
    h
}

/// splitmix64 finaliser.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
