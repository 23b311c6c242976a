//! Solid-angle sampling of triangles: uniform directions inside the spherical triangle a
//! triangle subtends (Arvo 1995, "Stratified sampling of spherical triangles", in the form
//! of pbrt-v4's `SampleSphericalTriangle`), and the solid angle itself.
//!
//! Computed in f64: the vertex angles sum to π + Ω, so in f32 a solid angle of 3e-4 sr
//! would keep only ~3 significant digits.

use crate::math::Vec3;
use glam::DVec3;

/// Below this solid angle (sr) triangle lights are sampled by area: the spherical
/// construction loses precision and area sampling is already nearly proportional to
/// solid angle. pbrt-v4's `MinSphericalSampleArea` is 3e-4; ours is higher because the
/// construction (f64, asin/atan2/sincos) is dear next to a shadow ray: on the Cornell box
/// of ../shared/peers (ceiling light ≈ 0.05 sr from the floor), solid-angle sampling cost
/// 30% more CPU for 3% lower relMSE at 64 spp, i.e. about 20% lower efficiency.
pub const MIN_SPHERICAL_SAMPLE_AREA: f32 = 0.1;
/// Above this (close to a hemisphere, 2π) the construction degenerates; area sampling
/// again (pbrt-v4's `MaxSphericalSampleArea`).
pub const MAX_SPHERICAL_SAMPLE_AREA: f32 = 6.22;

/// Whether a triangle subtending `solid_angle` from the reference point is sampled by solid
/// angle (else by area). `sample_li` and `pdf_li` both decide through this.
#[inline]
pub fn use_solid_angle_sampling(solid_angle: f32) -> bool {
    (MIN_SPHERICAL_SAMPLE_AREA..=MAX_SPHERICAL_SAMPLE_AREA).contains(&solid_angle)
}

/// The solid angle the triangle (p0, p0 + e1, p0 + e2) (unit normal `n`, area `area`)
/// subtends at `p` when that is in the range sampled by solid angle
/// ([`use_solid_angle_sampling`]), else `None` (the triangle is sampled by area). Decides
/// as `use_solid_angle_sampling(triangle_solid_angle(…))` does, but first tests a cheap
/// upper bound: with `h` the distance of `p` from the triangle's plane and `r_min` a lower
/// bound on its distance from the triangle (`max(h, d − R)`, `d` the distance to the
/// centroid, `R` the centroid's farthest vertex), `Ω = ∫ h / r³ dA ≤ area · h / r_min³`.
/// Where that is below [`MIN_SPHERICAL_SAMPLE_AREA`] with a margin of 1e-3 relative (far
/// above the f32 rounding of the exact solid angle, ~1e-6; `area` is trusted to 1e-6), the
/// exact solid angle is too, so
/// its f64 construction (atan2, three square roots: 6.6 % of `path`'s CPU on the Cornell
/// box, where most shading points see the ceiling light at ≈ 0.05 sr) is skipped and the
/// decision is the same.
#[inline]
pub fn sampled_solid_angle(
    p: Vec3,
    p0: Vec3,
    e1: Vec3,
    e2: Vec3,
    n: Vec3,
    area: f32,
) -> Option<f32> {
    // In f64, with each distance lowered (and `h` in the numerator raised) by far more than
    // its rounding error, so that the bound holds for the computed numbers too; only
    // square roots, no transcendental functions.
    let (pd, v0) = (p.as_dvec3(), p0.as_dvec3());
    let (d1, d2) = (e1.as_dvec3(), e2.as_dvec3());
    let c = v0 + (d1 + d2) * (1.0 / 3.0);
    let r = (v0 - c)
        .length_squared()
        .max((v0 + d1 - c).length_squared())
        .max((v0 + d2 - c).length_squared())
        .sqrt();
    let (d, to_p0) = ((pd - c).length(), (pd - v0).length());
    let h = (pd - v0).dot(n.as_dvec3()).abs();
    let slack = 1e-9 * (d + r + to_p0);
    let r_min = (h - slack).max(d - r - slack);
    if r_min > 0.0
        && f64::from(area) * (1.0 + 1e-6) * (h + slack)
            < f64::from(MIN_SPHERICAL_SAMPLE_AREA) * (1.0 - 1e-3) * r_min * r_min * r_min
    {
        return None;
    }
    let omega = triangle_solid_angle(p, p0, e1, e2);
    use_solid_angle_sampling(omega).then_some(omega)
}

/// Solid angle subtended at `p` by the triangle (p0, p0 + e1, p0 + e2) (Van Oosterom and
/// Strackee 1983). The triple product is taken as (p0 − p)·(e1 × e2), which has no
/// cancellation for far triangles.
pub fn triangle_solid_angle(p: Vec3, p0: Vec3, e1: Vec3, e2: Vec3) -> f32 {
    let a = p0.as_dvec3() - p.as_dvec3();
    let (e1, e2) = (e1.as_dvec3(), e2.as_dvec3());
    let (b, c) = (a + e1, a + e2);
    let triple = a.dot(e1.cross(e2)).abs();
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let denom = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    (2.0 * triple.atan2(denom)) as f32
}

/// Angle between unit vectors, accurate for nearly (anti)parallel ones.
fn angle_between(v1: DVec3, v2: DVec3) -> f64 {
    if v1.dot(v2) < 0.0 {
        std::f64::consts::PI - 2.0 * ((v1 + v2).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((v2 - v1).length() / 2.0).min(1.0).asin()
    }
}

fn gram_schmidt(v: DVec3, w: DVec3) -> DVec3 {
    v - w * v.dot(w)
}

/// A direction uniform in solid angle inside the spherical triangle that (p0, p0 + e1,
/// p0 + e2) subtends at `p`, returned as the barycentrics (b1, b2) of the point it hits
/// (point = p0 + b1·e1 + b2·e2). Density 1/[`triangle_solid_angle`]. `None` for degenerate
/// (zero solid angle) configurations.
pub fn sample_spherical_triangle(
    p: Vec3,
    p0: Vec3,
    e1: Vec3,
    e2: Vec3,
    u: [f32; 2],
) -> Option<(f32, f32)> {
    let pd = p.as_dvec3();
    let v0 = p0.as_dvec3();
    let (e1, e2) = (e1.as_dvec3(), e2.as_dvec3());
    let a = (v0 - pd).normalize_or_zero();
    let b = (v0 + e1 - pd).normalize_or_zero();
    let c = (v0 + e2 - pd).normalize_or_zero();
    let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
    if n_ab.length_squared() == 0.0 || n_bc.length_squared() == 0.0 || n_ca.length_squared() == 0.0
    {
        return None;
    }
    let (n_ab, n_bc, n_ca) = (n_ab.normalize(), n_bc.normalize(), n_ca.normalize());
    // Vertex angles of the spherical triangle.
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    // Sub-triangle of area A' = u0·A: A' + π is the angle sum of the sub-triangle.
    let a_pi = alpha + beta + gamma;
    let ap_pi = std::f64::consts::PI + (u[0] as f64) * (a_pi - std::f64::consts::PI);
    if a_pi - std::f64::consts::PI <= 0.0 {
        return None;
    }
    // cos of the arc from a to the new vertex c' on the arc a–c.
    let (cos_alpha, sin_alpha) = (alpha.cos(), alpha.sin());
    let (s_ap, c_ap) = ap_pi.sin_cos();
    let sin_phi = s_ap * cos_alpha - c_ap * sin_alpha;
    let cos_phi = c_ap * cos_alpha + s_ap * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
        / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
    if !cos_bp.is_finite() {
        return None;
    }
    let cos_bp = cos_bp.clamp(-1.0, 1.0);
    let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
    let cp = a * cos_bp + gram_schmidt(c, a).normalize_or_zero() * sin_bp;
    // Uniform in solid angle along the arc b–c'.
    let cos_theta = 1.0 - (u[1] as f64) * (1.0 - cp.dot(b));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let w = b * cos_theta + gram_schmidt(cp, b).normalize_or_zero() * sin_theta;
    // Barycentrics of the point w hits (Möller–Trumbore).
    let s1 = w.cross(e2);
    let div = s1.dot(e1);
    if div == 0.0 {
        return None;
    }
    let s = pd - v0;
    let b1 = (s.dot(s1) / div).clamp(0.0, 1.0);
    let b2 = (w.dot(s.cross(e1)) / div).clamp(0.0, 1.0);
    let sum = b1 + b2;
    let (b1, b2) = if sum > 1.0 {
        (b1 / sum, b2 / sum)
    } else {
        (b1, b2)
    };
    Some((b1 as f32, b2 as f32))
}
