//! Space-time photon density estimation (`spacetime-dept`): DEPT whose element estimates
//! pool photons over a per-element temporal window **centred** on the output frame and
//! then over neighbouring elements, with a bilateral filter that keeps abrupt changes
//! (Myszkowski et al. 2001; Weber et al., "Spatio-temporal photon density estimation using
//! bilateral filtering", CGI 2004).
//!
//! ## Look-ahead
//! Frame f is output after the photons of frames f+1 … f+K (K = `window`) have been
//! traced: each frame's photons are traced **once**, when the frame first enters a window
//! (its scene comes from the [`FrameSource`], which keeps the K + 2 most recent scenes so
//! the output frame's scene is not rebuilt), and its per-element sums stay in memory
//! until the frame leaves the window (memory: O(elements × (2K + 1))). Frame g uses
//! photons `g·N .. (g+1)·N` of the Halton stream (stopping rule: the first of
//! `g·max_photons ..`), the same as the frame-by-frame baselines.
//!
//! ## Per frame f
//! 1. **Change statistic**, once per traced frame g: the indirect + caustic luminance
//!    irradiance of every element side, *spatially pooled* with a Gaussian over
//!    `change_radius` element sizes (ratio estimator, as `dept-spatial`), and its standard
//!    error (from Σφ², see [`crate::kernels::elements::reconstruct`]). An element alone has a handful of
//!    photons per frame, too few to tell a 30 % drop from noise (the first, per-element
//!    test missed the box shutting off BoxAnimated's lamp); the pooled statistic has
//!    ~(change_radius/2)²·π times the photons, so its σ is several times smaller.
//! 2. **Temporal window, per element side**, grown one frame at a time on both sides of f
//!    (frames of the render list within ±K). A candidate frame k is refused, and that side
//!    closed, when it differs from the window so far by a **visible and significant**
//!    amount: `|Δ| > change_threshold · σ_Δ` **and** `|Δ| > change_weber · E_f` (E_f: the
//!    side's total irradiance in frame f, direct included, so sub-threshold drift is
//!    pooled: Myszkowski's perception-based energy test), where Δ is tested twice — frame
//!    k alone against the mean of the window, and the mean of *all* frames from k to the
//!    end of that side against the window (a step change between k−1 and k shifts every
//!    frame beyond it, so pooling them makes the test √(frames beyond) times more
//!    sensitive, like a CUSUM test). Once grown, every split of the window is tested
//!    the same way, the frames on one side of it against the other, and the window is cut
//!    at the most significant split until none fires (binary segmentation), because a
//!    window grown from the output frame alone has too little evidence against a step
//!    right next to it.
//! 3. **Temporal pooling** in the window: ratio estimator `Σ w_k Φ_k / Σ w_k N_k A_k`
//!    (Φ: flux sum, N: photons emitted, A: element area in frame k), so frames with more
//!    photons count more; `w_k` is a Gaussian in the frame distance (σ = `temporal_sigma`),
//!    optionally times a **temporal range kernel** on the change statistic
//!    ([`temporal_weight`], width `temporal_kappa` noise deviations; off by default): a
//!    bilateral filter in time, which bounds the smear of a change the cut missed by a
//!    noise-sized amount.
//! 4. **Spatial bilateral filtering** of the pooled sums over `radius` element sizes:
//!    spatial Gaussian × range kernel of `kappa` standard deviations of the pooled
//!    estimates' noise (a precise pooled estimate pools flat neighbourhoods and stops at
//!    edges; below `min_photons` pooled photons the range kernel is dropped: the published
//!    fix for noisy small elements). With `kernel_photons` set, σ_s adapts to the local
//!    photon density (grows where photons are sparse, shrinks where they are dense:
//!    [`crate::kernels::elements::reconstruct::adaptive_sigma2`]).
//! 5. Vertex interpolation and the eye pass are those of `dept` (light sampled per pixel,
//!    glossy surfaces continued to the next diffuse one, [`crate::kernels::elements::view`]), with the
//!    per-pixel light **pooled over the last `light_history` output frames** where the
//!    animation leaves the pixel's paths unchanged ([`crate::kernels::elements::reuse`]: from
//!    [`chronolux_core::scene::delta::FrameDelta`], never from pixel values), so a static
//!    pixel gets `(light_history + 1) · spp` light samples for the price of `spp`.
//!
//! A static scene keeps whole windows (2K + 1 frames, fewer at the ends of the render
//! list); a change cuts the window of the elements it visibly changes at the change, on
//! each side, so an abrupt change is not smeared into the frames before or after it.
//!
//! ## When it renders as `path`
//! A frame gains over path tracing at the same camera samples only by its pooled
//! per-pixel light and by the elements' indirect light. When no frame within
//! `light_history` on either side can pool light with it (decided from the animation:
//! [`Validity::may_allow_unprobed`], false under a sky or a sun while anything moves and
//! under a moving camera) and the **path probe** of its block of `window` frames
//! ([`crate::kernels::probe`]: the path tracer's relative variance with and without its
//! indirect part, on every 8th row of the block's first frame) finds that indirect light
//! adds at most 10 % to path tracing's noise, the frame is rendered by the path tracer at
//! `spp` samples, bit for bit `path`'s frame with the same seed, and its `path_probe`
//! report says so (`rendered_as`, the variance ratio and the frame probed; frames rendered
//! as `spacetime-dept` after a probe carry it too; the probe takes at most 4 samples per
//! pixel, so at 16 it costs 1/32 of a `path` frame per block). Sky-lit glTF models whose every part
//! moves are the case measured (BENCHMARKS.md, "Sky-lit models at 256²"); a lamp-lit
//! room, the demo, its dolly and cornell-moving stay `spacetime-dept` (ratios 2.8–33 at
//! 96²).
//! `path_probe = false` turns the probe off.
//!
//! ## Still sets: the light computed once
//! Where only the camera moves (a fly-through of a still interior, or nothing moves at all),
//! every frame of a window has the same photons' worth of light, so sliding the window
//! (tracing each frame's own `N` photons and pooling `2K + 1` frames) spends `N` photons per
//! frame to keep a solution that never changes. When every frame of the output frame's
//! window shows the same set — between consecutive frames of the window only the camera
//! differs ([`FrameDelta::only_camera_changed`], from the animation, never from pixels) —
//! the frame reads a **still solution** instead: the photons `0 .. (2K + 1)·N` (the whole
//! window's budget, the count the automatic element size assumes) traced once in the set,
//! completed by the bilateral filter once, and kept for every later output frame whose
//! window shows the same set. Its estimate has the sliding window's photons with equal
//! weights (at least the Gaussian-weighted window's effective count), so quality is not
//! lower; the indirect light does not flicker at all within the set, and a fly-through of
//! `L` frames traces `(2K + 1)·N` photons instead of `L·N` and filters once instead of `L`
//! times. It depends only on the set (not on where the render list or a farm segment
//! starts), so a segment renders a frame as a single run does. Off with
//! `still_set = false`, with the `auto` stopping rule (per-frame counts), and for a
//! single-frame render (a window of one frame: the solution would cost `2K + 1` frames'
//! photons for one). A frame whose window reaches a change (the first and last `K` frames
//! of a still stretch inside a moving animation) slides as before.

use crate::framework::integrator::{LightSplit, RenderedFrame, render_camera_rays};
use crate::framework::sequence::SequenceRenderer;
use crate::kernels::elements::assess_frame;
use crate::kernels::elements::budget::luminances;
use crate::kernels::elements::budget::{AutoPhotons, PhotonCount, next_total};
use crate::kernels::elements::element_map::{
    ElementAccumulators, ElementMesh, FrameElements, FramePhotons, deposit_more_photons,
    max_photon_bounces,
};
use crate::kernels::elements::reconstruct::{
    ADAPTIVE_LIST_RADIUS, ElementSolution, NeighbourCache, Neighbours, adaptive_sigma2,
    filter_with_sigma, prior_sq, range_weight,
};
use crate::kernels::elements::reuse::{EyeRecord, Validity, combine, eye_pass};
use crate::kernels::elements::view::DeptView;
use crate::kernels::probe::{Probe, path_tracer, probe, probe_frame};
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::parallel;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use std::sync::Arc;

/// Settings of `spacetime-dept`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpacetimeSettings {
    /// Camera samples, path depth and seed ([`crate::framework::technique::CommonSettings`]). `spp`:
    /// Camera samples per pixel of each frame. Default 16. `max_depth`: Longest path in
    /// segments from the camera (`--max-depth`, Mitsuba's `max_depth`), as `dept`'s
    /// ([`crate::kernels::elements::DeptSettings::common`]). `None` (default): unlimited. `seed`:
    /// Seed of the photon and camera streams. Default 0.
    #[serde(flatten)]
    pub common: crate::framework::technique::CommonSettings,
    /// Photons per frame when `auto` is not set. Default 100 000.
    pub photons: u64,
    /// Stopping rule choosing the photons of each frame from the noise of the space-time
    /// reconstruction ([`crate::kernels::elements::budget`]); `None`: `photons`.
    pub auto: Option<AutoPhotons>,
    /// Past frames whose per-pixel light (the eye pass's light samples) a pixel pools
    /// with its own where the animation leaves its paths unchanged
    /// ([`crate::kernels::elements::reuse`]); 0: none; at most `window` is used (a farm segment has
    /// `window` frames of context). Default 8.
    pub light_history: u32,
    /// Target element count along the scene diagonal. 0 (default): chosen from the
    /// photons an element's estimate pools, a frame's photons (with `auto`, its
    /// `max_photons`) times the whole window's 2K + 1 frames
    /// ([`crate::kernels::elements::element_map::auto_elements`]): e.g. 32 at 32k photons per frame
    /// and K = 8, 38 at the default 100k. Not from the frames a window actually keeps, so the mesh,
    /// and with it every image, is the same in a farm segment as in a single run.
    pub elements: f32,
    /// Longest specular chain of eye rays. Default 8.
    pub max_specular_depth: u32,
    /// Glossy surfaces an eye path continues through (as `dept`'s). Default 2.
    pub max_glossy: u32,
    /// Frames on each side of the output frame (K: the window has at most 2K + 1
    /// frames; frame f is output once frame f + K is traced). Default 8.
    /// (`RUST_LOG=chronolux_render=debug` prints the windows' power-weighted mean length.)
    pub window: u32,
    /// Temporal Gaussian σ in frames. Default 8 (weights ≥ 0.6 over ±8 frames: the change
    /// test and the range kernel, not this Gaussian, limit the temporal blur).
    pub temporal_sigma: f32,
    /// Temporal range kernel: a frame's weight is multiplied by
    /// `exp(−(S_k − S_f)² / (2 κ_t² (σ_k² + σ_f²)))` (S: the change statistic, σ² its
    /// variance; f the output frame), so frames whose light differs from the output
    /// frame's by more than its noise count less ([`temporal_weight`]). 0: flat (only the
    /// Gaussian and the cut). Default 0: with κ_t = 2 the FLIP error rose 1.5–2.7 % and
    /// the flicker 4–9 % on cornell-moving and the demo at 4k–16k photons per frame (κ_t =
    /// 4: no change), since the cut already stops the visible changes there and the range
    /// weights add noise (BENCHMARKS.md, issue 17).
    pub temporal_kappa: f32,
    /// Energy test: standard deviations of the difference that make a change
    /// significant. Default 3.
    pub change_threshold: f32,
    /// Energy test: luminance contrast (Weber fraction of the side's total irradiance)
    /// below which a change is invisible and frames are pooled across it. Default 0.02.
    pub change_weber: f32,
    /// Radius (element sizes) of the spatial Gaussian pooling of the change statistic.
    /// Default 2.5, the direct light's radius, so that both filters share one neighbour
    /// list: against 5 (the former default, 4× the list entries) it cost 20 % less CPU
    /// on the demo and cornell-moving at 4k–32k photons per frame for a FLIP error within
    /// ±1.3 % and flicker within +1.2 % (BENCHMARKS.md, issue 17).
    pub change_radius: f32,
    /// Spatial bilateral filter radius in element sizes (σ_s = radius / 2). Default 2.5
    /// (as `dept-spatial`).
    pub radius: f32,
    /// Adaptive spatial support: photons (pooled over the window) the spatial Gaussian
    /// should hold; σ_s² is scaled by `kernel_photons / (photons under the σ_s kernel)`
    /// within [1/2, 2] ([`crate::kernels::elements::reconstruct::adaptive_sigma2`]), so the support
    /// grows where photons are sparse and shrinks where they are dense. 0: fixed σ_s.
    /// Default 0: 32 lowers the FLIP error 3–6 % at 4k–16k photons per frame but costs
    /// 1.7–1.9× the CPU (lists of √2 the radius, a Gaussian per entry), more than the
    /// photons that gain as much (BENCHMARKS.md, issue 17).
    pub kernel_photons: f32,
    /// Range kernel width in noise standard deviations. Default 2.
    pub kappa: f32,
    /// Below this many pooled photons the range kernel is dropped (plain Gaussian).
    /// Default 8.
    pub min_photons: u32,
    /// Renders a frame as `path` at `spp` samples where the path probe shows that this
    /// technique cannot gain there (module documentation, "When it renders as `path`";
    /// [`crate::kernels::probe`]), and says so in the frame's `path_probe` report.
    /// Default true.
    pub path_probe: bool,
    /// Where only the camera moves, frames whose whole window shows the same set read one
    /// solution of `(2K + 1)·photons` photons traced and filtered once (module
    /// documentation, "Still sets"). Default true.
    pub still_set: bool,
}

impl Default for SpacetimeSettings {
    fn default() -> Self {
        SpacetimeSettings {
            common: crate::framework::technique::CommonSettings {
                spp: 16,
                max_depth: None,
                seed: 0,
            },
            photons: 100_000,
            auto: None,
            light_history: 8,
            elements: 0.0,
            max_specular_depth: 8,
            max_glossy: 2,
            window: 8,
            temporal_sigma: 8.0,
            temporal_kappa: 0.0,
            change_threshold: 3.0,
            change_weber: 0.02,
            change_radius: 2.5,
            radius: 2.5,
            kernel_photons: 0.0,
            kappa: 2.0,
            min_photons: 8,
            path_probe: true,
            still_set: true,
        }
    }
}

impl SpacetimeSettings {
    /// Elements per scene diagonal: `elements`, or when 0 the automatic count for the
    /// photons of a whole window (see `elements`).
    pub fn elements_per_diagonal(&self) -> f32 {
        let photons = self.auto.map_or(self.photons, |a| a.max_photons);
        let pooled = photons as f64 * (2 * self.window as u64 + 1) as f64;
        crate::kernels::elements::element_map::elements_per_diagonal(self.elements, pooled)
    }

    /// These settings with `--photons` applied (`None`: unchanged).
    pub fn with_photons(mut self, p: Option<PhotonCount>) -> Self {
        match p {
            None => {}
            Some(PhotonCount::Fixed(n)) => {
                self.photons = n;
                self.auto = None;
            }
            Some(PhotonCount::Auto(a)) => self.auto = Some(a),
        }
        self
    }
}

/// Weight of frame k in the temporal pooling of an element side: its temporal Gaussian
/// `gauss` times the range kernel of its change statistic `(S_k, var_k)` against the
/// output frame's `(S_f, var_f)`, `exp(−(S_k − S_f)² / (2 κ² (var_k + var_f)))` (1 when
/// `kappa` ≤ 0), the temporal counterpart of the spatial bilateral filter's
/// [`range_weight`] (Weber et al. 2004). A difference Δ pulls the pooled value by at most
/// `Δ · exp(−Δ² / (2κ²σ_Δ²))` per unit weight, whose largest value over all Δ is
/// `κ σ_Δ e^(−1/2)`: a step is smeared by at most that (times its weight share) whatever
/// its size, where flat weights smear it by Δ; on static light the weights stay near 1
/// (mean `1/√(1 + 1/κ²)` = 0.89 for κ = 2 when the statistic's noise is independent of
/// the pooled sums'). Within the window of [`choose_window`], whose cut catches the steps
/// too small per frame for the range kernel (it pools the frames on each side).
#[inline]
pub fn temporal_weight(gauss: f32, k: (f32, f32), f: (f32, f32), kappa: f32) -> f32 {
    if kappa <= 0.0 {
        return gauss;
    }
    gauss
        * range_weight(
            f.0,
            k.0,
            f.1.max(0.0).sqrt(),
            k.1.max(0.0).sqrt(),
            kappa,
            false,
        )
}

/// Chooses the temporal window of one element side. `series[k]` = (change statistic,
/// its variance) of the k-th frame of the look-ahead (increasing frames), `centre` the
/// output frame; returns the first and last index pooled. The window grows one frame at a
/// time on each side (after, then before) until a candidate frame is refused: it, or the
/// mean of all frames from it to the end of its side, differs from the mean of the window
/// so far by more than `threshold` standard deviations of the difference **and** by more
/// than `tolerance` (the visibility threshold). A second pass tests every split of the
/// grown window, the frames on one side against the other, and cuts at the most
/// significant one until none fires (binary segmentation). See the module documentation.
pub fn choose_window(
    series: &[(f32, f32)],
    centre: usize,
    threshold: f32,
    tolerance: f32,
) -> (usize, usize) {
    let n = series.len();
    debug_assert!(centre < n);
    let (thr, tol) = (threshold as f64, tolerance.max(0.0) as f64);
    let fires = |a: f64, va: f64, b: f64, vb: f64| {
        let d = (a - b).abs();
        d > thr * (va + vb).max(0.0).sqrt() && d > tol
    };
    let mean = |part: &[(f32, f32)]| {
        let m = part.len() as f64;
        let (s, v) = part.iter().fold((0.0f64, 0.0f64), |(s, v), x| {
            (s + x.0 as f64, v + x.1 as f64)
        });
        (s / m, v / (m * m))
    };
    let (mut lo, mut hi) = (centre, centre);
    let (mut sum, mut var, mut m) = (series[centre].0 as f64, series[centre].1 as f64, 1.0f64);
    let (mut open_lo, mut open_hi) = (centre > 0, centre + 1 < n);
    let refused = |k: usize, tail: &[(f32, f32)], sum: f64, var: f64, m: f64| {
        let (mw, vw) = (sum / m, var / (m * m));
        let (mt, vt) = mean(tail);
        fires(series[k].0 as f64, series[k].1 as f64, mw, vw) || fires(mt, vt, mw, vw)
    };
    while open_lo || open_hi {
        if open_hi {
            let k = hi + 1;
            if refused(k, &series[k..], sum, var, m) {
                open_hi = false;
            } else {
                hi = k;
                sum += series[k].0 as f64;
                var += series[k].1 as f64;
                m += 1.0;
                open_hi = hi + 1 < n;
            }
        }
        if open_lo {
            let k = lo - 1;
            if refused(k, &series[..=k], sum, var, m) {
                open_lo = false;
            } else {
                lo = k;
                sum += series[k].0 as f64;
                var += series[k].1 as f64;
                m += 1.0;
                open_lo = lo > 0;
            }
        }
    }
    // Second pass, with the whole window known (binary segmentation): every split of
    // the window is tested, the frames on one side of it against those on the other; the
    // most significant split that fires cuts the window, keeping the part with the
    // centre, and the rest is tested again. A window grown from the centre alone has too
    // little evidence against a step right next to it; the two sides pooled have it.
    loop {
        let mut best: Option<(f64, usize)> = None;
        for k in lo + 1..=hi {
            let ((ma, va), (mb, vb)) = (mean(&series[lo..k]), mean(&series[k..=hi]));
            if fires(ma, va, mb, vb) {
                let z = (ma - mb).abs() / (va + vb).max(1e-30).sqrt();
                if best.is_none_or(|(bz, _)| z > bz) {
                    best = Some((z, k));
                }
            }
        }
        match best {
            Some((_, k)) if k <= centre => lo = k,
            Some((_, k)) => hi = k - 1,
            None => break,
        }
    }
    (lo, hi)
}

/// Radius (element sizes) of the Gaussian filter of the photons' direct light (the
/// visibility threshold of the change test and of the stopping rule).
const DIRECT_RADIUS: f32 = 2.5;

/// One traced frame: its photon sums and its change statistic.
struct Traced {
    frame: u32,
    photons: FramePhotons,
    area: Vec<f32>,
    /// Change statistic per element side: indirect + caustic luminance irradiance,
    /// spatially pooled over `change_radius` elements.
    stat: Vec<f32>,
    /// Its variance.
    stat_var: Vec<f32>,
    /// Direct luminance irradiance of the photons' first hits (Gaussian over 2.5
    /// elements): sets the visibility threshold of the change test and of the stopping
    /// rule.
    direct: Vec<f32>,
}

impl Traced {
    fn new(frame: u32, mesh: &ElementMesh, fe: &FrameElements) -> Self {
        Traced {
            frame,
            photons: FramePhotons::new(mesh.element_count()),
            area: fe.area.clone(),
            stat: Vec::new(),
            stat_var: Vec::new(),
            direct: Vec::new(),
        }
    }

    /// (Re)computes the change statistic and the direct irradiance from the sums, with
    /// the neighbour lists of `fe` within `change_radius` (`nb_change`) and 2.5 element
    /// sizes (`nb_direct`).
    fn analyse(&mut self, fe: &FrameElements, nb_change: &Neighbours, nb_direct: &Neighbours) {
        let mut both: ElementAccumulators = self.photons.indirect.clone();
        let c = &self.photons.caustic;
        for s in 0..both.flux.len() {
            both.flux[s] += c.flux[s];
            both.count[s] += c.count[s];
            both.flux_sq[s] += c.flux_sq[s];
        }
        // Without the stopping rule's phantom-photon prior (`filter_with_sigma`'s
        // `prior`): it adds one mean photon per neighbour, which where photons are sparse
        // (≪ 1 per element and frame) inflates σ several times and hides real changes.
        // Sides with no photons in either frame have Δ = 0 and never cut.
        // The spatial Gaussians (σ = radius / 2) are the lists' `gauss`.
        let (e, sig) = filter_with_sigma(&both, fe, nb_change, 0.0, |_, _, _, g| g);
        self.stat = luminances(&e);
        self.stat_var = sig.iter().map(|s| s * s).collect();
        // As `filtered_irradiance_sigma` with `Filter::Gaussian { radius: 2.5 }`.
        let direct = &self.photons.direct;
        let (d, _) = filter_with_sigma(direct, fe, nb_direct, prior_sq(direct), |_, _, _, g| g);
        self.direct = luminances(&d);
    }

    /// Radii (world units) of the change statistic's and the direct light's filters.
    fn radii(mesh: &ElementMesh, change_radius: f32) -> (f32, f32) {
        (
            change_radius * mesh.element_size,
            DIRECT_RADIUS * mesh.element_size,
        )
    }
}

/// Temporally pooled sums of one element side: `Σ w Φ`, `Σ w N A`, `Σ w² Σφ²`, photons.
#[derive(Clone, Copy, Debug, Default)]
struct Pooled {
    flux: Rgb,
    na: f32,
    sq: f32,
    count: u32,
}

impl Pooled {
    #[inline]
    fn lum(&self) -> f32 {
        if self.na > 0.0 {
            luminance(self.flux) / self.na
        } else {
            0.0
        }
    }
    #[inline]
    fn sigma(&self) -> f32 {
        if self.na > 0.0 {
            self.sq.sqrt() / self.na
        } else {
            0.0
        }
    }
}

/// What the last frame's reconstruction did, per element side (diagnostics and tests).
#[derive(Clone, Debug, Default)]
pub struct SpacetimeFrameInfo {
    pub frame: u32,
    /// First and last frame pooled by each element side.
    pub window: Vec<(u32, u32)>,
    /// Reconstructed indirect + caustic irradiance of each element side.
    pub irradiance: Vec<Rgb>,
    /// Element areas in this frame.
    pub area: Vec<f32>,
}

/// The solution of a still set (module documentation, "Still sets"): the element sums of
/// the whole window's photons, traced once, and their completion.
struct StillSolution {
    /// The scene of the frame that traced it (any frame of the set).
    scene: Arc<FrameScene>,
    photons: u64,
    indirect: Vec<Rgb>,
    caustic: Vec<Rgb>,
}

/// The `spacetime-dept` sequence renderer.
pub struct SpacetimeDept {
    pub settings: SpacetimeSettings,
    mesh: Option<ElementMesh>,
    /// Traced frames of the current window, increasing.
    frames: Vec<Traced>,
    /// Output frames of the last `light_history` frames: scene and eye pass, increasing.
    history: Vec<(u32, Arc<FrameScene>, EyeRecord)>,
    last_output: Option<u32>,
    last_photons: Option<u64>,
    /// The last frame's windows and solution.
    pub info: Option<SpacetimeFrameInfo>,
    /// Neighbour lists carried from traced frame to traced frame (change statistic,
    /// direct light) and from output frame to output frame (the bilateral completion).
    nb_change: NeighbourCache,
    nb_direct: NeighbourCache,
    nb_output: NeighbourCache,
    /// The last path probe ([`crate::kernels::probe`]).
    probe: Option<Probe>,
    /// The current still set's solution, if any.
    still: Option<StillSolution>,
}

impl SpacetimeDept {
    pub fn new(settings: SpacetimeSettings) -> Self {
        SpacetimeDept {
            settings,
            mesh: None,
            frames: Vec::new(),
            history: Vec::new(),
            last_output: None,
            last_photons: None,
            info: None,
            nb_change: NeighbourCache::default(),
            nb_direct: NeighbourCache::default(),
            nb_output: NeighbourCache::default(),
            probe: None,
            still: None,
        }
    }

    /// Whether every frame of `window` (the output frame's) shows the same set (only the
    /// camera differs between consecutive frames), so that the frame reads the still
    /// solution (module documentation, "Still sets").
    fn window_is_still(&self, source: &mut FrameSource, window: &[u32]) -> bool {
        let s = &self.settings;
        if !s.still_set || s.auto.is_some() {
            return false;
        }
        if window.len() < 2 {
            return false;
        }
        let mut prev = source.frame(window[0]);
        for &g in &window[1..] {
            let next = source.frame(g);
            if !FrameDelta::between(&prev, &next).only_camera_changed() {
                return false;
            }
            prev = next;
        }
        true
    }

    /// The still solution for `scene` (kept, or traced and completed now): indirect and
    /// caustic irradiance per element side, the photons, and the photon rays traced for it
    /// in this frame (0 when kept).
    fn still_solution(
        &mut self,
        scene: &Arc<FrameScene>,
        mesh: &ElementMesh,
        fe: &FrameElements,
        nb: &Neighbours,
    ) -> (Vec<Rgb>, Vec<Rgb>, u64, u64) {
        if let Some(st) = &self.still
            && FrameDelta::between(&st.scene, scene).only_camera_changed()
        {
            return (st.indirect.clone(), st.caustic.clone(), st.photons, 0);
        }
        let s = &self.settings;
        let n = s.photons * (2 * s.window as u64 + 1);
        let mut ph = FramePhotons::new(mesh.element_count());
        deposit_more_photons(
            scene,
            mesh,
            0..n,
            s.common.seed,
            max_photon_bounces(s.common.max_depth),
            &mut ph,
        );
        let rays = ph.stats.rays;
        let total = ph.photons();
        // The sums of `pool` for a window of one frame (weight 1).
        let pooled = |acc: &ElementAccumulators| -> Vec<Pooled> {
            (0..acc.flux.len())
                .map(|k| {
                    let a = fe.area[k / 2];
                    if a <= 0.0 {
                        return Pooled::default();
                    }
                    Pooled {
                        flux: acc.flux[k],
                        na: total as f32 * a,
                        sq: acc.flux_sq[k],
                        count: acc.count[k],
                    }
                })
                .collect()
        };
        let (pi, pc) = (pooled(&ph.indirect), pooled(&ph.caustic));
        let (ind, _) = self.complete(&pi, nb, prior_sq(&ph.indirect));
        let (cau, _) = self.complete(&pc, nb, prior_sq(&ph.caustic));
        self.still = Some(StillSolution {
            scene: scene.clone(),
            photons: total,
            indirect: ind.clone(),
            caustic: cau.clone(),
        });
        (ind, cau, total, rays)
    }

    /// First photon index of frame `g` and the photons a frame gets when it is first
    /// traced (stopping rule: the last output frame's count, a prediction the rule
    /// corrects when the frame is output).
    fn first_photons(&self, g: u32) -> (u64, u64) {
        let s = &self.settings;
        match s.auto {
            None => (g as u64 * s.photons, s.photons),
            Some(a) => {
                let max = a.max_photons.max(1);
                let n = self
                    .last_photons
                    .unwrap_or(a.batch)
                    .clamp(a.batch.min(max), max);
                (g as u64 * max, n)
            }
        }
    }

    /// Windows (per side) and temporally pooled indirect and caustic sums around the
    /// frame at index `c` of `self.frames`.
    fn pool(&self, c: usize) -> (Vec<Pooled>, Vec<Pooled>, Vec<(u32, u32)>) {
        let s = &self.settings;
        let fr = &self.frames;
        let cur = &fr[c];
        let n_slots = cur.stat.len();
        let inv2s2 = 1.0 / (2.0 * s.temporal_sigma.max(1e-3).powi(2));
        let weights: Vec<f32> = fr
            .iter()
            .map(|t| {
                let dt = t.frame as f32 - cur.frame as f32;
                (-dt * dt * inv2s2).exp()
            })
            .collect();
        let rows = parallel::map_chunks(n_slots, 4096, |range| {
            let mut series = Vec::with_capacity(fr.len());
            let mut out = Vec::with_capacity(range.len());
            for slot in range {
                series.clear();
                series.extend(fr.iter().map(|t| (t.stat[slot], t.stat_var[slot])));
                let tol = s.change_weber * (cur.stat[slot] + cur.direct[slot]).max(0.0);
                let (lo, hi) = choose_window(&series, c, s.change_threshold, tol);
                let (mut ind, mut cau) = (Pooled::default(), Pooled::default());
                for k in lo..=hi {
                    let t = &fr[k];
                    let a = t.area[slot / 2];
                    if a <= 0.0 {
                        continue;
                    }
                    let w = temporal_weight(weights[k], series[k], series[c], s.temporal_kappa);
                    let na = w * t.photons.photons() as f32 * a;
                    for (p, acc) in [
                        (&mut ind, &t.photons.indirect),
                        (&mut cau, &t.photons.caustic),
                    ] {
                        p.flux += acc.flux[slot] * w;
                        p.na += na;
                        p.sq += acc.flux_sq[slot] * w * w;
                        p.count += acc.count[slot];
                    }
                }
                out.push((ind, cau, (fr[lo].frame, fr[hi].frame)));
            }
            out
        });
        let mut ind = Vec::with_capacity(n_slots);
        let mut cau = Vec::with_capacity(n_slots);
        let mut win = Vec::with_capacity(n_slots);
        for (i, c, w) in rows.into_iter().flatten() {
            ind.push(i);
            cau.push(c);
            win.push(w);
        }
        (ind, cau, win)
    }

    /// Spatial bilateral filter of pooled sums: irradiance per element side and the
    /// standard error of its luminance, with `prior` (one phantom photon's Σφ², see
    /// [`crate::kernels::elements::reconstruct::filter_with_sigma`]) added to every side's Σφ².
    fn complete(&self, p: &[Pooled], nb: &Neighbours, prior: f32) -> (Vec<Rgb>, Vec<f32>) {
        let s = &self.settings;
        let n = p.len() / 2;
        // Adaptive support: σ² per side (lists of ADAPTIVE_LIST_RADIUS × the radius, see
        // `output_radius`); fixed: the lists' own Gaussian.
        let sigma2 = (s.kernel_photons > 0.0).then(|| {
            let count: Vec<f32> = p.iter().map(|q| q.count as f32).collect();
            let sigma0 = 0.5 * nb.radius / ADAPTIVE_LIST_RADIUS;
            adaptive_sigma2(nb, &count, sigma0, s.kernel_photons)
        });
        // Luminance and noise of every side, once (not once per row that reads them).
        let ls: Vec<(f32, f32)> = p.iter().map(|q| (q.lum(), q.sigma())).collect();
        let rows = parallel::map_chunks(n, 1024, |range| {
            let mut out = Vec::with_capacity(2 * range.len());
            for e in range {
                for side in 0..2 {
                    let se = 2 * e + side;
                    let (ce, cs) = ls[se];
                    let relax = p[se].count < s.min_photons;
                    let (mut num, mut den, mut sq) = (Rgb::ZERO, 0.0f32, 0.0f32);
                    // Spatial Gaussian: σ = radius / 2 (`nb.gauss`) or adaptive.
                    let inv2s2 = sigma2.as_ref().map(|s2| 1.0 / (2.0 * s2[se]).max(1e-30));
                    for (&(j, d2), &g) in nb.of(e).iter().zip(nb.gauss(e)) {
                        let sj = 2 * j as usize + side;
                        let q = &p[sj];
                        if q.na <= 0.0 {
                            continue;
                        }
                        let g = inv2s2.map_or(g, |k| (-d2 * k).exp());
                        let w = range_weight(ce, ls[sj].0, cs, ls[sj].1, s.kappa, relax) * g;
                        num += q.flux * w;
                        den += q.na * w;
                        sq += (q.sq + prior) * w * w;
                    }
                    out.push(if den > 0.0 {
                        (num / den, sq.sqrt() / den)
                    } else {
                        (Rgb::ZERO, 0.0)
                    });
                }
            }
            out
        });
        rows.into_iter().flatten().unzip()
    }

    /// Radius (world) of the output frame's neighbour lists: the filter radius, times
    /// [`ADAPTIVE_LIST_RADIUS`] with the adaptive support (its widest kernel).
    fn output_radius(&self, mesh: &ElementMesh) -> f32 {
        let s = &self.settings;
        let r = s.radius * mesh.element_size;
        if s.kernel_photons > 0.0 {
            r * ADAPTIVE_LIST_RADIUS
        } else {
            r
        }
    }

    /// `frame` rendered as `path` at `spp` when no per-pixel light can be reused for it
    /// and the path probe of its block says path tracing suffices (module documentation,
    /// "When it renders as `path`"). Otherwise `Err` with the probe's report when one was
    /// consulted.
    fn as_path(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        scene: &Arc<FrameScene>,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<RenderedFrame, Option<serde_json::Value>> {
        let s = self.settings.clone();
        if !s.path_probe {
            return Err(None);
        }
        // From the animation: could any past frame's per-pixel light pool here, or this
        // frame's in a later one? (The past and future frames within `light_history`
        // stay cached: the look-ahead builds the future ones anyway.)
        let history = s.light_history.min(s.window);
        source.reserve(2 * history as usize + 2);
        for g in source.window(frame, history, history) {
            if g == frame {
                continue;
            }
            let sg = match self.history.iter().find(|(h, _, _)| *h == g) {
                Some((_, sc, _)) => sc.clone(),
                None => source.frame(g),
            };
            let v = if g < frame {
                Validity::between(&sg, scene)
            } else {
                Validity::between(scene, &sg)
            };
            if v.may_allow_unprobed() {
                return Err(None);
            }
        }
        let p = probe_frame(source, frame, s.window);
        let pr = match self.probe {
            Some(pr) if pr.frame == p => pr,
            _ => {
                let sp = if p == frame {
                    scene.clone()
                } else {
                    source.frame(p)
                };
                let pt = path_tracer(s.common.spp, s.common.max_depth, s.common.seed);
                let pr = probe(&sp, p, &pt, s.common.spp, s.common.seed);
                log::debug!(
                    "spacetime-dept frame {frame}: no per-pixel light reuse possible; path probe of frame {p}: variance ratio {:.3} over {} pixels",
                    pr.variance_ratio,
                    pr.pixels
                );
                self.probe = Some(pr);
                pr
            }
        };
        let path = pr.path_suffices();
        let mut report = serde_json::to_value(pr).expect("serialisable");
        report["rendered_as"] = if path { "path" } else { "spacetime-dept" }.into();
        if !path {
            return Err(Some(report));
        }
        let pt = path_tracer(s.common.spp, s.common.max_depth, s.common.seed);
        let mut img = render_camera_rays(&pt, scene, frame, s.common.spp, s.common.seed, progress);
        img.report.insert("path_probe".into(), report);
        img.report.insert("light_spp".into(), s.common.spp.into());
        Ok(img)
    }

    /// Traces the frames of `frame`'s window that are not traced yet, and forgets the
    /// frames that left it.
    fn trace_window(&mut self, source: &mut FrameSource, frame: u32, scene: &Arc<FrameScene>) {
        let s = self.settings.clone();
        let window = source.window(frame, s.window, s.window);
        self.frames.retain(|t| window.contains(&t.frame));
        let mesh = self.mesh.take().expect("mesh");
        let out_radius = self.output_radius(&mesh);
        for g in window {
            if self.frames.iter().any(|t| t.frame == g) {
                continue;
            }
            let sg = if g == frame {
                scene.clone()
            } else {
                source.frame(g)
            };
            let sc = &*sg;
            // A frame whose topology differs cannot share element ids: left out.
            if !mesh.matches(sc) {
                continue;
            }
            let fe = FrameElements::new(sc, &mesh);
            let mut t = Traced::new(g, &mesh, &fe);
            let (base, n) = self.first_photons(g);
            deposit_more_photons(
                sc,
                &mesh,
                base..base + n,
                s.common.seed,
                max_photon_bounces(s.common.max_depth),
                &mut t.photons,
            );
            let (rc, rd) = Traced::radii(&mesh, s.change_radius);
            let nd = self.nb_direct.get(&fe, rd);
            // One list for both filters when their radii agree (the default).
            let nc = if rc == rd {
                nd
            } else {
                self.nb_change.get(&fe, rc)
            };
            log::debug!(
                "spacetime-dept frame {g}: neighbour rows rebuilt {} of {} (change), {} (direct); mean row {:.1} (change), {:.1} (direct)",
                nc.rebuilt(),
                fe.area.len(),
                nd.rebuilt(),
                nc.entries() as f64 / fe.area.len().max(1) as f64,
                nd.entries() as f64 / fe.area.len().max(1) as f64
            );
            t.analyse(&fe, nc, nd);
            // The first output frame's lists are these when the radii agree (later ones
            // are updated from the previous output frame's).
            if g == frame && self.nb_output.is_empty() && rd == out_radius {
                self.nb_output = self.nb_direct.clone();
            }
            let at = self.frames.partition_point(|x| x.frame < g);
            self.frames.insert(at, t);
        }
        self.mesh = Some(mesh);
    }

    /// The element mesh for `scene` (built again where its topology changed) and a
    /// restart where the frames jump back.
    fn start_frame(&mut self, source: &mut FrameSource, frame: u32, scene: &FrameScene) {
        let s = &self.settings;
        if !self.mesh.as_ref().is_some_and(|m| m.matches(scene)) {
            // From frame 0's scene whatever frame the run starts at: the element size
            // follows the scene's bounds, which the animation can change, so a farm
            // segment building from its own first frame got other elements than the
            // single run (InterpolationTest: every frame of the last segment differed).
            // The output frame's own scene only if frame 0's topology differs.
            let start = source.frame(0);
            let mut mesh = ElementMesh::build(&start, s.elements_per_diagonal());
            if !mesh.matches(scene) {
                mesh = ElementMesh::build(scene, s.elements_per_diagonal());
            }
            log::debug!(
                "spacetime-dept: {} elements ({} clusters of small triangles) on {} triangles, element size {:.4}",
                mesh.element_count(),
                mesh.cluster_count(),
                mesh.triangle_count(),
                mesh.element_size
            );
            self.mesh = Some(mesh);
            self.frames.clear();
            self.still = None;
        }
        // Frames must arrive in increasing order; a jump back restarts.
        if self.last_output.is_some_and(|l| l >= frame) {
            self.frames.clear();
            self.history.clear();
            self.still = None;
            // The scene may have been edited (the live view renders a frame again).
            self.probe = None;
        }
        self.last_output = Some(frame);
    }

    /// The output frame's element irradiance (indirect, caustic; per element side) pooled
    /// over its windows, with the windows; shoots more photons into traced frame `c`
    /// while the `auto` stopping rule asks for them.
    fn solve_elements(
        &mut self,
        scene: &FrameScene,
        frame: u32,
        mesh: &ElementMesh,
        fe: &FrameElements,
        c: usize,
        nb: &Neighbours,
    ) -> (Vec<Rgb>, Vec<Rgb>, Vec<(u32, u32)>) {
        let s = self.settings.clone();
        loop {
            let (pi, pc, window) = self.pool(c);
            let cur = &self.frames[c].photons;
            let prior_i = prior_sq(&cur.indirect);
            let prior_c = prior_sq(&cur.caustic);
            let (ind, si) = self.complete(&pi, nb, prior_i);
            let (cau, sc) = self.complete(&pc, nb, prior_c);
            let Some(rule) = s.auto else {
                break (ind, cau, window);
            };
            let total = cur.photons();
            let a = assess_frame(&rule, mesh, fe, cur, &ind, &cau, &si, &sc);
            log::debug!(
                "spacetime-dept frame {frame}: {total} photons, {:.1} % of the power-weighted surface above the {} contrast threshold, {} photons predicted",
                100.0 * a.fraction_above,
                rule.weber,
                a.predicted_photons
            );
            match next_total(&rule, total, &a) {
                Some(t) => {
                    let base = frame as u64 * rule.max_photons.max(1);
                    let tr = &mut self.frames[c];
                    deposit_more_photons(
                        scene,
                        mesh,
                        base + total..base + t,
                        s.common.seed,
                        max_photon_bounces(s.common.max_depth),
                        &mut tr.photons,
                    );
                    let (rc, rd) = Traced::radii(mesh, s.change_radius);
                    tr.analyse(fe, &Neighbours::new(fe, rc), &Neighbours::new(fe, rd));
                }
                None => break (ind, cau, window),
            }
        }
    }
}

/// Debug log of a frame's windows: the power-weighted mean window length and the
/// fraction of the power whose window is whole.
fn log_windows(
    source: &mut FrameSource,
    frame: u32,
    k: u32,
    fe: &FrameElements,
    ind: &[Rgb],
    cau: &[Rgb],
    window: &[(u32, u32)],
) {
    // Power-weighted mean window length and fraction of whole windows.
    let whole = source.window(frame, k, k);
    let whole = (whole[0], *whole.last().expect("frame in its window"));
    let (mut w, mut len, mut full) = (0.0f64, 0.0f64, 0.0f64);
    for (slot, win) in window.iter().enumerate() {
        let p = (fe.area[slot / 2] * luminance(ind[slot] + cau[slot])) as f64;
        if p > 0.0 {
            w += p;
            len += p * (win.1 - win.0 + 1) as f64;
            full += p * (*win == whole) as u8 as f64;
        }
    }
    log::debug!(
        "spacetime-dept frame {frame}: power-weighted mean window {:.2} frames, {:.1} % of the power with the whole window {}..={}",
        len / w.max(1e-30),
        100.0 * full / w.max(1e-30),
        whole.0,
        whole.1
    );
}

impl SequenceRenderer for SpacetimeDept {
    fn name(&self) -> &'static str {
        "spacetime-dept"
    }

    /// Direct light per pixel, indirect from the pooled elements (the DEPT view).
    fn separates_light(&self) -> bool {
        true
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let s = self.settings.clone();
        // The output frame's scene stays cached while the look-ahead builds K more.
        source.reserve(s.window as usize + 2);
        let scene_arc = source.frame(frame);
        let scene = &*scene_arc;
        self.start_frame(source, frame, scene);
        let probed = match self.as_path(source, frame, &scene_arc, progress) {
            Ok(img) => return img,
            Err(probed) => probed,
        };
        // Wall-clock phases for `RUST_LOG=chronolux_render=debug` (a profile, not a
        // benchmark: see BENCHMARKS.md for CPU seconds).
        let t0 = std::time::Instant::now();
        // The frames of the output frame's window (the per-side windows below are cut
        // from it).
        let around = source.window(frame, s.window, s.window);
        let still = self.window_is_still(source, &around);
        if still {
            // The sliding frames are not needed while the window shows the still set.
            self.frames.retain(|t| around.contains(&t.frame));
        } else {
            self.trace_window(source, frame, &scene_arc);
        }
        let t_trace = t0.elapsed();
        let mesh = self.mesh.take().expect("mesh");
        let fe = FrameElements::new(scene, &mesh);
        let t0 = std::time::Instant::now();
        let mut nb_output = std::mem::take(&mut self.nb_output);
        let nb = nb_output.get(&fe, self.output_radius(&mesh));
        let (ind, cau, window, photon_rays, still_report) = if still {
            let (ind, cau, photons, rays) = self.still_solution(&scene_arc, &mesh, &fe, nb);
            self.last_photons = Some(photons);
            let whole = (around[0], *around.last().expect("frame in its window"));
            let report = serde_json::json!({ "photons": photons, "traced_here": rays > 0 });
            (ind, cau, vec![whole; fe.area.len() * 2], rays, Some(report))
        } else {
            self.still = None;
            let c = self
                .frames
                .iter()
                .position(|t| t.frame == frame)
                .expect("output frame traced");
            let (ind, cau, window) = self.solve_elements(scene, frame, &mesh, &fe, c, nb);
            let cur = &self.frames[c];
            self.last_photons = Some(cur.photons.photons());
            (ind, cau, window, cur.photons.stats.rays, None)
        };
        self.nb_output = nb_output;
        if log::log_enabled!(log::Level::Debug) {
            log_windows(source, frame, s.window, &fe, &ind, &cau, &window);
        }
        self.info = Some(SpacetimeFrameInfo {
            frame,
            window,
            irradiance: ind.iter().zip(&cau).map(|(a, b)| *a + *b).collect(),
            area: fe.area.clone(),
        });
        let indirect = ElementSolution::from_elements(&mesh, &fe, &ind);
        let caustic = ElementSolution::from_elements(&mesh, &fe, &cau);
        let view = DeptView {
            mesh: &mesh,
            indirect: &indirect,
            caustic: &caustic,
            max_specular_depth: s.max_specular_depth,
            max_glossy: s.max_glossy,
            max_depth: s.common.max_depth,
        };
        let t_pool = t0.elapsed();
        let t0 = std::time::Instant::now();
        let eye = eye_pass(&view, scene, frame, s.common.spp, s.common.seed, progress);
        let t_eye = t0.elapsed();
        // Per-pixel light of the past frames within `light_history` (at most `window`, so
        // that a farm segment's context of `window` frames holds them all).
        let history = s.light_history.min(s.window);
        self.history
            .retain(|(g, _, _)| *g < frame && g + history >= frame);
        // Frames of the render list in that range that were not output here (a farm
        // segment's context): their eye pass, as a single run over the range made it.
        // The per-pixel light and the reach do not depend on the element solution (only
        // the elements' term, which is not reused, does), so `view` serves any frame.
        if history > 0 {
            for g in source.window(frame, history, 0) {
                if g >= frame || self.history.iter().any(|(h, _, _)| *h == g) {
                    continue;
                }
                let sg = source.frame(g);
                // A record whose every pixel is refused adds nothing (after frames
                // rendered as `path`, most are).
                if !mesh.matches(&sg) || !Validity::between(&sg, scene).may_allow() {
                    continue;
                }
                let e = eye_pass(&view, &sg, g, s.common.spp, s.common.seed, &|_| {});
                let at = self.history.partition_point(|(h, _, _)| *h < g);
                self.history.insert(at, (g, sg, e));
            }
        }
        let past: Vec<(&EyeRecord, Validity)> = self
            .history
            .iter()
            .map(|(_, sc, e)| (e, Validity::between(sc, scene)))
            .collect();
        let (parts, variance, pooled) = combine(&eye, &past);
        log::debug!(
            "spacetime-dept frame {frame}: photons {:.3} s, pooling and filtering {:.3} s, eye pass {:.3} s, light reuse {:.3} s (wall)",
            t_trace.as_secs_f64(),
            t_pool.as_secs_f64(),
            t_eye.as_secs_f64(),
            (t0.elapsed() - t_eye).as_secs_f64()
        );
        let (direct, indirect): (Vec<Rgb>, Vec<Rgb>) = parts.iter().map(|[d, i]| (*d, *i)).unzip();
        let mut stats = eye.stats;
        stats.rays += photon_rays;
        let mut img = RenderedFrame {
            width: eye.width,
            height: eye.height,
            pixels: parts.iter().map(|[d, i]| *d + *i).collect(),
            variance,
            stats,
            invalid_samples: eye.invalid_samples,
            report: Default::default(),
            light: Some(LightSplit { direct, indirect }),
        };
        if let Some(p) = self.last_photons {
            img.report.insert("photons".into(), p.into());
        }
        // Mean camera samples of per-pixel light pooled per pixel (spp: no reuse).
        let mean_pooled =
            pooled.iter().map(|&m| m as f64).sum::<f64>() / pooled.len().max(1) as f64;
        img.report.insert("light_spp".into(), mean_pooled.into());
        if let Some(p) = probed {
            img.report.insert("path_probe".into(), p);
        }
        if let Some(r) = still_report {
            img.report.insert("still_set".into(), r);
        }
        img.report.insert(
            "elements_per_diagonal".into(),
            s.elements_per_diagonal().into(),
        );
        if history > 0 {
            self.history.push((frame, scene_arc.clone(), eye));
        }
        self.mesh = Some(mesh);
        img
    }
}

/// Registry entry of `spacetime-dept`.
pub static TECHNIQUE: crate::framework::technique::Preset<SpacetimeSettings> =
    crate::framework::technique::Preset {
        name: "spacetime-dept",
        summary: "photon density estimation on mesh elements, space-time window + bilateral filter",
        capabilities: crate::framework::technique::Capabilities {
            motion_blur: false,
            photons: true,
            window: true,
            max_depth: true,
            stateless: false,
            effort: crate::framework::technique::Effort {
                key: "photons",
                per_unit: 1000,
                unit: "thousand photons per frame",
            },
        },
        // Measured: BENCHMARKS.md, "The quality table" (the fastest candidate per level;
        // draft and preview with OIDN's fast network, which costs the same error less).
        quality: &[
            crate::framework::technique::QualityLevel::denoised(
                "draft",
                0.0953,
                &[("spp", "2"), ("photons", "32000")],
            )
            .fast(),
            // 128k photons cost 1 % more than 64k here (0.0799) for a tenth less error.
            crate::framework::technique::QualityLevel::denoised(
                "preview",
                0.0724,
                &[("spp", "4"), ("photons", "128000")],
            )
            .fast(),
            crate::framework::technique::QualityLevel::denoised(
                "final",
                0.063,
                &[("spp", "4"), ("photons", "256000")],
            ),
            // 512²: a camera sample costs 4× as much and the denoiser does more, so the
            // fastest route to each error moves (BENCHMARKS.md, 512² sweep). Preview keeps
            // spp 4: spp 2 and 3 reach 0.08 cheaper but flicker more than half Cycles'.
            // Photons are nearly free here (32k, 64k, 128k within the runs' noise), so
            // preview takes the count that lands nearest 0.08 (the 2026-12-07 one run).
            crate::framework::technique::QualityLevel::denoised(
                "draft",
                0.0895,
                &[("spp", "2"), ("photons", "32000")],
            )
            .fast()
            .at(512, 512),
            crate::framework::technique::QualityLevel::denoised(
                "preview",
                0.0778,
                &[("spp", "4"), ("photons", "64000")],
            )
            .fast()
            .at(512, 512),
            crate::framework::technique::QualityLevel::denoised(
                "final",
                0.0622,
                &[("spp", "4"), ("photons", "256000")],
            )
            .at(512, 512),
        ],
        defaults: SpacetimeSettings::default,
        common: |s| &mut s.common,
        build: |s, _, _| Ok(Box::new(SpacetimeDept::new(s))),
    };

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic "noise" in [−1, 1] (no RNG dependency in unit tests).
    fn wobble(k: usize) -> f32 {
        ((k as f32 * 12.9898).sin() * 43758.547).fract() * 2.0 - 1.0
    }

    #[test]
    fn static_series_keeps_the_whole_window() {
        // 9 frames of a constant 1.0 with ±1σ noise (σ = 0.05), threshold 3σ.
        let series: Vec<(f32, f32)> = (0..9).map(|k| (1.0 + 0.05 * wobble(k), 0.0025)).collect();
        for c in 0..9 {
            assert_eq!(choose_window(&series, c, 3.0, 0.02), (0, 8), "centre {c}");
        }
    }

    /// The automatic element count is that of a whole window's photons (2K + 1 frames,
    /// with the stopping rule its most photons per frame), whatever frame is output.
    #[test]
    fn automatic_elements_pool_a_whole_window() {
        use crate::kernels::elements::element_map::auto_elements;
        let s = SpacetimeSettings {
            photons: 4000,
            window: 4,
            ..Default::default()
        };
        assert_eq!(s.elements_per_diagonal(), auto_elements(36_000.0));
        let with_rule = SpacetimeSettings {
            auto: Some(AutoPhotons {
                max_photons: 8000,
                ..Default::default()
            }),
            ..s.clone()
        };
        assert_eq!(with_rule.elements_per_diagonal(), auto_elements(72_000.0));
        let fixed = SpacetimeSettings {
            elements: 100.0,
            ..s
        };
        assert_eq!(fixed.elements_per_diagonal(), 100.0);
    }

    #[test]
    fn a_step_cuts_the_window_on_both_sides_of_it() {
        // A 30 % drop between frames 4 and 5 with a per-frame σ of 12 %: the drop is only
        // 1.8 σ of a single-frame difference (the per-element test missed such steps),
        // but the frames on the two sides of the step pooled make it 30 % against
        // σ = 0.12·√(1/5 + 1/5) = 0.076, i.e. 3.9 σ > 3.
        let sigma = 0.12f32;
        let series: Vec<(f32, f32)> = (0..10)
            .map(|k| {
                let v = if k < 5 { 1.0 } else { 0.7 };
                (v + 0.3 * sigma * wobble(k), sigma * sigma)
            })
            .collect();
        for c in 0..10 {
            let (lo, hi) = choose_window(&series, c, 3.0, 0.02);
            if c < 5 {
                assert!(hi <= 4, "centre {c}: pooled up to {hi} across the step");
            } else {
                assert!(lo >= 5, "centre {c}: pooled down to {lo} across the step");
            }
        }
    }

    #[test]
    fn invisible_changes_are_pooled() {
        // A 1 % step, far below the 2 % visibility threshold, with no noise: pooled.
        let series: Vec<(f32, f32)> = (0..7)
            .map(|k| (if k < 3 { 1.0 } else { 1.01 }, 1e-8))
            .collect();
        assert_eq!(choose_window(&series, 3, 3.0, 0.02), (0, 6));
        assert_eq!(choose_window(&series, 3, 3.0, 0.005), (3, 6));
    }
}
