//! Eye rays over the SPT element solution: direct light per pixel, diffuse indirect light
//! from the elements, glossy and specular reflection by continuing the path.
//!
//! Per camera sample, at each surface:
//! - emission is added when the surface is seen directly or through delta (mirror,
//!   smooth glass) bounces only; after a glossy bounce the light reached is direct light
//!   already counted by next-event estimation at the previous vertex;
//! - **direct light** by next-event estimation through every non-delta lobe
//!   ([`crate::kernels::direct::next_event`], weight 1), as the `dept` family does;
//! - on a **rough** surface (no glossy specular lobe, [`Bsdf::is_glossy`] with α below
//!   `glossy_roughness`², and no delta specular lobe over a diffuse base), and on every
//!   surface once `max_glossy_depth` glossy vertices are passed, **indirect light** from
//!   the elements exactly as [`crate::kernels::elements::view`] reads it (`f cos · E/π`
//!   estimated with one BSDF sample), and the path ends (or continues through a delta
//!   lobe if one was sampled);
//! - on a **glossy** surface (and on a delta coating, mirror or glass over a diffuse
//!   base, which counts as a glossy vertex too) the BSDF is split into its diffuse base
//!   and its specular lobes (a [`Lobes`] copy with the other weights zeroed; the
//!   layering factor of the base is unchanged because it depends on `specular`,
//!   `specular_f0` and α only): the diffuse base reads the elements (`f_d cos · E/π`, one sample of the base alone), the
//!   specular lobes are sampled and the path continues with their weight — the glossy
//!   reflection of indirect light is traced, not read from the elements as if it were
//!   diffuse (what `dept`'s eye pass does). The two parts are estimates of `f_d` and
//!   `f − f_d`, so nothing is counted twice.
//!
//! The walk itself is the shared eye kernel, [`crate::kernels::eye`]; this module is its
//! reader for the SPT solution.

use crate::framework::integrator::RadianceEstimator;
use crate::kernels::direct::{NeeWeight, next_event};
use crate::kernels::elements::element_map::ElementMesh;
use crate::kernels::elements::reconstruct::ElementSolution;
use crate::kernels::eye::{EyePath, EyeReader, EyeVertex, Step, Uniforms, walk};
use chronolux_core::bsdf::microfacet::MIN_ALPHA;
use chronolux_core::bsdf::{Bsdf, Lobes, TransportMode};
use chronolux_core::color::Rgb;
use chronolux_core::geometry::Ray;
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
        let mut reader = SptReader {
            view: self,
            l: Rgb::ZERO,
            alpha_glossy: self.glossy_roughness * self.glossy_roughness,
        };
        let last = self.max_specular_depth + self.max_glossy_depth;
        walk(scene, camera_ray, last, &mut reader, sampler, stats);
        reader.l
    }
}

/// The SPT view's part of the eye walk (see the module documentation).
struct SptReader<'v> {
    view: &'v SptView<'v>,
    l: Rgb,
    /// GGX α below which a specular lobe is glossy.
    alpha_glossy: f32,
}

impl EyeReader for SptReader<'_> {
    fn escaped(&mut self, scene: &FrameScene, path: &EyePath, _: &mut Stats) {
        // Emission counts seen through delta bounces only.
        if let Some(l) = path.environment_seen(scene) {
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
        let (si, wo, bsdf) = (v.si, v.wo, v.bsdf);
        if path.scattered == 0 {
            self.l += beta * scene.emitted(si, wo);
        }
        let u_light = u.u1();
        let u_lp = u.u2();
        let u_lobe = u.u1();
        let u_dir = u.u2();
        let u_lobe2 = u.u1();
        let u_dir2 = u.u2();
        let non_delta = bsdf.has_non_delta();
        if non_delta {
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
        }
        let loc = || view.mesh.locate(v.hit.tri, v.hit.b1, v.hit.b2);
        let front = wo.dot(si.ng) >= 0.0;
        let elements =
            |loc: &_| view.indirect.irradiance(loc, front) + view.caustic.irradiance(loc, front);
        if non_delta && path.glossy < view.max_glossy_depth && split_here(bsdf, self.alpha_glossy) {
            let (diffuse, spec) = split(bsdf);
            if let Some(d) = diffuse
                && let Some(bs) = d.sample(wo, u_lobe2, u_dir2, TransportMode::Radiance)
            {
                self.l += beta * bs.weight * elements(&loc()) * FRAC_1_PI;
            }
            let Some(s) = spec else {
                return Step::Stop;
            };
            return match s.sample(wo, u_lobe, u_dir, TransportMode::Radiance) {
                Some(sample) => Step::Continue {
                    sample,
                    glossy: true,
                },
                None => Step::Stop,
            };
        }
        let Some(bs) = bsdf.sample(wo, u_lobe, u_dir, TransportMode::Radiance) else {
            return Step::Stop;
        };
        if !bs.is_delta {
            self.l += beta * bs.weight * elements(&loc()) * FRAC_1_PI;
            return Step::Stop;
        }
        Step::Continue {
            sample: bs,
            glossy: false,
        }
    }
}

/// Whether the view splits `b` into its diffuse base and its specular lobes (see the
/// module documentation): the specular lobes are glossy, or they are deltas over a
/// diffuse base (the base then reads the elements every sample, and the mirror image or
/// refraction is traced beside it, instead of one of the two chosen at random).
fn split_here(b: &Bsdf, alpha_glossy: f32) -> bool {
    let l = &b.lobes;
    b.is_glossy(alpha_glossy)
        || (l.alpha < MIN_ALPHA
            && l.alpha < alpha_glossy
            && l.diffuse != Rgb::ZERO
            && (l.specular_weight > 0.0 || l.metal_weight > 0.0 || l.transmission_weight > 0.0))
}

#[cfg(test)]
mod tests {
    use super::split_here;
    use crate::kernels::eye::glossy_cases;

    /// SPT splits glossy lobes below its bound and, as well, a delta coating over a
    /// diffuse base (not a bare mirror or smooth glass: no base to split off).
    #[test]
    fn split_here_glossy_lobes_and_delta_coatings() {
        for (name, b) in glossy_cases() {
            let split = [
                "smooth plastic",
                "glossy plastic",
                "glossy metal",
                "glossy glass",
            ]
            .contains(&name);
            assert_eq!(split_here(&b, 0.5 * 0.5), split, "{name}");
        }
        // No bound, no split: the delta coating's α is not below a zero bound either.
        for (name, b) in glossy_cases() {
            assert!(!split_here(&b, 0.0), "{name}");
        }
    }
}
