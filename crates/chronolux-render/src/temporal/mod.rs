//! Temporal techniques: sequence renderers that keep state between frames and call the
//! same kernels as their frame-by-frame baselines.
//!
//! - [`spacetime_dept`]: space-time photon density estimation on mesh elements with a
//!   spatio-temporal bilateral filter (Weber et al. 2004), baseline `dept-spatial`.
//! - [`window_film`]: accumulation of the open frames of a sliding window (samples made
//!   in one frame and reused in its neighbours), in tiles with an optional disk cache.
//! - [`probe`]: whether frame-by-frame path tracing renders a frame as well as a reuse
//!   technique (measured, so that one that cannot gain renders as its baseline).
//! - [`blur`]: motion blur by splatting a sample along its projected trajectory.

pub mod blur;
pub mod probe;
pub mod spacetime_dept;
pub mod stbpt;
pub mod window_film;
