//! An environment map: an equirectangular (latitude-longitude) image of linear radiance
//! arriving from infinity, importance-sampled by a piecewise-constant 2D distribution over
//! its texels weighted by sin θ (pbrt-v3's `InfiniteAreaLight`).
//!
//! Orientation (glTF's +Y up), chosen so that a map lights a scene exported from Blender
//! as Blender's Environment Texture node lights it there (Blender's +Z up is glTF's +Y,
//! Blender's +Y is glTF's −Z): the top row looks straight up (+Y), the bottom row straight
//! down; the image's centre column looks along +X, the column at a quarter of the width
//! along −Z, three quarters along +Z. With `rotation` (radians about +Y) the map is looked
//! up at the direction rotated by that angle, as Blender's Mapping node (type Point)
//! rotating about Z does before an Environment Texture.
//!
//! Lookup is nearest-texel, so radiance and the sampling density are constant over the
//! same cells and the sampling is exact (no texel with radiance has density zero).

use crate::color::{Rgb, luminance};
use crate::math::{Vec2, Vec3};
use crate::sampling::distrib::Distribution1D;
use std::f32::consts::PI;

/// An equirectangular environment map (see the module doc), radiance already scaled by
/// its strength.
#[derive(Clone)]
pub struct EnvMap {
    width: usize,
    height: usize,
    /// Row-major, top row (up) first; radiance × strength.
    texels: Vec<Rgb>,
    strength: f32,
    rotation: f32,
    cos_rot: f32,
    sin_rot: f32,
    /// Over rows: Σ_row luminance · sin θ_row (None: a black map).
    marginal: Option<Distribution1D>,
    /// Per row, over its texels by luminance (None: a black row).
    conditional: Vec<Option<Distribution1D>>,
    /// Mean radiance over the sphere of directions (exact for the nearest-texel lookup).
    mean: Rgb,
    /// Luminance-weighted mean direction towards the light (length ≤ 1).
    mean_direction: Vec3,
}

impl std::fmt::Debug for EnvMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvMap")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("strength", &self.strength)
            .field("rotation", &self.rotation)
            .field("mean", &self.mean)
            .finish_non_exhaustive()
    }
}

impl PartialEq for EnvMap {
    fn eq(&self, o: &Self) -> bool {
        self.width == o.width
            && self.height == o.height
            && self.strength.to_bits() == o.strength.to_bits()
            && self.rotation.to_bits() == o.rotation.to_bits()
            && self.texels.len() == o.texels.len()
            && self
                .texels
                .iter()
                .zip(&o.texels)
                .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits))
    }
}

impl EnvMap {
    /// A map of `width × height` texels (row-major, top row first) of linear radiance,
    /// multiplied by `strength`, rotated by `rotation_deg` degrees about +Y. Errors (never
    /// panics) for an empty or mis-sized image, a non-finite or negative texel, strength
    /// or rotation.
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<Rgb>,
        strength: f32,
        rotation_deg: f32,
    ) -> Result<EnvMap, String> {
        if width == 0 || height == 0 {
            return Err(format!(
                "environment map is empty ({width}x{height} texels)"
            ));
        }
        if width.checked_mul(height) != Some(texels.len()) {
            return Err(format!(
                "environment map has {} texels, not {width}x{height}",
                texels.len()
            ));
        }
        if !(strength.is_finite() && strength >= 0.0) {
            return Err(format!(
                "environment strength must be a finite number ≥ 0, not {strength}"
            ));
        }
        if !rotation_deg.is_finite() {
            return Err(format!(
                "environment rotation must be a finite number of degrees, not {rotation_deg}"
            ));
        }
        let mut texels = texels;
        for (i, t) in texels.iter_mut().enumerate() {
            // Negative radiance (a few tools write tiny negative values from filtering) is
            // clamped; NaN or infinity is an error: the map would light nothing sensibly.
            if !t.is_finite() {
                return Err(format!(
                    "environment map texel ({}, {}) is not finite ({t:?})",
                    i % width,
                    i / width
                ));
            }
            *t = t.max(Rgb::ZERO) * strength;
        }
        let rotation = rotation_deg.to_radians();
        let (dphi, dtheta) = (2.0 * PI as f64 / width as f64, PI as f64 / height as f64);
        let mut row_weights = Vec::with_capacity(height);
        let mut conditional = Vec::with_capacity(height);
        let mut sum = [0.0f64; 3];
        let mut dir_sum = [0.0f64; 3];
        let mut lum_sum = 0.0f64;
        for row in 0..height {
            let r = &texels[row * width..(row + 1) * width];
            let lum: Vec<f32> = r.iter().map(|&t| luminance(t).max(0.0)).collect();
            let theta = (row as f64 + 0.5) * dtheta;
            let row_sum: f64 = lum.iter().map(|&l| l as f64).sum();
            row_weights.push((row_sum * theta.sin()) as f32);
            conditional.push(Distribution1D::new(&lum));
            // Exact solid angle of the texel band: Δφ (cos θ0 − cos θ1).
            let (t0, t1) = (row as f64 * dtheta, (row + 1) as f64 * dtheta);
            let band = dphi * (t0.cos() - t1.cos());
            for (col, (&t, &l)) in r.iter().zip(&lum).enumerate() {
                for (c, s) in sum.iter_mut().enumerate() {
                    *s += t.to_array()[c] as f64 * band;
                }
                let phi = 2.0 * std::f64::consts::PI * ((col as f64 + 0.5) / width as f64 - 0.5);
                let (st, ct) = (theta.sin(), theta.cos());
                let w = [st * phi.cos(), ct, st * phi.sin()];
                for k in 0..3 {
                    dir_sum[k] += w[k] * l as f64 * band;
                }
                lum_sum += l as f64 * band;
            }
        }
        let marginal = Distribution1D::new(&row_weights);
        let four_pi = 4.0 * std::f64::consts::PI;
        let mean = Rgb::new(
            (sum[0] / four_pi) as f32,
            (sum[1] / four_pi) as f32,
            (sum[2] / four_pi) as f32,
        );
        let mut map = EnvMap {
            width,
            height,
            texels,
            strength,
            rotation,
            cos_rot: rotation.cos(),
            sin_rot: rotation.sin(),
            marginal,
            conditional,
            mean,
            mean_direction: Vec3::ZERO,
        };
        if lum_sum > 0.0 {
            let d = Vec3::new(
                (dir_sum[0] / lum_sum) as f32,
                (dir_sum[1] / lum_sum) as f32,
                (dir_sum[2] / lum_sum) as f32,
            );
            map.mean_direction = map.to_world(d).clamp_length_max(1.0);
        }
        Ok(map)
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    pub fn strength(&self) -> f32 {
        self.strength
    }

    /// Rotation about +Y in degrees.
    pub fn rotation_deg(&self) -> f32 {
        self.rotation.to_degrees()
    }

    /// Mean radiance over the sphere.
    pub fn mean(&self) -> Rgb {
        self.mean
    }

    /// Luminance-weighted mean of the directions towards the light (world space, length
    /// ≤ 1: 0 for a uniform map).
    pub fn mean_direction(&self) -> Vec3 {
        self.mean_direction
    }

    /// World direction → map direction (rotated by `rotation` about +Y).
    fn to_map(&self, w: Vec3) -> Vec3 {
        let (c, s) = (self.cos_rot, self.sin_rot);
        Vec3::new(w.x * c + w.z * s, w.y, -w.x * s + w.z * c)
    }

    /// Map direction → world direction.
    fn to_world(&self, m: Vec3) -> Vec3 {
        let (c, s) = (self.cos_rot, self.sin_rot);
        Vec3::new(m.x * c - m.z * s, m.y, m.x * s + m.z * c)
    }

    /// (row, column, sin θ) of the texel direction `w` (world, need not be unit) falls in.
    fn texel_of(&self, w: Vec3) -> Option<(usize, usize, f32)> {
        let m = self.to_map(w).normalize_or_zero();
        if m == Vec3::ZERO || !m.is_finite() {
            return None;
        }
        let y = m.y.clamp(-1.0, 1.0);
        let theta = y.acos();
        let phi = m.z.atan2(m.x);
        let u = 0.5 + phi / (2.0 * PI);
        let col = ((u * self.width as f32) as isize).rem_euclid(self.width as isize) as usize;
        let row = ((theta / PI * self.height as f32) as usize).min(self.height - 1);
        let sin_theta = (1.0 - y * y).max(0.0).sqrt();
        Some((row, col, sin_theta))
    }

    /// Radiance arriving from direction `w` (towards the environment; need not be unit).
    pub fn eval(&self, w: Vec3) -> Rgb {
        match self.texel_of(w) {
            Some((row, col, _)) => self.texels[row * self.width + col],
            None => Rgb::ZERO,
        }
    }

    /// Solid-angle density with which [`EnvMap::sample`] produces `w`.
    pub fn pdf(&self, w: Vec3) -> f32 {
        let (Some(marginal), Some((row, col, sin_theta))) = (&self.marginal, self.texel_of(w))
        else {
            return 0.0;
        };
        let Some(cond) = &self.conditional[row] else {
            return 0.0;
        };
        if sin_theta <= 0.0 {
            return 0.0;
        }
        let pdf_uv = marginal.pmf(row) * self.height as f32 * cond.pmf(col) * self.width as f32;
        pdf_uv / (2.0 * PI * PI * sin_theta)
    }

    /// Samples a direction towards the environment in proportion to luminance (per texel,
    /// weighted by sin θ); `None` for a black map or a sample on a pole. The returned
    /// density is [`EnvMap::pdf`] of the returned direction.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let marginal = self.marginal.as_ref()?;
        let (row, _, dv) = marginal.sample(u.y);
        let cond = self.conditional[row].as_ref()?;
        let (col, _, du) = cond.sample(u.x);
        let v = (row as f32 + dv) / self.height as f32;
        let uu = (col as f32 + du) / self.width as f32;
        let theta = v * PI;
        let phi = 2.0 * PI * (uu - 0.5);
        let (st, ct) = theta.sin_cos();
        let m = Vec3::new(st * phi.cos(), ct, st * phi.sin());
        let w = self.to_world(m).normalize_or_zero();
        // The density of the texel the direction lands in (the same lookup as `pdf`, so
        // that sample and pdf agree also where rounding moves a direction across a texel
        // edge).
        let pdf = self.pdf(w);
        (pdf > 0.0).then_some((w, pdf))
    }
}
