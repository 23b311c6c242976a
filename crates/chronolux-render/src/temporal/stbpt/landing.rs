//! Landing: where a sample generated in f shows in window frame g and how it serves g
//! there (module doc, "Reuse in frame g", steps 1–3), as one explicit [`Landing`]. The
//! scene comparisons come from the generation's [`FrameDelta`]s
//! (chronolux-core's one exact change record), never from checks of its own.

use super::generation::Generation;
use crate::bdpt::Vertex;
use chronolux_core::accel::multi_frame::FrameMask;
use chronolux_core::geometry::{Ray, spawn_ray_to};
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::desc::Projection;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;

/// How a sample generated in f serves window frame g (each carries the raster position
/// in g where it lands).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Landing {
    /// It does not land in g: g's camera is not a pinhole, or x1 is off g's screen, seen
    /// from the other side than in f, occluded in g, or moved and not locatable on its
    /// triangle; or an escaped camera ray's direction is off g's screen. It does not serve
    /// g's camera part (its light subpath still serves g's light tracing).
    Missed,
    /// An escaped camera ray reused as it is: g's camera has f's placement and the ray
    /// escapes in g too, so g's camera ray is the same ray with the same value.
    ReuseEscaped(Vec2),
    /// Everything the shading split depends on is reproduced in g: f's view-independent
    /// part is reused, only x1's BSDF and emission are re-evaluated for g's view.
    Reuse(Vec2),
    /// Only the light subpath is invalid in g (x1 and every camera segment reproduced,
    /// same lights and materials): the strategies s ≤ 1 are reused as in [`Landing::Reuse`],
    /// the strategies s ≥ 2 recomputed with the light subpath regenerated in g.
    Partial(Vec2),
    /// Same camera, x1 (not moved) and every camera segment reproduced in g: f's camera
    /// subpath is the walk g makes for this raster position; only the light subpath and
    /// the connections are g's own.
    RetraceConnections(Vec2),
    /// A fresh BDPT evaluation in g's scene, of the same streams, for a camera ray through
    /// the raster position.
    Retrace(Vec2),
}

/// What a sample's camera subpath in f tells about the other window frames.
pub(super) struct Walk<'v> {
    /// The first eye vertex, when it is on a surface.
    pub(super) x1: Option<&'v Vertex>,
    /// x1's barycentrics on its triangle (to move it with its object).
    pub(super) x1_bary: Option<(f32, f32)>,
    /// The camera ray (for an escaped sample: the direction it escaped along).
    pub(super) escape: Option<Ray>,
    /// Frames reproducing x1's camera segments and light subpath, with f's lights and
    /// materials (for an escaped ray: its escape).
    pub(super) cam_valid: FrameMask,
    /// Frames reproducing the camera segments after x1, with f's materials.
    pub(super) cam_segments: FrameMask,
}

impl Generation<'_> {
    /// The surface carrying geometry `geom` is the same in window frames `a` and `b` (its
    /// instance neither moved nor deformed: [`FrameDelta::geometry_changed`]). Known for
    /// f against every frame and, with motion blur, for neighbouring frames.
    pub(super) fn same_surface(&self, a: usize, b: usize, geom: u32) -> bool {
        let d: &FrameDelta = if a == b {
            return true;
        } else if a == self.jf {
            &self.from_f[b]
        } else if b == self.jf {
            &self.from_f[a]
        } else if a.abs_diff(b) == 1 {
            &self.steps[a.min(b)]
        } else {
            unreachable!("frames {a} and {b} are neither f nor neighbours")
        };
        !d.geometry_changed(&self.scenes[a], geom)
    }

    /// Where and how the sample whose camera walk in f is `walk` lands in window frame
    /// `j` ≠ f. The landing visibility of an unmoved x1 seen from f's eye is answered once
    /// for the whole window and kept in `land_occ`; shadow rays are counted in `stats`.
    pub(super) fn landing(
        &self,
        j: usize,
        walk: &Walk,
        land_occ: &mut Option<FrameMask>,
        stats: &mut [Stats],
    ) -> Landing {
        let jf = self.jf;
        let all = self.mfa.all_frames();
        let (scene_f, scene_g) = (&self.scenes[jf], &self.scenes[j]);
        let cam_g = &scene_g.camera;
        if !matches!(cam_g.projection, Projection::Perspective { .. }) {
            return Landing::Missed;
        }
        let eye = cam_g.position();
        let eye_f = scene_f.camera.position();
        let Some(v) = walk.x1 else {
            // Escaped camera ray (or an environment vertex): lands where its direction
            // projects; reused when g's camera is f's and the ray escapes in g too (then
            // g's camera ray is the same ray).
            let same_camera = cam_g.world_from_camera == scene_f.camera.world_from_camera;
            return match walk
                .escape
                .and_then(|r| cam_g.project(eye + r.d.normalize()))
            {
                Some(r) if same_camera && walk.cam_valid >> j & 1 == 1 => Landing::ReuseEscaped(r),
                Some(r) => Landing::Retrace(r),
                None => Landing::Missed,
            };
        };
        let sv = v.surface.as_ref().unwrap();
        let geom = sv.si.tri.geometry;
        let moved = !self.same_surface(jf, j, geom);
        let (p, ng) = if moved {
            let Some((b1, b2)) = walk.x1_bary else {
                return Landing::Missed;
            };
            let inst = scene_g.geometry_instance[geom as usize];
            let si = scene_g.surface_at(sv.si.tri, inst, b1, b2, None);
            (si.p, si.ng)
        } else {
            (v.p, v.ng)
        };
        let wo_g = (eye - p).normalize_or_zero();
        // Seen from the same side of the surface as in f.
        let faces = sv.si.ng.dot(sv.wo) * ng.dot(wo_g) > 0.0;
        let Some(r) = cam_g.project(p).filter(|_| faces) else {
            return Landing::Missed;
        };
        let shared = !moved && eye == eye_f && self.materials_same >> j & 1 == 1;
        let occluded = if shared {
            let occ = *land_occ.get_or_insert_with(|| {
                stats[jf].shadow_rays += 1;
                let ray = spawn_ray_to(p, ng, eye, Vec3::ZERO);
                self.mfa
                    .occluded_window(&ray, all, |t, b1, b2| scene_f.accept(t, b1, b2))
            });
            occ >> j & 1 == 1
        } else {
            stats[j].shadow_rays += 1;
            scene_g.occluded(&spawn_ray_to(p, ng, eye, Vec3::ZERO))
        };
        if occluded {
            return Landing::Missed;
        }
        let camera_moved = eye != eye_f;
        let valid = walk.cam_valid >> j & 1 == 1;
        // The continuation at x1 was sampled for f's view: not reused for another view at
        // a near-specular surface.
        let view_safe = !(sv.bsdf.near_specular() && camera_moved);
        let split_ok = view_safe && !moved && !v.delta;
        if valid && split_ok {
            Landing::Reuse(r)
        } else if split_ok && (walk.cam_segments & self.lights_same) >> j & 1 == 1 {
            // Only the light subpath differs in g: the camera subpath and the strategies
            // s ≤ 1 are g's as well.
            Landing::Partial(r)
        } else if self.same_camera >> j & 1 == 1 && walk.cam_segments >> j & 1 == 1 && !moved {
            Landing::RetraceConnections(r)
        } else {
            Landing::Retrace(r)
        }
    }
}

/// Barycentrics (b1, b2) of world point `p` on triangle `tri` of instance `instance`.
pub(super) fn barycentrics(scene: &FrameScene, v: &Vertex) -> Option<(f32, f32)> {
    let si = &v.surface.as_ref()?.si;
    let g = &scene.geometry[si.tri.geometry as usize];
    let [i0, i1, i2] = g.indices[si.tri.triangle as usize].map(|i| i as usize);
    let to_world = |q: Vec3| {
        if g.world_space {
            q
        } else {
            scene.accel.instances()[si.instance as usize]
                .world_from_object
                .transform_point3(q)
        }
    };
    let (p0, p1, p2) = (
        to_world(g.positions[i0]),
        to_world(g.positions[i1]),
        to_world(g.positions[i2]),
    );
    let (e1, e2, d) = (p1 - p0, p2 - p0, v.p - p0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if den.abs() < 1e-30 {
        return None;
    }
    Some(((d22 * d1 - d12 * d2) / den, (d11 * d2 - d12 * d1) / den))
}
