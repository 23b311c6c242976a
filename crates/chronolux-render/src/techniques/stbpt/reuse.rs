//! Reuse: the value a landed sample gives window frame g (module doc, "Reuse in frame g",
//! steps 2 and 3): f's view-independent part at x1 re-evaluated for g's view, with the
//! strategies s ≥ 2 recomputed against g's light subpath when only that changed
//! ([`reused_value`](Generation::reused_value)); or plain BDPT strategies in g's scene
//! ([`camera_strategies`](Generation::camera_strategies)) when the sample is re-traced.

use super::context::{Entry, Generation};
use crate::kernels::bdpt::{Vertex, ViewSplit, connect, connect_with, skip_connect, view_split};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::Ray;
use chronolux_core::math::Vec3;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::stats::Stats;

/// A re-traced sample's part reproduced in g (same camera, x1 not moved): what
/// [`Generation::prefix_strategies`] takes from f.
pub(super) struct Reproduced<'a> {
    /// Camera rays whose hits (and the materials there) are f's in g: camera vertices
    /// 0..=`camera` are f's.
    pub(super) camera: usize,
    /// Light vertices reproduced in g (0 when g's lights or materials differ from f's).
    pub(super) light: usize,
    /// f's strategies t ≥ 2 at x1 other than (0, 2), in the order evaluated ((t, s)
    /// increasing), and x1's emission (0, 2).
    pub(super) entries: &'a [Entry],
    pub(super) emission: Option<(Rgb, f32)>,
}

/// Partial reuse in g: what the recomputed strategies are made of.
pub(super) struct Regenerated<'a> {
    /// g's light subpath.
    pub(super) light: &'a [Vertex],
    /// f's camera subpath (reproduced in g) and its rays.
    pub(super) cam: &'a [Vertex],
    pub(super) cam_rays: &'a [Ray],
    /// Light vertices reproduced in g (the valid prefix).
    pub(super) kept: usize,
}

impl Generation<'_> {
    /// The value in window frame `j` of a sample reused at its first eye vertex `v`
    /// (which is where it was in f): `Le(x1 → wo_g)·w_e + Σ_k V_k(g) f(x1, wo_g, wi_k) ⊙
    /// R_k` over the `entries` split off in f (`emission`: x1's own emitted radiance and
    /// its MIS weight). With `regenerated` = (g's light subpath, f's camera subpath, its
    /// rays, the number p of light vertices reproduced in g), only the entries s ≤ max(p, 1)
    /// are reused and the strategies with more light vertices are recomputed by connecting
    /// f's camera subpath (reproduced in g) to g's light subpath in g's scene, split at x1
    /// the same way (partial reuse). A strategy (s, t) — its contribution and its MIS
    /// weight — depends only on light vertices 0..s and camera vertices 0..t.
    #[allow(clippy::too_many_arguments)] // reason: the sample's parts and the output
    pub(super) fn reused_value(
        &self,
        j: usize,
        v: &Vertex,
        emission: Option<(Rgb, f32)>,
        entries: &[Entry],
        regenerated: Option<Regenerated>,
        ns: &PixelSampler,
        st: &mut Stats,
    ) -> Rgb {
        let scene_g = &self.scenes[j];
        let eye = scene_g.camera.position();
        let max_segments = self.bdpt.depth() as usize;
        let kept = regenerated.as_ref().map_or(usize::MAX, |r| r.kept.max(1));
        let sv = v.surface.as_ref().unwrap();
        let wo_g = (eye - v.p).normalize_or_zero();
        // x1 is where it was in f (samples are reused only then), so with f's eye the view
        // direction is f's and the entries' values computed in f are g's: no BSDF
        // re-evaluation.
        let same_view = eye == self.scenes[self.jf].camera.position();
        // With light tracing, each entry is re-weighted for g's camera: x1's density from
        // it, and the densities at x1 that depend on the view (module doc, "MIS weights in
        // another frame").
        let rho = self.camera_density_ratio(j, v);
        // x1's BSDF density of `wi` for g's view over f's (`pf`), 1 for f's view.
        let view_ratio = |wi: Vec3, pf: f32| -> f32 {
            if same_view {
                1.0
            } else {
                sv.bsdf.pdf(wo_g, wi) / pf
            }
        };
        // t ≥ 3: the continuation's density, f's over g's: one direction shared by all
        // those strategies, the reused entries' and the recomputed ones', so one
        // evaluation per landing.
        let cont = entries
            .iter()
            .find(|e| e.continuation && e.split.is_some())
            .map(|e| (e.wi, e.pdf_f))
            .or_else(|| {
                let r = regenerated.as_ref().filter(|r| r.cam.len() > 2)?;
                let wi = r.cam_rays[1].d.normalize();
                Some((wi, sv.bsdf.pdf(sv.wo, wi)))
            })
            .map_or(1.0, |(wi, pf)| 1.0 / view_ratio(wi, pf));
        // t = 2: the reverse density at x1 towards the light vertex, g's over f's
        // (`light_ratio`, evaluated only where the light side has strategies).
        let reweigh = |sp: ViewSplit, t: usize, light_ratio: &dyn Fn() -> f32| {
            if t >= 3 {
                sp.reweight(rho, cont, 1.0)
            } else if sp.light > 0.0 {
                sp.reweight(rho, 1.0, light_ratio())
            } else {
                sp.reweight(rho, 1.0, 1.0)
            }
        };
        let reweight = |e: &Entry| {
            e.split
                .map_or(1.0, |sp| reweigh(sp, e.t, &|| view_ratio(e.wi, e.pdf_f)))
        };
        let kept_entries = entries
            .iter()
            .filter(|e| e.vis >> j & 1 == 1 && e.s <= kept);
        let mut l;
        if same_view {
            l = emission.map_or(Rgb::ZERO, |(c, _)| c);
            for e in kept_entries {
                l += e.c * reweight(e);
            }
        } else {
            l = emission.map_or(Rgb::ZERO, |(_, wm)| scene_g.emitted(&sv.si, wo_g) * wm);
            // The entries t ≥ 3 share x1's continuation direction: one BSDF evaluation.
            let mut continuation: Option<(Vec3, Rgb)> = None;
            for e in kept_entries {
                if e.continuation {
                    let c = continuation.get_or_insert((e.wi, Rgb::ZERO));
                    c.1 += e.r * reweight(e);
                } else {
                    l += sv.bsdf.f(wo_g, e.wi, TransportMode::Radiance) * e.r * reweight(e);
                }
            }
            if let Some((wi, r)) = continuation {
                l += sv.bsdf.f(wo_g, wi, TransportMode::Radiance) * r;
            }
        }
        if let Some(Regenerated {
            light: light_g,
            cam,
            cam_rays,
            ..
        }) = regenerated
        {
            // s > kept: f's camera subpath (reproduced in g) connected to g's light
            // subpath in g's scene, split at x1 like the entries.
            let mut sampler = ns.clone();
            for t in 2..=cam.len() {
                for s in (kept + 1).max(2)..=light_g.len() {
                    if s + t - 1 > max_segments {
                        continue;
                    }
                    let Some(conn) = connect_with(
                        scene_g,
                        self.bdpt,
                        light_g,
                        cam,
                        s,
                        t,
                        &mut sampler,
                        st,
                        &mut |r| !scene_g.occluded(r),
                    ) else {
                        continue;
                    };
                    let mut c = conn.contribution;
                    let wi = if t == 2 {
                        (light_g[s - 1].p - v.p).normalize_or_zero()
                    } else {
                        cam_rays[1].d.normalize()
                    };
                    if self.bdpt.light_tracing
                        && self.same_camera >> j & 1 == 0
                        && let Some(sp) = view_split(
                            scene_g,
                            self.bdpt,
                            light_g,
                            cam,
                            conn.sampled.as_ref(),
                            s,
                            t,
                        )
                    {
                        c.l *= reweigh(sp, t, &|| view_ratio(wi, sv.bsdf.pdf(sv.wo, wi)));
                    }
                    if same_view {
                        l += c.l;
                        continue;
                    }
                    let fv = sv.bsdf.f(sv.wo, wi, TransportMode::Radiance);
                    let fg = sv.bsdf.f(wo_g, wi, TransportMode::Radiance);
                    l += Rgb::new(
                        if fv.x != 0.0 {
                            c.l.x / fv.x * fg.x
                        } else {
                            0.0
                        },
                        if fv.y != 0.0 {
                            c.l.y / fv.y * fg.y
                        } else {
                            0.0
                        },
                        if fv.z != 0.0 {
                            c.l.z / fv.z * fg.z
                        } else {
                            0.0
                        },
                    );
                }
            }
        }
        l
    }

    /// p_f / p_g: the density with which f's camera sampled x1 (`v`, a camera vertex of
    /// f), over the density with which window frame `j`'s camera would sample it (both
    /// per unit area at x1). 1 when light tracing is off (no weight depends on it) or the
    /// cameras are the same.
    fn camera_density_ratio(&self, j: usize, v: &Vertex) -> f32 {
        if !self.bdpt.light_tracing || self.same_camera >> j & 1 == 1 {
            return 1.0;
        }
        let scene_g = &self.scenes[j];
        let eye = Vertex::camera(scene_g.camera.position(), Rgb::ONE, false);
        let p_g = eye.pdf(scene_g, None, v);
        #[cfg(debug_assertions)]
        {
            // x1's stored density is f's camera's, as computed here for g's.
            let scene_f = &self.scenes[self.jf];
            let eye_f = Vertex::camera(scene_f.camera.position(), Rgb::ONE, false);
            let p_f = eye_f.pdf(scene_f, None, v);
            debug_assert!(
                (p_f - v.pdf_fwd).abs() <= 1e-4 * p_f.abs().max(v.pdf_fwd.abs()),
                "x1's density from f's camera {p_f} is not its stored {}",
                v.pdf_fwd
            );
        }
        if p_g > 0.0 { v.pdf_fwd / p_g } else { 1.0 }
    }

    /// Sum of the t ≥ 2 strategies of `camera` and `light` in frame `j` (plain BDPT).
    pub(super) fn camera_strategies(
        &self,
        j: usize,
        light: &[Vertex],
        camera: &[Vertex],
        conn: &PixelSampler,
        stats: &mut Stats,
    ) -> Rgb {
        let scene = &self.scenes[j];
        let max_segments = self.bdpt.depth() as usize;
        let mut sampler = conn.clone();
        let mut l = Rgb::ZERO;
        for t in 2..=camera.len() {
            for s in 0..=self.bdpt.max_light_vertices(light.len()) {
                if s + t - 1 > max_segments {
                    continue;
                }
                if let Some(c) = connect(scene, self.bdpt, light, camera, s, t, &mut sampler, stats)
                {
                    l += c.l;
                }
            }
        }
        l
    }

    /// [`Generation::camera_strategies`] of a sample re-traced in frame `j` from f's raster
    /// position, whose camera subpath `camera` in g begins with f's vertices 0..=c and
    /// whose light subpath `light` begins with f's vertices 0..ℓ (c, ℓ: `reproduced`): the
    /// strategies (s, t) with t ≤ c + 1 and 1 ≤ ℓ, s ≤ ℓ are made of reproduced vertices
    /// only, and a strategy — contribution, MIS weight and the connection numbers it draws
    /// — depends on its own vertices only, so f's value is g's where its shadow ray is
    /// unoccluded in g (answered for the window in f). They are taken from f
    /// (`skip_connect` keeps the connection stream aligned); the others are evaluated in
    /// g. Same terms, same order: the sum equals the full evaluation's. Builds with debug
    /// assertions check that against the full evaluation.
    pub(super) fn prefix_strategies(
        &self,
        j: usize,
        light: &[Vertex],
        camera: &[Vertex],
        conn: &PixelSampler,
        reproduced: &Reproduced,
        stats: &mut Stats,
    ) -> Rgb {
        let scene = &self.scenes[j];
        let max_segments = self.bdpt.depth() as usize;
        let entries = reproduced.entries;
        let mut sampler = conn.clone();
        let mut l = Rgb::ZERO;
        // Cursor into `entries`, which are in (t, s) order.
        let mut next = 0usize;
        for t in 2..=camera.len() {
            for s in 0..=self.bdpt.max_light_vertices(light.len()) {
                if s + t - 1 > max_segments {
                    continue;
                }
                let from_f =
                    reproduced.light >= 1 && s <= reproduced.light && t <= reproduced.camera + 1;
                if !from_f {
                    if let Some(c) =
                        connect(scene, self.bdpt, light, camera, s, t, &mut sampler, stats)
                    {
                        l += c.l;
                    }
                    continue;
                }
                skip_connect(self.bdpt, light.len(), camera, s, t, &mut sampler);
                if (s, t) == (0, 2) {
                    if let Some((e, _)) = reproduced.emission {
                        l += e;
                    }
                    continue;
                }
                while entries.get(next).is_some_and(|e| (e.t, e.s) < (t, s)) {
                    next += 1;
                }
                if let Some(e) = entries.get(next).filter(|e| (e.t, e.s) == (t, s))
                    && e.vis >> j & 1 == 1
                {
                    l += e.c;
                }
            }
        }
        #[cfg(debug_assertions)]
        {
            let full = self.camera_strategies(j, light, camera, conn, &mut Stats::default());
            let tol = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6;
            debug_assert!(
                !(l.is_finite() && full.is_finite())
                    || (tol(l.x, full.x) && tol(l.y, full.y) && tol(l.z, full.z)),
                "prefix reuse {l:?} differs from the full evaluation {full:?} \
                 (camera prefix {}, light prefix {})",
                reproduced.camera,
                reproduced.light
            );
        }
        l
    }
}
