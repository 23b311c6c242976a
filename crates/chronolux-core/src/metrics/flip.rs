//! NVIDIA ꟻLIP (Andersson et al., HPG 2020) and HDR-ꟻLIP (Andersson et al., EGSR 2021),
//! written to give the same numbers as the reference implementation, `flip-evaluator` 1.7
//! (NVlabs/flip, `FLIP.h`), in single precision as it computes them.
//!
//! **LDR-ꟻLIP** of linear RGB images in [0, 1] (values are clamped):
//! 1. linear RGB → XYZ (D65) → YCxCz (opponent space, normalised by the D65 white);
//! 2. colour pipeline: each channel is filtered with the contrast sensitivity functions
//!    of the paper (Gaussians in visual degrees; the blue–yellow channel is a sum of two,
//!    applied as two separable passes), clamp-to-edge borders; back to linear RGB clamped
//!    to [0, 1], to CIELab with the Hunt adjustment (a, b scaled by 0.01 L); HyAB distance
//!    raised to 0.7, then remapped so that 0.4 · cmax maps to 0.95 and cmax to 1, where cmax
//!    is the HyAB distance between Hunt-adjusted pure green and pure blue;
//! 3. feature pipeline on the achromatic channel ((Y + 16)/116): first and second
//!    derivatives of a Gaussian (σ = 0.5 · 0.082 · ppd pixels, radius ⌈3σ⌉, positive and
//!    negative weights each normalised to ±1), edge = |∇|, point = |∇²| magnitudes; feature
//!    difference = (max(Δedge, Δpoint)/√2)^0.5;
//! 4. per-pixel error = colour difference^(1 − feature difference); the mean is over pixels.
//!
//! **HDR-ꟻLIP**: both images are exposed by 2^e, tone mapped (ACES by default, the
//! reference's choice), clamped to [0, 1] and compared with LDR-ꟻLIP for exposures e from
//! c_start to c_stop in max(2, ⌈c_stop − c_start⌉) equal steps; the per-pixel error is the
//! maximum over exposures. Unless given, c_start = log2(x_max / Y_max) and
//! c_stop = log2(x_max / Y_median), where Y is the reference's luminance (0.2126 R +
//! 0.7152 G + 0.0722 B), Y_median the element at index ⌊n/2⌋ of the sorted luminances, and
//! x_max the larger root of tonemap(x) = 0.85. The one deviation: when Y_median is 0 (more
//! than half the reference black), where the reference implementation would loop over an
//! infinite exposure range, the smallest nonzero luminance is used instead; an all-black
//! reference gives one exposure, 0.

use crate::color::Rgb;
use rayon::prelude::*;

const PI: f32 = std::f32::consts::PI;
/// ꟻLIP's constants (gqc, gpc, gpt, gw, gqf in the paper).
const GQC: f32 = 0.7;
const GPC: f32 = 0.4;
const GPT: f32 = 0.95;
const GW: f32 = 0.082;
const GQF: f32 = 0.5;

/// Pixels per degree of visual angle for a viewer `distance_m` from a monitor `width_px`
/// pixels and `width_m` metres wide (ꟻLIP's `calculatePPD`).
pub fn pixels_per_degree(distance_m: f32, width_px: f32, width_m: f32) -> f32 {
    distance_m * (width_px / width_m) * (PI / 180.0)
}

/// ꟻLIP's default viewing condition: 0.7 m from a 0.7 m wide, 3840-pixel monitor
/// (≈ 67.02 pixels per degree).
pub fn default_ppd() -> f32 {
    pixels_per_degree(0.7, 3840.0, 0.7)
}

/// Tone mapper of HDR-ꟻLIP.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMapper {
    /// Reinhard on luminance: c / (1 + Y).
    Reinhard,
    /// ACES filmic fit (Narkowicz), with ꟻLIP's 0.6 pre-exposure cancellation. The default.
    #[default]
    Aces,
    /// Hable (Uncharted 2).
    Hable,
}

impl ToneMapper {
    /// (x² a + x b + c) / (x² d + x e + f) coefficients (ꟻLIP's table).
    fn coefficients(self) -> [f32; 6] {
        match self {
            ToneMapper::Reinhard => [0.0, 1.0, 0.0, 0.0, 1.0, 1.0],
            ToneMapper::Aces => [
                0.6 * 0.6 * 2.51,
                0.6 * 0.03,
                0.0,
                0.6 * 0.6 * 2.43,
                0.6 * 0.59,
                0.14,
            ],
            ToneMapper::Hable => [0.231683, 0.013791, 0.0, 0.18, 0.3, 0.018],
        }
    }

    fn apply(self, c: Rgb) -> Rgb {
        if self == ToneMapper::Reinhard {
            let y = luminance(c);
            return c * (1.0 / (1.0 + y));
        }
        let t = self.coefficients();
        let f = |x: f32| (x * x * t[0] + x * t[1] + t[2]) / (x * x * t[3] + x * t[4] + t[5]);
        Rgb::new(f(c.x), f(c.y), f(c.z))
    }
}

/// Settings of HDR-ꟻLIP; `None` exposures are computed from the reference.
#[derive(Clone, Debug)]
pub struct HdrSettings {
    /// Pixels per degree (default [`default_ppd`]).
    pub ppd: f32,
    pub start_exposure: Option<f32>,
    pub stop_exposure: Option<f32>,
    pub num_exposures: Option<u32>,
    pub tone_mapper: ToneMapper,
}

impl Default for HdrSettings {
    fn default() -> Self {
        HdrSettings {
            ppd: default_ppd(),
            start_exposure: None,
            stop_exposure: None,
            num_exposures: None,
            tone_mapper: ToneMapper::Aces,
        }
    }
}

/// A ꟻLIP error map: one value in [0, 1] per pixel, row-major.
#[derive(Clone, Debug)]
pub struct FlipMap {
    pub width: usize,
    pub height: usize,
    pub errors: Vec<f32>,
    /// HDR-ꟻLIP: the exposures used (start, stop, count); `None` for LDR-ꟻLIP.
    pub exposures: Option<(f32, f32, u32)>,
}

impl FlipMap {
    /// Mean error over pixels (accumulated in f64): the number ꟻLIP reports.
    pub fn mean(&self) -> f64 {
        if self.errors.is_empty() {
            return 0.0;
        }
        self.errors.iter().map(|&e| f64::from(e)).sum::<f64>() / self.errors.len() as f64
    }

    /// The map through ꟻLIP's magma colour map, as 8-bit display RGB (what the ꟻLIP tool
    /// writes): entry ⌊255 e + 0.5⌋.
    pub fn magma_rgb8(&self) -> Vec<[u8; 3]> {
        self.errors.iter().map(|&e| magma_rgb8(e)).collect()
    }
}

/// Colour of error `e` ∈ [0, 1] in the magma map, 8-bit display RGB.
pub fn magma_rgb8(e: f32) -> [u8; 3] {
    let i = ((e * 255.0 + 0.5) as i64).rem_euclid(256) as usize;
    let c = super::magma::MAGMA[i];
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
}

#[inline]
fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

const WHITE: Rgb = Rgb::new(0.950_428_55, 1.0, 1.088_900_4);
const INV_WHITE: Rgb = Rgb::new(1.052_156_9, 1.0, 0.918_357_7);

fn linear_rgb_to_xyz(c: Rgb) -> Rgb {
    let a11 = 10135552.0f32 / 24577794.0;
    let a12 = 8788810.0f32 / 24577794.0;
    let a13 = 4435075.0f32 / 24577794.0;
    let a21 = 2613072.0f32 / 12288897.0;
    let a22 = 8788810.0f32 / 12288897.0;
    let a23 = 887015.0f32 / 12288897.0;
    let a31 = 1425312.0f32 / 73733382.0;
    let a32 = 8788810.0f32 / 73733382.0;
    let a33 = 70074185.0f32 / 73733382.0;
    Rgb::new(
        a11 * c.x + a12 * c.y + a13 * c.z,
        a21 * c.x + a22 * c.y + a23 * c.z,
        a31 * c.x + a32 * c.y + a33 * c.z,
    )
}

fn xyz_to_linear_rgb(c: Rgb) -> Rgb {
    Rgb::new(
        3.241_003_3 * c.x - 1.537_398_9 * c.y - 0.498_615_87 * c.z,
        -0.969_224_33 * c.x + 1.875_930_1 * c.y + 0.041_554_224 * c.z,
        0.055_639_423 * c.x - 0.204_011_2 * c.y + 1.057_148_9 * c.z,
    )
}

fn xyz_to_ycxcz(c: Rgb) -> Rgb {
    let c = c * INV_WHITE;
    Rgb::new(116.0 * c.y - 16.0, 500.0 * (c.x - c.y), 200.0 * (c.y - c.z))
}

fn ycxcz_to_xyz(c: Rgb) -> Rgb {
    let y = (c.x + 16.0) / 116.0;
    let cx = c.y / 500.0;
    let cz = c.z / 200.0;
    Rgb::new(y + cx, y, y - cz) * WHITE
}

fn xyz_to_lab(c: Rgb) -> Rgb {
    let delta = 6.0f32 / 29.0;
    let delta_sq = delta * delta;
    let delta_cube = delta * delta_sq;
    let factor = 1.0 / (3.0 * delta_sq);
    let term = 4.0f32 / 29.0;
    let c = c * INV_WHITE;
    let f = |v: f32| {
        if v > delta_cube {
            v.powf(1.0 / 3.0)
        } else {
            factor * v + term
        }
    };
    let (x, y, z) = (f(c.x), f(c.y), f(c.z));
    Rgb::new(116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z))
}

#[inline]
fn hunt(lab: Rgb) -> Rgb {
    Rgb::new(lab.x, 0.01 * lab.x * lab.y, 0.01 * lab.x * lab.z)
}

#[inline]
fn hyab(a: Rgb, b: Rgb) -> f32 {
    let dl = (a.x - b.x).abs();
    let da = a.y - b.y;
    let db = a.z - b.z;
    dl + (da * da + db * db).sqrt()
}

fn max_distance() -> f32 {
    let green = hunt(xyz_to_lab(linear_rgb_to_xyz(Rgb::new(0.0, 1.0, 0.0))));
    let blue = hunt(xyz_to_lab(linear_rgb_to_xyz(Rgb::new(0.0, 0.0, 1.0))));
    hyab(green, blue).powf(GQC)
}

/// 1D Gaussian in the paper's form a·√(π/b)·exp(−π² x² / b).
fn gaussian_ab(x2: f32, a: f32, b: f32) -> f32 {
    a * (PI / b).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// Square root of the amplitude of [`gaussian_ab`] (for separating a sum of Gaussians).
fn gaussian_ab_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    (a * (PI / b).sqrt()).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// (a1, b1) for Y, Cx, Cz; (a2, b2) second Gaussian (used by Cz only).
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2: [f32; 3] = [0.0, 0.0, 13.5];
const B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];

/// Spatial (CSF) filters: per tap (wY, wCx) and (wCz1, wCz2).
fn spatial_filters(ppd: f32) -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    let max_b = B1.iter().chain(B2.iter()).cloned().fold(f32::MIN, f32::max);
    let radius = (3.0 * (max_b / (2.0 * PI * PI)).sqrt() * ppd).ceil() as i32;
    let dx = 1.0 / ppd;
    let mut ycx = Vec::new();
    let mut cz = Vec::new();
    let (mut s_ycx, mut s_cz) = ([0.0f32; 2], [0.0f32; 2]);
    for i in 0..(2 * radius + 1) {
        let x = (i - radius) as f32 * dx;
        let x2 = x * x;
        let v = [gaussian_ab(x2, A1[0], B1[0]), gaussian_ab(x2, A1[1], B1[1])];
        let w = [
            gaussian_ab_sqrt(x2, A1[2], B1[2]),
            gaussian_ab_sqrt(x2, A2[2], B2[2]),
        ];
        s_ycx[0] += v[0];
        s_ycx[1] += v[1];
        s_cz[0] += w[0];
        s_cz[1] += w[1];
        ycx.push(v);
        cz.push(w);
    }
    let n_ycx = [1.0 / s_ycx[0], 1.0 / s_ycx[1]];
    let n_cz = 1.0 / (s_cz[0] * s_cz[0] + s_cz[1] * s_cz[1]).sqrt();
    for v in &mut ycx {
        v[0] *= n_ycx[0];
        v[1] *= n_ycx[1];
    }
    for w in &mut cz {
        w[0] *= n_cz;
        w[1] *= n_cz;
    }
    (ycx, cz)
}

/// Feature filter taps (Gaussian, first derivative, second derivative).
fn feature_filter(ppd: f32) -> Vec<[f32; 3]> {
    let sd = 0.5 * GW * ppd;
    let radius = (3.0 * sd).ceil() as i32;
    let mut taps = Vec::new();
    let (mut g_sum, mut dg_neg, mut dg_pos, mut ddg_neg, mut ddg_pos) =
        (0.0f32, 0.0, 0.0, 0.0, 0.0);
    for i in 0..(2 * radius + 1) {
        let x = (i - radius) as f32;
        let g = (-(x * x) / (2.0 * sd * sd)).exp();
        g_sum += g;
        let dg = -x * g;
        if dg > 0.0 {
            dg_pos += dg;
        } else {
            dg_neg -= dg;
        }
        let ddg = (x * x / (sd * sd) - 1.0) * g;
        if ddg > 0.0 {
            ddg_pos += ddg;
        } else {
            ddg_neg -= ddg;
        }
        taps.push([g, dg, ddg]);
    }
    for t in &mut taps {
        t[0] /= g_sum;
        t[1] /= if t[1] > 0.0 { dg_pos } else { dg_neg };
        t[2] /= if t[2] > 0.0 { ddg_pos } else { ddg_neg };
    }
    taps
}

/// Runs `f(y, row)` for every row of a `w × h` output in parallel.
fn rows<T: Send + Default + Clone>(
    w: usize,
    h: usize,
    f: impl Fn(usize, &mut [T]) + Sync,
) -> Vec<T> {
    let mut out = vec![T::default(); w * h];
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row)| f(y, row));
    out
}

/// LDR-ꟻLIP of two linear-RGB images already clamped to [0, 1]; returns per-pixel errors.
fn ldr_flip_errors(reference: &[Rgb], test: &[Rgb], w: usize, h: usize, ppd: f32) -> Vec<f32> {
    let r: Vec<Rgb> = reference
        .iter()
        .map(|&c| xyz_to_ycxcz(linear_rgb_to_xyz(c)))
        .collect();
    let t: Vec<Rgb> = test
        .iter()
        .map(|&c| xyz_to_ycxcz(linear_rgb_to_xyz(c)))
        .collect();

    // Colour pipeline: separable CSF filtering, then the colour difference.
    let (f_ycx, f_cz) = spatial_filters(ppd);
    let half = (f_ycx.len() / 2) as i64;
    let clampx = |x: i64| x.clamp(0, w as i64 - 1) as usize;
    let clampy = |y: i64| y.clamp(0, h as i64 - 1) as usize;
    // Per pixel: [ref YCx (2), ref Cz (2), test YCx (2), test Cz (2)].
    let inter: Vec<[f32; 8]> = rows(w, h, |y, row| {
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = [0.0f32; 8];
            for k in -half..=half {
                let xx = clampx(x as i64 + k);
                let wy = f_ycx[(k + half) as usize];
                let wc = f_cz[(k + half) as usize];
                let rc = r[y * w + xx];
                let tc = t[y * w + xx];
                acc[0] += wy[0] * rc.x;
                acc[1] += wy[1] * rc.y;
                acc[2] += wc[0] * rc.z;
                acc[3] += wc[1] * rc.z;
                acc[4] += wy[0] * tc.x;
                acc[5] += wy[1] * tc.y;
                acc[6] += wc[0] * tc.z;
                acc[7] += wc[1] * tc.z;
            }
            *out = acc;
        }
    });
    let cmax = max_distance();
    let pccmax = GPC * cmax;
    let color_diff: Vec<f32> = rows(w, h, |y, row| {
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = [0.0f32; 8];
            for k in -half..=half {
                let yy = clampy(y as i64 + k);
                let wy = f_ycx[(k + half) as usize];
                let wc = f_cz[(k + half) as usize];
                let p = &inter[yy * w + x];
                acc[0] += wy[0] * p[0];
                acc[1] += wy[1] * p[1];
                acc[2] += wc[0] * p[2];
                acc[3] += wc[1] * p[3];
                acc[4] += wy[0] * p[4];
                acc[5] += wy[1] * p[5];
                acc[6] += wc[0] * p[6];
                acc[7] += wc[1] * p[7];
            }
            let to_lab = |c: Rgb| {
                let rgb = xyz_to_linear_rgb(ycxcz_to_xyz(c)).clamp(Rgb::ZERO, Rgb::ONE);
                hunt(xyz_to_lab(linear_rgb_to_xyz(rgb)))
            };
            let rl = to_lab(Rgb::new(acc[0], acc[1], acc[2] + acc[3]));
            let tl = to_lab(Rgb::new(acc[4], acc[5], acc[6] + acc[7]));
            let mut d = hyab(rl, tl).powf(GQC);
            if d < pccmax {
                d *= GPT / pccmax;
            } else {
                d = GPT + ((d - pccmax) / (cmax - pccmax)) * (1.0 - GPT);
            }
            *out = d;
        }
    });

    // Feature pipeline on normalised achromatic values.
    let ff = feature_filter(ppd);
    let fh = (ff.len() / 2) as i64;
    let ry: Vec<f32> = r
        .iter()
        .map(|c| c.x * (1.0 / 116.0) + 16.0 / 116.0)
        .collect();
    let ty: Vec<f32> = t
        .iter()
        .map(|c| c.x * (1.0 / 116.0) + 16.0 / 116.0)
        .collect();
    // Per pixel: [ref dx, ref ddx, ref g, test dx, test ddx, test g].
    let inter_f: Vec<[f32; 6]> = rows(w, h, |y, row| {
        for (x, out) in row.iter_mut().enumerate() {
            let mut a = [0.0f32; 6];
            for k in -fh..=fh {
                let xx = clampx(x as i64 + k);
                let wt = ff[(k + fh) as usize];
                let (rv, tv) = (ry[y * w + xx], ty[y * w + xx]);
                a[0] += wt[1] * rv;
                a[1] += wt[2] * rv;
                a[2] += wt[0] * rv;
                a[3] += wt[1] * tv;
                a[4] += wt[2] * tv;
                a[5] += wt[0] * tv;
            }
            *out = a;
        }
    });
    let norm = 1.0 / 2.0f32.sqrt();
    rows(w, h, |y, row| {
        for (x, out) in row.iter_mut().enumerate() {
            // [dx, ddx, dy, ddy] for reference then test.
            let mut a = [0.0f32; 8];
            for k in -fh..=fh {
                let yy = clampy(y as i64 + k);
                let wt = ff[(k + fh) as usize];
                let p = &inter_f[yy * w + x];
                a[0] += wt[0] * p[0];
                a[1] += wt[0] * p[1];
                a[2] += wt[1] * p[2];
                a[3] += wt[2] * p[2];
                a[4] += wt[0] * p[3];
                a[5] += wt[0] * p[4];
                a[6] += wt[1] * p[5];
                a[7] += wt[2] * p[5];
            }
            let edge_r = (a[0] * a[0] + a[2] * a[2]).sqrt();
            let edge_t = (a[4] * a[4] + a[6] * a[6]).sqrt();
            let point_r = (a[1] * a[1] + a[3] * a[3]).sqrt();
            let point_t = (a[5] * a[5] + a[7] * a[7]).sqrt();
            let fd = (norm * (edge_r - edge_t).abs().max((point_r - point_t).abs())).powf(GQF);
            *out = color_diff[y * w + x].powf(1.0 - fd);
        }
    })
}

fn check(reference: &[Rgb], test: &[Rgb], w: usize, h: usize) {
    assert!(
        reference.len() == w * h && test.len() == w * h,
        "FLIP: images must both be {w}x{h} ({} and {} pixels given)",
        reference.len(),
        test.len()
    );
}

/// LDR-ꟻLIP of two linear-RGB images (values clamped to [0, 1] first, as ꟻLIP does) at
/// `ppd` pixels per degree. (For sRGB-encoded inputs decode them to linear first, as
/// `flip-evaluator` does with `inputsRGB=True`.)
///
/// # Panics
/// When either image does not have `width × height` pixels.
pub fn flip_ldr(reference: &[Rgb], test: &[Rgb], width: usize, height: usize, ppd: f32) -> FlipMap {
    check(reference, test, width, height);
    let clamp =
        |v: &[Rgb]| -> Vec<Rgb> { v.iter().map(|c| c.clamp(Rgb::ZERO, Rgb::ONE)).collect() };
    let errors = if width * height == 0 {
        Vec::new()
    } else {
        ldr_flip_errors(&clamp(reference), &clamp(test), width, height, ppd)
    };
    FlipMap {
        width,
        height,
        errors,
        exposures: None,
    }
}

/// HDR-ꟻLIP's automatic exposure range from the reference: (c_start, c_stop) (see the
/// module doc, including the one deviation for a mostly black reference).
pub fn auto_exposures(reference: &[Rgb], tone_mapper: ToneMapper) -> (f32, f32) {
    let tc = tone_mapper.coefficients();
    let t = 0.85f32;
    let a = tc[0] - t * tc[3];
    let b = tc[1] - t * tc[4];
    let c = tc[2] - t * tc[5];
    let x_max = if a == 0.0 {
        -c / b
    } else {
        let d1 = -0.5 * (b / a);
        let d2 = (d1 * d1 - c / a).sqrt();
        d1 + d2
    };
    let mut lum: Vec<f32> = reference.iter().map(|&p| luminance(p)).collect();
    if lum.is_empty() {
        return (0.0, 0.0);
    }
    let y_max = lum.iter().cloned().fold(-1e30f32, f32::max);
    let y_min = lum
        .iter()
        .cloned()
        .filter(|&l| l != 0.0)
        .fold(1e30f32, f32::min);
    let mid = lum.len() / 2;
    let (_, median, _) = lum.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    let mut y_median = *median;
    if !(y_max > 0.0) {
        return (0.0, 0.0);
    }
    if !(y_median > 0.0) {
        y_median = y_min;
    }
    ((x_max / y_max).log2(), (x_max / y_median).log2())
}

/// HDR-ꟻLIP of two linear-RGB images (negative values are set to 0 first, as the peers'
/// `metrics.py` does before calling `flip-evaluator`).
///
/// # Panics
/// When either image does not have `width × height` pixels, or the given start exposure
/// exceeds the stop exposure.
pub fn flip_hdr(
    reference: &[Rgb],
    test: &[Rgb],
    width: usize,
    height: usize,
    settings: &HdrSettings,
) -> FlipMap {
    check(reference, test, width, height);
    let pos = |v: &[Rgb]| -> Vec<Rgb> { v.iter().map(|c| c.max(Rgb::ZERO)).collect() };
    let (r, t) = (pos(reference), pos(test));
    let (mut start, mut stop) = (settings.start_exposure, settings.stop_exposure);
    if start.is_none() || stop.is_none() {
        let (s0, s1) = auto_exposures(&r, settings.tone_mapper);
        start = start.or(Some(s0));
        stop = stop.or(Some(s1));
    }
    let (start, stop) = (start.unwrap(), stop.unwrap());
    assert!(
        start <= stop,
        "FLIP: start exposure {start} above stop exposure {stop}"
    );
    let n = settings
        .num_exposures
        .unwrap_or_else(|| (stop - start).ceil().max(2.0) as u32)
        .max(1);
    let step = if n > 1 {
        (stop - start) / (n - 1) as f32
    } else {
        0.0
    };
    let mut errors = vec![0.0f32; width * height];
    if width * height > 0 {
        for i in 0..n {
            let e = start + i as f32 * step;
            let m = 2.0f32.powf(e);
            let ldr = |v: &[Rgb]| -> Vec<Rgb> {
                v.iter()
                    .map(|&c| settings.tone_mapper.apply(c * m).clamp(Rgb::ZERO, Rgb::ONE))
                    .collect()
            };
            let err = ldr_flip_errors(&ldr(&r), &ldr(&t), width, height, settings.ppd);
            for (acc, v) in errors.iter_mut().zip(err) {
                if v > *acc {
                    *acc = v;
                }
            }
        }
    }
    FlipMap {
        width,
        height,
        errors,
        exposures: Some((start, stop, n)),
    }
}
