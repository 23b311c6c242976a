//! What changed between two built frames, computed once and exactly: [`FrameDelta`].
//!
//! Temporal techniques reuse work across frames only where the scene did not change, so
//! they all need the same answers: did this object move, was this mesh deformed, did this
//! light, material or the camera change? [`FrameDelta::between`] answers them for two
//! [`FrameScene`]s (two frames or any two instants of one animation), and
//! [`FrameDelta::over`] for a segment of frames (what changes *anywhere* in it: the
//! segment's dynamic instances; the others make up its static scene).
//!
//! # Exactness
//!
//! Every answer compares the **evaluated** frame data, never a description of it or a
//! debug string: floating-point values bit for bit (`to_bits`; so `-0.0` and `0.0` differ
//! and a NaN equals the same NaN), materials and textures by `PartialEq` on their values.
//! Data shared between the frames (the same `Arc`) is equal without being read; the
//! builder shares everything that does not change, so comparing two frames costs a few
//! pointer tests plus a scan of the vertex data of deformed meshes. "Unchanged" therefore
//! means: rendering with either frame's data gives bit-identical results for that part.
//!
//! # Ids
//!
//! - **Instances** are indices into `FrameScene::accel.instances()`. Frames made by one
//!   [`FrameBuilder`](super::frame::FrameBuilder) always have the same instances in the
//!   same order (the static instance first if there is static geometry, then one per
//!   rigid node, then one per deformed node, both in node order), so an id names the same
//!   object in every frame. Geometry `g` (a stable [`GeometryId`](super::frame::GeometryId))
//!   is carried by instance `FrameScene::geometry_instance[g]`.
//! - **Lights** are indices into `FrameScene::lights` (stable too: emissive triangles in
//!   geometry order, then punctual lights in node order, then the environment).
//! - **Materials** are indices into `FrameScene::materials`.
//!
//! Frames of different builders may have different counts; an id present in only one of
//! the two frames is reported changed.
//!
//! # Where
//!
//! Besides *what* changed, a delta says *where*: [`FrameDelta::regions`], the world
//! bounds of every changed instance in each frame of the delta (from its vertices,
//! slightly padded: [`FrameScene::instance_world_bounds`]); for an instance that only
//! deformed (a skinned or morphed mesh that did not move), the bounds of the triangles
//! that are not the same surface in both frames ([`FrameDelta::triangle_changed`]): a
//! banner whose lower half swings changed in the lower half only. The techniques that keep
//! work outside a change (dept's pooling validity, spt's path scan) read these instead of
//! each computing a region its own way.

use super::desc::{Material, Projection};
use super::frame::{FrameScene, GeometryData};
use crate::accel::TriRef;
use crate::camera::Camera;
use crate::geometry::Bounds3;
use crate::light::Light;
use crate::math::{Affine3A, Vec2, Vec3, Vec4};
use std::sync::Arc;

/// What differs between two frames; see the module documentation for ids and exactness.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameDelta {
    /// Per instance: its placement (`world_from_object`, geometry base) differs.
    moved: Vec<bool>,
    /// Per instance: the vertex data of a geometry it carries differs.
    deformed: Vec<bool>,
    /// Per light: its evaluated value differs (see [`FrameDelta::light_changed`]).
    lights: Vec<bool>,
    /// Per material: its value or a texture it samples differs.
    materials: Vec<bool>,
    camera: bool,
    bounds: bool,
    /// Where: the changed instances' bounds in each frame (see [`Region`]).
    regions: Vec<Region>,
}

/// One changed instance in one frame of a delta: where it changed there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// The instance id.
    pub instance: u32,
    /// Which frame of the delta: 0 and 1 for [`FrameDelta::between`]'s `a` and `b`; the
    /// frame's index in the segment for [`FrameDelta::over`].
    pub frame: u32,
    /// Its world bounds in that frame (from its vertices, padded as
    /// [`FrameScene::instance_world_bounds`] pads); for an instance that only deformed,
    /// those of its changed triangles (an instance none of whose triangles changed has no
    /// region).
    pub bounds: Bounds3,
}

impl FrameDelta {
    /// What differs between frames `a` and `b` (symmetric in what changed: `between(b, a)`
    /// reports the same, with the regions' frames 0 and 1 swapped; `between(a, a)`
    /// reports nothing changed).
    pub fn between(a: &FrameScene, b: &FrameScene) -> FrameDelta {
        let (ia, ib) = (a.accel.instances(), b.accel.instances());
        let n_inst = ia.len().max(ib.len());
        let mut moved = vec![true; n_inst];
        for (i, (x, y)) in ia.iter().zip(ib).enumerate() {
            moved[i] = !(x.world_from_object.bit_eq(&y.world_from_object)
                && x.geometry_base == y.geometry_base);
        }
        // Instances present in only one frame: changed in every respect.
        let mut deformed: Vec<bool> = (0..n_inst).map(|i| i >= ia.len().min(ib.len())).collect();
        let n_geom = a.geometry.len().max(b.geometry.len());
        if !Arc::ptr_eq(&a.geometry, &b.geometry) {
            for g in 0..n_geom {
                let (ga, gb) = (a.geometry.get(g), b.geometry.get(g));
                let (ja, jb) = (
                    a.geometry_instance.get(g).copied(),
                    b.geometry_instance.get(g).copied(),
                );
                let same = match (ga, gb) {
                    (Some(x), Some(y)) => ja == jb && same_geometry(x, y),
                    _ => false,
                };
                if !same {
                    for j in [ja, jb].into_iter().flatten() {
                        if let Some(d) = deformed.get_mut(j as usize) {
                            *d = true;
                        }
                    }
                }
            }
        }
        let bounds = !(a.bounds.min.bit_eq(&b.bounds.min)
            && a.bounds.max.bit_eq(&b.bounds.max)
            && a.scene_radius.bit_eq(&b.scene_radius));
        let sphere_a = a.bounds.bounding_sphere();
        let sphere_b = b.bounds.bounding_sphere();
        let sphere_same = sphere_a.0.bit_eq(&sphere_b.0)
            && sphere_a.1.bit_eq(&sphere_b.1)
            && a.scene_radius.bit_eq(&b.scene_radius);
        let n_lights = a.lights.len().max(b.lights.len());
        let lights = (0..n_lights)
            .map(|l| match (a.lights.get(l), b.lights.get(l)) {
                (Some(x), Some(y)) => !(same_light(x, y) && (sphere_same || !is_infinite(x))),
                _ => true,
            })
            .collect();
        let n_mat = a.materials.len().max(b.materials.len());
        let textures_same = Arc::ptr_eq(&a.textures, &b.textures);
        let materials = if Arc::ptr_eq(&a.materials, &b.materials) && textures_same {
            vec![false; n_mat]
        } else {
            (0..n_mat)
                .map(|m| match (a.materials.get(m), b.materials.get(m)) {
                    (Some(x), Some(y)) => {
                        x != y
                            || (!textures_same
                                && texture_ids(x).any(|t| a.textures.get(t) != b.textures.get(t)))
                    }
                    _ => true,
                })
                .collect()
        };
        let changed = |i: usize| moved[i] || deformed[i];
        let mut regions = regions_in(a, 0, &changed);
        regions.extend(regions_in(b, 1, &changed));
        // An instance that only deformed changed where its changed triangles are.
        regions.retain_mut(|r| {
            let i = r.instance as usize;
            if moved[i] || !deformed[i] {
                return true;
            }
            let (this, other) = if r.frame == 0 { (a, b) } else { (b, a) };
            match changed_triangle_bounds(this, other, r.instance) {
                Some(Some(bounds)) => {
                    r.bounds = bounds;
                    true
                }
                Some(None) => false,
                None => true,
            }
        });
        FrameDelta {
            moved,
            deformed,
            lights,
            materials,
            camera: !same_camera(&a.camera, &b.camera),
            bounds,
            regions,
        }
    }

    /// The changed instances' bounds in each frame of the delta, frame by frame, each in
    /// instance order.
    pub fn regions(&self) -> &[Region] {
        &self.regions
    }

    /// The bounds of every [`Region`] (every frame), in [`FrameDelta::regions`]' order.
    pub fn changed_bounds(&self) -> Vec<Bounds3> {
        self.regions.iter().map(|r| r.bounds).collect()
    }

    /// The changed instances' bounds in frame `frame` of the delta (1: `between`'s `b`,
    /// the frame a technique moves to).
    pub fn changed_bounds_in(&self, frame: u32) -> Vec<Bounds3> {
        self.regions
            .iter()
            .filter(|r| r.frame == frame)
            .map(|r| r.bounds)
            .collect()
    }

    /// What changes anywhere in a segment of frames (in time order): the union of
    /// [`FrameDelta::between`] over consecutive frames. Because equality here is exact
    /// (an equivalence), an element is reported changed iff it is not the same in every
    /// frame of the segment; e.g. the segment's *static scene* is the instances with
    /// `!instance_changed(i)`. One frame or none: nothing changed. Its regions are those of
    /// each consecutive pair, numbered as the segment's frames (an instance that changes
    /// in two pairs has its middle frame's bounds twice; one that changes in none, none):
    /// together they cover everywhere a changed surface was in the segment.
    pub fn over(frames: &[&FrameScene]) -> FrameDelta {
        let mut d = FrameDelta::default();
        for (k, w) in frames.windows(2).enumerate() {
            d.merge_at(&FrameDelta::between(w[0], w[1]), k as u32);
        }
        if d.moved.is_empty()
            && let Some(f) = frames.first()
        {
            d = FrameDelta::between(f, f);
        }
        d
    }

    /// Adds what `other` reports changed (element-wise or; longer lists extend; its
    /// regions are appended as they are).
    pub fn merge(&mut self, other: &FrameDelta) {
        self.merge_at(other, 0);
    }

    /// [`FrameDelta::merge`] of the delta between frames `first` and `first + 1` of a
    /// segment: its regions' frames are renumbered as the segment's.
    pub fn merge_at(&mut self, other: &FrameDelta, first: u32) {
        self.regions.extend(other.regions.iter().map(|r| Region {
            frame: r.frame + first,
            ..*r
        }));
        fn or(a: &mut Vec<bool>, b: &[bool]) {
            if a.len() < b.len() {
                a.resize(b.len(), false);
            }
            a.iter_mut().zip(b).for_each(|(x, y)| *x |= y);
        }
        or(&mut self.moved, &other.moved);
        or(&mut self.deformed, &other.deformed);
        or(&mut self.lights, &other.lights);
        or(&mut self.materials, &other.materials);
        self.camera |= other.camera;
        self.bounds |= other.bounds;
    }

    /// Number of instance ids covered (the larger of the two frames' counts).
    pub fn instance_count(&self) -> usize {
        self.moved.len()
    }

    /// Instance `i` is placed differently: its `world_from_object` (bitwise) or geometry
    /// base differs. Deformed geometry is carried by an identity-placed instance, so its
    /// change shows in [`FrameDelta::instance_deformed`], not here. Panics if `i` is not
    /// an instance id of either frame.
    pub fn instance_moved(&self, i: usize) -> bool {
        self.moved[i]
    }

    /// The vertex data of a geometry carried by instance `i` differs (skinned or morphed
    /// positions, normals or tangents; also uvs, indices, the material slot or which
    /// instance carries it). A BLAS is a function of the vertex data it is built from, so
    /// an instance neither moved nor deformed intersects every ray identically in both
    /// frames, even where the builder rebuilt its BLAS. Panics if `i` is out of range.
    pub fn instance_deformed(&self, i: usize) -> bool {
        self.deformed[i]
    }

    /// Instance `i` moved or was deformed: its surface is not the same in both frames.
    pub fn instance_changed(&self, i: usize) -> bool {
        self.moved[i] || self.deformed[i]
    }

    /// Per instance id: moved or deformed (for a delta made by [`FrameDelta::over`], the
    /// segment's dynamic instances).
    pub fn dynamic_instances(&self) -> Vec<bool> {
        (0..self.moved.len())
            .map(|i| self.instance_changed(i))
            .collect()
    }

    /// The surface carrying geometry `g` of `scene` (either frame of the delta) is not the
    /// same in both frames: [`FrameDelta::instance_changed`] of its instance.
    pub fn geometry_changed(&self, scene: &FrameScene, g: u32) -> bool {
        self.instance_changed(scene.geometry_instance[g as usize] as usize)
    }

    /// Triangle `tri` (of geometry `tri.geometry` in frame `a`) is not the same surface in
    /// frames `a` and `b`, the delta's two frames in either order. Finer than
    /// [`FrameDelta::geometry_changed`] on deformed meshes: a skinned or morphed mesh
    /// changes only where its vertices move, and a triangle whose three vertices have
    /// bit-identical data (positions, normals, tangents, uvs) under the same indices,
    /// material and placement in both frames is the same surface: every ray meets it at
    /// the same point with the same barycentrics, and it shades the same, whatever its
    /// neighbours do. (A BLAS is a function of its triangles, and triangle intersection
    /// reads only the triangle's own vertices.) An instance that moved changes all its
    /// triangles; one neither moved nor deformed none. For a delta made by
    /// [`FrameDelta::between`]`(a, b)` (a delta [`FrameDelta::over`] a segment says nothing
    /// about the frames between its ends).
    pub fn triangle_changed(&self, a: &FrameScene, b: &FrameScene, tri: TriRef) -> bool {
        let g = tri.geometry as usize;
        let Some(&inst) = a.geometry_instance.get(g) else {
            return true;
        };
        let i = inst as usize;
        if self.moved.get(i).is_none_or(|&m| m) {
            return true;
        }
        if !self.deformed[i] {
            return false;
        }
        let (Some(x), Some(y)) = (a.geometry.get(g), b.geometry.get(g)) else {
            return true;
        };
        if b.geometry_instance.get(g) != Some(&inst)
            || x.material != y.material
            || x.world_space != y.world_space
        {
            return true;
        }
        let t = tri.triangle as usize;
        match (x.indices.get(t), y.indices.get(t)) {
            (Some(ix), Some(iy)) if ix == iy => !ix.iter().all(|&v| same_vertex(x, y, v as usize)),
            _ => true,
        }
    }

    /// Light `l` differs: any field of its evaluated value (position, direction,
    /// intensity, cone, triangle, ...) bitwise; for a light at infinity (directional or
    /// environment) also the scene's bounding sphere, which its emission and sampling use.
    /// Panics if `l` is out of range.
    pub fn light_changed(&self, l: usize) -> bool {
        self.lights[l]
    }

    /// Some light changed or the number of lights differs. When `false`, light selection
    /// (`FrameScene::light_sampler`, a function of the lights and, for lights at infinity,
    /// the scene radius) and light sampling give identical results in both frames.
    pub fn lights_changed(&self) -> bool {
        self.lights.iter().any(|&c| c)
    }

    /// Material `m` differs (its value or a texture it samples). Panics if out of range.
    pub fn material_changed(&self, m: usize) -> bool {
        self.materials[m]
    }

    /// Some material changed.
    pub fn materials_changed(&self) -> bool {
        self.materials.iter().any(|&c| c)
    }

    /// The camera differs: placement (`world_from_camera`, bitwise), projection or image
    /// size.
    pub fn camera_changed(&self) -> bool {
        self.camera
    }

    /// The scene bounds (and so its bounding sphere and `scene_radius`) differ.
    pub fn bounds_changed(&self) -> bool {
        self.bounds
    }

    /// Nothing but the camera changed: every instance, light, material and the bounds are
    /// the same in both frames, so all view-independent light (photons, element and cache
    /// solutions) is too. A fly-through of a still set is a run of such frames.
    pub fn only_camera_changed(&self) -> bool {
        !(self.moved.iter().any(|&c| c)
            || self.deformed.iter().any(|&c| c)
            || self.lights_changed()
            || self.materials_changed()
            || self.bounds)
    }

    /// Nothing changed: every instance, light, material, the camera and the bounds are the
    /// same in both frames.
    pub fn is_static(&self) -> bool {
        !(self.moved.iter().any(|&c| c)
            || self.deformed.iter().any(|&c| c)
            || self.lights_changed()
            || self.materials_changed()
            || self.camera
            || self.bounds)
    }
}

/// Per instance id, whether it moves or deforms anywhere in `frames` (in time order): the
/// dynamic instances of the segment ([`FrameDelta::over`]). A later technique traces the
/// segment's static part as the instances marked `false`.
pub fn dynamic_instances(frames: &[&FrameScene]) -> Vec<bool> {
    FrameDelta::over(frames).dynamic_instances()
}

/// The [`Region`]s of `scene` (frame `frame` of a delta) of the instances `changed` picks.
/// The bounds in `this` of the triangles of instance `inst` that are not the same surface
/// in `this` and `other` (as [`FrameDelta::triangle_changed`] decides, for an instance
/// that did not move), padded as [`FrameScene::instance_world_bounds`] pads the whole
/// instance: `Some(None)` when no triangle changed (only unused vertex data did), `None`
/// when the two frames' geometries of the instance cannot be compared triangle by
/// triangle (other geometries, indices, materials or placement: all of it changed).
fn changed_triangle_bounds(
    this: &FrameScene,
    other: &FrameScene,
    inst: u32,
) -> Option<Option<Bounds3>> {
    let xf = this.geometry_transforms();
    let mut bounds: Option<Bounds3> = None;
    for (g, x) in this.geometry.iter().enumerate() {
        if this.geometry_instance[g] != inst {
            continue;
        }
        let y = other.geometry.get(g)?;
        if other.geometry_instance.get(g) != Some(&inst)
            || x.material != y.material
            || x.world_space != y.world_space
            || x.indices.len() != y.indices.len()
        {
            return None;
        }
        for (ix, iy) in x.indices.iter().zip(y.indices.iter()) {
            if ix != iy {
                return None;
            }
            if ix.iter().all(|&v| same_vertex(x, y, v as usize)) {
                continue;
            }
            for &v in ix {
                let q = xf[g].transform_point3(*x.positions.get(v as usize)?);
                let b = Bounds3 { min: q, max: q };
                bounds = Some(bounds.map_or(b, |o| o.union(&b)));
            }
        }
    }
    Some(bounds.map(|b| {
        let pad = 1e-4 * (b.max - b.min).length().max(1e-3);
        Bounds3 {
            min: b.min - Vec3::splat(pad),
            max: b.max + Vec3::splat(pad),
        }
    }))
}

fn regions_in(scene: &FrameScene, frame: u32, changed: &dyn Fn(usize) -> bool) -> Vec<Region> {
    let n = scene.accel.instances().len();
    scene
        .instance_world_bounds_each(n, changed)
        .into_iter()
        .enumerate()
        .filter_map(|(i, b)| {
            b.map(|bounds| Region {
                instance: i as u32,
                frame,
                bounds,
            })
        })
        .collect()
}

/// Exact (bitwise) equality of evaluated values.
trait BitEq {
    fn bit_eq(&self, o: &Self) -> bool;
}

impl BitEq for f32 {
    fn bit_eq(&self, o: &Self) -> bool {
        self.to_bits() == o.to_bits()
    }
}

macro_rules! bit_eq_array {
    ($($t:ty),*) => {$(
        impl BitEq for $t {
            fn bit_eq(&self, o: &Self) -> bool {
                self.to_array().map(f32::to_bits) == o.to_array().map(f32::to_bits)
            }
        }
    )*};
}
bit_eq_array!(Vec2, Vec3, Vec4);

impl BitEq for crate::light::Environment {
    fn bit_eq(&self, o: &Self) -> bool {
        self.zenith.bit_eq(&o.zenith)
            && self.nadir.bit_eq(&o.nadir)
            && self.background.bit_eq(&o.background)
            && self.map_visible == o.map_visible
            && match (&self.map, &o.map) {
                (None, None) => true,
                // The same map (a scene's frames share one), or an equal one.
                (Some(a), Some(b)) => std::sync::Arc::ptr_eq(a, b) || a == b,
                _ => false,
            }
    }
}

impl BitEq for Affine3A {
    fn bit_eq(&self, o: &Self) -> bool {
        self.to_cols_array().map(f32::to_bits) == o.to_cols_array().map(f32::to_bits)
    }
}

impl BitEq for [u32; 3] {
    fn bit_eq(&self, o: &Self) -> bool {
        self == o
    }
}

impl<T: BitEq> BitEq for Option<T> {
    fn bit_eq(&self, o: &Self) -> bool {
        match (self, o) {
            (None, None) => true,
            (Some(a), Some(b)) => a.bit_eq(b),
            _ => false,
        }
    }
}

/// Shared data is equal without being read; otherwise element by element.
impl<T: BitEq> BitEq for Arc<Vec<T>> {
    fn bit_eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(self, o)
            || (self.len() == o.len() && self.iter().zip(o.iter()).all(|(a, b)| a.bit_eq(b)))
    }
}

fn same_geometry(a: &GeometryData, b: &GeometryData) -> bool {
    a.node == b.node
        && a.primitive == b.primitive
        && a.material == b.material
        && a.world_space == b.world_space
        && a.positions.bit_eq(&b.positions)
        && a.normals.bit_eq(&b.normals)
        && a.tangents.bit_eq(&b.tangents)
        && a.uvs[0].bit_eq(&b.uvs[0])
        && a.uvs[1].bit_eq(&b.uvs[1])
        && a.indices.bit_eq(&b.indices)
}

/// Vertex `v`'s data (everything a triangle's intersection and shading read) is the same
/// in both geometries; a vertex missing from either differs.
fn same_vertex(a: &GeometryData, b: &GeometryData, v: usize) -> bool {
    fn at<T: BitEq + Copy>(x: &Option<Arc<Vec<T>>>, y: &Option<Arc<Vec<T>>>, v: usize) -> bool {
        match (x, y) {
            (None, None) => true,
            (Some(x), Some(y)) => x.get(v).copied().bit_eq(&y.get(v).copied()),
            _ => false,
        }
    }
    let p = (a.positions.get(v), b.positions.get(v));
    matches!(p, (Some(p), Some(q)) if p.bit_eq(q))
        && at(&a.normals, &b.normals, v)
        && at(&a.tangents, &b.tangents, v)
        && at(&a.uvs[0], &b.uvs[0], v)
        && at(&a.uvs[1], &b.uvs[1], v)
}

fn is_infinite(l: &Light) -> bool {
    matches!(l, Light::Directional { .. } | Light::Environment { .. })
}

/// Every field of two lights, bitwise.
fn same_light(a: &Light, b: &Light) -> bool {
    use Light::*;
    match (a, b) {
        (
            Point { p, intensity },
            Point {
                p: p2,
                intensity: i2,
            },
        ) => p.bit_eq(p2) && intensity.bit_eq(i2),
        (
            Spot {
                p,
                axis,
                intensity,
                cos_inner,
                cos_outer,
            },
            Spot {
                p: p2,
                axis: a2,
                intensity: i2,
                cos_inner: ci2,
                cos_outer: co2,
            },
        ) => {
            p.bit_eq(p2)
                && axis.bit_eq(a2)
                && intensity.bit_eq(i2)
                && cos_inner.bit_eq(ci2)
                && cos_outer.bit_eq(co2)
        }
        (
            Directional { dir, irradiance },
            Directional {
                dir: d2,
                irradiance: i2,
            },
        ) => dir.bit_eq(d2) && irradiance.bit_eq(i2),
        (
            Triangle {
                p0,
                e1,
                e2,
                n,
                area,
                radiance,
                two_sided,
                tri,
                instance,
            },
            Triangle {
                p0: p02,
                e1: e12,
                e2: e22,
                n: n2,
                area: a2,
                radiance: r2,
                two_sided: t2,
                tri: tri2,
                instance: in2,
            },
        ) => {
            p0.bit_eq(p02)
                && e1.bit_eq(e12)
                && e2.bit_eq(e22)
                && n.bit_eq(n2)
                && area.bit_eq(a2)
                && radiance.bit_eq(r2)
                && two_sided == t2
                && tri == tri2
                && instance == in2
        }
        (Environment { env }, Environment { env: e2 }) => env.bit_eq(e2),
        _ => false,
    }
}

/// Placement, projection and image size, bitwise.
fn same_camera(a: &Camera, b: &Camera) -> bool {
    let projection = match (a.projection(), b.projection()) {
        (
            Projection::Perspective {
                yfov,
                aspect,
                znear,
            },
            Projection::Perspective {
                yfov: y2,
                aspect: a2,
                znear: z2,
            },
        ) => yfov.bit_eq(&y2) && aspect.bit_eq(&a2) && znear.bit_eq(&z2),
        (
            Projection::Orthographic { xmag, ymag },
            Projection::Orthographic { xmag: x2, ymag: y2 },
        ) => xmag.bit_eq(&x2) && ymag.bit_eq(&y2),
        _ => false,
    };
    projection
        && a.world_from_camera().bit_eq(&b.world_from_camera())
        && a.width == b.width
        && a.height == b.height
}

/// Indices of the textures a material samples.
fn texture_ids(m: &Material) -> impl Iterator<Item = usize> + '_ {
    [
        m.base_color_texture,
        m.metallic_roughness_texture,
        m.emissive_texture,
        m.normal_texture,
        m.transmission_texture,
    ]
    .into_iter()
    .flatten()
    .map(|t| t.texture.index())
}
