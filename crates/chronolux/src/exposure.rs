//! Automatic exposure of the PNGs and preview: measured once, on the first frame of the
//! sequence, so the whole sequence shares it (no pumping) and every farm segment, a
//! `--resume` and a `--config run.json` replay find the same value without having rendered
//! that frame themselves.
//!
//! The measurement is a small, deterministic path-traced pre-pass of the first frame —
//! long side at most [`PREPASS_SIDE`] pixels, [`PREPASS_SPP`] samples per pixel, fixed seed —
//! whatever the technique of the run, so its value depends only on the scene, camera,
//! aspect and frame; [`chronolux_io::image::auto_exposure`] turns the pixels that show
//! geometry (not the backdrop) into stops.

use anyhow::Result;
use chronolux_core::scene::desc::{AnimationId, SceneDesc};
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
use chronolux_core::scene::source::frame_time;
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::kernels::path::{PathSettings, PathTracer};
use std::sync::Arc;

/// Long side of the pre-pass image. 128 px is enough to rank luminances (the 90th
/// percentile of 16k pixels); the cost is that of 0.5 M paths.
pub const PREPASS_SIDE: u32 = 128;
/// Samples per pixel of the pre-pass: noise at 32 spp moves a high percentile by a few
/// percent (a few hundredths of a stop), invisible in an exposure.
pub const PREPASS_SPP: u32 = 32;

/// The automatic exposure (stops) of a run whose first frame is `frame` at `fps`, rendered
/// at `width`×`height`.
pub fn first_frame_exposure(
    desc: Arc<SceneDesc>,
    animation: Option<AnimationId>,
    camera: CameraChoice,
    (width, height): (u32, u32),
    fps: f32,
    frame: u32,
) -> Result<f32> {
    let s = (PREPASS_SIDE as f32 / width.max(height) as f32).min(1.0);
    let w = ((width as f32 * s).round() as u32).max(1);
    let h = ((height as f32 * s).round() as u32).max(1);
    let mut builder = FrameBuilder::new(desc, animation, camera, w, h)?;
    let scene = builder.build(frame_time(frame, fps));
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: PREPASS_SPP,
            max_depth: None,
            seed: 0x45_58_50, // "EXP": independent of the run's own seed
        },
        ..Default::default()
    });
    let img = pt.render(&scene, frame, &|_| {});
    // Measured on the pixels that show the scene: a small model in front of a backdrop
    // (the fallback light's, or a bright sky) is exposed for the model. Pixels whose centre
    // ray misses everything are left out, unless nothing is hit.
    let shown: Vec<_> = img
        .pixels
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            let (x, y) = ((*i as u32 % w) as f32 + 0.5, (*i as u32 / w) as f32 + 0.5);
            let ray = scene
                .camera
                .generate_ray(chronolux_core::math::Vec2::new(x, y));
            scene.intersect(&ray).is_some()
        })
        .map(|(_, p)| *p)
        .collect();
    let pixels = if shown.is_empty() {
        &img.pixels
    } else {
        &shown
    };
    Ok(chronolux_io::image::auto_exposure(pixels))
}
