//! Eye paths of the photon-mapping techniques (see the parent module doc, step 2): one
//! walk serves the render (radiance) and the probe pass (where the cache point of a pixel
//! is), so both stop at the same kind of vertex. The walk is the shared eye kernel,
//! [`crate::kernels::eye`]; this module is its reader for the photon maps and the cache.

use super::PmIcSettings;
use super::photon_map::PhotonMap;
use crate::framework::integrator::RadianceEstimator;
use crate::kernels::direct::{NeeWeight, next_event};
pub use crate::kernels::eye::Uniforms;
use crate::kernels::eye::{EyePath, EyeReader, EyeVertex, Step, walk};
use chronolux_core::bsdf::{Bsdf, TransportMode};
use chronolux_core::color::{Rgb, max_component};
use chronolux_core::geometry::Ray;
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

/// Whether a BSDF is traced as glossy (see the module doc): a glossy lobe below
/// `glossy_alpha` ([`Bsdf::is_glossy`]) that carries most of the surface's light (metal or
/// transmitting, or with no diffuse base), so a plastic's glossy coating is read from the
/// cache with its base.
pub fn follows_glossy(b: &Bsdf, glossy_alpha: f32) -> bool {
    let l = &b.lobes;
    b.is_glossy(glossy_alpha)
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
        probe: Option<&mut Option<CacheQuery>>,
    ) -> Rgb {
        let s = self.settings;
        let mut reader = GatherReader {
            view: self,
            l: Rgb::ZERO,
            probe,
        };
        let last = s.max_specular_depth + s.max_glossy_depth;
        walk(scene, camera_ray, last, &mut reader, u, stats);
        reader.l
    }
}

/// The photon-map view's part of the eye walk (see the module doc).
struct GatherReader<'v, 'q, S: IndirectSource> {
    view: &'v EyeView<'v, S>,
    l: Rgb,
    /// Where the probe pass stores the cache point; `None`: rendering.
    probe: Option<&'q mut Option<CacheQuery>>,
}

impl<S: IndirectSource> EyeReader for GatherReader<'_, '_, S> {
    fn escaped(&mut self, scene: &FrameScene, path: &EyePath, _: &mut Stats) {
        if self.probe.is_none()
            && let Some(l) = path.environment_seen(scene)
        {
            self.l += l;
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
        let (view, beta) = (self.view, path.beta);
        let s = view.settings;
        let (si, wo, bsdf) = (v.si, v.wo, v.bsdf);
        let render = self.probe.is_none();
        // Emission is not picked up after a non-delta bounce (next-event estimation there
        // has weight 1).
        if render && path.scattered == 0 {
            self.l += beta * scene.emitted(si, wo);
        }
        let u_light = u.u1();
        let u_lp = u.u2();
        let u_lobe = u.u1();
        let u_dir = u.u2();
        if !bsdf.has_non_delta() {
            return match bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) {
                Some(sample) => Step::Continue {
                    sample,
                    glossy: false,
                },
                None => Step::Stop,
            };
        }
        let n = if wo.dot(si.ng) >= 0.0 { si.ng } else { -si.ng };
        let query = || CacheQuery {
            p: si.p,
            n,
            footprint: view.footprint0 + path.length * view.footprint_per_unit,
            instance: si.instance,
        };
        let glossy_here =
            path.scattered < s.max_glossy_depth && follows_glossy(bsdf, s.glossy_alpha);
        if !glossy_here && let Some(slot) = self.probe.as_deref_mut() {
            *slot = Some(query());
            return Step::Stop;
        }
        if render {
            self.l += next_event(
                scene,
                si,
                wo,
                bsdf,
                beta,
                u_light,
                u_lp,
                NeeWeight::LightOnly,
                stats,
            );
            self.l += beta
                * view
                    .caustic
                    .radiance(si.p, n, wo, bsdf, &s.caustic, view.caustic_radius);
        }
        let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
            return Step::Stop;
        };
        if !glossy_here && !bs.is_delta {
            self.l += beta * bs.weight * view.source.irradiance(scene, &query()) * FRAC_1_PI;
            return Step::Stop;
        }
        Step::Continue {
            sample: bs,
            glossy: false,
        }
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

#[cfg(test)]
mod tests {
    use super::follows_glossy;
    use crate::kernels::eye::glossy_cases;

    /// The photon-map view follows a glossy lobe below `glossy_alpha` only where it
    /// carries the surface's light: a glossy plastic's coating is read with its base.
    #[test]
    fn follows_glossy_metal_and_glass_not_plastic() {
        for (name, b) in glossy_cases() {
            let follows = ["glossy metal", "glossy glass"].contains(&name);
            assert_eq!(follows_glossy(&b, 0.1), follows, "{name}");
        }
    }
}
