//! Ray-tracing acceleration behind our own interface.
//!
//! Two backends behind the same types: Intel Embree 4 where the library loads (the
//! default build fetches it; [`embree`] says why and how), and our own, described here,
//! where it does not or where `accept` filters are needed. [`Accel::intersect_many`] /
//! [`Accel::occluded_many`] trace rays in 16-wide packets on Embree.
//!
//! Two levels, on obvhs' compressed 8-wide BVH (CWBVH): a [`Blas`] per group of triangles
//! in its own space, kept across frames (static geometry is merged into one world-space
//! BLAS built once; each rigidly animated instance keeps its object-space BLAS and only its
//! transform changes; skinned and morphed geometry gets a new BLAS per frame), and a TLAS
//! over the instances rebuilt per frame (a handful of boxes). Closest-hit and any-hit
//! queries take an `accept` filter so alpha-masked surfaces can be skipped during traversal.

pub mod build;
// The FFI to Embree (a C library loaded at run time) is the one unsafe module of the crate.
#[allow(unsafe_code)]
pub mod embree;
pub mod multi_frame;

use crate::geometry::{Bounds3, PreparedTriangle, Ray};
use crate::math::{Affine3A, Vec3, Vec3A};
use obvhs::{
    BvhBuildParams, aabb::Aabb, cwbvh::CwBvh, ray::Ray as ORay, ray::RayHit, triangle::Triangle,
};
use std::sync::Arc;

/// Identifies a triangle of the frame: geometry (a primitive placed by a node) and index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TriRef {
    pub geometry: u32,
    pub triangle: u32,
}

/// An obvhs ray. Negative zeros in the direction are made positive: obvhs picks the slab
/// order from `d < 0` but the inverse from the sign bit, so a −0.0 component (e.g. from
/// negating +Z) would make every box test miss.
#[inline(always)]
fn oray(o: Vec3A, d: Vec3A, tmax: f32) -> ORay {
    ORay::new(o, d + Vec3A::ZERO, 0.0, tmax)
}

/// Up to [`embree::PACKET`] rays as one packet query's input.
#[inline]
fn packet_of(rays: &[Ray]) -> [embree::PacketRay; embree::PACKET] {
    let mut packet = [([0.0f32; 3], [0.0f32; 3], 0.0f32); embree::PACKET];
    for (p, r) in packet.iter_mut().zip(rays) {
        *p = (r.o.to_array(), r.d.to_array(), r.tmax);
    }
    packet
}

/// Most triangles in a frame traced as one flat Embree scene ([`Accel::new`]).
pub const FLAT_MAX: usize = 16_384;

/// Largest coordinate magnitude the BVH is built over. The builder's surface-area
/// arithmetic squares extents and sums areas in f32 (max 3.4e38 ≈ (1.8e19)²); beyond about
/// 1e19 it overflows to infinity and the build breaks (found by fuzzing: a vertex at −1.7e38
/// tripped obvhs-0.4.0's `bvh2_to_cwbvh.rs:365` assertion). 1e15 leaves eight orders of
/// magnitude of headroom and is far beyond any real scene in metres. Triangles with a vertex
/// beyond it (or not finite), and instances whose bounds are, are left out of the frame.
pub const MAX_COORD: f32 = 1e15;

fn representable(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORD
}

/// A bottom-level structure over triangles in one space.
pub struct Blas {
    bvh: Option<CwBvh>,
    /// The same triangles as an Embree scene (primitive *i* = `refs[i]`) where Embree is
    /// the backend ([`embree`]); then `bvh` and `tris` are empty.
    embree: Option<embree::Scene>,
    /// Under Embree, the object-space triangles of a small BLAS (at most [`FLAT_MAX`] in
    /// the frame), kept so that a small frame can be traced flat ([`Accel::new`]).
    soup: Vec<[[f32; 3]; 3]>,
    /// Triangles in BVH leaf order.
    tris: Vec<PreparedTriangle>,
    /// What each leaf-order triangle is (input order under Embree).
    refs: Vec<TriRef>,
    /// Some triangle needs the `accept` filter (alpha-tested material).
    pub needs_filter: bool,
    pub bounds: Bounds3,
    /// Which builder made the BVH ([`build`]).
    pub builder: build::Builder,
}

impl Blas {
    /// Builds over `(ref, vertices)`; `needs_filter` marks alpha-tested content. On the
    /// process's backend ([`embree::backend`]).
    pub fn build(items: &[(TriRef, [Vec3; 3])], needs_filter: bool) -> Blas {
        Self::build_on(items, needs_filter, true)
    }

    /// Builds on the own BVH, whatever the process's backend (tests, comparisons).
    pub fn build_own(items: &[(TriRef, [Vec3; 3])], needs_filter: bool) -> Blas {
        Self::build_on(items, needs_filter, false)
    }

    fn build_on(items: &[(TriRef, [Vec3; 3])], needs_filter: bool, embree_ok: bool) -> Blas {
        let kept: Vec<(TriRef, [Vec3; 3])>;
        let items = if items
            .iter()
            .all(|(_, v)| v.iter().all(|p| representable(*p)))
        {
            items
        } else {
            kept = items
                .iter()
                .filter(|(_, v)| v.iter().all(|p| representable(*p)))
                .copied()
                .collect();
            &kept
        };
        let mut bounds = Bounds3::EMPTY;
        for (_, v) in items {
            v.iter().for_each(|p| bounds.grow(*p));
        }
        if items.is_empty() {
            return Blas {
                bvh: None,
                embree: None,
                soup: vec![],
                tris: vec![],
                refs: vec![],
                needs_filter,
                bounds,
                builder: build::Builder::Ploc,
            };
        }
        if embree_ok && !needs_filter {
            let soup: Vec<[[f32; 3]; 3]> =
                items.iter().map(|(_, v)| v.map(|p| p.to_array())).collect();
            if let Some(scene) = embree::Scene::triangles(&soup) {
                let soup = if soup.len() <= FLAT_MAX { soup } else { vec![] };
                return Blas {
                    bvh: None,
                    embree: Some(scene),
                    soup,
                    tris: vec![],
                    refs: items.iter().map(|(r, _)| *r).collect(),
                    needs_filter,
                    bounds,
                    builder: build::Builder::Embree,
                };
            }
        }
        let otris: Vec<Triangle> = items
            .iter()
            .map(|(_, v)| Triangle {
                v0: v[0].into(),
                v1: v[1].into(),
                v2: v[2].into(),
            })
            .collect();
        let (bvh, builder) = build::build_cwbvh(&otris, BvhBuildParams::medium_build());
        let mut tris = Vec::with_capacity(bvh.primitive_indices.len());
        let mut refs = Vec::with_capacity(bvh.primitive_indices.len());
        for &i in &bvh.primitive_indices {
            let (r, v) = &items[i as usize];
            tris.push(PreparedTriangle::new(v[0], v[1], v[2]));
            refs.push(*r);
        }
        Blas {
            bvh: Some(bvh),
            embree: None,
            soup: vec![],
            tris,
            refs,
            needs_filter,
            bounds,
            builder,
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.refs.len()
    }

    /// Whether Embree answers this BLAS's queries.
    pub fn on_embree(&self) -> bool {
        self.embree.is_some()
    }

    /// Closest hit in this BLAS's space below `tmax`: (t, ref, b1, b2).
    #[inline]
    fn closest<F: Fn(TriRef, f32, f32) -> bool>(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        accept: &F,
    ) -> Option<(f32, TriRef, f32, f32)> {
        if let Some(scene) = &self.embree {
            return scene
                .intersect(o.to_array(), d.to_array(), tmax)
                .map(|h| (h.t, self.refs[h.prim as usize], h.u, h.v));
        }
        let bvh = self.bvh.as_ref()?;
        let mut best = None;
        let mut hit = RayHit::none();
        let ray = oray(o, d, tmax);
        bvh.ray_traverse(ray, &mut hit, |r, slot| {
            match self.tris[slot].intersect(o, d, r.tmax) {
                Some((t, b1, b2)) if !self.needs_filter || accept(self.refs[slot], b1, b2) => {
                    best = Some((t, self.refs[slot], b1, b2));
                    t
                }
                _ => f32::INFINITY,
            }
        });
        best
    }

    #[inline]
    fn any<F: Fn(TriRef, f32, f32) -> bool>(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        accept: &F,
    ) -> bool {
        if let Some(scene) = &self.embree {
            return scene.occluded(o.to_array(), d.to_array(), tmax);
        }
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        let ray = oray(o, d, tmax);
        !bvh.ray_traverse_miss(ray, |r, slot| {
            match self.tris[slot].intersect(o, d, r.tmax) {
                Some((t, b1, b2)) if !self.needs_filter || accept(self.refs[slot], b1, b2) => t,
                _ => f32::INFINITY,
            }
        })
    }
}

/// A BLAS placed in the world.
#[derive(Clone)]
pub struct Instance {
    pub blas: Arc<Blas>,
    pub world_from_object: Affine3A,
    pub object_from_world: Affine3A,
    /// Added to the BLAS's local geometry indices to give frame-wide geometry ids.
    pub geometry_base: u32,
    identity: bool,
}

impl Instance {
    pub fn new(blas: Arc<Blas>, world_from_object: Affine3A) -> Self {
        let identity = world_from_object == Affine3A::IDENTITY;
        Instance {
            blas,
            world_from_object,
            object_from_world: world_from_object.inverse(),
            geometry_base: 0,
            identity,
        }
    }

    /// The ray in this instance's object space (t is unchanged: directions are not
    /// renormalised).
    #[inline]
    fn to_object(&self, o: Vec3A, d: Vec3A) -> (Vec3A, Vec3A) {
        if self.identity {
            (o, d)
        } else {
            (
                self.object_from_world.transform_point3a(o),
                self.object_from_world.transform_vector3a(d),
            )
        }
    }

    /// A BLAS-local triangle reference with the frame-wide geometry id.
    #[inline]
    fn global(&self, t: TriRef) -> TriRef {
        TriRef {
            geometry: t.geometry + self.geometry_base,
            ..t
        }
    }

    /// Closest hit in this instance (world-space t, frame-wide geometry id).
    #[inline]
    pub(crate) fn closest_world<F: Fn(TriRef, f32, f32) -> bool>(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        accept: &F,
    ) -> Option<(f32, TriRef, f32, f32)> {
        let (lo, ld) = self.to_object(o, d);
        self.blas
            .closest(lo, ld, tmax, &|t, b1, b2| accept(self.global(t), b1, b2))
            .map(|(t, tri, b1, b2)| (t, self.global(tri), b1, b2))
    }

    /// Whether anything in this instance blocks the ray before `tmax` (world-space t).
    #[inline]
    pub(crate) fn any_world<F: Fn(TriRef, f32, f32) -> bool>(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmax: f32,
        accept: &F,
    ) -> bool {
        let (lo, ld) = self.to_object(o, d);
        self.blas
            .any(lo, ld, tmax, &|t, b1, b2| accept(self.global(t), b1, b2))
    }

    pub fn with_geometry_base(mut self, base: u32) -> Self {
        self.geometry_base = base;
        self
    }

    fn world_bounds(&self) -> Bounds3 {
        let b = self.blas.bounds;
        let mut out = Bounds3::EMPTY;
        if b.is_empty() {
            return out;
        }
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            out.grow(self.world_from_object.transform_point3(c));
        }
        out
    }
}

/// A closest hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub instance: u32,
    pub tri: TriRef,
    pub b1: f32,
    pub b2: f32,
}

/// The scene's acceleration structure for one frame.
pub struct Accel {
    instances: Vec<Instance>,
    tlas: Option<CwBvh>,
    /// The top level on Embree, where every non-empty instance's BLAS is on Embree and
    /// there is more than one instance or a transformed one; then `tlas` is unused.
    embree_tlas: Option<embree::Scene>,
    /// `embree_tlas` is flat (world-space triangles, geometry id = instance index), not
    /// instances of the BLASes.
    embree_flat: bool,
    pub bounds: Bounds3,
}

impl Accel {
    pub fn new(instances: Vec<Instance>) -> Accel {
        let boxes: Vec<Bounds3> = instances.iter().map(|i| i.world_bounds()).collect();
        let bounds = boxes.iter().fold(Bounds3::EMPTY, |a, b| a.union(b));
        // Empty instances keep their index (ids stay stable) with a point box nobody hits.
        let boxes: Vec<Bounds3> = boxes
            .into_iter()
            .map(|b| {
                if b.is_empty() || !representable(b.min) || !representable(b.max) {
                    Bounds3 {
                        min: Vec3::ZERO,
                        max: Vec3::ZERO,
                    }
                } else {
                    b
                }
            })
            .collect();
        let (embree_tlas, embree_flat) = match Self::embree_flat(&instances) {
            Some(flat) => (Some(flat), true),
            None => (Self::embree_top_level(&instances), false),
        };
        let tlas = if instances.len() > 1 && embree_tlas.is_none() {
            let aabbs: Vec<Aabb> = boxes
                .iter()
                .map(|b| Aabb {
                    min: b.min.into(),
                    max: b.max.into(),
                })
                .collect();
            Some(build::build_cwbvh(&aabbs, BvhBuildParams::fast_build()).0)
        } else {
            None
        };
        Accel {
            instances,
            tlas,
            embree_tlas,
            embree_flat,
            bounds,
        }
    }

    /// A small frame on Embree as one flat scene of world-space triangles: measured on
    /// cornell-moving (42 triangles, 2 instances), Embree's instance level costs 15–20 % of
    /// its ray rate (`bench rays`, 2026-12-07), while building a flat scene of at most
    /// [`FLAT_MAX`] triangles per frame costs about a millisecond.
    fn embree_flat(instances: &[Instance]) -> Option<embree::Scene> {
        let placed = instances.iter().filter(|i| i.blas.triangle_count() > 0);
        let total: usize = placed.clone().map(|i| i.blas.triangle_count()).sum();
        if total > FLAT_MAX
            || placed
                .clone()
                .any(|i| i.blas.embree.is_none() || i.blas.soup.len() != i.blas.triangle_count())
            || (instances.len() == 1 && instances[0].identity)
        {
            return None;
        }
        // Untransformed instances are passed as they are, moved ones transformed.
        let world: Vec<_> = instances
            .iter()
            .enumerate()
            .filter(|(_, i)| i.blas.triangle_count() > 0)
            .map(|(k, inst)| {
                let m = inst.world_from_object;
                let tris = if inst.identity {
                    std::borrow::Cow::Borrowed(inst.blas.soup.as_slice())
                } else {
                    std::borrow::Cow::Owned(
                        inst.blas
                            .soup
                            .iter()
                            .map(|t| t.map(|p| m.transform_point3(Vec3::from_array(p)).to_array()))
                            .collect(),
                    )
                };
                (k as u32, tris)
            })
            .collect();
        let soups: Vec<(u32, &[[[f32; 3]; 3]])> = world.iter().map(|(k, t)| (*k, &**t)).collect();
        embree::Scene::flat(&soups)
    }

    /// Embree's top level over `instances` (ids = indices), if all of them are on Embree
    /// (empty ones are left out: they keep their index, nobody hits them) and a single
    /// untransformed instance does not make it needless.
    fn embree_top_level(instances: &[Instance]) -> Option<embree::Scene> {
        let placed: Vec<&Instance> = instances
            .iter()
            .filter(|i| i.blas.triangle_count() > 0)
            .collect();
        if placed.iter().any(|i| !i.blas.on_embree())
            || (instances.len() == 1 && instances[0].identity)
        {
            return None;
        }
        let items: Vec<(u32, &embree::Scene, [f32; 12])> = instances
            .iter()
            .enumerate()
            .filter_map(|(k, inst)| {
                let scene = inst.blas.embree.as_ref()?;
                let m = inst.world_from_object;
                let mut x = [0.0f32; 12];
                x[0..3].copy_from_slice(&m.matrix3.x_axis.to_array());
                x[3..6].copy_from_slice(&m.matrix3.y_axis.to_array());
                x[6..9].copy_from_slice(&m.matrix3.z_axis.to_array());
                x[9..12].copy_from_slice(&m.translation.to_array());
                Some((k as u32, scene, x))
            })
            .collect();
        embree::Scene::instances(&items)
    }

    /// The hit of the Embree scene of [`Accel::embree_whole`] as ours: the flat scene
    /// names the instance by geometry, the instance level by instance, and a lone
    /// untransformed BLAS is instance 0.
    #[inline]
    fn embree_hit(&self, h: embree::RawHit) -> Hit {
        let instance = match (&self.embree_tlas, self.embree_flat) {
            (Some(_), true) => h.geom,
            (Some(_), false) => h.instance,
            (None, _) => 0,
        };
        let inst = &self.instances[instance as usize];
        Hit {
            t: h.t,
            instance,
            tri: inst.global(inst.blas.refs[h.prim as usize]),
            b1: h.u,
            b2: h.v,
        }
    }

    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// Closest hit with `t < ray.tmax`, skipping triangles `accept` rejects (only consulted
    /// for BLASes that need filtering).
    pub fn intersect<F: Fn(TriRef, f32, f32) -> bool>(&self, ray: &Ray, accept: F) -> Option<Hit> {
        if let Some(top) = &self.embree_tlas {
            return top
                .intersect(ray.o.to_array(), ray.d.to_array(), ray.tmax)
                .map(|h| self.embree_hit(h));
        }
        let (o, d): (Vec3A, Vec3A) = (ray.o.into(), ray.d.into());
        let local = |inst: &Instance, tmax: f32| inst.closest_world(o, d, tmax, &accept);
        match &self.tlas {
            None => {
                let inst = self.instances.first()?;
                local(inst, ray.tmax).map(|(t, tri, b1, b2)| Hit {
                    t,
                    instance: 0,
                    tri,
                    b1,
                    b2,
                })
            }
            Some(tlas) => {
                let mut best = None;
                let mut hit = RayHit::none();
                tlas.ray_traverse(oray(o, d, ray.tmax), &mut hit, |r, slot| {
                    let i = tlas.primitive_indices[slot] as usize;
                    match local(&self.instances[i], r.tmax) {
                        Some((t, tri, b1, b2)) => {
                            best = Some(Hit {
                                t,
                                instance: i as u32,
                                tri,
                                b1,
                                b2,
                            });
                            t
                        }
                        None => f32::INFINITY,
                    }
                });
                best
            }
        }
    }

    /// The Embree scene that answers this frame's queries whole, if there is one (then
    /// `accept` is never consulted: alpha-tested BLASes stay on the own BVH).
    #[inline]
    fn embree_whole(&self) -> Option<&embree::Scene> {
        self.embree_tlas
            .as_ref()
            .or_else(|| match &self.instances[..] {
                [only] if only.identity => only.blas.embree.as_ref(),
                _ => None,
            })
    }

    /// Closest hits of many rays (`out[k]` for `rays[k]`; equal to [`Accel::intersect`] on
    /// each), in packets of [`embree::PACKET`] where Embree holds the frame: Embree's
    /// packet kernels trace 16 rays per AVX-512 instruction stream.
    pub fn intersect_many<F: Fn(TriRef, f32, f32) -> bool>(
        &self,
        rays: &[Ray],
        accept: F,
        out: &mut [Option<Hit>],
    ) {
        let Some(scene) = self.embree_whole() else {
            for (r, o) in rays.iter().zip(out.iter_mut()) {
                *o = self.intersect(r, &accept);
            }
            return;
        };
        let mut raw: [Option<embree::RawHit>; embree::PACKET] = Default::default();
        for (rs, os) in rays
            .chunks(embree::PACKET)
            .zip(out.chunks_mut(embree::PACKET))
        {
            let packet = packet_of(rs);
            let packet = &packet[..rs.len()];
            scene.intersect_packet(packet, &mut raw);
            for (o, h) in os.iter_mut().zip(raw.iter_mut()) {
                *o = h.take().map(|h| self.embree_hit(h));
            }
        }
    }

    /// Occlusion of many rays (equal to [`Accel::occluded`] on each), in packets where
    /// Embree holds the frame.
    pub fn occluded_many<F: Fn(TriRef, f32, f32) -> bool>(
        &self,
        rays: &[Ray],
        accept: F,
        out: &mut [bool],
    ) {
        let Some(scene) = self.embree_whole() else {
            for (r, o) in rays.iter().zip(out.iter_mut()) {
                *o = self.occluded(r, &accept);
            }
            return;
        };
        for (rs, os) in rays
            .chunks(embree::PACKET)
            .zip(out.chunks_mut(embree::PACKET))
        {
            let packet = packet_of(rs);
            let packet = &packet[..rs.len()];
            scene.occluded_packet(packet, os);
        }
    }

    /// True if anything `accept`s along the ray with `t < ray.tmax`.
    pub fn occluded<F: Fn(TriRef, f32, f32) -> bool>(&self, ray: &Ray, accept: F) -> bool {
        if let Some(top) = &self.embree_tlas {
            return top.occluded(ray.o.to_array(), ray.d.to_array(), ray.tmax);
        }
        let (o, d): (Vec3A, Vec3A) = (ray.o.into(), ray.d.into());
        let local = |inst: &Instance, tmax: f32| inst.any_world(o, d, tmax, &accept);
        match &self.tlas {
            None => self.instances.first().is_some_and(|i| local(i, ray.tmax)),
            Some(tlas) => !tlas.ray_traverse_miss(oray(o, d, ray.tmax), |r, slot| {
                if local(
                    &self.instances[tlas.primitive_indices[slot] as usize],
                    r.tmax,
                ) {
                    0.0
                } else {
                    f32::INFINITY
                }
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::brute_force_closest;
    use crate::sampling::rng::Pcg32;

    fn random_soup(r: &mut Pcg32, n: usize, offset: Vec3) -> Vec<[Vec3; 3]> {
        (0..n)
            .map(|_| {
                let c = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 10.0 + offset;
                let mut v =
                    || Vec3::new(r.next_f32() - 0.5, r.next_f32() - 0.5, r.next_f32() - 0.5);
                [c + v(), c + v(), c + v()]
            })
            .collect()
    }

    /// Embree, where this build found it, answers the queries: under CI it must (the
    /// default build fetches it; `.ci/run` points the cache into the clone), so the
    /// brute-force tests below test it and not only the own BVH.
    #[test]
    fn embree_is_the_backend_where_the_build_found_it() {
        let built = option_env!("CHRONOLUX_EMBREE_BUILD_LIB").unwrap_or("");
        if std::env::var("CHRONOLUX_ACCEL").as_deref() == Ok("bvh") {
            return;
        }
        let backend = embree::backend();
        let Some(_) = crate::testing::external::require_external(
            (!built.is_empty()).then_some(()),
            "Embree 4 (the build did not find or fetch it)",
            "crates/chronolux-core/build.rs fetches the embreex wheel with python3 -m pip",
        ) else {
            return;
        };
        assert_eq!(*backend, embree::Backend::Embree, "{built} did not load");
        let tri = [(
            TriRef {
                geometry: 0,
                triangle: 0,
            },
            [Vec3::ZERO, Vec3::X, Vec3::Y],
        )];
        assert!(Blas::build(&tri, false).on_embree());
        // Alpha-tested content stays on the own BVH (the `accept` filter).
        assert!(!Blas::build(&tri, true).on_embree());
        assert!(!Blas::build_own(&tri, false).on_embree());
    }

    /// Closest hits through the two-level structure equal brute force over the same
    /// world-space triangles (exactly the same triangle and t up to float rounding of the
    /// instance transform), before and after the instances move; on the process's backend
    /// (Embree where it loads) and on the own BVH, and the same through the packet queries
    /// (`intersect_many`, `occluded_many`) as one ray at a time.
    #[test]
    fn two_level_equals_brute_force_before_and_after_motion() {
        for own in [false, true] {
            two_level_case(own);
        }
    }

    fn two_level_case(own: bool) {
        let build = |items: &[(TriRef, [Vec3; 3])]| {
            if own {
                Blas::build_own(items, false)
            } else {
                Blas::build(items, false)
            }
        };
        let mut r = Pcg32::new(3, 4);
        let a = random_soup(&mut r, 500, Vec3::ZERO);
        let b = random_soup(&mut r, 300, Vec3::new(3.0, 0.0, 0.0));
        let refs = |g: u32, t: &[[Vec3; 3]]| -> Vec<(TriRef, [Vec3; 3])> {
            t.iter()
                .enumerate()
                .map(|(i, v)| {
                    (
                        TriRef {
                            geometry: g,
                            triangle: i as u32,
                        },
                        *v,
                    )
                })
                .collect()
        };
        let blas_a = Arc::new(build(&refs(0, &a)));
        let blas_b = Arc::new(build(&refs(0, &b)));
        for frame in 0..3 {
            let m = Affine3A::from_rotation_translation(
                glam::Quat::from_rotation_y(0.4 * frame as f32),
                Vec3::new(frame as f32, 0.5, -(frame as f32)),
            );
            let accel = Accel::new(vec![
                Instance::new(blas_a.clone(), Affine3A::IDENTITY),
                Instance::new(blas_b.clone(), m).with_geometry_base(1),
            ]);
            let mut world: Vec<PreparedTriangle> = a
                .iter()
                .map(|v| PreparedTriangle::new(v[0], v[1], v[2]))
                .collect();
            let mut ids: Vec<TriRef> = (0..a.len())
                .map(|i| TriRef {
                    geometry: 0,
                    triangle: i as u32,
                })
                .collect();
            for (i, v) in b.iter().enumerate() {
                let w = v.map(|p| m.transform_point3(p));
                world.push(PreparedTriangle::new(w[0], w[1], w[2]));
                ids.push(TriRef {
                    geometry: 1,
                    triangle: i as u32,
                });
            }
            let mut mismatches = 0;
            let mut rays = Vec::new();
            for _ in 0..2000 {
                let o =
                    Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 14.0 - Vec3::splat(2.0);
                let d = crate::sampling::warps::sample_uniform_sphere(glam::Vec2::new(
                    r.next_f32(),
                    r.next_f32(),
                ));
                let ray = Ray::new(o, d);
                rays.push(ray);
                let got = accel.intersect(&ray, |_, _, _| true);
                let want = brute_force_closest(&world, &ray);
                match (got, want) {
                    (None, None) => {}
                    (Some(h), Some((i, t))) => {
                        // Relative 1e-4: transforming the ray into object space perturbs t by a few ULPs.
                        assert!((h.t - t).abs() <= 1e-4 * t.max(1.0), "t {} vs {}", h.t, t);
                        if h.tri != ids[i] {
                            mismatches += 1; // coincident-t ties between two triangles
                        }
                    }
                    (g, w) => panic!("frame {frame}: accel {g:?} vs brute force {w:?}"),
                }
                assert_eq!(accel.occluded(&ray, |_, _, _| true), want.is_some());
            }
            assert!(
                mismatches <= 2,
                "{mismatches} different triangles at equal t"
            );
            // Packets (2000 = 125 packets of 16) find what single rays find: the same
            // triangle, t within 1e-5 relative (Embree's packet and single-ray kernels may
            // round the intersection differently by a few ULPs).
            let mut many = vec![None; rays.len()];
            accel.intersect_many(&rays, |_, _, _| true, &mut many);
            let mut blocked = vec![false; rays.len()];
            accel.occluded_many(&rays, |_, _, _| true, &mut blocked);
            for (k, ray) in rays.iter().enumerate() {
                let one = accel.intersect(ray, |_, _, _| true);
                match (one, many[k]) {
                    (None, None) => {}
                    (Some(a), Some(b)) => {
                        assert_eq!((a.tri, a.instance), (b.tri, b.instance), "ray {k}");
                        assert!((a.t - b.t).abs() <= 1e-5 * a.t.max(1.0), "ray {k}");
                    }
                    (a, b) => panic!("ray {k}: single {a:?} vs packet {b:?}"),
                }
                assert_eq!(blocked[k], one.is_some(), "ray {k}");
            }
            if !own && *embree::backend() == embree::Backend::Embree {
                assert!(accel.embree_tlas.is_some());
            }
        }
    }
}

#[cfg(test)]
mod tiny_tests {
    use super::*;

    /// Rays are the open interval `0 < t < tmax` on both backends: a triangle through the
    /// origin (t = 0 exactly) is not hit, by single rays or packets, and one at t = 1 is.
    /// Embree is given `tnear = 0` (its test `tnear·|den| < T` is strict), the own BVH tests
    /// `t > 0`. Checked through a lone BLAS and through two instances (on Embree the flat
    /// scene of world-space triangles), one of them moved.
    #[test]
    fn a_triangle_through_the_origin_is_not_hit_at_t_zero() {
        let tri = |z: f32, k: u32| {
            (
                TriRef {
                    geometry: 0,
                    triangle: k,
                },
                [
                    Vec3::new(-1.0, -1.0, z),
                    Vec3::new(2.0, -1.0, z),
                    Vec3::new(-1.0, 2.0, z),
                ],
            )
        };
        for own in [false, true] {
            let build = |items: &[(TriRef, [Vec3; 3])]| {
                Arc::new(if own {
                    Blas::build_own(items, false)
                } else {
                    Blas::build(items, false)
                })
            };
            let lone = Accel::new(vec![Instance::new(
                build(&[tri(0.0, 0), tri(1.0, 1)]),
                Affine3A::IDENTITY,
            )]);
            // The second instance is the plane z = 0 moved to z = 1.
            let moved = Accel::new(vec![
                Instance::new(build(&[tri(0.0, 0)]), Affine3A::IDENTITY),
                Instance::new(
                    build(&[tri(0.0, 0)]),
                    Affine3A::from_translation(Vec3::new(0.0, 0.0, 1.0)),
                )
                .with_geometry_base(1),
            ]);
            for (name, accel) in [("lone", &lone), ("moved", &moved)] {
                // Origins on the plane z = 0 (exactly representable, so t = 0 exactly).
                let rays: Vec<Ray> = [(0.1, 0.1), (0.0, 0.0), (0.5, -0.25), (-0.5, 0.75)]
                    .iter()
                    .map(|&(x, y)| Ray::new(Vec3::new(x, y, 0.0), Vec3::Z))
                    .collect();
                for ray in &rays {
                    let h = accel.intersect(ray, |_, _, _| true);
                    // t = 1 up to the float rounding of the hit (a few ULPs at 1).
                    assert!(
                        h.is_some_and(|h| (h.t - 1.0).abs() < 1e-6),
                        "{name} own={own} {ray:?}: {h:?}"
                    );
                    let short = Ray { tmax: 0.5, ..*ray };
                    assert!(!accel.occluded(&short, |_, _, _| true), "{name} own={own}");
                    assert!(accel.occluded(ray, |_, _, _| true), "{name} own={own}");
                }
                let mut many = vec![None; rays.len()];
                accel.intersect_many(&rays, |_, _, _| true, &mut many);
                assert!(
                    many.iter()
                        .all(|h| h.is_some_and(|h| (h.t - 1.0).abs() < 1e-6)),
                    "{name} own={own}: {many:?}"
                );
                let short: Vec<Ray> = rays.iter().map(|r| Ray { tmax: 0.5, ..*r }).collect();
                let mut blocked = vec![true; rays.len()];
                accel.occluded_many(&short, |_, _, _| true, &mut blocked);
                assert!(blocked.iter().all(|b| !b), "{name} own={own}: {blocked:?}");
            }
        }
    }

    #[test]
    fn axis_aligned_rays_with_negative_zero_components_hit() {
        let q = [
            Vec3::new(-0.5, -0.5, 0.0),
            Vec3::new(0.5, -0.5, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(-0.5, 0.5, 0.0),
        ];
        let items = vec![
            (
                TriRef {
                    geometry: 0,
                    triangle: 0,
                },
                [q[0], q[1], q[2]],
            ),
            (
                TriRef {
                    geometry: 0,
                    triangle: 1,
                },
                [q[0], q[2], q[3]],
            ),
        ];
        let b = Arc::new(Blas::build(&items, false));
        let a = Accel::new(vec![Instance::new(b, Affine3A::IDENTITY)]);
        // -Vec3::Z is (-0, -0, -1): a flat quad hit straight on, by an axis-aligned ray.
        for d in [-Vec3::Z, Vec3::Z, -Vec3::X, Vec3::new(-0.0, 0.0, -1.0)] {
            let o = Vec3::new(0.1, 0.1, 0.0) - 5.0 * d;
            let h = a.intersect(&Ray::new(o, d), |_, _, _| true);
            assert!(
                h.is_some_and(|h| (h.t - 5.0).abs() < 1e-5) || d == -Vec3::X,
                "{d}: {h:?}"
            );
            assert_eq!(a.occluded(&Ray::new(o, d), |_, _, _| true), d != -Vec3::X);
            let (mut many, mut blocked) = ([None], [false]);
            a.intersect_many(&[Ray::new(o, d)], |_, _, _| true, &mut many);
            a.occluded_many(&[Ray::new(o, d)], |_, _, _| true, &mut blocked);
            assert_eq!(many[0].is_some(), d != -Vec3::X);
            assert_eq!(blocked[0], d != -Vec3::X);
        }
    }
}
