//! Motion blur by trajectory splatting: a sample whose point moves during the shutter is
//! spread over the pixels its projected trajectory crosses (Havran et al. 2003).
//!
//! The trajectory is given by its raster positions at a few instants across the shutter
//! (a piecewise-linear path, positions linear in time within a segment) and the sample's
//! radiance at those instants (interpolated linearly in time between them). A box shutter
//! integrates over time, so a pixel receives the fraction of the shutter time the point
//! spends in it, and the time integral of the radiance over that part:
//!
//! - weight of pixel p = Σ_segments τ_k · (length of segment k inside p) / (length of k),
//!   τ_k = the segment's share of the shutter time;
//! - value of pixel p = the same integral of the (linearly interpolated) radiance.
//!
//! With instants equally spaced in time and a point moving at constant speed — the case of
//! a uniformly moving object, and of any trajectory sampled finely enough — the weights are
//! exactly proportional to the trajectory's length in each pixel, as the paper states it;
//! weighting by time stays right when the speed changes between instants (a point that
//! stops spends its time where it stops). A trajectory of zero length puts everything in
//! its pixel.
//!
//! Cells along a segment come from a 2D DDA (Amanatides & Woo 1987) after clipping the
//! segment to the image (Liang–Barsky). Pixel (x, y) covers [x, x+1) × [y, y+1) in raster
//! coordinates. **Off-screen**: the part of the shutter during which the point is outside
//! the image contributes to no pixel; that weight is dropped, not renormalised onto the
//! visible part (renormalising would brighten objects leaving the frame — a box shutter
//! records only what the sensor sees), and [`splat_trajectory`] returns the on-screen
//! weight so the caller can tell.

use chronolux_core::color::Rgb;
use chronolux_core::math::Vec2;

/// A point of a sample's trajectory across the shutter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajectoryVertex {
    /// Raster position (pixels, (0,0) top-left corner of the image).
    pub raster: Vec2,
    /// Instant (any unit; only differences count); non-decreasing along the trajectory.
    pub time: f32,
    /// Radiance of the sample at this instant.
    pub radiance: Rgb,
}

/// What one pixel receives from one trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelShare {
    /// Pixel index `y · width + x`.
    pub pixel: u32,
    /// Fraction of the shutter time spent in the pixel.
    pub weight: f32,
    /// (1 / shutter time) × ∫ radiance dt over that time: the sample's contribution to the
    /// pixel (for a constant radiance L, `weight · L`).
    pub value: Rgb,
}

/// Calls `f(x, y, u0, u1)` for every pixel the segment `a → b` crosses inside the
/// `width`×`height` image, in order along the segment, with the parameter interval
/// `[u0, u1] ⊂ [0, 1]` of the segment inside that pixel (its length there is
/// `(u1 − u0)·|b − a|`). A segment of zero length inside the image gives its pixel with
/// `[0, 1]`. Parts outside the image, and segments with non-finite ends, give nothing.
/// Where the segment passes exactly through a pixel corner it steps diagonally (the side
/// pixels get length 0 and are not reported).
pub fn segment_cells(
    a: Vec2,
    b: Vec2,
    width: u32,
    height: u32,
    mut f: impl FnMut(u32, u32, f32, f32),
) {
    if !a.is_finite() || !b.is_finite() || width == 0 || height == 0 {
        return;
    }
    let d = b - a;
    let (w, h) = (width as f32, height as f32);
    // Clip the parameter range to the image rectangle [0, w] × [0, h].
    let (mut u0, mut u1) = (0.0f32, 1.0f32);
    for (p, dp, hi) in [(a.x, d.x, w), (a.y, d.y, h)] {
        if dp == 0.0 {
            if p < 0.0 || p >= hi {
                return;
            }
        } else {
            let (ta, tb) = ((0.0 - p) / dp, (hi - p) / dp);
            u0 = u0.max(ta.min(tb));
            u1 = u1.min(ta.max(tb));
        }
    }
    if !(u0 < u1) {
        return;
    }
    // Starting pixel: the one the segment enters at u0 (on a pixel edge while moving in
    // the negative direction, the pixel on the negative side).
    let start = a + d * u0;
    let cell = |p: f32, dp: f32, n: u32| -> i64 {
        let c = p.floor();
        let c = if dp < 0.0 && c == p { c - 1.0 } else { c };
        (c as i64).clamp(0, n as i64 - 1)
    };
    let (mut x, mut y) = (cell(start.x, d.x, width), cell(start.y, d.y, height));
    let step = |dp: f32| -> i64 {
        if dp > 0.0 {
            1
        } else if dp < 0.0 {
            -1
        } else {
            0
        }
    };
    let (sx, sy) = (step(d.x), step(d.y));
    // Parameter at which the segment leaves the current pixel along one axis, computed
    // from the pixel index each time (no accumulated error).
    let exit = |c: i64, p: f32, dp: f32| -> f32 {
        if dp > 0.0 {
            ((c + 1) as f32 - p) / dp
        } else if dp < 0.0 {
            (c as f32 - p) / dp
        } else {
            f32::INFINITY
        }
    };
    let mut u = u0;
    loop {
        let tx = exit(x, a.x, d.x);
        let ty = exit(y, a.y, d.y);
        let t = tx.min(ty).min(u1);
        if t > u {
            f(x as u32, y as u32, u, t);
            u = t;
        }
        if t >= u1 {
            break;
        }
        if tx <= t {
            x += sx;
        }
        if ty <= t {
            y += sy;
        }
        if x < 0 || y < 0 || x >= width as i64 || y >= height as i64 {
            // Rounding put the exit an ulp before u1: the rest is outside.
            break;
        }
    }
}

/// Spreads a sample over the pixels its trajectory crosses (see the module doc), appending
/// one [`PixelShare`] per pixel run to `out` (consecutive pieces in one pixel are merged; a
/// trajectory that comes back to a pixel gives it a second entry, to be added). Returns the
/// on-screen weight: 1 when the whole trajectory is inside the image (up to f32 rounding),
/// less by the fraction of the shutter spent off-screen.
///
/// Segment k gets the time share `(t_{k+1} − t_k) / (t_last − t_first)`; if all instants
/// are equal (no duration), shares proportional to segment length instead, and a
/// trajectory that is also of zero length gives everything to its pixel. A single vertex is
/// a point at rest.
pub fn splat_trajectory(
    verts: &[TrajectoryVertex],
    width: u32,
    height: u32,
    out: &mut Vec<PixelShare>,
) -> f32 {
    let Some(first) = verts.first() else {
        return 0.0;
    };
    let first_len = out.len();
    let push = |out: &mut Vec<PixelShare>, x: u32, y: u32, w: f32, v: Rgb| {
        let pixel = y * width + x;
        let ours = out.len() > first_len;
        match out.last_mut() {
            Some(s) if ours && s.pixel == pixel => {
                s.weight += w;
                s.value += v;
            }
            _ => out.push(PixelShare {
                pixel,
                weight: w,
                value: v,
            }),
        }
    };
    let mut on_screen = 0.0f32;
    if verts.len() == 1 {
        segment_cells(first.raster, first.raster, width, height, |x, y, _, _| {
            push(out, x, y, 1.0, first.radiance);
            on_screen = 1.0;
        });
        return on_screen;
    }
    let duration = verts.last().unwrap().time - first.time;
    let total_len: f32 = verts
        .windows(2)
        .map(|s| (s[1].raster - s[0].raster).length())
        .sum();
    let n_seg = (verts.len() - 1) as f32;
    for s in verts.windows(2) {
        let (p, q) = (&s[0], &s[1]);
        let share = if duration > 0.0 {
            (q.time - p.time) / duration
        } else if total_len > 0.0 {
            (q.raster - p.raster).length() / total_len
        } else {
            1.0 / n_seg
        };
        if !(share > 0.0) {
            continue;
        }
        segment_cells(p.raster, q.raster, width, height, |x, y, u0, u1| {
            let w = share * (u1 - u0);
            let l = p.radiance.lerp(q.radiance, 0.5 * (u0 + u1));
            push(out, x, y, w, l * w);
            on_screen += w;
        });
    }
    on_screen
}
