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
