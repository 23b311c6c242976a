use glam::Vec3;

/// An orthonormal shading basis; local coordinates have the normal along +Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// Frame around a unit normal, with an arbitrary (but deterministic) tangent.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let (s, t) = super::coordinate_system(n);
        Frame { s, t, n }
    }

    /// Frame around a unit normal with the tangent taken from `dpdu` (Gram–Schmidt);
    /// falls back to [`Frame::from_normal`] if `dpdu` is parallel to `n` or degenerate.
    #[inline]
    pub fn from_normal_tangent(n: Vec3, dpdu: Vec3) -> Self {
        let s = dpdu - n * n.dot(dpdu);
        let len2 = s.length_squared();
        if !(len2 > 1e-12) {
            return Self::from_normal(n);
        }
        let s = s / len2.sqrt();
        Frame {
            s,
            t: n.cross(s),
            n,
        }
    }

    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    #[inline]
    pub fn from_local(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}
