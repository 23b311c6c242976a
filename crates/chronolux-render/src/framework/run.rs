//! The one run loop: a technique over a list of frames, each finished frame handed to
//! [`FrameSink`]s.
//!
//! `chronolux render`, `reference`, `bench` and `bench quality` all go through [`run`]
//! (or, for progressive consumers, [`run_progressive`]); what they differ in is their
//! sinks: the EXR/PNG/preview/run.json writer, an in-memory sink ([`MemorySink`]) for
//! benchmarks and tests, progress reporting, and later the live viewer and farm segments.
//! The loop knows no technique: it asks the sinks which frames are still wanted (a
//! resumed render skips complete ones), times each frame (wall and process CPU), and
//! records the frame builder's statistics beside the technique's own report.

use crate::framework::aov::{self, Aovs, PassSet};
use crate::framework::integrator::RenderedFrame;
use crate::framework::sequence::{Flow, Pass, PassPlan, SequenceRenderer};
use chronolux_core::scene::source::FrameSource;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// An error a sink reports (writing a file, …); it ends the run.
pub type SinkError = Box<dyn std::error::Error + Send + Sync>;

/// A frame as the run loop hands it to the sinks.
pub struct FinishedFrame<'a> {
    pub frame: u32,
    /// Animation time of the frame in seconds.
    pub time_s: f32,
    /// Wall-clock seconds the technique took for this frame (look-ahead work included).
    pub wall_s: f64,
    /// The image, its statistics and the technique's report.
    pub output: &'a RenderedFrame,
    /// Statistics of the last scene the frame builder made.
    pub build: serde_json::Value,
    /// Position in the run: `k` of `n` frames.
    pub k: usize,
    pub n: usize,
    /// The geometric render passes asked for in [`RunOptions::passes`] (`None` when none
    /// were); direct and indirect light travel in [`RenderedFrame::light`].
    pub aovs: Option<&'a Aovs>,
}

/// What the run loop makes besides the technique's frames.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunOptions {
    /// Render passes of every frame ([`crate::framework::aov`]), the same for every technique.
    pub passes: PassSet,
    /// Seed of the passes' sample streams.
    pub seed: u64,
}

impl FinishedFrame<'_> {
    /// The frame's record for `run.json`: ray and sample counts, the frame builder's
    /// statistics, and every entry of the technique's report.
    pub fn record(&self) -> serde_json::Value {
        let o = self.output;
        let mut m = serde_json::Map::new();
        m.insert("rays".into(), o.stats.rays.into());
        m.insert("shadow_rays".into(), o.stats.shadow_rays.into());
        m.insert("samples".into(), o.stats.samples.into());
        m.insert("invalid_samples".into(), o.invalid_samples.into());
        m.insert("build".into(), self.build.clone());
        for (k, v) in &o.report {
            m.insert(k.clone(), v.clone());
        }
        serde_json::Value::Object(m)
    }
}

/// Where finished frames go. `Sync` because pixel progress is reported from the worker
/// threads.
pub trait FrameSink: Sync {
    /// Whether the sink still needs `frame` (false: it has it already, e.g. `--resume`).
    /// A frame no sink needs is not rendered.
    fn needs(&self, frame: u32) -> bool {
        let _ = frame;
        true
    }
    /// Frame `frame` (`k`-th of `n`) is about to be rendered.
    fn begin_frame(&mut self, frame: u32, k: usize, n: usize) {
        let _ = (frame, k, n);
    }
    /// `pixels` more pixels of the current frame are done (called from worker threads).
    fn pixels(&self, pixels: u64) {
        let _ = pixels;
    }
    /// A refinement of the current frame (progressive runs only).
    fn pass(&mut self, pass: &Pass) -> Flow {
        let _ = pass;
        Flow::Continue
    }
    /// Frame `frame` was skipped because no sink needed it.
    fn skipped(&mut self, frame: u32, k: usize, n: usize) {
        let _ = (frame, k, n);
    }
    /// A finished frame.
    fn frame(&mut self, frame: &FinishedFrame) -> Result<(), SinkError>;
    /// The run is over (every frame rendered or skipped).
    fn finish(&mut self, summary: &RunSummary) -> Result<(), SinkError> {
        let _ = summary;
        Ok(())
    }
}

/// What the loop measured over the whole run.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunSummary {
    pub rendered: Vec<u32>,
    pub skipped: Vec<u32>,
    pub wall_s: f64,
    /// Process CPU seconds (user + system) of the run; NaN where unavailable.
    pub cpu_s: f64,
    /// Whether the run was cancelled before its last frame.
    pub cancelled: bool,
}

/// Process CPU seconds (user + system) from /proc/self/stat (Linux; USER_HZ = 100, the
/// value every Linux ABI fixes for this interface). `None` elsewhere.
pub fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let (u, k): (f64, f64) = (f.get(11)?.parse().ok()?, f.get(12)?.parse().ok()?);
    Some((u + k) / 100.0)
}

/// Renders `frames` (in the order given) with `technique`, handing each to every sink.
/// `cancel`, when set, stops the run between frames.
pub fn run(
    technique: &mut dyn SequenceRenderer,
    source: &mut FrameSource,
    frames: &[u32],
    sinks: &mut [&mut dyn FrameSink],
    cancel: Option<&AtomicBool>,
) -> Result<RunSummary, SinkError> {
    drive(
        technique,
        source,
        frames,
        sinks,
        cancel,
        None,
        RunOptions::default(),
    )
}

/// [`run`] with options (render passes).
pub fn run_with(
    technique: &mut dyn SequenceRenderer,
    source: &mut FrameSource,
    frames: &[u32],
    sinks: &mut [&mut dyn FrameSink],
    cancel: Option<&AtomicBool>,
    options: RunOptions,
) -> Result<RunSummary, SinkError> {
    drive(technique, source, frames, sinks, cancel, None, options)
}

/// [`run`] with every frame rendered as successive refinements
/// ([`SequenceRenderer::render_passes`]); each pass goes to every sink's
/// [`FrameSink::pass`], and a frame ends when a sink answers [`Flow::Stop`] (or the
/// technique's plan is exhausted).
pub fn run_progressive(
    technique: &mut dyn SequenceRenderer,
    source: &mut FrameSource,
    frames: &[u32],
    plan: PassPlan,
    sinks: &mut [&mut dyn FrameSink],
    cancel: Option<&AtomicBool>,
) -> Result<RunSummary, SinkError> {
    drive(
        technique,
        source,
        frames,
        sinks,
        cancel,
        Some(plan),
        RunOptions::default(),
    )
}

fn drive(
    technique: &mut dyn SequenceRenderer,
    source: &mut FrameSource,
    frames: &[u32],
    sinks: &mut [&mut dyn FrameSink],
    cancel: Option<&AtomicBool>,
    plan: Option<PassPlan>,
    options: RunOptions,
) -> Result<RunSummary, SinkError> {
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let mut summary = RunSummary::default();
    let n = frames.len();
    for (k, &f) in frames.iter().enumerate() {
        if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            summary.cancelled = true;
            break;
        }
        if !sinks.iter().any(|s| s.needs(f)) {
            for s in sinks.iter_mut() {
                s.skipped(f, k, n);
            }
            summary.skipped.push(f);
            continue;
        }
        for s in sinks.iter_mut() {
            s.begin_frame(f, k, n);
        }
        let start = Instant::now();
        let out = {
            let shared: &[&mut dyn FrameSink] = sinks;
            let progress = |p: u64| {
                for s in shared {
                    s.pixels(p);
                }
            };
            match plan {
                None => technique.render_frame(source, f, &progress),
                Some(plan) => {
                    // The passes go to the sinks one after another; any Stop ends the frame.
                    let cell = std::cell::RefCell::new(&mut *sinks);
                    technique.render_passes(source, f, plan, &|_| {}, &mut |pass| {
                        let mut flow = Flow::Continue;
                        for s in cell.borrow_mut().iter_mut() {
                            if s.pass(pass) == Flow::Stop {
                                flow = Flow::Stop;
                            }
                        }
                        flow
                    })
                }
            }
        };
        let wall_s = start.elapsed().as_secs_f64();
        let aovs = options.passes.geometric().then(|| {
            // Neighbours for motion: the frames before and after on the timeline.
            let motion = options.passes.motion;
            let prev = (motion && f > 0).then(|| source.frame(f - 1));
            let next = motion.then(|| source.frame(f + 1));
            let scene = source.frame(f);
            aov::render_aovs(
                &scene,
                prev.as_deref(),
                next.as_deref(),
                f,
                options.seed,
                options.passes,
            )
        });
        let fin = FinishedFrame {
            frame: f,
            time_s: source.time(f),
            wall_s,
            output: &out,
            build: serde_json::to_value(source.last_build).unwrap_or_default(),
            k,
            n,
            aovs: aovs.as_ref(),
        };
        for s in sinks.iter_mut() {
            s.frame(&fin)?;
        }
        summary.rendered.push(f);
    }
    summary.wall_s = t0.elapsed().as_secs_f64();
    summary.cpu_s = match (c0, cpu_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => f64::NAN,
    };
    for s in sinks.iter_mut() {
        s.finish(&summary)?;
    }
    Ok(summary)
}

/// Keeps every finished frame in memory (benchmarks, tests).
#[derive(Default)]
pub struct MemorySink {
    /// (frame, image, run.json record) in the order rendered.
    pub frames: Vec<(u32, RenderedFrame, serde_json::Value)>,
}

impl MemorySink {
    pub fn new() -> Self {
        Self::default()
    }

    /// The images in the order rendered.
    pub fn images(&self) -> impl Iterator<Item = &RenderedFrame> {
        self.frames.iter().map(|(_, i, _)| i)
    }
}

impl FrameSink for MemorySink {
    fn frame(&mut self, f: &FinishedFrame) -> Result<(), SinkError> {
        self.frames.push((f.frame, f.output.clone(), f.record()));
        Ok(())
    }
}
