//! From a [`Material`] description and a surface point to a [`Bsdf`], emission and alpha.
//!
//! Textures multiply their factors (glTF rule): base colour (sRGB RGB, linear A), metallic
//! (linear B) and roughness (linear G), transmission (linear R), emission (sRGB RGB).
//! Normal maps are linear tangent-space normals with `xy` scaled by `normal_scale`.
//! A volume (`KHR_materials_volume`) absorbs along segments inside the mesh: the BSDF at the
//! point where such a segment ends, reached from behind, is weighted by the segment's
//! Beer–Lambert transmittance (see [`bsdf_at`]). Every integrator thereby attenuates
//! without knowing about media; a connection segment of a bidirectional method that runs
//! inside a volume between two non-delta (rough glass) vertices is not attenuated.

use crate::bsdf::{Bsdf, Lobes};
use crate::color::Rgb;
use crate::math::{Frame, Vec2, Vec3, Vec4};
use crate::scene::desc::{AlphaMode, ColorSpace, Material, Texture, TextureRef};
use crate::texture::lookup;

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
    /// World-space length of the ray segment that reached this point from behind the
    /// surface (against `ng`: from inside a closed mesh), 0 when it came from the front or
    /// is unknown. A material with a volume absorbs along it (see [`bsdf_at`]).
    pub interior_distance: f32,
}

#[inline]
fn tex(
    textures: &[Texture],
    tref: &Option<TextureRef>,
    uv: [Vec2; 2],
    space: ColorSpace,
) -> Option<Vec4> {
    tref.as_ref()
        .map(|r| lookup(textures, r, uv[(r.uv_set as usize).min(1)], space))
}

/// Smallest cosine a normal-mapped shading normal keeps with the geometric normal (on
/// the side of the interpolated shading normal).
const MIN_NORMAL_COS: f32 = 0.01;

/// Shading normal after normal mapping, and the tangent to build the frame with.
fn shading_normal(mat: &Material, textures: &[Texture], sp: &ShadingPoint) -> (Vec3, Vec3) {
    let ns = sp.ns;
    let tangent_dir = sp.tangent.map(|t| t.truncate()).unwrap_or(sp.dpdu);
    let Some(t) = tex(textures, &mat.normal_texture, sp.uv, ColorSpace::Linear) else {
        return (ns, tangent_dir);
    };
    // Tangent frame: T orthogonalised against ns, B = (ns × T)·w (glTF / MikkTSpace; with
    // only ∂p/∂u the handedness is taken as +1).
    let tt = tangent_dir - ns * ns.dot(tangent_dir);
    if tt.length_squared().is_nan() || tt.length_squared() <= 1e-12 {
        return (ns, tangent_dir);
    }
    let tt = tt.normalize();
    let w = sp
        .tangent
        .map(|t| if t.w < 0.0 { -1.0 } else { 1.0 })
        .unwrap_or(1.0);
    let bt = ns.cross(tt) * w;
    let c = Vec3::new(
        (2.0 * t.x - 1.0) * mat.normal_scale,
        (2.0 * t.y - 1.0) * mat.normal_scale,
        2.0 * t.z - 1.0,
    );
    let mut n = tt * c.x + bt * c.y + ns * c.z;
    if !n.is_finite() || n.length_squared() <= 1e-12 {
        return (ns, tangent_dir);
    }
    n = n.normalize();
    // Keep the perturbed normal on the side of ng that ns is on, a little above the
    // horizon, so the shading frame never flips the sidedness of the surface.
    let g = if ns.dot(sp.ng) >= 0.0 { sp.ng } else { -sp.ng };
    let d = n.dot(g);
    if d < MIN_NORMAL_COS {
        n = (n + (MIN_NORMAL_COS - d) * g).normalize();
        // One step suffices up to rounding; guard the exact-antipodal case.
        if n.dot(g).is_nan() || n.dot(g) <= 0.0 {
            n = ns;
        }
    }
    (n, tt)
}

/// BSDF of `mat` at `sp`.
pub fn bsdf_at(mat: &Material, textures: &[Texture], sp: &ShadingPoint) -> Bsdf {
    let mut base = mat.base_color;
    if let Some(t) = tex(textures, &mat.base_color_texture, sp.uv, ColorSpace::Srgb) {
        base *= t.truncate();
    }
    let (mut metallic, mut roughness) = (mat.metallic, mat.roughness);
    if let Some(t) = tex(
        textures,
        &mat.metallic_roughness_texture,
        sp.uv,
        ColorSpace::Linear,
    ) {
        roughness *= t.y;
        metallic *= t.z;
    }
    let mut transmission = mat.transmission;
    if let Some(t) = tex(
        textures,
        &mat.transmission_texture,
        sp.uv,
        ColorSpace::Linear,
    ) {
        transmission *= t.x;
    }
    let lobes = Lobes::gltf(
        base,
        metallic,
        roughness,
        mat.ior,
        mat.specular,
        mat.specular_color,
        transmission,
    );
    let mut lobes = lobes;
    // KHR_materials_volume: the segment that reached this point from inside travelled
    // through the medium; Beer–Lambert's exp(−σ·d) multiplies whatever continues from here
    // (transmission out, internal reflection, light sampled here): the BSDF carries it.
    if let Some(v) = &mat.volume
        && sp.interior_distance > 0.0
    {
        lobes.attenuation = Some(v.transmittance(sp.interior_distance));
    }
    let (n, tangent) = shading_normal(mat, textures, sp);
    Bsdf {
        frame: Frame::from_normal_tangent(n, tangent),
        ng: sp.ng,
        lobes,
    }
}

/// Emitted radiance of `mat` at `sp` (same in both hemispheres for double-sided materials;
/// the caller checks the side).
pub fn emission_at(mat: &Material, textures: &[Texture], sp: &ShadingPoint) -> Rgb {
    if mat.emissive == Rgb::ZERO {
        return Rgb::ZERO;
    }
    match tex(textures, &mat.emissive_texture, sp.uv, ColorSpace::Srgb) {
        Some(t) => mat.emissive * t.truncate(),
        None => mat.emissive,
    }
}

/// Coverage of the surface in [0, 1] (alpha mask/blend); 1 for opaque materials.
pub fn alpha_at(mat: &Material, textures: &[Texture], uv: [Vec2; 2]) -> f32 {
    let alpha = || {
        let a = mat.alpha
            * tex(textures, &mat.base_color_texture, uv, ColorSpace::Srgb).map_or(1.0, |t| t.w);
        a.clamp(0.0, 1.0)
    };
    match mat.alpha_mode {
        AlphaMode::Opaque => 1.0,
        AlphaMode::Mask(cutoff) => {
            if alpha() >= cutoff {
                1.0
            } else {
                0.0
            }
        }
        AlphaMode::Blend => alpha(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::{TextureId, WrapMode};

    fn sp() -> ShadingPoint {
        ShadingPoint {
            ng: Vec3::Z,
            ns: Vec3::Z,
            dpdu: Vec3::X,
            tangent: None,
            uv: [Vec2::splat(0.5); 2],
            interior_distance: 0.0,
        }
    }

    fn one_texel(p: [u8; 4]) -> Texture {
        Texture {
            name: "t".into(),
            width: 1,
            height: 1,
            rgba8: vec![p],
            wrap_s: WrapMode::Repeat,
            wrap_t: WrapMode::Repeat,
            bilinear: true,
        }
    }

    #[test]
    fn alpha_modes_and_emission() {
        let textures = [one_texel([255, 128, 0, 102])]; // alpha 0.4
        let mut m = Material::diffuse("m", Rgb::ONE);
        m.alpha = 0.5;
        m.base_color_texture = Some(TextureRef::new(TextureId(0), 0));
        let uv = [Vec2::ZERO; 2];
        assert_eq!(alpha_at(&m, &textures, uv), 1.0);
        m.alpha_mode = AlphaMode::Blend;
        assert!((alpha_at(&m, &textures, uv) - 0.2).abs() < 1e-6);
        m.alpha_mode = AlphaMode::Mask(0.25);
        assert_eq!(alpha_at(&m, &textures, uv), 0.0);
        m.alpha_mode = AlphaMode::Mask(0.15);
        assert_eq!(alpha_at(&m, &textures, uv), 1.0);
        m.emissive = Rgb::splat(2.0);
        m.emissive_texture = Some(TextureRef::new(TextureId(0), 1));
        let e = emission_at(&m, &textures, &sp());
        let lut = crate::texture::srgb_lut();
        assert!(
            (e - 2.0 * Rgb::new(lut[255], lut[128], 0.0))
                .abs()
                .max_element()
                < 1e-6
        );
    }

    #[test]
    fn normal_map_perturbs_and_stays_above_ng() {
        // Tangent-space normal (1, 0, 0) encoded as (255, 128, 128): fully tilted.
        let textures = [
            one_texel([255, 128, 128, 255]),
            one_texel([128, 128, 255, 255]),
        ];
        let mut m = Material::diffuse("m", Rgb::ONE);
        m.normal_texture = Some(TextureRef::new(TextureId(1), 0));
        let b = bsdf_at(&m, &textures, &sp());
        assert!((b.frame.n - Vec3::Z).length() < 1e-2);
        m.normal_texture = Some(TextureRef::new(TextureId(0), 0));
        m.normal_scale = 0.5;
        let b = bsdf_at(&m, &textures, &sp());
        let want = Vec3::new(0.5, 0.0, 0.0039).normalize();
        assert!(
            b.frame.n.x > 0.0 && b.frame.n.dot(Vec3::Z) >= MIN_NORMAL_COS * 0.99,
            "{:?} {want:?}",
            b.frame.n
        );
        let mut s = sp();
        s.tangent = Some(Vec4::new(0.0, 1.0, 0.0, -1.0));
        let b = bsdf_at(&m, &textures, &s);
        assert!(b.frame.n.y > 0.0 && (b.frame.n.length() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn textures_multiply_factors() {
        // metallic-roughness texel: G = 128 (roughness ×0.502), B = 255 (metallic ×1).
        let textures = [one_texel([0, 128, 255, 255])];
        let mut m = Material {
            metallic: 0.5,
            roughness: 1.0,
            ..Default::default()
        };
        m.metallic_roughness_texture = Some(TextureRef::new(TextureId(0), 0));
        let b = bsdf_at(&m, &textures, &sp());
        assert!((b.lobes.metal_weight - 0.5).abs() < 1e-6);
        assert!((b.lobes.alpha - (128.0f32 / 255.0).powi(2)).abs() < 1e-6);
    }
}
