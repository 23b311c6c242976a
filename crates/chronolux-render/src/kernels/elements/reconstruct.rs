//! From element photon sums to a smooth irradiance field.
//!
//! 1. **Element irradiance** `E_e = Φ_e / (N · A_e)` per element side (Φ_e: flux sum of the
//!    photons on it, N: photons emitted, A_e: its world area in this frame), with the noise
//!    estimate `σ_e = √(Σ φ²) / (N · A_e)` (φ: luminance flux of each photon; the photon
//!    count on an element is ~Poisson, so Var Σφ ≈ Σφ²).
//! 2. **Filtering** (optional) over neighbouring elements: a ratio estimator
//!    `E'_e = Σ_j w_ej Φ_j / (N Σ_j w_ej A_j)` with a spatial Gaussian `w = exp(−d²/2σ²)`
//!    (σ = radius / 2, cut at the radius, neighbours facing the same way: normals within
//!    ~25°), and for the bilateral filter a range kernel
//!    `exp(−(E_j − E_e)² / (2 κ² (σ_e² + σ_j²)))` on luminance. The range kernel's width
//!    comes from the estimates' own noise, so elements with few photons (large σ) relax
//!    towards the plain Gaussian, and below `min_photons` it is dropped altogether (the
//!    published fix for noisy small elements); a constant field is left unchanged by
//!    either filter (both are normalised averages).
//! 3. **Vertices**: each grid vertex takes the area-weighted mean of the irradiance of
//!    the elements around it; a point is shaded with the barycentric interpolation of its
//!    element's three vertices (continuous across elements and across triangles that
//!    share vertices).
//!
//! Bias: the vertex average spreads every element's value over its one-ring, i.e. the
//! solution is the true irradiance convolved with a kernel about two elements wide
//! (plus the filter's kernel). It vanishes where irradiance is linear across that support
//! and is of order `h² |∇²E|` elsewhere (h: element size), larger at shadow boundaries.

use super::element_map::{ElementAccumulators, ElementMesh, FrameElements, Located};
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::math::Vec3;
use chronolux_core::math::cell_hash::CellMap;
use chronolux_core::parallel;

/// Filtering of element estimates (radius in element sizes).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Filter {
    /// Plain density estimation per element.
    None,
    /// Spatial Gaussian over elements within `radius` element sizes.
    Gaussian { radius: f32 },
    /// Spatial bilateral: Gaussian in space, range kernel of width `kappa` noise standard
    /// deviations; plain Gaussian for elements with fewer than `min_photons` photons.
    Bilateral {
        radius: f32,
        kappa: f32,
        min_photons: u32,
    },
}

/// Minimum cosine between the normals of elements filtered together.
pub const NORMAL_COS: f32 = 0.9;

/// Neighbouring elements (within a world radius, facing the same way) of every element,
/// in compressed rows: `(element, squared distance)`, the element itself first, with the
/// spatial Gaussian weight of each entry (σ = radius / 2, see [`Neighbours::gauss`]).
/// Stored in chunks of 1024 elements, so that an update moves the chunks whose rows
/// did not change instead of copying them.
#[derive(Clone, Debug)]
pub struct Neighbours {
    pub radius: f32,
    chunks: Vec<Chunk>,
    rebuilt: usize,
}

/// One row of [`Neighbours`]: `(element, squared distance)`.
type Row = Vec<(u32, f32)>;

/// Elements per chunk of [`Neighbours`].
const CHUNK: usize = 1024;

/// Rows of `CHUNK` consecutive elements.
#[derive(Clone, Debug, Default)]
struct Chunk {
    offsets: Vec<u32>,
    items: Vec<(u32, f32)>,
    gauss: Vec<f32>,
}

impl Chunk {
    /// Rows of elements `range` of `fe`: rebuilt from `grid` where `dirty` (all when
    /// `old` is `None`), copied from `old` elsewhere; rows already built are taken from
    /// `pre` (sorted elements and their rows).
    fn build(
        fe: &FrameElements,
        grid: &Grid,
        range: std::ops::Range<usize>,
        old: Option<(&Chunk, &[bool])>,
        pre: (&[u32], &[Row]),
    ) -> Chunk {
        let r2 = grid.cell * grid.cell;
        let inv2s2 = gauss_inv2s2(grid.cell);
        let mut c = Chunk {
            offsets: Vec::with_capacity(range.len() + 1),
            ..Default::default()
        };
        c.offsets.push(0);
        let start = range.start;
        for e in range {
            match old {
                Some((o, dirty)) if !dirty[e] => {
                    let (a, b) = (
                        o.offsets[e - start] as usize,
                        o.offsets[e - start + 1] as usize,
                    );
                    c.items.extend_from_slice(&o.items[a..b]);
                    c.gauss.extend_from_slice(&o.gauss[a..b]);
                }
                _ => {
                    let from = c.items.len();
                    match pre.0.binary_search(&(e as u32)) {
                        Ok(i) => c.items.extend_from_slice(&pre.1[i]),
                        Err(_) => grid.row(fe, e, r2, &mut c.items),
                    }
                    // Rows are deterministic without sorting: grid buckets are filled in
                    // element order and visited in a fixed order. (They were sorted by
                    // element id before, a large share of `spacetime-dept`'s CPU in a
                    // profile of issue 17 whose figure BENCHMARKS.md does not keep.)
                    c.gauss
                        .extend(c.items[from..].iter().map(|&(_, d2)| (-d2 * inv2s2).exp()));
                }
            }
            c.offsets.push(c.items.len() as u32);
        }
        c
    }
}

/// `1 / (2σ²)` of the spatial Gaussian of a filter of radius `r` (σ = r / 2).
#[inline]
pub fn gauss_inv2s2(r: f32) -> f32 {
    1.0 / (2.0 * (0.5 * r) * (0.5 * r))
}

/// Uniform grid of element centroids (cell = the neighbour radius), buckets filled in
/// element order.
struct Grid {
    cell: f32,
    buckets: CellMap<(i32, i32, i32), Vec<u32>>,
}

impl Grid {
    fn new(fe: &FrameElements, radius: f32) -> Self {
        let mut g = Grid {
            cell: radius.max(1e-12),
            buckets: CellMap::default(),
        };
        for (e, c) in fe.centroid.iter().enumerate() {
            if fe.area[e] > 0.0 {
                g.buckets.entry(g.key(*c)).or_default().push(e as u32);
            }
        }
        g
    }

    #[inline]
    fn key(&self, p: Vec3) -> (i32, i32, i32) {
        let q = (p / self.cell).floor();
        (q.x as i32, q.y as i32, q.z as i32)
    }

    /// Calls `f` with every element in the 27 cells around `p`, in a fixed order.
    #[inline]
    fn around(&self, p: Vec3, mut f: impl FnMut(u32)) {
        let (x, y, z) = self.key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = self.buckets.get(&(x + dx, y + dy, z + dz)) {
                        list.iter().for_each(|&j| f(j));
                    }
                }
            }
        }
    }

    /// Row of `e` (itself first, then the grid elements within `r2` facing its way).
    #[inline]
    fn row(&self, fe: &FrameElements, e: usize, r2: f32, out: &mut Vec<(u32, f32)>) {
        let (c, nrm) = (fe.centroid[e], fe.normal[e]);
        out.push((e as u32, 0.0));
        self.around(c, |j| {
            if j as usize == e || fe.normal[j as usize].dot(nrm) < NORMAL_COS {
                return;
            }
            let d2 = (fe.centroid[j as usize] - c).length_squared();
            if d2 < r2 {
                out.push((j, d2));
            }
        });
    }
}

impl Neighbours {
    pub fn new(fe: &FrameElements, radius: f32) -> Self {
        let n = fe.centroid.len();
        let grid = Grid::new(fe, radius);
        let chunks = parallel::map_chunks(n, CHUNK, |range| {
            Chunk::build(fe, &grid, range, None, (&[], &[]))
        });
        Neighbours {
            radius,
            chunks,
            rebuilt: n,
        }
    }

    /// The lists of `new`, a later (or earlier) frame of the same element mesh, from
    /// these lists of `old`: only the rows of elements within the radius of an element
    /// that moved (centroid or normal changed, or its area became or stopped being
    /// positive), in either frame, are rebuilt; the others are kept. Validity comes from
    /// the elements' geometry (the animation), never from their light. The result is
    /// identical to `Neighbours::new(new, radius)`, row order included: a kept row holds
    /// only static elements, whose grid cells and bucket order (element order) are
    /// unchanged. The rebuilt count is [`Neighbours::rebuilt`].
    pub fn update(self, old: &FrameElements, new: &FrameElements) -> Self {
        let n = new.centroid.len();
        if old.centroid.len() != n {
            return Self::new(new, self.radius);
        }
        let moved: Vec<u32> = (0..n)
            .filter(|&e| {
                old.centroid[e] != new.centroid[e]
                    || old.normal[e] != new.normal[e]
                    || (old.area[e] > 0.0) != (new.area[e] > 0.0)
            })
            .map(|e| e as u32)
            .collect();
        if moved.is_empty() {
            return Neighbours { rebuilt: 0, ..self };
        }
        let grid = Grid::new(new, self.radius);
        let r2 = self.radius * self.radius;
        // The new rows of the moved elements, then the dirty rows: the moved elements,
        // every element without area (it is in no row, so found by no test below: rebuilt
        // always) and every element in a moved element's old or new row. That is enough:
        // for elements with area, e is in j's row exactly when j is in e's (distance and
        // normal test are symmetric), so a row that held or gains a moved element is that
        // of an element in the moved one's old or new row.
        let moved_rows: Vec<Row> = parallel::map_chunks(moved.len(), 64, |r| {
            r.map(|i| {
                let mut row = Vec::new();
                grid.row(new, moved[i] as usize, r2, &mut row);
                row
            })
            .collect::<Vec<_>>()
        })
        .into_iter()
        .flatten()
        .collect();
        let mut dirty: Vec<bool> = new.area.iter().map(|&a| !(a > 0.0)).collect();
        for (&j, row) in moved.iter().zip(&moved_rows) {
            for &(e, _) in self.of(j as usize).iter().chain(row) {
                dirty[e as usize] = true;
            }
        }
        let rebuilt = dirty.iter().filter(|&&d| d).count();
        let touched: Vec<usize> = (0..self.chunks.len())
            .filter(|&c| dirty[c * CHUNK..((c + 1) * CHUNK).min(n)].contains(&true))
            .collect();
        let fresh = parallel::map_chunks(touched.len(), 1, |r| {
            r.map(|t| {
                let c = touched[t];
                let range = c * CHUNK..((c + 1) * CHUNK).min(n);
                Chunk::build(
                    new,
                    &grid,
                    range,
                    Some((&self.chunks[c], &dirty)),
                    (&moved, &moved_rows),
                )
            })
            .collect::<Vec<_>>()
        });
        let mut fresh = touched
            .iter()
            .copied()
            .zip(fresh.into_iter().flatten())
            .peekable();
        let chunks = self
            .chunks
            .into_iter()
            .enumerate()
            .map(|(c, old)| match fresh.next_if(|(t, _)| *t == c) {
                Some((_, ch)) => ch,
                None => old,
            })
            .collect();
        Neighbours {
            radius: self.radius,
            chunks,
            rebuilt,
        }
    }

    /// Entries in all rows.
    pub fn entries(&self) -> usize {
        self.chunks.iter().map(|c| c.items.len()).sum()
    }

    /// Rows rebuilt by the [`Neighbours::update`] that made these lists (all of them for
    /// [`Neighbours::new`]).
    pub fn rebuilt(&self) -> usize {
        self.rebuilt
    }

    /// Neighbours of `e` (itself first) with squared distances.
    #[inline]
    pub fn of(&self, e: usize) -> &[(u32, f32)] {
        let (c, i) = (&self.chunks[e / CHUNK], e % CHUNK);
        &c.items[c.offsets[i] as usize..c.offsets[i + 1] as usize]
    }

    /// The spatial Gaussian weights `exp(−d² / 2σ²)`, σ = radius / 2, of the entries of
    /// [`Neighbours::of`] (computed once per row, as `(-d2 * gauss_inv2s2(radius)).exp()`).
    #[inline]
    pub fn gauss(&self, e: usize) -> &[f32] {
        let (c, i) = (&self.chunks[e / CHUNK], e % CHUNK);
        &c.gauss[c.offsets[i] as usize..c.offsets[i + 1] as usize]
    }
}

/// Neighbour lists of one radius carried from frame to frame: each request updates the
/// lists of the previous one ([`Neighbours::update`]), so on a mostly static scene only
/// the rows around moving elements are rebuilt (identical to [`Neighbours::new`]).
#[derive(Clone, Debug, Default)]
pub struct NeighbourCache {
    last: Option<(FrameElements, Neighbours)>,
}

impl NeighbourCache {
    /// No lists yet.
    pub fn is_empty(&self) -> bool {
        self.last.is_none()
    }

    /// The lists of `fe` within `radius` (world units).
    pub fn get(&mut self, fe: &FrameElements, radius: f32) -> &Neighbours {
        let nb = match self.last.take() {
            Some((old, nb)) if nb.radius == radius => nb.update(&old, fe),
            _ => Neighbours::new(fe, radius),
        };
        &self.last.insert((fe.clone(), nb)).1
    }
}

/// Largest factor by which the adaptive spatial support changes σ_s² either way
/// ([`adaptive_sigma2`]): σ_s within [σ₀/√2, √2 σ₀], so neighbour lists of radius
/// [`ADAPTIVE_LIST_RADIUS`] × 2σ₀ hold the widest kernel to 2σ, as the fixed one is cut.
pub const ADAPTIVE_RANGE: f32 = 2.0;

/// Radius of the neighbour lists for the adaptive support, relative to the fixed
/// filter's radius 2σ₀: √[`ADAPTIVE_RANGE`].
pub const ADAPTIVE_LIST_RADIUS: f32 = std::f32::consts::SQRT_2;

/// Adaptive spatial support (the adaptive σ_s of Weber et al. 2004): the squared Gaussian
/// σ of every element side, grown where photons are sparse and shrunk where they are
/// dense so that about `target` photons fall under the kernel. `count[slot]`: photons of
/// each element side; the photons under the kernel of σ₀ are `C₀ = Σ_j g₀(d_j) count_j`
/// over the row (g₀ = exp(−d²/2σ₀²)), and since on a surface of locally constant photon
/// density the count under a Gaussian grows as σ², `σ² = σ₀² · target / C₀`, clamped to
/// [σ₀²/[`ADAPTIVE_RANGE`], σ₀² · [`ADAPTIVE_RANGE`]] (the neighbour lists bound the
/// growth; the shrink keeps the filter's bias floor of one element ring).
pub fn adaptive_sigma2(nb: &Neighbours, count: &[f32], sigma0: f32, target: f32) -> Vec<f32> {
    let n = count.len() / 2;
    let inv2s2 = 1.0 / (2.0 * sigma0 * sigma0).max(1e-30);
    let s02 = sigma0 * sigma0;
    let rows = parallel::map_chunks(n, 1024, |range| {
        let mut out = Vec::with_capacity(2 * range.len());
        for e in range {
            let mut c = [0.0f32; 2];
            for &(j, d2) in nb.of(e) {
                let g = (-d2 * inv2s2).exp();
                c[0] += g * count[2 * j as usize];
                c[1] += g * count[2 * j as usize + 1];
            }
            for c0 in c {
                let f = if c0 > 0.0 {
                    (target / c0).clamp(1.0 / ADAPTIVE_RANGE, ADAPTIVE_RANGE)
                } else {
                    ADAPTIVE_RANGE
                };
                out.push(s02 * f);
            }
        }
        out
    });
    rows.into_iter().flatten().collect()
}

/// Irradiance per element side without filtering: Φ / (N · A).
pub fn element_irradiance(acc: &ElementAccumulators, fe: &FrameElements) -> Vec<Rgb> {
    let inv_n = 1.0 / acc.photons.max(1) as f32;
    (0..acc.flux.len())
        .map(|s| {
            let a = fe.area[s / 2];
            if a > 0.0 {
                acc.flux[s] * (inv_n / a)
            } else {
                Rgb::ZERO
            }
        })
        .collect()
}

/// Noise standard deviation of each element side's irradiance (luminance).
pub fn element_sigma(acc: &ElementAccumulators, fe: &FrameElements) -> Vec<f32> {
    let inv_n = 1.0 / acc.photons.max(1) as f32;
    (0..acc.flux.len())
        .map(|s| {
            let a = fe.area[s / 2];
            if a > 0.0 {
                acc.flux_sq[s].sqrt() * inv_n / a
            } else {
                0.0
            }
        })
        .collect()
}

/// Generic normalised filter over element sides: `E'_e = Σ w Φ_j / (N Σ w A_j)`, with
/// `weight(e_slot, j_slot, d²)` the (unnormalised) weight of neighbour `j`.
pub fn filter_with(
    acc: &ElementAccumulators,
    fe: &FrameElements,
    nb: &Neighbours,
    weight: impl Fn(usize, usize, f32) -> f32 + Sync,
) -> Vec<Rgb> {
    filter_with_sigma(acc, fe, nb, 0.0, |se, sj, d2, _| weight(se, sj, d2)).0
}

/// [`filter_with`] and the standard error of each filtered luminance estimate,
/// `√(Σ w² (Σφ²_j + prior)) / (N Σ w A_j)` (weights taken as fixed). `prior` is added to
/// every element's Σφ² so that elements that have no photons *yet* do not look
/// noise-free (one phantom photon of mean power, [`prior_sq`]); 0 for the plain estimate.
/// `weight(e_slot, j_slot, d², g)` also gets the entry's spatial Gaussian `g`
/// ([`Neighbours::gauss`]).
pub fn filter_with_sigma(
    acc: &ElementAccumulators,
    fe: &FrameElements,
    nb: &Neighbours,
    prior: f32,
    weight: impl Fn(usize, usize, f32, f32) -> f32 + Sync,
) -> (Vec<Rgb>, Vec<f32>) {
    let inv_n = 1.0 / acc.photons.max(1) as f32;
    let n = fe.area.len();
    let rows = parallel::map_chunks(n, 1024, |range| {
        let mut out = Vec::with_capacity(2 * range.len());
        for e in range {
            for side in 0..2 {
                let se = 2 * e + side;
                let (mut num, mut den, mut sq) = (Rgb::ZERO, 0.0f32, 0.0f32);
                for (&(j, d2), &g) in nb.of(e).iter().zip(nb.gauss(e)) {
                    let sj = 2 * j as usize + side;
                    let w = weight(se, sj, d2, g);
                    num += acc.flux[sj] * w;
                    den += fe.area[j as usize] * w;
                    sq += (acc.flux_sq[sj] + prior) * w * w;
                }
                out.push(if den > 0.0 {
                    (num * (inv_n / den), sq.sqrt() * inv_n / den)
                } else {
                    (Rgb::ZERO, 0.0)
                });
            }
        }
        out
    });
    rows.into_iter().flatten().unzip()
}

/// Element irradiance after `filter` (per element side).
pub fn filtered_irradiance(
    mesh: &ElementMesh,
    acc: &ElementAccumulators,
    fe: &FrameElements,
    filter: Filter,
) -> Vec<Rgb> {
    filtered_irradiance_sigma(mesh, acc, fe, filter).0
}

/// [`filtered_irradiance`] and the standard error of each filtered luminance estimate
/// (what the stopping rule reads, [`super::budget`]).
pub fn filtered_irradiance_sigma(
    mesh: &ElementMesh,
    acc: &ElementAccumulators,
    fe: &FrameElements,
    filter: Filter,
) -> (Vec<Rgb>, Vec<f32>) {
    let prior = prior_sq(acc);
    let (radius, bilateral) = match filter {
        Filter::None => {
            let inv_n = 1.0 / acc.photons.max(1) as f32;
            let sig = (0..acc.flux.len())
                .map(|s| {
                    let a = fe.area[s / 2];
                    if a > 0.0 {
                        (acc.flux_sq[s] + prior).sqrt() * inv_n / a
                    } else {
                        0.0
                    }
                })
                .collect();
            return (element_irradiance(acc, fe), sig);
        }
        Filter::Gaussian { radius } => (radius, None),
        Filter::Bilateral {
            radius,
            kappa,
            min_photons,
        } => (radius, Some((kappa, min_photons))),
    };
    let r = radius * mesh.element_size;
    let nb = Neighbours::new(fe, r);
    // The spatial Gaussian `exp(−d² / 2σ²)`, σ = r / 2, is `nb.gauss`.
    match bilateral {
        None => filter_with_sigma(acc, fe, &nb, prior, |_, _, _, g| g),
        Some((kappa, min_photons)) => {
            let e = element_irradiance(acc, fe);
            let lum: Vec<f32> = e.iter().map(|c| luminance(*c)).collect();
            let sig = element_sigma(acc, fe);
            filter_with_sigma(acc, fe, &nb, prior, |se, sj, _, g| {
                range_weight(
                    lum[se],
                    lum[sj],
                    sig[se],
                    sig[sj],
                    kappa,
                    acc.count[se] < min_photons,
                ) * g
            })
        }
    }
}

/// Mean squared luminance flux of one photon in `acc` (Σ Σφ² / Σ count; 0 if empty): the
/// variance prior of the noise estimates.
pub fn prior_sq(acc: &ElementAccumulators) -> f32 {
    let n: u64 = acc.count.iter().map(|&c| c as u64).sum();
    if n == 0 {
        return 0.0;
    }
    (acc.flux_sq.iter().map(|&x| x as f64).sum::<f64>() / n as f64) as f32
}

/// Range kernel of the bilateral filter on luminance estimates `a` (centre) and `b` with
/// noise deviations `sa`, `sb`; 1 when `relax` (too few photons at the centre).
#[inline]
pub fn range_weight(a: f32, b: f32, sa: f32, sb: f32, kappa: f32, relax: bool) -> f32 {
    if relax {
        return 1.0;
    }
    let var = kappa * kappa * (sa * sa + sb * sb);
    if var <= 0.0 {
        return if a == b { 1.0 } else { 0.0 };
    }
    (-(a - b) * (a - b) / (2.0 * var)).exp()
}

/// A smooth irradiance field on the element mesh.
#[derive(Clone, Debug, Default)]
pub struct ElementSolution {
    /// Irradiance per vertex side (`2·vertex + side`).
    pub vertex: Vec<Rgb>,
}

impl ElementSolution {
    /// Vertex values from per-element-side irradiance (area-weighted one-ring means over
    /// the cells around each vertex; a cell of a cluster weighs its share of the
    /// cluster's area).
    pub fn from_elements(mesh: &ElementMesh, fe: &FrameElements, elem: &[Rgb]) -> Self {
        let nv = mesh.vertex_count();
        let mut num = vec![Rgb::ZERO; 2 * nv];
        let mut den = vec![0.0f32; nv];
        for c in 0..mesh.cell_count() as u32 {
            let e = mesh.cell_element(c) as usize;
            let a = fe.area[e] * mesh.cell_share(c);
            if a <= 0.0 {
                continue;
            }
            for v in mesh.cell_vertices(c) {
                let v = v as usize;
                num[2 * v] += elem[2 * e] * a;
                num[2 * v + 1] += elem[2 * e + 1] * a;
                den[v] += a;
            }
        }
        let vertex = num
            .iter()
            .enumerate()
            .map(|(s, n)| {
                let d = den[s / 2];
                if d > 0.0 { *n / d } else { Rgb::ZERO }
            })
            .collect();
        ElementSolution { vertex }
    }

    /// Interpolated irradiance at a located point, on its front or back side.
    #[inline]
    pub fn irradiance(&self, loc: &Located, front: bool) -> Rgb {
        if self.vertex.is_empty() {
            return Rgb::ZERO;
        }
        let side = (!front) as usize;
        (0..3)
            .map(|k| self.vertex[2 * loc.vertices[k] as usize + side] * loc.weights[k])
            .sum()
    }
}
