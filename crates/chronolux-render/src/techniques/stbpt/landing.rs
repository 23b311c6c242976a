//! Landing: where a sample generated in f shows in window frame g and how it serves g
//! there (module doc, "Reuse in frame g", steps 1–3), as one explicit [`Landing`]. The
//! scene comparisons come from the generation's [`FrameDelta`]s
//! (chronolux-core's one exact change record), never from checks of its own.

use super::context::{Coverage, Generation, same_hit};
use crate::kernels::bdpt::Vertex;
use chronolux_core::accel::multi_frame::FrameMask;
use chronolux_core::accel::{Hit, TriRef};
use chronolux_core::geometry::{Ray, spawn_ray_to};
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
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
    /// triangle; or an escaped camera ray's direction is off g's screen or g's ray there
    /// meets a surface; or the pixel it lands in is one f does not wholly see
    /// ([`Generation::coverage`]). It does not serve
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
    /// Same camera and x1 not moved, but the split is not reusable in g (a camera segment
    /// after x1 or the lights differ, or x1 is a delta or near-specular vertex): re-traced
    /// from f's raster position, so that the camera vertices whose rays give f's hits in g
    /// are f's (answered without a traversal) and the strategies made of reproduced
    /// vertices only are f's values (module doc, "Reuse in frame g", step 3).
    RetracePrefix(Vec2),
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
    /// Triangle `tri` is the same surface in window frames `a` and `b`: its instance did
    /// not move and, on a deformed mesh, its own vertices did not
    /// ([`FrameDelta::triangle_changed`]: the still part of a skinned or morphed mesh is
    /// reused as static geometry is). Known for f against every frame and, with motion
    /// blur, for neighbouring frames.
    pub(super) fn same_surface(&self, a: usize, b: usize, tri: TriRef) -> bool {
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
        !d.triangle_changed(&self.scenes[a], &self.scenes[b], tri)
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
        if !matches!(cam_g.projection(), Projection::Perspective { .. }) {
            return Landing::Missed;
        }
        let eye = cam_g.position();
        let eye_f = scene_f.camera.position();
        let Some(v) = walk.x1 else {
            // Escaped camera ray (or an environment vertex): lands where its direction
            // projects; reused when g's camera is f's and the ray escapes in g too (then
            // g's camera ray is the same ray).
            let same_camera = cam_g.world_from_camera() == scene_f.camera.world_from_camera();
            return match walk
                .escape
                .and_then(|r| cam_g.project(eye + r.d.normalize()))
                .filter(|&r| self.covered(j, r))
            {
                Some(r) if same_camera && walk.cam_valid >> j & 1 == 1 => Landing::ReuseEscaped(r),
                Some(r) => {
                    // g's camera ray there must escape too: where it meets a surface, that
                    // surface's own landings from f already serve the point (the landing
                    // would count it twice: module doc, "Bias").
                    stats[j].rays += 1;
                    if scene_g.intersect(&cam_g.generate_ray(r)).is_some() {
                        Landing::Missed
                    } else {
                        Landing::Retrace(r)
                    }
                }
                None => Landing::Missed,
            };
        };
        let sv = v.surface.as_ref().unwrap();
        let geom = sv.si.tri.geometry;
        let moved = !self.same_surface(jf, j, sv.si.tri);
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
        let Some(r) = cam_g.project(p).filter(|&r| faces && self.covered(j, r)) else {
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
        } else if self.same_camera >> j & 1 == 1 && !moved {
            Landing::RetracePrefix(r)
        } else {
            Landing::Retrace(r)
        }
    }
}

impl Generation<'_> {
    /// Whether pixel `r` (raster position) of window frame `j` takes landings from f.
    fn covered(&self, j: usize, r: Vec2) -> bool {
        let Some(Some(c)) = self.coverage.get(j) else {
            return true;
        };
        let w = self.scenes[j].camera.width;
        let h = self.scenes[j].camera.height;
        c[((r.y as u32).min(h - 1) * w + (r.x as u32).min(w - 1)) as usize]
    }

    /// Per window frame g, which of its pixels take landings from f: those whose footprint
    /// f sees, tested at its four corners and its centre ([`Generation::seen_from_f`]). A
    /// pixel part of which f does not see (off f's screen, hidden in f, or background
    /// that f sees covered) would take f's landings only on the part f sees: its mean
    /// would be that part's (module doc, "Bias"). Frames with f's camera and materials
    /// share one window query per test point (the same ray in every such frame): a point
    /// g sees on a surface unchanged since f, or background, is seen by f iff f's answer
    /// along the ray is the same; only a point on a moved surface needs the full test.
    /// The rays are counted in `stats` (the shared window query in f's).
    pub(super) fn coverage(&self, stats: &mut [Stats]) -> Vec<Coverage> {
        let (jf, n) = (self.jf, self.scenes.len());
        let scene_f = &self.scenes[jf];
        let pinhole =
            |s: &FrameScene| matches!(s.camera.projection(), Projection::Perspective { .. });
        let (w, h) = (scene_f.camera.width, scene_f.camera.height);
        // The frames whose view may differ from f's.
        let mut test: FrameMask = 0;
        for j in (0..n).filter(|&j| j != jf) {
            let d = &self.from_f[j];
            let g = &self.scenes[j];
            let static_view = !d.camera_changed()
                && !d.materials_changed()
                && (0..d.instance_count()).all(|i| !d.instance_changed(i));
            let size = (g.camera.width, g.camera.height) == (w, h);
            if !static_view && pinhole(g) && pinhole(scene_f) && size {
                test |= 1 << j;
            }
        }
        if test == 0 {
            return vec![None; n];
        }
        let shared = test & self.same_camera & self.materials_same;
        let bits = |m: FrameMask| (0..n).filter(move |&j| m >> j & 1 == 1);
        // Test points inside the image: the corners on the border are moved in by a
        // thousandth of a pixel.
        let at = |x: u32, y: u32, half: f32| {
            let e = 1e-3;
            Vec2::new(
                (x as f32 + half).clamp(e, w as f32 - e),
                (y as f32 + half).clamp(e, h as f32 - e),
            )
        };
        // The frames that see what g sees at `q`.
        let seen_at = |q: Vec2, st: &mut [Stats]| -> FrameMask {
            let mut seen: FrameMask = 0;
            if shared != 0 {
                let ray = scene_f.camera.generate_ray(q);
                st[jf].rays += 1;
                let wh = self
                    .mfa
                    .intersect_window(&ray, shared | 1 << jf, |t, b1, b2| {
                        scene_f.accept(t, b1, b2)
                    });
                let hf = wh.frame(jf);
                for j in bits(shared) {
                    let hj = wh.frame(j);
                    let moved = hj.is_some_and(|h| !self.same_surface(jf, j, h.tri));
                    let ok = if moved {
                        self.seen_from_f(j, &ray, hj, &mut st[j])
                    } else {
                        same_hit(hj, hf)
                    };
                    seen |= u64::from(ok) << j;
                }
            }
            for j in bits(test & !shared) {
                let scene_g = &self.scenes[j];
                let ray = scene_g.camera.generate_ray(q);
                st[j].rays += 1;
                let hj = scene_g.intersect(&ray);
                seen |= u64::from(self.seen_from_f(j, &ray, hj, &mut st[j])) << j;
            }
            seen
        };
        // Rows of corners (h + 1 of w + 1) and of centres (h of w).
        let rows = parallel::map_chunks(2 * h as usize + 1, 1, |range| {
            let mut st = vec![Stats::default(); n];
            let seen: Vec<Vec<FrameMask>> = range
                .map(|i| {
                    let (y, half) = ((i / 2) as u32, (i % 2) as f32 * 0.5);
                    let count = w + 1 - (i % 2) as u32;
                    (0..count)
                        .map(|x| seen_at(at(x, y, half), &mut st))
                        .collect()
                })
                .collect();
            (seen, st)
        });
        let mut grid: Vec<Vec<FrameMask>> = Vec::with_capacity(2 * h as usize + 1);
        for (seen, st) in rows {
            for (a, b) in stats.iter_mut().zip(st) {
                *a += b;
            }
            grid.extend(seen);
        }
        (0..n)
            .map(|j| {
                if test >> j & 1 == 0 {
                    return None;
                }
                let mut c = vec![false; (w * h) as usize];
                for y in 0..h as usize {
                    let (top, mid, bottom) = (&grid[2 * y], &grid[2 * y + 1], &grid[2 * y + 2]);
                    for x in 0..w as usize {
                        let all = top[x] & top[x + 1] & mid[x] & bottom[x] & bottom[x + 1];
                        c[y * w as usize + x] = all >> j & 1 == 1;
                    }
                }
                Some(c)
            })
            .collect()
    }

    /// Whether f sees what window frame g sees along g's camera ray `ray` (its hit in g:
    /// `hit`): the surface point (moved with its object into f) on f's screen, from the
    /// same side as g and unoccluded from f's eye; or, where g's ray escapes, the same
    /// direction escaping from f's eye on f's screen. One shadow query in f.
    fn seen_from_f(&self, j: usize, ray: &Ray, hit: Option<Hit>, st: &mut Stats) -> bool {
        let (scene_f, scene_g) = (&self.scenes[self.jf], &self.scenes[j]);
        let eye_f = scene_f.camera.position();
        st.shadow_rays += 1;
        let Some(hit) = hit else {
            return scene_f.camera.project(eye_f + ray.d.normalize()).is_some()
                && !scene_f.occluded(&Ray::new(eye_f, ray.d));
        };
        let geom = hit.tri.geometry;
        let si_g = scene_g.surface_at(hit.tri, hit.instance, hit.b1, hit.b2, Some(ray.at(hit.t)));
        let (p, ng) = if self.same_surface(self.jf, j, hit.tri) {
            (si_g.p, si_g.ng)
        } else {
            let inst = scene_f.geometry_instance[geom as usize];
            let si = scene_f.surface_at(hit.tri, inst, hit.b1, hit.b2, None);
            (si.p, si.ng)
        };
        let faces = si_g.ng.dot(-ray.d) * ng.dot(eye_f - p) > 0.0;
        faces
            && scene_f.camera.project(p).is_some()
            && !scene_f.occluded(&spawn_ray_to(p, ng, eye_f, Vec3::ZERO))
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
