//! Eye rays reading the element solution.
//!
//! Per camera sample: emission seen directly or through specular chains is added as is;
//! delta (mirror, smooth glass) bounces are followed; at a **diffuse** surface (only a
//! Lambertian lobe besides deltas) the pixel gets
//! - **direct light** by light sampling with the path tracer's kernel
//!   ([`crate::kernels::direct::next_event`]: one light chosen power-proportionally, one
//!   point on it, ray-traced shadow; every light kind; weight 1 instead of MIS because
//!   emission is never picked up after a non-delta bounce of a diffuse surface here; in a
//!   scene with a light at infinity, a sky, the BSDF sample below is also traced and the
//!   emission it finds, sky or emitter, is MIS-weighted against the light sample: light
//!   samples alone are noisy for a sky, and with the MIS the eye pass on sky-lit models
//!   has 5–8× less relMSE at 16 samples per pixel, BENCHMARKS.md, "Issue 17: the
//!   default"), and
//! - **indirect light** from the elements: `∫ f cos · E/π dω` with `E` the interpolated
//!   irradiance of the photons that bounced at least once (indirect + caustic fields),
//!   i.e. incident radiance taken as uniform `E/π`; one BSDF sample estimates
//!   `∫ f cos dω` (exactly ρ for a Lambertian surface, so no noise there).
//!
//! At a **glossy** surface ([`Bsdf::is_glossy`](chronolux_core::bsdf::Bsdf::is_glossy) with no roughness bound: a rough
//! specular, metal or transmission lobe, not a delta) incident light is far from uniform — read as `E/π`, a rough-metal
//! sphere comes out as a flat grey ball — so the path continues there as in the path
//! tracer: next-event estimation with MIS weights, one BSDF sample of all its lobes,
//! emission found by that ray weighted the other way, and at the next diffuse surface the
//! reading above (its light sample and its elements). At most `max_glossy` glossy
//! vertices are passed per path; at the last one allowed (and at the end of the chain)
//! the elements are read as uniform again. `max_glossy = 0` is the flat reading
//! everywhere.
//!
//! If the BSDF sample picks a delta lobe instead, the chain continues through it (its
//! weight already divides by the lobe's selection probability, so the delta and the
//! non-delta parts add up without double counting). At most `max_specular_depth` bounces
//! (delta and glossy) are followed.
//!
//! ## Path depth
//! With `max_depth` = D (segments from the camera, as the path tracer's and Mitsuba's
//! `max_depth`), a vertex reached after e segments adds emission only if e ≤ D, its light
//! sample and BSDF-sampled emission only if e + 1 ≤ D, and the elements only if e + 2 ≤ D
//! (the shortest photon path to it, light → surface → here, has two segments). The
//! elements hold photons of at most D − 2 scattering events
//! ([`super::element_map::max_photon_bounces`]), which is exact for a surface seen
//! straight from the camera (e = 1); seen through e − 1 delta or glossy bounces it lets
//! paths of up to D + e − 1 segments in, so a depth-limited render is exact except in
//! mirrors, glass and glossy reflections, where it keeps up to e − 1 more bounces of
//! light than the limit (elements per photon depth would be needed for those).
//!
//! The walk itself (rays, throughput, the chain's state) is the shared eye kernel,
//! [`crate::kernels::eye`]; this module is its reader for the elements.

use super::element_map::ElementMesh;
use super::reconstruct::ElementSolution;
use crate::framework::integrator::RadianceEstimator;
use crate::kernels::direct::{NeeWeight, bsdf_hit_weight, next_event};
use crate::kernels::eye::{EyePath, EyeReader, EyeVertex, Step, Uniforms, walk};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::{Bounds3, Ray, spawn_ray};
use chronolux_core::math::Vec3;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;
use std::f32::consts::FRAC_1_PI;

/// Radiance estimator over an element solution.
pub struct DeptView<'a> {
    pub mesh: &'a ElementMesh,
    /// Irradiance of photons with at least one non-specular bounce.
    pub indirect: &'a ElementSolution,
    /// Irradiance of caustic photons (light → specular⁺ → surface).
    pub caustic: &'a ElementSolution,
    /// Longest chain of delta and glossy bounces followed.
    pub max_specular_depth: u32,
    /// Glossy vertices a path passes before the elements are read as uniform there
    /// (0: the flat reading at every non-delta surface).
    pub max_glossy: u32,
    /// Longest path in segments from the camera (Mitsuba's `max_depth`); `None`:
    /// unlimited. See the module documentation, "Path depth".
    pub max_depth: Option<u32>,
}

impl DeptView<'_> {
    /// One camera sample, split with [`crate::framework::integrator::LightSplit`]'s convention: direct = emission
    /// seen through delta bounces, and the light arriving straight from an emitter at the
    /// first non-delta surface (its light sample; at a glossy one also the emission its
    /// BSDF ray hits, MIS-weighted); indirect = everything else (the elements' term, and
    /// the light sample of a diffuse surface seen through a glossy one).
    ///
    /// Returned as three parts `[direct, light-sampled indirect, elements]`: the first
    /// two are the per-pixel light (independent of the element solution, so reusable
    /// over frames where the animation leaves the path unchanged: [`super::reuse`]), the
    /// third the elements' term. `reach`, when given, grows by every vertex of the path
    /// and becomes [`Reach::Unbounded`] when a ray leaves the scene (its light then
    /// depends on everything the environment's directions pass).
    pub fn trace_parts(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
        mut reach: Option<&mut Reach>,
    ) -> [Rgb; 3] {
        if let Some(r) = reach.as_deref_mut() {
            r.origin(camera_ray.o);
        }
        if self.max_depth == Some(0) {
            return [Rgb::ZERO; 3];
        }
        let last = match self.max_depth {
            Some(d) => self.max_specular_depth.min(d.saturating_sub(1)),
            None => self.max_specular_depth,
        };
        let mut reader = DeptReader {
            view: self,
            l: [Rgb::ZERO; 3],
            reach,
            // A sky (light at infinity): light samples alone are noisy for it at diffuse
            // surfaces, so direct light there is MIS of a light sample and the BSDF sample.
            sky: scene.environment_light.is_some(),
            last,
        };
        walk(scene, camera_ray, last, &mut reader, sampler, stats);
        reader.l
    }

    /// Segments a path may still have after the vertex reached by `bounce + 1` of them.
    fn room(&self, bounce: u32) -> u32 {
        self.max_depth
            .map_or(u32::MAX, |d| d.saturating_sub(bounce + 1))
    }
}

/// The element view's part of the eye walk (see the module documentation).
struct DeptReader<'v, 'r> {
    view: &'v DeptView<'v>,
    /// `[direct, light-sampled indirect, elements]`, as [`DeptView::trace_parts`].
    l: [Rgb; 3],
    reach: Option<&'r mut Reach>,
    sky: bool,
    last: u32,
}

/// The part of [`DeptReader::l`] that emission found at `path`'s vertex goes to: direct
/// when seen through delta bounces only, or straight after the first non-delta one.
fn slot(path: &EyePath) -> usize {
    usize::from(!(path.scattered == 0 || (path.scattered == 1 && !path.specular_bounce)))
}

/// The slot of the elements' term.
const ELEMENTS: usize = 2;

impl EyeReader for DeptReader<'_, '_> {
    fn escaped(&mut self, scene: &FrameScene, path: &EyePath, _: &mut Stats) {
        if let Some(r) = self.reach.as_deref_mut() {
            *r = Reach::Unbounded;
        }
        let Some(env) = &scene.environment else {
            return;
        };
        let (beta, ray) = (path.beta, path.ray);
        if path.bounce == 0 {
            // The camera ray itself shows the backdrop.
            self.l[0] += beta * env.seen_by_camera(ray.d);
        } else {
            let w = match (path.specular_bounce, scene.environment_light) {
                (false, Some(ei)) => {
                    bsdf_hit_weight(scene, ei, path.prev_p, path.prev_p + ray.d, path.prev_pdf)
                }
                _ => 1.0,
            };
            self.l[slot(path)] += beta * env.radiance(ray.d) * w;
        }
    }

    fn surface<U: Uniforms>(
        &mut self,
        scene: &FrameScene,
        path: &EyePath,
        v: &EyeVertex,
        u: &mut U,
        stats: &mut Stats,
    ) -> Step {
        let (view, sky, beta, bounce) = (self.view, self.sky, path.beta, path.bounce);
        let (si, wo, bsdf) = (v.si, v.wo, v.bsdf);
        let l = &mut self.l;
        if let Some(r) = self.reach.as_deref_mut() {
            r.vertex(si.p);
        }
        let le = scene.emitted(si, wo);
        if le != Rgb::ZERO {
            // After a glossy vertex, MIS-weighted against its light sample.
            let w = match (path.specular_bounce, scene.light_of(si.tri)) {
                (false, Some(li)) => bsdf_hit_weight(scene, li, path.prev_p, si.p, path.prev_pdf),
                _ => 1.0,
            };
            l[slot(path)] += beta * le * w;
        }
        let u_light = u.u1();
        let u_lp = u.u2();
        let u_lobe = u.u1();
        let u_dir = u.u2();
        // Continue through this glossy surface, or read the elements here.
        let glossy =
            bsdf.is_glossy(f32::INFINITY) && path.scattered < view.max_glossy && bounce < self.last;
        if bsdf.has_non_delta() && view.room(bounce) >= 1 {
            l[usize::from(path.scattered > 0)] += next_event(
                scene,
                si,
                wo,
                bsdf,
                beta,
                u_light,
                u_lp,
                if glossy || sky {
                    NeeWeight::Mis
                } else {
                    NeeWeight::LightOnly
                },
                stats,
            );
        }
        let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
            return Step::Stop;
        };
        if bs.is_delta || glossy {
            return Step::Continue {
                sample: bs,
                glossy: false,
            };
        }
        // The BSDF-sampled emission is one more segment, the elements' paths at least
        // two.
        if sky && view.room(bounce) >= 1 {
            // The other half of MIS: the BSDF-sampled ray's emission (sky or emitter),
            // weighted against the light sample above.
            stats.rays += 1;
            let r = spawn_ray(si.p, si.ng, bs.wi);
            let s = usize::from(path.scattered > 0);
            match scene.intersect(&r) {
                None => {
                    if let Some(rr) = self.reach.as_deref_mut() {
                        *rr = Reach::Unbounded;
                    }
                    if let (Some(env), Some(ei)) = (&scene.environment, scene.environment_light) {
                        l[s] += beta
                            * bs.weight
                            * env.radiance(r.d)
                            * bsdf_hit_weight(scene, ei, si.p, si.p + r.d, bs.pdf);
                    }
                }
                Some(h2) => {
                    let si2 = scene.interaction(&h2, &r);
                    let le = scene.emitted(&si2, -r.d.normalize());
                    if le != Rgb::ZERO
                        && let Some(li) = scene.light_of(si2.tri)
                    {
                        if let Some(rr) = self.reach.as_deref_mut() {
                            rr.vertex(si2.p);
                        }
                        l[s] +=
                            beta * bs.weight * le * bsdf_hit_weight(scene, li, si.p, si2.p, bs.pdf);
                    }
                }
            }
        }
        if view.room(bounce) >= 2 {
            let hit = v.hit;
            let loc = view.mesh.locate(hit.tri, hit.b1, hit.b2);
            let front = wo.dot(si.ng) >= 0.0;
            let e = view.indirect.irradiance(&loc, front) + view.caustic.irradiance(&loc, front);
            l[ELEMENTS] += beta * bs.weight * e * FRAC_1_PI;
        }
        Step::Stop
    }
}

impl RadianceEstimator for DeptView<'_> {
    fn li(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
    ) -> Rgb {
        let [d, p, e] = self.trace_parts(scene, camera_ray, sampler, stats, None);
        d + p + e
    }

    fn separates_light(&self) -> bool {
        true
    }

    fn li_split(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
    ) -> [Rgb; 2] {
        let [d, p, e] = self.trace_parts(scene, camera_ray, sampler, stats, None);
        [d, p + e]
    }
}

/// Where the light of a pixel's paths comes from: bounds of their ray origins and of
/// their vertices, or unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    Bounded { origins: Bounds3, vertices: Bounds3 },
    Unbounded,
}

impl Default for Reach {
    fn default() -> Self {
        Reach::Bounded {
            origins: Bounds3::EMPTY,
            vertices: Bounds3::EMPTY,
        }
    }
}

impl Reach {
    /// Adds a camera ray's origin.
    pub fn origin(&mut self, p: Vec3) {
        if let Reach::Bounded { origins, .. } = self {
            origins.grow(p);
        }
    }

    /// Both reaches: bounded when both are, by the union of their boxes.
    pub fn union(&self, o: &Reach) -> Reach {
        match (self, o) {
            (
                Reach::Bounded { origins, vertices },
                Reach::Bounded {
                    origins: o2,
                    vertices: v2,
                },
            ) => Reach::Bounded {
                origins: origins.union(o2),
                vertices: vertices.union(v2),
            },
            _ => Reach::Unbounded,
        }
    }

    /// Adds a path vertex.
    pub fn vertex(&mut self, p: Vec3) {
        if let Reach::Bounded { vertices, .. } = self {
            vertices.grow(p);
        }
    }
}
