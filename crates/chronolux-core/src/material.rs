//! From a [`Material`] description and a surface point to a [`Bsdf`], emission and alpha.

use crate::bsdf::Bsdf;
use crate::color::Rgb;
use crate::math::{Vec2, Vec3, Vec4};
use crate::scene::desc::{Material, Texture};

/// Surface attributes the material needs at a hit (world space).
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint {
    /// Geometric normal, unit, oriented by the triangle's winding (object-space winding
    /// corrected for negative-determinant transforms).
    pub ng: Vec3,
    /// Interpolated shading normal, unit (equal to `ng` when the mesh has no normals).
    pub ns: Vec3,
    /// ∂p/∂u of the UV parameterisation (zero if no UVs).
    pub dpdu: Vec3,
    /// Interpolated tangent (xyz world, w handedness), if the mesh has tangents.
    pub tangent: Option<Vec4>,
    /// TEXCOORD_0 and TEXCOORD_1 (zero when absent).
    pub uv: [Vec2; 2],
}

/// BSDF of `mat` at `sp`.
pub fn bsdf_at(mat: &Material, textures: &[Texture], sp: &ShadingPoint) -> Bsdf {
    let _ = textures;
    Bsdf::lambert(mat.base_color * (1.0 - mat.metallic), sp.ns, sp.ng)
}

/// Emitted radiance of `mat` at `sp` (same in both hemispheres for double-sided materials;
/// the caller checks the side).
pub fn emission_at(mat: &Material, textures: &[Texture], sp: &ShadingPoint) -> Rgb {
    let _ = (textures, sp);
    mat.emissive
}

/// Coverage of the surface in [0, 1] (alpha mask/blend); 1 for opaque materials.
pub fn alpha_at(mat: &Material, textures: &[Texture], uv: [Vec2; 2]) -> f32 {
    let _ = (textures, uv);
    let _ = mat;
    1.0
}
