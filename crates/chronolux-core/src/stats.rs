//! Counters gathered while rendering a frame (rays, samples), merged deterministically.

use serde::{Deserialize, Serialize};

/// Per-frame statistics. Each worker keeps its own and they are summed at the end.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Stats {
    /// Closest-hit rays cast.
    pub rays: u64,
    /// Any-hit (shadow) rays cast.
    pub shadow_rays: u64,
    /// Camera samples taken.
    pub samples: u64,
}

impl std::ops::AddAssign for Stats {
    fn add_assign(&mut self, o: Stats) {
        self.rays += o.rays;
        self.shadow_rays += o.shadow_rays;
        self.samples += o.samples;
    }
}
