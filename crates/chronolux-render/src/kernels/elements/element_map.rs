//! The illumination mesh and its per-element photon accumulators.
//!
//! ## Elements
//! Every triangle of every geometry is split uniformly into `k²` sub-triangles
//! ("elements"), `k = clamp(⌈ℓ / element size⌉, 1, MAX_K)`, where the element size `h` is
//! the scene's bounding-box diagonal divided by a target count and `ℓ` is the triangle's
//! *subdivision length* ([`subdivision_length`]): its longest edge `L` for a well-shaped
//! triangle, less for a sliver. With `ℓ = L`, a sliver (longest edge over altitude 48 on
//! RiggedSimple's cylinder) got elements 24× smaller in area than a well-shaped
//! triangle's, so the reconstruction's rows (elements within a few `h`) grew to hundreds
//! or thousands of entries: 5.4× the mean row length of the Cornell scenes. An element
//! is addressed by (geometry, triangle, barycentrics), never by a world position, so:
//! - element ids are stable across frames (geometry ids are; the mesh is built once from
//!   the first frame and reused while the topology matches, [`ElementMesh::matches`]);
//! - the elements of a moving or deforming object move with it.
//!
//! ## Clusters of small triangles
//! A triangle much smaller than an element (`ℓ < CLUSTER_BELOW · h`, e.g. a finely
//! tessellated model) is not an element of its own: the small triangles of one geometry
//! whose centroids fall into the same cube of `CLUSTER_CELL · h` (in the frame the mesh is
//! built from) and whose normals fall into the same of 96 direction buckets (a cube map
//! with 4 × 4 cells per face: two normals in one bucket are at most 36.9° apart) form one
//! element, so an element keeps the size `h` the photons were budgeted for. Before, every
//! triangle was at least one element: TransmissionTest (129k triangles) had 129k elements
//! with 547 neighbours each within the filters' 2.5 h (1.8 GB of neighbour lists, 56 % of
//! the CPU in building them), where the scene's 38 elements per diagonal call for
//! about 10k. The triangles of a cluster are its *cells*: each keeps its three mesh
//! vertices for the interpolation, so a vertex inside a cluster takes the cluster's value
//! and a vertex on its border the area-weighted mean of the clusters around it; the
//! cluster's centroid, normal and area are the area-weighted ones of its cells in each
//! frame (a deforming cluster follows its triangles). Clusters never span geometries, so
//! they move with their object; ids are assigned in triangle order, so they are as
//! stable across frames as the triangles'. Triangles of the element size or larger are
//! split as before, so scenes without small triangles keep their elements exactly.
//!
//! Cells of the `k × k` barycentric grid: `u = b1·k`, `v = b2·k`, cell `(i, j) = (⌊u⌋, ⌊v⌋)`;
//! the "lower" sub-triangle has vertices `(i,j), (i+1,j), (i,j+1)`, the "upper" one
//! (`frac(u) + frac(v) > 1`) `(i+1,j+1), (i,j+1), (i+1,j)`. Grid vertices are shared with
//! neighbouring triangles through the mesh's vertex indices (corners) and edges (points
//! along an edge whose two triangles have the same `k`), which is what makes the
//! interpolated solution continuous across triangles of a smooth mesh; meshes that split
//! vertices (hard edges, UV seams) stay discontinuous there, as they should.
//!
//! ## Accumulators
//! Per element and side (front = the side the geometric normal points to), per frame:
//! photon flux sum (RGB), photon count, and sum of squared luminance flux (for the noise
//! estimate of the reconstruction). Not hit points: memory is O(elements).

use crate::kernels::photon::{MAX_BOUNCES, PhotonHit, PhotonStats, trace_photons_within};
use chronolux_core::accel::TriRef;
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::math::Vec3;
use chronolux_core::scene::frame::FrameScene;
use std::collections::HashMap;

/// Scale of the automatic element count, [`auto_elements`]: `e = 3.5 · P^(1/6)`.
pub const AUTO_ELEMENTS_SCALE: f64 = 3.5;

/// Elements per scene diagonal for an element estimate that pools `pooled_photons`
/// emitted photons (a frame's photons times the frames pooled): `3.5 · P^(1/6)`, within
/// [4, 200].
///
/// The element is the kernel of a density estimate, so its size trades bias (large
/// elements blur) for variance (small ones hold few photons); for a kernel estimate in
/// two dimensions the error is least at a bandwidth `h ∝ P^(−1/6)`, i.e. elements per
/// diagonal `∝ P^(1/6)`. Finer elements also cost more: the reconstruction's work is
/// per element (neighbour lists, filters, change statistics), not per photon. The scale
/// 3.5 is the middle of the least-FLIP element counts measured at 64² and 256² on
/// RiggedSimple in the Cornell stage and on cornell-moving, for `dept-spatial` (1 frame
/// pooled) and `spacetime-dept` (17 frames) at 2k–128k photons per frame, whose optima
/// lie at 3.0–3.9 · P^(1/6) (BENCHMARKS.md, issue 17, "element size from the photons").
/// The former fixed 100 per diagonal is that optimum only at ~5·10⁸ pooled photons.
/// Calibrated in FLIP at 64² and 256²: a much larger image shows the blur of coarse
/// elements over more pixels, where a fixed finer count (`elements`) may pay.
pub fn auto_elements(pooled_photons: f64) -> f32 {
    (AUTO_ELEMENTS_SCALE * pooled_photons.max(1.0).powf(1.0 / 6.0)).clamp(4.0, 200.0) as f32
}

/// The elements per diagonal a technique uses: its `elements` setting when positive,
/// otherwise [`auto_elements`] of the photons its estimates pool.
pub fn elements_per_diagonal(setting: f32, pooled_photons: f64) -> f32 {
    if setting > 0.0 {
        setting
    } else {
        auto_elements(pooled_photons)
    }
}

/// Largest subdivision of one triangle (k² = 4096 elements).
pub const MAX_K: u32 = 64;

/// Triangles with a subdivision length below this many element sizes are merged into
/// clusters (module documentation): about four or more of them fit into one element.
pub const CLUSTER_BELOW: f32 = 0.5;

/// Edge of the cubes that group small triangles into clusters, in element sizes: a flat
/// surface across a cube gives a cluster of area ≈ (0.7 h)² ≈ h²/2, that of a split
/// triangle's elements (h²/4 … h²/2).
pub const CLUSTER_CELL: f32 = 0.7;

/// Direction bucket of a normal: cube-map face (6) × 4 × 4 cells of the face's
/// coordinates in [−1, 1]; 96 for a zero normal. Two directions in one bucket are at most
/// 36.9° apart (opposite corners of a central cell, (1, ½, 0) and (1, 0, ½): cos = 0.8).
pub fn normal_bucket(n: Vec3) -> u8 {
    let a = n.abs();
    let m = a.max_element();
    if !(m > 0.0) {
        return 96;
    }
    let (face, u, v) = if a.x == m {
        (if n.x >= 0.0 { 0 } else { 1 }, n.y, n.z)
    } else if a.y == m {
        (if n.y >= 0.0 { 2 } else { 3 }, n.z, n.x)
    } else {
        (if n.z >= 0.0 { 4 } else { 5 }, n.x, n.y)
    };
    let q = |c: f32| (((c / m + 1.0) * 2.0).floor() as i32).clamp(0, 3) as u8;
    face * 16 + q(u) * 4 + q(v)
}

/// The length a triangle's subdivision is measured by: `min(L, max(2√2·√A, L/4))` for
/// longest edge `L` and area `A`.
///
/// - Every triangle with `L²/(2A)` (longest edge over its altitude) ≤ 4 has `2√2·√A ≥ L`
///   and keeps `ℓ = L`: right isosceles and equilateral triangles, and the halves of
///   rectangles up to aspect 3.7 (`4ab ≥ a² + b²`), so the Cornell stage's walls and
///   boxes are split exactly as before.
/// - A thinner triangle is split by `2√2·√A`: its elements' area is then at least
///   `h²/8`, half that of a right isosceles triangle's elements (`h²/4`), instead of
///   shrinking with the aspect ratio; they are longer than `h` along the long edge (about
///   3.5 h at RiggedSimple's aspect 48).
/// - The floor `L/4` keeps an extreme sliver's elements no longer than `4h`, i.e. within
///   the reconstruction's support of a few `h`.
pub fn subdivision_length(p: [Vec3; 3]) -> f32 {
    let longest = (p[1] - p[0])
        .length()
        .max((p[2] - p[1]).length())
        .max((p[0] - p[2]).length());
    let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
    longest.min((8.0 * area).sqrt().max(0.25 * longest))
}

/// Where a surface point falls on the element mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Located {
    pub element: u32,
    /// Global ids of the element's three grid vertices.
    pub vertices: [u32; 3],
    /// Barycentric weights of the point w.r.t. those vertices.
    pub weights: [f32; 3],
}

/// The illumination mesh: element and grid-vertex ids of every triangle.
///
/// A *cell* is one sub-triangle of a triangle's `k × k` split (the whole triangle when
/// k = 1); an *element* is one cell, or a cluster of the cells of small triangles
/// (module documentation).
#[derive(Clone, Debug)]
pub struct ElementMesh {
    /// Target element edge length (world units, in the frame it was built from).
    pub element_size: f32,
    /// First global triangle of each geometry (len = geometries + 1).
    geom_tri: Vec<u32>,
    /// Subdivision of each triangle.
    tri_k: Vec<u32>,
    /// First cell of each triangle (len = triangles + 1).
    tri_cell: Vec<u32>,
    /// First entry of each triangle in `vert_ids` (len = triangles + 1).
    tri_vert: Vec<u32>,
    /// Global vertex id of each local grid vertex, per triangle.
    vert_ids: Vec<u32>,
    /// Grid vertices of each cell.
    cell_verts: Vec<[u32; 3]>,
    /// Element of each cell.
    cell_elem: Vec<u32>,
    /// Each cell's share of its element's area in the frame the mesh was built from
    /// (exactly 1 for an element of one cell).
    cell_share: Vec<f32>,
    /// Whether each element is a cluster (several cells).
    clustered: Vec<bool>,
    n_vertices: u32,
}

/// Local index of grid vertex (i, j), i + j ≤ k.
#[inline]
fn grid_index(k: u32, i: u32, j: u32) -> u32 {
    i * (k + 1) - i * i.saturating_sub(1) / 2 + j
}

/// Local element index of the lower (`up = false`) or upper cell (i, j).
#[inline]
fn cell_index(k: u32, i: u32, j: u32, up: bool) -> u32 {
    if !up {
        i * k - i * i.saturating_sub(1) / 2 + j
    } else {
        k * (k + 1) / 2 + i * (k - 1) - i * i.saturating_sub(1) / 2 + j
    }
}

/// Local grid vertices (i, j) of a cell.
#[inline]
fn cell_vertices(i: u32, j: u32, up: bool) -> [(u32, u32); 3] {
    if up {
        [(i + 1, j + 1), (i, j + 1), (i + 1, j)]
    } else {
        [(i, j), (i + 1, j), (i, j + 1)]
    }
}

impl ElementMesh {
    /// Elements for `scene` with edge ≈ `diagonal / elements_per_diagonal`.
    pub fn build(scene: &FrameScene, elements_per_diagonal: f32) -> ElementMesh {
        let diag = scene.bounds.diagonal().length();
        let h = if diag > 0.0 && elements_per_diagonal > 0.0 {
            diag / elements_per_diagonal
        } else {
            1.0
        };
        let xf = scene.geometry_transforms();
        let mut m = ElementMesh {
            element_size: h,
            geom_tri: vec![0],
            tri_k: Vec::new(),
            tri_cell: vec![0],
            tri_vert: vec![0],
            vert_ids: Vec::new(),
            cell_verts: Vec::new(),
            cell_elem: Vec::new(),
            cell_share: Vec::new(),
            clustered: Vec::new(),
            n_vertices: 0,
        };
        // Area of each element in this frame (for the cells' shares).
        let mut elem_area: Vec<f64> = Vec::new();
        let mut cell_area: Vec<f64> = Vec::new();
        let cube = CLUSTER_CELL * h;
        for (gid, g) in scene.geometry.iter().enumerate() {
            // Shared grid vertices of this geometry: corners by mesh vertex, edge points
            // by (edge, k, step from the lower-indexed end).
            let mut corner: HashMap<u32, u32> = HashMap::new();
            let mut edge: HashMap<(u32, u32, u32, u32), u32> = HashMap::new();
            // Clusters of this geometry's small triangles: (cube, normal bucket) → element.
            let mut clusters: HashMap<(i32, i32, i32, u8), u32> = HashMap::new();
            for tri in g.indices.iter() {
                let p = tri.map(|i| xf[gid].transform_point3(g.positions[i as usize]));
                let ell = subdivision_length(p);
                let k = ((ell / h).ceil() as u32).clamp(1, MAX_K);
                let t = m.tri_k.len() as u32;
                m.tri_k.push(k);
                let mut next = m.n_vertices;
                let mut fresh = || {
                    next += 1;
                    next - 1
                };
                let mut shared_edge = |a: u32, b: u32, s: u32, fresh: &mut dyn FnMut() -> u32| {
                    let key = if a < b {
                        (a, b, k, s)
                    } else {
                        (b, a, k, k - s)
                    };
                    *edge.entry(key).or_insert_with(fresh)
                };
                for i in 0..=k {
                    for j in 0..=(k - i) {
                        let id = match (i, j) {
                            (0, 0) => *corner.entry(tri[0]).or_insert_with(&mut fresh),
                            (i, 0) if i == k => *corner.entry(tri[1]).or_insert_with(&mut fresh),
                            (0, j) if j == k => *corner.entry(tri[2]).or_insert_with(&mut fresh),
                            (i, 0) => shared_edge(tri[0], tri[1], i, &mut fresh),
                            (0, j) => shared_edge(tri[0], tri[2], j, &mut fresh),
                            (i, j) if i + j == k => shared_edge(tri[1], tri[2], j, &mut fresh),
                            _ => fresh(),
                        };
                        debug_assert_eq!(
                            m.vert_ids.len() as u32 - m.tri_vert[t as usize],
                            grid_index(k, i, j)
                        );
                        m.vert_ids.push(id);
                    }
                }
                m.n_vertices = next;
                m.tri_vert.push(m.vert_ids.len() as u32);
                let base = m.tri_vert[t as usize];
                let mut cells = vec![[0u32; 3]; (k * k) as usize];
                for i in 0..k {
                    for j in 0..k - i {
                        for up in [false, true] {
                            if up && i + j + 2 > k {
                                continue;
                            }
                            let v = cell_vertices(i, j, up)
                                .map(|(a, b)| m.vert_ids[(base + grid_index(k, a, b)) as usize]);
                            cells[cell_index(k, i, j, up) as usize] = v;
                        }
                    }
                }
                m.cell_verts.extend(cells);
                let n = (p[1] - p[0]).cross(p[2] - p[0]);
                let area = 0.5 * n.length() as f64;
                if ell < CLUSTER_BELOW * h {
                    let c = (p[0] + p[1] + p[2]) / (3.0 * cube);
                    let key = (
                        c.x.floor() as i32,
                        c.y.floor() as i32,
                        c.z.floor() as i32,
                        normal_bucket(n),
                    );
                    let e = *clusters.entry(key).or_insert_with(|| {
                        m.clustered.push(true);
                        elem_area.push(0.0);
                        m.clustered.len() as u32 - 1
                    });
                    elem_area[e as usize] += area;
                    m.cell_elem.push(e);
                    cell_area.push(area);
                } else {
                    let first = m.clustered.len() as u32;
                    m.cell_elem.extend(first..first + k * k);
                    m.clustered
                        .extend(std::iter::repeat_n(false, (k * k) as usize));
                    elem_area.extend(std::iter::repeat_n(0.0, (k * k) as usize));
                    cell_area.extend(std::iter::repeat_n(0.0, (k * k) as usize));
                }
                m.tri_cell.push(m.cell_verts.len() as u32);
            }
            m.geom_tri.push(m.tri_k.len() as u32);
        }
        m.cell_share = m
            .cell_elem
            .iter()
            .zip(&cell_area)
            .map(|(&e, &a)| {
                let total = elem_area[e as usize];
                if !m.clustered[e as usize] {
                    1.0
                } else if total > 0.0 {
                    (a / total) as f32
                } else {
                    0.0
                }
            })
            .collect();
        m
    }

    /// True when `scene` has the topology this mesh was built for (same geometries and
    /// triangle counts), so element ids carry over.
    pub fn matches(&self, scene: &FrameScene) -> bool {
        self.geom_tri.len() == scene.geometry.len() + 1
            && scene
                .geometry
                .iter()
                .enumerate()
                .all(|(g, d)| self.geom_tri[g + 1] - self.geom_tri[g] == d.indices.len() as u32)
    }

    pub fn element_count(&self) -> usize {
        self.clustered.len()
    }

    /// Cells (sub-triangles, or whole small triangles) of the mesh.
    pub fn cell_count(&self) -> usize {
        self.cell_elem.len()
    }

    /// Elements that are clusters of small triangles.
    pub fn cluster_count(&self) -> usize {
        self.clustered.iter().filter(|&&c| c).count()
    }

    pub fn vertex_count(&self) -> usize {
        self.n_vertices as usize
    }

    pub fn triangle_count(&self) -> usize {
        self.tri_k.len()
    }

    /// Global triangle index of a triangle reference.
    #[inline]
    pub fn triangle(&self, tri: TriRef) -> u32 {
        self.geom_tri[tri.geometry as usize] + tri.triangle
    }

    /// Subdivision `k` of a global triangle.
    #[inline]
    pub fn subdivision(&self, t: u32) -> u32 {
        self.tri_k[t as usize]
    }

    /// Cells of a global triangle.
    #[inline]
    pub fn cells_of(&self, t: u32) -> std::ops::Range<u32> {
        self.tri_cell[t as usize]..self.tri_cell[t as usize + 1]
    }

    /// Element of a cell.
    #[inline]
    pub fn cell_element(&self, c: u32) -> u32 {
        self.cell_elem[c as usize]
    }

    /// A cell's share of its element's area (1 for an element of one cell).
    #[inline]
    pub fn cell_share(&self, c: u32) -> f32 {
        self.cell_share[c as usize]
    }

    /// Whether an element is a cluster of small triangles.
    #[inline]
    pub fn is_cluster(&self, e: u32) -> bool {
        self.clustered[e as usize]
    }

    /// Grid vertices of a cell.
    #[inline]
    pub fn cell_vertices(&self, c: u32) -> [u32; 3] {
        self.cell_verts[c as usize]
    }

    /// Barycentrics (b1, b2) of a cell's centroid on its triangle `t`.
    pub fn cell_centroid_bary(&self, t: u32, c: u32) -> (f32, f32) {
        let k = self.tri_k[t as usize];
        let local = c - self.tri_cell[t as usize];
        let lower = k * (k + 1) / 2;
        let (up, mut rest) = if local < lower {
            (false, local)
        } else {
            (true, local - lower)
        };
        let row_len = |i: u32| if up { k - 1 - i } else { k - i };
        let mut i = 0;
        while rest >= row_len(i) {
            rest -= row_len(i);
            i += 1;
        }
        let j = rest;
        let v = cell_vertices(i, j, up);
        let s = v
            .iter()
            .fold((0.0, 0.0), |a, (x, y)| (a.0 + *x as f32, a.1 + *y as f32));
        (s.0 / (3.0 * k as f32), s.1 / (3.0 * k as f32))
    }

    /// Element containing barycentrics (b1, b2) of triangle `tri`.
    #[inline]
    pub fn locate(&self, tri: TriRef, b1: f32, b2: f32) -> Located {
        let t = self.triangle(tri);
        let k = self.tri_k[t as usize];
        let kf = k as f32;
        let u = (b1.clamp(0.0, 1.0) * kf).min(kf);
        let v = (b2.clamp(0.0, 1.0) * kf).min(kf);
        let i = (u.floor() as u32).min(k - 1);
        // Points past the far edge by rounding fall into the last cell of their row.
        let j = (v.floor() as u32).min(k - 1 - i);
        let (fu, fv) = (u - i as f32, v - j as f32);
        let up = fu + fv > 1.0 && i + j + 2 <= k;
        let weights = if up {
            [fu + fv - 1.0, 1.0 - fu, 1.0 - fv]
        } else {
            [1.0 - fu - fv, fu, fv]
        }
        .map(|w| w.clamp(0.0, 1.0));
        let c = (self.tri_cell[t as usize] + cell_index(k, i, j, up)) as usize;
        Located {
            element: self.cell_elem[c],
            vertices: self.cell_verts[c],
            weights,
        }
    }
}

/// Side slot of an element: `2·element + side`, side 0 = front (geometric normal's side).
#[inline]
pub fn slot(element: u32, front: bool) -> usize {
    2 * element as usize + (!front) as usize
}

/// Per element-side photon sums of one frame.
#[derive(Clone, Debug, Default)]
pub struct ElementAccumulators {
    /// Σ flux (per emitted photon: divide by `photons` for watts).
    pub flux: Vec<Rgb>,
    /// Number of photons.
    pub count: Vec<u32>,
    /// Σ luminance(flux)².
    pub flux_sq: Vec<f32>,
    /// Photons emitted for these sums.
    pub photons: u64,
}

impl ElementAccumulators {
    pub fn new(elements: usize) -> Self {
        ElementAccumulators {
            flux: vec![Rgb::ZERO; 2 * elements],
            count: vec![0; 2 * elements],
            flux_sq: vec![0.0; 2 * elements],
            photons: 0,
        }
    }

    #[inline]
    pub fn deposit(&mut self, slot: usize, power: Rgb) {
        self.flux[slot] += power;
        self.count[slot] += 1;
        let l = luminance(power);
        self.flux_sq[slot] += l * l;
    }

    /// Total deposited flux (watts: Σ flux / photons).
    pub fn total_power(&self) -> Rgb {
        self.flux.iter().copied().sum::<Rgb>() / self.photons.max(1) as f32
    }
}

/// The photons of one frame on the element mesh: indirect (at least one bounce, not a
/// pure specular chain) and caustic (light → specular⁺ → diffuse) kept apart. Photons
/// straight from the lights go to `direct`, which only the stopping rule reads (for its
/// contrast threshold, [`super::budget`]): direct light is rendered per pixel.
#[derive(Clone, Debug)]
pub struct FramePhotons {
    pub indirect: ElementAccumulators,
    pub caustic: ElementAccumulators,
    pub direct: ElementAccumulators,
    pub stats: PhotonStats,
}

impl FramePhotons {
    /// Empty sums for `elements` elements.
    pub fn new(elements: usize) -> Self {
        FramePhotons {
            indirect: ElementAccumulators::new(elements),
            caustic: ElementAccumulators::new(elements),
            direct: ElementAccumulators::new(elements),
            stats: PhotonStats::default(),
        }
    }

    /// Photons emitted for these sums.
    pub fn photons(&self) -> u64 {
        self.indirect.photons
    }
}

/// Photons traced per batch (bounds the memory of the in-order deposit lists).
const BATCH: u64 = 1 << 18;

/// Traces photons `indices` (stream `seed`) and deposits them on `mesh`'s elements.
/// Deterministic for any thread count (deposits are summed in photon-index order).
pub fn deposit_photons(
    scene: &FrameScene,
    mesh: &ElementMesh,
    indices: std::ops::Range<u64>,
    seed: u64,
) -> FramePhotons {
    let mut out = FramePhotons::new(mesh.element_count());
    deposit_more_photons(scene, mesh, indices, seed, None, &mut out);
    out
}

/// The most scattering events a deposited photon may have had for paths of at most
/// `max_depth` segments from the camera (Mitsuba's `max_depth`) when its surface is seen
/// straight from the camera: the eye's one segment plus the photon's `bounces + 1` make
/// `bounces + 2`. `None`: unlimited.
pub fn max_photon_bounces(max_depth: Option<u32>) -> Option<u32> {
    max_depth.map(|d| d.saturating_sub(2))
}

/// Adds photons `indices` to `out` (the photon total grows by their number), in
/// photon-index order: depositing `a..b` then `b..c` gives exactly `a..c`'s sums. Paths
/// end after `max_bounces` scattering events ([`max_photon_bounces`]): their later hits
/// are neither traced nor deposited.
pub fn deposit_more_photons(
    scene: &FrameScene,
    mesh: &ElementMesh,
    indices: std::ops::Range<u64>,
    seed: u64,
    max_bounces: Option<u32>,
    out: &mut FramePhotons,
) {
    let photons = indices.end.saturating_sub(indices.start);
    out.indirect.photons += photons;
    out.caustic.photons += photons;
    out.direct.photons += photons;
    let mut lo = indices.start;
    while lo < indices.end {
        let hi = (lo + BATCH).min(indices.end);
        // Paths end at the depth limit: the hits past it carry light of longer paths
        // (the photons still count as emitted, so the estimate stays per emitted photon).
        let cap = max_bounces.unwrap_or(MAX_BOUNCES);
        let (hits, stats) = trace_photons_within(scene, lo..hi, seed, cap, |h: &PhotonHit| {
            let e = mesh.locate(h.tri, h.b1, h.b2).element;
            let kind = if !h.is_indirect() {
                0u8
            } else if h.caustic {
                2
            } else {
                1
            };
            Some((slot(e, h.wi.dot(h.ng) >= 0.0) as u32, h.power, kind))
        });
        for (s, p, kind) in hits {
            match kind {
                0 => out.direct.deposit(s as usize, p),
                1 => out.indirect.deposit(s as usize, p),
                _ => out.caustic.deposit(s as usize, p),
            }
        }
        out.stats += stats;
        lo = hi;
    }
}

/// World-space data of the elements in one frame.
#[derive(Clone, Debug)]
pub struct FrameElements {
    /// Area of each element.
    pub area: Vec<f32>,
    /// Centroid of each element.
    pub centroid: Vec<Vec3>,
    /// Unit geometric normal of each element (its triangle's).
    pub normal: Vec<Vec3>,
}

impl FrameElements {
    pub fn new(scene: &FrameScene, mesh: &ElementMesh) -> Self {
        let xf = scene.geometry_transforms();
        let n = mesh.element_count();
        let mut f = FrameElements {
            area: vec![0.0; n],
            centroid: vec![Vec3::ZERO; n],
            normal: vec![Vec3::ZERO; n],
        };
        for (gid, g) in scene.geometry.iter().enumerate() {
            let flip = xf[gid].matrix3.determinant() < 0.0;
            for (ti, tri) in g.indices.iter().enumerate() {
                let p = tri.map(|i| xf[gid].transform_point3(g.positions[i as usize]));
                let c = (p[1] - p[0]).cross(p[2] - p[0]);
                let t = mesh.triangle(TriRef {
                    geometry: gid as u32,
                    triangle: ti as u32,
                });
                let k = mesh.subdivision(t);
                let a = 0.5 * c.length() / (k * k) as f32;
                let nrm = if flip { -c } else { c }.normalize_or_zero();
                for cell in mesh.cells_of(t) {
                    let (b1, b2) = mesh.cell_centroid_bary(t, cell);
                    let centroid = (1.0 - b1 - b2) * p[0] + b1 * p[1] + b2 * p[2];
                    let e = mesh.cell_element(cell) as usize;
                    if mesh.is_cluster(e as u32) {
                        // Area-weighted sums, divided below.
                        f.area[e] += a;
                        f.centroid[e] += a * centroid;
                        f.normal[e] += a * nrm;
                    } else {
                        f.area[e] = a;
                        f.centroid[e] = centroid;
                        f.normal[e] = nrm;
                    }
                }
            }
        }
        for e in 0..n {
            if mesh.is_cluster(e as u32) && f.area[e] > 0.0 {
                f.centroid[e] /= f.area[e];
                f.normal[e] = f.normal[e].normalize_or_zero();
            }
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The automatic count follows the kernel-bandwidth law `P^(1/6)` (64× the photons:
    /// exactly twice the elements per diagonal, up to f32 rounding), is clamped to
    /// [4, 200], and a positive setting is used as given.
    #[test]
    fn automatic_elements_grow_as_the_sixth_root_of_the_photons() {
        for p in [1e3, 3.2e4, 1e5] {
            let ratio = auto_elements(64.0 * p) / auto_elements(p);
            assert!((ratio - 2.0).abs() < 1e-5, "{p}: {ratio}");
        }
        assert!((auto_elements(1e6) - 35.0).abs() < 1e-4);
        assert_eq!(auto_elements(0.0), 4.0);
        assert_eq!(auto_elements(1e30), 200.0);
        assert_eq!(elements_per_diagonal(100.0, 1e3), 100.0);
        assert_eq!(elements_per_diagonal(0.0, 1e6), auto_elements(1e6));
    }

    /// Well-shaped triangles keep their longest edge as the subdivision length (so their
    /// elements are unchanged); a sliver's elements get area h²/8 (k = ℓ/h before the
    /// ceiling), and an extreme one is held to elements ≤ 4 h long.
    #[test]
    fn subdivision_length_keeps_well_shaped_triangles_and_bounds_slivers() {
        let tri = |b: f32, c: f32| [Vec3::ZERO, Vec3::new(b, 0.0, 0.0), Vec3::new(0.0, c, 0.0)];
        for (b, c) in [(1.0f32, 1.0f32), (3.7, 1.0), (1.0, 3.7), (0.2, 0.5)] {
            let l = (b * b + c * c).sqrt();
            assert!(
                (subdivision_length(tri(b, c)) - l).abs() <= 1e-6 * l,
                "{b}×{c}"
            );
        }
        let eq = [Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.75f32.sqrt(), 0.0)];
        assert!((subdivision_length(eq) - 1.0).abs() < 1e-6);
        // Longest edge over altitude 48 (RiggedSimple): A = L²/96.
        let sliver = [
            Vec3::ZERO,
            Vec3::new(48.0, 0.0, 0.0),
            Vec3::new(24.0, 1.0, 0.0),
        ];
        let (ell, area, h) = (subdivision_length(sliver), 24.0f32, 1.0f32);
        let k = ell / h;
        assert!(
            (area / (k * k) - h * h / 8.0).abs() < 1e-4,
            "element area {}",
            area / (k * k)
        );
        assert!(48.0 / k < 4.0 * h);
        // Aspect 4096: the L/4 floor.
        let needle = [
            Vec3::ZERO,
            Vec3::new(64.0, 0.0, 0.0),
            Vec3::new(32.0, 1.0 / 64.0, 0.0),
        ];
        assert_eq!(subdivision_length(needle), 16.0);
    }

    /// Brute force over a dense set of directions: two normals in one bucket are at most
    /// 36.9° apart (the documented bound: a central cell's corners (1, ½, 0) and
    /// (1, 0, ½), cos = 1/1.25), and all 96 buckets occur.
    #[test]
    fn normal_buckets_hold_directions_within_37_degrees() {
        let mut members: Vec<Vec<Vec3>> = vec![Vec::new(); 97];
        let n = 60;
        for i in 0..n {
            for j in 0..2 * n {
                let (th, ph) = (
                    std::f32::consts::PI * (i as f32 + 0.5) / n as f32,
                    std::f32::consts::PI * j as f32 / n as f32,
                );
                let d = Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                members[normal_bucket(d) as usize].push(d);
            }
        }
        assert!(members[..96].iter().all(|m| !m.is_empty()));
        assert!(members[96].is_empty());
        assert_eq!(normal_bucket(Vec3::ZERO), 96);
        let min_cos = 0.8 - 1e-6;
        for m in &members {
            for a in m {
                for b in m {
                    assert!(a.dot(*b) >= min_cos, "{a} {b}: {}", a.dot(*b));
                }
            }
        }
    }

    #[test]
    fn grid_and_cell_indices_are_dense() {
        for k in 1..7u32 {
            let mut seen = vec![false; (k * k) as usize];
            for i in 0..k {
                for j in 0..k - i {
                    for up in [false, true] {
                        if up && i + j + 2 > k {
                            continue;
                        }
                        let c = cell_index(k, i, j, up) as usize;
                        assert!(!seen[c]);
                        seen[c] = true;
                    }
                }
            }
            assert!(seen.iter().all(|&s| s));
            let mut g = 0;
            for i in 0..=k {
                for j in 0..=k - i {
                    assert_eq!(grid_index(k, i, j), g);
                    g += 1;
                }
            }
        }
    }
}
