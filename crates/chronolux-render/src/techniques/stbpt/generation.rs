//! Generation: one frame's samples, made once in f and served to every frame of its
//! window (see "Per sample (generated once, in frame f)" in the module doc). The subpaths
//! are traced through the window structure, so each segment's validity in the other
//! frames comes with its hit, and the view-independent part at x1 is split off here;
//! per window frame, [`super::landing`] decides how the sample serves it,
//! [`super::reuse`] computes the value and [`super::motion`] the motion-blur trajectory.

use super::context::{Entry, Generation, same_hit};
use super::landing::{Landing, Walk, barycentrics};
use super::reuse::{Regenerated, Reproduced};
use super::strategies::{self, Mode, Pilot, SHADOW_QUERY_COST, luminance, pilot_pixel};
use super::{CONNECTION_STREAM, LIGHT_STREAM, Stbpt, TILES_PER_BATCH, adapt};
use crate::framework::integrator::{TILE, tile_rect};
use crate::framework::window_film::Contribution;
use crate::kernels::bdpt::{
    BdptSettings, Connection, MisHeuristic, Vertex, VertexKind, connect_with,
    generate_camera_subpath, generate_camera_subpath_with, generate_light_subpath_with, mis_weight,
    strategy_ratios, view_split,
};
use chronolux_core::accel::Hit;
use chronolux_core::accel::multi_frame::{FrameMask, MultiFrameAccel, WindowHit};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::Ray;
use chronolux_core::math::Vec2;
use chronolux_core::parallel;
use chronolux_core::sampling::sampler::{PixelSampler, SOBOL_MAX_SAMPLES};
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use chronolux_core::stats::Stats;
use std::sync::Arc;

/// Counts of one generated frame's samples, per window frame.
#[derive(Clone, Debug, Default)]
pub(super) struct Counts {
    /// Samples that landed in each window frame (own frame included).
    pub(super) landed: Vec<u64>,
    /// Of those, served by reuse of the view-independent part / by re-tracing.
    pub(super) reused: Vec<u64>,
    /// Of the reused: only the strategies s ≤ 1 (the light subpath changed in g; the
    /// strategies s ≥ 2 were recomputed with g's light subpath).
    pub(super) partial: Vec<u64>,
    pub(super) retraced: Vec<u64>,
    /// Of the re-traced: those that began with f's camera vertices through x1 at least
    /// (module doc, "Valid prefix of a camera subpath").
    pub(super) prefix: Vec<u64>,
    /// Of the reused and the re-traced from a prefix: those whose x1 lies on a deformed
    /// mesh (on a triangle the same in both frames: [`FrameDelta::triangle_changed`]).
    pub(super) on_deformed: Vec<u64>,
    pub(super) invalid: Vec<u64>,
    /// Ray queries (closest-hit and shadow) of the re-traced landings' camera subpaths and
    /// connections.
    pub(super) retrace_queries: Vec<u64>,
}

impl Counts {
    fn new(n: usize) -> Self {
        Counts {
            landed: vec![0; n],
            reused: vec![0; n],
            partial: vec![0; n],
            retraced: vec![0; n],
            prefix: vec![0; n],
            on_deformed: vec![0; n],
            invalid: vec![0; n],
            retrace_queries: vec![0; n],
        }
    }

    fn add(&mut self, o: &Counts) {
        for (a, b) in [
            (&mut self.landed, &o.landed),
            (&mut self.reused, &o.reused),
            (&mut self.partial, &o.partial),
            (&mut self.retraced, &o.retraced),
            (&mut self.prefix, &o.prefix),
            (&mut self.on_deformed, &o.on_deformed),
            (&mut self.invalid, &o.invalid),
            (&mut self.retrace_queries, &o.retrace_queries),
        ] {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
    }
}

/// Ray queries (closest-hit and shadow) counted in `s`.
fn queries(s: &Stats) -> u64 {
    s.rays + s.shadow_rays
}

/// Ray-query cost in closest-hit units ([`SHADOW_QUERY_COST`]).
fn query_cost(s: &Stats) -> f64 {
    s.rays as f64 + SHADOW_QUERY_COST * s.shadow_rays as f64
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
    hits: Option<&'a mut Vec<Option<Hit>>>,
) -> impl FnMut(&Ray) -> Option<Hit> + 'a {
    masks.clear();
    let mut rays = rays;
    if let Some(r) = rays.as_deref_mut() {
        r.clear();
    }
    let mut hits = hits;
    if let Some(h) = hits.as_deref_mut() {
        h.clear();
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
        if let Some(h) = hits.as_deref_mut() {
            h.push(hf);
        }
        hf
    }
}

/// The rays of a subpath regenerated in a window frame g from f's stream (light or
/// camera): the first `n` are f's rays and give f's hits in g (the multi-frame masks), so
/// they are answered with f's `hits` without a traversal; the others are traced in g.
struct ReproducedPrefix<'h> {
    hits: &'h [Option<Hit>],
    n: usize,
    next: usize,
}

impl<'h> ReproducedPrefix<'h> {
    fn new(hits: &'h [Option<Hit>], n: usize) -> Self {
        ReproducedPrefix { hits, n, next: 0 }
    }

    /// The answer to the walk's next ray.
    fn trace(&mut self, scene_g: &FrameScene, ray: &Ray) -> Option<Hit> {
        let i = self.next;
        self.next += 1;
        if i < self.n {
            self.hits[i]
        } else {
            scene_g.intersect(ray)
        }
    }

    /// Rays answered from f's hits (not traced, so not counted as g's rays).
    fn answered(&self) -> u64 {
        self.next.min(self.n) as u64
    }
}

/// Per-thread scratch buffers.
#[derive(Default)]
pub(super) struct Scratch {
    cam: Vec<Vertex>,
    cam_rays: Vec<Ray>,
    /// Frame f's hits of the camera subpath's rays.
    cam_hits: Vec<Option<Hit>>,
    /// Per traced ray of the camera / light subpath: the window frames reproducing it.
    cam_masks: Vec<FrameMask>,
    light_masks: Vec<FrameMask>,
    /// Frame f's hits of the light subpath's rays.
    light_hits: Vec<Option<Hit>>,
    /// Per light vertex i: the window frames in which vertices 0..=i are reproduced (same
    /// lights and materials, the rays that made vertices 1..=i give f's hits).
    light_prefix: Vec<FrameMask>,
    wh: WindowHit,
    light: Vec<Vertex>,
    light_g: Vec<Vertex>,
    cam_g: Vec<Vertex>,
    entries: Vec<Entry>,
    /// Frame f's light-tracing splats: (light vertices s, pixel, value, frames where
    /// unoccluded).
    splats: Vec<(usize, u32, Rgb, FrameMask)>,
}

/// Most frames whose samples at a pixel share one sequence (module doc, "Sample streams").
const STREAM_BLOCK: u32 = 1024;

/// The stream of sample `index` of frame `f` at a pixel (module doc, "Sample streams"):
/// the block key (passed as the sampler's frame) and the sample's index in the block's
/// sequence. Frame f is the (f / n)-th frame generating the pixel (`n`: the interleave),
/// so the frames generating a pixel take consecutive runs of `spp` indices: never a
/// strided subsequence, whose Sobol points would share their leading digits.
pub fn stream_index(f: u32, n: u32, spp: u32, index: u32) -> (u32, u32) {
    // At most STREAM_BLOCK frames, and no more than the Sobol points there are.
    let len = (SOBOL_MAX_SAMPLES / spp.max(1)).clamp(1, STREAM_BLOCK);
    let round = f / n.max(1);
    (round / len, (round % len) * spp + index)
}

/// A sample landed in window frame `j` at `raster` with `value` (buffered until the
/// sample is complete, so a motion-blurred landing can use the sample's values in the
/// neighbouring frames).
#[derive(Clone, Copy)]
pub(super) struct Landed {
    pub(super) j: usize,
    pub(super) raster: Vec2,
    pub(super) value: Rgb,
    /// Motion blur: raster positions of the sample's point one frame before / after.
    pub(super) around: [Option<Vec2>; 2],
    /// The landing shows the point the sample found in its own frame (own frame or
    /// reuse), so its values in two frames are the radiance of one point at two times;
    /// a re-traced landing may show another point.
    pub(super) same_point: bool,
}

/// Output of one tile of one pass.
pub(super) struct TileOut {
    pub(super) batch: Vec<Contribution>,
    pub(super) squares: Vec<Contribution>,
    pub(super) splats: Vec<Contribution>,
    /// Motion blur: per landed sample, its raster offsets to where its point is seen one
    /// frame before / after, and its values there (films `film_blur[0..4]`).
    pub(super) blur: [Vec<Contribution>; 4],
    /// Pilot (strategy choice): per own sample of f, (pixel, luminance of the camera part
    /// with the generation's strategies, of the path strategies' estimate).
    pub(super) pilot: Vec<(u32, f64, f64, f64)>,
    /// Pilot: the path strategies' second moment estimated from the light-tracing splats
    /// of f's own samples, (pixel, term) ([`Generation::path_moment`]).
    pub(super) pilot_splats: Vec<(u32, f64)>,
    /// Pilot: luminance of f's own contributions from paths the path strategies cannot
    /// make, and of all of them.
    pub(super) unreachable: f64,
    pub(super) reachable: f64,
    /// Pilot: luminance of f's own contributions by strategy group: s ≤ 1 (t ≥ 2), s ≥ 2
    /// with t ≥ 2 (connections), t = 1 (light tracing).
    pub(super) shares: [f64; 3],
    /// Cost (closest-hit units) of the pilot samples' own-frame work, all of it and the
    /// path strategies' part, and their number; the same for f's other samples.
    pub(super) pilot_cost: [f64; 2],
    pub(super) pilot_n: u64,
    pub(super) other_cost: f64,
    pub(super) other_n: u64,
    pub(super) landings: Vec<Landed>,
    pub(super) stats: Vec<Stats>,
    pub(super) counts: Counts,
}

impl TileOut {
    /// Empty, for a window of `n` frames.
    fn new(n: usize) -> Self {
        TileOut {
            batch: Vec::new(),
            squares: Vec::new(),
            splats: Vec::new(),
            blur: Default::default(),
            landings: Vec::new(),
            stats: vec![Stats::default(); n],
            counts: Counts::new(n),
            pilot: Vec::new(),
            pilot_splats: Vec::new(),
            unreachable: 0.0,
            reachable: 0.0,
            shares: [0.0; 3],
            pilot_cost: [0.0; 2],
            pilot_n: 0,
            other_cost: 0.0,
            other_n: 0,
        }
    }
}

/// The sums of one generated frame's tiles, in tile order: per window frame its counts
/// and ray statistics, and the pilot measurement at f.
struct Totals {
    counts: Counts,
    stats: Vec<Stats>,
    pilot: Pilot,
}

impl Totals {
    /// Adds one tile's output (generated in frame `f`); `rho` and `rho_measured` are the
    /// shares of f's pixels whose samples use all strategies / are measured.
    fn add(&mut self, r: &TileOut, f: u32, rho: f64, rho_measured: f64) {
        let pilot = &mut self.pilot;
        self.counts.add(&r.counts);
        for (a, b) in self.stats.iter_mut().zip(&r.stats) {
            *a += *b;
        }
        for &(pixel, b, p, m) in &r.pilot {
            pilot.add_sample(pixel, b, p, m);
        }
        for &(pixel, m) in &r.pilot_splats {
            pilot.moment[pixel as usize] += m / rho_measured;
        }
        pilot.unreachable += r.unreachable;
        pilot.reachable += r.reachable;
        for (a, b) in pilot.shares.iter_mut().zip(r.shares) {
            *a += b;
        }
        pilot.cost_bdpt += r.pilot_cost[0];
        pilot.cost_path += r.pilot_cost[1];
        pilot.samples += r.pilot_n;
        pilot.other_cost += r.other_cost;
        pilot.other_samples += r.other_n;
        // Splats come from a share rho of the samples' light subpaths: scaled to what
        // every sample's would give.
        for c in r.splats.iter().filter(|c| c.splat && c.frame == f) {
            pilot.splat_sq[c.pixel as usize] += luminance(c.value).powi(2) / rho;
        }
    }
}

/// What differs between f and each frame of its window (and, for motion blur, between
/// neighbouring frames): every decision of the samples about the scene is read from
/// these.
struct WindowChanges {
    from_f: Vec<FrameDelta>,
    steps: Vec<FrameDelta>,
    /// Frames with f's lights (and scene bounds), f's materials, f's camera.
    lights_same: FrameMask,
    materials_same: FrameMask,
    same_camera: FrameMask,
}

impl WindowChanges {
    fn new(scenes: &[Arc<FrameScene>], jf: usize, blur: bool) -> Self {
        let from_f: Vec<FrameDelta> = scenes
            .iter()
            .map(|s| FrameDelta::between(&scenes[jf], s))
            .collect();
        let steps: Vec<FrameDelta> = if blur {
            scenes
                .windows(2)
                .map(|w| FrameDelta::between(&w[0], &w[1]))
                .collect()
        } else {
            Vec::new()
        };
        let mut lights_same: FrameMask = 0;
        let mut materials_same: FrameMask = 0;
        let mut same_camera: FrameMask = 0;
        for (j, d) in from_f.iter().enumerate() {
            // Light subpaths and light samples depend on the lights and, through lights
            // at infinity, on the scene's bounding sphere; a change of the bounds counts
            // in any case (conservative where no light is at infinity).
            if !(d.lights_changed() || d.bounds_changed()) {
                lights_same |= 1 << j;
            }
            if !d.materials_changed() {
                materials_same |= 1 << j;
            }
            if !d.camera_changed() {
                same_camera |= 1 << j;
            }
        }
        WindowChanges {
            from_f,
            steps,
            lights_same,
            materials_same,
            same_camera,
        }
    }
}

/// The pixels generating samples, and of all of f's `w × h` pixels (not of the generating
/// ones) the shares whose samples use all strategies and are measured: they normalise
/// per-pixel sums of light subpaths over the whole image.
fn pixel_shares(
    w: u32,
    h: u32,
    gen_at: impl Fn(u32, u32) -> bool,
    all_at: impl Fn(u32, u32) -> bool,
    measured_at: impl Fn(u32, u32) -> bool,
) -> (usize, f64, f64) {
    let (mut generating, mut with_all, mut measured) = (0usize, 0usize, 0usize);
    for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
        if gen_at(x, y) {
            generating += 1;
            with_all += usize::from(all_at(x, y));
            measured += usize::from(measured_at(x, y));
        }
    }
    let rho = with_all as f64 / (w as f64 * h as f64).max(1.0);
    let rho_measured = measured as f64 / (w as f64 * h as f64).max(1.0);
    (generating, rho, rho_measured)
}

impl Generation<'_> {
    /// The path strategies' second moment for the path of connection `c` (strategy (s, t)
    /// of f), estimated by importance sampling from BDPT's sample (module doc, "BDPT or
    /// the path strategies"): `Y(c) · Y(c / w) · Σ_A w'² p_u / p_{s'}` (Y: luminance), A the path strategies
    /// able to make the path (s′ ≤ 1, t′ ≥ 2), w' their weights among themselves. `None`
    /// when no path strategy can make it.
    fn path_moment(
        &self,
        light: &[Vertex],
        cam: &[Vertex],
        c: &Connection,
        s: usize,
        t: usize,
        ratios: &mut Vec<(usize, f32)>,
    ) -> Option<f64> {
        let scene_f = &self.scenes[self.jf];
        strategy_ratios(
            scene_f,
            self.bdpt,
            light,
            cam,
            c.sampled.as_ref(),
            s,
            t,
            ratios,
        );
        let (mut r2, mut r3, mut r1) = (0.0f64, 0.0f64, 0.0f64);
        for &(sp, r) in ratios.iter() {
            if sp <= 1 && s + t - sp >= 2 && r > 0.0 {
                let r = r as f64;
                r1 += r;
                r2 += r * r;
                r3 += r * r * r;
            }
        }
        let factor = match self.bdpt.mis {
            // w' = r² / Σ r²: Σ w'² / r = Σ r³ / (Σ r²)².
            MisHeuristic::Power if r2 > 0.0 => r3 / (r2 * r2),
            // w' = r / Σ r: Σ w'² / r = 1 / Σ r.
            MisHeuristic::Balance if r1 > 0.0 => 1.0 / r1,
            _ => return None,
        };
        Some(luminance(c.unweighted) * luminance(c.contribution.l) * factor)
    }

    /// The t = 1 strategies of `light` with at least `s_min` light vertices in frame `j`,
    /// splatted into `out`. With `record` (frame f only), shadow rays are answered for the
    /// whole window and every splat is recorded with its s and the frames it is unoccluded
    /// in, for the frames that share f's camera.
    #[allow(clippy::too_many_arguments)] // reason: the subpaths, the frame and the outputs
    fn light_trace(
        &self,
        j: usize,
        light: &[Vertex],
        camera: &[Vertex],
        conn: &PixelSampler,
        s_min: usize,
        out: &mut TileOut,
        invalid: &mut u64,
        mut record: Option<&mut Vec<(usize, u32, Rgb, FrameMask)>>,
    ) {
        if !self.bdpt.light_tracing {
            return;
        }
        let scene = &self.scenes[j];
        let (w, h) = (scene.camera.width, scene.camera.height);
        let max_segments = self.bdpt.depth() as usize;
        let mut sampler = conn.clone();
        let all = self.mfa.all_frames();
        for s in s_min.max(2)..=light.len() {
            if s > max_segments {
                break;
            }
            let mut vis: FrameMask = 1 << j;
            // Recording: the shadow ray answered for the whole window; otherwise for j.
            let windowed = record.is_some();
            let conn = connect_with(
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
            );
            let Some(conn) = conn else { continue };
            let c = conn.contribution;
            let Some(r) = c.raster else { continue };
            if !c.l.is_finite() {
                *invalid += 1;
                continue;
            }
            let (x, y) = (r.x as u32, r.y as u32);
            if r.x >= 0.0 && r.y >= 0.0 && x < w && y < h {
                if self.pilot && j == self.jf && vis >> j & 1 == 1 {
                    let mut ratios = Vec::new();
                    let lum = luminance(c.l);
                    out.reachable += lum;
                    out.shares[2] += lum;
                    match self.path_moment(light, camera, &conn, s, 1, &mut ratios) {
                        Some(m) => out.pilot_splats.push((y * w + x, m)),
                        None => out.unreachable += lum,
                    }
                }
                if let Some(rec) = record.as_deref_mut() {
                    rec.push((s, y * w + x, c.l, vis));
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

    fn land(
        out: &mut TileOut,
        j: usize,
        raster: Vec2,
        value: Rgb,
        around: [Option<Vec2>; 2],
        same_point: bool,
    ) {
        out.landings.push(Landed {
            j,
            raster,
            value,
            around,
            same_point,
        });
    }

    /// The shading split of a sample at its first eye vertex x1 (module doc, "Per sample"):
    /// every strategy t ≥ 2 of `cam` and `light` evaluated in f, its shadow ray answered
    /// for the whole window, written into `entries` as `f(x1, wo, wi_k) ⊙ R_k` (R_k: all
    /// but x1's BSDF for f's view). Returns x1's own emission (s = 0, t = 2) with its MIS
    /// weight, kept apart because it is re-evaluated towards another view. Adds to
    /// `pilot` the path strategies' value in f, their cost and the correction of their
    /// second moment, and to `reach` the luminance unreachable by them, in all and per
    /// strategy group (with [`Generation::pilot`]; the value and cost always).
    #[allow(clippy::too_many_arguments)] // reason: the subpaths, the streams and the pilot's sums
    fn split_at_x1(
        &self,
        light: &[Vertex],
        cam: &[Vertex],
        cam_rays: &[Ray],
        ns: &PixelSampler,
        entries: &mut Vec<Entry>,
        st: &mut Stats,
        pilot: &mut (Rgb, f64, f64),
        out_reach: &mut (f64, f64, [f64; 3]),
    ) -> Option<(Rgb, f32)> {
        let scene_f = &self.scenes[self.jf];
        let all = self.mfa.all_frames();
        let max_segments = self.bdpt.depth() as usize;
        entries.clear();
        let mut emission: Option<(Rgb, f32)> = None;
        let mut sampler = ns.clone();
        let jf = self.jf;
        let mut ratios = Vec::new();
        // Some window frame has another camera: the entries keep their weights' split.
        let split_weights = self.bdpt.light_tracing && self.same_camera != all;
        for t in 2..=cam.len() {
            for s in 0..=self.bdpt.max_light_vertices(light.len()) {
                if s + t - 1 > max_segments {
                    continue;
                }
                let before = query_cost(st);
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
                if self.pilot
                    && let Some(c) = &c
                    && vis >> jf & 1 == 1
                {
                    let lum = luminance(c.contribution.l);
                    out_reach.1 += lum;
                    out_reach.2[usize::from(s >= 2)] += lum;
                    match self.path_moment(light, cam, c, s, t, &mut ratios) {
                        Some(m) => pilot.2 += m,
                        None => out_reach.0 += lum,
                    }
                }
                if s <= 1 {
                    let (value, cost, moment) = (&mut pilot.0, &mut pilot.1, &mut pilot.2);
                    // The path strategies' part: its queries, and its value in f with
                    // the path strategies' MIS weights (the same unweighted contribution).
                    *cost += query_cost(st) - before;
                    if let Some(c) = &c
                        && vis >> jf & 1 == 1
                    {
                        let w = if self.bdpt.path_strategies || !self.pilot {
                            c.weight
                        } else {
                            mis_weight(
                                scene_f,
                                self.path_bdpt,
                                light,
                                cam,
                                c.sampled.as_ref(),
                                s,
                                t,
                            )
                        };
                        let cp = c.unweighted * w;
                        *value += cp;
                        // Its square: the sampled counterpart of the importance-sampled
                        // diagonal term above.
                        if self.pilot {
                            *moment -= luminance(cp).powi(2);
                        }
                    }
                }
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
                    cam_rays[1].d.normalize()
                };
                let fv = sv.bsdf.f(sv.wo, wi, TransportMode::Radiance);
                let r = Rgb::new(
                    if fv.x != 0.0 { l.x / fv.x } else { 0.0 },
                    if fv.y != 0.0 { l.y / fv.y } else { 0.0 },
                    if fv.z != 0.0 { l.z / fv.z } else { 0.0 },
                );
                let split = split_weights
                    .then(|| view_split(scene_f, self.bdpt, light, cam, c.sampled.as_ref(), s, t))
                    .flatten();
                let pdf_f = if split.is_some() {
                    sv.bsdf.pdf(sv.wo, wi)
                } else {
                    0.0
                };
                entries.push(Entry {
                    s,
                    t,
                    wi,
                    r,
                    c: l,
                    continuation: t >= 3,
                    vis,
                    split,
                    pdf_f,
                });
            }
        }
        emission
    }

    /// One sample: generated in f, landed/reused/re-traced in every window frame. The
    /// phases: [`Generation::trace_in_f`] (the subpaths, through the window structure),
    /// [`Generation::validity`] (which frames reproduce which segments),
    /// [`Generation::serve_own_frame`] (the ordinary BDPT sample in f, and the
    /// view-independent part at x1), then per other window frame the light part
    /// ([`Generation::light_part_in`]) and the camera part
    /// ([`Generation::camera_part_in`]).
    pub(super) fn sample(&self, px: u32, py: u32, index: u32, sc: &mut Scratch, out: &mut TileOut) {
        let traced = self.trace_in_f(px, py, index, sc, out);
        let valid = self.validity(sc);
        let own = self.serve_own_frame(&traced, sc, out);
        // Landing visibility of x1 from f's eye, answered once for the whole window (the
        // same ray in every frame where x1 and the eye do not move).
        let mut land_occ: Option<FrameMask> = None;
        for j in (0..self.scenes.len()).filter(|&j| j != self.jf) {
            let mut inv = 0u64;
            let light_kept = self.light_part_in(j, &traced, &valid, sc, out, &mut inv);
            self.camera_part_in(
                j,
                &traced,
                &valid,
                &own,
                light_kept,
                sc,
                out,
                &mut land_occ,
                inv,
            );
        }
        self.flush(out);
    }

    /// Phase 1 of [`Generation::sample`]: the camera and light subpaths in f, each ray's
    /// validity in the window frames recorded with its hit (into `sc`).
    fn trace_in_f(
        &self,
        px: u32,
        py: u32,
        index: u32,
        sc: &mut Scratch,
        out: &mut TileOut,
    ) -> Traced {
        let (seed, f, jf) = (self.bdpt.common.seed, self.f, self.jf);
        let scene_f = &self.scenes[jf];
        // One sequence per pixel for the frames of a block (module doc, "Sample streams"):
        // the samples the frames of a window land in a pixel are stratified together.
        let (block, idx) = stream_index(f, self.interleave, self.bdpt.common.spp, index);
        let mut cs = PixelSampler::new(seed, block, px, py);
        cs.start_sample(idx);
        let mut ls = PixelSampler::new(seed ^ LIGHT_STREAM, block, px, py);
        ls.start_sample(idx);
        let mut ns = PixelSampler::new(seed ^ CONNECTION_STREAM, block, px, py);
        ns.start_sample(idx);
        let raster = Vec2::new(px as f32, py as f32) + cs.next_2d();
        let cs0 = cs.clone();
        let ls0 = ls.clone();
        let st = &mut out.stats[jf];
        let cost0 = query_cost(st);
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
                Some(&mut sc.cam_hits),
            ),
        );
        let cam_cost = query_cost(st) - cost0;
        if self.bdpt.path_strategies {
            // No light subpath: valid wherever the lights and materials are f's.
            sc.light.clear();
            sc.light_masks.clear();
            sc.light_hits.clear();
        } else {
            generate_light_subpath_with(
                scene_f,
                self.bdpt,
                &mut ls,
                &mut sc.light,
                st,
                &mut window_trace(
                    self.mfa,
                    scene_f,
                    jf,
                    &mut sc.wh,
                    &mut sc.light_masks,
                    None,
                    Some(&mut sc.light_hits),
                ),
            );
        }
        st.samples += 1;
        Traced {
            raster,
            cs0,
            ls0,
            ns,
            cost0,
            cam_cost,
        }
    }

    /// Phase 2 of [`Generation::sample`]: the frames in which the sampled segments are
    /// reproduced (module doc, "Valid prefixes"); fills `sc.light_prefix`.
    fn validity(&self, sc: &mut Scratch) -> Validity {
        let (n, jf) = (self.scenes.len(), self.jf);
        let all = self.mfa.all_frames();
        let and = |m: &[FrameMask]| m.iter().fold(all, |a, b| a & b);
        // The light subpath's vertices depend on the lights and on the materials of the
        // surfaces it meets.
        let light_same = self.lights_same & self.materials_same;
        let light_valid = and(&sc.light_masks) & light_same;
        sc.light_prefix.clear();
        sc.light_prefix.push(light_same);
        for (i, &m) in sc
            .light_masks
            .iter()
            .enumerate()
            .take(sc.light.len().saturating_sub(1))
        {
            let prev = sc.light_prefix[i];
            sc.light_prefix.push(prev & m);
        }
        let x1 = first_surface(&sc.cam);
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
        Validity {
            light_valid,
            cam_segments,
            cam_valid,
            x1_bary: x1.and_then(|v| barycentrics(&self.scenes[jf], v)),
        }
    }

    /// Phase 3 of [`Generation::sample`]: the view-independent part at x1 (t ≥ 2, shadow
    /// rays answered for the whole window) and the ordinary BDPT sample in f, landed with
    /// its light-tracing splats (recorded in `sc.splats` for the other frames).
    fn serve_own_frame(&self, traced: &Traced, sc: &mut Scratch, out: &mut TileOut) -> Own {
        let jf = self.jf;
        let n = self.scenes.len();
        let scene_f = &self.scenes[jf];
        let (cam, light) = (&sc.cam, &sc.light);
        let mut pilot = (Rgb::ZERO, traced.cam_cost, 0.0);
        let mut reach = (0.0, 0.0, [0.0; 3]);
        let emission = self.split_at_x1(
            light,
            cam,
            &sc.cam_rays,
            &traced.ns,
            &mut sc.entries,
            &mut out.stats[jf],
            &mut pilot,
            &mut reach,
        );
        out.unreachable += reach.0;
        out.reachable += reach.1;
        for (a, b) in out.shares.iter_mut().zip(reach.2) {
            *a += b;
        }

        let mut own = emission.map_or(Rgb::ZERO, |(l, _)| l);
        for e in &sc.entries {
            if e.vis >> jf & 1 == 1 {
                own += e.c;
            }
        }
        let (path_value, path_cost, path_moment) = pilot;
        let raster = traced.raster;
        if self.pilot {
            out.pilot_cost[1] += path_cost;
            if own.is_finite() && path_value.is_finite() {
                let (w, h) = (scene_f.camera.width, scene_f.camera.height);
                let pixel = (raster.y as u32).min(h - 1) * w + (raster.x as u32).min(w - 1);
                out.pilot
                    .push((pixel, luminance(own), luminance(path_value), path_moment));
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
        self.light_trace(jf, light, cam, &traced.ns, 2, out, &mut inv, record);
        out.counts.invalid[jf] += inv;
        let own_cost = query_cost(&out.stats[jf]) - traced.cost0;
        if self.pilot {
            out.pilot_cost[0] += own_cost;
            out.pilot_n += 1;
        } else {
            out.other_cost += own_cost;
            out.other_n += 1;
        }
        Own {
            value: own,
            emission,
        }
    }

    /// Phase 4a of [`Generation::sample`], window frame `j`: the light subpath reused, or
    /// regenerated from the same light stream (into `sc.light_g`) with its reproduced
    /// prefix answered from f's hits, and its light-tracing splats. Returns how many
    /// light vertices g reproduces (module doc, "Valid prefixes").
    fn light_part_in(
        &self,
        j: usize,
        traced: &Traced,
        valid: &Validity,
        sc: &mut Scratch,
        out: &mut TileOut,
        inv: &mut u64,
    ) -> usize {
        let scene_g = &self.scenes[j];
        let frame_g = self.frames[j];
        let (cam, light) = (&sc.cam, &sc.light);
        let light_ok = valid.light_valid >> j & 1 == 1;
        let light_kept = sc
            .light_prefix
            .iter()
            .take_while(|&&m| m >> j & 1 == 1)
            .count();
        if !light_ok && self.bdpt.path_strategies {
            sc.light_g.clear();
        } else if !light_ok {
            // Regenerated from the same stream: the rays of the reproduced prefix are
            // f's rays with f's hits in g, answered without a traversal.
            let mut l2 = traced.ls0.clone();
            // Ray i leaves vertex i and makes vertex i + 1: the first light_kept − 1
            // rays made reproduced vertices.
            let mut prefix = ReproducedPrefix::new(&sc.light_hits, light_kept.saturating_sub(1));
            generate_light_subpath_with(
                scene_g,
                self.bdpt,
                &mut l2,
                &mut sc.light_g,
                &mut out.stats[j],
                &mut |r| prefix.trace(scene_g, r),
            );
            out.stats[j].rays -= prefix.answered();
        }
        let same_camera = self.same_camera >> j & 1 == 1;
        if same_camera {
            // Same camera: the splats of the reproduced light vertices are f's, where
            // unoccluded in g; the others are made from g's light subpath.
            for &(s, pixel, value, vis) in &sc.splats {
                if s <= light_kept && vis >> j & 1 == 1 {
                    out.splats.push(Contribution {
                        frame: frame_g,
                        pixel,
                        value,
                        weight: 0.0,
                        splat: true,
                    });
                }
            }
            if !light_ok {
                self.light_trace(
                    j,
                    &sc.light_g,
                    cam,
                    &traced.ns,
                    light_kept + 1,
                    out,
                    inv,
                    None,
                );
            }
        } else {
            let light_g: &[Vertex] = if light_ok { light } else { &sc.light_g };
            self.light_trace(j, light_g, cam, &traced.ns, 2, out, inv, None);
        }
        light_kept
    }

    /// Phase 4b of [`Generation::sample`], window frame `j`: where the sample lands in g
    /// ([`Generation::landing`]) and how it serves g there: f's value (an escaped ray),
    /// the view-independent part reused (all strategies, or those s ≤ 1 with g's light
    /// subpath for the rest), or the camera subpath re-traced in g (from f's reproduced
    /// prefix when there is one).
    #[allow(clippy::too_many_arguments)]
    fn camera_part_in(
        &self,
        j: usize,
        traced: &Traced,
        valid: &Validity,
        own: &Own,
        light_kept: usize,
        sc: &mut Scratch,
        out: &mut TileOut,
        land_occ: &mut Option<FrameMask>,
        mut inv: u64,
    ) {
        let scene_g = &self.scenes[j];
        let (cam, light) = (&sc.cam, &sc.light);
        let x1 = first_surface(cam);
        let walk = Walk {
            x1,
            x1_bary: valid.x1_bary,
            escape: sc.cam_rays.first().copied(),
            cam_valid: valid.cam_valid,
            cam_segments: valid.cam_segments,
        };
        let landing = self.landing(j, &walk, land_occ, &mut out.stats);
        let esc_dir = sc.cam_rays.first().map(|r| r.d);
        let light_ok = valid.light_valid >> j & 1 == 1;
        let light_g: &[Vertex] = if light_ok { light } else { &sc.light_g };
        let mut around = [None, None];
        if matches!(
            landing,
            Landing::Reuse(_) | Landing::Partial(_) | Landing::RetracePrefix(_)
        ) && x1
            .and_then(|v| v.surface.as_ref())
            .is_some_and(|sv| self.from_f[j].instance_deformed(sv.si.instance as usize))
        {
            out.counts.on_deformed[j] += 1;
        }
        let raster = traced.raster;
        let (raster_g, value, same_point) = match landing {
            Landing::Missed => {
                out.counts.invalid[j] += inv;
                return;
            }
            Landing::ReuseEscaped(r) => {
                out.counts.reused[j] += 1;
                around = self.trajectory(j, self.jf, None, esc_dir);
                (r, own.value, true)
            }
            Landing::Reuse(r) | Landing::Partial(r) => {
                let partial = matches!(landing, Landing::Partial(_));
                around = self.trajectory(j, self.jf, x1, esc_dir);
                let v = x1.expect("reuse needs x1 on a surface");
                let regenerated = partial.then_some(Regenerated {
                    light: &sc.light_g,
                    cam,
                    cam_rays: &sc.cam_rays,
                    kept: light_kept,
                });
                let l = self.reused_value(
                    j,
                    v,
                    own.emission,
                    &sc.entries,
                    regenerated,
                    &traced.ns,
                    &mut out.stats[j],
                );
                if partial {
                    out.counts.partial[j] += 1;
                }
                out.counts.reused[j] += 1;
                (r, l, true)
            }
            Landing::RetracePrefix(r) => {
                out.counts.retraced[j] += 1;
                let before = queries(&out.stats[j]);
                // Camera vertices 0..=kept are f's in g (the rays that made them give
                // f's hits, same materials): re-traced from f's raster position, those
                // rays answered with f's hits, the strategies on reproduced vertices
                // only taken from f (module doc, "Reuse in frame g", step 3).
                let kept = if self.materials_same >> j & 1 == 1 {
                    sc.cam_masks
                        .iter()
                        .take_while(|&&m| m >> j & 1 == 1)
                        .count()
                } else {
                    0
                };
                if kept >= 1 {
                    out.counts.prefix[j] += 1;
                }
                let cam_g: &[Vertex] = if kept == sc.cam_masks.len() {
                    cam
                } else {
                    let mut c2 = traced.cs0.clone();
                    let mut prefix = ReproducedPrefix::new(&sc.cam_hits, kept);
                    generate_camera_subpath_with(
                        scene_g,
                        self.bdpt,
                        raster,
                        &mut c2,
                        &mut sc.cam_g,
                        &mut out.stats[j],
                        &mut |ray| prefix.trace(scene_g, ray),
                    );
                    out.stats[j].rays -= prefix.answered();
                    if self.shutter > 0.0 {
                        let d = scene_g.camera.generate_ray(raster).d;
                        around = self.trajectory(j, j, sc.cam_g.get(1), Some(d));
                    }
                    &sc.cam_g
                };
                let reproduced = Reproduced {
                    camera: kept,
                    light: light_kept,
                    entries: &sc.entries,
                    emission: own.emission,
                };
                let l = self.prefix_strategies(
                    j,
                    light_g,
                    cam_g,
                    &traced.ns,
                    &reproduced,
                    &mut out.stats[j],
                );
                out.counts.retrace_queries[j] += queries(&out.stats[j]) - before;
                (r, l, false)
            }
            Landing::Retrace(r) => {
                let before = queries(&out.stats[j]);
                let mut c2 = traced.cs0.clone();
                generate_camera_subpath(
                    scene_g,
                    self.bdpt,
                    r,
                    &mut c2,
                    &mut sc.cam_g,
                    &mut out.stats[j],
                );
                out.counts.retraced[j] += 1;
                if self.shutter > 0.0 {
                    let d = scene_g.camera.generate_ray(r).d;
                    around = self.trajectory(j, j, sc.cam_g.get(1), Some(d));
                }
                let l =
                    self.camera_strategies(j, light_g, &sc.cam_g, &traced.ns, &mut out.stats[j]);
                out.counts.retrace_queries[j] += queries(&out.stats[j]) - before;
                (r, l, false)
            }
        };
        out.counts.landed[j] += 1;
        if value.is_finite() {
            Self::land(out, j, raster_g, value, around, same_point);
        } else {
            inv += 1;
            Self::land(out, j, raster_g, Rgb::ZERO, around, same_point);
        }
        out.counts.invalid[j] += inv;
    }
}

/// What [`Generation::trace_in_f`] leaves for the later phases of a sample.
struct Traced {
    /// The sample's raster position in f.
    raster: Vec2,
    /// The camera and light samplers at the start of their subpaths (to regenerate them
    /// in another frame from the same numbers).
    cs0: PixelSampler,
    ls0: PixelSampler,
    /// The connection stream.
    ns: PixelSampler,
    /// Query cost in f before the sample, and that of its camera subpath.
    cost0: f64,
    cam_cost: f64,
}

/// The frames reproducing a sample's segments ([`Generation::validity`]).
struct Validity {
    /// Frames reproducing the whole light subpath, with f's lights and materials.
    light_valid: FrameMask,
    /// As [`Walk::cam_segments`] and [`Walk::cam_valid`].
    cam_segments: FrameMask,
    cam_valid: FrameMask,
    /// x1's barycentrics on its triangle in f.
    x1_bary: Option<(f32, f32)>,
}

/// The sample's value in f and its emission part ([`Generation::serve_own_frame`]).
struct Own {
    value: Rgb,
    emission: Option<(Rgb, f32)>,
}

/// The first eye vertex when it is on a surface.
fn first_surface(cam: &[Vertex]) -> Option<&Vertex> {
    cam.get(1).filter(|v| v.kind == VertexKind::Surface)
}

impl Stbpt {
    /// Generates the samples of frame `f` of the render list: without adaptivity at the
    /// cap K with the strategies of the settings; with it, a grid frame ([`adapt::GRID`])
    /// at the cap K with the measurements, any other frame with the K and strategies its
    /// grid frame chose (generating that grid frame first when this process has not:
    /// a farm segment starting after it).
    pub(super) fn generate_next(
        &mut self,
        source: &mut FrameSource,
        f: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) {
        let cap = self.k();
        let path = self.settings.bdpt.path_strategies;
        if !self.settings.adaptive {
            let mode = if path { Mode::Path } else { Mode::Bdpt };
            let frames = source.window(f, cap, cap);
            return self.generate(source, f, cap, mode, frames, progress);
        }
        let g = f - f % adapt::GRID;
        if !self.grid.contains_key(&g) {
            self.generate_grid(source, g, progress);
        }
        if f != g {
            let (k, mode) = self.grid[&g];
            let frames = source.window(f, k, k);
            self.generate(source, f, k, mode, frames, progress);
        }
        // Older grid frames are not needed any more (frames come in increasing order).
        self.grid.retain(|&h, _| h >= g);
    }

    /// Generates grid frame `g` (module doc, "Choosing K"): at the cap K, all strategies
    /// measuring at the pilot pixels (a pilot frame when `path_strategies` is set), over
    /// every frame within the cap whether in the render list or not, so that its
    /// measurement, and with it every decision it makes, is the same in any process that
    /// renders any part of the clip. Its landings serve the frames of the render list.
    fn generate_grid(&mut self, source: &mut FrameSource, g: u32, progress: &(dyn Fn(u64) + Sync)) {
        let cap = self.k();
        let mode = if self.settings.bdpt.path_strategies {
            Mode::Pilot
        } else {
            Mode::Bdpt
        };
        let frames: Vec<u32> = (g.saturating_sub(cap)..=g.saturating_add(cap)).collect();
        self.generate(source, g, cap, mode, frames, progress);
    }

    /// Generates the samples of frame `f` with window half-width `k` and strategies `mode`
    /// over window `frames`, adds them to every frame of the window that is in the render
    /// list and assesses what serving each distance gave ([`adapt::assess`],
    /// [`strategies::decide`]): on a grid frame, the choices of the frames up to the next.
    fn generate(
        &mut self,
        source: &mut FrameSource,
        f: u32,
        k: u32,
        mode: Mode,
        frames: Vec<u32>,
        progress: &(dyn Fn(u64) + Sync),
    ) {
        let list = source.frames().to_vec();
        let in_list = |g: u32| list.binary_search(&g).is_ok();
        let scenes: Vec<Arc<FrameScene>> = frames.iter().map(|&g| source.frame(g)).collect();
        let jf = frames
            .iter()
            .position(|&g| g == f)
            .expect("f is in its window");
        let accels: Vec<_> = scenes.iter().map(|s| &s.accel).collect();
        let mfa = MultiFrameAccel::new(frames[0], &accels);
        let WindowChanges {
            from_f,
            steps,
            lights_same,
            materials_same,
            same_camera,
        } = WindowChanges::new(&scenes, jf, self.settings.shutter > 0.0);
        self.open_films(scenes[jf].camera.width, scenes[jf].camera.height);
        // Under a moving camera the entries reused in a frame with another camera are
        // re-weighted for it (module doc, "MIS weights in another frame"). The path
        // strategies have no light tracing.
        let light_tracing = self.settings.bdpt.light_tracing;
        let bdpt = BdptSettings {
            light_tracing,
            path_strategies: false,
            ..self.settings.bdpt.clone()
        };
        let path_bdpt = BdptSettings {
            light_tracing: false,
            path_strategies: true,
            ..bdpt.clone()
        };
        let adaptive = self.settings.adaptive;
        let gen_all = Generation {
            same_camera,
            bdpt: &bdpt,
            interleave: self.settings.interleave,
            frames: &frames,
            scenes: &scenes,
            jf,
            f,
            mfa: &mfa,
            lights_same,
            materials_same,
            shutter: self.settings.shutter,
            from_f: &from_f,
            steps: &steps,
            path_bdpt: &path_bdpt,
            pilot: adaptive,
            count_lt: light_tracing && adaptive,
            coverage: &[],
        };
        let mut stats = vec![Stats::default(); frames.len()];
        let coverage = gen_all.coverage(&mut stats);
        let gen_all = Generation {
            coverage: &coverage,
            ..gen_all
        };
        // All strategies without the measurements (a frame with all strategies measures
        // at the pilot pixels only: enough for the comparison, a quarter of its work).
        let gen_quiet = Generation {
            pilot: false,
            ..gen_all
        };
        let gen_path = Generation {
            bdpt: &path_bdpt,
            pilot: false,
            count_lt: false,
            ..gen_all
        };
        // Which samples use all strategies, and their share of the frame's samples; which
        // are measured, and theirs.
        let all_at = |x: u32, y: u32| match mode {
            Mode::Bdpt | Mode::BdptQuiet => true,
            Mode::Path => false,
            Mode::Pilot => pilot_pixel(x, y),
        };
        let measured_at =
            |x: u32, y: u32| matches!(mode, Mode::Bdpt | Mode::Pilot) && pilot_pixel(x, y);
        // The pixels that generate samples in f (all but with `interleave`).
        let interleave = self.settings.interleave;
        let gen_at = |x: u32, y: u32| super::generated_at(x, y, f, interleave);
        let cam = &scenes[jf].camera;
        let (w, h) = (cam.width, cam.height);
        let film = self.film.as_mut().expect("opened");
        let film_sq = self.film_sq.as_mut().expect("opened");
        let film_splat = self.film_splat.as_mut().expect("opened");
        let film_blur = &mut self.film_blur;
        let tiles_x = w.div_ceil(TILE);
        let n_tiles = (tiles_x * h.div_ceil(TILE)) as usize;
        let n = frames.len();
        let spp = self.settings.bdpt.common.spp;
        let mut totals = Totals {
            counts: Counts::new(n),
            stats,
            pilot: Pilot::new(w, h),
        };
        let (generating, rho, rho_measured) = pixel_shares(w, h, gen_at, all_at, measured_at);
        for (s, first) in
            (0..spp).flat_map(|s| (0..n_tiles).step_by(TILES_PER_BATCH).map(move |t| (s, t)))
        {
            let batch_tiles = TILES_PER_BATCH.min(n_tiles - first);
            let results = parallel::map_chunks(batch_tiles, 1, |range| {
                let t = (first + range.start) as u32;
                let (x0, y0, tw, th) = tile_rect(t, tiles_x, TILE, w, h);
                let mut out = TileOut::new(n);
                let mut sc = Scratch::default();
                for y in y0..y0 + th {
                    for x in (x0..x0 + tw).filter(|&x| gen_at(x, y)) {
                        let g = if measured_at(x, y) {
                            &gen_all
                        } else if all_at(x, y) {
                            &gen_quiet
                        } else {
                            &gen_path
                        };
                        g.sample(x, y, s, &mut sc, &mut out);
                    }
                }
                let np = (tw * th) as u64;
                progress(np * (s as u64 + 1) / spp as u64 - np * s as u64 / spp as u64);
                out
            });
            // Landings in frames outside the render list (a grid frame's) only count.
            for r in &results {
                film.add_batch_where(&r.batch, in_list);
                film_sq.add_batch_where(&r.squares, in_list);
                film_splat.add_batch_where(&r.splats, in_list);
                for (film, batch) in film_blur.iter_mut().zip(&r.blur) {
                    film.add_batch_where(batch, in_list);
                }
                totals.add(r, f, rho, rho_measured);
            }
        }
        self.record_served(f, k, mode, &frames, in_list, &totals, generating, rho);
    }

    /// The end of [`Stbpt::generate`]: the counts of every frame of the render list the
    /// samples served (for its report), and what serving each distance gave
    /// ([`adapt::assess`], [`strategies::decide`]): on a grid frame, the choices of the
    /// frames up to the next.
    #[allow(clippy::too_many_arguments)]
    fn record_served(
        &mut self,
        f: u32,
        k: u32,
        mode: Mode,
        frames: &[u32],
        in_list: impl Fn(u32) -> bool,
        totals: &Totals,
        generating: usize,
        rho: f64,
    ) {
        let Totals {
            counts,
            stats,
            pilot,
        } = totals;
        let light_tracing = self.settings.bdpt.light_tracing;
        let adaptive = self.settings.adaptive;
        let spp = self.settings.bdpt.common.spp;
        for (j, &g) in frames.iter().enumerate().filter(|&(_, &g)| in_list(g)) {
            let p = self.pending.entry(g).or_default();
            p.stats += stats[j];
            p.landed += counts.landed[j];
            p.reused += counts.reused[j];
            p.partial += counts.partial[j];
            p.retraced += counts.retraced[j];
            p.retraced_prefix += counts.prefix[j];
            p.on_deformed += counts.on_deformed[j];
            p.invalid += counts.invalid[j];
            p.served_by += 1;
            if light_tracing {
                p.served_by_lt += rho;
            }
            p.served_by_light += rho;
        }
        let generated = (generating as u64 * spp as u64).max(1);
        let (next, mut strategy) = strategies::decide(pilot, spp, mode, adaptive);
        self.served.insert(
            f,
            counts.landed.iter().sum::<u64>() as f64 / generated as f64,
        );
        let served: Vec<adapt::Served> = frames
            .iter()
            .enumerate()
            .map(|(j, &g)| adapt::Served {
                distance: g.abs_diff(f),
                landed: counts.landed[j],
                reused: counts.reused[j],
                retraced: counts.retraced[j],
                stats: stats[j],
                retrace_queries: counts.retrace_queries[j],
            })
            .collect();
        let decision = adapt::assess(
            &served,
            generated,
            k,
            u32::from(self.settings.shutter > 0.0).min(self.k()),
            self.k(),
            self.settings.adaptive,
        );
        let mut decision = decision;
        if adaptive {
            if f.is_multiple_of(adapt::GRID) {
                self.grid.insert(f, (decision.k_next, next));
            } else {
                // The frames up to the next grid frame are made as their grid frame chose.
                let (k_g, mode_g) = self.grid[&(f - f % adapt::GRID)];
                decision.k_next = k_g;
                decision.decision = "grid".to_string();
                strategy.next = strategies::Mode::name(mode_g);
                strategy.decision = "grid".to_string();
            }
        }
        self.strategy_decisions.insert(f, strategy);
        self.decisions.insert(f, decision);
    }
}
