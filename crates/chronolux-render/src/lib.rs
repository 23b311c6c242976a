//! # chronolux-render
//!
//! Light transport, in three layers that only import downwards:
//!
//! - [`framework`]: the contract every technique meets and the machinery around it —
//!   [`framework::technique`] (settings, capabilities, presets),
//!   [`framework::integrator`] (the single-frame [`Integrator`](framework::integrator::Integrator)
//!   and the per-path [`RadianceEstimator`](framework::integrator::RadianceEstimator)),
//!   [`framework::sequence`] (the [`SequenceRenderer`](framework::sequence::SequenceRenderer)
//!   every technique is) and [`framework::run`], the one run loop that times frames and
//!   hands them to sinks (files, memory, progress). It names no technique.
//! - [`kernels`]: one kernel per estimator, shared by a baseline and its temporal
//!   technique — [`kernels::path`] (the path tracer's
//!   [`li`](framework::integrator::RadianceEstimator::li)), [`kernels::bdpt`],
//!   [`kernels::photon`], [`kernels::direct`], [`kernels::elements`] (density estimation
//!   on mesh elements), [`kernels::gather`] (photon maps, irradiance cache, final gather),
//!   and [`kernels::eye`], the one eye walk through specular chains that the views of the
//!   element, SPT and photon-map techniques read their solutions along (each view says
//!   what a vertex adds and where the path ends; one glossy test,
//!   `chronolux_core::bsdf::Bsdf::is_glossy`).
//! - [`techniques`]: one module per technique, holding its registry entry and its
//!   sequence renderer (what it reuses across frames); the kernels do the light transport.
//!
//! [`registry`] sits on top: the one list of techniques (name, summary, settings,
//! capabilities, constructor) that the CLI reads, so the driver knows no names and a new
//! technique is one module plus one entry. Baselines and temporal techniques differ only
//! in light-transport reuse.
//!
//! Techniques (the registry's list; more follow the MPI temporal-coherence work, see the
//! repository README):
//! - `path`: unidirectional path tracing with next-event estimation, MIS (power
//!   heuristic), Russian roulette and Owen-scrambled Sobol samples per pixel — the
//!   reference every other method is measured against.
//! - `bdpt`: bidirectional path tracing ([`kernels::bdpt`]), every (s, t) strategy including light
//!   tracing splatted through [`framework::integrator::render_with_splats`], MIS by the ratio trick —
//!   the frame-by-frame baseline of the spatio-temporal technique.
//! - `dept`, `dept-spatial`, `dept-bilateral`: photon tracing with density estimation on
//!   mesh elements, frame by frame, without / with spatial Gaussian / with spatial
//!   bilateral filtering (Myszkowski et al. 2001; Weber et al. 2004) — [`techniques::dept`] on
//!   [`kernels::elements`], photons
//!   from the one replayable kernel [`kernels::photon`].
//! - `spacetime-dept`: the same photons pooled over a per-element temporal window cut by
//!   an energy test, completed by a spatial bilateral filter (Weber et al. 2004) —
//!   [`techniques::spacetime_dept`].
//! - `spt`: selective photon tracing (Dmitriev et al. 2002): a fixed pool of Halton
//!   photons in coherent groups on the `dept` elements, only the groups invalidated by a
//!   change re-shot (signed deposits), found by pilot photons — [`techniques::spt`].
//! - `stbpt`: spatio-temporal BDPT (Havran et al. 2003), each bidirectional sample reused
//!   in the frames of a window around its own — [`techniques::stbpt`].
//! - `pm-ic`: photon mapping (global + caustic maps in a k-d tree) with final gathering
//!   cached in an irradiance cache with gradients, frame by frame — [`techniques::pm_ic`] on [`kernels::gather`].
//! - `ic-static-dynamic`: the same with a static cache per segment of frames and dynamic
//!   photons (negative ones included) and a dynamic cache per frame, blended —
//!   [`techniques::ic_static_dynamic`].
//! - `ic-selective`: `pm-ic` whose records keep their gather directions between frames (in
//!   a paged store) and re-cast those a change reached plus a fraction chosen by age —
//!   [`techniques::ic_selective`].

pub mod framework;
pub mod kernels;
pub mod registry;
pub mod techniques;
