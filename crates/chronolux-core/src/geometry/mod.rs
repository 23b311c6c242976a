//! Rays, triangles, bounds and the one robust ray-spawning rule.

use crate::math::{Vec3, Vec3A};

/// A ray `o + t·d`, `t ∈ (0, tmax)`. `d` need not be unit length (then `t` is in units of
/// |d|); integrators use unit directions.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub tmax: f32,
}

impl Ray {
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray {
            o,
            d,
            tmax: f32::INFINITY,
        }
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// Offsets a ray origin `p` on a surface with geometric normal `n` to the side of
/// direction `w`, so that the spawned ray cannot re-hit the surface it leaves.
///
/// Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray Tracing
/// Gems, ch. 6): the offset is a fixed number of ULPs of the coordinates (plus a tiny
/// absolute offset near the origin), which bounds the error of a hit point computed from
/// barycentric interpolation of single-precision vertices. This is the only place in the
/// renderer where self-intersection is handled; no epsilons appear in integrators.
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let n = if n.dot(w) < 0.0 { -n } else { n };
    let of_i = [
        (INT_SCALE * n.x) as i32,
        (INT_SCALE * n.y) as i32,
        (INT_SCALE * n.z) as i32,
    ];
    let off = |pc: f32, oi: i32| -> f32 {
        let bits = pc.to_bits() as i32;
        f32::from_bits((bits + if pc < 0.0 { -oi } else { oi }) as u32)
    };
    let p_i = Vec3::new(off(p.x, of_i[0]), off(p.y, of_i[1]), off(p.z, of_i[2]));
    Vec3::new(
        if p.x.abs() < ORIGIN {
            p.x + FLOAT_SCALE * n.x
        } else {
            p_i.x
        },
        if p.y.abs() < ORIGIN {
            p.y + FLOAT_SCALE * n.y
        } else {
            p_i.y
        },
        if p.z.abs() < ORIGIN {
            p.z + FLOAT_SCALE * n.z
        } else {
            p_i.z
        },
    )
}

/// Ray from a surface point towards direction `w`.
#[inline]
pub fn spawn_ray(p: Vec3, ng: Vec3, w: Vec3) -> Ray {
    Ray::new(offset_ray_origin(p, ng, w), w)
}

/// Ray from a surface point `p0` to a point `p1` (on another surface with normal `n1`, or
/// a light at `p1` when `n1` is zero), stopping just short of `p1`.
#[inline]
pub fn spawn_ray_to(p0: Vec3, n0: Vec3, p1: Vec3, n1: Vec3) -> Ray {
    let d = p1 - p0;
    let o = offset_ray_origin(p0, n0, d);
    let target = if n1 == Vec3::ZERO {
        p1
    } else {
        offset_ray_origin(p1, n1, -d)
    };
    let d = target - o;
    // tmax just below 1 keeps the target surface out; 1 - 2^-20 is ~8 ULPs of 1.
    Ray {
        o,
        d,
        tmax: 1.0 - 1.0 / (1u32 << 20) as f32,
    }
}

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds3 {
    pub const EMPTY: Bounds3 = Bounds3 {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, o: &Bounds3) -> Bounds3 {
        Bounds3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    pub fn diagonal(&self) -> Vec3 {
        self.max - self.min
    }

    /// Centre and radius of a sphere enclosing the box.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        if self.is_empty() {
            return (Vec3::ZERO, 0.0);
        }
        (self.center(), 0.5 * self.diagonal().length())
    }
}

/// A triangle prepared for intersection: one vertex and two edges.
#[derive(Clone, Copy, Debug)]
pub struct PreparedTriangle {
    pub v0: Vec3A,
    pub e1: Vec3A,
    pub e2: Vec3A,
}

impl PreparedTriangle {
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        PreparedTriangle {
            v0: a.into(),
            e1: (b - a).into(),
            e2: (c - a).into(),
        }
    }

    /// Möller–Trumbore, two-sided. Returns (t, b1, b2) for hits with `tmin < t < tmax`;
    /// the hit point is `(1-b1-b2)·v0 + b1·v1 + b2·v2`.
    #[inline(always)]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, f32, f32)> {
        let pvec = d.cross(self.e2);
        let det = self.e1.dot(pvec);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let tvec = o - self.v0;
        let u = tvec.dot(pvec) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let qvec = tvec.cross(self.e1);
        let v = d.dot(qvec) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(qvec) * inv;
        if t > 0.0 && t < tmax {
            Some((t, u, v))
        } else {
            None
        }
    }
}

/// Brute-force closest hit over triangles (reference for acceleration-structure tests).
pub fn brute_force_closest(tris: &[PreparedTriangle], ray: &Ray) -> Option<(usize, f32)> {
    let mut best: Option<(usize, f32)> = None;
    let mut tmax = ray.tmax;
    for (i, t) in tris.iter().enumerate() {
        if let Some((th, _, _)) = t.intersect(ray.o.into(), ray.d.into(), tmax) {
            tmax = th;
            best = Some((i, th));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    #[test]
    fn spawned_rays_do_not_self_intersect() {
        // Large and small coordinates, random triangles: a ray leaving the hit point of the
        // triangle it lies on, in any direction on the normal's side, must not hit it again.
        let mut r = Pcg32::new(7, 1);
        let mut f = || r.next_f32();
        for k in 0..20_000 {
            let scale = [1e-3, 1.0, 1e3, 1e5][k % 4];
            let v = |f: &mut dyn FnMut() -> f32| Vec3::new(f() - 0.5, f() - 0.5, f() - 0.5) * scale;
            let (a, b, c) = (v(&mut f), v(&mut f), v(&mut f));
            let tri = PreparedTriangle::new(a, b, c);
            let n = (b - a).cross(c - a);
            if n.length_squared() == 0.0 {
                continue;
            }
            let n = n.normalize();
            let (b1, b2) =
                crate::sampling::warps::sample_uniform_triangle(glam::Vec2::new(f(), f()));
            let p = (1.0 - b1 - b2) * a + b1 * b + b2 * c;
            let mut w = crate::sampling::warps::sample_uniform_sphere(glam::Vec2::new(f(), f()));
            if w.dot(n).abs() < 1e-3 {
                continue;
            }
            if w.dot(n) < 0.0 && k % 2 == 0 {
                w = -w;
            }
            let ray = spawn_ray(p, n, w);
            assert!(
                tri.intersect(ray.o.into(), ray.d.into(), f32::INFINITY)
                    .is_none(),
                "self hit at k={k}"
            );
        }
    }
}
