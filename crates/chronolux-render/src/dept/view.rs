//! Eye rays reading the element solution.
//!
//! Per camera sample: emission seen directly or through specular chains is added as is;
//! delta (mirror, smooth glass) bounces are followed up to `max_specular_depth`; at the
//! first surface with a non-delta lobe the pixel gets
//! - **direct light** by light sampling with the path tracer's kernel
//!   ([`crate::kernels::direct::next_event`]: one light chosen power-proportionally, one
//!   point on it, ray-traced shadow; every light kind; weight 1 instead of MIS because
//!   emission is never picked up after a non-delta bounce here), and
//! - **indirect light** from the elements: `∫ f cos · E/π dω` with `E` the interpolated
//!   irradiance of the photons that bounced at least once (indirect + caustic fields),
//!   i.e. incident radiance taken as uniform `E/π`; one BSDF sample estimates
//!   `∫ f cos dω` over the non-delta lobes (exactly ρ for a Lambertian surface, so no
//!   noise there). Glossy lobes therefore see indirect light as if it were uniform —
//!   the usual limit of element-based density estimation.
//!
//! If the BSDF sample picks a delta lobe instead, the chain continues through it (its
//! weight already divides by the lobe's selection probability, so the delta and the
//! non-delta parts add up without double counting).

use super::element_map::ElementMesh;
use super::reconstruct::ElementSolution;
use crate::integrator::RadianceEstimator;
use crate::kernels::direct::{NeeWeight, next_event};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::{Ray, spawn_ray};
use chronolux_core::material;
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
    pub max_specular_depth: u32,
}

impl DeptView<'_> {
    /// One camera sample as `[direct, indirect]` when `split` (everything in `[0]`
    /// otherwise, summed in the original order): direct = emission seen through delta
    /// bounces and the light sample at the first non-delta surface; indirect = the
    /// elements' term there (photons that bounced at least once, and caustic photons).
    fn trace(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
        split: bool,
    ) -> [Rgb; 2] {
        let mut l = [Rgb::ZERO; 2];
        let indirect = usize::from(split);
        let mut beta = Rgb::ONE;
        let mut ray = *camera_ray;
        for bounce in 0..=self.max_specular_depth {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&ray) else {
                if let Some(env) = scene.environment {
                    // The camera ray itself shows the backdrop.
                    l[0] += beta
                        * if bounce == 0 {
                            env.background
                        } else {
                            env.radiance(ray.d)
                        };
                }
                break;
            };
            let si = scene.interaction(&hit, &ray);
            let wo = -ray.d.normalize();
            l[0] += beta * scene.emitted(&si, wo);
            let mat = &scene.materials[si.material as usize];
            let bsdf = material::bsdf_at(mat, &scene.textures, &si.shading);
            let u_light = sampler.next_1d();
            let u_lp = sampler.next_2d();
            let u_lobe = sampler.next_1d();
            let u_dir = sampler.next_2d();
            let diffuse = bsdf.has_non_delta();
            if diffuse {
                l[0] += next_event(
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
            let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
                break;
            };
            if !bs.is_delta {
                let loc = self.mesh.locate(hit.tri, hit.b1, hit.b2);
                let front = wo.dot(si.ng) >= 0.0;
                let e =
                    self.indirect.irradiance(&loc, front) + self.caustic.irradiance(&loc, front);
                l[indirect] += beta * bs.weight * e * FRAC_1_PI;
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

impl RadianceEstimator for DeptView<'_> {
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
