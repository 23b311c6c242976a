//! What one generated frame's parts share: the read-only [`Generation`] state (its
//! methods live with the phase that uses them: [`super::generation`] traces and splits,
//! [`super::landing`] decides how a sample serves a window frame, [`super::reuse`]
//! computes its value there), the view-independent [`Entry`] at x1 and the coverage of a
//! window frame's pixels. Kept apart so that those phases import this module and not
//! each other.

use crate::kernels::bdpt::{BdptSettings, ViewSplit};
use chronolux_core::accel::Hit;
use chronolux_core::accel::multi_frame::{FrameMask, MultiFrameAccel};
use chronolux_core::color::Rgb;
use chronolux_core::math::Vec3;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use std::sync::Arc;

/// Two answers of one ray that give the same vertex.
pub(super) fn same_hit(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.tri == b.tri
                && a.instance == b.instance
                && a.t.to_bits() == b.t.to_bits()
                && a.b1.to_bits() == b.b1.to_bits()
                && a.b2.to_bits() == b.b2.to_bits()
        }
        _ => false,
    }
}

/// One view-independent entry at x1.
pub(super) struct Entry {
    /// Light vertices of the strategy: s ≤ 1 does not depend on the light subpath.
    pub(super) s: usize,
    /// Camera vertices of the strategy (t ≥ 2).
    pub(super) t: usize,
    pub(super) wi: Vec3,
    pub(super) r: Rgb,
    /// The contribution as computed in f (for f itself, no rounding from the split).
    pub(super) c: Rgb,
    /// t ≥ 3: `wi` is x1's sampled continuation, shared by every such entry.
    pub(super) continuation: bool,
    /// Window frames in which the entry's shadow ray is unoccluded.
    pub(super) vis: FrameMask,
    /// Its MIS weight split by what depends on the camera ([`view_split`](crate::kernels::bdpt::connect::view_split)), kept when
    /// light tracing is on and a window frame has another camera: a frame g with another
    /// camera re-weights the entry for it (module doc, "MIS weights in another frame").
    pub(super) split: Option<ViewSplit>,
    /// With `split`: x1's BSDF density of `wi` for f's view (the view-dependent density
    /// the split's terms scale with, computed once here instead of in every frame).
    pub(super) pdf_f: f32,
}

/// Which pixels of a window frame g take landings from f (module doc, "Bias"): `None`
/// when all do (g's camera and geometry are f's, so f sees every point g sees), else
/// per pixel of g whether its test points ([`Generation::coverage`]) are all seen by f.
pub(super) type Coverage = Option<Vec<bool>>;

/// Read-only state of one generated frame.
pub(super) struct Generation<'a> {
    pub(super) bdpt: &'a BdptSettings,
    /// [`StbptSettings::interleave`](super::StbptSettings::interleave).
    pub(super) interleave: u32,
    pub(super) frames: &'a [u32],
    pub(super) scenes: &'a [Arc<FrameScene>],
    pub(super) jf: usize,
    pub(super) f: u32,
    pub(super) mfa: &'a MultiFrameAccel,
    /// Frames whose lights (and materials) equal f's.
    pub(super) lights_same: FrameMask,
    pub(super) materials_same: FrameMask,
    /// Frames whose camera is f's (same placement, projection and image size).
    pub(super) same_camera: FrameMask,
    /// Shutter as a fraction of the frame interval (0: no motion blur).
    pub(super) shutter: f32,
    /// What differs between f and each window frame (`from_f[jf]`: nothing).
    pub(super) from_f: &'a [FrameDelta],
    /// What differs between window frames `j` and `j + 1` (motion blur only; else empty).
    pub(super) steps: &'a [FrameDelta],
    /// `bdpt` with only the path strategies (their MIS weights for the pilot).
    pub(super) path_bdpt: &'a BdptSettings,
    /// Measure what the path strategies would give (the frame has all strategies and
    /// chooses the next frame's: module doc, "BDPT or the path strategies").
    pub(super) pilot: bool,
    /// Count each landing of this frame in the splat film's weights: the frame has light
    /// tracing and frames without it may serve the same frames (module doc, "BDPT or the
    /// path strategies").
    pub(super) count_lt: bool,
    /// Per window frame, which of its pixels take landings from f
    /// ([`Generation::coverage`]; empty while it is computed: all).
    pub(super) coverage: &'a [Coverage],
}
