//! Per-path code shared by every estimator, with no drivers: each kernel traces one path
//! (or one photon) and reports what it finds; the techniques decide what to keep.
//!
//! - [`direct`]: next-event estimation and the emitted radiance of a sampled light point.
//! - [`photon`]: emit and trace photon #i from Halton point #i (replayable by index).

pub mod direct;
pub mod photon;
