//! χ² goodness-of-fit machinery shared by the BSDF and light tests (after Mitsuba's
//! chi2.py): incomplete gamma, histograms over directions (the whole sphere, or a spherical
//! cap around an axis for small targets such as far triangle lights), expected counts by
//! quadrature, and the pooled χ² p-value.

use chronolux_core::math::Vec3;
use glam::DVec3;
use std::f64::consts::PI;

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9; ~1e-15 relative).
pub fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma Q(a, x) = Γ(a, x)/Γ(a) (series for x < a + 1,
/// Lentz continued fraction otherwise; Numerical Recipes §6.2).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let ln_pre = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut ap, mut del) = (a, 1.0 / a);
        let mut sum = del;
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * ln_pre.exp()
    } else {
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        ln_pre.exp() * h
    }
}

#[test]
fn incomplete_gamma_matches_known_values() {
    // Q(1, x) = e^−x; Q(1/2, x) = erfc(√x); erfc(1) = 0.157299207050285. Tolerances: the
    // series/fraction stop at 1e-15 relative; 1e-10 leaves room for ln Γ rounding.
    for x in [0.1, 1.0, 3.0, 20.0] {
        assert!((gamma_q(1.0, x) - (-x).exp()).abs() < 1e-10);
    }
    assert!((gamma_q(0.5, 1.0) - 0.157_299_207_050_285).abs() < 1e-10);
    // χ² with 10 dof at 18.307 has upper tail 0.05 (standard table value, 4 digits).
    assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4);
    assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-10);
}

/// Histogram resolution over (cos θ, φ): odd in cos θ (Mitsuba's choice; the equator lies
/// inside the middle row, so both hemispheres' pdfs are integrated consistently), and
/// `SUB` (even) Simpson sub-intervals per cell and axis for the expected counts.
pub const N_COS: usize = 31;
pub const N_PHI: usize = 61;
pub const SUB: usize = 16;

pub fn cell_of(w: Vec3) -> usize {
    let z = w.z.clamp(-1.0, 1.0) as f64;
    let phi = (w.y as f64).atan2(w.x as f64).rem_euclid(2.0 * PI);
    let i = (((z + 1.0) / 2.0 * N_COS as f64) as usize).min(N_COS - 1);
    let j = ((phi / (2.0 * PI) * N_PHI as f64) as usize).min(N_PHI - 1);
    i * N_PHI + j
}

/// ∫ pdf over every cell (composite Simpson in (cos θ, φ), where dω = dcos θ dφ).
pub fn integrate_cells(pdf: impl Fn(Vec3) -> f64) -> Vec<f64> {
    let (nz, np) = (N_COS * SUB + 1, N_PHI * SUB + 1);
    let (hz, hp) = (2.0 / (N_COS * SUB) as f64, 2.0 * PI / (N_PHI * SUB) as f64);
    let mut vals = vec![0.0f64; nz * np];
    for a in 0..nz {
        let z = (-1.0 + a as f64 * hz).clamp(-1.0, 1.0);
        let r = (1.0 - z * z).max(0.0).sqrt();
        for b in 0..np {
            let phi = b as f64 * hp;
            let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            vals[a * np + b] = pdf(w);
        }
    }
    let sw = |k: usize| {
        if k == 0 || k == SUB {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        }
    };
    let mut cells = vec![0.0; N_COS * N_PHI];
    for i in 0..N_COS {
        for j in 0..N_PHI {
            let mut s = 0.0;
            for a in 0..=SUB {
                for b in 0..=SUB {
                    s += sw(a) * sw(b) * vals[(i * SUB + a) * np + j * SUB + b];
                }
            }
            cells[i * N_PHI + j] = s * hz * hp / 9.0;
        }
    }
    cells
}

/// χ² p-value of observed against expected counts. Cells with expected count < 5 are pooled
/// (the χ² approximation needs it). `extra` is one more (observed, expected) cell, used for
/// samples that the histogram does not hold (e.g. samples lost by `sample`); it counts only
/// when its expectation is ≥ 5. A cell with expectation 0 but observations fails outright
/// (p = 0).
pub fn pooled_p_value(obs: &[f64], exp: &[f64], extra: Option<(f64, f64)>) -> f64 {
    let mut idx: Vec<usize> = (0..exp.len()).collect();
    idx.sort_by(|&a, &b| exp[a].total_cmp(&exp[b]));
    let (mut chsq, mut dof) = (0.0, 0i64);
    let (mut pool_obs, mut pool_exp, mut pooled) = (0.0, 0.0, 0);
    for &i in &idx {
        if exp[i] == 0.0 && obs[i] > 0.0 {
            return 0.0;
        }
        if exp[i] < 5.0 || (pooled > 0 && pool_exp < 5.0) {
            pool_obs += obs[i];
            pool_exp += exp[i];
            pooled += 1;
        } else {
            chsq += (obs[i] - exp[i]).powi(2) / exp[i];
            dof += 1;
        }
    }
    if pool_exp > 0.0 {
        chsq += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        dof += 1;
    }
    if let Some((o, e)) = extra
        && e >= 5.0
    {
        chsq += (o - e).powi(2) / e;
        dof += 1;
    }
    dof -= 1;
    if dof <= 0 {
        return 1.0;
    }
    gamma_q(dof as f64 / 2.0, chsq / 2.0)
}

/// A histogram over the directions of the spherical cap {w : w·axis ≥ z_min}, in cells
/// equal in solid angle: `n_cos` rows uniform in w·axis, `n_phi` columns uniform in
/// azimuth. With `z_min = −1` it is the whole sphere.
pub struct CapGrid {
    s: DVec3,
    t: DVec3,
    n: DVec3,
    pub z_min: f64,
    pub n_cos: usize,
    pub n_phi: usize,
}

/// Midpoint-rule cell integrals of a possibly discontinuous density (see
/// [`CapGrid::integrate_midpoint`]).
pub struct CellIntegrals {
    /// ∫ pdf over each cell.
    pub value: Vec<f64>,
    /// Per cell, a bound on the error of `value` from sub-cells the support boundary
    /// crosses (area × largest pdf seen in the sub-cell).
    pub boundary: Vec<f64>,
}

impl CapGrid {
    pub fn new(axis: Vec3, z_min: f64, n_cos: usize, n_phi: usize) -> Self {
        let n = axis.as_dvec3().normalize();
        let s = if n.x.abs() > 0.5 { DVec3::Y } else { DVec3::X };
        let s = (s - n * n.dot(s)).normalize();
        let t = n.cross(s);
        CapGrid {
            s,
            t,
            n,
            z_min: z_min.clamp(-1.0, 1.0),
            n_cos,
            n_phi,
        }
    }

    pub fn cells(&self) -> usize {
        self.n_cos * self.n_phi
    }

    /// Cell of a direction, `None` outside the cap.
    pub fn cell(&self, w: Vec3) -> Option<usize> {
        let w = w.as_dvec3();
        let z = w.dot(self.n).clamp(-1.0, 1.0);
        if z < self.z_min {
            return None;
        }
        let phi = w.dot(self.t).atan2(w.dot(self.s)).rem_euclid(2.0 * PI);
        let i = (((z - self.z_min) / (1.0 - self.z_min) * self.n_cos as f64) as usize)
            .min(self.n_cos - 1);
        let j = ((phi / (2.0 * PI) * self.n_phi as f64) as usize).min(self.n_phi - 1);
        Some(i * self.n_phi + j)
    }

    /// Direction at cap coordinates (z = w·axis, φ).
    pub fn dir(&self, z: f64, phi: f64) -> DVec3 {
        let z = z.clamp(-1.0, 1.0);
        let r = (1.0 - z * z).max(0.0).sqrt();
        self.s * (r * phi.cos()) + self.t * (r * phi.sin()) + self.n * z
    }

    /// Grid coordinates (z, φ) of a direction.
    fn coords(&self, w: DVec3) -> (f64, f64) {
        (
            w.dot(self.n).clamp(-1.0, 1.0),
            w.dot(self.t).atan2(w.dot(self.s)).rem_euclid(2.0 * PI),
        )
    }

    /// ∫ pdf over every cell by the midpoint rule on `sub × sub` sub-cells per cell (dω =
    /// dz dφ, so sub-cells are equal in solid angle). Meant for densities with a jump at
    /// the edge of their support (pdf = 0 outside), given as dense points along that edge
    /// (`edge`, may be empty): a sub-cell counts as crossed by the edge when its centre and
    /// four corners disagree on pdf > 0 or an edge point lies in it; crossed sub-cells are
    /// refined [`REFINE`]× per axis, [`LEVELS`] times, and each crossed leaf's area × the
    /// largest pdf seen there bounds its error. Not bounded: edges that cross a leaf
    /// between two edge points without changing any of its five values (a corner clipped
    /// by less than the edge-point spacing), and the O(h²) midpoint error of the smooth
    /// density inside the support.
    pub fn integrate_midpoint(
        &self,
        sub: usize,
        pdf: impl Fn(DVec3) -> f64,
        edge: &[DVec3],
    ) -> CellIntegrals {
        let (nz, np) = (self.n_cos * sub, self.n_phi * sub);
        let hz = (1.0 - self.z_min) / nz as f64;
        let hp = 2.0 * PI / np as f64;
        let at = |z: f64, phi: f64| pdf(self.dir(z, phi));
        let mut marks: std::collections::HashMap<(usize, usize), Vec<(f64, f64)>> =
            Default::default();
        for &w in edge {
            let (z, phi) = self.coords(w);
            if z < self.z_min {
                continue;
            }
            let a = (((z - self.z_min) / hz) as usize).min(nz - 1);
            let b = ((phi / hp) as usize).min(np - 1);
            marks.entry((a, b)).or_default().push((z, phi));
        }
        // Corner lattice ((nz+1) × (np+1), the last column repeats the first).
        let mut corner = vec![0.0f64; (nz + 1) * (np + 1)];
        for a in 0..=nz {
            let z = self.z_min + a as f64 * hz;
            for b in 0..=np {
                corner[a * (np + 1) + b] = if b == np {
                    corner[a * (np + 1)]
                } else {
                    at(z, b as f64 * hp)
                };
            }
        }
        let mut value = vec![0.0; self.cells()];
        let mut boundary = vec![0.0; self.cells()];
        for a in 0..nz {
            let z0 = self.z_min + a as f64 * hz;
            for b in 0..np {
                let c = at(z0 + 0.5 * hz, (b as f64 + 0.5) * hp);
                let k = [
                    corner[a * (np + 1) + b],
                    corner[a * (np + 1) + b + 1],
                    corner[(a + 1) * (np + 1) + b],
                    corner[(a + 1) * (np + 1) + b + 1],
                ];
                let pts = marks.get(&(a, b)).map_or(&[][..], |v| &v[..]);
                let cell = (a / sub) * self.n_phi + b / sub;
                let (v, e) = sub_cell(&at, z0, b as f64 * hp, hz, hp, c, k, pts, LEVELS);
                value[cell] += v;
                boundary[cell] += e;
            }
        }
        CellIntegrals { value, boundary }
    }
}

/// Refinement factor per axis of a sub-cell crossed by the support edge.
pub const REFINE: usize = 4;
/// Refinement levels.
pub const LEVELS: u32 = 3;

/// (midpoint integral, error bound) of the sub-cell [z0, z0+hz] × [p0, p0+hp], given its
/// centre value `c`, corner values `k` and the edge points inside it.
fn sub_cell(
    at: &impl Fn(f64, f64) -> f64,
    z0: f64,
    p0: f64,
    hz: f64,
    hp: f64,
    c: f64,
    k: [f64; 4],
    pts: &[(f64, f64)],
    levels: u32,
) -> (f64, f64) {
    let inside = c > 0.0;
    if pts.is_empty() && k.iter().all(|&v| (v > 0.0) == inside) {
        return (c * hz * hp, 0.0);
    }
    if levels == 0 {
        return (c * hz * hp, hz * hp * k.iter().fold(c, |m, &v| m.max(v)));
    }
    let r = REFINE;
    let (sz, sp) = (hz / r as f64, hp / r as f64);
    let mut corner = vec![0.0f64; (r + 1) * (r + 1)];
    for a in 0..=r {
        for b in 0..=r {
            corner[a * (r + 1) + b] = match (a, b) {
                (0, 0) => k[0],
                (0, _) if b == r => k[1],
                (_, 0) if a == r => k[2],
                _ if a == r && b == r => k[3],
                _ => at(z0 + a as f64 * sz, p0 + b as f64 * sp),
            };
        }
    }
    let mut child_pts: Vec<Vec<(f64, f64)>> = vec![Vec::new(); r * r];
    for &(z, phi) in pts {
        let a = (((z - z0) / sz).max(0.0) as usize).min(r - 1);
        let b = (((phi - p0) / sp).max(0.0) as usize).min(r - 1);
        child_pts[a * r + b].push((z, phi));
    }
    let (mut v, mut e) = (0.0, 0.0);
    for a in 0..r {
        for b in 0..r {
            let cc = at(z0 + (a as f64 + 0.5) * sz, p0 + (b as f64 + 0.5) * sp);
            let kk = [
                corner[a * (r + 1) + b],
                corner[a * (r + 1) + b + 1],
                corner[(a + 1) * (r + 1) + b],
                corner[(a + 1) * (r + 1) + b + 1],
            ];
            let (dv, de) = sub_cell(
                at,
                z0 + a as f64 * sz,
                p0 + b as f64 * sp,
                sz,
                sp,
                cc,
                kk,
                &child_pts[a * r + b],
                levels - 1,
            );
            v += dv;
            e += de;
        }
    }
    (v, e)
}
