//! The scene as the viewer's user has edited it: the loaded description plus the edits
//! (the animation time, per-node offsets, light intensities, material base colours),
//! turned into a [`FrameScene`] on demand.

use anyhow::Result;
use chronolux_core::color::Rgb;
use chronolux_core::math::{Quat, Vec3};
use chronolux_core::scene::desc::{AnimationId, ChannelTarget, Interpolation, SceneDesc};
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder, FrameScene};
use glam::EulerRot;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use std::sync::Arc;

/// Largest intensity factor a light accepts (of its value in the file).
pub const MAX_INTENSITY: f32 = 100.0;
/// Largest node offset accepted, in multiples of the scene's bounding radius at load.
pub const MAX_OFFSET_RADII: f32 = 10.0;

/// One change the user makes. Every edit sets an absolute value (not an increment), so
/// replaying or coalescing edits of one control gives the same scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Edit {
    /// The animation time in seconds (clamped to the clip).
    Time { t: f32 },
    /// Offsets of a node from its animated placement: `translate` (scene units, in the
    /// parent's frame) and `rotate` (degrees about x, then y, then z, about the node's
    /// origin).
    Node {
        node: u32,
        translate: [f32; 3],
        rotate: [f32; 3],
    },
    /// A light node's intensity, as a factor of its value in the file: a punctual light's
    /// intensity, or the emission of an emissive mesh's materials.
    Light { node: u32, intensity: f32 },
    /// A material's base colour (linear RGB in [0, 1]).
    Material { material: u32, base_color: [f32; 3] },
}

/// What an edit is checked against (a copy the web server keeps, so that a bad edit is
/// refused at once, without waiting for the render loop).
#[derive(Clone, Debug)]
pub struct Limits {
    nodes: usize,
    materials: usize,
    lights: Vec<bool>,
    radius: f32,
}

impl Limits {
    /// Checks `e` against the scene without applying it.
    pub fn check(&self, e: &Edit) -> Result<(), String> {
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        let node = |n: u32| {
            if (n as usize) < self.nodes {
                Ok(n as usize)
            } else {
                Err(format!("no node {n} (the scene has {})", self.nodes))
            }
        };
        match e {
            Edit::Time { t } => {
                if !t.is_finite() {
                    return Err("t must be a finite number of seconds".into());
                }
            }
            Edit::Node {
                node: n,
                translate,
                rotate,
            } => {
                node(*n)?;
                if !finite(translate) || !finite(rotate) {
                    return Err("offsets must be finite".into());
                }
                let lim = MAX_OFFSET_RADII * self.radius;
                if translate.iter().any(|x| x.abs() > lim) {
                    return Err(format!(
                        "a translation beyond {lim} ({MAX_OFFSET_RADII} scene radii) is refused"
                    ));
                }
            }
            Edit::Light { node: n, intensity } => {
                let n = node(*n)?;
                if !self.lights[n] {
                    return Err(format!("node {n} is not a light"));
                }
                if !(*intensity >= 0.0 && *intensity <= MAX_INTENSITY) {
                    return Err(format!("intensity must be in [0, {MAX_INTENSITY}]"));
                }
            }
            Edit::Material {
                material,
                base_color,
            } => {
                if *material as usize >= self.materials {
                    return Err(format!("no material {material}"));
                }
                if !base_color.iter().all(|c| (0.0..=1.0).contains(c)) {
                    return Err("base_color components must be in [0, 1]".into());
                }
            }
        }
        Ok(())
    }
}

/// The loaded scene and the edits applied to it.
pub struct EditableScene {
    base: SceneDesc,
    anim: Option<AnimationId>,
    camera: CameraChoice,
    width: u32,
    height: u32,
    /// The clip's duration (0 without animation).
    pub duration: f32,
    /// The bounding radius of the scene at load (limits the offsets).
    radius: f32,
    t: f32,
    offsets: Vec<([f32; 3], [f32; 3])>,
    intensity: Vec<f32>,
    base_color: Vec<Rgb>,
    /// Per material: the emission factor last set through a light node that uses it.
    emission: Vec<f32>,
    /// Per node: the emissive materials of its mesh (an area light when not empty).
    emissive_materials: Vec<Vec<usize>>,
}

impl EditableScene {
    /// The scene `base` seen through `camera` at `width`×`height`, clip `anim`, time 0,
    /// and its first frame. Fails when the frame cannot be built (e.g. no such camera).
    pub fn new(
        base: SceneDesc,
        anim: Option<AnimationId>,
        camera: CameraChoice,
        width: u32,
        height: u32,
    ) -> Result<(EditableScene, FrameScene)> {
        let duration = anim.map_or(0.0, |a| base.animations[a.index()].duration());
        let n = base.nodes.len();
        let emissive_materials = base
            .nodes
            .iter()
            .map(|node| {
                let mut ms: Vec<usize> = node
                    .mesh
                    .map(|m| {
                        base.meshes[m.index()]
                            .primitives
                            .iter()
                            .filter_map(|p| p.material)
                            .map(|m| m.index())
                            .filter(|&m| base.materials[m].emissive != Rgb::ZERO)
                            .collect()
                    })
                    .unwrap_or_default();
                ms.sort_unstable();
                ms.dedup();
                ms
            })
            .collect();
        let mut s = EditableScene {
            anim,
            camera,
            width,
            height,
            duration,
            radius: 1.0,
            t: 0.0,
            offsets: vec![([0.0; 3], [0.0; 3]); n],
            intensity: vec![1.0; n],
            base_color: base.materials.iter().map(|m| m.base_color).collect(),
            emission: vec![1.0; base.materials.len()],
            emissive_materials,
            base,
        };
        let frame = s.build()?;
        s.radius = frame.scene_radius.max(1e-6);
        Ok((s, frame))
    }

    /// Whether node `n` is a light: a punctual light or a mesh with emissive materials.
    pub fn is_light(&self, n: usize) -> bool {
        self.base.nodes[n].light.is_some() || !self.emissive_materials[n].is_empty()
    }

    /// The current animation time.
    pub fn time(&self) -> f32 {
        self.t
    }

    /// What edits are checked against.
    pub fn limits(&self) -> Limits {
        Limits {
            nodes: self.base.nodes.len(),
            materials: self.base.materials.len(),
            lights: (0..self.base.nodes.len())
                .map(|n| self.is_light(n))
                .collect(),
            radius: self.radius,
        }
    }

    /// Applies `e` (checked first).
    pub fn apply(&mut self, e: &Edit) -> Result<(), String> {
        self.limits().check(e)?;
        match *e {
            Edit::Time { t } => self.t = t.clamp(0.0, self.duration),
            Edit::Node {
                node,
                translate,
                rotate,
            } => self.offsets[node as usize] = (translate, rotate),
            Edit::Light { node, intensity } => {
                let n = node as usize;
                self.intensity[n] = intensity;
                for &m in &self.emissive_materials[n] {
                    self.emission[m] = intensity;
                }
            }
            Edit::Material {
                material,
                base_color,
            } => self.base_color[material as usize] = Vec3::from_array(base_color),
        }
        Ok(())
    }

    /// The description with the edits applied. A node's offset is applied to its rest
    /// transform and to every key of the clip's channels for it (translation added to the
    /// key values, rotation multiplied onto them from the left; for cubic splines also
    /// the rotation tangents, which are linear in the quaternion), so it holds at every
    /// time of the clip.
    pub fn desc(&self) -> SceneDesc {
        let mut d = self.base.clone();
        for (n, &(t, r)) in self.offsets.iter().enumerate() {
            if t == [0.0; 3] && r == [0.0; 3] {
                continue;
            }
            let dt = Vec3::from_array(t);
            let dr = Quat::from_euler(
                EulerRot::XYZ,
                r[0].to_radians(),
                r[1].to_radians(),
                r[2].to_radians(),
            );
            let tr = &mut d.nodes[n].transform;
            tr.translation += dt;
            tr.rotation = (dr * tr.rotation).normalize();
            if let Some(a) = self.anim {
                for ch in &mut d.animations[a.index()].channels {
                    if ch.node.index() != n {
                        continue;
                    }
                    let c = ch.components;
                    let cubic = ch.interpolation == Interpolation::CubicSpline;
                    let stride = if cubic { 3 * c } else { c };
                    for key in ch.values.chunks_exact_mut(stride) {
                        match ch.target {
                            ChannelTarget::Translation => {
                                let v = if cubic { &mut key[c..2 * c] } else { key };
                                for (x, o) in v.iter_mut().zip(t) {
                                    *x += o;
                                }
                            }
                            ChannelTarget::Rotation => {
                                for q in key.chunks_exact_mut(4) {
                                    let r = dr * Quat::from_xyzw(q[0], q[1], q[2], q[3]);
                                    q.copy_from_slice(&r.to_array());
                                }
                            }
                            ChannelTarget::Scale | ChannelTarget::Weights => {}
                        }
                    }
                }
            }
        }
        for (n, node) in self.base.nodes.iter().enumerate() {
            if let Some(l) = node.light
                && self.intensity[n] != 1.0
            {
                d.lights[l.index()].intensity =
                    self.base.lights[l.index()].intensity * self.intensity[n];
            }
        }
        for (m, mat) in d.materials.iter_mut().enumerate() {
            mat.base_color = self.base_color[m];
            mat.emissive = self.base.materials[m].emissive * self.emission[m];
        }
        d
    }

    /// The frame of the edited scene at the current time. Every node is movable
    /// ([`FrameBuilder::with_movable`]), so frames before and after an edit have the same
    /// instances and differ only where the edit changed something.
    pub fn build(&self) -> Result<FrameScene> {
        let movable = vec![true; self.base.nodes.len()];
        let mut b = FrameBuilder::with_movable(
            Arc::new(self.desc()),
            self.anim,
            self.camera.clone(),
            self.width,
            self.height,
            &movable,
        )?;
        Ok(b.build(self.t))
    }

    /// What the page lists: nodes (with parent, whether a mesh or a light, their
    /// materials), materials (with the current base colour), the clip's duration.
    pub fn info(&self) -> Value {
        let d = &self.base;
        let nodes: Vec<Value> = d
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let materials: Vec<usize> = n
                    .mesh
                    .map(|m| {
                        let mut v: Vec<usize> = d.meshes[m.index()]
                            .primitives
                            .iter()
                            .filter_map(|p| p.material.map(|m| m.index()))
                            .collect();
                        v.sort_unstable();
                        v.dedup();
                        v
                    })
                    .unwrap_or_default();
                json!({
                    "index": i,
                    "name": if n.name.is_empty() { format!("node{i}") } else { n.name.clone() },
                    "parent": n.parent.map(|p| p.index()),
                    "mesh": n.mesh.is_some(),
                    "light": self.is_light(i),
                    "materials": materials,
                    "translate": self.offsets[i].0,
                    "rotate": self.offsets[i].1,
                    "intensity": self.intensity[i],
                })
            })
            .collect();
        let materials: Vec<Value> = d
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| {
                json!({
                    "index": i,
                    "name": if m.name.is_empty() { format!("material{i}") } else { m.name.clone() },
                    "base_color": self.base_color[i].to_array(),
                })
            })
            .collect();
        json!({
            "name": d.name,
            "duration": self.duration,
            "time": self.t,
            "radius": self.radius,
            "width": self.width,
            "height": self.height,
            "nodes": nodes,
            "materials": materials,
        })
    }
}
