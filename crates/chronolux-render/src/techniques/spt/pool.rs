//! The photon pool, its signed element solution, the pilots, the queue of invalid groups
//! and the update step ([`SptState`]).

use super::groups::{GroupLayout, used_dims};
use super::{Order, SptSettings};
use crate::kernels::elements::element_map::{
    ElementAccumulators, ElementMesh, FrameElements, slot,
};
use crate::kernels::photon::{PhotonStats, segment_hits_box, trace_photon_path};
use chronolux_core::accel::TriRef;
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::geometry::Bounds3;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::hash_words;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// No slot / no light.
const NONE: u32 = u32::MAX;

/// Deposit kinds (which accumulator a deposit goes to).
const DIRECT: u8 = 0;
const INDIRECT: u8 = 1;
const CAUSTIC: u8 = 2;

/// One vertex of a stored photon path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecVertex {
    /// World position of the hit.
    pub p: Vec3,
    pub instance: u32,
    pub material: u32,
    pub tri: TriRef,
    /// Element side deposited on, `NONE` for a delta (purely specular) vertex.
    pub slot: u32,
    pub kind: u8,
    pub power: Rgb,
}

/// A photon's path as last shot: what it touched and what it deposited.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonRecord {
    /// Emitting light (`NONE`: nothing emitted).
    pub light: u32,
    /// Where the photon left the light.
    pub origin: Vec3,
    pub vertices: Vec<RecVertex>,
    /// Direction of the last segment when it left the scene without a hit (zero when the
    /// path ended at a vertex or emitted nothing).
    pub escape: Vec3,
}

impl PhotonRecord {
    /// The path touches something `changes` reports changed (its light, the instance or
    /// the material of a vertex).
    ///
    /// `selection_changed`: the light selection probabilities differ between the two
    /// scenes (some light's power changed), which changes every photon's light choice
    /// and power: then every path that left a light touches the change.
    pub fn touches(&self, changes: &FrameDelta, selection_changed: bool) -> bool {
        (self.light != NONE && (selection_changed || changes.light_changed(self.light as usize)))
            || self.vertices.iter().any(|v| {
                changes.instance_changed(v.instance as usize)
                    || changes.material_changed(v.material as usize)
            })
    }

    /// Some segment of the path (emission point → vertices → escape ray) passes through
    /// one of `boxes` (conservative: a segment that crosses a box may miss what is in it).
    pub fn crosses(&self, boxes: &[Bounds3]) -> bool {
        if self.light == NONE || boxes.is_empty() {
            return false;
        }
        let mut a = self.origin;
        for v in &self.vertices {
            if boxes.iter().any(|b| segment_hits_box(a, v.p - a, 1.0, b)) {
                return true;
            }
            a = v.p;
        }
        self.escape != Vec3::ZERO
            && boxes
                .iter()
                .any(|b| segment_hits_box(a, self.escape, f32::INFINITY, b))
    }

    /// The two paths differ: another light, another vertex count, another instance,
    /// material, triangle, element side or deposit kind at some vertex, or a power that
    /// differs by more than `tol` relative to the larger one.
    pub fn differs(&self, o: &PhotonRecord, tol: f32) -> bool {
        self.light != o.light
            || self.vertices.len() != o.vertices.len()
            || self.vertices.iter().zip(&o.vertices).any(|(a, b)| {
                a.instance != b.instance
                    || a.material != b.material
                    || a.tri != b.tri
                    || a.slot != b.slot
                    || a.kind != b.kind
                    || {
                        let d = (a.power - b.power).abs().max_element();
                        d > tol * a.power.max_element().max(b.power.max_element())
                    }
            })
    }
}

/// What the path scan needs of a [`PhotonRecord`] to rule it out, kept beside the records
/// in one contiguous array (the records' vertices are scattered over the heap): the box of
/// every point the path can pass through and masks of the instances and materials of its
/// vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSummary {
    /// Box of the emission point and the vertices, padded by [`SUMMARY_PAD`], and open
    /// towards infinity along each axis the escape ray (if any) goes.
    pub lo: Vec3,
    pub hi: Vec3,
    /// Bit `i mod 64` for each vertex's instance `i`.
    pub instances: u64,
    /// Bit `m mod 64` for each vertex's material `m`.
    pub materials: u64,
    /// The emitting light (`NONE`: nothing emitted).
    pub light: u32,
    /// Vertices of the path (the points of its [`PathPoints`] when at most
    /// [`PATH_POINTS`] − 1).
    pub vertices: u32,
    /// The emission point, the vertices and, for a path that escapes, the point where its
    /// escape ray leaves the grid box, on the state's [`QuantGrid`] (when `quantized`).
    pub q: [[u16; 3]; QUANT_POINTS + 1],
    /// `q` holds every point of the path (at most `QUANT_POINTS − 1` vertices, all inside
    /// the grid): the scan can rule its segments out from the summary alone
    /// ([`QuantGrid::may_cross`]).
    pub quantized: bool,
    /// The path ends in an escape ray (its last point in `q` is the ray's exit from the
    /// grid box: beyond it the ray can cross only bounds that leave the box).
    pub escapes: bool,
}

/// Points of a [`PathPoints`]: the emission point and the first `PATH_POINTS − 1`
/// vertices (most paths have fewer: 2.3 vertices on average in the demo, 3.8 among the
/// photons a localized change flags).
pub const PATH_POINTS: usize = 5;

/// Points of a path a [`PathSummary`] holds on the [`QuantGrid`] (the emission point and
/// up to `QUANT_POINTS − 1` vertices, plus an escape ray's exit): longer than
/// [`PathPoints`], because a path the summary cannot rule out costs a scattered read of
/// its record (long paths are the ones whose boxes meet a change).
pub const QUANT_POINTS: usize = 9;

/// The points of a stored path the segment test reads, beside the records in one
/// contiguous array (read only for the paths whose [`PathSummary`] box meets a changed
/// bound): the emission point, the first vertices and the escape direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPoints {
    pub p: [Vec3; PATH_POINTS],
    pub escape: Vec3,
}

impl PathPoints {
    pub fn of(rec: &PhotonRecord) -> PathPoints {
        let mut p = [Vec3::ZERO; PATH_POINTS];
        p[0] = rec.origin;
        for (k, v) in rec.vertices.iter().take(PATH_POINTS - 1).enumerate() {
            p[k + 1] = v.p;
        }
        PathPoints {
            p,
            escape: rec.escape,
        }
    }
}

/// [`PhotonRecord::crosses`] of the record summarised by `s` and `pts`, from them alone
/// when the path has at most `PATH_POINTS − 1` vertices (the same segments and the same
/// arithmetic, so the same answer), else from the record.
#[inline]
fn crosses_from(s: &PathSummary, pts: &PathPoints, rec: &PhotonRecord, boxes: &[Bounds3]) -> bool {
    let n = s.vertices as usize;
    if n >= PATH_POINTS {
        return rec.crosses(boxes);
    }
    if s.light == NONE || boxes.is_empty() {
        return false;
    }
    let mut a = pts.p[0];
    for &v in &pts.p[1..=n] {
        if boxes.iter().any(|b| segment_hits_box(a, v - a, 1.0, b)) {
            return true;
        }
        a = v;
    }
    pts.escape != Vec3::ZERO
        && boxes
            .iter()
            .any(|b| segment_hits_box(a, pts.escape, f32::INFINITY, b))
}

/// Padding of a [`PathSummary`]'s box: absolute 1e-4 plus 1e-5 of the coordinate. The
/// exact segment test ([`segment_hits_box`]) rounds its slab distances in `f32`
/// (relative error a few 1e-7), so it may report a crossing a hair outside the box; the
/// padding, two orders of magnitude larger, keeps every such segment among the
/// candidates (the box test must never rule out what the exact test accepts).
pub const SUMMARY_PAD: (f32, f32) = (1e-4, 1e-5);

impl PathSummary {
    /// The summary of `rec`, its points on `quant` (none without it).
    pub fn of(rec: &PhotonRecord, quant: Option<&QuantGrid>) -> PathSummary {
        let mut s = PathSummary {
            lo: Vec3::splat(f32::INFINITY),
            hi: Vec3::splat(f32::NEG_INFINITY),
            instances: 0,
            materials: 0,
            light: rec.light,
            vertices: rec.vertices.len() as u32,
            q: [[0; 3]; QUANT_POINTS + 1],
            quantized: false,
            escapes: rec.escape != Vec3::ZERO,
        };
        if rec.light == NONE {
            return s;
        }
        if let Some(g) = quant
            && rec.vertices.len() < QUANT_POINTS
        {
            s.quantized = true;
            let pts = std::iter::once(rec.origin).chain(rec.vertices.iter().map(|v| v.p));
            let mut last = rec.origin;
            for (k, p) in pts.enumerate() {
                match g.quantize(p) {
                    Some(q) => s.q[k] = q,
                    None => s.quantized = false,
                }
                last = p;
            }
            if s.escapes {
                match g.exit(last, rec.escape) {
                    Some(q) => s.q[rec.vertices.len() + 1] = q,
                    None => s.quantized = false,
                }
            }
        }
        s.lo = rec.origin;
        s.hi = rec.origin;
        for v in &rec.vertices {
            s.lo = s.lo.min(v.p);
            s.hi = s.hi.max(v.p);
            s.instances |= 1u64 << (v.instance % 64);
            s.materials |= 1u64 << (v.material % 64);
        }
        let pad = |x: Vec3| Vec3::splat(SUMMARY_PAD.0) + x.abs() * SUMMARY_PAD.1;
        let (plo, phi) = (pad(s.lo), pad(s.hi));
        s.lo -= plo;
        s.hi += phi;
        let e = rec.escape;
        for k in 0..3 {
            if e[k] > 0.0 {
                s.hi[k] = f32::INFINITY;
            } else if e[k] < 0.0 {
                s.lo[k] = f32::NEG_INFINITY;
            } else if e[k].is_nan() {
                s.lo[k] = f32::NEG_INFINITY;
                s.hi[k] = f32::INFINITY;
            }
        }
        s
    }

    /// The box meets one of `boxes` (closed intervals).
    #[inline]
    pub fn overlaps_any(&self, boxes: &[Bounds3]) -> bool {
        boxes.iter().any(|b| {
            self.lo.x <= b.max.x
                && self.hi.x >= b.min.x
                && self.lo.y <= b.max.y
                && self.hi.y >= b.min.y
                && self.lo.z <= b.max.z
                && self.hi.z >= b.min.z
        })
    }
}

/// A 16-bit grid over the box of the stored paths for the points of a [`PathSummary`]: the
/// scan tests a candidate's segments on these points (inside the summary, which it reads
/// anyway, one sequential pass) against the changed bounds grown by [`QuantGrid::grow`],
/// and reads its scattered [`PathPoints`] for the exact test only when that cannot rule
/// it out. Conservative: a point is moved by at most half a step per axis by rounding to
/// the grid (points outside it are not quantized), so every point of a true segment lies
/// within half a step (per axis) of the quantized segment; the boxes grow by two steps
/// plus [`SUMMARY_PAD`], which also covers the slab test's own rounding on both sides.
/// Not kept in `scratch` order (which does not scan).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuantGrid {
    lo: Vec3,
    step: Vec3,
    inv: Vec3,
}

impl QuantGrid {
    /// The grid over the box of the records' points, padded by 1 % of its diagonal.
    pub fn over(records: &[PhotonRecord]) -> QuantGrid {
        let mut b = Bounds3::EMPTY;
        for r in records.iter().filter(|r| r.light != NONE) {
            b.grow(r.origin);
            for v in &r.vertices {
                b.grow(v.p);
            }
        }
        if b.is_empty() {
            b = Bounds3 {
                min: Vec3::splat(-1.0),
                max: Vec3::splat(1.0),
            };
        }
        let m = Vec3::splat(0.01 * b.diagonal().length().max(1e-3));
        let (lo, hi) = (b.min - m, b.max + m);
        let step = (hi - lo) / 65535.0;
        QuantGrid {
            lo,
            step,
            inv: Vec3::ONE / step,
        }
    }

    /// `p` on the grid (nearest grid point), `None` outside it (or not finite).
    #[inline]
    pub fn quantize(&self, p: Vec3) -> Option<[u16; 3]> {
        let t = ((p - self.lo) * self.inv).round();
        (0..3)
            .all(|k| t[k] >= 0.0 && t[k] <= 65535.0)
            .then_some([t.x as u16, t.y as u16, t.z as u16])
    }

    /// Where the ray from `a` (inside the grid box) along `d` leaves the grid box, on the
    /// grid (clamped: the computed exit may round a hair outside); `None` when `a` is
    /// outside or `d` has a NaN component.
    pub fn exit(&self, a: Vec3, d: Vec3) -> Option<[u16; 3]> {
        self.quantize(a)?;
        let hi = self.lo + self.step * 65535.0;
        let mut t = f32::INFINITY;
        for k in 0..3 {
            if d[k].is_nan() {
                return None;
            }
            if d[k] > 0.0 {
                t = t.min((hi[k] - a[k]) / d[k]);
            } else if d[k] < 0.0 {
                t = t.min((self.lo[k] - a[k]) / d[k]);
            }
        }
        if !t.is_finite() {
            return None;
        }
        let p = ((a + d * t.max(0.0) - self.lo) * self.inv).round();
        let c = |x: f32| x.clamp(0.0, 65535.0) as u16;
        Some([c(p.x), c(p.y), c(p.z)])
    }

    /// Every point of `b` lies strictly inside the grid box.
    pub fn contains(&self, b: &Bounds3) -> bool {
        let hi = self.lo + self.step * 65535.0;
        (0..3).all(|k| b.min[k] > self.lo[k] && b.max[k] < hi[k])
    }

    /// The grid point `q`.
    #[inline]
    pub fn point(&self, q: [u16; 3]) -> Vec3 {
        self.lo + Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * self.step
    }

    /// `b` grown by two grid steps and [`SUMMARY_PAD`] of its coordinates per axis.
    pub fn grow(&self, b: &Bounds3) -> Bounds3 {
        let m = b.min.abs().max(b.max.abs());
        let g = self.step * 2.0 + Vec3::splat(SUMMARY_PAD.0) + m * SUMMARY_PAD.1;
        Bounds3 {
            min: b.min - g,
            max: b.max + g,
        }
    }

    /// Some segment of the quantized path of `s` (which must be `quantized`) passes
    /// through one of `grown` (boxes grown by [`QuantGrid::grow`], for an escaping path
    /// all inside the grid box): false only when no segment of the true path can cross
    /// the ungrown boxes (the escape ray's part inside the grid box is the segment to its
    /// exit point; beyond it the ray is outside every grown box).
    #[inline]
    pub fn may_cross(&self, s: &PathSummary, grown: &[Bounds3]) -> bool {
        let n = s.vertices as usize + s.escapes as usize;
        let mut a = self.point(s.q[0]);
        for q in &s.q[1..=n] {
            let v = self.point(*q);
            // The segment's box first (exact comparisons: a segment lies in its box), the
            // slab test only for the segments whose box meets a grown bound.
            let (lo, hi) = (a.min(v), a.max(v));
            if grown.iter().any(|b| {
                lo.cmple(b.max).all() && hi.cmpge(b.min).all() && segment_hits_box(a, v - a, 1.0, b)
            }) {
                return true;
            }
            a = v;
        }
        false
    }
}

/// The changes of a [`FrameDelta`] as the [`PathSummary`] test reads them.
pub struct ChangeMasks {
    instances: u64,
    materials: u64,
    /// Per light: a path from it touches the change (its light changed, or the selection).
    lights: Vec<bool>,
    /// At most 64 instances and 64 materials: one bit each, so [`ChangeMasks::may_touch`]
    /// is exactly [`PhotonRecord::touches`].
    pub exact: bool,
}

impl ChangeMasks {
    pub fn new(changes: &FrameDelta, scene: &FrameScene, selection_changed: bool) -> Self {
        let mut m = ChangeMasks {
            instances: 0,
            materials: 0,
            lights: (0..scene.lights.len())
                .map(|l| selection_changed || changes.light_changed(l))
                .collect(),
            exact: scene.accel.instances().len() <= 64 && scene.materials.len() <= 64,
        };
        for i in 0..scene.accel.instances().len() {
            if changes.instance_changed(i) {
                m.instances |= 1u64 << (i % 64);
            }
        }
        for k in 0..scene.materials.len() {
            if changes.material_changed(k) {
                m.materials |= 1u64 << (k % 64);
            }
        }
        m
    }

    /// The path may [touch](PhotonRecord::touches) the change (never false when it does;
    /// exactly whether it does when `exact`).
    #[inline]
    pub fn may_touch(&self, s: &PathSummary) -> bool {
        (s.light != NONE && self.lights.get(s.light as usize).copied().unwrap_or(true))
            || s.instances & self.instances != 0
            || s.materials & self.materials != 0
    }
}

/// Traces photon `i` in `scene` and records its path on `mesh`'s elements.
pub fn trace_record(
    scene: &FrameScene,
    mesh: &ElementMesh,
    i: u64,
    seed: u64,
) -> (PhotonRecord, PhotonStats) {
    let mut verts = Vec::new();
    let (head, stats) = trace_into(scene, mesh, i, seed, &mut verts);
    let rec = PhotonRecord {
        light: head.light,
        origin: head.origin,
        vertices: verts,
        escape: head.escape,
    };
    (rec, stats)
}

/// A path of a [`TracedBatch`]: its light, emission point and escape direction as in a
/// [`PhotonRecord`], its vertices `verts[start .. start + len]` of the batch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathHead {
    pub light: u32,
    pub origin: Vec3,
    pub escape: Vec3,
    pub start: u32,
    pub len: u32,
}

/// Paths traced together, all their vertices in one buffer: tracing a batch allocates
/// per batch, not per photon (what re-shooting stores is copied into the photon's
/// record in place, [`SptState`]'s `store_traced`).
#[derive(Clone, Debug, Default)]
pub struct TracedBatch {
    pub heads: Vec<PathHead>,
    pub verts: Vec<RecVertex>,
}

impl TracedBatch {
    /// The vertices of path `k`.
    #[inline]
    pub fn vertices(&self, k: usize) -> &[RecVertex] {
        let h = &self.heads[k];
        &self.verts[h.start as usize..(h.start + h.len) as usize]
    }
}

/// Traces photon `i` and appends its vertices to `verts` (what [`trace_record`] records).
fn trace_into(
    scene: &FrameScene,
    mesh: &ElementMesh,
    i: u64,
    seed: u64,
    verts: &mut Vec<RecVertex>,
) -> (PathHead, PhotonStats) {
    let mut head = PathHead {
        light: NONE,
        origin: Vec3::ZERO,
        escape: Vec3::ZERO,
        start: verts.len() as u32,
        len: 0,
    };
    let mut escape = Vec3::ZERO;
    let stats = trace_photon_path(
        scene,
        i,
        seed,
        |l, ray| {
            head.light = l as u32;
            head.origin = ray.o;
        },
        |v| {
            let h = &v.hit;
            let (s, kind) = if v.deposited {
                let e = mesh.locate(h.tri, h.b1, h.b2).element;
                let kind = if !h.is_indirect() {
                    DIRECT
                } else if h.caustic {
                    CAUSTIC
                } else {
                    INDIRECT
                };
                (slot(e, h.wi.dot(h.ng) >= 0.0) as u32, kind)
            } else {
                (NONE, DIRECT)
            };
            verts.push(RecVertex {
                p: h.p,
                instance: h.instance,
                material: v.material,
                tri: h.tri,
                slot: s,
                kind,
                power: h.power,
            });
        },
        |ray| escape = ray.d,
    );
    head.escape = escape;
    head.len = verts.len() as u32 - head.start;
    (head, stats)
}

/// Traces photons `indices` in parallel into batches (in the order of `indices`: the
/// batches in order, each path in order within its batch).
pub fn trace_batches(
    scene: &FrameScene,
    mesh: &ElementMesh,
    indices: &[u64],
    seed: u64,
) -> (Vec<TracedBatch>, PhotonStats) {
    let chunks = parallel::map_chunks(indices.len(), 256, |r| {
        let mut st = PhotonStats::default();
        let mut b = TracedBatch {
            heads: Vec::with_capacity(r.len()),
            verts: Vec::with_capacity(4 * r.len()),
        };
        for &i in &indices[r] {
            let (h, s) = trace_into(scene, mesh, i, seed, &mut b.verts);
            st += s;
            b.heads.push(h);
        }
        (b, st)
    });
    let mut out = Vec::with_capacity(chunks.len());
    let mut stats = PhotonStats::default();
    for (b, s) in chunks {
        out.push(b);
        stats += s;
    }
    (out, stats)
}

/// Traces photons `indices` in parallel; records in the order of `indices`.
pub fn trace_records(
    scene: &FrameScene,
    mesh: &ElementMesh,
    indices: &[u64],
    seed: u64,
) -> (Vec<PhotonRecord>, PhotonStats) {
    let chunks = parallel::map_chunks(indices.len(), 256, |r| {
        let mut st = PhotonStats::default();
        let v: Vec<PhotonRecord> = indices[r]
            .iter()
            .map(|&i| {
                let (rec, s) = trace_record(scene, mesh, i, seed);
                st += s;
                rec
            })
            .collect();
        (v, st)
    });
    let mut out = Vec::with_capacity(indices.len());
    let mut stats = PhotonStats::default();
    for (v, s) in chunks {
        out.extend(v);
        stats += s;
    }
    (out, stats)
}

/// Per element side photon sums that accept negative deposits.
///
/// Sums are kept in `f64` and a removed photon subtracts exactly the values it added (its
/// stored deposits), so the sums always describe the photons currently in the solution:
/// `count` is their number on the side (a removal decrements it) and `flux_sq` their
/// Σ luminance(φ)², the same noise estimate as for unsigned sums
/// ([`crate::kernels::elements::reconstruct`]) — a removal does not add variance, it takes the removed
/// photon's term out. Adding and removing the same deposit returns every sum to its old
/// value up to one `f64` rounding per operation (relative 1e-16).
#[derive(Clone, Debug)]
pub struct SignedAccumulators {
    pub flux: Vec<[f64; 3]>,
    pub count: Vec<i64>,
    pub flux_sq: Vec<f64>,
}

impl SignedAccumulators {
    pub fn new(elements: usize) -> Self {
        SignedAccumulators {
            flux: vec![[0.0; 3]; 2 * elements],
            count: vec![0; 2 * elements],
            flux_sq: vec![0.0; 2 * elements],
        }
    }

    /// Adds (`sign = 1`) or removes (`sign = −1`) one deposit.
    #[inline]
    pub fn deposit(&mut self, slot: usize, power: Rgb, sign: f64) {
        let f = &mut self.flux[slot];
        f[0] += sign * power.x as f64;
        f[1] += sign * power.y as f64;
        f[2] += sign * power.z as f64;
        self.count[slot] += sign as i64;
        let l = luminance(power) as f64;
        self.flux_sq[slot] += sign * l * l;
    }

    /// The sums as the (unsigned, `f32`) accumulators the reconstruction reads, for
    /// `photons` photons in the solution. Tiny negative leftovers of cancellation are
    /// clamped to 0 (a side's true sum of positive photon powers is never negative).
    pub fn to_accumulators(&self, photons: u64) -> ElementAccumulators {
        ElementAccumulators {
            flux: self
                .flux
                .iter()
                .map(|f| Rgb::new(f[0] as f32, f[1] as f32, f[2] as f32).max(Rgb::ZERO))
                .collect(),
            count: self.count.iter().map(|&c| c.max(0) as u32).collect(),
            flux_sq: self.flux_sq.iter().map(|&s| s.max(0.0) as f32).collect(),
            photons,
        }
    }

    /// Sides (two per element).
    pub fn len(&self) -> usize {
        self.flux.len()
    }

    /// No sides.
    pub fn is_empty(&self) -> bool {
        self.flux.is_empty()
    }

    /// Every side's flux sum.
    pub fn flux(&self) -> Vec<[f64; 3]> {
        self.flux.clone()
    }

    /// Every side's photon count.
    pub fn count(&self) -> Vec<i64> {
        self.count.clone()
    }

    /// Every side's Σ luminance(φ)².
    pub fn flux_sq(&self) -> Vec<f64> {
        self.flux_sq.clone()
    }

    /// Luminance of the flux sum of a side.
    #[inline]
    pub fn lum(&self, slot: usize) -> f64 {
        let f = self.flux[slot];
        0.2126 * f[0] + 0.7152 * f[1] + 0.0722 * f[2]
    }
}

/// The element solution of the pool: one signed accumulator per deposit kind.
#[derive(Clone, Debug)]
pub struct Solution {
    pub direct: SignedAccumulators,
    pub indirect: SignedAccumulators,
    pub caustic: SignedAccumulators,
}

impl Solution {
    pub fn new(elements: usize) -> Self {
        Solution {
            direct: SignedAccumulators::new(elements),
            indirect: SignedAccumulators::new(elements),
            caustic: SignedAccumulators::new(elements),
        }
    }

    /// Adds or removes every deposit of a record.
    pub fn apply(&mut self, rec: &PhotonRecord, sign: f64) {
        self.apply_vertices(&rec.vertices, sign);
    }

    /// Adds or removes every deposit of a path's vertices.
    pub fn apply_vertices(&mut self, vertices: &[RecVertex], sign: f64) {
        for v in vertices {
            if v.slot == NONE {
                continue;
            }
            let acc = match v.kind {
                DIRECT => &mut self.direct,
                INDIRECT => &mut self.indirect,
                _ => &mut self.caustic,
            };
            acc.deposit(v.slot as usize, v.power, sign);
        }
    }
}

/// A limit on how much one call of [`SptState::drain`] re-shoots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Budget {
    /// Most photons traced (0: no limit). Whole groups only: a limit smaller than a
    /// group re-shoots nothing (a budget is never exceeded).
    pub photons: u64,
    /// Most wall-clock time (checked between batches of groups; `None`: no limit).
    pub time: Option<Duration>,
}

impl Budget {
    /// Photons this budget still allows after `traced` in a drain started at `t0`
    /// (`u64::MAX` without a photon limit), or `None` once its time is up.
    fn room(&self, t0: Instant, traced: u64) -> Option<u64> {
        if self.time.is_some_and(|t| t0.elapsed() >= t) {
            return None;
        }
        Some(if self.photons == 0 {
            u64::MAX
        } else {
            self.photons.saturating_sub(traced)
        })
    }

    /// No limit: drain the whole queue.
    pub const ALL: Budget = Budget {
        photons: 0,
        time: None,
    };
    /// Nothing: only the pilots of [`SptState::update`] are traced.
    pub const NONE: Budget = Budget {
        photons: 0,
        time: Some(Duration::ZERO),
    };
}

/// What one update (or drain) did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct UpdateStats {
    /// Pilot photons re-traced.
    pub pilots_traced: u64,
    /// Groups newly marked invalid (pilots and path scan; in scratch order, all groups).
    pub groups_invalidated: u64,
    /// Groups whose pilots saw the change.
    pub groups_by_pilots: u64,
    /// Groups only the scan of the stored paths found (`scan_paths`).
    pub groups_by_scan: u64,
    /// Groups re-shot.
    pub groups_reshot: u64,
    /// Groups still queued afterwards (carried over to the next update).
    pub groups_queued: u64,
    /// Photons traced (pilots included).
    pub photons_traced: u64,
    /// Closest-hit rays cast.
    pub rays: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Photons the path scan flagged (possibly stale).
    pub photons_flagged: u64,
    /// Stored paths the scan read beyond their [`PathSummary`] (all of them with
    /// `scan_bounds = false`).
    pub scan_candidates: u64,
    /// Coverage rays traced again (of `COVERAGE_GRID²`; 0 when all were, or none needed).
    pub coverage_rays_traced: u64,
    /// The update restarted from scratch: the scan flagged more than `restart_fraction`
    /// of the pool, or scratch order.
    pub restarted: bool,
    /// Where the time went.
    pub phases: Phases,
}

/// The clock [`Phases`] are timed with (seconds from any origin), set at most once per
/// process ([`set_phase_clock`]); default wall-clock.
static PHASE_CLOCK: std::sync::OnceLock<fn() -> f64> = std::sync::OnceLock::new();

/// Times [`Phases`] with `clock` from now on (e.g. a CPU clock: `chronolux bench update`
/// sets the process CPU clock, which the workspace's no-unsafe rule keeps out of this
/// crate). False if a clock was set already.
pub fn set_phase_clock(clock: fn() -> f64) -> bool {
    PHASE_CLOCK.set(clock).is_ok()
}

fn phase_clock() -> f64 {
    match PHASE_CLOCK.get() {
        Some(c) => c(),
        None => {
            static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
            START.get_or_init(Instant::now).elapsed().as_secs_f64()
        }
    }
}

/// Seconds of an update's phases, on the clock of [`set_phase_clock`] (wall-clock unless
/// set): what `chronolux bench update` reports (with the process CPU clock) to find the
/// fixed costs of an update.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Phases {
    /// Screen coverage of the element sides (priority order's weights).
    pub coverage: f64,
    /// The scan of the stored paths.
    pub scan: f64,
    /// Order keys of the flagged photons or groups, and sorting the queue.
    pub keys: f64,
    /// Tracing re-shot photons (and pilots).
    pub trace: f64,
    /// Removing old deposits, adding the new ones, storing the records.
    pub apply: f64,
}

impl std::ops::AddAssign<&Phases> for Phases {
    fn add_assign(&mut self, o: &Phases) {
        self.coverage += o.coverage;
        self.scan += o.scan;
        self.keys += o.keys;
        self.trace += o.trace;
        self.apply += o.apply;
    }
}

impl std::ops::AddAssign<&UpdateStats> for UpdateStats {
    fn add_assign(&mut self, o: &UpdateStats) {
        self.pilots_traced += o.pilots_traced;
        self.groups_invalidated += o.groups_invalidated;
        self.groups_by_pilots += o.groups_by_pilots;
        self.groups_by_scan += o.groups_by_scan;
        self.groups_reshot += o.groups_reshot;
        self.groups_queued = o.groups_queued;
        self.photons_traced += o.photons_traced;
        self.rays += o.rays;
        self.seconds += o.seconds;
        self.photons_flagged += o.photons_flagged;
        self.scan_candidates += o.scan_candidates;
        self.coverage_rays_traced += o.coverage_rays_traced;
        self.restarted |= o.restarted;
        self.phases += &o.phases;
    }
}

/// The result of [`SptState::audit`]: what a full re-trace finds stale.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Audit {
    /// Groups with at least one photon whose stored path differs from its path in the
    /// current scene.
    pub stale_groups: u64,
    /// Of those, groups not queued: changed, but their pilots did not see it (misses).
    pub missed_groups: u64,
    /// `missed_groups / stale_groups` (0 when nothing is stale).
    pub miss_rate: f64,
    /// Stale photons in missed groups.
    pub missed_photons: u64,
    /// Stale photons in all.
    pub stale_photons: u64,
}

/// Side length of the grid of primary rays that estimates each element's screen coverage.
pub const COVERAGE_GRID: u32 = 64;

/// The state of selective photon tracing: a fixed pool of `Z` photons on an element mesh,
/// each photon's last path, the signed element solution, and the queue of invalid groups.
///
/// Made for incremental use: [`SptState::update`] takes the next version of the scene
/// with what changed (an animation frame, or an edit in a viewer), traces the pilots and
/// queues the groups they invalidate, then drains the queue within a budget;
/// [`SptState::drain`] continues between updates, [`SptState::queue_len`] says how much
/// is left. Groups queued by one change and not yet re-shot stay queued across later
/// changes (their stored paths, whatever scene they were traced in, are what is removed
/// when they are re-shot).
pub struct SptState {
    pub settings: SptSettings,
    pub layout: GroupLayout,
    pub mesh: ElementMesh,
    scene: Arc<FrameScene>,
    /// Photon `i`'s last path (`i < Z`).
    records: Vec<PhotonRecord>,
    /// Photon `i`'s [`PathSummary`] and [`PathPoints`] (of `records[i]`).
    summaries: Vec<PathSummary>,
    points: Vec<PathPoints>,
    /// The grid of the summaries' points (`None` in `scratch` order, which does not scan).
    quant: Option<QuantGrid>,
    pub solution: Solution,
    /// Per group: its photons are in the solution (false only while a scratch restart
    /// has not reached it).
    in_solution: Vec<bool>,
    /// Photons currently in the solution (the `N` of `Φ / (N·A)`).
    photons_in_solution: u64,
    /// Pilots per group (members `0 .. pilots` of each group).
    pub pilots: u64,
    /// Per photon: the path scan found its stored path possibly stale (with
    /// [`SptSettings::per_photon`]: the photon is in the queue).
    flagged: Vec<bool>,
    /// Per photon, with [`SptSettings::per_photon`]: its order key (larger first).
    pkey: Vec<f64>,
    /// Per group, with [`SptSettings::per_photon`]: its photons in the queue.
    pending: Vec<u32>,
    /// Groups with a photon in the queue, with [`SptSettings::per_photon`].
    queued_groups: u64,
    /// Whether the pilots are current (traced in the current scene); false after a
    /// scratch restart.
    pilots_current: bool,
    queued: Vec<bool>,
    /// Order key of each group (larger first).
    key: Vec<f64>,
    /// Queued groups (with [`SptSettings::per_photon`]: queued photons) sorted by
    /// ascending key (the next one is last).
    queue: Vec<u32>,
    /// Number of updates made (varies the random order between changes).
    epoch: u64,
    /// Screen coverage of each element side (pixels of the coverage grid).
    coverage: Vec<f32>,
    /// The coverage grid's rays in the scene `coverage` was last brought up to date in
    /// (empty: never).
    coverage_rays: Vec<CoverageRay>,
    /// A scratch restart (`restart_fraction`) is being drained: the queue holds groups,
    /// whatever [`SptSettings::per_photon`] says.
    restarting: bool,
}

impl SptState {
    /// Shoots the whole pool in `scene`, on an element mesh built from it.
    pub fn new(scene: Arc<FrameScene>, settings: SptSettings) -> SptState {
        let mesh = ElementMesh::build(&scene, settings.elements_per_diagonal());
        Self::new_on_mesh(scene, settings, mesh)
    }

    /// Shoots the whole pool in `scene` on a given element mesh (element ids of another
    /// state's mesh, for comparisons; it must [match](ElementMesh::matches) `scene`).
    pub fn new_on_mesh(
        scene: Arc<FrameScene>,
        settings: SptSettings,
        mesh: ElementMesh,
    ) -> SptState {
        assert!(mesh.matches(&scene), "element mesh of another topology");
        let layout = GroupLayout::choose(
            settings.photons,
            settings.group_size.max(1),
            used_dims(&scene),
        );
        let n = layout.photons();
        let pilots = ((settings.pilot_fraction as f64 * layout.members as f64).round() as u64)
            .clamp(1, layout.members);
        let indices: Vec<u64> = (0..n).collect();
        let (records, _) = trace_records(&scene, &mesh, &indices, settings.common.seed);
        let quant = (settings.scan_paths && settings.order != Order::Scratch)
            .then(|| QuantGrid::over(&records));
        let summaries = parallel::map_chunks(records.len(), 8192, |r| {
            records[r]
                .iter()
                .map(|rec| PathSummary::of(rec, quant.as_ref()))
                .collect::<Vec<_>>()
        })
        .into_iter()
        .flatten()
        .collect();
        let points = parallel::map_chunks(records.len(), 8192, |r| {
            records[r].iter().map(PathPoints::of).collect::<Vec<_>>()
        })
        .into_iter()
        .flatten()
        .collect();
        let mut solution = Solution::new(mesh.element_count());
        for r in &records {
            solution.apply(r, 1.0);
        }
        let g = layout.groups as usize;
        let coverage = vec![0.0; 2 * mesh.element_count()];
        let mut s = SptState {
            settings,
            layout,
            mesh,
            scene,
            records,
            summaries,
            points,
            quant,
            solution,
            in_solution: vec![true; g],
            photons_in_solution: n,
            pilots,
            flagged: vec![false; n as usize],
            pkey: Vec::new(),
            pending: vec![0; g],
            queued_groups: 0,
            pilots_current: true,
            queued: vec![false; g],
            key: vec![0.0; g],
            queue: Vec::new(),
            epoch: 0,
            coverage,
            coverage_rays: Vec::new(),
            restarting: false,
        };
        if s.settings.per_photon() {
            s.pkey = vec![0.0; n as usize];
        }
        if s.settings.order == Order::Priority {
            s.coverage_rays = coverage_rays(&s.scene, &s.mesh, COVERAGE_GRID);
            s.coverage = coverage_from_rays(&s.coverage_rays, s.mesh.element_count());
        }
        s
    }

    /// Stores `rec` as photon `i`'s path (and its summary).
    #[inline]
    fn store(&mut self, i: usize, rec: PhotonRecord) {
        self.summaries[i] = PathSummary::of(&rec, self.quant.as_ref());
        self.points[i] = PathPoints::of(&rec);
        self.records[i] = rec;
    }

    /// Stores path `k` of `batch` as photon `i`'s path, in place: the record keeps its
    /// vertex buffer (no allocation unless the new path is longer than any before it).
    #[inline]
    fn store_traced(&mut self, i: usize, batch: &TracedBatch, k: usize) {
        let h = batch.heads[k];
        let r = &mut self.records[i];
        r.light = h.light;
        r.origin = h.origin;
        r.escape = h.escape;
        r.vertices.clear();
        r.vertices.extend_from_slice(batch.vertices(k));
        self.summaries[i] = PathSummary::of(r, self.quant.as_ref());
        self.points[i] = PathPoints::of(r);
    }

    /// Whether the queue holds single photons: [`SptSettings::per_photon`], except during
    /// a scratch restart.
    fn photon_queue(&self) -> bool {
        self.settings.per_photon() && !self.restarting
    }

    /// Photon `i` is flagged: found possibly stale by the path scan and not yet re-shot.
    pub fn flagged(&self, i: u64) -> bool {
        self.flagged[i as usize]
    }

    /// The screen coverage of each element side the priority keys weigh by (pixels of the
    /// `COVERAGE_GRID²` grid; zeros in orders that need no keys).
    pub fn coverage(&self) -> &[f32] {
        &self.coverage
    }

    /// The scene the solution is (being brought) up to date with.
    pub fn scene(&self) -> &Arc<FrameScene> {
        &self.scene
    }

    /// Groups waiting to be re-shot (with [`SptSettings::per_photon`]: groups with a
    /// photon waiting).
    pub fn queue_len(&self) -> usize {
        if self.photon_queue() {
            self.queued_groups as usize
        } else {
            self.queue.len()
        }
    }

    /// Photons waiting to be re-shot: the queued photons with
    /// [`SptSettings::per_photon`], else the members of the queued groups that their
    /// re-shooting will trace.
    pub fn queued_photons(&self) -> u64 {
        if self.photon_queue() {
            return self.queue.len() as u64;
        }
        let only_flagged =
            self.settings.scan_paths && self.settings.reshoot == super::Reshoot::Flagged;
        let skip = if self.pilots_current { self.pilots } else { 0 };
        let n = self.layout.groups;
        self.queue
            .iter()
            .map(|&g| {
                (skip..self.layout.members)
                    .filter(|&m| {
                        let i = g as u64 + m * n;
                        !only_flagged || !self.in_solution[g as usize] || self.flagged[i as usize]
                    })
                    .count() as u64
            })
            .sum()
    }

    /// Photons currently in the solution.
    pub fn photons_in_solution(&self) -> u64 {
        self.photons_in_solution
    }

    /// Photon `i`'s stored path.
    pub fn record(&self, i: u64) -> &PhotonRecord {
        &self.records[i as usize]
    }

    /// Whether `scene` can update this state (same geometry topology and light count:
    /// element ids and light indices carry over). Otherwise build a new state.
    pub fn accepts(&self, scene: &FrameScene) -> bool {
        self.mesh.matches(scene) && scene.lights.len() == self.scene.lights.len()
    }

    /// Takes `scene` as the new current scene (`changes`: what differs from the current
    /// one, [`FrameDelta::between`]), traces the pilots and queues the groups they
    /// invalidate, then re-shoots queued groups within `budget`.
    pub fn update(
        &mut self,
        scene: Arc<FrameScene>,
        changes: &FrameDelta,
        budget: Budget,
    ) -> UpdateStats {
        let mut st = self.invalidate(scene, changes);
        let d = self.drain(budget);
        st += &d;
        st
    }

    /// The first half of [`SptState::update`]: new scene, pilots, queue.
    pub fn invalidate(&mut self, scene: Arc<FrameScene>, changes: &FrameDelta) -> UpdateStats {
        let t0 = Instant::now();
        assert!(
            self.accepts(&scene),
            "SptState::invalidate: topology changed"
        );
        let selection_changed = (0..scene.lights.len())
            .any(|l| scene.light_sampler.pmf(l) != self.scene.light_sampler.pmf(l));
        self.scene = scene;
        self.epoch += 1;
        let mut st = UpdateStats::default();
        let groups = self.layout.groups;
        // Only priority order reads the keys, and so the screen coverage they weigh by.
        let keyed = self.settings.order == Order::Priority;
        if self.settings.order == Order::Scratch || self.restarting {
            // Recomputation from scratch (or a change during a scratch restart: it starts
            // over, as scratch order does).
            self.restart(&mut st);
        } else if !changes.is_static() {
            let tol = self.settings.path_tolerance;
            let mut change = vec![0.0f64; groups as usize];
            let mut invalid = vec![false; groups as usize];
            let use_pilots = self.settings.uses_pilots();
            // Φ₀ of the keys, from the solution before the pilots change it (without
            // pilots it is taken below from the same per-side totals as the weights).
            let mut phi0 = 0.0;
            if keyed && use_pilots {
                let t = phase_clock();
                phi0 = flux_floor(&self.side_totals());
                st.phases.keys += phase_clock() - t;
            }
            if use_pilots {
                if keyed {
                    self.update_coverage(changes, &mut st);
                }
                let t = phase_clock();
                let pilots: Vec<u64> = (0..groups)
                    .flat_map(|g| (0..self.pilots).map(move |m| (g, m)))
                    .map(|(g, m)| self.layout.photon(g, m))
                    .collect();
                let (new, ps) =
                    trace_records(&self.scene, &self.mesh, &pilots, self.settings.common.seed);
                st.phases.trace += phase_clock() - t;
                let t = phase_clock();
                st.pilots_traced = pilots.len() as u64;
                st.photons_traced += pilots.len() as u64;
                st.rays += ps.rays;
                for (&i, rec) in pilots.iter().zip(new) {
                    let g = self.layout.group_of(i) as usize;
                    let old = &self.records[i as usize];
                    let differs = old.differs(&rec, tol);
                    if differs
                        || old.touches(changes, selection_changed)
                        || rec.touches(changes, selection_changed)
                    {
                        invalid[g] = true;
                    }
                    if differs && keyed {
                        change[g] += self.perceived_change(old, &rec, phi0);
                    }
                    if *old != rec {
                        // The pilot itself is brought up to date at once (also when it differs
                        // by less than the tolerance: the pool stays exactly current).
                        if self.in_solution[g] {
                            self.solution.apply(old, -1.0);
                            self.solution.apply(&rec, 1.0);
                        }
                        self.store(i as usize, rec);
                    }
                }
                st.phases.apply += phase_clock() - t;
                self.pilots_current = true;
                st.groups_by_pilots = invalid.iter().filter(|&&b| b).count() as u64;
            } else {
                // No pilots: they are re-shot like any other photon (the scan covers them).
                self.pilots_current = false;
            }
            let per_photon = self.photon_queue();
            if self.settings.scan_paths {
                // Every stored path that touched a change, or whose segments cross the
                // new bounds of a changed instance, is (possibly) stale: its group goes
                // into the queue too, with the change its removal makes as its weight.
                // `changes` is from the pool's previous scene to `self.scene` (frame 1).
                let t = phase_clock();
                // Pilots are current already when traced above.
                let first_non_pilot = if use_pilots {
                    (self.pilots * groups) as usize
                } else {
                    0
                };
                let (hits, candidates) = self.scan(changes, selection_changed, first_non_pilot);
                st.scan_candidates = candidates;
                st.photons_flagged = hits.len() as u64;
                st.phases.scan += phase_clock() - t;
                let z = self.records.len() as f64;
                if hits.len() as f64 > self.settings.restart_fraction * z {
                    // Nearly every photon is flagged: re-shooting them one by one (remove,
                    // add, keys, queue) costs more than shooting the pool again.
                    self.restart(&mut st);
                    self.sort_queue();
                    st.groups_queued = self.queue.len() as u64;
                    st.seconds = t0.elapsed().as_secs_f64();
                    return st;
                }
                if keyed && !use_pilots {
                    self.update_coverage(changes, &mut st);
                }
                let t = phase_clock();
                let w = if keyed {
                    let totals = self.side_totals();
                    if !use_pilots {
                        phi0 = flux_floor(&totals);
                    }
                    self.side_weights(totals, phi0)
                } else {
                    Vec::new()
                };
                for i in hits {
                    let g = i % groups as usize;
                    if !invalid[g] {
                        invalid[g] = true;
                        st.groups_by_scan += 1;
                    }
                    let c = if keyed {
                        removal_change(&self.records[i], &w)
                    } else {
                        0.0
                    };
                    if per_photon {
                        let k = match self.settings.order {
                            Order::Random => self.random_key(i as u64, 0x0050_4854),
                            _ => c + 1e-30,
                        };
                        self.enqueue_photon(i, k);
                    } else {
                        self.flagged[i] = true;
                    }
                    change[g] += c;
                }
                st.phases.keys += phase_clock() - t;
            }
            let t = phase_clock();
            for g in 0..groups as usize {
                if !invalid[g] {
                    continue;
                }
                st.groups_invalidated += 1;
                if per_photon {
                    // Queued photon by photon above.
                    continue;
                }
                let k = match self.settings.order {
                    Order::Random => {
                        (hash_words(&[
                            self.settings.common.seed,
                            self.epoch,
                            g as u64,
                            0x0053_5054,
                        ]) >> 11) as f64
                    }
                    // A tiny floor keeps groups that touched a change without a visible
                    // difference in the queue (last).
                    _ => change[g] + 1e-30,
                };
                if self.queued[g] {
                    if self.settings.order != Order::Random {
                        self.key[g] += k;
                    }
                } else {
                    self.queued[g] = true;
                    self.key[g] = k;
                }
            }
            st.phases.keys += phase_clock() - t;
        }
        let t = phase_clock();
        self.sort_queue();
        st.phases.keys += phase_clock() - t;
        st.groups_queued = self.queue_len() as u64;
        st.seconds = t0.elapsed().as_secs_f64();
        st
    }

    /// Starts a recomputation from scratch: empty solution, every group queued in index
    /// order (the key makes group 0 come first), re-shot whole by the group drain; any
    /// photon queued before is dropped from the queue (the restart re-shoots it anyway).
    fn restart(&mut self, st: &mut UpdateStats) {
        let groups = self.layout.groups;
        self.solution = Solution::new(self.mesh.element_count());
        self.in_solution.iter_mut().for_each(|b| *b = false);
        self.photons_in_solution = 0;
        self.pilots_current = false;
        self.flagged.iter_mut().for_each(|b| *b = false);
        self.pending.iter_mut().for_each(|p| *p = 0);
        self.queued_groups = 0;
        for g in 0..groups as usize {
            self.queued[g] = true;
            self.key[g] = -(g as f64);
        }
        self.restarting = self.settings.order != Order::Scratch;
        st.restarted = true;
        st.groups_invalidated = groups;
    }

    /// The path scan: the photons (from `first` on) whose stored path touches `changes` or
    /// crosses the new bounds of a changed instance, in index order, and how many paths
    /// passed the summary test (all of them with `scan_bounds = false`).
    ///
    /// With `scan_bounds` each path's [`PathSummary`] is tested first, from one contiguous
    /// array: a path whose instance and material masks miss every changed one and whose
    /// (padded) box overlaps no changed bound can neither touch nor cross the change; with
    /// at most 64 instances and materials the masks answer `touches` exactly. Only the
    /// paths whose box meets a changed bound, and (for paths of at most `QUANT_POINTS −
    /// 1` vertices) one of whose quantized segments meets it grown by
    /// [`QuantGrid::grow`] ([`QuantGrid::may_cross`], from the summary too), go on
    /// (`candidates`) to the exact segment test, on their [`PathPoints`] (another
    /// contiguous array; the scattered record only for paths of more than `PATH_POINTS −
    /// 1` vertices) — the flags are those of the full scan (tested against it).
    fn scan(
        &self,
        changes: &FrameDelta,
        selection_changed: bool,
        first: usize,
    ) -> (Vec<usize>, u64) {
        let boxes = changes.changed_bounds_in(1);
        let z = self.records.len();
        let cull = self.settings.scan_bounds;
        let masks = ChangeMasks::new(changes, &self.scene, selection_changed);
        // The changed bounds grown for the quantized points of the summaries.
        let grown: Vec<Bounds3> = match &self.quant {
            Some(g) => boxes.iter().map(|b| g.grow(b)).collect(),
            None => Vec::new(),
        };
        // An escaping path's quantized points end where its ray leaves the grid box, which
        // answers only for bounds inside the box.
        let inside = self
            .quant
            .as_ref()
            .is_some_and(|g| grown.iter().all(|b| g.contains(b)));
        let chunks = parallel::map_chunks(z, 8192, |r| {
            let mut candidates = 0u64;
            let hits = r
                .filter(|&i| {
                    if i < first {
                        return false;
                    }
                    if !cull {
                        candidates += 1;
                        let rec = &self.records[i];
                        return rec.touches(changes, selection_changed) || rec.crosses(&boxes);
                    }
                    let s = &self.summaries[i];
                    let may_touch = masks.may_touch(s);
                    if may_touch && masks.exact {
                        return true;
                    }
                    let may_cross = s.overlaps_any(&boxes)
                        && !(s.quantized
                            && (inside || !s.escapes)
                            && self.quant.as_ref().is_some_and(|g| !g.may_cross(s, &grown)));
                    if !(may_touch || may_cross) {
                        return false;
                    }
                    candidates += 1;
                    let rec = &self.records[i];
                    (may_touch && rec.touches(changes, selection_changed))
                        || (may_cross && crosses_from(s, &self.points[i], rec, &boxes))
                })
                .collect::<Vec<usize>>();
            (hits, candidates)
        });
        let mut hits = Vec::new();
        let mut candidates = 0;
        for (h, c) in chunks {
            hits.extend(h);
            candidates += c;
        }
        (hits, candidates)
    }

    /// Brings the screen coverage of the element sides to the current scene. Only the
    /// coverage rays the change can affect are traced again: all of them when the camera
    /// changed, else those whose stored first hit lies on a changed instance or whose
    /// segment from the camera to it (the whole ray when it escaped) crosses the new bounds
    /// of a changed instance — a ray that does neither hits what it hit before (a new
    /// first hit would be on a changed instance, inside its new bounds, nearer than the
    /// old one); all of them also when a material changed. The result equals a full
    /// [`screen_coverage`] (tested).
    fn update_coverage(&mut self, changes: &FrameDelta, st: &mut UpdateStats) {
        let t = phase_clock();
        // A material change may change what a ray hits (alpha masks): everything again.
        if changes.camera_changed() || changes.materials_changed() || self.coverage_rays.is_empty()
        {
            self.coverage_rays = coverage_rays(&self.scene, &self.mesh, COVERAGE_GRID);
        } else {
            let boxes = changes.changed_bounds_in(1);
            let scene = &self.scene;
            let mesh = &self.mesh;
            let n = COVERAGE_GRID;
            let rays = &self.coverage_rays;
            let redo: Vec<usize> = (0..rays.len())
                .filter(|&k| {
                    let c = &rays[k];
                    (c.instance != NONE && changes.instance_changed(c.instance as usize)) || {
                        let ray = coverage_ray(scene, n, k);
                        boxes.iter().any(|b| segment_hits_box(ray.o, ray.d, c.t, b))
                    }
                })
                .collect();
            let fresh = parallel::map_chunks(redo.len(), 64, |r| {
                redo[r]
                    .iter()
                    .map(|&k| trace_coverage_ray(scene, mesh, n, k))
                    .collect::<Vec<_>>()
            });
            for (&k, c) in redo.iter().zip(fresh.into_iter().flatten()) {
                self.coverage_rays[k] = c;
            }
            st.coverage_rays_traced = redo.len() as u64;
        }
        self.coverage = coverage_from_rays(&self.coverage_rays, self.mesh.element_count());
        st.phases.coverage += phase_clock() - t;
    }

    /// A random order key for photon or group `i` in this epoch (`tag` tells the uses apart).
    fn random_key(&self, i: u64, tag: u64) -> f64 {
        (hash_words(&[self.settings.common.seed, self.epoch, i, tag]) >> 11) as f64
    }

    /// Puts photon `i` in the queue with key `k` ([`SptSettings::per_photon`]); one already
    /// there keeps its random key, or adds `k` to its priority.
    fn enqueue_photon(&mut self, i: usize, k: f64) {
        if self.flagged[i] {
            if self.settings.order != Order::Random {
                self.pkey[i] += k;
            }
            return;
        }
        self.flagged[i] = true;
        self.pkey[i] = k;
        let g = i % self.layout.groups as usize;
        self.pending[g] += 1;
        if self.pending[g] == 1 {
            self.queued[g] = true;
            self.queued_groups += 1;
        }
    }

    /// Perceptual size of the change from path `old` to `new`: over the element sides
    /// whose displayed (indirect and caustic) flux changes, Σ |ΔΦ| / (Φ + Φ₀) · (c + c₀):
    /// a Weber contrast against the side's current total flux Φ (direct photons included,
    /// they mask indirect changes; Φ₀ = 1 % of the mean per-side flux keeps dark sides
    /// finite), weighted by the side's screen coverage `c` in pixels of the coverage grid
    /// (`c₀ = 0.1`: sides off screen still count a little, their light reaches the screen
    /// by further bounces).
    fn perceived_change(&self, old: &PhotonRecord, new: &PhotonRecord, phi0: f64) -> f64 {
        let mut out = 0.0;
        let sol = &self.solution;
        let mut one = |rec: &PhotonRecord, sign: f64| {
            for v in &rec.vertices {
                if v.slot == NONE || v.kind == DIRECT {
                    continue;
                }
                let s = v.slot as usize;
                let total = sol.direct.lum(s) + sol.indirect.lum(s) + sol.caustic.lum(s);
                let c = self.coverage[s] as f64 + 0.1;
                out += sign.abs() * luminance(v.power) as f64 / (total.max(0.0) + phi0) * c;
            }
        };
        one(old, -1.0);
        one(new, 1.0);
        out
    }

    /// Per element side, the luminance of its total flux sum Φ (direct, indirect and
    /// caustic): one pass over the sums serves both [`flux_floor`] and
    /// [`Self::side_weights`].
    fn side_totals(&self) -> Vec<f64> {
        let sol = &self.solution;
        (0..sol.direct.len())
            .map(|k| sol.direct.lum(k) + sol.indirect.lum(k) + sol.caustic.lum(k))
            .collect()
    }

    /// Per element side, the factor of [`Self::perceived_change`] by which a deposit's
    /// luminance counts: `(c + c₀) / (Φ + Φ₀)` (for the keys of the path scan, where the
    /// solution does not change between keys: one read per deposit instead of the four
    /// of the side's sums and coverage), from the sides' `totals` ([`Self::side_totals`]).
    fn side_weights(&self, mut totals: Vec<f64>, phi0: f64) -> Vec<f64> {
        for (t, c) in totals.iter_mut().zip(&self.coverage) {
            *t = (*c as f64 + 0.1) / (t.max(0.0) + phi0);
        }
        totals
    }

    /// Queues `groups` for re-shooting (ahead of every queued group in priority order,
    /// with a fresh random key in random order) whatever their pilots say: for a caller
    /// that knows better (a viewer's "refresh", tests).
    pub fn requeue(&mut self, groups: impl IntoIterator<Item = u64>) {
        if self.photon_queue() {
            for g in groups {
                for m in 0..self.layout.members {
                    let i = self.layout.photon(g, m);
                    let k = match self.settings.order {
                        Order::Random => self.random_key(i, 0x0052_4551),
                        _ => f64::MAX,
                    };
                    if self.flagged[i as usize] {
                        self.pkey[i as usize] = k;
                    } else {
                        self.enqueue_photon(i as usize, k);
                    }
                }
            }
            self.sort_queue();
            return;
        }
        for g in groups {
            for m in 0..self.layout.members {
                self.flagged[self.layout.photon(g, m) as usize] = true;
            }
            let g = g as usize;
            self.queued[g] = true;
            self.key[g] = match self.settings.order {
                Order::Random => {
                    (hash_words(&[self.settings.common.seed, self.epoch, g as u64, 0x0052_4551])
                        >> 11) as f64
                }
                _ => f64::MAX,
            };
        }
        self.sort_queue();
    }

    fn sort_queue(&mut self) {
        if self.photon_queue() {
            self.queue = (0..self.flagged.len() as u32)
                .filter(|&i| self.flagged[i as usize])
                .collect();
            let key = &self.pkey;
            self.queue
                .sort_by(|a, b| key[*a as usize].total_cmp(&key[*b as usize]).then(b.cmp(a)));
            return;
        }
        self.queue = (0..self.layout.groups as u32)
            .filter(|&g| self.queued[g as usize])
            .collect();
        let key = &self.key;
        self.queue
            .sort_by(|a, b| key[*a as usize].total_cmp(&key[*b as usize]).then(b.cmp(a)));
    }

    /// Re-shoots queued groups in queue order within `budget`, one group after the other
    /// (photons of a batch of groups are traced in parallel and applied in queue order,
    /// so the result does not depend on the thread count).
    pub fn drain(&mut self, budget: Budget) -> UpdateStats {
        if self.photon_queue() {
            return self.drain_photons(budget);
        }
        let t0 = Instant::now();
        let mut st = UpdateStats::default();
        let members = self.layout.members;
        let skip = if self.pilots_current { self.pilots } else { 0 };
        let threads = rayon::current_num_threads() as u64;
        let n_groups = self.layout.groups;
        // Only the flagged photons of a group when the flags are complete (path scan on,
        // `reshoot = flagged`) and the group is in the solution; else the whole group.
        let only_flagged =
            self.settings.scan_paths && self.settings.reshoot == super::Reshoot::Flagged;
        loop {
            if self.queue.is_empty() {
                break;
            }
            let Some(room) = budget.room(t0, st.photons_traced) else {
                break;
            };
            // Whole groups in queue order, about 4096 photons per thread between time
            // checks, never past the photon budget.
            let mut groups: Vec<u32> = Vec::new();
            let mut indices: Vec<u64> = Vec::new();
            while let Some(&g) = self.queue.last() {
                let gi = g as usize;
                let before = indices.len();
                for m in skip..members {
                    let i = g as u64 + m * n_groups;
                    if !only_flagged || !self.in_solution[gi] || self.flagged[i as usize] {
                        indices.push(i);
                    }
                }
                if indices.len() as u64 > room {
                    indices.truncate(before);
                    break;
                }
                groups.push(self.queue.pop().unwrap());
                if indices.len() as u64 >= 4096 * threads {
                    break;
                }
            }
            if groups.is_empty() {
                break;
            }
            let t = phase_clock();
            let (batches, ps) =
                trace_batches(&self.scene, &self.mesh, &indices, self.settings.common.seed);
            st.phases.trace += phase_clock() - t;
            let t = phase_clock();
            st.rays += ps.rays;
            st.photons_traced += indices.len() as u64;
            let traced = batches
                .iter()
                .flat_map(|b| (0..b.heads.len()).map(move |k| (b, k)));
            for (&i, (b, k)) in indices.iter().zip(traced) {
                let g = self.layout.group_of(i) as usize;
                if self.in_solution[g] {
                    self.solution
                        .apply_vertices(&self.records[i as usize].vertices, -1.0);
                }
                self.solution.apply_vertices(b.vertices(k), 1.0);
                self.store_traced(i as usize, b, k);
                self.flagged[i as usize] = false;
            }
            for &g in &groups {
                let g = g as usize;
                if !self.in_solution[g] {
                    // A scratch restart reaching this group: its pilots too were traced
                    // above (skip = 0); the group now counts in the solution.
                    self.in_solution[g] = true;
                    self.photons_in_solution += members;
                }
                self.queued[g] = false;
                self.key[g] = 0.0;
            }
            st.groups_reshot += groups.len() as u64;
            st.phases.apply += phase_clock() - t;
        }
        if self.queue.is_empty() && !self.pilots_current {
            self.pilots_current = true;
        }
        if self.queue.is_empty() {
            self.restarting = false;
        }
        st.groups_queued = self.queue.len() as u64;
        st.seconds = t0.elapsed().as_secs_f64();
        st
    }

    /// [`SptState::drain`] when the queue holds photons ([`SptSettings::per_photon`]):
    /// photons in queue order, traced in parallel in batches of about 4096 per thread,
    /// applied in queue order (the result does not depend on the thread count). The photon
    /// budget is met exactly.
    fn drain_photons(&mut self, budget: Budget) -> UpdateStats {
        let t0 = Instant::now();
        let mut st = UpdateStats::default();
        let threads = rayon::current_num_threads() as u64;
        let batch = 4096 * threads;
        let n_groups = self.layout.groups as usize;
        loop {
            if self.queue.is_empty() {
                break;
            }
            let Some(room) = budget.room(t0, st.photons_traced) else {
                break;
            };
            let take = room.min(batch).min(self.queue.len() as u64) as usize;
            if take == 0 {
                break;
            }
            let indices: Vec<u64> = (0..take)
                .map(|_| self.queue.pop().expect("queue holds `take` photons") as u64)
                .collect();
            let t = phase_clock();
            let (batches, ps) =
                trace_batches(&self.scene, &self.mesh, &indices, self.settings.common.seed);
            st.phases.trace += phase_clock() - t;
            let t = phase_clock();
            st.rays += ps.rays;
            st.photons_traced += indices.len() as u64;
            let traced = batches
                .iter()
                .flat_map(|b| (0..b.heads.len()).map(move |k| (b, k)));
            for (&i, (b, k)) in indices.iter().zip(traced) {
                let i = i as usize;
                self.solution
                    .apply_vertices(&self.records[i].vertices, -1.0);
                self.solution.apply_vertices(b.vertices(k), 1.0);
                self.store_traced(i, b, k);
                self.flagged[i] = false;
                let g = i % n_groups;
                self.pending[g] -= 1;
                if self.pending[g] == 0 {
                    self.queued[g] = false;
                    self.queued_groups -= 1;
                    st.groups_reshot += 1;
                }
            }
            st.phases.apply += phase_clock() - t;
        }
        if self.queue.is_empty() && !self.pilots_current {
            self.pilots_current = true;
        }
        st.groups_queued = self.queued_groups;
        st.seconds = t0.elapsed().as_secs_f64();
        st
    }

    /// Re-traces every photon in the current scene and compares with the stored paths:
    /// stale groups, and of them those not queued (missed by their pilots). Costs a full
    /// pass; for tests and `--set audit=true`.
    pub fn audit(&self) -> Audit {
        let n = self.layout.photons();
        let indices: Vec<u64> = (0..n).collect();
        let (recs, _) = trace_records(&self.scene, &self.mesh, &indices, self.settings.common.seed);
        let g = self.layout.groups as usize;
        let mut stale = vec![0u64; g];
        for (i, rec) in recs.iter().enumerate() {
            if self.in_solution[i % g] && self.records[i].differs(rec, self.settings.path_tolerance)
            {
                stale[i % g] += 1;
            }
        }
        let mut a = Audit::default();
        for (k, &s) in stale.iter().enumerate() {
            if s > 0 {
                a.stale_groups += 1;
                a.stale_photons += s;
                if !self.queued[k] {
                    a.missed_groups += 1;
                    a.missed_photons += s;
                }
            }
        }
        a.miss_rate = if a.stale_groups > 0 {
            a.missed_groups as f64 / a.stale_groups as f64
        } else {
            0.0
        };
        a
    }

    /// The element sums as the reconstruction reads them: (direct, indirect, caustic).
    pub fn accumulators(
        &self,
    ) -> (
        ElementAccumulators,
        ElementAccumulators,
        ElementAccumulators,
    ) {
        let n = self.photons_in_solution;
        (
            self.solution.direct.to_accumulators(n),
            self.solution.indirect.to_accumulators(n),
            self.solution.caustic.to_accumulators(n),
        )
    }

    /// World-space element data of the current scene.
    pub fn frame_elements(&self) -> FrameElements {
        FrameElements::new(&self.scene, &self.mesh)
    }
}

/// One primary ray of the coverage grid: the element side it hits first, the instance
/// and the distance (`NONE` and infinity when it leaves the scene).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoverageRay {
    pub slot: u32,
    pub instance: u32,
    pub t: f32,
}

/// Ray `k` (row-major) of the `n × n` coverage grid through pixel centres of `scene`'s
/// camera.
fn coverage_ray(scene: &FrameScene, n: u32, k: usize) -> chronolux_core::geometry::Ray {
    let cam = &scene.camera;
    let (x, y) = ((k as u32) % n, (k as u32) / n);
    let raster = Vec2::new(
        (x as f32 + 0.5) / n as f32 * cam.width as f32,
        (y as f32 + 0.5) / n as f32 * cam.height as f32,
    );
    cam.generate_ray(raster)
}

/// Traces ray `k` of the coverage grid.
fn trace_coverage_ray(scene: &FrameScene, mesh: &ElementMesh, n: u32, k: usize) -> CoverageRay {
    let ray = coverage_ray(scene, n, k);
    match scene.intersect(&ray) {
        Some(h) => {
            let si = scene.interaction(&h, &ray);
            let e = mesh.locate(h.tri, h.b1, h.b2).element;
            CoverageRay {
                slot: slot(e, -ray.d.dot(si.ng) >= 0.0) as u32,
                instance: h.instance,
                t: h.t,
            }
        }
        None => CoverageRay {
            slot: NONE,
            instance: NONE,
            t: f32::INFINITY,
        },
    }
}

/// Every ray of the `n × n` coverage grid, row-major.
pub fn coverage_rays(scene: &FrameScene, mesh: &ElementMesh, n: u32) -> Vec<CoverageRay> {
    let total = (n * n) as usize;
    parallel::map_chunks(total, 4 * n as usize, |r| {
        r.map(|k| trace_coverage_ray(scene, mesh, n, k))
            .collect::<Vec<_>>()
    })
    .into_iter()
    .flatten()
    .collect()
}

/// Per element side (indexed by [`slot`]): the coverage rays whose first hit is on it.
fn coverage_from_rays(rays: &[CoverageRay], elements: usize) -> Vec<f32> {
    let mut c = vec![0.0f32; 2 * elements];
    for r in rays {
        if r.slot != NONE {
            c[r.slot as usize] += 1.0;
        }
    }
    c
}

/// `Φ₀` of [`SptState::perceived_change`]: 1 % of the mean flux sum per element side, from
/// the sides' totals ([`SptState::side_totals`]).
fn flux_floor(totals: &[f64]) -> f64 {
    let n = totals.len().max(1);
    let t: f64 = totals.iter().sum();
    (0.01 * t / n as f64).max(1e-30)
}

/// The perceived change of removing path `rec` ([`SptState::perceived_change`] against an
/// empty path), with the per-side weights `w` of [`SptState::side_weights`].
fn removal_change(rec: &PhotonRecord, w: &[f64]) -> f64 {
    rec.vertices
        .iter()
        .filter(|v| v.slot != NONE && v.kind != DIRECT)
        .map(|v| luminance(v.power) as f64 * w[v.slot as usize])
        .sum()
}

/// Screen coverage of each element side of `mesh` (indexed by [`slot`]): an `n × n` grid of
/// primary rays through pixel centres of `scene`'s camera, counted on the side each hits
/// first.
pub fn screen_coverage(scene: &FrameScene, mesh: &ElementMesh, n: u32) -> Vec<f32> {
    coverage_from_rays(&coverage_rays(scene, mesh, n), mesh.element_count())
}
