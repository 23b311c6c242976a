//! A farm segment as `render` runs it: the frames it owns and computes, and the warm-up
//! history a stateful technique needs before them. Below both [`crate::render`] (which
//! runs one) and [`crate::farm`] (which plans them), so neither imports the other's run.

/// A segment as `render` runs it.
#[derive(Clone, Debug)]
pub struct SegmentRun {
    pub index: u32,
    pub owned: Vec<u32>,
    pub compute: Vec<u32>,
    pub render_before: bool,
}

impl SegmentRun {
    /// The frames the run loop visits: the owned ones, preceded by the warm-up history
    /// for a stateful technique.
    pub fn run_frames(&self) -> Vec<u32> {
        if self.render_before {
            let last = *self.owned.last().expect("a segment owns frames");
            self.compute
                .iter()
                .copied()
                .filter(|&f| f <= last)
                .collect()
        } else {
            self.owned.clone()
        }
    }

    /// `run.segment-NNNN.json`.
    pub fn manifest_name(&self) -> String {
        format!("run.segment-{:04}.json", self.index)
    }
}

/// For a stateful technique (`render_before`) writing `owned` (ascending), the last frame
/// that must be rendered, every frame before it rendered too, in order, so that the history
/// is that of an uninterrupted run: the last owned frame not yet `done` (with --resume),
/// else the last owned frame; 0 when every frame is done. `None` for the others. A farm
/// segment owns its frames (`done`: complete and recorded, as the render's own test); a
/// whole `render --resume` is one segment owning every frame.
pub fn warm_up_until(
    owned: &[u32],
    render_before: bool,
    done: impl Fn(u32) -> bool,
    resume: bool,
) -> Option<u32> {
    if !render_before {
        return None;
    }
    let last = if resume {
        owned.iter().rev().find(|&&f| !done(f)).copied()
    } else {
        owned.last().copied()
    };
    Some(last.unwrap_or(0))
}
