//! The one integration-test binary of chronolux-render: integrators on scenes with
//! derivable answers.

mod aov;
mod bdpt;
mod blur;
mod caustic;
mod delta;
mod dept;
mod determinism;
mod envmap;
mod furnace;
mod icsel;
mod light;
mod matrix;
mod multi_frame;
mod peer;
mod photon;
mod pmic;
mod spt;
mod stbpt;
mod volume;
mod window_film;

use chronolux_core::scene::desc::SceneDesc;
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder, FrameScene};
use std::sync::Arc;

/// Frame 0 (t = 0) of `desc` at `w`×`h`, first animation clip if any.
pub fn frame0(desc: SceneDesc, w: u32, h: u32) -> FrameScene {
    let anim = (!desc.animations.is_empty()).then_some(chronolux_core::scene::desc::AnimationId(0));
    let mut b = FrameBuilder::new(Arc::new(desc), anim, CameraChoice::First, w, h).unwrap();
    b.build(0.0)
}

/// The frame source of `desc` at `w`×`h` and `fps`, first animation clip if any, for
/// rendering `frames`.
pub fn source(
    desc: SceneDesc,
    w: u32,
    h: u32,
    fps: f32,
    frames: Vec<u32>,
) -> chronolux_core::scene::source::FrameSource {
    let anim = (!desc.animations.is_empty()).then_some(chronolux_core::scene::desc::AnimationId(0));
    let b = FrameBuilder::new(Arc::new(desc), anim, CameraChoice::First, w, h).unwrap();
    chronolux_core::scene::source::FrameSource::new(b, fps, frames)
}

/// Largest relative error over 8×8-pixel blocks of `img` (`w` pixels wide) against the
/// blocks `reference` ([`blocks`]), and the relative error of the image mean.
pub fn block_errors(img: &[glam::Vec3], reference: &[f64], w: usize) -> (f64, f64) {
    let b = blocks(img, w, 8);
    let max = b
        .iter()
        .zip(reference)
        .fold(0.0f64, |m, (x, r)| m.max(((x - r) / r).abs()));
    let (sa, sr) = (b.iter().sum::<f64>(), reference.iter().sum::<f64>());
    (max, ((sa - sr) / sr).abs())
}

/// Mean of each `b`×`b` block (channel average).
pub fn blocks(px: &[glam::Vec3], w: usize, b: usize) -> Vec<f64> {
    let h = px.len() / w;
    let mut out = Vec::new();
    for by in 0..h / b {
        for bx in 0..w / b {
            let mut s = 0.0;
            for y in 0..b {
                for x in 0..b {
                    let p = px[(by * b + y) * w + bx * b + x];
                    s += ((p.x + p.y + p.z) / 3.0) as f64;
                }
            }
            out.push(s / (b * b) as f64);
        }
    }
    out
}

/// Mean and standard error of the mean over pixels (channel average).
pub fn mean_and_stderr(px: &[glam::Vec3]) -> (f64, f64) {
    let v: Vec<f64> = px
        .iter()
        .map(|p| ((p.x + p.y + p.z) / 3.0) as f64)
        .collect();
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Pixels as bit patterns, for bit-for-bit comparisons (`==` on floats would equate
/// 0.0 and −0.0 and never NaN).
pub fn bits(px: &[glam::Vec3]) -> Vec<[u32; 3]> {
    px.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}
