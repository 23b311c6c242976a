//! Unidirectional path tracing: next-event estimation with multiple importance sampling
//! (power heuristic), Russian roulette, Owen-scrambled Sobol samples per pixel.

use crate::framework::integrator::{
    Integrator, RadianceEstimator, RenderedFrame, render_camera_rays,
};
use crate::kernels::direct::{NeeWeight, bsdf_hit_weight, next_event};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::{Rgb, max_component};
use chronolux_core::geometry::{Ray, spawn_ray};
use chronolux_core::math::Vec3;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;

/// Path tracer settings.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PathSettings {
    /// Camera samples, path depth and seed ([`crate::framework::technique::CommonSettings`]). `spp`:
    /// Samples per pixel. Default 64. `max_depth`: Longest path in segments from the
    /// camera, Mitsuba's `max_depth` convention: 1 = emitters seen directly, 2 = direct
    /// lighting. `None` = unlimited (Russian roulette ends paths). Default `None`. `seed`:
    /// Seed of all sample streams. Default 0.
    #[serde(flatten)]
    pub common: crate::framework::technique::CommonSettings,
    /// Path depth (segments) from which Russian roulette may end a path. Default 5
    /// (Mitsuba's `rr_depth`).
    pub rr_depth: u32,
}

impl Default for PathSettings {
    fn default() -> Self {
        PathSettings {
            common: crate::framework::technique::CommonSettings {
                spp: 64,
                max_depth: None,
                seed: 0,
            },
            rr_depth: 5,
        }
    }
}

/// Hard cap on path length when `max_depth` is unlimited, so a pathological scene (e.g. a
/// perfect mirror box) cannot loop forever; Russian roulette ends paths long before it.
const DEPTH_CAP: u32 = 1024;

#[derive(Clone, Debug, Default)]
pub struct PathTracer {
    pub settings: PathSettings,
}

impl PathTracer {
    pub fn new(settings: PathSettings) -> Self {
        PathTracer { settings }
    }
}

impl PathTracer {
    /// One path sample. Every contribution goes to `l[0]` unless `split`, in which case
    /// direct light goes to `l[0]` and indirect light to `l[1]` ([`LightSplit`]'s
    /// convention: direct = emission reached from the camera through delta bounces only,
    /// plus light arriving straight from an emitter at the first non-delta vertex, by
    /// its light sample or by its BSDF-sampled ray, MIS-weighted). Without `split` the
    /// contributions are summed in the same order as before there was a split.
    ///
    /// [`LightSplit`]: crate::framework::integrator::LightSplit
    fn trace(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
        split: bool,
    ) -> [Rgb; 2] {
        let max_depth = self
            .settings
            .common
            .max_depth
            .unwrap_or(DEPTH_CAP)
            .min(DEPTH_CAP);
        let mut l = [Rgb::ZERO; 2];
        // Non-delta scattering vertices so far (bounces sampled from a non-delta lobe).
        let mut scattered = 0u32;
        // Where emission found now, and the light sample of the current vertex, go:
        // direct (0) with no non-delta vertex before, or with one that was the last bounce.
        let slot = |scattered: u32, specular_bounce: bool| -> usize {
            usize::from(split && !(scattered == 0 || (scattered == 1 && !specular_bounce)))
        };
        let mut beta = Rgb::ONE;
        let mut ray = *camera_ray;
        // Segments of the current ray from the camera (the camera ray is segment 1).
        let mut depth = 1u32;
        let mut specular_bounce = true;
        let mut prev_pdf = 1.0f32;
        let mut prev_p = Vec3::ZERO;
        // Product of η² over refractions, undone for Russian roulette (pbrt's etaScale).
        let mut eta_scale = 1.0f32;
        loop {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&ray) else {
                // Escaped: environment light.
                if let (Some(env), Some(ei)) = (&scene.environment, scene.environment_light) {
                    if depth == 1 {
                        // The camera ray itself: the backdrop (no other strategy sees it).
                        l[0] += beta * env.seen_by_camera(ray.d);
                    } else {
                        let w = if specular_bounce {
                            1.0
                        } else {
                            bsdf_hit_weight(scene, ei, prev_p, prev_p + ray.d, prev_pdf)
                        };
                        l[slot(scattered, specular_bounce)] += beta * env.radiance(ray.d) * w;
                    }
                }
                break;
            };
            let si = scene.interaction(&hit, &ray);
            let wo = -ray.d.normalize();

            // Emission seen along the path, MIS-weighted against light sampling.
            let le = scene.emitted(&si, wo);
            if le != Rgb::ZERO {
                let w = if specular_bounce {
                    1.0
                } else {
                    match scene.light_of(si.tri) {
                        Some(li) => bsdf_hit_weight(scene, li, prev_p, si.p, prev_pdf),
                        None => 1.0,
                    }
                };
                l[slot(scattered, specular_bounce)] += beta * le * w;
            }
            if depth >= max_depth {
                break;
            }

            let bsdf = scene.bsdf(&si);

            // Next-event estimation. Three dimensions are consumed whether or not they are
            // used, so each bounce's dimensions stay aligned across samples.
            let u_light = sampler.next_1d();
            let u_lp = sampler.next_2d();
            if bsdf.has_non_delta() {
                // The light sample of this vertex: direct at the first non-delta vertex.
                l[usize::from(split && scattered > 0)] += next_event(
                    scene,
                    &si,
                    wo,
                    &bsdf,
                    beta,
                    u_light,
                    u_lp,
                    NeeWeight::Mis,
                    stats,
                );
            }

            // Continue the path by sampling the BSDF.
            let u_lobe = sampler.next_1d();
            let u_dir = sampler.next_2d();
            let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
                break;
            };
            if bs.weight == Rgb::ZERO {
                break;
            }
            beta *= bs.weight;
            specular_bounce = bs.is_delta;
            if !bs.is_delta {
                scattered += 1;
            }
            prev_pdf = bs.pdf;
            prev_p = si.p;
            if bs.is_transmission {
                eta_scale *= bs.eta * bs.eta;
            }
            ray = spawn_ray(si.p, si.ng, bs.wi);
            depth += 1;

            // Possibly terminate the path with Russian roulette.
            if depth > self.settings.rr_depth {
                let q = (max_component(beta) * eta_scale).min(0.95);
                if sampler.next_1d() >= q {
                    break;
                }
                beta /= q;
            }
        }
        l
    }
}

impl RadianceEstimator for PathTracer {
    fn li(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
    ) -> Rgb {
        self.trace(scene, camera_ray, sampler, stats, false)[0]
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
        self.trace(scene, camera_ray, sampler, stats, true)
    }
}

impl Integrator for PathTracer {
    fn render(
        &self,
        scene: &FrameScene,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        render_camera_rays(
            self,
            scene,
            frame,
            self.settings.common.spp,
            self.settings.common.seed,
            progress,
        )
    }

    fn separates_light(&self) -> bool {
        true
    }

    fn batch(&self, spp: u32, round: u32, half: u32) -> Option<Box<dyn Integrator + Send>> {
        let mut settings = self.settings.clone();
        settings.common.spp = spp;
        settings.common.seed =
            crate::framework::sequence::batch_seed(settings.common.seed, round, half);
        Some(Box::new(PathTracer::new(settings)))
    }
}

impl crate::framework::shutter::ShutterIntegrator for PathTracer {
    const NAME: &'static str = "path";
    fn spp(&self) -> u32 {
        self.settings.common.spp
    }
    fn render_shutter(
        &self,
        scenes: &[FrameScene],
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let s = &self.settings;
        crate::framework::shutter::render_time_sampled(
            self,
            scenes,
            frame,
            s.common.spp,
            s.common.seed,
            progress,
        )
    }
}
