//! Linear, scene-referred RGB and the sRGB transfer functions.

/// Linear Rec.709/sRGB-primaries RGB radiance, reflectance or weight.
pub type Rgb = glam::Vec3;

/// Relative luminance (Rec. 709 weights).
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// True when every channel is zero.
#[inline]
pub fn is_black(c: Rgb) -> bool {
    c.x == 0.0 && c.y == 0.0 && c.z == 0.0
}

/// Largest channel.
#[inline]
pub fn max_component(c: Rgb) -> f32 {
    c.x.max(c.y).max(c.z)
}

/// sRGB electro-optical transfer: encoded value in [0, 1] → linear.
#[inline]
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB opto-electronic transfer: linear → encoded value in [0, 1] (input clamped).
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}
