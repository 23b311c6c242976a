//! Lights of a frame: punctual lights (KHR_lights_punctual), emissive triangles as area
//! lights, an environment (uniform or a sky-to-ground gradient, see [`Environment`]); and
//! power-proportional light selection.
//!
//! Units: see the crate doc. Spot falloff follows the KHR_lights_punctual reference: a
//! smooth step in cos θ between the outer and inner cone, squared.

use crate::accel::TriRef;
use crate::color::{Rgb, luminance};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::distrib::Distribution1D;
use crate::sampling::warps;
use std::f32::consts::PI;
use std::sync::Arc;

pub mod emit;
pub mod envmap;
pub use envmap::EnvMap;
pub mod spherical;
use spherical::{sample_spherical_triangle, sampled_solid_angle};

/// One light of a frame (world space).
#[derive(Clone, Debug)]
pub enum Light {
    Point {
        p: Vec3,
        intensity: Rgb,
    },
    Spot {
        p: Vec3,
        axis: Vec3,
        intensity: Rgb,
        cos_inner: f32,
        cos_outer: f32,
    },
    /// Light travelling along `dir` (unit) with irradiance `irradiance` on a perpendicular
    /// surface.
    Directional {
        dir: Vec3,
        irradiance: Rgb,
    },
    /// An emissive triangle; `radiance` is the emissive factor (texture evaluated at the
    /// sampled point by the caller through the material when present).
    Triangle {
        p0: Vec3,
        e1: Vec3,
        e2: Vec3,
        n: Vec3,
        area: f32,
        radiance: Rgb,
        two_sided: bool,
        tri: TriRef,
        instance: u32,
    },
    Environment {
        env: Environment,
    },
}

/// Radiance arriving from infinity: a gradient linear in the vertical (y, glTF's up)
/// component of the direction, from `nadir` (looking straight down) to `zenith` (straight
/// up); `zenith == nadir` is a uniform environment. `background` is what a camera ray that
/// leaves the scene without hitting anything shows (a studio backdrop: reflections,
/// refractions and lighting see the gradient); equal to the gradient's mean for a uniform
/// environment.
///
/// Linear in w.y, the gradient's mean over the sphere is exactly (zenith + nadir)/2, so the
/// power and the emitted flux of [`Light::Environment`] keep their uniform-sphere form with
/// that mean; uniform sphere sampling stays unbiased (the ratio of the brightest to the
/// mean direction is at most 2).
///
/// With `map` (an equirectangular image, [`EnvMap`]) the map replaces the gradient: its
/// radiance, its mean, and importance sampling by its luminance ([`Environment::sample_dir`],
/// [`Environment::pdf_dir`], which every technique reaches through [`Light::sample_li`],
/// [`Light::pdf_li`], [`Light::sample_le`] and [`Light::pdf_le`]). Camera rays see the map
/// when `map_visible`, else `background`.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub zenith: Rgb,
    pub nadir: Rgb,
    pub background: Rgb,
    pub map: Option<Arc<EnvMap>>,
    /// Whether camera rays that escape see the map (only with `map`).
    pub map_visible: bool,
}

impl Environment {
    /// The same radiance in every direction, also as background.
    pub fn uniform(radiance: Rgb) -> Self {
        Environment {
            zenith: radiance,
            nadir: radiance,
            background: radiance,
            map: None,
            map_visible: false,
        }
    }

    /// A gradient from `nadir` to `zenith` with a constant `background`.
    pub fn gradient(zenith: Rgb, nadir: Rgb, background: Rgb) -> Self {
        Environment {
            zenith,
            nadir,
            background,
            map: None,
            map_visible: false,
        }
    }

    /// An environment map; camera rays see it when `visible`, else black.
    pub fn from_map(map: EnvMap, visible: bool) -> Self {
        let mean = map.mean();
        Environment {
            zenith: mean,
            nadir: mean,
            background: Rgb::ZERO,
            map: Some(Arc::new(map)),
            map_visible: visible,
        }
    }

    /// Whether every direction, and the background, have the same radiance.
    pub fn is_uniform(&self) -> bool {
        self.map.is_none() && self.zenith == self.nadir && self.background == self.zenith
    }

    /// Radiance arriving from direction `w` (towards the environment; need not be unit).
    pub fn radiance(&self, w: Vec3) -> Rgb {
        if let Some(m) = &self.map {
            return m.eval(w);
        }
        if self.zenith == self.nadir {
            return self.zenith;
        }
        let l = w.length();
        let up = if l > 0.0 {
            (w.y / l).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let t = 0.5 * (1.0 + up);
        self.nadir * (1.0 - t) + self.zenith * t
    }

    /// What a camera ray leaving the scene along `w` (straight or through specular
    /// bounces only) shows: the map where it is visible, else `background`.
    pub fn seen_by_camera(&self, w: Vec3) -> Rgb {
        match &self.map {
            Some(m) if self.map_visible => m.eval(w),
            _ => self.background,
        }
    }

    /// Mean radiance over the sphere of directions.
    pub fn mean(&self) -> Rgb {
        match &self.map {
            Some(m) => m.mean(),
            None => (self.zenith + self.nadir) * 0.5,
        }
    }

    /// Samples a direction towards the environment: by the map's luminance with a map,
    /// uniformly over the sphere otherwise. (direction, solid-angle density).
    pub fn sample_dir(&self, u: Vec2) -> Option<(Vec3, f32)> {
        match &self.map {
            Some(m) => m.sample(u),
            None => Some((warps::sample_uniform_sphere(u), warps::UNIFORM_SPHERE_PDF)),
        }
    }

    /// Solid-angle density with which [`Environment::sample_dir`] produces `w`.
    pub fn pdf_dir(&self, w: Vec3) -> f32 {
        match &self.map {
            Some(m) => m.pdf(w),
            None => warps::UNIFORM_SPHERE_PDF,
        }
    }
}

/// A sampled light direction from a reference point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the reference point towards the light.
    pub wi: Vec3,
    /// Point on the light (for shadow rays); at infinity lights it is far along `wi`.
    pub p: Vec3,
    /// Normal at `p` (zero for punctual and infinite lights).
    pub n: Vec3,
    /// Incident radiance (or intensity/d² for punctual lights), before the texture factor
    /// for triangles (see [`Light::Triangle`]).
    pub li: Rgb,
    /// Solid-angle density of `wi` (1 for delta lights).
    pub pdf: f32,
    pub is_delta: bool,
    /// For triangle lights, the barycentrics of `p`.
    pub bary: Vec2,
}

impl Light {
    /// Total emitted power (W-equivalent, luminance of the colour), used for light
    /// selection. Infinite lights report the flux entering the scene's bounding sphere of
    /// radius `scene_radius`: E·πR² for a directional light, 4πR²·πL̄ for an environment of
    /// mean radiance L̄ (for a uniform one every point of the sphere receives πL through its
    /// inward hemisphere; the gradient's w.y term integrates to zero over the sphere).
    pub fn power(&self, scene_radius: f32) -> f32 {
        match self {
            Light::Point { intensity, .. } => 4.0 * PI * luminance(*intensity),
            Light::Spot {
                intensity,
                cos_inner,
                cos_outer,
                ..
            } => spot_solid_angle(*cos_inner, *cos_outer) * luminance(*intensity),
            Light::Directional { irradiance, .. } => {
                PI * scene_radius * scene_radius * luminance(*irradiance)
            }
            Light::Triangle {
                area,
                radiance,
                two_sided,
                ..
            } => PI * area * luminance(*radiance) * if *two_sided { 2.0 } else { 1.0 },
            Light::Environment { env } => {
                4.0 * PI * PI * scene_radius * scene_radius * luminance(env.mean())
            }
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point { .. } | Light::Spot { .. } | Light::Directional { .. }
        )
    }

    /// Samples incident illumination at `p` (surface point, normal used only to pick
    /// environment samples). `u` uniform in the unit square. `scene_radius` for infinite lights.
    ///
    /// Triangle lights are sampled uniformly in the solid angle they subtend at `p` when
    /// that lies in [`spherical::MIN_SPHERICAL_SAMPLE_AREA`,
    /// `spherical::MAX_SPHERICAL_SAMPLE_AREA`], uniformly by area otherwise; [`Light::pdf_li`]
    /// makes the same choice from the same (p, triangle).
    pub fn sample_li(&self, p: Vec3, u: Vec2, scene_radius: f32) -> Option<LightSample> {
        match self {
            Light::Point { p: lp, intensity } => {
                let d = *lp - p;
                let d2 = d.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let wi = d / d2.sqrt();
                Some(LightSample {
                    wi,
                    p: *lp,
                    n: Vec3::ZERO,
                    li: *intensity / d2,
                    pdf: 1.0,
                    is_delta: true,
                    bary: Vec2::ZERO,
                })
            }
            Light::Spot {
                p: lp,
                axis,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                let d = *lp - p;
                let d2 = d.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let wi = d / d2.sqrt();
                let f = spot_falloff((-wi).dot(*axis), *cos_inner, *cos_outer);
                if f == 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    p: *lp,
                    n: Vec3::ZERO,
                    li: *intensity * f / d2,
                    pdf: 1.0,
                    is_delta: true,
                    bary: Vec2::ZERO,
                })
            }
            Light::Directional { dir, irradiance } => {
                let wi = -*dir;
                Some(LightSample {
                    wi,
                    p: p + wi * (4.0 * scene_radius.max(1e-3)),
                    n: Vec3::ZERO,
                    li: *irradiance,
                    pdf: 1.0,
                    is_delta: true,
                    bary: Vec2::ZERO,
                })
            }
            Light::Triangle {
                p0,
                e1,
                e2,
                n,
                area,
                radiance,
                two_sided,
                ..
            } => {
                let sampled = sampled_solid_angle(p, *p0, *e1, *e2, *n, *area);
                let spherical = sampled.is_some();
                let omega = sampled.unwrap_or(0.0);
                if spherical && !*two_sided && (p - *p0).dot(*n) <= 0.0 {
                    return None;
                }
                let (b1, b2) = if spherical {
                    sample_spherical_triangle(p, *p0, *e1, *e2, [u.x, u.y])?
                } else {
                    warps::sample_uniform_triangle(u)
                };
                let lp = *p0 + *e1 * b1 + *e2 * b2;
                let d = lp - p;
                let d2 = d.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let wi = d / d2.sqrt();
                let pdf = if spherical {
                    1.0 / omega
                } else {
                    let cos_l = -wi.dot(*n);
                    if cos_l <= 0.0 && !*two_sided {
                        return None;
                    }
                    let cos_l = cos_l.abs();
                    if cos_l == 0.0 {
                        return None;
                    }
                    d2 / (cos_l * *area)
                };
                Some(LightSample {
                    wi,
                    p: lp,
                    n: *n,
                    li: *radiance,
                    pdf,
                    is_delta: false,
                    bary: Vec2::new(b1, b2),
                })
            }
            Light::Environment { env } => {
                let (wi, pdf) = env.sample_dir(u)?;
                Some(LightSample {
                    wi,
                    p: p + wi * (4.0 * scene_radius.max(1e-3)),
                    n: Vec3::ZERO,
                    li: env.radiance(wi),
                    pdf,
                    is_delta: false,
                    bary: Vec2::ZERO,
                })
            }
        }
    }

    /// Solid-angle density with which [`Light::sample_li`] from `p` produces a direction
    /// that reaches this light at `lp` (normal side irrelevant for two-sided lights).
    pub fn pdf_li(&self, p: Vec3, lp: Vec3) -> f32 {
        match self {
            Light::Triangle {
                p0,
                e1,
                e2,
                n,
                area,
                two_sided,
                ..
            } => {
                if let Some(omega) = sampled_solid_angle(p, *p0, *e1, *e2, *n, *area) {
                    return if !*two_sided && (p - *p0).dot(*n) <= 0.0 {
                        0.0
                    } else {
                        1.0 / omega
                    };
                }
                let d = lp - p;
                let d2 = d.length_squared();
                let cos_l = -d.dot(*n) / d2.sqrt();
                if (cos_l <= 0.0 && !*two_sided) || cos_l == 0.0 {
                    return 0.0;
                }
                d2 / (cos_l.abs() * *area)
            }
            Light::Environment { env } => env.pdf_dir(lp - p),
            _ => 0.0,
        }
    }

    /// Radiance leaving a triangle light at its side facing `w` (direction from the light
    /// towards the viewer); zero on the back of a one-sided light.
    pub fn triangle_radiance(n: Vec3, two_sided: bool, radiance: Rgb, w: Vec3) -> Rgb {
        if two_sided || n.dot(w) > 0.0 {
            radiance
        } else {
            Rgb::ZERO
        }
    }

    /// Frame with the light's axis along +Z (for spot lights; used by light tracing later).
    pub fn spot_frame(axis: Vec3) -> Frame {
        Frame::from_normal(axis)
    }
}

/// KHR_lights_punctual spot attenuation: linear in cos between outer and inner, squared.
pub fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_theta <= cos_outer {
        return 0.0;
    }
    if cos_theta >= cos_inner || cos_inner <= cos_outer {
        return 1.0;
    }
    let s = (cos_theta - cos_outer) / (cos_inner - cos_outer);
    s * s
}

/// ∫ spot_falloff dω over the sphere: with s = (c − cos_outer)/(cos_inner − cos_outer)
/// the falloff is 1 for c ≥ cos_inner and s² between the cones, so the integral is
/// 2π[(1 − cos_inner) + ∫ s² dc] = 2π[(1 − cos_inner) + (cos_inner − cos_outer)/3]
/// (a hard cone 2π(1 − cos_outer) when the cones coincide or are inverted).
pub fn spot_solid_angle(cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_inner <= cos_outer {
        return 2.0 * PI * (1.0 - cos_outer);
    }
    2.0 * PI * ((1.0 - cos_inner) + (cos_inner - cos_outer) / 3.0)
}

/// Chooses lights in proportion to their power.
#[derive(Clone, Debug, Default)]
pub struct LightSampler {
    distrib: Option<Distribution1D>,
}

impl LightSampler {
    pub fn new(lights: &[Light], scene_radius: f32) -> Self {
        let powers: Vec<f32> = lights
            .iter()
            .map(|l| l.power(scene_radius).max(0.0))
            .collect();
        LightSampler {
            distrib: Distribution1D::new(&powers),
        }
    }

    /// (light index, probability).
    pub fn sample(&self, u: f32) -> Option<(usize, f32, f32)> {
        self.distrib.as_ref().map(|d| d.sample(u))
    }

    /// Probability of choosing light `i`.
    pub fn pmf(&self, i: usize) -> f32 {
        self.distrib.as_ref().map_or(0.0, |d| d.pmf(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    /// The irradiance at a point from a triangle light, estimated by sample_li, equals the
    /// closed form for a small triangle far away (E ≈ L·A·cos_l·cos_r/d²) within MC error.
    #[test]
    fn triangle_light_irradiance_matches_area_integral() {
        let l = Light::Triangle {
            p0: Vec3::new(-0.5, 10.0, -0.5),
            e1: Vec3::new(1.0, 0.0, 0.0),
            e2: Vec3::new(0.0, 0.0, 1.0),
            n: Vec3::new(0.0, -1.0, 0.0),
            area: 0.5,
            radiance: Rgb::ONE,
            two_sided: false,
            tri: TriRef {
                geometry: 0,
                triangle: 0,
            },
            instance: 0,
        };
        let mut r = Pcg32::new(1, 1);
        let n = 20_000;
        let mut e = 0.0f64;
        for _ in 0..n {
            let s = l
                .sample_li(Vec3::ZERO, Vec2::new(r.next_f32(), r.next_f32()), 1.0)
                .unwrap();
            assert!((s.pdf - l.pdf_li(Vec3::ZERO, s.p)).abs() <= 1e-3 * s.pdf);
            e += (s.li.x * s.wi.y / s.pdf) as f64;
        }
        e /= n as f64;
        // Closed form ≈ A/d² (cosines ≈ 1 at d=10 over a 1-unit triangle; error ~ (0.5/10)² ≈ 0.3%).
        assert!((e - 0.5 / 100.0).abs() < 0.01 * 0.005, "E = {e}");
    }

    #[test]
    fn spot_falloff_is_monotone_and_bounded() {
        let (ci, co) = (0.9f32, 0.7f32);
        assert_eq!(spot_falloff(0.95, ci, co), 1.0);
        assert_eq!(spot_falloff(0.6, ci, co), 0.0);
        assert!((spot_falloff(0.8, ci, co) - 0.25).abs() < 1e-6);
    }
}
