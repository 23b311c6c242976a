//! Motion blur (module doc, "Motion blur"): where a landed sample's point is seen one
//! frame before and after ([`trajectory`](Generation::trajectory)), the films of those
//! offsets and values ([`flush`](Generation::flush)), and the per-pixel trajectory splat
//! of a reconstructed frame ([`splat_pixel_trajectories`]).

use super::context::Generation;
use super::generation::TileOut;
use super::landing::barycentrics;
use crate::framework::window_film::Contribution;
use crate::kernels::bdpt::{Vertex, VertexKind};
use crate::kernels::blur::{TrajectoryVertex, splat_trajectory};
use chronolux_core::color::Rgb;
use chronolux_core::math::{Vec2, Vec3};

impl Generation<'_> {
    /// Motion blur: where the point a sample shows in window frame `j` is seen one frame
    /// before and after `j` (raster positions in those frames, visible or not). The point
    /// is `v` on a surface of frame `src`'s scene (moved with its object), or, for an
    /// escaped camera ray, the direction `dir` (at infinity).
    pub(super) fn trajectory(
        &self,
        j: usize,
        src: usize,
        v: Option<&Vertex>,
        dir: Option<Vec3>,
    ) -> [Option<Vec2>; 2] {
        if self.shutter <= 0.0 {
            return [None, None];
        }
        let v = v.filter(|v| v.kind == VertexKind::Surface);
        let bary = v.and_then(|v| barycentrics(&self.scenes[src], v));
        let at = |dj: isize| -> Option<Vec2> {
            let jn = j
                .checked_add_signed(dj)
                .filter(|&jn| jn < self.frames.len())?;
            if self.frames[jn].abs_diff(self.frames[j]) != 1 {
                return None;
            }
            let scene_n = &self.scenes[jn];
            let cam_n = &scene_n.camera;
            match v {
                None => dir.and_then(|d| cam_n.project(cam_n.position() + d.normalize())),
                Some(v) => {
                    let sv = v.surface.as_ref()?;
                    let geom = sv.si.tri.geometry;
                    let p = if self.same_surface(src, jn, sv.si.tri) {
                        v.p
                    } else {
                        let (b1, b2) = bary?;
                        let inst = scene_n.geometry_instance[geom as usize];
                        scene_n.surface_at(sv.si.tri, inst, b1, b2, None).p
                    };
                    cam_n.project(p)
                }
            }
        };
        [at(-1), at(1)]
    }

    /// Turns the sample's buffered landings into film contributions: one landed sample at
    /// its pixel, or (motion blur) a landed count at its pixel and its trajectory over the
    /// shutter as splats.
    pub(super) fn flush(&self, out: &mut TileOut) {
        let shutter = self.shutter;
        let landings = std::mem::take(&mut out.landings);
        for l in &landings {
            let cam = &self.scenes[l.j].camera;
            let (w, h) = (cam.width, cam.height);
            let pixel = (l.raster.y as u32).min(h - 1) * w + (l.raster.x as u32).min(w - 1);
            let frame = self.frames[l.j];
            out.squares.push(Contribution {
                frame,
                pixel,
                value: l.value * l.value,
                weight: 1.0,
                splat: false,
            });
            out.batch.push(Contribution {
                frame,
                pixel,
                value: l.value,
                weight: 1.0,
                splat: false,
            });
            if self.count_lt {
                // The splat film's weights count the landings of frames with light
                // tracing (module doc, "BDPT or the path strategies").
                out.splats.push(Contribution {
                    frame,
                    pixel,
                    value: Rgb::ZERO,
                    weight: 1.0,
                    splat: false,
                });
            }
            if shutter <= 0.0 {
                continue;
            }
            // Neighbouring frames of the window one frame interval away: where the
            // sample's point is seen there, and its value there if it landed.
            let neighbour = |dj: isize| -> Option<(Vec2, Rgb)> {
                let jn =
                    l.j.checked_add_signed(dj)
                        .filter(|&jn| jn < self.frames.len())?;
                if self.frames[jn].abs_diff(frame) != 1 {
                    return None;
                }
                let r = l.around[if dj < 0 { 0 } else { 1 }]?;
                // Radiance interpolated between frames only between values of one point.
                let v = landings
                    .iter()
                    .find(|o| o.j == jn && o.same_point && l.same_point)
                    .map_or(l.value, |o| o.value);
                Some((r, v))
            };
            let (before, after) = match (neighbour(-1), neighbour(1)) {
                (Some(b), Some(a)) => (b, a),
                (Some(b), None) => (b, (2.0 * l.raster - b.0, l.value)),
                (None, Some(a)) => ((2.0 * l.raster - a.0, l.value), a),
                (None, None) => ((l.raster, l.value), (l.raster, l.value)),
            };
            let d_before = before.0 - l.raster;
            let d_after = after.0 - l.raster;
            for (k, value) in [
                Rgb::new(d_before.x, d_before.y, 0.0),
                Rgb::new(d_after.x, d_after.y, 0.0),
                before.1,
                after.1,
            ]
            .into_iter()
            .enumerate()
            {
                out.blur[k].push(Contribution {
                    frame,
                    pixel,
                    value,
                    weight: 1.0,
                    splat: false,
                });
            }
        }
        out.landings = landings;
        out.landings.clear();
    }
}

/// Motion blur of a reconstructed frame: every pixel's value (the mean of its landed
/// samples) is spread over the pixels its trajectory crosses during the shutter
/// ([`splat_trajectory`]), the trajectory being the mean over its landed samples of where
/// their points are seen one frame before and after (`blur[0]`, `blur[1]`: raster offsets),
/// positions and radiance (`blur[2]`, `blur[3]`: values there) linear in time between
/// frames. Pixels no sample landed in contribute nothing.
pub(super) fn splat_pixel_trajectories(
    means: &[Rgb],
    weights: &[f32],
    blur: &[Vec<Rgb>],
    w: u32,
    h: u32,
    shutter: f32,
) -> Vec<Rgb> {
    let half = 0.5 * shutter;
    let mut out = vec![Rgb::ZERO; means.len()];
    let mut shares = Vec::new();
    for (i, (&l, &n)) in means.iter().zip(weights).enumerate() {
        if n <= 0.0 {
            continue;
        }
        let c = Vec2::new((i as u32 % w) as f32 + 0.5, (i as u32 / w) as f32 + 0.5);
        let (db, da) = (blur[0][i], blur[1][i]);
        let (lb, la) = (blur[2][i], blur[3][i]);
        let traj = [
            TrajectoryVertex {
                raster: c + Vec2::new(db.x, db.y) * half,
                time: -half,
                radiance: l + (lb - l) * half,
            },
            TrajectoryVertex {
                raster: c,
                time: 0.0,
                radiance: l,
            },
            TrajectoryVertex {
                raster: c + Vec2::new(da.x, da.y) * half,
                time: half,
                radiance: l + (la - l) * half,
            },
        ];
        shares.clear();
        splat_trajectory(&traj, w, h, &mut shares);
        for sh in &shares {
            out[sh.pixel as usize] += sh.value;
        }
    }
    out
}
