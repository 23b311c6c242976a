//! # chronolux-render
//!
//! Light transport. Single-frame integrators implement [`integrator::Integrator`]; the
//! per-path logic of each estimator lives in one kernel ([`pt::PathTracer::li`] for path
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

pub mod bdpt;
pub mod integrator;
pub mod pt;
pub mod registry;
pub mod sequence;
