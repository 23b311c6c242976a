//! Spatio-temporal bidirectional path tracing (Havran, Damez, Myszkowski, Seidel, "An
//! efficient spatio-temporal architecture for animation rendering", EGSR 2003): every
//! bidirectional sample made for a pixel of frame f also serves the frames g of the
//! centred window [f − K, f + K], at the pixel through which its first eye vertex is seen
//! in g.
//!
//! # Per sample (generated once, in frame f)
//!
//! A BDPT sample as [`crate::bdpt`] makes it (camera subpath, light subpath, every
//! strategy (s, t) with MIS), from three streams of its own keyed by (seed, f, pixel,
//! sample index): camera, light and connection numbers. Separate streams let a sample be
//! re-traced in another frame with a camera subpath of a different length without the
//! light subpath or the light samples reusing numbers the camera subpath consumed.
//!
//! Recorded: the first eye vertex x1 (a surface point: geometry id, triangle and
//! barycentrics through the instance that carries it — never a pixel), every ray the two
//! subpaths traced, and the **shading split** (item 4): the t ≥ 2 contributions are
//! written `f(x1, wo, wi_k) ⊙ R_k` with `R_k` holding everything but x1's BSDF value for
//! the view direction `wo` — the NEE and light-vertex connections at x1 (t = 2, `wi_k`
//! towards the light point), and each strategy with t ≥ 3 (they all share x1's sampled
//! continuation `wi`: `R = c ⊘ f(wo_f, wi)`, i.e. the incident radiance estimate times
//! |cos|/pdf and its MIS weight). x1's own emission (s = 0, t = 2) is kept as its MIS
//! weight, the emitted radiance being re-evaluated towards the new view. Directions are
//! kept in world space: reuse happens only while x1's object does not move, when x1's
//! shading frame is the same in f and g, so world and local directions are equivalent.
//!
//! # Reuse in frame g
//!
//! 1. **Landing.** x1 in g (same triangle and barycentrics on g's geometry: motion
//!    compensated) is projected into g's camera; it lands in g iff it is on screen, faces
//!    g's camera from the same side as f's, and nothing in g occludes it. Samples whose
//!    camera ray escaped land where their direction projects in g. A sample that does not
//!    land does not serve g's camera part (it still serves g's light tracing, below).
//! 2. **Reuse** (the view-dependent part only) when everything the split depends on is
//!    reproduced in g: x1's instance has the same placement in f and g, the sample
//!    continued from x1 by a non-delta lobe, x1 is not near-specular (GGX α < 0.1) while
//!    the camera moved (the continuation, sampled for f's view, would not cover g's lobe),
//!    materials and lights are the same, and every segment the subpaths sampled beyond x1
//!    — camera segments after x1, all light segments, escape rays included — gives the
//!    same hit in g as in f according to [`MultiFrameAccel::intersect_window`] (the
//!    module's "Use for sample reuse"). Shadow rays of the connections are not a validity
//!    condition: [`MultiFrameAccel::occluded_window`] answers them for every frame at
//!    generation, and an occluded connection contributes 0 in that frame. The value in g
//!    is `Le(x1 → wo_g)·w_e + Σ_k V_k(g) f(x1, wo_g, wi_k) ⊙ R_k`: only x1's BSDF and
//!    emission are re-evaluated.
//!    **Partial reuse** when only the light subpath is invalid in g (x1 and every camera
//!    segment reproduced, same lights and materials): the strategies without light-subpath
//!    vertices (s ≤ 1: emission, NEE, camera paths hitting a light) are reused as above,
//!    and the strategies s ≥ 2 are recomputed in g's scene by connecting f's camera
//!    subpath (which is g's walk too) to the light subpath regenerated in g, split at x1
//!    the same way. Each strategy's weighted contribution is an unbiased estimate of its
//!    share on its own, so mixing f's s ≤ 1 terms with g's s ≥ 2 terms is unbiased.
//! 3. **Re-trace** otherwise: a fresh BDPT evaluation in g's scene, of the same streams,
//!    for a camera ray through the raster position where x1 landed. A sample invalid for
//!    g never contributes a stale value; re-tracing (instead of dropping) keeps the
//!    samples landing in a pixel independent of where geometry changed, so changed regions
//!    are not under-sampled relative to static ones.
//! 4. **Light tracing** (t = 1): every light subpath of the window serves g: reused when
//!    its segments are reproduced in g and the lights are the same, otherwise re-generated
//!    in g from the same light stream; its vertices are connected to g's camera and
//!    splatted. When g's camera is f's and the light subpath is reused, the connections
//!    are the same too: f's splats are reused, each where its shadow ray (answered for
//!    the window at generation) is unoccluded in g. Frame g's splats are scaled by
//!    1 / (spp × frames of g's window).
//!
//! # Cost
//!
//! Both subpaths are traced through the window structure itself
//! ([`MultiFrameAccel::intersect_window`], whose answer for f equals f's own query), so each
//! segment's validity over the window costs no second traversal. x1's landing visibility
//! is one [`MultiFrameAccel::occluded_window`] query for every frame in which x1 and the
//! eye are where they were in f (static object, static camera position), one ray per
//! frame otherwise.
//!
//! Pixel value of g: Σ values / Σ landed samples per pixel ([`WindowFilm`]), plus the
//! scaled splats.
//!
//! # Bias
//!
//! Each landed sample is an unbiased estimate of the radiance through the raster position
//! it landed at (re-traced ones trivially; reused ones because f's continuation density
//! is the density the sample was drawn with — `f(wo_g, wi)/pdf_f(wi)` is an ordinary
//! importance-sampling weight wherever `pdf_f > 0`, which holds for the non-delta,
//! non-near-specular lobes reuse is restricted to). The pixel value is the mean over the
//! samples that landed, so it estimates the radiance averaged over the pixel with the
//! *landing density* instead of the uniform box filter. That density is uniform (the
//! frame-f density moved by a smooth map) except where landing is interrupted: points
//! hidden in g, disocclusions (nothing lands where f could not see) and image borders.
//! The estimator is therefore **consistently biased**: the bias is confined to pixels
//! containing such an edge and vanishes as the number of samples grows only in the
//! sense that the estimate converges to a slightly different filter of the image there;
//! on static animations (and everywhere else) the landing density is uniform and the
//! result is unbiased.
//!
//! MIS weights are those computed in f. They are the weights of the densities the sample
//! was drawn with (f's camera sampled x1, f's view sampled the continuation), and the
//! strategies t ≥ 2 and t = 1 partition each path's contribution exactly when g's camera
//! samples x1 with f's density, i.e. whenever the camera does not move between f and g.
//! **Deviation:** with a moving camera the t = 1 weights (computed with g's camera) and
//! the kept t ≥ 2 weights (f's camera) no longer sum exactly to one; the error is the
//! change in the light-tracing weight between the two views, small where light tracing
//! carries little (it is largest on caustics seen directly).
//!
//! # Motion blur (`shutter` > 0)
//!
//! Every landing also records where the point it shows is seen one frame before and one
//! after (the sample's x1 moved with its object into those frames and projected by their
//! cameras, visible or not; an escaped ray's direction for the background), and its value
//! there when that landing shows the same point (own frame or reuse; a re-traced landing
//! may show another point, so its radiance is not interpolated). Per pixel of frame g the
//! films keep the means of these over the landed samples; when g is finished, each pixel's
//! value is spread over the pixels its trajectory crosses during the shutter
//! ([`splat_trajectory`], 2D DDA, weight ∝ time ∝ length at constant speed), positions and
//! radiance linear in time between frames. **Deviation from a per-sample splat:** the
//! trajectory is splatted per pixel of the reconstructed frame, not per sample, because
//! a landed sample's share of its pixel (1 / samples landed there) is known only when the
//! window is complete; splatting each sample as it lands would weight pixels by landing
//! density (which doubles where the scene's motion brings samples of two frames onto the
//! same point). Consequences: a pixel showing two differently moving surfaces spreads its
//! mean along their mean trajectory; only points visible at the frame instant are spread,
//! so background revealed during the shutter is missing from the blur (as in the paper);
//! light-tracing splats are not blurred. Needs K ≥ 1 (the neighbouring frames); at the
//! ends of the render list the trajectory is extrapolated from the frame on the other
//! side. Test: a quad moving at constant speed against the analytic box⊗box blur
//! (`tests/it/blur.rs`).
//!
//! # Memory
//!
//! Samples are not stored: each is made, landed in every frame of its window and
//! dropped. What stays is the open frames' films (value, square, splat, and four motion
//! films with motion blur) in [`WindowFilm`]s sharing `film_budget_mb` (tiles beyond it go
//! to a disk cache), the 2K + 2 scenes of the frame source, and one batch of
//! `TILES_PER_BATCH` tiles of contributions: bounded whatever the resolution and frame
//! count.
//!
//! Orthographic cameras: samples serve only their own frame (the landing test needs a
//! pinhole). The window holds at most [`MAX_WINDOW_FRAMES`] frames (K ≤ 31).

use crate::bdpt::{
    BdptSettings, Vertex, VertexKind, connect, connect_with, generate_camera_subpath,
    generate_camera_subpath_with, generate_light_subpath, generate_light_subpath_with, mis_weight,
};
use crate::integrator::{RenderedFrame, TILE, tile_rect};
use crate::sequence::{ReuseStats, SequenceRenderer};
use crate::temporal::blur::{TrajectoryVertex, splat_trajectory};
use crate::temporal::window_film::{Contribution, FilmStats, WindowFilm};
use chronolux_core::accel::Hit;
use chronolux_core::accel::multi_frame::{
    FrameMask, MAX_WINDOW_FRAMES, MultiFrameAccel, WindowHit,
};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::{Ray, spawn_ray_to};
use chronolux_core::light::Light;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::desc::Projection;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use chronolux_core::stats::Stats;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Settings of [`Stbpt`].
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StbptSettings {
    /// The per-sample estimator (samples per pixel generated per frame, depth, MIS, seed).
    pub bdpt: BdptSettings,
    /// Half-width K of the window [f − K, f + K] a sample serves (0 = frame by frame).
    /// Default 4.
    /// At most 31.
    pub window: u32,
    /// Motion blur: fraction of the frame interval the shutter is open, centred on the
    /// frame time (0 = off). Each landed sample's trajectory is splatted (see "Motion
    /// blur" in the module doc). Default 0. Not a light-transport setting: set from the
    /// run's shutter when built, so it is not serialised with the technique's settings.
    #[serde(skip)]
    pub shutter: f32,
    /// Memory budget of the accumulation films in MiB (all open frames together); tiles
    /// beyond it go to a disk cache ([`WindowFilm::with_budget`]). Default 512.
    #[serde(default = "default_film_budget")]
    pub film_budget_mb: u64,
}

fn default_film_budget() -> u64 {
    512
}

impl Default for StbptSettings {
    fn default() -> Self {
        StbptSettings {
            bdpt: BdptSettings::default(),
            window: 4,
            shutter: 0.0,
            film_budget_mb: default_film_budget(),
        }
    }
}

/// Tiles of 16² pixels whose samples are made in one parallel batch before their
/// contributions are merged into the films: bounds the memory of in-flight contributions
/// (≈ 1024 tiles × 256 px × (2K + 1) frames × 3 films × 28 B ≈ 200 MB at K = 4) whatever
/// the resolution.
const TILES_PER_BATCH: usize = 1024;

/// Salts separating a sample's light and connection streams from its camera stream.
const LIGHT_STREAM: u64 = 0x9e37_79b9_7f4a_7c15;
const CONNECTION_STREAM: u64 = 0xc2b2_ae3d_27d4_eb4f;
/// GGX α below which a specular lobe at x1 is "near-specular": its continuation sampled
/// for one view is not reused for another view.
const NEAR_SPECULAR_ALPHA: f32 = 0.1;

/// Counts of one generated frame's samples, per window frame.
#[derive(Clone, Debug, Default)]
struct Counts {
    /// Samples that landed in each window frame (own frame included).
    landed: Vec<u64>,
    /// Of those, served by reuse of the view-independent part / by re-tracing.
    reused: Vec<u64>,
    /// Of the reused: only the strategies s ≤ 1 (the light subpath changed in g; the
    /// strategies s ≥ 2 were recomputed with g's light subpath).
    partial: Vec<u64>,
    retraced: Vec<u64>,
    invalid: Vec<u64>,
}

impl Counts {
    fn new(n: usize) -> Self {
        Counts {
            landed: vec![0; n],
            reused: vec![0; n],
            partial: vec![0; n],
            retraced: vec![0; n],
            invalid: vec![0; n],
        }
    }

    fn add(&mut self, o: &Counts) {
        for (a, b) in [
            (&mut self.landed, &o.landed),
            (&mut self.reused, &o.reused),
            (&mut self.partial, &o.partial),
            (&mut self.retraced, &o.retraced),
            (&mut self.invalid, &o.invalid),
        ] {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }
}

/// What an output frame received so far.
#[derive(Clone, Debug, Default)]
struct Pending {
    stats: Stats,
    landed: u64,
    reused: u64,
    partial: u64,
    retraced: u64,
    invalid: u64,
}

/// Spatio-temporal BDPT; see the module documentation.
pub struct Stbpt {
    pub settings: StbptSettings,
    film: Option<WindowFilm>,
    /// Squares of the landed values (per-pixel variance of the weighted mean).
    film_sq: Option<WindowFilm>,
    /// Light-tracing splats (kept apart so the variance above is that of the landed
    /// samples).
    film_splat: Option<WindowFilm>,
    /// Motion blur: per pixel, the mean offsets and values of the landed samples in the
    /// neighbouring frames (empty without motion blur).
    film_blur: Vec<WindowFilm>,
    /// Index in the render list of the next frame to generate.
    next: usize,
    pending: BTreeMap<u32, Pending>,
    /// Mean number of frames served by the samples generated for each frame.
    served: BTreeMap<u32, f64>,
    last_output: Option<u32>,
}

impl Stbpt {
    pub fn new(settings: StbptSettings) -> Self {
        Stbpt {
            settings,
            film: None,
            film_sq: None,
            film_splat: None,
            film_blur: Vec::new(),
            next: 0,
            pending: BTreeMap::new(),
            served: BTreeMap::new(),
            last_output: None,
        }
    }

    fn k(&self) -> u32 {
        self.settings.window.min((MAX_WINDOW_FRAMES as u32 - 1) / 2)
    }

    /// Creates the films on first use: the memory budget is shared by the four films in
    /// proportion to what a pixel costs in each (the blur film only holds tiles when
    /// motion blur is on).
    fn open_films(&mut self, w: u32, h: u32) {
        if self.film.is_some() {
            return;
        }
        let budget = self.settings.film_budget_mb.max(1) << 20;
        let blur = if self.settings.shutter > 0.0 { 4 } else { 0 };
        let each = budget / (3 + blur);
        self.film = Some(WindowFilm::with_budget(w, h, each, None));
        self.film_sq = Some(WindowFilm::with_budget(w, h, each, None));
        self.film_splat = Some(WindowFilm::with_budget(w, h, each, None));
        self.film_blur = (0..blur)
            .map(|_| WindowFilm::with_budget(w, h, each, None))
            .collect();
    }

    /// Peak bytes held in memory by the films and their cache traffic (summed over the
    /// films; the peaks of different films may not coincide, so this is an upper bound).
    pub fn film_stats(&self) -> FilmStats {
        let mut t = FilmStats::default();
        let films = [&self.film, &self.film_sq, &self.film_splat];
        for f in films.into_iter().flatten().chain(&self.film_blur) {
            let s = f.stats();
            t.peak_bytes += s.peak_bytes;
            t.tile_hits += s.tile_hits;
            t.tile_misses += s.tile_misses;
            t.bytes_written += s.bytes_written;
            t.bytes_read += s.bytes_read;
            t.io_seconds += s.io_seconds;
            t.tiles_written += s.tiles_written;
            t.budget_bytes = t.budget_bytes.saturating_add(s.budget_bytes);
        }
        t
    }
}

/// Two answers of one ray that give the same vertex.
fn same_hit(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.tri == b.tri
                && a.instance == b.instance
                && a.t.to_bits() == b.t.to_bits()
                && a.b1.to_bits() == b.b1.to_bits()
                && a.b2.to_bits() == b.b2.to_bits()
        }
        _ => false,
    }
}

/// Answers the rays of a subpath walked in window frame `jf` with one multi-frame query
/// each: returns frame `jf`'s hit (exactly what `scene.intersect` gives: the structure's
/// answers equal per-frame queries) and pushes to `masks` the window frames in which the
/// ray gives that same hit, i.e. in which the segment is reproduced. This replaces tracing
/// the walk in f and then checking every segment again against the window (one traversal
/// per segment instead of two).
fn window_trace<'a>(
    mfa: &'a MultiFrameAccel,
    scene: &'a FrameScene,
    jf: usize,
    wh: &'a mut WindowHit,
    masks: &'a mut Vec<FrameMask>,
    rays: Option<&'a mut Vec<Ray>>,
) -> impl FnMut(&Ray) -> Option<Hit> + 'a {
    masks.clear();
    let mut rays = rays;
    if let Some(r) = rays.as_deref_mut() {
        r.clear();
    }
    let all = mfa.all_frames();
    move |ray| {
        if let Some(r) = rays.as_deref_mut() {
            r.push(*ray);
        }
        mfa.intersect_window_into(ray, all, |t, b1, b2| scene.accept(t, b1, b2), wh);
        let hf = wh.frame(jf);
        let mut mask = all;
        if wh.differs != 0 {
            for j in 0..mfa.frame_count() {
                if !same_hit(wh.frame(j), hf) {
                    mask &= !(1u64 << j);
                }
            }
        }
        masks.push(mask);
        hf
    }
}

/// Barycentrics (b1, b2) of world point `p` on triangle `tri` of instance `instance`.
fn barycentrics(scene: &FrameScene, v: &Vertex) -> Option<(f32, f32)> {
    let si = &v.surface.as_ref()?.si;
    let g = &scene.geometry[si.tri.geometry as usize];
    let [i0, i1, i2] = g.indices[si.tri.triangle as usize].map(|i| i as usize);
    let to_world = |q: Vec3| {
        if g.world_space {
            q
        } else {
            scene.accel.instances()[si.instance as usize]
                .world_from_object
                .transform_point3(q)
        }
    };
    let (p0, p1, p2) = (
        to_world(g.positions[i0]),
        to_world(g.positions[i1]),
        to_world(g.positions[i2]),
    );
    let (e1, e2, d) = (p1 - p0, p2 - p0, v.p - p0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if den.abs() < 1e-30 {
        return None;
    }
    Some(((d22 * d1 - d12 * d2) / den, (d11 * d2 - d12 * d1) / den))
}

/// The instance carrying geometry `geom` has the same placement (and data) in both frames.
fn same_placement(a: &FrameScene, b: &FrameScene, geom: u32) -> bool {
    let g = geom as usize;
    let (ia, ib) = (a.geometry_instance[g], b.geometry_instance[g]);
    if ia != ib || !Arc::ptr_eq(&a.geometry[g].positions, &b.geometry[g].positions) {
        return false;
    }
    let (x, y) = (
        &a.accel.instances()[ia as usize],
        &b.accel.instances()[ib as usize],
    );
    Arc::ptr_eq(&x.blas, &y.blas)
        && x.world_from_object == y.world_from_object
        && x.geometry_base == y.geometry_base
}

/// What light subpaths and light samples depend on, as a comparable key.
fn light_key(scene: &FrameScene) -> String {
    let infinite = scene
        .lights
        .iter()
        .any(|l| matches!(l, Light::Directional { .. } | Light::Environment { .. }));
    let sphere = infinite.then(|| scene.bounds.bounding_sphere());
    format!(
        "{:?}|{:?}|{:?}|{:?}|{}",
        scene.lights, scene.light_sampler, scene.environment, sphere, scene.scene_radius
    )
}

/// Motion blur of a reconstructed frame: every pixel's value (the mean of its landed
/// samples) is spread over the pixels its trajectory crosses during the shutter
/// ([`splat_trajectory`]), the trajectory being the mean over its landed samples of where
/// their points are seen one frame before and after (`blur[0]`, `blur[1]`: raster offsets),
/// positions and radiance (`blur[2]`, `blur[3]`: values there) linear in time between
/// frames. Pixels no sample landed in contribute nothing.
fn splat_pixel_trajectories(
    means: &[Rgb],
    weights: &[f32],
    blur: &[Vec<Rgb>],
    w: u32,
    h: u32,
    shutter: f32,
) -> Vec<Rgb> {
    let half = 0.5 * shutter;
    let mut out = vec![Rgb::ZERO; means.len()];
    let mut shares = Vec::new();
    for (i, (&l, &n)) in means.iter().zip(weights).enumerate() {
        if n <= 0.0 {
            continue;
        }
        let c = Vec2::new((i as u32 % w) as f32 + 0.5, (i as u32 / w) as f32 + 0.5);
        let (db, da) = (blur[0][i], blur[1][i]);
        let (lb, la) = (blur[2][i], blur[3][i]);
        let traj = [
            TrajectoryVertex {
                raster: c + Vec2::new(db.x, db.y) * half,
                time: -half,
                radiance: l + (lb - l) * half,
            },
            TrajectoryVertex {
                raster: c,
                time: 0.0,
                radiance: l,
            },
            TrajectoryVertex {
                raster: c + Vec2::new(da.x, da.y) * half,
                time: half,
                radiance: l + (la - l) * half,
            },
        ];
        shares.clear();
        splat_trajectory(&traj, w, h, &mut shares);
        for sh in &shares {
            out[sh.pixel as usize] += sh.value;
        }
    }
    out
}

/// One view-independent entry at x1.
struct Entry {
    /// Light vertices of the strategy: s ≤ 1 does not depend on the light subpath.
    s: usize,
    wi: Vec3,
    r: Rgb,
    /// The contribution as computed in f (for f itself, no rounding from the split).
    c: Rgb,
    /// Window frames in which the entry's shadow ray is unoccluded.
    vis: FrameMask,
}

/// Per-thread scratch buffers.
#[derive(Default)]
struct Scratch {
    cam: Vec<Vertex>,
    cam_rays: Vec<Ray>,
    /// Per traced ray of the camera / light subpath: the window frames reproducing it.
    cam_masks: Vec<FrameMask>,
    light_masks: Vec<FrameMask>,
    wh: WindowHit,
    light: Vec<Vertex>,
    light_g: Vec<Vertex>,
    cam_g: Vec<Vertex>,
    entries: Vec<Entry>,
    /// Frame f's light-tracing splats: (pixel, value, frames where unoccluded).
    splats: Vec<(u32, Rgb, FrameMask)>,
}

/// Read-only state of one generated frame.
struct Generation<'a> {
    bdpt: &'a BdptSettings,
    frames: &'a [u32],
    scenes: &'a [Arc<FrameScene>],
    jf: usize,
    f: u32,
    mfa: &'a MultiFrameAccel,
    /// Frames whose lights (and materials) equal f's.
    lights_same: FrameMask,
    materials_same: FrameMask,
    /// Frames whose camera is f's (same placement, projection and image size).
    same_camera: FrameMask,
    /// Shutter as a fraction of the frame interval (0: no motion blur).
    shutter: f32,
}

/// A sample landed in window frame `j` at `raster` with `value` (buffered until the
/// sample is complete, so a motion-blurred landing can use the sample's values in the
/// neighbouring frames).
#[derive(Clone, Copy)]
struct Landing {
    j: usize,
    raster: Vec2,
    value: Rgb,
    /// Motion blur: raster positions of the sample's point one frame before / after.
    around: [Option<Vec2>; 2],
    /// The landing shows the point the sample found in its own frame (own frame or
    /// reuse), so its values in two frames are the radiance of one point at two times;
    /// a re-traced landing may show another point.
    same_point: bool,
}

/// Output of one tile of one pass.
struct TileOut {
    batch: Vec<Contribution>,
    squares: Vec<Contribution>,
    splats: Vec<Contribution>,
    /// Motion blur: per landed sample, its raster offsets to where its point is seen one
    /// frame before / after, and its values there (films `film_blur[0..4]`).
    blur: [Vec<Contribution>; 4],
    landings: Vec<Landing>,
    stats: Vec<Stats>,
    counts: Counts,
}

impl Generation<'_> {
    /// The t = 1 strategies of `light` in frame `j`, splatted into `out`. With `record`
    /// (frame f only), shadow rays are answered for the whole window and every splat is
    /// recorded with the frames it is unoccluded in, for the frames that share f's camera.
    #[allow(clippy::too_many_arguments)] // reason: the subpaths, the frame and the outputs
    fn light_trace(
        &self,
        j: usize,
        light: &[Vertex],
        camera: &[Vertex],
        conn: &PixelSampler,
        out: &mut TileOut,
        invalid: &mut u64,
        mut record: Option<&mut Vec<(u32, Rgb, FrameMask)>>,
    ) {
        let scene = &self.scenes[j];
        let (w, h) = (scene.camera.width, scene.camera.height);
        let max_segments = self.bdpt.depth() as usize;
        let mut sampler = conn.clone();
        let all = self.mfa.all_frames();
        for s in 2..=light.len() {
            if s > max_segments {
                break;
            }
            let mut vis: FrameMask = 1 << j;
            // Recording: the shadow ray answered for the whole window; otherwise for j.
            let windowed = record.is_some();
            let c = connect_with(
                scene,
                self.bdpt,
                light,
                camera,
                s,
                1,
                &mut sampler,
                &mut out.stats[j],
                &mut |r| {
                    if windowed {
                        vis = all
                            & !self
                                .mfa
                                .occluded_window(r, all, |a, b1, b2| scene.accept(a, b1, b2));
                        vis != 0
                    } else {
                        !scene.occluded(r)
                    }
                },
            )
            .map(|c| c.contribution);
            let Some(c) = c else { continue };
            let Some(r) = c.raster else { continue };
            if !c.l.is_finite() {
                *invalid += 1;
                continue;
            }
            let (x, y) = (r.x as u32, r.y as u32);
            if r.x >= 0.0 && r.y >= 0.0 && x < w && y < h {
                if let Some(rec) = record.as_deref_mut() {
                    rec.push((y * w + x, c.l, vis));
                }
                if vis >> j & 1 == 1 {
                    out.splats.push(Contribution {
                        frame: self.frames[j],
                        pixel: y * w + x,
                        value: c.l,
                        weight: 0.0,
                        splat: true,
                    });
                }
            }
        }
    }

    /// Sum of the t ≥ 2 strategies of `camera` and `light` in frame `j` (plain BDPT).
    fn camera_strategies(
        &self,
        j: usize,
        light: &[Vertex],
        camera: &[Vertex],
        conn: &PixelSampler,
        stats: &mut Stats,
    ) -> Rgb {
        let scene = &self.scenes[j];
        let max_segments = self.bdpt.depth() as usize;
        let mut sampler = conn.clone();
        let mut l = Rgb::ZERO;
        for t in 2..=camera.len() {
            for s in 0..=light.len() {
                if s + t - 1 > max_segments {
                    continue;
                }
                if let Some(c) = connect(scene, self.bdpt, light, camera, s, t, &mut sampler, stats)
                {
                    l += c.l;
                }
            }
        }
        l
    }

    fn land(
        out: &mut TileOut,
        j: usize,
        raster: Vec2,
        value: Rgb,
        around: [Option<Vec2>; 2],
        same_point: bool,
    ) {
        out.landings.push(Landing {
            j,
            raster,
            value,
            around,
            same_point,
        });
    }

    /// Motion blur: where the point a sample shows in window frame `j` is seen one frame
    /// before and after `j` (raster positions in those frames, visible or not). The point
    /// is `v` on a surface of frame `src`'s scene (moved with its object), or, for an
    /// escaped camera ray, the direction `dir` (at infinity).
    fn trajectory(
        &self,
        j: usize,
        src: usize,
        v: Option<&Vertex>,
        dir: Option<Vec3>,
    ) -> [Option<Vec2>; 2] {
        if self.shutter <= 0.0 {
            return [None, None];
        }
        let v = v.filter(|v| v.kind == VertexKind::Surface);
        let bary = v.and_then(|v| barycentrics(&self.scenes[src], v));
        let at = |dj: isize| -> Option<Vec2> {
            let jn = j
                .checked_add_signed(dj)
                .filter(|&jn| jn < self.frames.len())?;
            if self.frames[jn].abs_diff(self.frames[j]) != 1 {
                return None;
            }
            let scene_n = &self.scenes[jn];
            let cam_n = &scene_n.camera;
            match v {
                None => dir.and_then(|d| cam_n.project(cam_n.position() + d.normalize())),
                Some(v) => {
                    let sv = v.surface.as_ref()?;
                    let geom = sv.si.tri.geometry;
                    let p = if same_placement(&self.scenes[src], scene_n, geom) {
                        v.p
                    } else {
                        let (b1, b2) = bary?;
                        let inst = scene_n.geometry_instance[geom as usize];
                        scene_n.surface_at(sv.si.tri, inst, b1, b2, None).p
                    };
                    cam_n.project(p)
                }
            }
        };
        [at(-1), at(1)]
    }

    /// Turns the sample's buffered landings into film contributions: one landed sample at
    /// its pixel, or (motion blur) a landed count at its pixel and its trajectory over the
    /// shutter as splats.
    fn flush(&self, out: &mut TileOut) {
        let shutter = self.shutter;
        let landings = std::mem::take(&mut out.landings);
        for l in &landings {
            let cam = &self.scenes[l.j].camera;
            let (w, h) = (cam.width, cam.height);
            let pixel = (l.raster.y as u32).min(h - 1) * w + (l.raster.x as u32).min(w - 1);
            let frame = self.frames[l.j];
            out.squares.push(Contribution {
                frame,
                pixel,
                value: l.value * l.value,
                weight: 1.0,
                splat: false,
            });
            out.batch.push(Contribution {
                frame,
                pixel,
                value: l.value,
                weight: 1.0,
                splat: false,
            });
            if shutter <= 0.0 {
                continue;
            }
            // Neighbouring frames of the window one frame interval away: where the
            // sample's point is seen there, and its value there if it landed.
            let neighbour = |dj: isize| -> Option<(Vec2, Rgb)> {
                let jn =
                    l.j.checked_add_signed(dj)
                        .filter(|&jn| jn < self.frames.len())?;
                if self.frames[jn].abs_diff(frame) != 1 {
                    return None;
                }
                let r = l.around[if dj < 0 { 0 } else { 1 }]?;
                // Radiance interpolated between frames only between values of one point.
                let v = landings
                    .iter()
                    .find(|o| o.j == jn && o.same_point && l.same_point)
                    .map_or(l.value, |o| o.value);
                Some((r, v))
            };
            let (before, after) = match (neighbour(-1), neighbour(1)) {
                (Some(b), Some(a)) => (b, a),
                (Some(b), None) => (b, (2.0 * l.raster - b.0, l.value)),
                (None, Some(a)) => ((2.0 * l.raster - a.0, l.value), a),
                (None, None) => ((l.raster, l.value), (l.raster, l.value)),
            };
            let d_before = before.0 - l.raster;
            let d_after = after.0 - l.raster;
            for (k, value) in [
                Rgb::new(d_before.x, d_before.y, 0.0),
                Rgb::new(d_after.x, d_after.y, 0.0),
                before.1,
                after.1,
            ]
            .into_iter()
            .enumerate()
            {
                out.blur[k].push(Contribution {
                    frame,
                    pixel,
                    value,
                    weight: 1.0,
                    splat: false,
                });
            }
        }
        out.landings = landings;
        out.landings.clear();
    }

    /// One sample: generated in f, landed/reused/re-traced in every window frame.
    fn sample(&self, px: u32, py: u32, index: u32, sc: &mut Scratch, out: &mut TileOut) {
        let (seed, f, jf) = (self.bdpt.seed, self.f, self.jf);
        let n = self.scenes.len();
        let scene_f = &self.scenes[jf];
        let all = self.mfa.all_frames();
        let mut cs = PixelSampler::new(seed, f, px, py);
        cs.start_sample(index);
        let mut ls = PixelSampler::new(seed ^ LIGHT_STREAM, f, px, py);
        ls.start_sample(index);
        let mut ns = PixelSampler::new(seed ^ CONNECTION_STREAM, f, px, py);
        ns.start_sample(index);
        let raster = Vec2::new(px as f32, py as f32) + cs.next_2d();
        let cs0 = cs.clone();
        let ls0 = ls.clone();
        let st = &mut out.stats[jf];
        generate_camera_subpath_with(
            scene_f,
            self.bdpt,
            raster,
            &mut cs,
            &mut sc.cam,
            st,
            &mut window_trace(
                self.mfa,
                scene_f,
                jf,
                &mut sc.wh,
                &mut sc.cam_masks,
                Some(&mut sc.cam_rays),
            ),
        );
        generate_light_subpath_with(
            scene_f,
            self.bdpt,
            &mut ls,
            &mut sc.light,
            st,
            &mut window_trace(self.mfa, scene_f, jf, &mut sc.wh, &mut sc.light_masks, None),
        );
        st.samples += 1;
        let (cam, light) = (&sc.cam, &sc.light);
        let max_segments = self.bdpt.depth() as usize;

        // Validity of the sampled segments in the other frames.
        let and = |m: &[FrameMask]| m.iter().fold(all, |a, b| a & b);
        let light_valid = and(&sc.light_masks) & self.lights_same;
        let x1 = cam.get(1).filter(|v| v.kind == VertexKind::Surface);
        // Camera segments after x1 reproduced (the camera subpath is the same walk in g).
        let cam_segments = if x1.is_some() {
            and(sc.cam_masks.get(1..).unwrap_or(&[])) & self.materials_same
        } else {
            1 << jf
        };
        let cam_valid = if n > 1 && x1.is_some() {
            cam_segments & light_valid
        } else if n > 1 && !sc.cam_masks.is_empty() {
            // An escaped camera ray: its value (the environment, or nothing) is reused
            // where the same ray escapes too.
            sc.cam_masks[0] & self.lights_same & self.materials_same
        } else {
            1 << jf
        };

        // View-independent part at x1 (t ≥ 2), shadow rays answered for the whole window.
        sc.entries.clear();
        let mut emission: Option<(Rgb, f32)> = None;
        let mut sampler = ns.clone();
        for t in 2..=cam.len() {
            for s in 0..=light.len() {
                if s + t - 1 > max_segments {
                    continue;
                }
                let mut vis = all;
                let c = connect_with(
                    scene_f,
                    self.bdpt,
                    light,
                    cam,
                    s,
                    t,
                    &mut sampler,
                    st,
                    &mut |r| {
                        vis = all
                            & !self
                                .mfa
                                .occluded_window(r, all, |a, b1, b2| scene_f.accept(a, b1, b2));
                        vis != 0
                    },
                );
                let Some(c) = c else { continue };
                let l = c.contribution.l;
                let x1v = &cam[1];
                if s == 0 && t == 2 {
                    let w = mis_weight(scene_f, self.bdpt, light, cam, None, 0, 2);
                    emission = Some((l, w));
                    continue;
                }
                let sv = x1v
                    .surface
                    .as_ref()
                    .expect("strategies other than (0, 2) need x1 on a surface");
                let wi = if t == 2 {
                    (c.light_point.expect("s ≥ 1") - x1v.p).normalize_or_zero()
                } else {
                    sc.cam_rays[1].d.normalize()
                };
                let fv = sv.bsdf.f(sv.wo, wi, TransportMode::Radiance);
                let r = Rgb::new(
                    if fv.x != 0.0 { l.x / fv.x } else { 0.0 },
                    if fv.y != 0.0 { l.y / fv.y } else { 0.0 },
                    if fv.z != 0.0 { l.z / fv.z } else { 0.0 },
                );
                sc.entries.push(Entry {
                    s,
                    wi,
                    r,
                    c: l,
                    vis,
                });
            }
        }

        // Own frame: the ordinary BDPT sample.
        let mut own = emission.map_or(Rgb::ZERO, |(l, _)| l);
        for e in &sc.entries {
            if e.vis >> jf & 1 == 1 {
                own += e.c;
            }
        }
        let mut inv = 0u64;
        let around_f = self.trajectory(jf, jf, cam.get(1), sc.cam_rays.first().map(|r| r.d));
        if own.is_finite() {
            Self::land(out, jf, raster, own, around_f, true);
        } else {
            inv += 1;
            Self::land(out, jf, raster, Rgb::ZERO, around_f, true);
        }
        out.counts.landed[jf] += 1;
        sc.splats.clear();
        let record = (n > 1).then_some(&mut sc.splats);
        self.light_trace(jf, light, cam, &ns, out, &mut inv, record);
        out.counts.invalid[jf] += inv;

        // Other frames of the window.
        let x1_bary = x1.and_then(|v| barycentrics(scene_f, v));
        let eye_f = scene_f.camera.position();
        // Landing visibility of x1 from f's eye, answered once for the whole window (the
        // same ray in every frame where x1 and the eye do not move).
        let mut land_occ: Option<FrameMask> = None;
        for j in (0..n).filter(|&j| j != jf) {
            let scene_g = &self.scenes[j];
            let frame_g = self.frames[j];
            let mut inv = 0u64;
            // Light part: reused or re-generated from the same light stream.
            let light_ok = light_valid >> j & 1 == 1;
            if !light_ok {
                let mut l2 = ls0.clone();
                generate_light_subpath(
                    scene_g,
                    self.bdpt,
                    &mut l2,
                    &mut sc.light_g,
                    &mut out.stats[j],
                );
            }
            if light_ok && self.same_camera >> j & 1 == 1 {
                // Same light subpath, same camera: the same splats, where unoccluded in g.
                for &(pixel, value, vis) in &sc.splats {
                    if vis >> j & 1 == 1 {
                        out.splats.push(Contribution {
                            frame: frame_g,
                            pixel,
                            value,
                            weight: 0.0,
                            splat: true,
                        });
                    }
                }
            } else {
                let light_g: &[Vertex] = if light_ok { light } else { &sc.light_g };
                self.light_trace(j, light_g, cam, &ns, out, &mut inv, None);
            }

            // Camera part: where does the sample land in g?
            let cam_g = &scene_g.camera;
            if !matches!(cam_g.projection, Projection::Perspective { .. }) {
                out.counts.invalid[j] += inv;
                continue;
            }
            let eye = cam_g.position();
            // (raster, reuse everything, reuse the strategies s ≤ 1 only)
            let landing: Option<(Vec2, bool, bool)> = match x1 {
                None => {
                    // Escaped camera ray (or an environment vertex): lands where its
                    // direction projects; reused when g's camera is f's and the ray
                    // escapes in g too (then g's camera ray is the same ray).
                    let same_camera = cam_g.world_from_camera == scene_f.camera.world_from_camera;
                    sc.cam_rays
                        .first()
                        .and_then(|r| cam_g.project(eye + r.d.normalize()))
                        .map(|r| (r, same_camera && cam_valid >> j & 1 == 1, false))
                }
                Some(v) => {
                    let sv = v.surface.as_ref().unwrap();
                    let geom = sv.si.tri.geometry;
                    let moved = !same_placement(scene_f, scene_g, geom);
                    let (p, ng) = if moved {
                        match x1_bary {
                            Some((b1, b2)) => {
                                let inst = scene_g.geometry_instance[geom as usize];
                                let si = scene_g.surface_at(sv.si.tri, inst, b1, b2, None);
                                (si.p, si.ng)
                            }
                            None => {
                                out.counts.invalid[j] += inv;
                                continue;
                            }
                        }
                    } else {
                        (v.p, v.ng)
                    };
                    let wo_g = (eye - p).normalize_or_zero();
                    // Seen from the same side of the surface as in f.
                    let faces = sv.si.ng.dot(sv.wo) * ng.dot(wo_g) > 0.0;
                    let raster_g = cam_g.project(p);
                    match raster_g {
                        Some(r) if faces => {
                            let shared =
                                !moved && eye == eye_f && self.materials_same >> j & 1 == 1;
                            let occluded = if shared {
                                let occ = *land_occ.get_or_insert_with(|| {
                                    out.stats[jf].shadow_rays += 1;
                                    let ray = spawn_ray_to(p, ng, eye, Vec3::ZERO);
                                    self.mfa.occluded_window(&ray, all, |t, b1, b2| {
                                        scene_f.accept(t, b1, b2)
                                    })
                                });
                                occ >> j & 1 == 1
                            } else {
                                out.stats[j].shadow_rays += 1;
                                scene_g.occluded(&spawn_ray_to(p, ng, eye, Vec3::ZERO))
                            };
                            if occluded {
                                None
                            } else {
                                let near_specular = {
                                    let lo = &sv.bsdf.lobes;
                                    (lo.specular_weight > 0.0
                                        || lo.metal_weight > 0.0
                                        || lo.transmission_weight > 0.0)
                                        && lo.alpha < NEAR_SPECULAR_ALPHA
                                };
                                let camera_moved = eye != scene_f.camera.position();
                                let valid = cam_valid >> j & 1 == 1;
                                let view_safe = !(near_specular && camera_moved);
                                let split_ok = view_safe && !moved && !v.delta;
                                let reuse = valid && split_ok;
                                // Only the light subpath differs in g: the camera subpath
                                // and the strategies s ≤ 1 are g's as well.
                                let partial = !valid
                                    && split_ok
                                    && (cam_segments & self.lights_same) >> j & 1 == 1;
                                Some((r, reuse, partial))
                            }
                        }
                        _ => None,
                    }
                }
            };
            let Some((raster_g, reuse, partial)) = landing else {
                out.counts.invalid[j] += inv;
                continue;
            };
            let esc_dir = sc.cam_rays.first().map(|r| r.d);
            let mut around = [None, None];
            let value = if reuse && x1.is_none() {
                out.counts.reused[j] += 1;
                around = self.trajectory(j, jf, None, esc_dir);
                own
            } else if reuse || partial {
                around = self.trajectory(j, jf, x1, esc_dir);
                let v = x1.unwrap();
                let sv = v.surface.as_ref().unwrap();
                let wo_g = (eye - v.p).normalize_or_zero();
                let mut l =
                    emission.map_or(Rgb::ZERO, |(_, wm)| scene_g.emitted(&sv.si, wo_g) * wm);
                for e in &sc.entries {
                    if e.vis >> j & 1 == 1 && (reuse || e.s <= 1) {
                        l += sv.bsdf.f(wo_g, e.wi, TransportMode::Radiance) * e.r;
                    }
                }
                if partial {
                    // s ≥ 2: f's camera subpath (reproduced in g) connected to g's light
                    // subpath in g's scene, split at x1 like the entries.
                    let same_view = wo_g == sv.wo;
                    let mut sampler = ns.clone();
                    let st = &mut out.stats[j];
                    for t in 2..=cam.len() {
                        for s in 2..=sc.light_g.len() {
                            if s + t - 1 > max_segments {
                                continue;
                            }
                            let Some(c) = connect(
                                scene_g,
                                self.bdpt,
                                &sc.light_g,
                                cam,
                                s,
                                t,
                                &mut sampler,
                                st,
                            ) else {
                                continue;
                            };
                            if same_view {
                                l += c.l;
                                continue;
                            }
                            let wi = if t == 2 {
                                (sc.light_g[s - 1].p - v.p).normalize_or_zero()
                            } else {
                                sc.cam_rays[1].d.normalize()
                            };
                            let fv = sv.bsdf.f(sv.wo, wi, TransportMode::Radiance);
                            let fg = sv.bsdf.f(wo_g, wi, TransportMode::Radiance);
                            l += Rgb::new(
                                if fv.x != 0.0 {
                                    c.l.x / fv.x * fg.x
                                } else {
                                    0.0
                                },
                                if fv.y != 0.0 {
                                    c.l.y / fv.y * fg.y
                                } else {
                                    0.0
                                },
                                if fv.z != 0.0 {
                                    c.l.z / fv.z * fg.z
                                } else {
                                    0.0
                                },
                            );
                        }
                    }
                    out.counts.partial[j] += 1;
                }
                out.counts.reused[j] += 1;
                l
            } else if x1.is_some_and(|v| {
                self.same_camera >> j & 1 == 1
                    && cam_segments >> j & 1 == 1
                    && same_placement(
                        scene_f,
                        scene_g,
                        v.surface.as_ref().unwrap().si.tri.geometry,
                    )
            }) {
                // Same camera, x1 and every camera segment reproduced in g: f's camera
                // subpath is the walk g makes for this raster position; only the light
                // subpath (regenerated in g) and the connections are g's own.
                let light_g: &[Vertex] = if light_ok { light } else { &sc.light_g };
                out.counts.retraced[j] += 1;
                self.camera_strategies(j, light_g, cam, &ns, &mut out.stats[j])
            } else {
                let mut c2 = cs0.clone();
                generate_camera_subpath(
                    scene_g,
                    self.bdpt,
                    raster_g,
                    &mut c2,
                    &mut sc.cam_g,
                    &mut out.stats[j],
                );
                let light_g: &[Vertex] = if light_ok { light } else { &sc.light_g };
                out.counts.retraced[j] += 1;
                if self.shutter > 0.0 {
                    let d = scene_g.camera.generate_ray(raster_g).d;
                    around = self.trajectory(j, j, sc.cam_g.get(1), Some(d));
                }
                self.camera_strategies(j, light_g, &sc.cam_g, &ns, &mut out.stats[j])
            };
            out.counts.landed[j] += 1;
            if value.is_finite() {
                Self::land(out, j, raster_g, value, around, reuse || partial);
            } else {
                inv += 1;
                Self::land(out, j, raster_g, Rgb::ZERO, around, reuse || partial);
            }
            out.counts.invalid[j] += inv;
        }
        self.flush(out);
    }
}

impl Stbpt {
    /// Generates the samples of frame `f` and adds them to every frame of its window.
    fn generate(&mut self, source: &mut FrameSource, f: u32, progress: &(dyn Fn(u64) + Sync)) {
        let k = self.k();
        let frames = source.window(f, k, k);
        let scenes: Vec<Arc<FrameScene>> = frames.iter().map(|&g| source.frame(g)).collect();
        let jf = frames
            .iter()
            .position(|&g| g == f)
            .expect("f is in its window");
        let accels: Vec<_> = scenes.iter().map(|s| &s.accel).collect();
        let mfa = MultiFrameAccel::new(frames[0], &accels);
        let key_f = light_key(&scenes[jf]);
        let mut lights_same: FrameMask = 0;
        let mut materials_same: FrameMask = 0;
        for (j, s) in scenes.iter().enumerate() {
            if j == jf || light_key(s) == key_f {
                lights_same |= 1 << j;
            }
            if Arc::ptr_eq(&s.materials, &scenes[jf].materials)
                && Arc::ptr_eq(&s.textures, &scenes[jf].textures)
            {
                materials_same |= 1 << j;
            }
        }
        let cam_key = |s: &FrameScene| format!("{:?}", s.camera);
        let same_camera = scenes
            .iter()
            .enumerate()
            .filter(|(_, s)| cam_key(s) == cam_key(&scenes[jf]))
            .fold(0, |m, (j, _)| m | 1 << j);
        self.open_films(scenes[jf].camera.width, scenes[jf].camera.height);
        let gen_ = Generation {
            same_camera,
            bdpt: &self.settings.bdpt,
            frames: &frames,
            scenes: &scenes,
            jf,
            f,
            mfa: &mfa,
            lights_same,
            materials_same,
            shutter: self.settings.shutter,
        };
        let cam = &scenes[jf].camera;
        let (w, h) = (cam.width, cam.height);
        let film = self.film.as_mut().expect("opened");
        let film_sq = self.film_sq.as_mut().expect("opened");
        let film_splat = self.film_splat.as_mut().expect("opened");
        let film_blur = &mut self.film_blur;
        let tiles_x = w.div_ceil(TILE);
        let n_tiles = (tiles_x * h.div_ceil(TILE)) as usize;
        let n = frames.len();
        let spp = self.settings.bdpt.spp;
        let mut counts = Counts::new(n);
        let mut stats = vec![Stats::default(); n];
        for (s, first) in
            (0..spp).flat_map(|s| (0..n_tiles).step_by(TILES_PER_BATCH).map(move |t| (s, t)))
        {
            let batch_tiles = TILES_PER_BATCH.min(n_tiles - first);
            let results = parallel::map_chunks(batch_tiles, 1, |range| {
                let t = (first + range.start) as u32;
                let (x0, y0, tw, th) = tile_rect(t, tiles_x, TILE, w, h);
                let mut out = TileOut {
                    batch: Vec::new(),
                    squares: Vec::new(),
                    splats: Vec::new(),
                    blur: Default::default(),
                    landings: Vec::new(),
                    stats: vec![Stats::default(); n],
                    counts: Counts::new(n),
                };
                let mut sc = Scratch::default();
                for y in y0..y0 + th {
                    for x in x0..x0 + tw {
                        gen_.sample(x, y, s, &mut sc, &mut out);
                    }
                }
                let np = (tw * th) as u64;
                progress(np * (s as u64 + 1) / spp as u64 - np * s as u64 / spp as u64);
                out
            });
            for r in &results {
                film.add_batch(&r.batch);
                film_sq.add_batch(&r.squares);
                film_splat.add_batch(&r.splats);
                for (film, batch) in film_blur.iter_mut().zip(&r.blur) {
                    film.add_batch(batch);
                }
                counts.add(&r.counts);
                for (a, b) in stats.iter_mut().zip(&r.stats) {
                    *a += *b;
                }
            }
        }
        for (j, &g) in frames.iter().enumerate() {
            let p = self.pending.entry(g).or_default();
            p.stats += stats[j];
            p.landed += counts.landed[j];
            p.reused += counts.reused[j];
            p.partial += counts.partial[j];
            p.retraced += counts.retraced[j];
            p.invalid += counts.invalid[j];
        }
        let generated = (w as u64 * h as u64 * spp as u64).max(1) as f64;
        self.served
            .insert(f, counts.landed.iter().sum::<u64>() as f64 / generated);
    }
}

impl SequenceRenderer for Stbpt {
    fn name(&self) -> &'static str {
        "stbpt"
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let k = self.k();
        source.reserve(2 * k as usize + 2);
        let list = source.frames().to_vec();
        // Frames come in increasing order; a request for an earlier frame starts over
        // (the open frames are dropped, the samples regenerated).
        if self.last_output.is_some_and(|l| frame <= l) {
            *self = Stbpt::new(self.settings.clone());
        }
        if self.next == 0 {
            self.next = list.partition_point(|&g| g.saturating_add(k) < frame);
        }
        self.last_output = Some(frame);
        while self.next < list.len() && list[self.next] <= frame.saturating_add(k) {
            let f = list[self.next];
            self.generate(source, f, progress);
            self.next += 1;
        }
        let window = source.window(frame, k, k).len().max(1) as u32;
        let spp = self.settings.bdpt.spp;
        let scene = source.frame(frame);
        let (w, h) = (scene.camera.width, scene.camera.height);
        let splat_scale = 1.0 / (spp as f32 * window as f32);
        self.open_films(w, h);
        let (mut means, weights) = self.film.as_mut().expect("opened").finish(frame, 0.0);
        let (squares, _) = self.film_sq.as_mut().expect("opened").finish(frame, 0.0);
        let (splats, _) = self
            .film_splat
            .as_mut()
            .expect("opened")
            .finish(frame, splat_scale);
        if self.settings.shutter > 0.0 {
            let blur: Vec<Vec<Rgb>> = self
                .film_blur
                .iter_mut()
                .map(|f| f.finish(frame, 0.0).0)
                .collect();
            means = splat_pixel_trajectories(&means, &weights, &blur, w, h, self.settings.shutter);
        }
        // Variance of the mean of the landed samples, (E[v²] − E[v]²)/(n − 1); the splats'
        // share is not included (they are summed over many light subpaths).
        let variance = means
            .iter()
            .zip(&squares)
            .zip(&weights)
            .map(|((&m, &sq), &n)| {
                if n > 1.0 {
                    (sq - m * m).max(Rgb::ZERO) / (n - 1.0)
                } else {
                    Rgb::ZERO
                }
            })
            .collect();
        let pixels = means.iter().zip(&splats).map(|(&m, &s)| m + s).collect();
        let p = self.pending.remove(&frame).unwrap_or_default();
        let npix = (w as f64 * h as f64).max(1.0);
        let reuse = ReuseStats {
            window,
            effective_spp: p.landed as f64 / npix,
            reused: p.reused,
            reused_partially: p.partial,
            retraced: p.retraced,
            reuse_factor: self.served.get(&frame).copied().unwrap_or(0.0),
            light_subpaths_per_pixel: spp as f64 * window as f64,
            film: self.film_stats(),
        };
        self.served.retain(|&f, _| f + k >= frame);
        RenderedFrame {
            width: w,
            height: h,
            pixels,
            variance,
            stats: p.stats,
            invalid_samples: p.invalid,
            report: [(
                "reuse".to_string(),
                serde_json::to_value(reuse).expect("serialisable"),
            )]
            .into_iter()
            .collect(),
        }
    }
}

/// Registry entry of `stbpt`; the shutter is the run's ([`BuildContext`](crate::registry::BuildContext)).
pub static TECHNIQUE: crate::registry::Preset<StbptSettings> = crate::registry::Preset {
    name: "stbpt",
    summary: "spatio-temporal BDPT: each sample reused in the frames of a window [f-K, f+K]",
    capabilities: crate::registry::Capabilities {
        motion_blur: true,
        photons: false,
        window: true,
        stateless: false,
        effort: crate::registry::Effort {
            key: "spp",
            per_unit: 1,
            unit: "samples per pixel generated per frame",
        },
    },
    defaults: StbptSettings::default,
    build: |mut s, ctx, _| {
        s.shutter = ctx.shutter;
        Box::new(Stbpt::new(s))
    },
};
