//! The irradiance cache (Ward, Rubinstein, Clear 1988) with irradiance gradients (Ward &
//! Heckbert 1992), and the stratified final gather that makes its records.
//!
//! ## Records and weights
//! A record holds position `x_i`, normal `n_i`, irradiance `E_i` (RGB), the harmonic mean
//! distance `R_i` of its gather rays' hits, and per colour channel a rotational gradient
//! `∇r_i` and a translational gradient `∇t_i`. At a point `x` with normal `n` its error
//! measure is Ward's `ε_i = |x − x_i|/R_i + √(1 − n·n_i)`, its weight `w_i = 1/ε_i`; it is
//! valid when `ε_i < a` (the accuracy `a`) and it does not lie in front of `x`
//! (`(x − x_i)·(n + n_i)/2 ≥ −0.05 R_i`, Ward's test). The interpolated irradiance is
//!
//! `E(x) = Σ w_i (E_i + (n_i × n)·∇r_i + (x − x_i)·∇t_i) / Σ w_i` (each channel ≥ 0).
//!
//! ## Gather and gradients
//! [`gather`] samples the hemisphere around `n` in `M × N` strata of a cosine-weighted
//! parametrisation, `sin²θ = (j + ξ)/M`, `φ = 2π(k + ψ)/N`, so `E ≈ π/(MN) Σ L_jk`. The
//! gradients are Ward & Heckbert's (in the form of Křivánek et al. 2008, eqs. 2.7–2.8):
//!
//! - rotational: `∇r E = π/(MN) Σ_k v_k Σ_j tan θ_j L_jk` (`v_k` the tangent direction
//!   at `φ_k + π/2`). Ward & Heckbert write `−tan θ_j` with the opposite orientation of
//!   the rotation; with the extrapolation `(n_i × n)·∇r` used here the sign is `+`
//!   (checked against finite differences in `tests/it/pmic.rs`);
//! - translational: `∇t E = Σ_k [ u_k (2π/N) Σ_{j≥1} sin θ_j⁻ cos² θ_j⁻ / min(R_jk,
//!   R_{j−1,k}) (L_jk − L_{j−1,k}) + v_k⁻ Σ_j (sin θ_j⁺ − sin θ_j⁻) / min(R_jk, R_{j,k−1})
//!   (L_jk − L_{j,k−1}) ]`, with `θ_j^±` the stratum's θ-bounds, `u_k` the direction
//!   at `φ_k` and `v_k⁻` the tangent at the boundary `2πk/N + π/2`.
//!
//! ## Deviations and clamps
//! - `R_i` is clamped so that the validity radius `a·R_i` is between `r_min_px` and
//!   `r_max_px` pixel footprints at the record (Tabellion & Lamorlette 2004 clamp in
//!   pixels too), after limiting it by the translational gradient
//!   (`R_i ≤ E_i/|∇t E_i|`, luminance; Křivánek & Gautron 2009 §2.3.2) so a steep
//!   gradient shrinks the record's reach instead of extrapolating past zero; when the
//!   lower clamp then raises `R_i` again, the translational gradient is scaled down by
//!   the same factor, so `|∇t E_i|·R_i ≤ E_i` still holds.
//! - Spatial structure: a hashed multi-level grid (cell sizes doubling from a base); a
//!   record is stored at the level whose cell is at least its validity diameter `2aR_i`,
//!   in the ≤ 8 cells its validity sphere touches, so a query reads one cell per level
//!   in use. Ward's octree does the same job; the hash grid needs no rebalancing.

use chronolux_core::color::{Rgb, luminance};
use chronolux_core::math::cell_hash::CellMap;
use chronolux_core::math::{Frame, Vec3};
use std::f32::consts::PI;

/// One irradiance record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    pub p: Vec3,
    pub n: Vec3,
    pub e: Rgb,
    /// Harmonic mean distance after limiting and clamping.
    pub r: f32,
    /// Rotational gradient per channel (r, g, b).
    pub grad_r: [Vec3; 3],
    /// Translational gradient per channel.
    pub grad_t: [Vec3; 3],
}

impl Record {
    /// Ward's error measure at (x, n); `None` when the record is not usable there at all
    /// (behind the surface, or in front of x).
    #[inline]
    pub fn error(&self, x: Vec3, n: Vec3) -> Option<f32> {
        let c = n.dot(self.n);
        if c <= 0.0 {
            return None;
        }
        let d = x - self.p;
        if d.dot(n + self.n) * 0.5 < -0.05 * self.r {
            return None;
        }
        Some(d.length() / self.r + (1.0 - c).max(0.0).sqrt())
    }

    /// The record's irradiance extrapolated to (x, n) with its gradients.
    #[inline]
    pub fn extrapolate(&self, x: Vec3, n: Vec3) -> Rgb {
        let rot = self.n.cross(n);
        let d = x - self.p;
        Rgb::new(
            self.e.x + rot.dot(self.grad_r[0]) + d.dot(self.grad_t[0]),
            self.e.y + rot.dot(self.grad_r[1]) + d.dot(self.grad_t[1]),
            self.e.z + rot.dot(self.grad_r[2]) + d.dot(self.grad_t[2]),
        )
    }
}

/// The result of one final gather.
#[derive(Clone, Copy, Debug)]
pub struct Gather {
    pub e: Rgb,
    /// Harmonic mean distance of the hits (unclamped; `f32::INFINITY` if nothing was hit).
    pub r_harmonic: f32,
    pub grad_r: [Vec3; 3],
    pub grad_t: [Vec3; 3],
}

/// Stratified final gather over the hemisphere of `n` at `x`: `m × n_phi` rays, stratum
/// (j, k) jittered by `jitter(j, k) ∈ [0,1)²`; `trace(dir)` returns the radiance arriving
/// along `-dir` at x and the distance to the surface it comes from (`None`: nothing hit,
/// zero radiance and infinite distance). See the module doc for the formulas.
pub fn gather(
    n: Vec3,
    m: u32,
    n_phi: u32,
    mut jitter: impl FnMut(u32, u32) -> (f32, f32),
    mut trace: impl FnMut(Vec3) -> Option<(Rgb, f32)>,
) -> Gather {
    let (m, np) = (m.max(1), n_phi.max(1));
    let frame = Frame::from_normal(n);
    let mut l = vec![Rgb::ZERO; (m * np) as usize];
    let mut r = vec![f32::INFINITY; (m * np) as usize];
    let mut tan_theta = vec![0.0f32; (m * np) as usize];
    for j in 0..m {
        for k in 0..np {
            let (xi, psi) = jitter(j, k);
            let (dir, tan) = stratum_direction(&frame, m, np, j, k, xi, psi);
            let i = (j * np + k) as usize;
            tan_theta[i] = tan;
            if let Some((li, dist)) = trace(dir) {
                l[i] = li;
                r[i] = dist.max(1e-6);
            }
        }
    }
    gather_from_strata(&frame, m, np, &l, &r, &tan_theta)
}

/// Direction (world space) and `tan θ` of stratum (j, k) of an `m × n_phi` gather around
/// `frame`'s normal, jittered by (ξ, ψ) ∈ [0,1)² (see the module doc).
#[inline]
pub fn stratum_direction(
    frame: &Frame,
    m: u32,
    n_phi: u32,
    j: u32,
    k: u32,
    xi: f32,
    psi: f32,
) -> (Vec3, f32) {
    let s2 = ((j as f32 + xi) / m as f32).min(1.0 - 1e-7);
    let (st, ct) = (s2.sqrt(), (1.0 - s2).sqrt());
    let phi = 2.0 * PI * (k as f32 + psi) / n_phi as f32;
    let local = Vec3::new(st * phi.cos(), st * phi.sin(), ct);
    (frame.from_local(local).normalize(), st / ct)
}

/// Irradiance, harmonic mean distance and gradients of a gather from its strata: per
/// stratum `j·n_phi + k` the incident radiance `l`, the hit distance `r` (`∞`: nothing hit)
/// and `tan θ` of its direction; `frame` is [`Frame::from_normal`] of the gather's normal.
/// [`gather`] is this after tracing; the selective cache (`ic-selective`) calls it on
/// strata cast in different frames.
pub fn gather_from_strata(
    frame: &Frame,
    m: u32,
    np: u32,
    l: &[Rgb],
    r: &[f32],
    tan_theta: &[f32],
) -> Gather {
    let mut inv_r_sum = 0.0f64;
    for &ri in r {
        if ri.is_finite() {
            inv_r_sum += 1.0 / ri as f64;
        }
    }
    let scale = PI / (m * np) as f32;
    let mut e = Rgb::ZERO;
    for v in l {
        e += *v;
    }
    e *= scale;
    let r_harmonic = if inv_r_sum > 0.0 {
        ((m * np) as f64 / inv_r_sum) as f32
    } else {
        f32::INFINITY
    };
    // Gradients (per channel), in world space via the tangent frame.
    let mut gr = [Vec3::ZERO; 3];
    let mut gt = [Vec3::ZERO; 3];
    let at = |j: u32, k: u32| (j * np + k) as usize;
    for k in 0..np {
        let phi_c = 2.0 * PI * (k as f32 + 0.5) / np as f32;
        let u_k = frame.from_local(Vec3::new(phi_c.cos(), phi_c.sin(), 0.0));
        let v_k = frame.from_local(Vec3::new(-phi_c.sin(), phi_c.cos(), 0.0));
        let phi_b = 2.0 * PI * k as f32 / np as f32;
        let v_km = frame.from_local(Vec3::new(-phi_b.sin(), phi_b.cos(), 0.0));
        let km1 = (k + np - 1) % np;
        let mut rot = Rgb::ZERO;
        let mut theta_sum = Rgb::ZERO;
        let mut phi_sum = Rgb::ZERO;
        for j in 0..m {
            let i = at(j, k);
            rot += l[i] * tan_theta[i];
            let s_minus = (j as f32 / m as f32).sqrt();
            let s_plus = ((j + 1) as f32 / m as f32).sqrt();
            if j >= 1 {
                let c2 = 1.0 - j as f32 / m as f32;
                let rmin = r[i].min(r[at(j - 1, k)]);
                if rmin.is_finite() {
                    theta_sum += (l[i] - l[at(j - 1, k)]) * (s_minus * c2 / rmin);
                }
            }
            let rmin = r[i].min(r[at(j, km1)]);
            if rmin.is_finite() {
                phi_sum += (l[i] - l[at(j, km1)]) * ((s_plus - s_minus) / rmin);
            }
        }
        let theta_sum = theta_sum * (2.0 * PI / np as f32);
        for c in 0..3 {
            gr[c] += v_k * (rot[c] * scale);
            gt[c] += u_k * theta_sum[c] + v_km * phi_sum[c];
        }
    }
    Gather {
        e,
        r_harmonic,
        grad_r: gr,
        grad_t: gt,
    }
}

/// Parameters of a cache.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CacheParams {
    /// Ward's accuracy `a`: a record serves points with `ε < a`.
    pub accuracy: f32,
    /// Clamp of a record's validity radius `a·R`, in pixel footprints at the record (the
    /// harmonic mean distance `R` is clamped to `[r_min_px, r_max_px] · footprint / a`):
    /// at least one pixel, so a record made at a pixel centre serves the whole pixel.
    pub r_min_px: f32,
    pub r_max_px: f32,
}

impl Default for CacheParams {
    fn default() -> Self {
        CacheParams {
            accuracy: 0.2,
            r_min_px: 2.0,
            r_max_px: 16.0,
        }
    }
}

/// A record from a gather: the radius limited by the translational gradient, then clamped
/// to `[r_min, r_max]` (world units).
pub fn make_record(p: Vec3, n: Vec3, g: &Gather, r_min: f32, r_max: f32) -> Record {
    let mut r = g.r_harmonic;
    let e_lum = luminance(g.e);
    let g_lum = g.grad_t[0] * 0.2126 + g.grad_t[1] * 0.7152 + g.grad_t[2] * 0.0722;
    let gl = g_lum.length();
    if gl > 0.0 && e_lum > 0.0 {
        r = r.min(e_lum / gl);
    }
    let limited = r;
    let r = r.clamp(r_min, r_max.max(r_min));
    // A radius raised by the lower clamp must not extrapolate the gradient further than
    // the limit allowed: scale it down by the same factor (Křivánek & Gautron 2009).
    let mut grad_t = g.grad_t;
    if r > limited && limited.is_finite() && limited > 0.0 {
        let k = limited / r;
        grad_t = grad_t.map(|v| v * k);
    }
    Record {
        p,
        n,
        e: g.e,
        r,
        grad_r: g.grad_r,
        grad_t,
    }
}

const LEVELS: usize = 24;

/// The irradiance cache: records and a multi-level hash grid over them.
pub struct IrradianceCache {
    pub accuracy: f32,
    records: Vec<Record>,
    base_cell: f32,
    grid: CellMap<(u8, i32, i32, i32), Vec<u32>>,
    levels_used: u32,
}

impl IrradianceCache {
    /// An empty cache; `base_cell` is the smallest grid cell (world units, e.g. a small
    /// fraction of the scene size).
    pub fn new(accuracy: f32, base_cell: f32) -> Self {
        IrradianceCache {
            accuracy,
            records: Vec::new(),
            base_cell: base_cell.max(1e-9),
            grid: CellMap::default(),
            levels_used: 0,
        }
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    pub fn records(&self) -> &[Record] {
        &self.records
    }

    fn cell(&self, level: usize, p: Vec3) -> (u8, i32, i32, i32) {
        let s = self.base_cell * (1u64 << level) as f32;
        let c = (p / s).floor();
        (level as u8, c.x as i32, c.y as i32, c.z as i32)
    }

    /// Adds a record.
    pub fn insert(&mut self, rec: Record) {
        let id = self.records.len() as u32;
        let reach = self.accuracy * rec.r;
        let mut level = 0;
        while level + 1 < LEVELS && self.base_cell * ((1u64 << level) as f32) < 2.0 * reach {
            level += 1;
        }
        self.levels_used |= 1 << level;
        let lo = self.cell(level, rec.p - Vec3::splat(reach));
        let hi = self.cell(level, rec.p + Vec3::splat(reach));
        for x in lo.1..=hi.1 {
            for y in lo.2..=hi.2 {
                for z in lo.3..=hi.3 {
                    self.grid
                        .entry((level as u8, x, y, z))
                        .or_default()
                        .push(id);
                }
            }
        }
        self.records.push(rec);
    }

    /// Calls `f(record, ε)` for every record valid at (x, n) (`ε < a`).
    #[inline]
    pub fn for_valid(&self, x: Vec3, n: Vec3, mut f: impl FnMut(&Record, f32)) {
        self.for_valid_indexed(x, n, |_, rec, eps| f(rec, eps));
    }

    /// [`Self::for_valid`] with each record's index in [`Self::records`].
    #[inline]
    pub fn for_valid_indexed(&self, x: Vec3, n: Vec3, mut f: impl FnMut(usize, &Record, f32)) {
        for level in 0..LEVELS {
            if self.levels_used & (1 << level) == 0 {
                continue;
            }
            let Some(ids) = self.grid.get(&self.cell(level, x)) else {
                continue;
            };
            for &id in ids {
                let rec = &self.records[id as usize];
                if let Some(eps) = rec.error(x, n)
                    && eps < self.accuracy
                {
                    f(id as usize, rec, eps);
                }
            }
        }
    }

    /// Whether some record is valid at (x, n): [`Self::for_valid`]'s test, stopping at
    /// the first record that passes it.
    pub fn covers(&self, x: Vec3, n: Vec3) -> bool {
        (0..LEVELS).any(|level| {
            self.levels_used & (1 << level) != 0
                && self.grid.get(&self.cell(level, x)).is_some_and(|ids| {
                    ids.iter().any(|&id| {
                        self.records[id as usize]
                            .error(x, n)
                            .is_some_and(|eps| eps < self.accuracy)
                    })
                })
        })
    }

    /// Ward's interpolation at (x, n): the weighted irradiance and the weight sum, `None`
    /// when no record is valid there.
    pub fn interpolate(&self, x: Vec3, n: Vec3) -> Option<(Rgb, f32)> {
        let mut sum = Rgb::ZERO;
        let mut wsum = 0.0f32;
        self.for_valid(x, n, |rec, eps| {
            let w = 1.0 / eps.max(1e-6);
            sum += rec.extrapolate(x, n) * w;
            wsum += w;
        });
        (wsum > 0.0).then(|| ((sum / wsum).max(Rgb::ZERO), wsum))
    }
}
