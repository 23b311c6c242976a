//! Bidirectional path tracing (Veach 1997, ch. 10; pbrt-v4's `BDPTIntegrator` as the
//! model): a camera subpath and a light subpath per pixel sample, every connection
//! strategy (s, t) — s = 0 (the camera path hits an emitter), s = 1 (light sampling at a
//! camera vertex), t = 1 (light tracing, splatted to the pixel the light vertex projects
//! to), and deterministic connections — weighted by multiple importance sampling (balance
//! or power heuristic) computed with the ratio trick over reversed densities.
//!
//! Delta lights (point, spot, directional), delta BSDF lobes (mirror, smooth glass) and
//! area lights are handled as in pbrt-v4: connections to delta vertices are skipped and
//! the MIS weights exclude the strategies that cannot produce a path.
//!
//! ## Densities through delta vertices (not as in pbrt-v4)
//! A delta lobe's solid-angle density is a Dirac delta; it appears once in every strategy
//! able to produce a path through that vertex (sampled forward by one, backward by the
//! other, equal under reciprocity), so it cancels from the ratios of the MIS weights. The
//! geometry factor `|cos θ| / d²` that converts the *next* vertex's density to area measure
//! does not cancel. pbrt-v4 stores 0 as the delta lobe's density (remapped to 1 in the
//! weights), which drops that factor too: the vertex after a delta vertex gets area
//! density 1 whatever its distance and angle, in both directions. Here the delta lobe's
//! density is 1 and the conversion is kept, so the ratios are those of the true path
//! densities (up to the `η²` of a single refraction, which cancels on a path entering and
//! leaving the same medium). The difference matters where a path has two strategies on
//! either side of a specular chain: the caustic at the foot of the demo's glass sphere
//! (E D S S L: light tracing against the camera path hitting the lamp) and the floor lit
//! through the glass and seen after a diffuse bounce (E S S D D S S L), which carried most
//! of the variance through the sphere (`bench-results/2026-12-02-caustics/`). For the
//! first, the ratio of light tracing's density to the camera path's is, exactly,
//! `p_A(L) p_ω(L→d) cos_D / (p_cam(D) p_ω(D→c) cos_L)`; pbrt-v4's convention multiplies it
//! by `cos_d |D−c|² cos_L / (|L−d|² cos_c cos_D)`, i.e. by the square of the short hop
//! from the sphere to the floor over the long one from the lamp: tens to hundreds of times
//! too small, so the camera path's s = 0 strategy kept weight near 1 for rare, bright
//! paths. The weights still sum to 1 for every path (all strategies derive their ratios
//! from the same stored densities), so the estimator is unbiased either way; the change
//! lowers the variance: the demo's HDR-FLIP at equal samples falls 5–11 % for `bdpt` and
//! `stbpt`, and the default render's relMSE 2.9× (BENCHMARKS.md, "Issue 17: densities
//! through delta vertices").
//!
//! The kernel is three public functions the spatio-temporal technique reuses:
//! [`generate_camera_subpath`], [`generate_light_subpath`] and [`connect::connect`].
//! [`Bdpt`] composes them per pixel sample; [`crate::framework::integrator::render_with_splats`]
//! drives the samples.
//!
//! Sample streams: every number of a sample of pixel p — camera raster, camera subpath,
//! light subpath, connections — comes from that pixel's [`PixelSampler`], in that order.

pub mod caustic;
pub mod connect;
pub mod vertex;

use crate::framework::integrator::{
    Integrator, RenderedFrame, SplattingEstimator, render_with_splats,
};
use chronolux_core::accel::Hit;
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::{Rgb, max_component};
use chronolux_core::geometry::{Ray, spawn_ray};
use chronolux_core::math::Vec2;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::desc::Projection;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;
pub use connect::{
    Connection, Contribution, ViewSplit, connect, connect_with, mis_weight, skip_connect,
    strategy_ratios, view_split,
};
pub use vertex::{Vertex, VertexKind};

/// MIS heuristic over the strategies of a path length.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MisHeuristic {
    Balance,
    /// β = 2 (Veach's recommendation). Default.
    #[default]
    Power,
}

/// Bidirectional path tracer settings.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BdptSettings {
    /// Camera samples, path depth and seed ([`crate::framework::technique::CommonSettings`]). `spp`:
    /// Samples per pixel (each one camera and one light subpath). Default 64. `max_depth`:
    /// Longest path in segments from the camera (Mitsuba's `max_depth`, as for
    /// [`crate::kernels::path::PathSettings`]): strategy (s, t) builds s + t − 1 segments. `None` =
    /// unlimited (Russian roulette ends subpaths). Default `None`. `seed`: Seed of all
    /// sample streams. Default 0.
    #[serde(flatten)]
    pub common: crate::framework::technique::CommonSettings,
    /// Subpath depth (segments from its endpoint) from which Russian roulette may end a
    /// subpath. Default 5.
    pub rr_depth: u32,
    /// MIS heuristic. Default power.
    #[serde(default)]
    pub mis: MisHeuristic,
    /// Use the light-tracing strategies (t = 1: light-subpath vertices connected to the
    /// camera and splatted). Without them the remaining strategies' MIS weights sum to one
    /// on their own (they all sample the first eye vertex from the camera, so the camera's
    /// density cancels from their ratios): what stbpt needs when the camera moves, where a
    /// sample's weights, computed in its own frame, must stay valid in the frames it
    /// serves. Default true.
    #[serde(default = "yes")]
    pub light_tracing: bool,
    /// Only the strategies of unidirectional path tracing: s = 0 (the camera subpath hits
    /// an emitter) and s = 1 (a light sample at each camera vertex, next-event estimation),
    /// with MIS over those two only; no light subpath is traced and there is no light
    /// tracing. The estimator is `path`'s (same walk, same Russian roulette, same power-
    /// heuristic weights between light and BSDF sampling), written with BDPT's vertices so
    /// that stbpt can reuse it across frames (its "path mode"). Default false.
    #[serde(default)]
    pub path_strategies: bool,
    /// Caustics seen through glass ([`caustic`]): photons emitted per frame for the
    /// density estimate of the paths E S⁺ X S⁺ L, whose s = 0 contribution the strategies
    /// then drop; 0 = off (every path by the strategies alone). Only with unlimited depth
    /// (`max_depth = None`; ignored otherwise). Default 0 (off in every preset: on the demo
    /// these paths are not where its fireflies come from, BENCHMARKS.md "Issue 17:
    /// caustics through glass"); 200 000 is the count measured there.
    #[serde(default)]
    pub caustic_photons: u64,
}

fn yes() -> bool {
    true
}

impl Default for BdptSettings {
    fn default() -> Self {
        BdptSettings {
            common: crate::framework::technique::CommonSettings {
                spp: 64,
                max_depth: None,
                seed: 0,
            },
            rr_depth: 5,
            mis: MisHeuristic::Power,
            light_tracing: true,
            path_strategies: false,
            caustic_photons: 0,
        }
    }
}

/// Hard cap on path length when `max_depth` is unlimited (as the path tracer's).
const DEPTH_CAP: u32 = 1024;

impl BdptSettings {
    /// Maximum path length in segments.
    pub fn depth(&self) -> u32 {
        self.common.max_depth.unwrap_or(DEPTH_CAP).min(DEPTH_CAP)
    }

    /// Largest number of light vertices s of a strategy with a light subpath of
    /// `light_len` vertices: 1 (the light sample, no subpath) with
    /// [`BdptSettings::path_strategies`].
    pub fn max_light_vertices(&self, light_len: usize) -> usize {
        if self.path_strategies { 1 } else { light_len }
    }

    /// Whether the caustic photon estimate is on ([`caustic`]): photons requested and the
    /// depth unlimited. When it is, the strategies drop the s = 0 contribution of the
    /// paths E S⁺ X S⁺ L and [`caustic::add_caustics`] must add the photon estimate.
    pub fn caustics(&self) -> bool {
        self.caustic_photons > 0 && self.common.max_depth.is_none()
    }
}

/// Extends `path` (whose last vertex emitted `ray` with solid-angle density `pdf`) by
/// BSDF sampling, adding at most `max_vertices` vertices. Returns nothing; `path` grows.
#[allow(clippy::too_many_arguments)] // reason: the walk's full state, as pbrt's RandomWalk
fn random_walk<T: FnMut(&Ray) -> Option<Hit>>(
    scene: &FrameScene,
    settings: &BdptSettings,
    mut ray: Ray,
    mut beta: Rgb,
    pdf: f32,
    max_vertices: u32,
    mode: TransportMode,
    sampler: &mut PixelSampler,
    path: &mut Vec<Vertex>,
    stats: &mut Stats,
    trace: &mut T,
) {
    if max_vertices == 0 {
        return;
    }
    let mut pdf_fwd = pdf;
    let mut added = 0u32;
    // Product of BSDF weights (Russian roulette), and of η² undoing radiance scaling.
    let mut throughput = Rgb::ONE;
    let mut eta_scale = 1.0f32;
    loop {
        stats.rays += 1;
        let prev = path.last().expect("a walk starts at an endpoint");
        let Some(hit) = trace(&ray) else {
            if mode == TransportMode::Radiance && scene.environment.is_some() {
                let mut v = Vertex::light(
                    scene,
                    scene.environment_light,
                    ray.o + ray.d,
                    chronolux_core::math::Vec3::ZERO,
                    beta,
                    0.0,
                );
                v.infinite = true;
                v.pdf_fwd = pdf_fwd;
                path.push(v);
            }
            return;
        };
        let si = scene.interaction(&hit, &ray);
        let wo = -ray.d.normalize();
        let bsdf = scene.bsdf(&si);
        let mut v = Vertex::surface(si, bsdf, wo, beta);
        v.pdf_fwd = prev.convert_density(pdf_fwd, &v);
        path.push(v);
        added += 1;
        if added >= max_vertices {
            return;
        }
        let u_lobe = sampler.next_1d();
        let u_dir = sampler.next_2d();
        let v = path.last().unwrap();
        let sv = v.surface.as_ref().unwrap();
        let Some(bs) = sv.bsdf.sample(wo, u_lobe, u_dir, mode) else {
            return;
        };
        if bs.weight == Rgb::ZERO {
            return;
        }
        beta *= bs.weight;
        throughput *= bs.weight;
        pdf_fwd = bs.pdf;
        let mut pdf_rev = sv.bsdf.pdf(bs.wi, wo);
        if mode == TransportMode::Radiance && bs.is_transmission {
            eta_scale *= bs.eta * bs.eta;
        }
        let (p, ng) = (sv.si.p, sv.si.ng);
        let n = path.len();
        if bs.is_delta {
            // The delta cancels from the MIS ratios; the next conversion's cos / d² must
            // not (module doc, "Densities through delta vertices").
            path[n - 1].delta = true;
            pdf_fwd = 1.0;
            pdf_rev = 1.0;
        }
        let rev = path[n - 1].convert_density(pdf_rev, &path[n - 2]);
        path[n - 2].pdf_rev = rev;
        ray = spawn_ray(p, ng, bs.wi);
        // The next segment is segment number n of this subpath.
        if n as u32 > settings.rr_depth {
            let q = (max_component(throughput) * eta_scale).min(0.95);
            if sampler.next_1d() >= q {
                return;
            }
            beta /= q;
            throughput /= q;
        }
    }
}

/// Generates the camera subpath of the camera sample at `raster` into `path` (cleared):
/// the camera vertex, then up to `max_depth` surface vertices (or a final vertex at
/// infinity when the ray escapes into an environment).
///
/// ## Estimator contract
/// Vertex 0 is the camera with β = 1 (the pixel measurement's We/pdf for a raster position
/// uniform in the pixel); vertex i's β is the product of BSDF sample weights
/// f·|cos|/pdf (radiance mode) and Russian-roulette factors along the way, so
/// `β_i · (incident radiance at vertex i towards i−1)` estimates the pixel value. Each
/// vertex carries area densities `pdf_fwd`/`pdf_rev` for [`connect::mis_weight`].
/// Draws 3 numbers per bounce (+1 for Russian roulette past `rr_depth`).
pub fn generate_camera_subpath(
    scene: &FrameScene,
    settings: &BdptSettings,
    raster: Vec2,
    sampler: &mut PixelSampler,
    path: &mut Vec<Vertex>,
    stats: &mut Stats,
) {
    generate_camera_subpath_with(scene, settings, raster, sampler, path, stats, &mut |r| {
        scene.intersect(r)
    });
}

/// [`generate_camera_subpath`], answering each ray the walk traces with `trace` instead of
/// `scene.intersect` (which `trace` must equal for this frame), in order: ray `k` leaves
/// vertex `k`; it reached vertex `k + 1` when that is a surface vertex, else it escaped the
/// scene. The sample-reusing technique answers them for every frame of its window at once
/// (one multi-frame query per segment instead of a per-frame trace plus a window check).
pub fn generate_camera_subpath_with<T: FnMut(&Ray) -> Option<Hit>>(
    scene: &FrameScene,
    settings: &BdptSettings,
    raster: Vec2,
    sampler: &mut PixelSampler,
    path: &mut Vec<Vertex>,
    stats: &mut Stats,
    trace: &mut T,
) {
    path.clear();
    let max_depth = settings.depth();
    if max_depth == 0 {
        return;
    }
    let cam = &scene.camera;
    let ray = cam.generate_ray(raster);
    let ortho = matches!(cam.projection(), Projection::Orthographic { .. });
    let (_, pdf_dir) = cam.pdf_we(ray.d);
    path.push(Vertex::camera(ray.o, Rgb::ONE, ortho));
    random_walk(
        scene,
        settings,
        ray,
        Rgb::ONE,
        pdf_dir,
        max_depth,
        TransportMode::Radiance,
        sampler,
        path,
        stats,
        trace,
    );
}

/// Generates a light subpath into `path` (cleared): a light chosen in proportion to power,
/// a ray from [`Light::sample_le`](chronolux_core::light::Light::sample_le), then up to `max_depth − 1` surface vertices traced in
/// importance mode (the BSDF applies the adjoint shading-normal correction).
///
/// ## Estimator contract
/// Vertex 0 is on the light with β = Le (textured) and `pdf_fwd = pmf · pdf_pos` (pbrt's
/// convention for lights at infinity: see [`vertex`]); vertex i ≥ 1 has
/// β = Le·|cos|/(pmf·pdf_pos·pdf_dir) times BSDF weights and Russian-roulette factors, so
/// β_i is the flux-like weight of a particle arriving at vertex i. Always draws 5 numbers
/// (light choice, position, direction), then 3 per bounce (+1 past `rr_depth`).
pub fn generate_light_subpath(
    scene: &FrameScene,
    settings: &BdptSettings,
    sampler: &mut PixelSampler,
    path: &mut Vec<Vertex>,
    stats: &mut Stats,
) {
    generate_light_subpath_with(scene, settings, sampler, path, stats, &mut |r| {
        scene.intersect(r)
    });
}

/// [`generate_light_subpath`], answering the traced rays with `trace`, as
/// [`generate_camera_subpath_with`] does.
pub fn generate_light_subpath_with<T: FnMut(&Ray) -> Option<Hit>>(
    scene: &FrameScene,
    settings: &BdptSettings,
    sampler: &mut PixelSampler,
    path: &mut Vec<Vertex>,
    stats: &mut Stats,
    trace: &mut T,
) {
    path.clear();
    let u_light = sampler.next_1d();
    let u_pos = sampler.next_2d();
    let u_dir = sampler.next_2d();
    let max_depth = settings.depth();
    if max_depth == 0 {
        return;
    }
    let Some((li, pmf, _)) = scene.light_sampler.sample(u_light) else {
        return;
    };
    if pmf <= 0.0 {
        return;
    }
    let light = &scene.lights[li];
    let (center, radius) = scene.bounds.bounding_sphere();
    let Some(les) = light.sample_le(u_pos, u_dir, center, radius) else {
        return;
    };
    if les.pdf_pos <= 0.0 || les.pdf_dir <= 0.0 {
        return;
    }
    let le = vertex::light_emission(scene, light, les.le, les.ray.o);
    if le == Rgb::ZERO {
        return;
    }
    let v0 = Vertex::light(scene, Some(li), les.ray.o, les.n, le, les.pdf_pos * pmf);
    let infinite = v0.infinite;
    path.push(v0);
    let cos = if les.n == chronolux_core::math::Vec3::ZERO {
        1.0
    } else {
        les.n.dot(les.ray.d).abs()
    };
    let beta = le * (cos / (pmf * les.pdf_pos * les.pdf_dir));
    random_walk(
        scene,
        settings,
        les.ray,
        beta,
        les.pdf_dir,
        max_depth - 1,
        TransportMode::Importance,
        sampler,
        path,
        stats,
        trace,
    );
    if infinite {
        if path.len() > 1 {
            let mut p = les.pdf_pos;
            if path[1].is_on_surface() {
                p *= path[1].ng.dot(les.ray.d).abs();
            }
            path[1].pdf_fwd = p;
        }
        path[0].pdf_fwd = vertex::infinite_light_density(scene, -les.ray.d);
    }
}

/// Bidirectional path tracer.
#[derive(Clone, Debug, Default)]
pub struct Bdpt {
    pub settings: BdptSettings,
}

impl Bdpt {
    pub fn new(settings: BdptSettings) -> Self {
        Bdpt { settings }
    }
}

thread_local! {
    static PATHS: std::cell::RefCell<(Vec<Vertex>, Vec<Vertex>)> =
        const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

impl SplattingEstimator for Bdpt {
    fn sample(
        &self,
        scene: &FrameScene,
        raster: Vec2,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
        splats: &mut Vec<(Vec2, Rgb)>,
    ) -> Rgb {
        PATHS.with_borrow_mut(|(camera, light)| {
            let s = &self.settings;
            generate_camera_subpath(scene, s, raster, sampler, camera, stats);
            if s.path_strategies {
                light.clear();
            } else {
                generate_light_subpath(scene, s, sampler, light, stats);
            }
            let max_segments = s.depth() as usize;
            let mut l = Rgb::ZERO;
            for t in 1..=camera.len() {
                for s_ in 0..=s.max_light_vertices(light.len()) {
                    // t = 1 is light tracing: never with s = 1, and only when enabled.
                    if (t == 1 && (s_ == 1 || !self.settings.light_tracing))
                        || s_ + t < 2
                        || s_ + t - 1 > max_segments
                    {
                        continue;
                    }
                    if let Some(c) = connect(scene, s, light, camera, s_, t, sampler, stats) {
                        match c.raster {
                            Some(r) => splats.push((r, c.l)),
                            None => l += c.l,
                        }
                    }
                }
            }
            l
        })
    }
}

impl Integrator for Bdpt {
    fn render(
        &self,
        scene: &FrameScene,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let mut f = render_with_splats(
            self,
            scene,
            frame,
            self.settings.common.spp,
            self.settings.common.seed,
            progress,
        );
        caustic::add_caustics(&mut f, scene, &self.settings);
        f
    }

    fn batch(&self, spp: u32, round: u32, half: u32) -> Option<Box<dyn Integrator + Send>> {
        let mut settings = self.settings.clone();
        settings.common.spp = spp;
        settings.common.seed =
            crate::framework::sequence::batch_seed(settings.common.seed, round, half);
        Some(Box::new(Bdpt::new(settings)))
    }
}

impl crate::framework::shutter::ShutterIntegrator for Bdpt {
    const NAME: &'static str = "bdpt";
    fn spp(&self) -> u32 {
        self.settings.common.spp
    }
    fn render_shutter(
        &self,
        scenes: &[FrameScene],
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        // The caustic photon pass needs one scene (crate::kernels::bdpt::caustic, "Limits"): with
        // a shutter, BDPT keeps its own estimate of every path.
        let plain = Bdpt::new(BdptSettings {
            caustic_photons: 0,
            ..self.settings.clone()
        });
        let s = &plain.settings;
        crate::framework::shutter::render_with_splats_time_sampled(
            &plain,
            scenes,
            frame,
            s.common.spp,
            s.common.seed,
            progress,
        )
    }
}
