//! The photon pool's coherent groups: how many (`N_g`), which photons, and the bound of
//! Dmitriev et al.'s Equation 1 they satisfy.
//!
//! Photon `i` of the pool is Halton point `i` ([`crate::kernels::photon`]); group `r` is
//! `{ i < Z : i ≡ r (mod N_g) }`, member `m` of it is photon `r + m·N_g`. With
//! `N_g = Π_j b_j^k_j` over the coherent dimensions `j` (bases `b_j`), the radical inverses
//! of two members agree in their first `k_j` base-`b_j` digits (those digits are the
//! digits of `i mod b_j^k_j`, equal for `i ≡ r`), i.e. before scrambling both lie in the
//! same interval `[a·b_j^-k_j, (a+1)·b_j^-k_j)` (Eq. 1: `|φ_j(i) − φ_j(i + m·N_g)| <
//! b_j^-k_j`). The kernel's Cranley–Patterson shift adds one constant per dimension
//! modulo 1, which moves every group's interval by the same amount: the bound holds for
//! the toroidal distance `min(|x − y|, 1 − |x − y|)` of the scrambled points, and in each
//! dimension exactly one group in `b_j^k_j` has its interval cut by the wrap at 1 (its
//! members sit at both ends of [0, 1), e.g. at two opposite edges of the light).
//!
//! [`GroupLayout::choose`] picks the exponents greedily: starting from `N_g = 1`, it
//! repeatedly multiplies `N_g` by the base of the coherent dimension whose cell is widest
//! (ties: the smaller base), skipping bases that would take `N_g` past `Z / group_size`,
//! until none fits. The coherent dimensions are the six that decide a path's coherence:
//! the light choice with the point on it (0, 1), the emitted direction (2, 3) and the
//! first bounce's direction (4, 5); the point on the light is dropped for scenes whose
//! only light is punctual (its coordinates are not used).

use crate::kernels::photon::{DIRECTION_DIMS, FIRST_BOUNCE_DIMS, POSITION_DIMS};
use chronolux_core::light::Light;
use chronolux_core::sampling::qmc::PRIMES;
use chronolux_core::scene::frame::FrameScene;

/// The Halton dimensions whose coherence [`GroupLayout`] controls, in kernel order.
pub const COHERENT_DIMS: [usize; 6] = [
    POSITION_DIMS[0],
    POSITION_DIMS[1],
    DIRECTION_DIMS[0],
    DIRECTION_DIMS[1],
    FIRST_BOUNCE_DIMS[0],
    FIRST_BOUNCE_DIMS[1],
];

/// How the pool is cut into groups.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GroupLayout {
    /// `N_g`, the number of groups (the period of the group structure).
    pub groups: u64,
    /// Photons per group (`Z = groups · members`).
    pub members: u64,
    /// Exponent `k_j` of each coherent dimension's base in `N_g` (order of [`COHERENT_DIMS`]).
    pub exponents: [u32; 6],
}

impl GroupLayout {
    /// Groups for about `photons` photons in groups of about `group_size`; `used[j]` says
    /// whether coherent dimension `j` matters (see [`used_dims`]). The pool is
    /// `groups · members` photons with `members = max(1, round(photons / groups))`.
    pub fn choose(photons: u64, group_size: u64, used: [bool; 6]) -> GroupLayout {
        let target = (photons / group_size.max(1)).max(1);
        let mut n = 1u64;
        let mut k = [0u32; 6];
        loop {
            let mut order: Vec<usize> = (0..6).filter(|&j| used[j]).collect();
            // Widest cell first (b^-k larger ⇔ b^k smaller), then the smaller base.
            order.sort_by_key(|&j| {
                (
                    (PRIMES[COHERENT_DIMS[j]] as u64).pow(k[j]),
                    PRIMES[COHERENT_DIMS[j]],
                )
            });
            let Some(&j) = order
                .iter()
                .find(|&&j| n * PRIMES[COHERENT_DIMS[j]] as u64 <= target)
            else {
                break;
            };
            n *= PRIMES[COHERENT_DIMS[j]] as u64;
            k[j] += 1;
        }
        let members = ((photons as f64 / n as f64).round() as u64).max(1);
        GroupLayout {
            groups: n,
            members,
            exponents: k,
        }
    }

    /// Photons in the pool.
    pub fn photons(&self) -> u64 {
        self.groups * self.members
    }

    /// Group of photon `i`.
    #[inline]
    pub fn group_of(&self, i: u64) -> u64 {
        i % self.groups
    }

    /// Photon index of member `m` of group `g`.
    #[inline]
    pub fn photon(&self, g: u64, m: u64) -> u64 {
        g + m * self.groups
    }

    /// Width `b_j^-k_j` of the interval that holds every member of a group in coherent
    /// dimension `j` (1 when `k_j = 0`: no coherence there).
    pub fn cell_width(&self, j: usize) -> f64 {
        (PRIMES[COHERENT_DIMS[j]] as f64).powi(-(self.exponents[j] as i32))
    }
}

/// Which coherent dimensions a scene's photons use: the point on the light only when some
/// light has an extent or there are several lights (dimension 0 also chooses the light).
pub fn used_dims(scene: &FrameScene) -> [bool; 6] {
    let punctual_only = scene.lights.len() <= 1
        && scene
            .lights
            .iter()
            .all(|l| matches!(l, Light::Point { .. } | Light::Spot { .. }));
    [!punctual_only, !punctual_only, true, true, true, true]
}

/// Toroidal distance of two points of [0, 1) (what a Cranley–Patterson shift preserves).
#[inline]
pub fn toroidal_distance(a: f64, b: f64) -> f64 {
    let d = (a - b).abs();
    d.min(1.0 - d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greedy_layout_balances_cells_and_respects_the_target() {
        let l = GroupLayout::choose(300_000, 64, [true; 6]);
        // 2·3·5·7·11 = 2310, then a second factor 2 (the widest cell left that fits):
        // 4620 ≤ 300000/64 = 4687.
        assert_eq!(l.groups, 4620);
        assert_eq!(l.exponents, [2, 1, 1, 1, 1, 0]);
        assert_eq!(l.members, 65);
        let p = GroupLayout::choose(300_000, 64, [false, false, true, true, true, true]);
        assert_eq!(p.exponents[..2], [0, 0]);
        assert!(p.groups <= 4687);
    }
}
