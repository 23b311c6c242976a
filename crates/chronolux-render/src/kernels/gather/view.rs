//! Eye paths of the photon-mapping techniques (see the parent module doc, step 2): one
//! walk serves the render (radiance) and the probe pass (where the cache point of a pixel
//! is), so both stop at the same kind of vertex.

use super::PmIcSettings;
use super::photon_map::PhotonMap;
use crate::framework::integrator::RadianceEstimator;
use crate::kernels::direct::{NeeWeight, next_event};
use chronolux_core::bsdf::microfacet::MIN_ALPHA;
use chronolux_core::bsdf::{Bsdf, TransportMode};
use chronolux_core::color::{Rgb, max_component};
use chronolux_core::geometry::{Ray, spawn_ray};
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;
use std::f32::consts::FRAC_1_PI;

/// A point where indirect diffuse irradiance is needed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheQuery {
    pub p: Vec3,
    /// Geometric normal turned to the side the eye path arrived from.
    pub n: Vec3,
    /// Width of a pixel's footprint there (world units, along the eye path).
    pub footprint: f32,
    /// Instance the point lies on.
    pub instance: u32,
}

/// Where the indirect diffuse irradiance at an eye vertex comes from.
pub trait IndirectSource: Sync {
    fn irradiance(&self, scene: &FrameScene, q: &CacheQuery) -> Rgb;
}

/// No indirect light (the probe pass never asks).
pub struct NoIndirect;

impl IndirectSource for NoIndirect {
    fn irradiance(&self, _: &FrameScene, _: &CacheQuery) -> Rgb {
        Rgb::ZERO
    }
}

/// Uniform numbers for a walk.
pub trait Uniforms {
    fn u1(&mut self) -> f32;
    fn u2(&mut self) -> Vec2;
}

impl Uniforms for PixelSampler {
    fn u1(&mut self) -> f32 {
        self.next_1d()
    }
    fn u2(&mut self) -> Vec2 {
        self.next_2d()
    }
}

impl Uniforms for Pcg32 {
    fn u1(&mut self) -> f32 {
        self.next_f32()
    }
    fn u2(&mut self) -> Vec2 {
        Vec2::new(self.next_f32(), self.next_f32())
    }
}

/// Whether a BSDF is traced as glossy (see the module doc).
pub fn is_glossy(b: &Bsdf, glossy_alpha: f32) -> bool {
    let l = &b.lobes;
    let specular = l.metal_weight > 0.0 || l.transmission_weight > 0.0 || l.specular_weight > 0.0;
    specular
        && l.alpha >= MIN_ALPHA
        && l.alpha < glossy_alpha
        && (l.metal_weight + l.transmission_weight >= 0.5 || max_component(l.diffuse) == 0.0)
}

/// The eye estimator.
pub struct EyeView<'a, S: IndirectSource> {
    pub settings: &'a PmIcSettings,
    pub caustic: &'a PhotonMap,
    pub caustic_radius: f32,
    pub source: &'a S,
    /// Pixel footprint at the camera (orthographic width) and its growth per unit of path
    /// length (perspective angle).
    pub footprint0: f32,
    pub footprint_per_unit: f32,
}

impl<'a, S: IndirectSource> EyeView<'a, S> {
    pub fn new(
        settings: &'a PmIcSettings,
        scene: &FrameScene,
        caustic: &'a PhotonMap,
        source: &'a S,
    ) -> Self {
        let cam = &scene.camera;
        let c = Vec2::new(cam.width as f32 * 0.5, cam.height as f32 * 0.5);
        let a = cam.generate_ray(c);
        let b = cam.generate_ray(c + Vec2::new(1.0, 0.0));
        EyeView {
            settings,
            caustic,
            caustic_radius: super::world_radius(scene, &settings.caustic),
            source,
            footprint0: (b.o - a.o).length(),
            footprint_per_unit: (b.d.normalize() - a.d.normalize()).length(),
        }
    }

    /// The cache point a pixel's eye path reaches (numbers from `u`).
    pub fn probe(&self, scene: &FrameScene, ray: &Ray, u: &mut Pcg32) -> Option<CacheQuery> {
        let mut stats = Stats::default();
        let mut q = None;
        self.walk(scene, ray, u, &mut stats, Some(&mut q));
        q
    }

    /// One eye path. With `probe`, stops at the first cache point and stores it there
    /// (no light is estimated); otherwise returns the radiance.
    fn walk<U: Uniforms>(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        u: &mut U,
        stats: &mut Stats,
        mut probe: Option<&mut Option<CacheQuery>>,
    ) -> Rgb {
        let s = self.settings;
        let render = probe.is_none();
        let mut l = Rgb::ZERO;
        let mut beta = Rgb::ONE;
        let mut ray = *camera_ray;
        let mut path_len = 0.0f32;
        let mut after_non_delta = false;
        let mut glossy = 0u32;
        for bounce in 0..=s.max_specular_depth + s.max_glossy_depth {
            stats.rays += 1;
            let Some(hit) = scene.intersect(&ray) else {
                if render
                    && !after_non_delta
                    && let Some(env) = &scene.environment
                {
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
            path_len += (si.p - ray.o).length();
            let wo = -ray.d.normalize();
            if render && !after_non_delta {
                l += beta * scene.emitted(&si, wo);
            }
            let bsdf = scene.bsdf(&si);
            let u_light = u.u1();
            let u_lp = u.u2();
            let u_lobe = u.u1();
            let u_dir = u.u2();
            let wi = if bsdf.has_non_delta() {
                let n = if wo.dot(si.ng) >= 0.0 { si.ng } else { -si.ng };
                let glossy_here = glossy < s.max_glossy_depth && is_glossy(&bsdf, s.glossy_alpha);
                if !glossy_here && let Some(slot) = probe.as_deref_mut() {
                    *slot = Some(CacheQuery {
                        p: si.p,
                        n,
                        footprint: self.footprint0 + path_len * self.footprint_per_unit,
                        instance: si.instance,
                    });
                    break;
                }
                if render {
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
                    l += beta
                        * self.caustic.radiance(
                            si.p,
                            n,
                            wo,
                            &bsdf,
                            &s.caustic,
                            self.caustic_radius,
                        );
                }
                let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
                    break;
                };
                if glossy_here {
                    if !bs.is_delta {
                        after_non_delta = true;
                        glossy += 1;
                    }
                } else if !bs.is_delta {
                    let q = CacheQuery {
                        p: si.p,
                        n,
                        footprint: self.footprint0 + path_len * self.footprint_per_unit,
                        instance: si.instance,
                    };
                    l += beta * bs.weight * self.source.irradiance(scene, &q) * FRAC_1_PI;
                    break;
                }
                beta *= bs.weight;
                bs.wi
            } else {
                let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
                    break;
                };
                beta *= bs.weight;
                bs.wi
            };
            if beta == Rgb::ZERO {
                break;
            }
            ray = spawn_ray(si.p, si.ng, wi);
        }
        l
    }
}

impl<S: IndirectSource> RadianceEstimator for EyeView<'_, S> {
    fn li(
        &self,
        scene: &FrameScene,
        camera_ray: &Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
    ) -> Rgb {
        self.walk(scene, camera_ray, sampler, stats, None)
    }
}
