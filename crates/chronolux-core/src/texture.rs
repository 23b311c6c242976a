//! Texture lookup over decoded 8-bit images (decoding is chronolux-io's).
//!
//! [`lookup`] applies the `KHR_texture_transform` affine map, the sampler's wrap modes
//! (repeat, clamp-to-edge, mirrored repeat) and nearest or bilinear filtering. Texels are
//! decoded to linear values *before* filtering (sRGB through a 256-entry table, linear data
//! as `v / 255`); alpha is always linear. Texel centres sit at half-integer coordinates
//! (`u·width − 0.5`), as in OpenGL/Vulkan samplers.

use crate::math::{Vec2, Vec4};
use crate::scene::desc::{ColorSpace, Texture, TextureRef, WrapMode};
use std::sync::OnceLock;

/// The sRGB → linear decoding table for 8-bit values (`srgb_to_linear(i / 255)`).
pub fn srgb_lut() -> &'static [f32; 256] {
    static LUT: OnceLock<[f32; 256]> = OnceLock::new();
    LUT.get_or_init(|| std::array::from_fn(|i| crate::color::srgb_to_linear(i as f32 / 255.0)))
}

/// Maps an integer texel coordinate to `[0, n)` according to `mode`.
#[inline]
pub fn wrap_texel(i: i64, n: u32, mode: WrapMode) -> u32 {
    let n = n as i64;
    let k = match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::ClampToEdge => i.clamp(0, n - 1),
        WrapMode::MirroredRepeat => {
            let k = i.rem_euclid(2 * n);
            if k < n { k } else { 2 * n - 1 - k }
        }
    };
    k as u32
}

#[inline]
fn texel(tex: &Texture, x: i64, y: i64, space: ColorSpace) -> Vec4 {
    let x = wrap_texel(x, tex.width, tex.wrap_s);
    let y = wrap_texel(y, tex.height, tex.wrap_t);
    let p = tex.rgba8[(y as usize) * (tex.width as usize) + x as usize];
    let a = p[3] as f32 * (1.0 / 255.0);
    match space {
        ColorSpace::Srgb => {
            let lut = srgb_lut();
            Vec4::new(
                lut[p[0] as usize],
                lut[p[1] as usize],
                lut[p[2] as usize],
                a,
            )
        }
        ColorSpace::Linear => {
            Vec4::new(p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32) * (1.0 / 255.0)
        }
    }
}

/// Looks up `tref` at texture coordinates `uv` (already chosen from the right UV set),
/// returning RGBA with RGB decoded according to `space` (alpha is always linear).
/// A texture with no texels, or a non-finite coordinate, reads as opaque white (the
/// neutral factor).
pub fn lookup(textures: &[Texture], tref: &TextureRef, uv: Vec2, space: ColorSpace) -> Vec4 {
    let tex = &textures[tref.texture.index()];
    let m = &tref.transform;
    let uv = m[0] * uv.x + m[1] * uv.y + m[2];
    if tex.width == 0
        || tex.height == 0
        || tex.rgba8.len() < (tex.width as usize) * (tex.height as usize)
    {
        return Vec4::ONE;
    }
    if !(uv.x.is_finite() && uv.y.is_finite()) {
        return Vec4::ONE;
    }
    let x = uv.x as f64 * tex.width as f64;
    let y = uv.y as f64 * tex.height as f64;
    if tex.bilinear {
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let t00 = texel(tex, x0, y0, space);
        let t10 = texel(tex, x0 + 1, y0, space);
        let t01 = texel(tex, x0, y0 + 1, space);
        let t11 = texel(tex, x0 + 1, y0 + 1, space);
        (t00 * (1.0 - fx) + t10 * fx) * (1.0 - fy) + (t01 * (1.0 - fx) + t11 * fx) * fy
    } else {
        texel(tex, x.floor() as i64, y.floor() as i64, space)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::TextureId;

    fn tex(w: u32, h: u32, px: Vec<[u8; 4]>, wrap: WrapMode, bilinear: bool) -> Texture {
        Texture {
            name: "t".into(),
            width: w,
            height: h,
            rgba8: px,
            wrap_s: wrap,
            wrap_t: wrap,
            bilinear,
        }
    }

    #[test]
    fn srgb_lut_matches_formula() {
        let lut = srgb_lut();
        for (i, &v) in lut.iter().enumerate() {
            let c = i as f64 / 255.0;
            let exact = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
            // f32 evaluation of the same formula: a few ulps of relative error.
            assert!(
                (v as f64 - exact).abs() <= 1e-6 * exact.max(1e-3),
                "{i}: {v} vs {exact}"
            );
        }
        assert_eq!(lut[0], 0.0);
        assert!((lut[255] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(
            (-1..6)
                .map(|i| wrap_texel(i, 3, WrapMode::Repeat))
                .collect::<Vec<_>>(),
            [2, 0, 1, 2, 0, 1, 2]
        );
        assert_eq!(
            (-2..5)
                .map(|i| wrap_texel(i, 3, WrapMode::ClampToEdge))
                .collect::<Vec<_>>(),
            [0, 0, 0, 1, 2, 2, 2]
        );
        assert_eq!(
            (-3..7)
                .map(|i| wrap_texel(i, 3, WrapMode::MirroredRepeat))
                .collect::<Vec<_>>(),
            [2, 1, 0, 0, 1, 2, 2, 1, 0, 0]
        );
    }

    #[test]
    fn nearest_lookup_with_wrap_and_transform() {
        let px = vec![[0, 0, 0, 255], [255, 255, 255, 255]];
        let r = TextureRef::new(TextureId(0), 0);
        for (wrap, u, want) in [
            (WrapMode::Repeat, 1.25, 0.0),
            (WrapMode::Repeat, -0.25, 1.0),
            (WrapMode::ClampToEdge, 1.75, 1.0),
            (WrapMode::ClampToEdge, -3.0, 0.0),
            (WrapMode::MirroredRepeat, 1.25, 1.0),
            (WrapMode::MirroredRepeat, 1.75, 0.0),
        ] {
            let t = [tex(2, 1, px.clone(), wrap, false)];
            let v = lookup(&t, &r, Vec2::new(u, 0.5), ColorSpace::Linear);
            assert_eq!(v.x, want, "{wrap:?} u={u}");
        }
        // Offset transform by half the texture moves texel 1 to u = 0.25.
        let t = [tex(2, 1, px, WrapMode::Repeat, false)];
        let mut r2 = r;
        r2.transform[2] = Vec2::new(0.5, 0.0);
        assert_eq!(
            lookup(&t, &r2, Vec2::new(0.25, 0.5), ColorSpace::Linear).x,
            1.0
        );
    }

    #[test]
    fn bilinear_midpoint_is_average_of_decoded_texels() {
        let px = vec![[0, 50, 255, 0], [255, 200, 0, 255]];
        let t = [tex(2, 1, px, WrapMode::ClampToEdge, true)];
        let r = TextureRef::new(TextureId(0), 0);
        // u = 0.5 is exactly between the two texel centres (0.25 and 0.75).
        let v = lookup(&t, &r, Vec2::new(0.5, 0.5), ColorSpace::Srgb);
        let lut = srgb_lut();
        let want = [
            (lut[0] + lut[255]) / 2.0,
            (lut[50] + lut[200]) / 2.0,
            (lut[255] + lut[0]) / 2.0,
            0.5,
        ];
        for (a, b) in v.to_array().iter().zip(want) {
            // One f32 lerp: rounding error only.
            assert!((a - b).abs() < 1e-6, "{v:?} vs {want:?}");
        }
        let l = lookup(&t, &r, Vec2::new(0.5, 0.5), ColorSpace::Linear);
        assert!((l.y - 125.0 / 255.0).abs() < 1e-6);
        // At a texel centre, bilinear returns that texel.
        assert!((lookup(&t, &r, Vec2::new(0.25, 0.5), ColorSpace::Linear).x).abs() < 1e-6);
    }
}
