//! The framework: what every technique plugs into, naming none of them.
//!
//! - [`technique`]: the technique contract ([`technique::Technique`], [`technique::Preset`],
//!   capabilities, the common settings block, quality levels, frame context) and the JSON
//!   settings helpers.
//! - [`integrator`]: single-frame integrators, radiance and splatting estimators, the
//!   camera-ray and splatting drivers over tiles.
//! - [`sequence`]: [`sequence::SequenceRenderer`], the interface of a technique that
//!   renders frames in order, and frame-by-frame adaptors.
//! - [`run`]: the one run loop (frames, passes, timing, sinks).
//! - [`aov`]: per-pixel passes beside the beauty image.
//! - [`shutter`]: motion blur by time sampling for any shutter integrator.
//! - [`window_film`]: the film of the open frames of a sliding window (samples made in one
//!   frame and reused in its neighbours), in tiles with an optional disk cache.
//!
//! Nothing here imports a kernel or a technique (`crate::kernels`, `crate::techniques`).

pub mod aov;
pub mod integrator;
pub mod run;
pub mod sequence;
pub mod shutter;
pub mod technique;
pub mod window_film;
