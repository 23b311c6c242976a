//! What changed between two versions of a scene, as the pilots need it.
//!
//! **Stand-in, to be replaced by `chronolux_core::scene::delta::FrameDelta`** (being
//! written on the `delta` branch; not on `main` when this was written). Same ids and the
//! same meaning as its documented API (`instance_changed`, `light_changed`,
//! `material_changed`, `is_static`): instances are indices into `accel.instances()`
//! (stable across frames of one builder), lights into `FrameScene::lights`, materials into
//! `FrameScene::materials`. Instances and geometry are compared exactly (bitwise
//! transforms, vertex data unless the same `Arc`); lights and materials, which have no
//! `PartialEq` on `main`, by their `Debug` text (which prints every `f32` in its shortest
//! round-trip form, so equal text ⇔ equal values) — the one part FrameDelta does better.

use chronolux_core::scene::frame::FrameScene;
use std::sync::Arc;

/// Per instance / light / material: changed between two scenes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SceneChanges {
    instances: Vec<bool>,
    lights: Vec<bool>,
    materials: Vec<bool>,
    camera: bool,
}

impl SceneChanges {
    /// What differs between `a` and `b` (ids present in only one are changed).
    pub fn between(a: &FrameScene, b: &FrameScene) -> SceneChanges {
        let (ia, ib) = (a.accel.instances(), b.accel.instances());
        let mut instances: Vec<bool> = (0..ia.len().max(ib.len()))
            .map(|i| match (ia.get(i), ib.get(i)) {
                (Some(x), Some(y)) => {
                    x.world_from_object != y.world_from_object || x.geometry_base != y.geometry_base
                }
                _ => true,
            })
            .collect();
        for g in 0..a.geometry.len().max(b.geometry.len()) {
            let same = match (a.geometry.get(g), b.geometry.get(g)) {
                (Some(x), Some(y)) => {
                    (Arc::ptr_eq(&x.positions, &y.positions) || x.positions == y.positions)
                        && (Arc::ptr_eq(&x.indices, &y.indices) || x.indices == y.indices)
                        && x.material == y.material
                }
                _ => false,
            };
            if !same {
                for s in [a, b] {
                    if let Some(&i) = s.geometry_instance.get(g)
                        && let Some(slot) = instances.get_mut(i as usize)
                    {
                        *slot = true;
                    }
                }
            }
        }
        let bounds_changed = a.bounds != b.bounds;
        let lights = (0..a.lights.len().max(b.lights.len()))
            .map(|l| match (a.lights.get(l), b.lights.get(l)) {
                (Some(x), Some(y)) => {
                    let infinite = matches!(
                        x,
                        chronolux_core::light::Light::Directional { .. }
                            | chronolux_core::light::Light::Environment { .. }
                    );
                    format!("{x:?}") != format!("{y:?}")
                        || (infinite && bounds_changed)
                        || a.light_sampler.pmf(l) != b.light_sampler.pmf(l)
                }
                _ => true,
            })
            .collect();
        let materials = (0..a.materials.len().max(b.materials.len()))
            .map(|m| match (a.materials.get(m), b.materials.get(m)) {
                (Some(x), Some(y)) => format!("{x:?}") != format!("{y:?}"),
                _ => true,
            })
            .collect();
        SceneChanges {
            instances,
            lights,
            materials,
            camera: format!("{:?}", a.camera) != format!("{:?}", b.camera),
        }
    }

    /// Instance `i` moved or was deformed (out of range: changed).
    pub fn instance_changed(&self, i: usize) -> bool {
        self.instances.get(i).copied().unwrap_or(true)
    }

    /// Light `l` changed (its value, its selection probability, or for a light at
    /// infinity the scene bounds its emission depends on).
    pub fn light_changed(&self, l: usize) -> bool {
        self.lights.get(l).copied().unwrap_or(true)
    }

    /// Material `m` changed.
    pub fn material_changed(&self, m: usize) -> bool {
        self.materials.get(m).copied().unwrap_or(true)
    }

    /// The camera changed.
    pub fn camera_changed(&self) -> bool {
        self.camera
    }

    /// Nothing that photons see changed (the camera does not matter to them).
    pub fn is_static(&self) -> bool {
        !(self.instances.iter().any(|&c| c)
            || self.lights.iter().any(|&c| c)
            || self.materials.iter().any(|&c| c))
    }
}
