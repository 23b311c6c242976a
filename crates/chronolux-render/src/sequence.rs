//! Frame sequences: the [`SequenceRenderer`] contract and the frame-by-frame wrapper used
//! by every baseline.

use crate::integrator::{Integrator, RenderedFrame};
use chronolux_core::scene::source::FrameSource;

/// Renders the frames of an animation in increasing order; may keep state between frames
/// (temporal techniques do, baselines do not).
pub trait SequenceRenderer {
    /// Short name of the technique (`path`, ...).
    fn name(&self) -> &'static str;
    /// Renders frame `frame`, taking its scene (and, for techniques with a window, the
    /// scenes of neighbouring frames) from `source`.
    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame;

    /// Photons emitted for the frame last rendered (photon methods; `None` otherwise).
    fn photons_last_frame(&self) -> Option<u64> {
        None
    }

    /// Sample reuse of the frame last rendered (sample-reusing methods; `None` otherwise).
    fn reuse_last_frame(&self) -> Option<ReuseStats> {
        None
    }
}

/// How much a frame of a sample-reusing technique got from its window.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ReuseStats {
    /// Frames of the render list in the frame's window (generated frames that served it).
    pub window: u32,
    /// Samples that landed in the frame, per pixel (its own and its neighbours').
    pub effective_spp: f64,
    /// Samples from other frames served by reusing their view-independent part / by
    /// re-tracing them in this frame.
    pub reused: u64,
    /// Of `reused`: those whose light subpath was invalid in this frame (only the
    /// strategies without light-subpath vertices reused, the others recomputed here).
    pub reused_partially: u64,
    pub retraced: u64,
    /// Mean number of frames served by each sample generated for this frame.
    pub reuse_factor: f64,
    /// Light subpaths whose splats this frame received, per pixel.
    pub light_subpaths_per_pixel: f64,
    /// The accumulation films so far: peak bytes in memory, disk-cache traffic and hit
    /// counts (cumulative over the frames rendered).
    pub film: crate::temporal::window_film::FilmStats,
}

/// Every frame rendered from scratch by a single-frame integrator.
pub struct FrameByFrame<I: Integrator> {
    pub integrator: I,
    pub name: &'static str,
}

impl<I: Integrator> SequenceRenderer for FrameByFrame<I> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let scene = source.frame(frame);
        self.integrator.render(&scene, frame, progress)
    }
}
