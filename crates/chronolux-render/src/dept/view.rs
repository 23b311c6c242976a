//! Eye rays reading the element solution.
//!
//! Per camera sample: emission seen directly or through specular chains is added as is;
//! delta (mirror, smooth glass) bounces are followed up to `max_specular_depth`; at the
//! first surface with a non-delta lobe the pixel gets
//! - **direct light** by light sampling (one light chosen power-proportionally, one point
//!   on it, ray-traced shadow; every light kind; no MIS because emission is never picked
//!   up after a non-delta bounce here), and
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
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::{Ray, spawn_ray, spawn_ray_to};
use chronolux_core::light::Light;
use chronolux_core::material;
use chronolux_core::math::Vec2;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::{FrameScene, SurfaceInteraction};
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

/// Radiance of a light towards a sampled point, emission textures included.
fn light_radiance(scene: &FrameScene, light: &Light, li: Rgb, bary: Vec2) -> Rgb {
    if let Light::Triangle { tri, instance, .. } = light {
        let g = &scene.geometry[tri.geometry as usize];
        let m = &scene.materials[g.material as usize];
        if m.emissive_texture.is_some() {
            let si = scene.surface_at(*tri, *instance, bary.x, bary.y, None);
            return material::emission_at(m, &scene.textures, &si.shading);
        }
    }
    li
}

/// Direct light at `si` towards `wo` by one light sample (no MIS), through the non-delta
/// lobes of `bsdf`.
pub fn direct_light_sample(
    scene: &FrameScene,
    si: &SurfaceInteraction,
    wo: chronolux_core::math::Vec3,
    bsdf: &chronolux_core::bsdf::Bsdf,
    u_light: f32,
    u_lp: Vec2,
    stats: &mut Stats,
) -> Rgb {
    let Some((li_idx, pmf, _)) = scene.light_sampler.sample(u_light) else {
        return Rgb::ZERO;
    };
    let light = &scene.lights[li_idx];
    let Some(ls) = light.sample_li(si.p, u_lp, scene.scene_radius) else {
        return Rgb::ZERO;
    };
    if pmf <= 0.0 || ls.pdf <= 0.0 {
        return Rgb::ZERO;
    }
    let f = bsdf.f(wo, ls.wi, TransportMode::Radiance) * ls.wi.dot(bsdf.frame.n).abs();
    if f == Rgb::ZERO {
        return Rgb::ZERO;
    }
    stats.shadow_rays += 1;
    if scene.occluded(&spawn_ray_to(si.p, si.ng, ls.p, ls.n)) {
        return Rgb::ZERO;
    }
    f * light_radiance(scene, light, ls.li, ls.bary) / (pmf * ls.pdf)
}

impl RadianceEstimator for DeptView<'_> {
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
        for _ in 0..=self.max_specular_depth {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&ray) else {
                if let Some(env) = scene.environment {
                    l += beta * env;
                }
                break;
            };
            let si = scene.interaction(&hit, &ray);
            let wo = -ray.d.normalize();
            l += beta * scene.emitted(&si, wo);
            let mat = &scene.materials[si.material as usize];
            let bsdf = material::bsdf_at(mat, &scene.textures, &si.shading);
            let u_light = sampler.next_1d();
            let u_lp = sampler.next_2d();
            let u_lobe = sampler.next_1d();
            let u_dir = sampler.next_2d();
            let diffuse = bsdf.has_non_delta();
            if diffuse {
                l += beta * direct_light_sample(scene, &si, wo, &bsdf, u_light, u_lp, stats);
            }
            let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
                break;
            };
            if !bs.is_delta {
                let loc = self.mesh.locate(hit.tri, hit.b1, hit.b2);
                let front = wo.dot(si.ng) >= 0.0;
                let e =
                    self.indirect.irradiance(&loc, front) + self.caustic.irradiance(&loc, front);
                l += beta * bs.weight * e * FRAC_1_PI;
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
