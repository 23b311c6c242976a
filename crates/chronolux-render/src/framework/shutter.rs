//! Motion blur by time sampling (`--shutter S`), for any [`ShutterIntegrator`] (the path
//! tracer and BDPT implement it in their kernels).
//!
//! The shutter is open for `S` of a frame interval, centred on the frame time (Blender's
//! default): frame f integrates over `[f/fps − S/(2·fps), f/fps + S/(2·fps)]`. Scenes are
//! built per instant ([`FrameSource::at_time`]), so the interval is discretised into
//! `T = min(spp, 16)` sub-intervals of equal length and the scene is built at the midpoint
//! of each (camera and objects both move, so camera motion blurs too). Each pixel sample
//! draws a time `u` from its own sample stream — the Sobol dimension right after the two
//! raster dimensions — and is traced in the scene of sub-interval `⌊u·T⌋`. One dimension
//! of Owen-scrambled Sobol points is stratified over any aligned power-of-two block of
//! sample indices, so when `T` divides a power-of-two `spp` every instant gets exactly
//! `spp / T` samples of every pixel (otherwise as evenly as the sequence allows). The T
//! scenes of a frame are held together while it renders (T times the memory of one
//! frame's scene and acceleration structure, built T times per frame).
//!
//! **Discretisation error.** The estimate converges to the midpoint rule
//! `(1/T) Σ_j I(t_j)` instead of the shutter integral `(1/Δ) ∫ I(t) dt` of the pixel value
//! `I(t)`. On each sub-interval of width h the midpoint rule is exact for `I` linear in
//! time, and its error is at most (h/2) × the variation of `I` over the sub-interval
//! (|I(t) − I(mid)| is at most the variation between t and mid), so the per-pixel error of
//! the average is at most `TV(I) / (2T)`, `TV` the total variation of the pixel value
//! across the shutter (for an edge of contrast C crossing the pixel once, `C / (2T)`). In
//! image terms a moving edge is drawn at `T` positions `v·S/T` pixels apart: while that
//! spacing is at most a pixel the box pixel filter makes `I(t)` piecewise linear and the
//! error is far below the bound (zero except in the sub-intervals where `I` has a kink);
//! beyond it the blur shows `T` discrete copies (strobing). `S = 0` renders the frame
//! exactly as without motion blur (same sample streams).

use crate::framework::integrator::{
    Integrator, RadianceEstimator, RenderedFrame, Scenes, SplattingEstimator, TILE, camera_rays,
    splatting,
};
use crate::framework::sequence::SequenceRenderer;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::{FrameSource, frame_time};

/// Largest number of instants a shutter interval is discretised into.
pub const MAX_INSTANTS: u32 = 16;

/// Instants (s) of a frame's shutter: the midpoints of `n` equal sub-intervals of
/// `[t − S/(2·fps), t + S/(2·fps)]`, `t = frame / fps`.
pub fn shutter_instants(frame: u32, fps: f32, shutter: f32, n: u32) -> Vec<f32> {
    let t = frame_time(frame, fps);
    let open = shutter / fps;
    (0..n)
        .map(|j| t + open * ((j as f32 + 0.5) / n as f32 - 0.5))
        .collect()
}

/// An integrator that can time-sample a shutter: it renders one frame from the scenes of
/// the shutter's instants, each pixel sample drawing its instant from its own stream.
pub trait ShutterIntegrator: Integrator + Send {
    /// Technique name (`path`, `bdpt`).
    const NAME: &'static str;
    fn spp(&self) -> u32;
    /// Renders frame `frame` over `scenes` (one per instant, in time order).
    fn render_shutter(
        &self,
        scenes: &[FrameScene],
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame;
}

/// A single-frame integrator with a shutter: frame by frame, each frame time-sampled over
/// its shutter interval (see the module doc).
pub struct MotionBlur<I: ShutterIntegrator> {
    pub integrator: I,
    /// Fraction of the frame interval the shutter is open, in [0, 1].
    pub shutter: f32,
}

impl<I: ShutterIntegrator> MotionBlur<I> {
    pub fn new(integrator: I, shutter: f32) -> Self {
        debug_assert!(crate::framework::technique::check_shutter(shutter).is_ok());
        MotionBlur {
            integrator,
            shutter,
        }
    }

    /// Number of instants the shutter of a frame is discretised into.
    pub fn instants(&self) -> u32 {
        self.integrator.spp().clamp(1, MAX_INSTANTS)
    }
}

impl<I: ShutterIntegrator> SequenceRenderer for MotionBlur<I> {
    fn name(&self) -> &'static str {
        I::NAME
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        if self.shutter == 0.0 {
            return self
                .integrator
                .render(&source.frame(frame), frame, progress);
        }
        let scenes: Vec<FrameScene> =
            shutter_instants(frame, source.fps(), self.shutter, self.instants())
                .into_iter()
                .map(|t| source.at_time(t))
                .collect();
        self.integrator.render_shutter(&scenes, frame, progress)
    }

    fn separates_light(&self) -> bool {
        self.integrator.separates_light()
    }
}

/// [`render_camera_rays`](crate::framework::integrator::render_camera_rays) over a shutter: sample `s` of a pixel takes a time dimension
/// right after its raster position and is traced in `scenes[⌊u·T⌋]` (camera included).
/// Tiles in parallel, merged in tile order: bit-identical for any thread count. With one
/// scene it is still time-sampled (one dimension is drawn and ignored), so it differs from
/// `render_camera_rays`; callers use that one for a closed shutter.
pub fn render_time_sampled<E: RadianceEstimator>(
    est: &E,
    scenes: &[FrameScene],
    frame: u32,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    assert!(!scenes.is_empty(), "no scene in the shutter interval");
    camera_rays(
        est,
        Scenes::Shutter(scenes),
        frame,
        spp,
        seed,
        TILE,
        progress,
    )
}

/// [`render_with_splats`](crate::framework::integrator::render_with_splats) over a shutter: in pass
/// `s`, every pixel's sample draws its instant (the dimension after its raster position)
/// and runs in that instant's scene; its splats land where that instant's camera sees
/// them. A pixel's pass value is its own estimate plus the splats it receives from every
/// pixel's sample of the pass, each at its own instant: since every pixel's instant is
/// uniform over the T instants, the expectation is the time average (midpoint rule) of the
/// per-instant images. Tiles in parallel, splats merged in tile order: bit-identical for
/// any thread count.
pub fn render_with_splats_time_sampled<E: SplattingEstimator>(
    est: &E,
    scenes: &[FrameScene],
    frame: u32,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    assert!(!scenes.is_empty(), "no scene in the shutter interval");
    splatting(est, Scenes::Shutter(scenes), frame, spp, seed, progress)
}

/// What the frame-by-frame camera-sample techniques (`path`, `bdpt`) can do: motion blur
/// by time sampling, effort in samples per pixel.
pub const FRAME_BY_FRAME_SPP: crate::framework::technique::Capabilities =
    crate::framework::technique::Capabilities {
        motion_blur: true,
        photons: false,
        window: false,
        max_depth: true,
        stateless: true,
        effort: crate::framework::technique::Effort {
            key: "spp",
            per_unit: 1,
            unit: "samples per pixel",
        },
    };

/// A frame-by-frame technique of `integrator`, time-sampled over the shutter when it is
/// open ([`MotionBlur`]), else plain ([`crate::framework::sequence::FrameByFrame`], which also renders
/// progressive passes).
pub fn frame_by_frame<I: ShutterIntegrator + 'static>(
    integrator: I,
    shutter: f32,
    name: &'static str,
) -> crate::framework::technique::Renderer {
    if shutter > 0.0 {
        Box::new(MotionBlur::new(integrator, shutter))
    } else {
        Box::new(crate::framework::sequence::FrameByFrame { integrator, name })
    }
}
