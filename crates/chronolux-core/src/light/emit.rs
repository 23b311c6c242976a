//! Emission sampling (`sample_le` / `pdf_le`): rays leaving lights, for photon tracing,
//! light tracing and bidirectional methods.

use super::{Light, spot_falloff};
use crate::color::Rgb;
use crate::geometry::{Ray, offset_ray_origin};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warps;

/// A ray leaving a light.
#[derive(Clone, Copy, Debug)]
pub struct LeSample {
    /// Origin on the light (already offset off emissive surfaces) and unit direction.
    pub ray: Ray,
    /// Surface normal at the origin, on the emitting side (zero for punctual and infinite lights).
    pub n: Vec3,
    /// Emitted radiance (area and infinite lights) or intensity (point and spot lights)
    /// along the ray; irradiance for directional lights.
    pub le: Rgb,
    /// Density of the origin: w.r.t. area (area lights, and the disk of infinite lights);
    /// 1 for a delta position (point/spot).
    pub pdf_pos: f32,
    /// Density of the direction w.r.t. solid angle; 1 for a delta direction (directional).
    pub pdf_dir: f32,
}

impl LeSample {
    /// Flux carried by a particle started from this sample, before dividing by the
    /// probability of choosing the light: le·|cos θ| / (pdf_pos · pdf_dir).
    pub fn flux_weight(&self) -> Rgb {
        let cos = if self.n == Vec3::ZERO {
            1.0
        } else {
            self.n.dot(self.ray.d).abs()
        };
        self.le * (cos / (self.pdf_pos * self.pdf_dir))
    }
}

impl Light {
    /// Samples a ray leaving the light. `center`, `radius` bound the scene (for
    /// directional and environment lights, whose rays start on a disk facing the scene).
    pub fn sample_le(
        &self,
        u_pos: Vec2,
        u_dir: Vec2,
        center: Vec3,
        radius: f32,
    ) -> Option<LeSample> {
        match self {
            Light::Point { p, intensity } => {
                let d = warps::sample_uniform_sphere(u_dir);
                Some(LeSample {
                    ray: Ray::new(*p, d),
                    n: Vec3::ZERO,
                    le: *intensity,
                    pdf_pos: 1.0,
                    pdf_dir: warps::UNIFORM_SPHERE_PDF,
                })
            }
            Light::Spot {
                p,
                axis,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                let local = warps::sample_uniform_cone(u_dir, *cos_outer);
                let d = Frame::from_normal(*axis).from_local(local);
                let f = spot_falloff(local.z, *cos_inner, *cos_outer);
                if f == 0.0 {
                    return None;
                }
                Some(LeSample {
                    ray: Ray::new(*p, d),
                    n: Vec3::ZERO,
                    le: *intensity * f,
                    pdf_pos: 1.0,
                    pdf_dir: warps::uniform_cone_pdf(*cos_outer),
                })
            }
            Light::Directional { dir, irradiance } => {
                let r = radius.max(1e-4);
                let disk = warps::sample_concentric_disk(u_pos) * r;
                let f = Frame::from_normal(*dir);
                let o = center - *dir * r + f.s * disk.x + f.t * disk.y;
                Some(LeSample {
                    ray: Ray::new(o, *dir),
                    n: Vec3::ZERO,
                    le: *irradiance,
                    pdf_pos: 1.0 / (std::f32::consts::PI * r * r),
                    pdf_dir: 1.0,
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
                if *area <= 0.0 {
                    return None;
                }
                let (b1, b2) = warps::sample_uniform_triangle(u_pos);
                let p = *p0 + *e1 * b1 + *e2 * b2;
                // Two-sided lights pick a side with probability 1/2, reusing u_dir.x.
                let (side, u) = if *two_sided {
                    if u_dir.x < 0.5 {
                        (*n, Vec2::new(u_dir.x * 2.0, u_dir.y))
                    } else {
                        (-*n, Vec2::new(u_dir.x * 2.0 - 1.0, u_dir.y))
                    }
                } else {
                    (*n, u_dir)
                };
                let local = warps::sample_cosine_hemisphere(u);
                let d = Frame::from_normal(side).from_local(local);
                let mut pdf_dir = warps::cosine_hemisphere_pdf(local.z);
                if *two_sided {
                    pdf_dir *= 0.5;
                }
                if pdf_dir == 0.0 {
                    return None;
                }
                Some(LeSample {
                    ray: Ray::new(offset_ray_origin(p, side, d), d),
                    n: side,
                    le: *radiance,
                    pdf_pos: 1.0 / *area,
                    pdf_dir,
                })
            }
            Light::Environment { env } => {
                // Direction towards the environment w, the ray travels along −w from a disk
                // perpendicular to w outside the scene's bounding sphere.
                let (w, pdf_dir) = env.sample_dir(u_dir)?;
                let r = radius.max(1e-4);
                let disk = warps::sample_concentric_disk(u_pos) * r;
                let f = Frame::from_normal(w);
                let o = center + w * r + f.s * disk.x + f.t * disk.y;
                Some(LeSample {
                    ray: Ray::new(o, -w),
                    n: Vec3::ZERO,
                    le: env.radiance(w),
                    pdf_pos: 1.0 / (std::f32::consts::PI * r * r),
                    pdf_dir,
                })
            }
        }
    }

    /// Densities (pdf_pos, pdf_dir) with which [`Light::sample_le`] produces a ray leaving
    /// from `n` (the light's normal there, zero otherwise) in direction `d`. For delta
    /// distributions the delta part is reported as 1, as in `sample_le`.
    pub fn pdf_le(&self, d: Vec3, n: Vec3, radius: f32) -> (f32, f32) {
        match self {
            Light::Point { .. } => (1.0, warps::UNIFORM_SPHERE_PDF),
            Light::Spot {
                axis, cos_outer, ..
            } => {
                if d.dot(*axis) >= *cos_outer {
                    (1.0, warps::uniform_cone_pdf(*cos_outer))
                } else {
                    (1.0, 0.0)
                }
            }
            Light::Directional { .. } => {
                let r = radius.max(1e-4);
                (1.0 / (std::f32::consts::PI * r * r), 1.0)
            }
            Light::Triangle {
                n: ln,
                area,
                two_sided,
                ..
            } => {
                let nn = if n == Vec3::ZERO { *ln } else { n };
                let c = nn.dot(d);
                let cos = if *two_sided { c.abs() } else { c };
                if cos <= 0.0 || *area <= 0.0 {
                    return (0.0, 0.0);
                }
                let mut pdf_dir = warps::cosine_hemisphere_pdf(cos);
                if *two_sided {
                    pdf_dir *= 0.5;
                }
                (1.0 / *area, pdf_dir)
            }
            Light::Environment { env } => {
                // `d` is the ray's direction, −w.
                let r = radius.max(1e-4);
                (1.0 / (std::f32::consts::PI * r * r), env.pdf_dir(-d))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::TriRef;
    use crate::sampling::rng::Pcg32;

    /// The mean flux weight of emitted rays is the light's power (for infinite lights, the
    /// flux through the disk, πr²·E or 4π·πr²·L... as in `power`): E[le·cos/(pdf_pos·pdf_dir)] = Φ.
    #[test]
    fn emitted_flux_equals_power() {
        let lights = vec![
            Light::Point {
                p: Vec3::ZERO,
                intensity: Rgb::splat(2.0),
            },
            Light::Spot {
                p: Vec3::ZERO,
                axis: Vec3::Y,
                intensity: Rgb::ONE,
                cos_inner: 0.9,
                cos_outer: 0.7,
            },
            Light::Directional {
                dir: -Vec3::Y,
                irradiance: Rgb::splat(3.0),
            },
            Light::Triangle {
                p0: Vec3::ZERO,
                e1: Vec3::X,
                e2: Vec3::Z,
                n: -Vec3::Y,
                area: 0.5,
                radiance: Rgb::ONE,
                two_sided: true,
                tri: TriRef {
                    geometry: 0,
                    triangle: 0,
                },
                instance: 0,
            },
            Light::Environment {
                env: crate::light::Environment::uniform(Rgb::splat(0.5)),
            },
            Light::Environment {
                env: crate::light::Environment::gradient(
                    Rgb::splat(1.0),
                    Rgb::splat(0.2),
                    Rgb::ZERO,
                ),
            },
            // An environment map with a bright patch: emission samples it by luminance.
            Light::Environment {
                env: crate::light::Environment::from_map(
                    crate::light::EnvMap::new(
                        8,
                        4,
                        (0..32)
                            .map(|i| {
                                if i == 10 {
                                    Rgb::new(20.0, 15.0, 10.0)
                                } else {
                                    Rgb::splat(0.1 + (i % 3) as f32 * 0.2)
                                }
                            })
                            .collect(),
                        2.0,
                        25.0,
                    )
                    .unwrap(),
                    true,
                ),
            },
        ];
        let mut r = Pcg32::new(5, 6);
        for l in &lights {
            let n = 200_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let s = l.sample_le(
                    Vec2::new(r.next_f32(), r.next_f32()),
                    Vec2::new(r.next_f32(), r.next_f32()),
                    Vec3::ZERO,
                    2.0,
                );
                if let Some(s) = s {
                    let (pp, pd) = l.pdf_le(s.ray.d, s.n, 2.0);
                    assert!(
                        (pp - s.pdf_pos).abs() <= 1e-4 * pp
                            && (pd - s.pdf_dir).abs() <= 1e-3 * pd.max(1e-3),
                        "{l:?}"
                    );
                    sum += crate::color::luminance(s.flux_weight()) as f64;
                }
            }
            let phi = sum / n as f64;
            let want = l.power(2.0) as f64;
            // 1% relative: the estimator's relative standard error is below 0.3% at 2e5
            // samples for these smooth lights (the spot's falloff weight is the roughest).
            assert!(
                (phi - want).abs() < 0.01 * want,
                "{l:?}: flux {phi} vs power {want}"
            );
        }
    }
}
