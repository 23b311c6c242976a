//! Per-path code shared by every estimator, with no drivers: each kernel traces one path
//! (or one photon) and reports what it finds; the techniques decide what to keep.
//!
//! - [`photon`]: emit and trace photon #i from Halton point #i (replayable by index).

pub mod photon;
