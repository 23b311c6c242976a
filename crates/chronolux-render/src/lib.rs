//! # chronolux-render
//!
//! Light transport. Single-frame integrators implement [`integrator::Integrator`]; the
//! per-path logic of each estimator lives in one kernel
//! ([`RadianceEstimator::li`](integrator::RadianceEstimator::li) of [`pt::PathTracer`] for
//! path tracing) that temporal techniques call as their baselines do. Every technique is a
//! [`sequence::SequenceRenderer`] named once, in [`registry`] (name, summary, settings,
//! capabilities, constructor); frame sequences go through [`run`], the one run loop that
//! times frames and hands them to sinks (files, memory, progress), so baselines and
//! temporal techniques differ only in light-transport reuse.
//!
//! Techniques (the registry's list; more follow the MPI temporal-coherence work, see the
//! repository README):
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
//! - `spt`: selective photon tracing (Dmitriev et al. 2002): a fixed pool of Halton
//!   photons in coherent groups on the `dept` elements, only the groups invalidated by a
//!   change re-shot (signed deposits), found by pilot photons — [`spt`].
//! - `stbpt`: spatio-temporal BDPT (Havran et al. 2003), each bidirectional sample reused
//!   in the frames of a window around its own — [`temporal::stbpt`].
//! - `pm-ic`: photon mapping (global + caustic maps in a k-d tree) with final gathering
//!   cached in an irradiance cache with gradients, frame by frame — [`pmic`].
//! - `ic-static-dynamic`: the same with a static cache per segment of frames and dynamic
//!   photons (negative ones included) and a dynamic cache per frame, blended —
//!   [`pmic::static_dynamic`].
//! - `ic-selective`: `pm-ic` whose records keep their gather directions between frames (in
//!   a paged store) and re-cast those a change reached plus a fraction chosen by age —
//!   [`pmic::selective`].

pub mod framework;
pub mod kernels;
pub mod registry;
pub mod techniques;
