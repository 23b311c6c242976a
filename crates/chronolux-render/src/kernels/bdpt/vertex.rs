//! Path vertices of bidirectional estimators and the densities between them (pbrt-v4's
//! `Vertex`, with the same conventions).
//!
//! ## Density conventions
//! - `pdf_fwd` is the density with which the subpath's own sampling produced this vertex,
//!   `pdf_rev` the density with which the *other* direction would produce it; both w.r.t.
//!   **area** at the vertex (solid angle for vertices at infinity), 0 after a delta
//!   (specular) sample, which the MIS weights treat as "strategy impossible".
//! - A light vertex's `pdf_fwd` is `pmf(light) · pdf_pos`; for lights at infinity
//!   (directional, environment) it is the directional density `Σ pmf · pdf_li`, and the
//!   following vertex carries the disk position density `pdf_pos · |cos|` instead (pbrt's
//!   convention, so that `sample_le` and `sample_li` strategies compare like with like).

use chronolux_core::bsdf::{Bsdf, TransportMode};
use chronolux_core::color::Rgb;
use chronolux_core::geometry::spawn_ray_to;
use chronolux_core::light::Light;
use chronolux_core::math::Vec3;
use chronolux_core::scene::desc::Projection;
use chronolux_core::scene::frame::{FrameScene, SurfaceInteraction};
use chronolux_core::stats::Stats;

/// What a vertex is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    Camera,
    /// An endpoint on a light: the first vertex of a light subpath, a light sampled for the
    /// s = 1 strategy, or the point at infinity of a camera ray that escaped the scene.
    Light,
    Surface,
}

/// Surface data of a [`VertexKind::Surface`] vertex.
#[derive(Clone, Debug)]
pub struct SurfaceVertex {
    pub si: SurfaceInteraction,
    pub bsdf: Bsdf,
    /// Unit direction towards the previous vertex of the subpath.
    pub wo: Vec3,
}

/// One vertex of a camera or light subpath.
#[derive(Clone, Debug)]
pub struct Vertex {
    pub kind: VertexKind,
    pub p: Vec3,
    /// Geometric normal; zero for vertices not on a surface (camera, punctual lights,
    /// points at infinity).
    pub ng: Vec3,
    /// Normal of the cosine factors: the BSDF's shading normal at surfaces, the emitting
    /// side's normal on area lights, zero elsewhere.
    pub ns: Vec3,
    /// Subpath throughput up to and including this vertex: importance/pdf from the camera
    /// (camera subpaths) or emitted power/pdf (light subpaths).
    pub beta: Rgb,
    pub pdf_fwd: f32,
    pub pdf_rev: f32,
    /// The subpath left this vertex by sampling a delta lobe (or the camera is orthographic).
    pub delta: bool,
    /// Index in [`FrameScene::lights`] of a light vertex (`None` for an escaped camera ray
    /// when the scene has no environment light).
    pub light: Option<usize>,
    /// A light vertex at infinity (directional, environment, escaped camera ray).
    pub infinite: bool,
    pub surface: Option<SurfaceVertex>,
}

impl Vertex {
    /// The camera endpoint; `delta` for cameras with a delta direction (orthographic).
    pub fn camera(p: Vec3, beta: Rgb, delta: bool) -> Self {
        Vertex {
            kind: VertexKind::Camera,
            p,
            ng: Vec3::ZERO,
            ns: Vec3::ZERO,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta,
            light: None,
            infinite: false,
            surface: None,
        }
    }

    /// A light endpoint at `p` with normal `n` (zero off surfaces).
    pub fn light(
        scene: &FrameScene,
        light: Option<usize>,
        p: Vec3,
        n: Vec3,
        beta: Rgb,
        pdf_fwd: f32,
    ) -> Self {
        let infinite = light.is_none_or(|l| {
            matches!(
                scene.lights[l],
                Light::Directional { .. } | Light::Environment { .. }
            )
        });
        Vertex {
            kind: VertexKind::Light,
            p,
            ng: n,
            ns: n,
            beta,
            pdf_fwd,
            pdf_rev: 0.0,
            delta: false,
            light,
            infinite,
            surface: None,
        }
    }

    /// A surface vertex (`pdf_fwd` set by the caller once the vertex exists).
    pub fn surface(si: SurfaceInteraction, bsdf: Bsdf, wo: Vec3, beta: Rgb) -> Self {
        Vertex {
            kind: VertexKind::Surface,
            p: si.p,
            ng: si.ng,
            ns: bsdf.frame.n,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            light: None,
            infinite: false,
            surface: Some(SurfaceVertex { si, bsdf, wo }),
        }
    }

    #[inline]
    pub fn is_on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    /// Light index of this vertex if it emits: a light endpoint, or a surface on an
    /// emissive triangle that is one of the scene's lights.
    pub fn light_index(&self, scene: &FrameScene) -> Option<usize> {
        match self.kind {
            VertexKind::Light => self.light,
            VertexKind::Surface => scene.light_of(self.surface.as_ref()?.si.tri),
            VertexKind::Camera => None,
        }
    }

    /// Whether the vertex emits light (is an endpoint of the s = 0 strategy).
    pub fn is_light(&self, scene: &FrameScene) -> bool {
        match self.kind {
            VertexKind::Light => true,
            _ => self.light_index(scene).is_some(),
        }
    }

    /// A light endpoint whose position or direction is a delta distribution.
    pub fn is_delta_light(&self, scene: &FrameScene) -> bool {
        self.kind == VertexKind::Light && self.light.is_some_and(|l| scene.lights[l].is_delta())
    }

    /// Whether a deterministic connection to this vertex can carry light: not through a
    /// purely specular BSDF, not to a directional light, not to an orthographic camera.
    pub fn is_connectible(&self, scene: &FrameScene) -> bool {
        match self.kind {
            VertexKind::Camera => {
                matches!(scene.camera.projection(), Projection::Perspective { .. })
            }
            VertexKind::Light => self
                .light
                .is_some_and(|l| !matches!(scene.lights[l], Light::Directional { .. })),
            VertexKind::Surface => self
                .surface
                .as_ref()
                .is_some_and(|s| s.bsdf.has_non_delta()),
        }
    }

    /// BSDF value (no cosine) for the path continuing from this vertex towards `next`.
    pub fn f(&self, next: &Vertex, mode: TransportMode) -> Rgb {
        let Some(s) = &self.surface else {
            return Rgb::ZERO;
        };
        let wi = (next.p - self.p).normalize_or_zero();
        if wi == Vec3::ZERO {
            return Rgb::ZERO;
        }
        s.bsdf.f(s.wo, wi, mode)
    }

    /// Converts a solid-angle density at this vertex of sampling `next` to an area density
    /// at `next` (unchanged when `next` is at infinity).
    pub fn convert_density(&self, pdf: f32, next: &Vertex) -> f32 {
        if next.infinite && next.kind == VertexKind::Light {
            return pdf;
        }
        let w = next.p - self.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let inv = 1.0 / d2;
        let mut pdf = pdf * inv;
        if next.is_on_surface() {
            pdf *= next.ng.dot(w * inv.sqrt()).abs();
        }
        pdf
    }

    /// Area density with which a subpath arriving at this vertex from `prev` continues to
    /// `next` (pbrt-v4 `Vertex::PDF`). `prev` is required for surface vertices.
    pub fn pdf(&self, scene: &FrameScene, prev: Option<&Vertex>, next: &Vertex) -> f32 {
        let wn = (next.p - self.p).normalize_or_zero();
        if wn == Vec3::ZERO {
            return 0.0;
        }
        let pdf = match self.kind {
            VertexKind::Light => return self.pdf_light(scene, next),
            VertexKind::Camera => scene.camera.pdf_we(wn).1,
            VertexKind::Surface => {
                let (Some(s), Some(prev)) = (&self.surface, prev) else {
                    return 0.0;
                };
                let wp = (prev.p - self.p).normalize_or_zero();
                s.bsdf.pdf(wp, wn)
            }
        };
        self.convert_density(pdf, next)
    }

    /// Area density at `v` of a ray emitted by this light vertex towards it
    /// (`sample_le`'s direction density, or the disk density for lights at infinity).
    pub fn pdf_light(&self, scene: &FrameScene, v: &Vertex) -> f32 {
        let w = v.p - self.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let w = w / d2.sqrt();
        let (_, radius) = scene.bounds.bounding_sphere();
        let mut pdf = if self.infinite {
            let r = radius.max(1e-4);
            1.0 / (std::f32::consts::PI * r * r)
        } else {
            let Some(l) = self.light_index(scene) else {
                return 0.0;
            };
            let n = if self.kind == VertexKind::Surface {
                self.ng
            } else {
                self.ns
            };
            scene.lights[l].pdf_le(w, n, radius).1 / d2
        };
        if v.is_on_surface() {
            pdf *= v.ng.dot(w).abs();
        }
        pdf
    }

    /// Density of this light vertex as the origin of a light subpath (light choice times
    /// position density; the directional density for lights at infinity).
    pub fn pdf_light_origin(&self, scene: &FrameScene, v: &Vertex) -> f32 {
        if self.infinite {
            // Towards the environment: from `v` to this vertex (far along the direction).
            return infinite_light_density(scene, (self.p - v.p).normalize_or_zero());
        }
        let Some(l) = self.light_index(scene) else {
            return 0.0;
        };
        let w = (v.p - self.p).normalize_or_zero();
        let (_, radius) = scene.bounds.bounding_sphere();
        let (pdf_pos, _) = scene.lights[l].pdf_le(w, self.ng, radius);
        scene.light_sampler.pmf(l) * pdf_pos
    }

    /// Radiance emitted from this vertex towards `v` (zero unless it is a light).
    pub fn le(&self, scene: &FrameScene, v: &Vertex) -> Rgb {
        let w = (v.p - self.p).normalize_or_zero();
        match self.kind {
            // At infinity: the environment seen along −w; straight from the camera, the
            // backdrop (only the camera strategy sees it: no light subpath reaches a camera
            // vertex from infinity).
            VertexKind::Light if self.infinite => {
                scene.environment.as_ref().map_or(Rgb::ZERO, |e| {
                    if v.kind == VertexKind::Camera {
                        e.seen_by_camera(-w)
                    } else {
                        e.radiance(-w)
                    }
                })
            }
            VertexKind::Surface => {
                if self.light_index(scene).is_none() {
                    return Rgb::ZERO;
                }
                scene.emitted(&self.surface.as_ref().unwrap().si, w)
            }
            _ => Rgb::ZERO,
        }
    }
}

/// Solid-angle density (times light choice) with which light sampling produces the
/// direction `w` towards the lights at infinity: only the environment has one (uniform,
/// or by its map's luminance; directional lights are deltas).
pub fn infinite_light_density(scene: &FrameScene, w: Vec3) -> f32 {
    match (scene.environment_light, &scene.environment) {
        (Some(ei), Some(env)) => scene.light_sampler.pmf(ei) * env.pdf_dir(w),
        _ => 0.0,
    }
}

/// Geometry term between two vertices, with visibility: |cos|·|cos|/d² (cosines only at
/// surface vertices, shading normals as the BSDF's frame).
/// `visible` answers the shadow ray.
pub fn g(
    v0: &Vertex,
    v1: &Vertex,
    stats: &mut Stats,
    visible: &mut dyn FnMut(&chronolux_core::geometry::Ray) -> bool,
) -> f32 {
    let d = v0.p - v1.p;
    let d2 = d.length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    let mut g = 1.0 / d2;
    let d = d * g.sqrt();
    if v0.is_on_surface() {
        g *= v0.ns.dot(d).abs();
    }
    if v1.is_on_surface() {
        g *= v1.ns.dot(d).abs();
    }
    if g == 0.0 {
        return 0.0;
    }
    stats.shadow_rays += 1;
    if visible(&spawn_ray_to(v0.p, v0.ng, v1.p, v1.ng)) {
        g
    } else {
        0.0
    }
}

/// Emitted radiance of a light sampled by `sample_li` at barycentrics `bary` (the shared
/// [`crate::kernels::direct::light_radiance`]).
pub use crate::kernels::direct::light_radiance as light_emission_bary;
/// Emitted radiance of a light at a point of it (the shared
/// [`crate::kernels::direct::light_radiance_at`]).
pub use crate::kernels::direct::light_radiance_at as light_emission;
