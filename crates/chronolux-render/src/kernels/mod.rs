//! Kernels: per-path and per-photon code shared by techniques, with no drivers. Each
//! kernel traces a path, a photon or a gather and reports what it finds; the techniques
//! decide what to keep between frames. Kernels import the framework and other kernels,
//! never a technique.
//!
//! - [`direct`]: next-event estimation and the emitted radiance of a sampled light point.
//! - [`photon`]: emit and trace photon #i from Halton point #i (replayable by index).
//! - [`path`]: the path tracer's radiance estimator (`path`, and the probe's).
//! - [`bdpt`]: bidirectional subpaths, connections with MIS and caustic photons (`bdpt`,
//!   `stbpt`).
//! - [`eye`]: the eye walk through specular chains (delta and glossy bounces) that the
//!   views reading a stored solution share: the element view (`dept*`,
//!   `spacetime-dept`), the SPT view and the photon-map view (`pm-ic`, `ic-*`). The walk
//!   owns the path; each view, an [`eye::EyeReader`], says what a vertex adds and where
//!   the path ends, and asks the one glossy test, `Bsdf::is_glossy`.
//! - [`elements`]: photon density estimation on mesh elements: the element map, photon
//!   budget (stopping rule), reconstruction filters, eye pass over elements and eye-path
//!   reuse records (`dept*`, `spacetime-dept`, `spt`).
//! - [`gather`]: photon maps, final gathering and the irradiance cache, with their eye
//!   pass (`pm-ic`, `ic-static-dynamic`, `ic-selective`).
//! - [`probe`]: whether frame-by-frame path tracing renders a frame as well as a reuse
//!   technique (measured, so that one that cannot gain renders as its baseline).
//! - [`blur`]: motion blur by splatting a sample along its projected trajectory.

pub mod bdpt;
pub mod blur;
pub mod direct;
pub mod elements;
pub mod eye;
pub mod gather;
pub mod path;
pub mod photon;
pub mod probe;
