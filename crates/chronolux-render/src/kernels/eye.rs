//! The eye walk through specular chains, shared by the eye passes that read a stored
//! solution at diffuse surfaces: the element view ([`super::elements::view`]: `dept*`,
//! `spacetime-dept`), the photon-map view ([`super::gather::view`]: `pm-ic`,
//! `ic-static-dynamic`, `ic-selective`) and the SPT view (`spt`).
//!
//! [`walk`] owns the path: the camera ray, one intersection per bounce (counted in
//! [`Stats::rays`]), the throughput `beta`, the next ray spawned from a sampled direction,
//! and what the path has passed ([`EyePath`]: bounces, delta and non-delta ones, glossy
//! vertices, the previous vertex and its pdf for MIS, the length travelled). A view, an
//! [`EyeReader`], says what a vertex contributes and whether the path goes on: it adds
//! emission, direct light and the stored solution, and either stops or hands back the
//! [`BsdfSample`] to continue with. Where a view follows a glossy lobe instead of reading
//! its solution, it asks [`Bsdf::is_glossy`], the one glossy test, with its own roughness
//! bound and glossy budget. Two views add a rule of their own on top, each a choice of
//! what to trace rather than of what is glossy: the photon-map view follows a glossy lobe
//! only where it carries the surface's light (not a plastic's coating), and the SPT view
//! also splits a delta coating off a diffuse base.

use chronolux_core::accel::Hit;
use chronolux_core::bsdf::{Bsdf, BsdfSample};
use chronolux_core::color::Rgb;
use chronolux_core::geometry::{Ray, spawn_ray};
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::{FrameScene, SurfaceInteraction};
use chronolux_core::stats::Stats;

/// Uniform numbers for a walk: a pixel's sampler when rendering, a plain generator for
/// passes that only look where paths go (the photon-map view's probe).
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

/// What an eye path has passed when it reaches a vertex (or leaves the scene).
#[derive(Clone, Copy, Debug)]
pub struct EyePath {
    /// Segments before the current one (0: the camera ray).
    pub bounce: u32,
    /// Throughput up to the current vertex.
    pub beta: Rgb,
    /// The ray that reached the current vertex.
    pub ray: Ray,
    /// The last bounce was a delta one (true for the camera ray): emission found now is
    /// not also found by a light sample at the previous vertex.
    pub specular_bounce: bool,
    /// Non-delta bounces so far.
    pub scattered: u32,
    /// Vertices a view continued through as glossy ([`Step::Continue`]'s `glossy`).
    pub glossy: u32,
    /// Solid-angle pdf of the last bounce (1 for the camera ray) and its vertex, for MIS
    /// weights of emission found now.
    pub prev_pdf: f32,
    pub prev_p: Vec3,
    /// Length of the path from the camera to the current vertex.
    pub length: f32,
}

impl EyePath {
    /// The environment's radiance along this escaped path's ray when it was reached through
    /// delta bounces only (no non-delta vertex before): the backdrop for the camera ray
    /// itself (as in `dept`'s view), the environment's radiance behind mirrors and glass,
    /// times the throughput. `None` without an environment or after a non-delta vertex.
    pub fn environment_seen(&self, scene: &FrameScene) -> Option<Rgb> {
        let env = scene.environment.as_ref().filter(|_| self.scattered == 0)?;
        Some(
            self.beta
                * if self.bounce == 0 {
                    env.seen_by_camera(self.ray.d)
                } else {
                    env.radiance(self.ray.d)
                },
        )
    }
}

/// A surface vertex of an eye path.
pub struct EyeVertex<'a> {
    pub hit: &'a Hit,
    pub si: &'a SurfaceInteraction,
    /// Direction back along the path (unit).
    pub wo: Vec3,
    pub bsdf: &'a Bsdf,
}

/// How a view goes on from a vertex.
pub enum Step {
    /// Stop here (the solution was read, or nothing can be sampled).
    Stop,
    /// Continue with this sample; `glossy`: the vertex counts as a glossy one.
    Continue { sample: BsdfSample, glossy: bool },
}

/// A view's part of an eye walk: what the path adds where it leaves the scene and at each
/// surface, and where it ends.
pub trait EyeReader {
    /// The path left the scene along `path.ray`.
    fn escaped(&mut self, scene: &FrameScene, path: &EyePath, stats: &mut Stats);

    /// The path reached `v`: add its light and say whether to go on. Draws the vertex's
    /// numbers from `u`.
    fn surface<U: Uniforms>(
        &mut self,
        scene: &FrameScene,
        path: &EyePath,
        v: &EyeVertex,
        u: &mut U,
        stats: &mut Stats,
    ) -> Step;
}

/// Walks an eye path from `camera_ray` through at most `last + 1` segments (bounces
/// `0..=last`), handing each event to `reader`. Ends where the reader stops, the path
/// leaves the scene or its throughput becomes zero.
pub fn walk<R: EyeReader, U: Uniforms>(
    scene: &FrameScene,
    camera_ray: &Ray,
    last: u32,
    reader: &mut R,
    u: &mut U,
    stats: &mut Stats,
) {
    let mut path = EyePath {
        bounce: 0,
        beta: Rgb::ONE,
        ray: *camera_ray,
        specular_bounce: true,
        scattered: 0,
        glossy: 0,
        prev_pdf: 1.0,
        prev_p: Vec3::ZERO,
        length: 0.0,
    };
    for bounce in 0..=last {
        path.bounce = bounce;
        stats.rays += 1;
        let Some(hit) = scene.intersect(&path.ray) else {
            reader.escaped(scene, &path, stats);
            break;
        };
        let si = scene.interaction(&hit, &path.ray);
        path.length += (si.p - path.ray.o).length();
        let wo = -path.ray.d.normalize();
        let bsdf = scene.bsdf(&si);
        let v = EyeVertex {
            hit: &hit,
            si: &si,
            wo,
            bsdf: &bsdf,
        };
        let Step::Continue { sample: bs, glossy } = reader.surface(scene, &path, &v, u, stats)
        else {
            break;
        };
        path.beta *= bs.weight;
        if path.beta == Rgb::ZERO {
            break;
        }
        path.specular_bounce = bs.is_delta;
        if !bs.is_delta {
            path.scattered += 1;
        }
        if glossy {
            path.glossy += 1;
        }
        path.prev_pdf = bs.pdf;
        path.prev_p = si.p;
        path.ray = spawn_ray(si.p, si.ng, bs.wi);
    }
}

/// BSDFs that the views' glossy rules tell apart, by name (for their tests).
#[cfg(test)]
pub(crate) fn glossy_cases() -> Vec<(&'static str, Bsdf)> {
    use chronolux_core::bsdf::Lobes;
    use chronolux_core::math::Frame;
    // (name, metallic, perceptual roughness, specular factor, transmission)
    let cases = [
        ("lambert", 0.0, 1.0, 0.0, 0.0),
        ("smooth plastic", 0.0, 0.0, 1.0, 0.0),
        ("glossy plastic", 0.0, 0.2, 1.0, 0.0),
        ("rough plastic", 0.0, 0.8, 1.0, 0.0),
        ("smooth metal", 1.0, 0.0, 1.0, 0.0),
        ("glossy metal", 1.0, 0.2, 1.0, 0.0),
        ("rough metal", 1.0, 0.8, 1.0, 0.0),
        ("smooth glass", 0.0, 0.0, 1.0, 1.0),
        ("glossy glass", 0.0, 0.2, 1.0, 1.0),
    ];
    cases
        .into_iter()
        .map(|(name, metallic, roughness, specular, transmission)| {
            let lobes = Lobes::gltf(
                Rgb::splat(0.8),
                metallic,
                roughness,
                1.5,
                specular,
                Rgb::ONE,
                transmission,
            );
            let bsdf = Bsdf {
                frame: Frame::from_normal(Vec3::Z),
                ng: Vec3::Z,
                lobes,
            };
            (name, bsdf)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::glossy_cases;

    /// The one glossy test: a rough specular, metal or transmission lobe, never a delta
    /// and never a BSDF without such a lobe; the bound is exclusive.
    #[test]
    fn is_glossy_is_a_rough_non_delta_specular_lobe() {
        for (name, b) in glossy_cases() {
            let rough = [
                "glossy plastic",
                "rough plastic",
                "glossy metal",
                "rough metal",
                "glossy glass",
            ]
            .contains(&name);
            assert_eq!(b.is_glossy(f32::INFINITY), rough, "{name}");
            if rough {
                assert!(
                    !b.is_glossy(b.lobes.alpha),
                    "{name}: the bound is exclusive"
                );
                assert!(b.is_glossy(b.lobes.alpha * 1.01), "{name}");
            }
        }
    }
}
