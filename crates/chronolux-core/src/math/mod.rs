//! Vector math (glam re-exported), shading frames and robust floating-point helpers.

pub use glam::{Affine3A, Mat3, Mat4, Quat, UVec2, Vec2, Vec3, Vec3A, Vec4, vec2, vec3, vec4};

pub mod cell_hash;
mod frame;
pub use frame::Frame;

/// γ(n) of pbrt's floating-point error analysis: a bound on the relative error of `n`
/// chained IEEE-754 single-precision operations.
#[inline]
pub fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5 * n as f32;
    e / (1.0 - e)
}

/// Builds an orthonormal basis around a unit vector `n` (Duff et al. 2017, branchless).
#[inline]
pub fn coordinate_system(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Reflects `wo` about `n` (both pointing away from the surface).
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refracts `wi` (pointing away from the surface) through a surface with normal `n`
/// (on the side of `wi`) and relative index `eta` = n_transmitted / n_incident.
/// `None` on total internal reflection.
#[inline]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(wi);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wi / eta + (cos_i / eta - cos_t) * n)
}

/// Squares a value.
#[inline]
pub fn sqr(x: f32) -> f32 {
    x * x
}

/// `sqrt` clamped to non-negative input (guards against tiny negative rounding).
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// Spherical direction from (cos θ, sin θ, φ) around +Z.
#[inline]
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let (s, c) = phi.sin_cos();
    Vec3::new(
        sin_theta.clamp(-1.0, 1.0) * c,
        sin_theta.clamp(-1.0, 1.0) * s,
        cos_theta.clamp(-1.0, 1.0),
    )
}

/// True when every component is finite.
#[inline]
pub fn is_finite3(v: Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}
