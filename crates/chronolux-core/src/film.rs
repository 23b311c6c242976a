//! Film: per-pixel accumulation with a box filter (each sample counts for the pixel it
//! falls in, as Mitsuba's `box` reconstruction filter), and the resulting linear image.

use crate::color::Rgb;

/// Sum of sample values and weights per pixel.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    sum: Vec<Rgb>,
    /// Sum of squared sample values (for the per-pixel variance of the mean).
    sum_sq: Vec<Rgb>,
    weight: Vec<f32>,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        Film {
            width,
            height,
            sum: vec![Rgb::ZERO; n],
            sum_sq: vec![Rgb::ZERO; n],
            weight: vec![0.0; n],
        }
    }

    /// Adds a sample to pixel (x, y); non-finite values are dropped (and counted by the caller).
    #[inline]
    pub fn add(&mut self, x: u32, y: u32, v: Rgb, w: f32) {
        let i = (y * self.width + x) as usize;
        self.sum[i] += v * w;
        self.sum_sq[i] += v * v * w;
        self.weight[i] += w;
    }

    /// Copies a tile film into this one at (x0, y0).
    pub fn merge_tile(&mut self, tile: &Film, x0: u32, y0: u32) {
        for y in 0..tile.height {
            for x in 0..tile.width {
                let s = (y * tile.width + x) as usize;
                let d = ((y0 + y) * self.width + x0 + x) as usize;
                self.sum[d] += tile.sum[s];
                self.sum_sq[d] += tile.sum_sq[s];
                self.weight[d] += tile.weight[s];
            }
        }
    }

    /// Estimated variance of each pixel's mean, per channel: the unbiased sample variance
    /// of its (unit-weight) samples divided by their number. Zero for pixels with fewer
    /// than two samples.
    pub fn variance_of_mean(&self) -> Vec<Rgb> {
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .zip(&self.weight)
            .map(|((s, q), &n)| {
                if n < 2.0 {
                    return Rgb::ZERO;
                }
                let m = *s / n;
                ((*q / n - m * m) * (n / (n - 1.0))).max(Rgb::ZERO) / n
            })
            .collect()
    }

    /// Mean value per pixel (row-major, top row first).
    pub fn pixels(&self) -> Vec<Rgb> {
        self.sum
            .iter()
            .zip(&self.weight)
            .map(|(s, &w)| if w > 0.0 { *s / w } else { Rgb::ZERO })
            .collect()
    }
}
