//! The one frame source: every renderer gets the scene of a frame (or of any instant, for
//! motion blur) from here, never by building it itself.
//!
//! Temporal techniques need frames other than the one being output: a centred window
//! `[f − K, f + K]` needs the scenes of the next K frames before frame f can be finished,
//! and motion blur needs instants inside the shutter interval. A [`FrameSource`] owns the
//! [`FrameBuilder`] of the animation, knows the frame rate and the frames the user asked
//! for, and keeps the last few built frames (least recently used first out), so a window
//! sliding by one frame builds one new scene, not 2K + 1.

use super::delta::FrameDelta;
use super::frame::{BuildStats, FrameBuilder, FrameScene};
use std::collections::VecDeque;
use std::sync::Arc;

/// Time (s) at which frame `frame` is shown at `fps` frames per second: `frame / fps`.
/// The one frame-to-time mapping ([`FrameSource::time`] uses it; so should everything that
/// needs a frame's time without a source).
pub fn frame_time(frame: u32, fps: f32) -> f32 {
    frame as f32 / fps
}

/// Scenes of the frames of one animation clip at one frame rate.
pub struct FrameSource {
    builder: FrameBuilder,
    fps: f32,
    frames: Vec<u32>,
    cache: VecDeque<(u32, Arc<FrameScene>)>,
    capacity: usize,
    /// What the last build did (a cached frame costs nothing and leaves this as it was).
    pub last_build: BuildStats,
    /// Scenes built so far (frames and instants).
    pub builds: u64,
}

impl FrameSource {
    /// `frames`: the frames that will be rendered, in increasing order (temporal
    /// techniques keep their windows inside this list). `fps` must be positive.
    pub fn new(builder: FrameBuilder, fps: f32, frames: Vec<u32>) -> Self {
        debug_assert!(fps > 0.0 && fps.is_finite());
        let mut frames = frames;
        frames.sort_unstable();
        frames.dedup();
        FrameSource {
            builder,
            fps,
            frames,
            cache: VecDeque::new(),
            capacity: 2,
            last_build: BuildStats::default(),
            builds: 0,
        }
    }

    /// Frames per second.
    pub fn fps(&self) -> f32 {
        self.fps
    }

    /// Time (s) of frame `f` ([`frame_time`]).
    pub fn time(&self, f: u32) -> f32 {
        frame_time(f, self.fps)
    }

    /// The frames to be rendered, increasing.
    pub fn frames(&self) -> &[u32] {
        &self.frames
    }

    /// Frames of the render list within `[f − before, f + after]`, increasing.
    pub fn window(&self, f: u32, before: u32, after: u32) -> Vec<u32> {
        let lo = f.saturating_sub(before);
        let hi = f.saturating_add(after);
        self.frames
            .iter()
            .copied()
            .filter(|&g| g >= lo && g <= hi)
            .collect()
    }

    /// Keeps at least `n` built frames (a technique with a window of 2K + 1 frames asks
    /// for 2K + 1). Never lowers the capacity below what was asked before.
    pub fn reserve(&mut self, n: usize) {
        self.capacity = self.capacity.max(n);
    }

    /// The scene of frame `f` (built once while it stays among the `capacity` most
    /// recently used).
    pub fn frame(&mut self, f: u32) -> Arc<FrameScene> {
        if let Some(i) = self.cache.iter().position(|(g, _)| *g == f) {
            let e = self.cache.remove(i).expect("index in range");
            let s = e.1.clone();
            self.cache.push_back(e);
            return s;
        }
        let s = Arc::new(self.at_time(self.time(f)));
        self.cache.push_back((f, s.clone()));
        while self.cache.len() > self.capacity {
            self.cache.pop_front();
        }
        s
    }

    /// The scene at time `t` (s), not cached (motion-blur instants).
    pub fn at_time(&mut self, t: f32) -> FrameScene {
        let s = self.builder.build(t);
        self.last_build = self.builder.last_build;
        self.builds += 1;
        s
    }

    /// What changes anywhere in the segment of `frames` (increasing): [`FrameDelta::over`]
    /// their scenes, built through the cache two at a time (a segment longer than the
    /// cache capacity is not held in memory at once).
    pub fn delta_over(&mut self, frames: &[u32]) -> FrameDelta {
        let mut delta = FrameDelta::default();
        let mut prev: Option<Arc<FrameScene>> = None;
        for (k, &f) in frames.iter().enumerate() {
            let s = self.frame(f);
            let d = match &prev {
                Some(p) => FrameDelta::between(p, &s),
                None => FrameDelta::between(&s, &s),
            };
            delta.merge_at(&d, (k as u32).saturating_sub(1));
            prev = Some(s);
        }
        delta
    }

    /// The builder (scene description, geometry count).
    pub fn builder(&self) -> &FrameBuilder {
        &self.builder
    }
}
