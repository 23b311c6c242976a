//! # chronolux-render
//!
//! Light transport. Single-frame integrators implement [`integrator::Integrator`]; the
//! per-path logic of each estimator lives in one kernel ([`RadianceEstimator::li`](integrator::RadianceEstimator::li) of [`pt::PathTracer`] for path
//! tracing) that temporal techniques will call as their baselines do. Frame sequences go
//! through [`sequence`], the one loop that builds frames and times them, so baselines and
//! temporal techniques differ only in light-transport reuse.
//!
//! Techniques (more follow the MPI temporal-coherence work, see the repository README):
//! - `path`: unidirectional path tracing with next-event estimation, MIS (power
//!   heuristic), Russian roulette and Owen-scrambled Sobol samples per pixel — the
//!   reference every other method is measured against.
//! - `bdpt`: bidirectional path tracing ([`bdpt`]), every (s, t) strategy including light
//!   tracing splatted through [`integrator::render_with_splats`], MIS by the ratio trick —
//!   the frame-by-frame baseline of the spatio-temporal technique.
//! - `dept`, `dept-spatial`, `dept-bilateral`: photon tracing with density estimation on
//!   mesh elements, frame by frame, without / with spatial Gaussian / with spatial
//!   bilateral filtering (Myszkowski et al. 2001; Weber et al. 2004) — [`dept`], photons
//!   from the one replayable kernel [`kernels::photon`].
//! - `spacetime-dept`: the same photons pooled over a per-element temporal window cut by
//!   an energy test, completed by a spatial bilateral filter (Weber et al. 2004) —
//!   [`temporal::spacetime_dept`].

pub mod bdpt;
pub mod dept;
pub mod integrator;
pub mod kernels;
pub mod motion_blur;
pub mod pt;
pub mod registry;
pub mod sequence;
pub mod temporal;
