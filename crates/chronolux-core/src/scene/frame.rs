//! The render-ready frame: [`FrameScene`] (immutable, `Sync`) and the [`FrameBuilder`]
//! that makes one per animation time while keeping everything that does not change.
//!
//! Geometry classes, decided once from the animation (never from pixels):
//! - **static**: nodes no channel affects; their primitives (deformed once if morphed or
//!   skinned) are baked into one world-space BLAS built once for the whole animation;
//! - **rigid**: nodes moved by the animation but not deformed; each mesh has one
//!   object-space BLAS shared by all its instances and kept across frames; only the
//!   instance transform changes per frame;
//! - **deformed**: skinned or morphed nodes whose pose changes; their world-space BLAS is
//!   rebuilt per frame (topology is fixed, so geometry ids stay the same).
//!
//! Geometry ids ([`GeometryId`]: one per (node, primitive), in node order) are stable over
//! the animation, so per-element data of later techniques can be keyed by them.

use super::anim::{self, Pose};
use super::desc::{AlphaMode, AnimationId, CameraDesc, MaterialId, NodeId, Projection, SceneDesc};
use crate::accel::{Accel, Blas, Hit, Instance, TriRef};
use crate::camera::Camera;
use crate::color::Rgb;
use crate::geometry::{Bounds3, Ray};
use crate::light::{Light, LightSampler};
use crate::material::{self, ShadingPoint};
use crate::math::{Affine3A, Mat3, Mat4, Vec2, Vec3, Vec4};
use crate::scene::desc::{Material, Texture};
use std::collections::HashMap;
use std::sync::Arc;

/// Stable id of a (node, primitive) pair.
pub type GeometryId = u32;

/// Vertex data of one geometry in the space of its BLAS.
#[derive(Clone, Debug)]
pub struct GeometryData {
    pub node: NodeId,
    pub primitive: u32,
    pub positions: Arc<Vec<Vec3>>,
    pub normals: Option<Arc<Vec<Vec3>>>,
    pub tangents: Option<Arc<Vec<Vec4>>>,
    pub uvs: [Option<Arc<Vec<Vec2>>>; 2],
    pub indices: Arc<Vec<[u32; 3]>>,
    /// Index into [`FrameScene::materials`].
    pub material: u32,
    /// `true` when the data is in world space; otherwise in the object space of the
    /// instance that hit it.
    pub world_space: bool,
}

/// Everything about a surface point that shading needs (world space).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    pub p: Vec3,
    /// Geometric normal, front side per the (determinant-corrected) winding.
    pub ng: Vec3,
    pub shading: ShadingPoint,
    pub material: u32,
    pub tri: TriRef,
    pub instance: u32,
}

/// How to choose the camera.
#[derive(Clone, Debug, Default)]
pub enum CameraChoice {
    /// The scene's first camera; automatic framing when it has none.
    #[default]
    First,
    /// A camera node by name (the node's or the camera's).
    Named(String),
}

/// One frame, ready to render.
pub struct FrameScene {
    pub time: f32,
    pub accel: Accel,
    pub geometry: Arc<Vec<GeometryData>>,
    pub materials: Arc<Vec<Material>>,
    pub textures: Arc<Vec<Texture>>,
    pub lights: Vec<Light>,
    pub light_sampler: LightSampler,
    /// Light index of triangle 0 of each geometry (`u32::MAX`: not emissive); triangle `k`
    /// of an emissive geometry is light `base + k`.
    pub emissive_base: Vec<u32>,
    pub environment: Option<crate::light::Environment>,
    /// Index of the environment light in `lights`.
    pub environment_light: Option<usize>,
    pub camera: Camera,
    pub bounds: Bounds3,
    pub scene_radius: f32,
    /// Index in `accel.instances()` of the instance that carries each geometry (the
    /// static instance for static geometry, the node's instance for rigid and deformed
    /// geometry). Its `world_from_object` maps the geometry's vertex data to world space
    /// (identity for `world_space` data).
    pub geometry_instance: Vec<u32>,
    /// Per-geometry: material is alpha tested.
    alpha_tested: Vec<bool>,
}

impl FrameScene {
    /// World transform of every geometry's vertex data (identity for world-space data),
    /// from the instance that carries it ([`FrameScene::geometry_instance`]).
    pub fn geometry_transforms(&self) -> Vec<Affine3A> {
        let inst = self.accel.instances();
        self.geometry
            .iter()
            .zip(&self.geometry_instance)
            .map(|(g, &i)| {
                if g.world_space {
                    Affine3A::IDENTITY
                } else {
                    inst[i as usize].world_from_object
                }
            })
            .collect()
    }

    /// World bounds of every instance `i < n` that `select(i)` picks, from its vertices,
    /// slightly padded (1e-4 of the diagonal, at least 1e-7) so that surfaces on a box
    /// face count as inside; in instance order. Instances with no geometry give no box.
    pub fn instance_world_bounds(&self, n: usize, select: impl Fn(usize) -> bool) -> Vec<Bounds3> {
        self.instance_world_bounds_each(n, select)
            .into_iter()
            .flatten()
            .collect()
    }

    /// [`FrameScene::instance_world_bounds`] indexed by instance (`None`: not picked, or
    /// no vertices).
    pub fn instance_world_bounds_each(
        &self,
        n: usize,
        select: impl Fn(usize) -> bool,
    ) -> Vec<Option<Bounds3>> {
        let xf = self.geometry_transforms();
        let mut boxes: Vec<Option<Bounds3>> = vec![None; n];
        for (g, geo) in self.geometry.iter().enumerate() {
            let i = self.geometry_instance[g] as usize;
            if i >= n || !select(i) {
                continue;
            }
            for p in geo.positions.iter() {
                let q = xf[g].transform_point3(*p);
                let b = Bounds3 { min: q, max: q };
                boxes[i] = Some(boxes[i].map_or(b, |o| o.union(&b)));
            }
        }
        boxes
            .into_iter()
            .map(|b| {
                b.map(|b| {
                    let pad = 1e-4 * (b.max - b.min).length().max(1e-3);
                    Bounds3 {
                        min: b.min - Vec3::splat(pad),
                        max: b.max + Vec3::splat(pad),
                    }
                })
            })
            .collect()
    }

    /// Whether a ray may stop at this triangle point (alpha mask / stochastic blend).
    #[inline]
    pub fn accept(&self, tri: TriRef, b1: f32, b2: f32) -> bool {
        let g = &self.geometry[tri.geometry as usize];
        if !self.alpha_tested[tri.geometry as usize] {
            return true;
        }
        let m = &self.materials[g.material as usize];
        let uv = interp_uvs(g, tri.triangle, b1, b2);
        let a = material::alpha_at(m, &self.textures, uv);
        match m.alpha_mode {
            AlphaMode::Blend => {
                // Deterministic stochastic transparency: hash the hit location.
                let h = crate::sampling::hash_words(&[
                    tri.geometry as u64,
                    tri.triangle as u64,
                    b1.to_bits() as u64,
                    b2.to_bits() as u64,
                ]);
                ((h >> 40) as f32 / (1u64 << 24) as f32) < a
            }
            _ => a > 0.5,
        }
    }

    /// Closest surface along `ray`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.accel
            .intersect(ray, |t, b1, b2| self.accept(t, b1, b2))
    }

    /// Whether anything blocks `ray` before `ray.tmax`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray, |t, b1, b2| self.accept(t, b1, b2))
    }

    /// Closest hits of many rays at once (`out[k]` for `rays[k]`, equal to
    /// [`FrameScene::intersect`] on each; in packets on Embree).
    pub fn intersect_many(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.accel
            .intersect_many(rays, |t, b1, b2| self.accept(t, b1, b2), out)
    }

    /// Occlusion of many rays at once (equal to [`FrameScene::occluded`] on each).
    pub fn occluded_many(&self, rays: &[Ray], out: &mut [bool]) {
        self.accel
            .occluded_many(rays, |t, b1, b2| self.accept(t, b1, b2), out)
    }

    /// Surface data at a hit.
    pub fn interaction(&self, hit: &Hit, ray: &Ray) -> SurfaceInteraction {
        let mut si = self.surface_at(hit.tri, hit.instance, hit.b1, hit.b2, Some(ray.at(hit.t)));
        // Reached from behind (against the winding's normal): the segment ran inside the
        // mesh; its world-space length is what a volume absorbs along.
        if ray.d.dot(si.ng) > 0.0 {
            si.shading.interior_distance = hit.t * ray.d.length();
        }
        si
    }

    /// The BSDF of the surface at `si`: its material with this scene's textures at its
    /// shading point.
    pub fn bsdf(&self, si: &SurfaceInteraction) -> crate::bsdf::Bsdf {
        material::bsdf_at(
            &self.materials[si.material as usize],
            &self.textures,
            &si.shading,
        )
    }

    /// Surface data at barycentrics (b1, b2) of a triangle of an instance.
    pub fn surface_at(
        &self,
        tri: TriRef,
        instance: u32,
        b1: f32,
        b2: f32,
        p_hint: Option<Vec3>,
    ) -> SurfaceInteraction {
        let g = &self.geometry[tri.geometry as usize];
        let [i0, i1, i2] = g.indices[tri.triangle as usize].map(|i| i as usize);
        let b0 = 1.0 - b1 - b2;
        let (p0, p1, p2) = (g.positions[i0], g.positions[i1], g.positions[i2]);
        let (to_world, normal_m) = if g.world_space {
            (Affine3A::IDENTITY, Mat3::IDENTITY)
        } else {
            let inst = &self.accel.instances()[instance as usize];
            (
                inst.world_from_object,
                Mat3::from(inst.object_from_world.matrix3).transpose(),
            )
        };
        let p_obj = b0 * p0 + b1 * p1 + b2 * p2;
        let p = p_hint.unwrap_or_else(|| to_world.transform_point3(p_obj));
        let ng_obj = (p1 - p0).cross(p2 - p0);
        let ng = (normal_m * ng_obj).normalize_or_zero();
        let ns = match &g.normals {
            Some(n) => {
                let v = normal_m * (b0 * n[i0] + b1 * n[i1] + b2 * n[i2]);
                let v = v.normalize_or_zero();
                if v == Vec3::ZERO { ng } else { v }
            }
            None => ng,
        };
        let uv = interp_uvs(g, tri.triangle, b1, b2);
        let mut dpdu = Vec3::ZERO;
        if let Some(uvs) = &g.uvs[0] {
            let (duv1, duv2) = (uvs[i1] - uvs[i0], uvs[i2] - uvs[i0]);
            let det = duv1.x * duv2.y - duv1.y * duv2.x;
            if det.abs() > 1e-12 {
                let d = ((p1 - p0) * duv2.y - (p2 - p0) * duv1.y) / det;
                dpdu = to_world.transform_vector3(d);
            }
        }
        let tangent = g.tangents.as_ref().map(|t| {
            let v = b0 * t[i0] + b1 * t[i1] + b2 * t[i2];
            let xyz = to_world.transform_vector3(v.truncate()).normalize_or_zero();
            xyz.extend(if t[i0].w < 0.0 { -1.0 } else { 1.0 })
        });
        SurfaceInteraction {
            p,
            ng,
            shading: ShadingPoint {
                ng,
                ns,
                dpdu,
                tangent,
                uv,
                interior_distance: 0.0,
            },
            material: g.material,
            tri,
            instance,
        }
    }

    /// Emitted radiance of a surface point towards `w` (unit, away from the surface).
    pub fn emitted(&self, si: &SurfaceInteraction, w: Vec3) -> Rgb {
        let m = &self.materials[si.material as usize];
        if m.emissive == Rgb::ZERO {
            return Rgb::ZERO;
        }
        if !m.double_sided && si.ng.dot(w) <= 0.0 {
            return Rgb::ZERO;
        }
        material::emission_at(m, &self.textures, &si.shading)
    }

    /// This frame with the instances `drop[i]` (true) emptied: each is replaced by an empty
    /// placeholder, so instance and geometry ids, lights, camera, bounds and scene radius
    /// stay exactly those of the frame (a photon or camera path traced in the copy makes
    /// the same decisions as in the frame until it would have hit a dropped instance).
    /// The light list is kept as is: the caller decides what a light on a dropped
    /// instance means. Used for the static part of a segment of frames (the scene without
    /// its dynamic objects, `ic-static-dynamic`).
    pub fn without_instances(&self, drop: &[bool]) -> FrameScene {
        let empty = Arc::new(crate::accel::Blas::build(&[], false));
        let instances = self
            .accel
            .instances()
            .iter()
            .enumerate()
            .map(|(i, inst)| {
                if drop.get(i).copied().unwrap_or(false) {
                    Instance::new(empty.clone(), inst.world_from_object)
                        .with_geometry_base(inst.geometry_base)
                } else {
                    inst.clone()
                }
            })
            .collect();
        let mut accel = Accel::new(instances);
        accel.bounds = self.bounds;
        FrameScene {
            time: self.time,
            accel,
            geometry: self.geometry.clone(),
            materials: self.materials.clone(),
            textures: self.textures.clone(),
            lights: self.lights.clone(),
            light_sampler: self.light_sampler.clone(),
            emissive_base: self.emissive_base.clone(),
            environment: self.environment.clone(),
            environment_light: self.environment_light,
            camera: self.camera.clone(),
            bounds: self.bounds,
            scene_radius: self.scene_radius,
            geometry_instance: self.geometry_instance.clone(),
            alpha_tested: self.alpha_tested.clone(),
        }
    }

    /// Light index of an emissive triangle.
    pub fn light_of(&self, tri: TriRef) -> Option<usize> {
        let b = self.emissive_base[tri.geometry as usize];
        (b != u32::MAX).then(|| (b + tri.triangle) as usize)
    }
}

fn interp_uvs(g: &GeometryData, tri: u32, b1: f32, b2: f32) -> [Vec2; 2] {
    let [i0, i1, i2] = g.indices[tri as usize].map(|i| i as usize);
    let b0 = 1.0 - b1 - b2;
    let f = |u: &Option<Arc<Vec<Vec2>>>| {
        u.as_ref()
            .map_or(Vec2::ZERO, |u| b0 * u[i0] + b1 * u[i1] + b2 * u[i2])
    };
    [f(&g.uvs[0]), f(&g.uvs[1])]
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Static,
    Rigid,
    Deformed,
}

/// One (node, primitive) of the scene.
struct Slot {
    node: NodeId,
    primitive: u32,
    class: Class,
    material: u32,
}

/// Builds [`FrameScene`]s for times of one animation clip, keeping BLASes across frames.
pub struct FrameBuilder {
    desc: Arc<SceneDesc>,
    anim: Option<AnimationId>,
    slots: Vec<Slot>,
    materials: Arc<Vec<Material>>,
    textures: Arc<Vec<Texture>>,
    alpha_tested: Vec<bool>,
    static_blas: Option<Arc<Blas>>,
    static_geometry: HashMap<GeometryId, GeometryData>,
    /// Object-space BLAS per rigid node (shared by nodes with the same mesh), with the
    /// first geometry id of the node.
    rigid: Vec<(NodeId, Arc<Blas>, GeometryId)>,
    /// Object-space geometry data of rigid slots.
    rigid_geometry: HashMap<GeometryId, GeometryData>,
    /// Statistics of the last build.
    pub last_build: BuildStats,
    camera: CameraChoice,
    width: u32,
    height: u32,
}

/// What the last [`FrameBuilder::build`] did.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct BuildStats {
    pub blas_rebuilt: u32,
    pub triangles_rebuilt: u64,
    pub instances: u32,
    pub seconds: f64,
}

/// Errors choosing a camera.
#[derive(Debug, thiserror::Error)]
pub enum FrameError {
    #[error("no camera named '{0}' in the scene (cameras: {1})")]
    NoSuchCamera(String, String),
}

impl FrameBuilder {
    pub fn new(
        desc: Arc<SceneDesc>,
        anim: Option<AnimationId>,
        camera: CameraChoice,
        width: u32,
        height: u32,
    ) -> Result<Self, FrameError> {
        Self::with_movable(desc, anim, camera, width, height, &[])
    }

    /// [`FrameBuilder::new`], with the nodes `movable[n]` (and their descendants) treated
    /// as animated even where the clip leaves them still: their meshes get their own
    /// instance instead of joining the static BVH, so that a later builder over the same
    /// scene with those nodes moved has the same instances, and [`FrameDelta`] reports only
    /// the moved ones (the live viewer's edits). A shorter slice leaves the rest as `new`.
    ///
    /// [`FrameDelta`]: super::delta::FrameDelta
    pub fn with_movable(
        desc: Arc<SceneDesc>,
        anim: Option<AnimationId>,
        camera: CameraChoice,
        width: u32,
        height: u32,
        movable: &[bool],
    ) -> Result<Self, FrameError> {
        if let CameraChoice::Named(name) = &camera
            && find_camera(&desc, Some(name)).is_none()
        {
            let names: Vec<String> = camera_nodes(&desc)
                .iter()
                .map(|(n, c)| format!("{} ({})", c.name, desc.nodes[n.index()].name))
                .collect();
            return Err(FrameError::NoSuchCamera(
                name.clone(),
                if names.is_empty() {
                    "none".into()
                } else {
                    names.join(", ")
                },
            ));
        }
        let mut dynamic = anim::dynamic_nodes(&desc, anim);
        if movable.iter().any(|&m| m) {
            for id in desc.topological_order() {
                let i = id.index();
                let parent_moves = desc.nodes[i].parent.is_some_and(|p| dynamic[p.index()]);
                dynamic[i] |= movable.get(i).copied().unwrap_or(false) || parent_moves;
            }
        }
        let mut materials = desc.materials.clone();
        let default_material = materials.len() as u32;
        materials.push(Material::gltf_default());
        let mut slots = Vec::new();
        for id in desc.topological_order() {
            let node = &desc.nodes[id.index()];
            let Some(mesh) = node.mesh else { continue };
            let mesh = &desc.meshes[mesh.index()];
            let deforming =
                node.skin.is_some() || mesh.primitives.iter().any(|p| !p.morph_targets.is_empty());
            let class = match (dynamic[id.index()], deforming) {
                (false, _) => Class::Static,
                (true, false) => Class::Rigid,
                (true, true) => Class::Deformed,
            };
            for (k, p) in mesh.primitives.iter().enumerate() {
                slots.push(Slot {
                    node: id,
                    primitive: k as u32,
                    class,
                    material: p.material.map_or(default_material, |m: MaterialId| m.0),
                });
            }
        }
        let alpha_tested = slots
            .iter()
            .map(|s| materials[s.material as usize].alpha_mode != AlphaMode::Opaque)
            .collect();
        let textures = Arc::new(desc.textures.clone());
        let mut b = FrameBuilder {
            desc,
            anim,
            slots,
            materials: Arc::new(materials),
            textures,
            alpha_tested,
            static_blas: None,
            static_geometry: HashMap::new(),
            rigid: Vec::new(),
            rigid_geometry: HashMap::new(),
            last_build: BuildStats::default(),
            camera,
            width,
            height,
        };
        b.build_persistent();
        Ok(b)
    }

    pub fn desc(&self) -> &SceneDesc {
        &self.desc
    }

    /// Number of geometries (stable ids `0..n`).
    pub fn geometry_count(&self) -> usize {
        self.slots.len()
    }

    fn geometry_data(&self, gid: usize, pose: &Pose, world: bool) -> GeometryData {
        let s = &self.slots[gid];
        let node = &self.desc.nodes[s.node.index()];
        let mesh = &self.desc.meshes[node.mesh.unwrap().index()];
        let prim = &mesh.primitives[s.primitive as usize];
        let (mut pos, mut nrm, skinned) =
            match anim::deform_primitive(&self.desc, s.node, prim, pose) {
                Some((p, n)) => (p, n, node.skin.is_some()),
                None => (prim.positions.clone(), prim.normals.clone(), false),
            };
        let mut indices = prim.indices.clone();
        let mut tangents = prim.tangents.clone();
        if world && !skinned {
            let m: Mat4 = pose.world[s.node.index()];
            let nm = Mat3::from_mat4(m).inverse().transpose();
            pos.iter_mut().for_each(|p| *p = m.transform_point3(*p));
            if let Some(n) = nrm.as_mut() {
                n.iter_mut()
                    .for_each(|v| *v = (nm * *v).normalize_or_zero());
            }
            if let Some(t) = tangents.as_mut() {
                t.iter_mut().for_each(|v| {
                    *v = m
                        .transform_vector3(v.truncate())
                        .normalize_or_zero()
                        .extend(v.w)
                });
            }
            // A mirroring transform flips the winding; keep the front face (glTF rule).
            if m.determinant() < 0.0 {
                indices.iter_mut().for_each(|t| t.swap(1, 2));
            }
        }
        GeometryData {
            node: s.node,
            primitive: s.primitive,
            positions: Arc::new(pos),
            normals: nrm.map(Arc::new),
            tangents: tangents.map(Arc::new),
            uvs: [
                prim.uvs.clone().map(Arc::new),
                prim.uvs1.clone().map(Arc::new),
            ],
            indices: Arc::new(indices),
            material: s.material,
            world_space: world,
        }
    }

    fn blas_items(
        gid: GeometryId,
        local: u32,
        g: &GeometryData,
        out: &mut Vec<(TriRef, [Vec3; 3])>,
    ) {
        let _ = gid;
        for (k, t) in g.indices.iter().enumerate() {
            let v = t.map(|i| g.positions[i as usize]);
            out.push((
                TriRef {
                    geometry: local,
                    triangle: k as u32,
                },
                v,
            ));
        }
    }

    /// Geometry-id ranges of each mesh node (a node's primitives have consecutive ids).
    fn node_groups(&self) -> Vec<(NodeId, std::ops::Range<usize>)> {
        let mut out: Vec<(NodeId, std::ops::Range<usize>)> = Vec::new();
        for (gid, s) in self.slots.iter().enumerate() {
            match out.last_mut() {
                Some((n, r)) if *n == s.node => r.end = gid + 1,
                _ => out.push((s.node, gid..gid + 1)),
            }
        }
        out
    }

    fn build_persistent(&mut self) {
        let pose = anim::pose_at(&self.desc, self.anim, 0.0);
        let mut items = Vec::new();
        let mut filter = false;
        for gid in 0..self.slots.len() {
            if self.slots[gid].class == Class::Static {
                let g = self.geometry_data(gid, &pose, true);
                Self::blas_items(gid as u32, gid as u32, &g, &mut items);
                filter |= self.alpha_tested[gid];
                self.static_geometry.insert(gid as u32, g);
            }
        }
        if !items.is_empty() {
            self.static_blas = Some(Arc::new(Blas::build(&items, filter)));
        }
        // Rigid nodes: one object-space BLAS per mesh, shared by nodes using it.
        let mut by_mesh: HashMap<u32, Arc<Blas>> = HashMap::new();
        for (node, range) in self.node_groups() {
            let (gid, n_prims) = (range.start, range.len());
            if self.slots[gid].class == Class::Rigid {
                let mesh = self.desc.nodes[node.index()].mesh.unwrap().0;
                let mut items = Vec::new();
                let mut filter = false;
                for k in 0..n_prims {
                    let g = self.geometry_data(gid + k, &pose, false);
                    Self::blas_items((gid + k) as u32, k as u32, &g, &mut items);
                    filter |= self.alpha_tested[gid + k];
                    self.rigid_geometry.insert((gid + k) as u32, g);
                }
                let blas = by_mesh
                    .entry(mesh)
                    .or_insert_with(|| Arc::new(Blas::build(&items, filter)))
                    .clone();
                self.rigid.push((node, blas, gid as u32));
            }
        }
    }

    /// Builds the frame at time `t` (seconds).
    pub fn build(&mut self, t: f32) -> FrameScene {
        let start = std::time::Instant::now();
        let pose = anim::pose_at(&self.desc, self.anim, t);
        let mut stats = BuildStats::default();
        let mut geometry: Vec<Option<GeometryData>> = vec![None; self.slots.len()];
        let mut instances = Vec::new();
        if let Some(b) = &self.static_blas {
            instances.push(Instance::new(b.clone(), Affine3A::IDENTITY).with_geometry_base(0));
        }
        for (gid, g) in &self.static_geometry {
            geometry[*gid as usize] = Some(g.clone());
        }
        for (node, blas, base) in &self.rigid {
            let m = Affine3A::from_mat4(pose.world[node.index()]);
            instances.push(Instance::new(blas.clone(), m).with_geometry_base(*base));
        }
        // Deformed nodes: world-space data and a fresh BLAS per node.
        let mut instance_of = vec![0u32; self.slots.len()];
        for (_, range) in self.node_groups() {
            let (gid, n_prims) = (range.start, range.len());
            if self.slots[gid].class == Class::Deformed {
                let mut items = Vec::new();
                let mut filter = false;
                for k in 0..n_prims {
                    let g = self.geometry_data(gid + k, &pose, true);
                    Self::blas_items((gid + k) as u32, k as u32, &g, &mut items);
                    filter |= self.alpha_tested[gid + k];
                    geometry[gid + k] = Some(g);
                }
                stats.blas_rebuilt += 1;
                stats.triangles_rebuilt += items.len() as u64;
                instance_of[range.clone()].fill(instances.len() as u32);
                instances.push(
                    Instance::new(Arc::new(Blas::build(&items, filter)), Affine3A::IDENTITY)
                        .with_geometry_base(gid as u32),
                );
            }
        }
        // Instance index of each rigid geometry (for world-space light triangles): rigid
        // instances follow the static one, in `self.rigid` order. (Static geometry: the
        // static instance, 0; deformed geometry: set above.)
        let first_rigid = self.static_blas.is_some() as u32;
        for (k, (node, _, base)) in self.rigid.iter().enumerate() {
            for (g, s) in self.slots.iter().enumerate().skip(*base as usize) {
                if s.node != *node {
                    break;
                }
                instance_of[g] = first_rigid + k as u32;
            }
        }
        let accel = Accel::new(instances);
        for (gid, g) in self.rigid_geometry.iter() {
            geometry[*gid as usize] = Some(g.clone());
        }
        let geometry: Vec<GeometryData> = geometry
            .into_iter()
            .map(|g| g.expect("every slot has data"))
            .collect();
        let bounds = accel.bounds;
        let (_, radius) = bounds.bounding_sphere();

        // Lights.
        let mut lights = Vec::new();
        let mut emissive_base = vec![u32::MAX; geometry.len()];
        for (gid, g) in geometry.iter().enumerate() {
            let m = &self.materials[g.material as usize];
            if m.emissive == Rgb::ZERO {
                continue;
            }
            emissive_base[gid] = lights.len() as u32;
            let to_world = if g.world_space {
                Affine3A::IDENTITY
            } else {
                accel.instances()[instance_of[gid] as usize].world_from_object
            };
            let flip = !g.world_space && to_world.matrix3.determinant() < 0.0;
            for (k, tri) in g.indices.iter().enumerate() {
                let [a, b, c] = tri.map(|i| to_world.transform_point3(g.positions[i as usize]));
                let (e1, e2) = (b - a, c - a);
                let cr = e1.cross(e2);
                let area = 0.5 * cr.length();
                let n = if flip { -cr } else { cr }.normalize_or_zero();
                lights.push(Light::Triangle {
                    p0: a,
                    e1,
                    e2,
                    n,
                    area,
                    radiance: if area > 0.0 { m.emissive } else { Rgb::ZERO },
                    two_sided: m.double_sided,
                    tri: TriRef {
                        geometry: gid as u32,
                        triangle: k as u32,
                    },
                    instance: instance_of[gid],
                });
            }
        }
        for (i, node) in self.desc.nodes.iter().enumerate() {
            let Some(l) = node.light else { continue };
            let l = &self.desc.lights[l.index()];
            let m = pose.world[i];
            let p = m.transform_point3(Vec3::ZERO);
            let axis = m.transform_vector3(-Vec3::Z).normalize_or_zero();
            let c = l.color * l.intensity;
            lights.push(match l.kind {
                super::desc::LightKind::Point => Light::Point { p, intensity: c },
                super::desc::LightKind::Spot {
                    inner_cone,
                    outer_cone,
                } => Light::Spot {
                    p,
                    axis,
                    intensity: c,
                    cos_inner: inner_cone.cos(),
                    cos_outer: outer_cone.cos(),
                },
                super::desc::LightKind::Directional => Light::Directional {
                    dir: axis,
                    irradiance: c,
                },
            });
        }
        let mut environment_light = None;
        if let Some(env) = self.desc.environment.clone() {
            environment_light = Some(lights.len());
            lights.push(Light::Environment { env });
        }
        let light_sampler = LightSampler::new(&lights, radius);
        let camera = self.camera_at(&pose, bounds, &lights, radius);
        stats.instances = accel.instances().len() as u32;
        stats.seconds = start.elapsed().as_secs_f64();
        self.last_build = stats;
        FrameScene {
            time: t,
            accel,
            geometry: Arc::new(geometry),
            materials: self.materials.clone(),
            textures: self.textures.clone(),
            lights,
            light_sampler,
            emissive_base,
            environment: self.desc.environment.clone(),
            environment_light,
            camera,
            bounds,
            scene_radius: radius,
            geometry_instance: instance_of,
            alpha_tested: self.alpha_tested.clone(),
        }
    }

    /// The camera may move (or change) during the clip: its node or an ancestor is
    /// animated, or, for the automatic camera (framed from the scene's bounds), anything
    /// is. Derived from the animation (conservative: a channel whose keys differ counts
    /// even if the camera happens to return), never from rendered frames.
    pub fn camera_may_move(&self) -> bool {
        let name = match &self.camera {
            CameraChoice::First => None,
            CameraChoice::Named(n) => Some(n.as_str()),
        };
        let dynamic = super::anim::dynamic_nodes(&self.desc, self.anim);
        match find_camera(&self.desc, name) {
            Some((node, _)) => dynamic[node.index()],
            None => dynamic.iter().any(|&d| d),
        }
    }

    fn camera_at(&self, pose: &Pose, bounds: Bounds3, lights: &[Light], radius: f32) -> Camera {
        let name = match &self.camera {
            CameraChoice::First => None,
            CameraChoice::Named(n) => Some(n.as_str()),
        };
        match find_camera(&self.desc, name) {
            Some((node, cam)) => Camera::new(
                Affine3A::from_mat4(pose.world[node.index()]),
                cam.projection,
                self.width,
                self.height,
            ),
            None => auto_camera(
                bounds,
                light_side(lights, bounds, radius),
                self.width,
                self.height,
            ),
        }
    }
}

fn camera_nodes(desc: &SceneDesc) -> Vec<(NodeId, &CameraDesc)> {
    desc.topological_order()
        .into_iter()
        .filter_map(|n| {
            desc.nodes[n.index()]
                .camera
                .map(|c| (n, &desc.cameras[c.index()]))
        })
        .collect()
}

fn find_camera<'a>(desc: &'a SceneDesc, name: Option<&str>) -> Option<(NodeId, &'a CameraDesc)> {
    let cams = camera_nodes(desc);
    match name {
        None => cams.into_iter().next(),
        Some(n) => cams
            .into_iter()
            .find(|(node, c)| c.name == n || desc.nodes[node.index()].name == n),
    }
}

/// Where the light comes from, seen from the centre of `bounds`: the power-weighted mean
/// of the unit directions towards each light (towards a point or spot light, against a
/// directional light's travel, towards an emissive triangle's centroid, and up for an
/// environment brighter above than below, weighted by its zenith–nadir contrast). Its length
/// (≤ 1) says how one-sided the lighting is: 0 for a uniform environment or lights all around.
pub fn light_side(lights: &[Light], bounds: Bounds3, radius: f32) -> Vec3 {
    let (c, _) = bounds.bounding_sphere();
    let mut sum = Vec3::ZERO;
    let mut total = 0.0f32;
    for l in lights {
        let power = l.power(radius);
        if !(power.is_finite() && power > 0.0) {
            continue;
        }
        let dir = match l {
            Light::Point { p, .. } | Light::Spot { p, .. } => (*p - c).normalize_or_zero(),
            Light::Directional { dir, .. } => -dir.normalize_or_zero(),
            Light::Triangle { p0, e1, e2, .. } => {
                (*p0 + (*e1 + *e2) * (1.0 / 3.0) - c).normalize_or_zero()
            }
            Light::Environment { env } if env.map.is_some() => {
                env.map.as_ref().map_or(Vec3::ZERO, |m| m.mean_direction())
            }
            Light::Environment { env } => {
                let up = crate::color::luminance(env.zenith - env.nadir);
                let both = crate::color::luminance(env.zenith + env.nadir);
                Vec3::Y * if both > 0.0 { up / both } else { 0.0 }
            }
        };
        sum += dir * power;
        total += power;
    }
    if total > 0.0 && sum.is_finite() {
        sum / total
    } else {
        Vec3::ZERO
    }
}

/// A perspective camera (yfov 40°) looking at the scene's centre from a distance at which
/// the bounding sphere fills the view. Without a light side (`light_side` zero) it stands on
/// the +Z side, slightly above; otherwise it turns towards the light side by its strength
/// ([`light_side`]), so a model lit from above or from one side shows its lit faces, with
/// the elevation kept within ±60° so "up" stays defined.
pub fn auto_camera(bounds: Bounds3, light_side: Vec3, width: u32, height: u32) -> Camera {
    let (c, r) = bounds.bounding_sphere();
    let r = if r > 0.0 { r } else { 1.0 };
    let mut view = Vec3::new(0.0, 0.25, 1.0).normalize() + light_side.clamp_length_max(1.0);
    let horizontal = Vec3::new(view.x, 0.0, view.z);
    let h = horizontal.length();
    let max_elev = 60f32.to_radians();
    if h < 1e-3 || view.y.abs() > h * max_elev.tan() {
        let hdir = if h < 1e-3 { Vec3::Z } else { horizontal / h };
        view = hdir * max_elev.cos() + Vec3::Y * max_elev.sin() * view.y.signum();
    }
    let view = view.normalize();
    let yfov = 40f32.to_radians();
    let half = (0.5 * yfov).min(0.5 * yfov * width as f32 / height as f32);
    let dist = r / half.sin();
    let eye = c + view * dist;
    let f = (c - eye).normalize();
    let right = f.cross(Vec3::Y).normalize();
    let up = right.cross(f);
    let world_from_camera = Affine3A::from_cols(right.into(), up.into(), (-f).into(), eye.into());
    Camera::new(
        world_from_camera,
        Projection::Perspective {
            yfov,
            aspect: None,
            znear: 0.01,
        },
        width,
        height,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::desc::{
        Animation, Channel, ChannelTarget, Interpolation, Mesh, MeshId, Node, Primitive,
    };

    /// A unit quad in the XY plane facing +Z, on a node; a second, static quad far behind.
    fn quad_scene(scale: Vec3, animated: bool) -> SceneDesc {
        let quad = Primitive {
            positions: vec![
                Vec3::new(-0.5, -0.5, 0.0),
                Vec3::new(0.5, -0.5, 0.0),
                Vec3::new(0.5, 0.5, 0.0),
                Vec3::new(-0.5, 0.5, 0.0),
            ],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            ..Default::default()
        };
        let mut desc = SceneDesc {
            nodes: vec![
                Node {
                    name: "moving".into(),
                    mesh: Some(MeshId(0)),
                    transform: Trs {
                        scale,
                        ..Default::default()
                    },
                    ..Default::default()
                },
                Node {
                    name: "wall".into(),
                    mesh: Some(MeshId(0)),
                    transform: Trs {
                        translation: Vec3::new(0.0, 0.0, -10.0),
                        scale: Vec3::splat(100.0),
                        ..Default::default()
                    },
                    ..Default::default()
                },
            ],
            roots: vec![NodeId(0), NodeId(1)],
            meshes: vec![Mesh {
                primitives: vec![quad],
                ..Default::default()
            }],
            materials: vec![],
            ..Default::default()
        };
        if animated {
            desc.animations.push(Animation {
                name: "slide".into(),
                channels: vec![Channel {
                    node: NodeId(0),
                    target: ChannelTarget::Translation,
                    interpolation: Interpolation::Linear,
                    times: vec![0.0, 1.0],
                    values: vec![0.0, 0.0, 0.0, 2.0, 0.0, 0.0],
                    components: 3,
                }],
            });
        }
        desc
    }

    use crate::scene::desc::Trs;

    #[test]
    fn rigid_instance_follows_its_animation_and_static_geometry_stays() {
        let desc = Arc::new(quad_scene(Vec3::ONE, true));
        let mut b =
            FrameBuilder::new(desc, Some(AnimationId(0)), CameraChoice::First, 8, 8).unwrap();
        for (t, x) in [(0.0f32, 0.0f32), (0.5, 1.0), (1.0, 2.0)] {
            let f = b.build(t);
            let hit = f
                .intersect(&Ray::new(Vec3::new(x, 0.0, 5.0), -Vec3::Z))
                .unwrap();
            assert!(
                (hit.t - 5.0).abs() < 1e-5,
                "t={t}: moving quad not at x={x}"
            );
            assert_eq!(f.geometry[hit.tri.geometry as usize].node, NodeId(0));
            // Just outside the moving quad, the ray reaches the static wall at z = -10.
            let miss = f
                .intersect(&Ray::new(Vec3::new(x + 0.6, 0.0, 5.0), -Vec3::Z))
                .unwrap();
            assert!((miss.t - 15.0).abs() < 1e-4);
            assert_eq!(f.geometry[miss.tri.geometry as usize].node, NodeId(1));
        }
        assert_eq!(
            b.last_build.blas_rebuilt, 0,
            "rigid motion must not rebuild any BLAS"
        );
    }

    #[test]
    fn mirrored_nodes_keep_their_front_face() {
        // Scale (-1, 1, 1) mirrors the quad; glTF says the winding flips with it, so the
        // front face still points to +Z (towards where the unmirrored quad faced).
        for animated in [false, true] {
            let desc = Arc::new(quad_scene(Vec3::new(-1.0, 1.0, 1.0), animated));
            let anim = animated.then_some(AnimationId(0));
            let mut b = FrameBuilder::new(desc, anim, CameraChoice::First, 8, 8).unwrap();
            let f = b.build(0.0);
            let ray = Ray::new(Vec3::new(0.1, 0.1, 5.0), -Vec3::Z);
            let hit = f.intersect(&ray).unwrap();
            let si = f.interaction(&hit, &ray);
            assert!(si.ng.z > 0.99, "animated={animated}: ng = {}", si.ng);
        }
    }
}
