//! Eye rays over the SPT element solution: direct light per pixel, diffuse indirect light
//! from the elements, glossy and specular reflection by continuing the path.
//!
//! Per camera sample, at each surface:
//! - emission is added when the surface is seen directly or through delta (mirror,
//!   smooth glass) bounces only; after a glossy bounce the light reached is direct light
//!   already counted by next-event estimation at the previous vertex;
//! - **direct light** by next-event estimation through every non-delta lobe
//!   ([`crate::kernels::direct::next_event`], weight 1), as the `dept` family does;
//! - on a **rough** surface (no non-delta specular lobe, or one of perceptual roughness ≥
//!   `glossy_roughness`), and on every surface once `max_glossy_depth` glossy bounces are
//!   used, **indirect light** from the elements exactly as [`crate::kernels::elements::view`] reads it
//!   (`f cos · E/π` estimated with one BSDF sample), and the path ends (or continues
//!   through a delta lobe if one was sampled);
//! - on a **glossy** surface the BSDF is split into its diffuse base and its specular
//!   lobes (a [`Lobes`] copy with the other weights zeroed; the layering factor of the
//!   base is unchanged because it depends on `specular`, `specular_f0` and α only): the
//!   diffuse base reads the elements (`f_d cos · E/π`, one sample of the base alone), the
//!   specular lobes are sampled and the path continues with their weight — the glossy
//!   reflection of indirect light is traced, not read from the elements as if it were
//!   diffuse (what `dept`'s eye pass does). The two parts are estimates of `f_d` and
//!   `f − f_d`, so nothing is counted twice.

use crate::framework::integrator::RadianceEstimator;
use crate::kernels::direct::{NeeWeight, next_event};
use crate::kernels::elements::element_map::ElementMesh;
use crate::kernels::elements::reconstruct::ElementSolution;
use chronolux_core::bsdf::{Bsdf, Lobes, TransportMode};
use chronolux_core::color::Rgb;
use chronolux_core::geometry::{Ray, spawn_ray};
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;
use std::f32::consts::FRAC_1_PI;

/// Radiance estimator over an SPT solution.
pub struct SptView<'a> {
    pub mesh: &'a ElementMesh,
    /// Irradiance of photons with at least one non-specular bounce.
    pub indirect: &'a ElementSolution,
    /// Irradiance of caustic photons (light → specular⁺ → surface).
    pub caustic: &'a ElementSolution,
    pub max_specular_depth: u32,
    pub max_glossy_depth: u32,
    /// Perceptual roughness below which a non-delta specular lobe is glossy.
    pub glossy_roughness: f32,
}

/// The diffuse base and the specular lobes of `b` as two BSDFs (`None` for an absent part).
fn split(b: &Bsdf) -> (Option<Bsdf>, Option<Bsdf>) {
    let l = &b.lobes;
    let diffuse = (l.diffuse != Rgb::ZERO).then(|| Bsdf {
        lobes: Lobes {
            specular_weight: 0.0,
            metal_weight: 0.0,
            transmission_weight: 0.0,
            ..l.clone()
        },
        ..b.clone()
    });
    let spec = (l.specular_weight > 0.0 || l.metal_weight > 0.0 || l.transmission_weight > 0.0)
        .then(|| Bsdf {
            lobes: Lobes {
                diffuse: Rgb::ZERO,
                ..l.clone()
            },
            ..b.clone()
        });
    (diffuse, spec)
}

impl RadianceEstimator for SptView<'_> {
    fn li(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
    ) -> Rgb {
        let mut l = Rgb::ZERO;
        let mut beta = Rgb::ONE;
        let mut ray = *camera_ray;
        let mut emission_counts = true;
        let mut glossy = 0u32;
        let alpha_glossy = self.glossy_roughness * self.glossy_roughness;
        for bounce in 0..=(self.max_specular_depth + self.max_glossy_depth) {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&ray) else {
                if emission_counts && let Some(env) = &scene.environment {
                    // The camera ray itself shows the backdrop (as in `dept`'s view).
                    l += beta
                        * if bounce == 0 {
                            env.seen_by_camera(ray.d)
                        } else {
                            env.radiance(ray.d)
                        };
                }
                break;
            };
            let si = scene.interaction(&hit, &ray);
            let wo = -ray.d.normalize();
            if emission_counts {
                l += beta * scene.emitted(&si, wo);
            }
            let bsdf = scene.bsdf(&si);
            let u_light = sampler.next_1d();
            let u_lp = sampler.next_2d();
            let u_lobe = sampler.next_1d();
            let u_dir = sampler.next_2d();
            let u_lobe2 = sampler.next_1d();
            let u_dir2 = sampler.next_2d();
            let non_delta = bsdf.has_non_delta();
            if non_delta {
                l += next_event(
                    scene,
                    &si,
                    wo,
                    &bsdf,
                    beta,
                    u_light,
                    u_lp,
                    NeeWeight::LightOnly,
                    stats,
                );
            }
            let loc = || self.mesh.locate(hit.tri, hit.b1, hit.b2);
            let front = wo.dot(si.ng) >= 0.0;
            let elements = |loc: &_| {
                self.indirect.irradiance(loc, front) + self.caustic.irradiance(loc, front)
            };
            let is_glossy = non_delta
                && bsdf.lobes.alpha < alpha_glossy
                && glossy < self.max_glossy_depth
                && (bsdf.lobes.specular_weight > 0.0
                    || bsdf.lobes.metal_weight > 0.0
                    || bsdf.lobes.transmission_weight > 0.0);
            if is_glossy {
                let (diffuse, spec) = split(&bsdf);
                if let Some(d) = diffuse
                    && let Some(bs) = d.sample(wo, u_lobe2, u_dir2, TransportMode::Radiance)
                {
                    l += beta * bs.weight * elements(&loc()) * FRAC_1_PI;
                }
                let Some(s) = spec else { break };
                let Some(bs) = s.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
                    break;
                };
                beta *= bs.weight;
                if beta == Rgb::ZERO {
                    break;
                }
                glossy += 1;
                emission_counts = bs.is_delta && emission_counts;
                ray = spawn_ray(si.p, si.ng, bs.wi);
                continue;
            }
            let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
                break;
            };
            if !bs.is_delta {
                l += beta * bs.weight * elements(&loc()) * FRAC_1_PI;
                break;
            }
            beta *= bs.weight;
            if beta == Rgb::ZERO {
                break;
            }
            ray = spawn_ray(si.p, si.ng, bs.wi);
        }
        l
    }
}
