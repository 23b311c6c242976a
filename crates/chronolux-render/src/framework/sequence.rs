//! Frame sequences: the [`SequenceRenderer`] contract every technique implements, its
//! progressive form ([`SequenceRenderer::render_passes`]), and the frame-by-frame wrapper
//! used by every baseline.
//!
//! A technique never names another one and the driver never names a technique: the
//! registry ([`crate::registry`]) builds a `Box<dyn SequenceRenderer>` from settings, and
//! the one run loop ([`crate::framework::run`]) drives it. What a technique wants to say about a
//! frame (photons shot, reuse statistics, …) travels with the frame in
//! [`RenderedFrame::report`], not through per-technique hooks on this trait.

use crate::framework::integrator::{Integrator, RenderedFrame};
use chronolux_core::color::Rgb;
use chronolux_core::sampling::hash_words;
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

    /// Renders `frame` as successive refinements. Each [`Pass`] is handed to `on_pass`,
    /// which may stop the refinement ([`Flow::Stop`]: cancellation between passes); the
    /// returned frame is the combination of every pass made. `plan` bounds the effort.
    ///
    /// The default makes one pass, the whole frame ([`Self::render_frame`]): a technique
    /// that cannot refine still serves a progressive consumer, with one refinement.
    fn render_passes(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        plan: PassPlan,
        progress: &(dyn Fn(u64) + Sync),
        on_pass: &mut dyn FnMut(&Pass) -> Flow,
    ) -> RenderedFrame {
        let _ = plan;
        single_pass(self.render_frame(source, frame, progress), on_pass)
    }

    /// Whether its frames carry direct and indirect light separately
    /// ([`RenderedFrame::light`]; the passes `direct`, `indirect`). False by default.
    fn separates_light(&self) -> bool {
        false
    }
}

/// A whole frame handed over as the one refinement of a technique that cannot refine.
fn single_pass(out: RenderedFrame, on_pass: &mut dyn FnMut(&Pass) -> Flow) -> RenderedFrame {
    on_pass(&Pass {
        index: 0,
        spp: 0,
        total_spp: 0,
        image: &out,
        independent: false,
    });
    out
}

/// What a progressive consumer asks for: the samples per pixel of the first pair of
/// passes (both together) and the most samples per pixel of the frame in all.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PassPlan {
    pub first_spp: u32,
    pub max_spp: u32,
}

/// One refinement of a frame.
pub struct Pass<'a> {
    /// 0, 1, 2, … in the order made.
    pub index: u32,
    /// Samples per pixel of this pass alone (0 when the technique does not count so).
    pub spp: u32,
    /// Samples per pixel of all passes so far, this one included.
    pub total_spp: u32,
    /// This pass alone: an estimate of the frame from its own samples.
    pub image: &'a RenderedFrame,
    /// Whether the passes are independent estimates (each from its own randomisation),
    /// so that the spread between them estimates the error (see `chronolux reference`).
    pub independent: bool,
}

/// Whether a progressive rendering goes on after a pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    Continue,
    Stop,
}

/// Seed of pass `2·round + half` of the paired-doubling schedule: every pass gets its
/// own Owen scrambling of the Sobol sequence, an independent randomisation.
pub fn batch_seed(seed: u64, round: u32, half: u32) -> u64 {
    hash_words(&[seed, 0x7265_6665_7265_6e63, round as u64, half as u64])
}

/// How much a frame of a sample-reusing technique got from its window.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// Of `retraced`: those re-traced from the valid prefix of their camera subpath (the
    /// same camera and first eye vertex as where they were made: the vertices and
    /// strategies reproduced in this frame taken from there, only the rest traced here).
    #[serde(default)]
    pub retraced_from_prefix: u64,
    /// Of `reused` and `retraced_from_prefix`: those whose first eye vertex lies on a
    /// skinned or morphed mesh, on a triangle whose vertices did not move between the
    /// two frames (the still part of a deforming mesh is reused as static geometry is).
    #[serde(default)]
    pub kept_on_deformed: u64,
    /// Mean number of frames served by each sample generated for this frame.
    pub reuse_factor: f64,
    /// Light subpaths whose splats this frame received, per pixel.
    pub light_subpaths_per_pixel: f64,
    /// Pixels that no landing reached and that got samples of their own frame instead
    /// (stbpt's interleaved generation).
    pub filled: u64,
    /// The accumulation films so far: peak bytes in memory, disk-cache traffic and hit
    /// counts (cumulative over the frames rendered).
    pub film: crate::framework::window_film::FilmStats,
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

    fn separates_light(&self) -> bool {
        self.integrator.separates_light()
    }

    /// Passes of the **paired-doubling** schedule when the integrator can be re-batched
    /// ([`Integrator::batch`]): passes come in pairs (A, B) of equal sample count, pair 0
    /// with `first_spp / 2` each (at least 1), every later pair with as many as each half
    /// already has, so the total doubles with each pair; the last pair is cut to
    /// `max_spp`. Pass `2r + h` draws from [`batch_seed`]`(seed, r, h)`, so all passes are
    /// independent, and the two halves' difference estimates the error of their mean.
    /// The result is the sample-weighted mean of all passes.
    fn render_passes(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        plan: PassPlan,
        progress: &(dyn Fn(u64) + Sync),
        on_pass: &mut dyn FnMut(&Pass) -> Flow,
    ) -> RenderedFrame {
        if self.integrator.batch(1, 0, 0).is_none() {
            return single_pass(self.render_frame(source, frame, progress), on_pass);
        }
        let scene = source.frame(frame);
        let mut batch = (plan.first_spp / 2).max(1);
        let mut n_half = 0u32;
        let mut acc: Option<RenderedFrame> = None;
        let mut sum: Vec<Rgb> = Vec::new();
        // Direct and indirect sums, while every pass has them.
        let mut light_sum: Option<[Vec<Rgb>; 2]> = None;
        let mut index = 0u32;
        'rounds: for round in 0.. {
            for half in 0..2 {
                let integ = self
                    .integrator
                    .batch(batch, round, half)
                    .expect("re-batchable");
                let out = integ.render(&scene, frame, progress);
                if sum.is_empty() {
                    sum = vec![Rgb::ZERO; out.pixels.len()];
                }
                for (s, p) in sum.iter_mut().zip(&out.pixels) {
                    *s += *p * batch as f32;
                }
                light_sum = match (index, light_sum.take(), &out.light) {
                    (0, _, Some(l)) => Some([
                        l.direct.iter().map(|p| *p * batch as f32).collect(),
                        l.indirect.iter().map(|p| *p * batch as f32).collect(),
                    ]),
                    (_, Some(mut acc), Some(l)) => {
                        for (a, p) in acc[0].iter_mut().zip(&l.direct) {
                            *a += *p * batch as f32;
                        }
                        for (a, p) in acc[1].iter_mut().zip(&l.indirect) {
                            *a += *p * batch as f32;
                        }
                        Some(acc)
                    }
                    _ => None,
                };
                let total = 2 * n_half + (half + 1) * batch;
                let flow = on_pass(&Pass {
                    index,
                    spp: batch,
                    total_spp: total,
                    image: &out,
                    independent: true,
                });
                index += 1;
                acc = Some(match acc.take() {
                    None => out,
                    Some(mut a) => {
                        a.stats += out.stats;
                        a.invalid_samples += out.invalid_samples;
                        a
                    }
                });
                // Only whole pairs end a frame, so both halves always hold equal samples.
                if half == 1 {
                    n_half += batch;
                    let room = (plan.max_spp / 2).saturating_sub(n_half);
                    if flow == Flow::Stop || room == 0 {
                        break 'rounds;
                    }
                    batch = n_half.min(room);
                }
            }
        }
        let mut out = acc.expect("at least one pass");
        let inv = 1.0 / (2 * n_half) as f32;
        out.light = light_sum.map(|[d, i]| crate::framework::integrator::LightSplit {
            direct: d.iter().map(|s| *s * inv).collect(),
            indirect: i.iter().map(|s| *s * inv).collect(),
        });
        out.pixels = match &out.light {
            // The beauty is their sum, as in one pass.
            Some(l) => l
                .direct
                .iter()
                .zip(&l.indirect)
                .map(|(d, i)| *d + *i)
                .collect(),
            None => sum.iter().map(|s| *s * inv).collect(),
        };
        // The per-pass variances are not combined (passes of different sizes): the
        // consumer of independent passes estimates the error from their spread.
        out.variance = vec![Rgb::ZERO; out.pixels.len()];
        out
    }
}
