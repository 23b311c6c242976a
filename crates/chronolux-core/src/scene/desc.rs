//! `SceneDesc`: a plain, format-independent description of an animated scene.
//!
//! Loaders (glTF in `chronolux-io`, the built-in demo, `testing`) produce it; nothing here
//! knows about BSDF objects or acceleration structures. Every entity has a typed index that
//! is stable for the whole animation (the identity temporal reuse relies on). Topology is
//! fixed over the animation: only node transforms, morph weights (and through them skinned
//! and morphed vertex positions) change with time.

use crate::color::Rgb;
use crate::math::{Mat4, Quat, Vec2, Vec3, Vec4};

macro_rules! typed_id {
    ($($(#[$m:meta])* $name:ident),*) => {$(
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
        pub struct $name(pub u32);
        impl $name {
            #[inline]
            pub fn index(self) -> usize { self.0 as usize }
        }
    )*};
}

typed_id!(
    /// Index into [`SceneDesc::nodes`].
    NodeId,
    /// Index into [`SceneDesc::meshes`].
    MeshId,
    /// Index into [`SceneDesc::materials`].
    MaterialId,
    /// Index into [`SceneDesc::textures`].
    TextureId,
    /// Index into [`SceneDesc::lights`].
    LightId,
    /// Index into [`SceneDesc::cameras`].
    CameraId,
    /// Index into [`SceneDesc::skins`].
    SkinId,
    /// Index into [`SceneDesc::animations`].
    AnimationId
);

/// The warning a loader gives when it adds the default environment to a scene without
/// lights (a stage that brings its own lights removes it again).
pub const DEFAULT_ENVIRONMENT_WARNING: &str = "scene has no light (no punctual light, no emissive material): added a default environment light (white sky above, dim ground below, dark grey background)";

/// The default environment of a scene without lights (see [`DEFAULT_ENVIRONMENT_WARNING`]):
/// a neutral sky-to-ground gradient, radiance 1 straight up and 0.2 straight down, so
/// untextured white models show their shape: L(w) = 0.6 + 0.4·w.y, so an unoccluded face
/// turned up receives E/π = 0.6 + 0.4·2/3 ≈ 0.87, a vertical face 0.6, a face turned down
/// 0.33; seen against a dark grey backdrop (0.05, about 25% grey after the sRGB curve) that
/// no lit white surface matches.
pub fn default_environment() -> crate::light::Environment {
    crate::light::Environment::gradient(Rgb::splat(1.0), Rgb::splat(0.2), Rgb::splat(0.05))
}

/// The whole scene.
#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    /// Human-readable name (file name or demo name).
    pub name: String,
    pub nodes: Vec<Node>,
    /// Nodes of the displayed scene without a parent, in file order.
    pub roots: Vec<NodeId>,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<LightDesc>,
    pub cameras: Vec<CameraDesc>,
    pub skins: Vec<Skin>,
    pub animations: Vec<Animation>,
    /// Environment radiance seen by rays that leave the scene (`None`: black).
    pub environment: Option<crate::light::Environment>,
    /// Messages for the user produced while loading (ignored optional extensions, skipped
    /// degenerate triangles, ...).
    pub warnings: Vec<String>,
}

/// Translation, rotation, scale; the node's local transform is T·R·S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Default for Trs {
    fn default() -> Self {
        Trs {
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        }
    }
}

impl Trs {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// A node of the transform hierarchy.
#[derive(Clone, Debug, Default)]
pub struct Node {
    pub name: String,
    pub parent: Option<NodeId>,
    pub children: Vec<NodeId>,
    /// Rest transform (relative to the parent). A glTF node given by a matrix is
    /// decomposed; a matrix that is not TRS-decomposable is reported by the loader.
    pub transform: Trs,
    pub mesh: Option<MeshId>,
    pub camera: Option<CameraId>,
    pub light: Option<LightId>,
    /// Skin deforming this node's mesh; when set, the node's own transform is ignored for
    /// the mesh (glTF rule) and vertices are placed by the joints.
    pub skin: Option<SkinId>,
    /// Rest morph weights overriding the mesh's default weights (empty: use the mesh's).
    pub weights: Vec<f32>,
}

/// A mesh: one or more primitives sharing morph-target weights.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
    /// Default morph weights (one per target; may be empty when there are no targets).
    pub weights: Vec<f32>,
}

/// Indexed triangles with one material. Vertex attributes are in object space.
#[derive(Clone, Debug, Default)]
pub struct Primitive {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (unit length), if given.
    pub normals: Option<Vec<Vec3>>,
    /// TEXCOORD_0.
    pub uvs: Option<Vec<Vec2>>,
    /// TEXCOORD_1 (used by textures that reference texCoord 1).
    pub uvs1: Option<Vec<Vec2>>,
    /// Tangents with handedness in w, if given.
    pub tangents: Option<Vec<Vec4>>,
    /// Triangles as vertex-index triples; degenerate ones already removed by the loader.
    pub indices: Vec<[u32; 3]>,
    /// `None`: the glTF default material (white, rough dielectric).
    pub material: Option<MaterialId>,
    pub morph_targets: Vec<MorphTarget>,
    /// JOINTS_0: four joint indices (into the skin's joint list) per vertex.
    pub joints: Option<Vec<[u16; 4]>>,
    /// WEIGHTS_0: four weights per vertex.
    pub joint_weights: Option<Vec<Vec4>>,
}

/// Displacements added to the base attributes, scaled by the morph weight.
#[derive(Clone, Debug, Default)]
pub struct MorphTarget {
    pub positions: Option<Vec<Vec3>>,
    pub normals: Option<Vec<Vec3>>,
    pub tangents: Option<Vec<Vec3>>,
}

/// How a texture's texels are to be decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// 8-bit sRGB-encoded colour (base colour, emission).
    Srgb,
    /// Linear data (metallic-roughness, transmission, normal maps).
    Linear,
}

/// Texture addressing outside [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    #[default]
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

/// A decoded 8-bit RGBA image with its sampler settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Row-major RGBA8, first row at the top (v = 0), as glTF's UV convention expects.
    pub rgba8: Vec<[u8; 4]>,
    pub wrap_s: WrapMode,
    pub wrap_t: WrapMode,
    /// Bilinear (true) or nearest filtering for magnification.
    pub bilinear: bool,
}

/// A texture used by a material slot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: TextureId,
    /// 0 = TEXCOORD_0, 1 = TEXCOORD_1.
    pub uv_set: u32,
    /// KHR_texture_transform as a 2×3 affine map applied to the UV (column-major:
    /// `uv' = m[0]*u + m[1]*v + m[2]`); identity when absent.
    pub transform: [Vec2; 3],
}

impl TextureRef {
    pub const IDENTITY_TRANSFORM: [Vec2; 3] = [
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(0.0, 0.0),
    ];

    pub fn new(texture: TextureId, uv_set: u32) -> Self {
        TextureRef {
            texture,
            uv_set,
            transform: Self::IDENTITY_TRANSFORM,
        }
    }
}

/// glTF alpha modes.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum AlphaMode {
    #[default]
    Opaque,
    /// Surface is absent where alpha < cutoff.
    Mask(f32),
    /// Treated as stochastic coverage with probability alpha.
    Blend,
}

/// A glTF metallic-roughness material with the extensions Chronolux supports.
/// Colours are linear. Textures multiply their factors (glTF rule).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear RGB base colour factor.
    pub base_color: Rgb,
    /// Base colour alpha factor.
    pub alpha: f32,
    /// sRGB texture (RGB) with alpha in A.
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    /// Perceptual roughness in [0, 1] (α = roughness²).
    pub roughness: f32,
    /// Linear texture: roughness in G, metallic in B.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Emitted radiance: emissiveFactor × KHR_materials_emissive_strength.
    pub emissive: Rgb,
    /// sRGB texture multiplying `emissive`.
    pub emissive_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    /// KHR_materials_specular `specularFactor` (1 when absent; 0 = no dielectric specular).
    pub specular: f32,
    /// KHR_materials_specular `specularColorFactor` (linear).
    pub specular_color: Rgb,
    /// KHR_materials_transmission factor (0 when absent).
    pub transmission: f32,
    pub transmission_texture: Option<TextureRef>,
    /// KHR_materials_ior (1.5 when absent).
    pub ior: f32,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// KHR_materials_volume: absorption inside the (closed) mesh; `None`: thin-walled or no
    /// absorption.
    pub volume: Option<Volume>,
}

/// A homogeneous absorbing medium inside a transmissive closed mesh (`KHR_materials_volume`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Volume {
    /// Absorption coefficient per world unit, per channel: σ = −ln(attenuationColor) /
    /// attenuationDistance, so white light has the attenuation colour after the attenuation
    /// distance (Beer–Lambert; a zero channel absorbs it completely).
    pub sigma_a: Rgb,
}

impl Volume {
    /// From the extension's `attenuationColor` and `attenuationDistance` (world units,
    /// +∞ for none).
    pub fn from_attenuation(color: Rgb, distance: f32) -> Self {
        let s = |c: f32| {
            if distance.is_infinite() || c >= 1.0 {
                0.0
            } else if c <= 0.0 {
                f32::INFINITY
            } else {
                -c.ln() / distance
            }
        };
        Volume {
            sigma_a: Rgb::new(s(color.x), s(color.y), s(color.z)),
        }
    }

    /// Transmittance exp(−σ·d) along a world-space length `d`.
    pub fn transmittance(&self, d: f32) -> Rgb {
        let t = |s: f32| if s == 0.0 { 1.0 } else { (-s * d).exp() };
        Rgb::new(t(self.sigma_a.x), t(self.sigma_a.y), t(self.sigma_a.z))
    }
}

impl Default for Material {
    /// The glTF default material: white, metallic 1 by glTF's factor defaults is the
    /// default for *specified* materials; a primitive without material uses
    /// [`Material::gltf_default`].
    fn default() -> Self {
        Material {
            name: String::new(),
            base_color: Rgb::ONE,
            alpha: 1.0,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            emissive: Rgb::ZERO,
            emissive_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            specular: 1.0,
            specular_color: Rgb::ONE,
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            volume: None,
        }
    }
}

impl Material {
    /// Material of a primitive with no material: per the glTF spec a default material
    /// (white, metallic 1, roughness 1) — we follow common viewers and render it as a
    /// white rough dielectric (metallic 0) so untextured test assets stay visible.
    pub fn gltf_default() -> Self {
        Material {
            name: "default".into(),
            metallic: 0.0,
            double_sided: true,
            ..Default::default()
        }
    }

    /// A plain Lambertian-looking material: diffuse `albedo`, no specular layer.
    pub fn diffuse(name: &str, albedo: Rgb) -> Self {
        Material {
            name: name.into(),
            base_color: albedo,
            metallic: 0.0,
            roughness: 1.0,
            specular: 0.0,
            double_sided: true,
            ..Default::default()
        }
    }
}

/// KHR_lights_punctual lights, in glTF's photometric units. They sit at their node's origin
/// and point down the node's local −Z.
#[derive(Clone, Debug, PartialEq)]
pub struct LightDesc {
    pub name: String,
    /// Linear RGB colour.
    pub color: Rgb,
    /// Candela for point and spot lights, lux for directional lights.
    pub intensity: f32,
    pub kind: LightKind,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Cone angles in radians from the axis.
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
    Directional,
}

/// A camera; it looks down its node's local −Z with +Y up.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    pub name: String,
    pub projection: Projection,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Vertical field of view in radians; aspect ratio (w/h) if the file fixes it.
    Perspective {
        yfov: f32,
        aspect: Option<f32>,
        znear: f32,
    },
    /// Half-width and half-height of the view volume.
    Orthographic { xmag: f32, ymag: f32 },
}

/// Skinning data.
#[derive(Clone, Debug, Default)]
pub struct Skin {
    pub name: String,
    pub joints: Vec<NodeId>,
    /// One per joint (identity when the file has none).
    pub inverse_bind_matrices: Vec<Mat4>,
}

/// A clip: channels animating node properties over time (seconds).
#[derive(Clone, Debug, Default)]
pub struct Animation {
    pub name: String,
    pub channels: Vec<Channel>,
}

impl Animation {
    /// Largest key time over all channels (0 for an empty clip).
    pub fn duration(&self) -> f32 {
        self.channels
            .iter()
            .filter_map(|c| c.times.last().copied())
            .fold(0.0, f32::max)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelTarget {
    Translation,
    Rotation,
    Scale,
    /// Morph target weights of the node's mesh.
    Weights,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug)]
pub struct Channel {
    pub node: NodeId,
    pub target: ChannelTarget,
    pub interpolation: Interpolation,
    /// Strictly increasing key times in seconds.
    pub times: Vec<f32>,
    /// Key values, flattened: per key `n` components (3 for T/S, 4 for R as x,y,z,w, the
    /// number of morph targets for weights). CUBICSPLINE stores per key
    /// (in-tangent, value, out-tangent), so `3·n` floats per key.
    pub values: Vec<f32>,
    /// Components per value (3, 4 or the morph target count).
    pub components: usize,
}

impl SceneDesc {
    /// Adds a white punctual light of `kind` and `intensity` (candela, or lux for a
    /// directional light) on a new root node `name` placed by `transform` (a light shines
    /// along its node's −Z); returns that node.
    pub fn add_light(
        &mut self,
        name: &str,
        intensity: f32,
        kind: LightKind,
        transform: Trs,
    ) -> NodeId {
        let light = LightId(self.lights.len() as u32);
        self.lights.push(LightDesc {
            name: name.into(),
            color: Rgb::ONE,
            intensity,
            kind,
        });
        self.add_root(Node {
            name: name.into(),
            light: Some(light),
            transform,
            ..Default::default()
        })
    }

    /// Adds a mesh `name` of the one primitive `prim` with `material` on a new root node
    /// `name` placed by `transform`; returns that node.
    pub fn add_mesh(
        &mut self,
        name: &str,
        prim: Primitive,
        material: MaterialId,
        transform: Trs,
    ) -> NodeId {
        let mesh = MeshId(self.meshes.len() as u32);
        self.meshes.push(Mesh {
            name: name.into(),
            primitives: vec![Primitive {
                material: Some(material),
                ..prim
            }],
            weights: Vec::new(),
        });
        self.add_root(Node {
            name: name.into(),
            transform,
            mesh: Some(mesh),
            ..Default::default()
        })
    }

    /// Adds `node` as a new root; returns its id.
    pub fn add_root(&mut self, node: Node) -> NodeId {
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(node);
        self.roots.push(id);
        id
    }

    /// Node ids in an order where every parent precedes its children (roots in order).
    pub fn topological_order(&self) -> Vec<NodeId> {
        let mut out = Vec::with_capacity(self.nodes.len());
        let mut stack: Vec<NodeId> = self.roots.iter().rev().copied().collect();
        while let Some(n) = stack.pop() {
            out.push(n);
            stack.extend(self.nodes[n.index()].children.iter().rev().copied());
        }
        out
    }

    /// Finds an animation by name or decimal index.
    pub fn find_animation(&self, key: &str) -> Option<AnimationId> {
        if let Some(i) = self.animations.iter().position(|a| a.name == key) {
            return Some(AnimationId(i as u32));
        }
        key.parse::<usize>()
            .ok()
            .filter(|&i| i < self.animations.len())
            .map(|i| AnimationId(i as u32))
    }

    /// Total triangle count over mesh instances in the scene.
    pub fn instanced_triangle_count(&self) -> usize {
        self.nodes
            .iter()
            .filter_map(|n| n.mesh)
            .map(|m| {
                self.meshes[m.index()]
                    .primitives
                    .iter()
                    .map(|p| p.indices.len())
                    .sum::<usize>()
            })
            .sum()
    }
}
