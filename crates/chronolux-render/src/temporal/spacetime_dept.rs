//! Space-time photon density estimation (`spacetime-dept`): DEPT whose element estimates
//! pool photons over a per-element temporal window and then over neighbouring elements,
//! with a bilateral filter that keeps abrupt changes (Myszkowski et al. 2001; Weber et al.,
//! "Spatio-temporal photon density estimation using bilateral filtering", CGI 2004).
//!
//! ## Per frame t
//! 1. Photons `t·N .. (t+1)·N` are traced with the shared kernel and deposited on the
//!    element mesh, which is built once from the first frame (stable element ids; rebuilt,
//!    and the history dropped, only if the topology changes). The frame's per-element
//!    sums (flux, count, Σφ²) and element areas go into a history of the last `window`
//!    frames (memory: O(elements × window)).
//! 2. **Temporal window, per element side**: starting from frame t, earlier frames
//!    t−1, t−2, … are added (ratio estimator Σ w_k Φ_k / (N Σ w_k A_k), Gaussian weight
//!    w_k in the frame distance, σ = `temporal_sigma`) until the element has enough
//!    photons (at least `target_photons` and a standard error below `weber` (2 %) of its
//!    total irradiance, direct included: the perceptual threshold of the stopping rule),
//!    or until the **energy test** fails: frame k's irradiance differs from the
//!    window's so far by more than `change_threshold` standard deviations of their
//!    difference (σ from Σφ², see `dept::reconstruct`). So static lighting pools
//!    up to `window` frames and a change (a light switching on, an object arriving) cuts
//!    the window at the change — the temporal blur the method is meant to avoid.
//! 3. **Spatial completion**: elements that still do not have enough photons are
//!    filtered with the spatial bilateral filter over neighbours' temporal estimates
//!    (range kernel from the estimates' noise, relaxed to a plain Gaussian below
//!    `min_photons`); elements with enough photons keep their own estimate.
//! 4. Vertex interpolation and the eye pass are those of `dept` (direct light per pixel).
//!
//! ## Causal window (design choice)
//! The `render` loop hands frames over in order; this renderer uses only the current and
//! **past** frames, so it needs neither a lag nor its own `FrameBuilder`, and frame t's
//! image never waits for frame t+1. The published method uses a window centred on t;
//! a causal window has the same variance reduction for static lighting and lags by
//! nothing at a change because the energy test cuts the window there, but after a change
//! the first frames have only their own photons (plus spatial filtering) until the new
//! lighting has accumulated.

use crate::dept::budget::luminances;
use crate::dept::budget::{AutoPhotons, PhotonCount, next_total};
use crate::dept::element_map::{
    ElementAccumulators, ElementMesh, FrameElements, FramePhotons, deposit_more_photons,
};
use crate::dept::reconstruct::{
    ElementSolution, Filter, Neighbours, filtered_irradiance_sigma, prior_sq, range_weight,
};
use crate::dept::{DeptSettings, assess_frame, render_view};
use crate::integrator::RenderedFrame;
use crate::sequence::SequenceRenderer;
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::parallel;
use std::collections::VecDeque;

/// Settings of `spacetime-dept`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpacetimeSettings {
    /// Photons per frame when `auto` is not set. Default 100 000.
    pub photons: u64,
    /// Stopping rule choosing the photons of each frame from the noise of the space-time
    /// reconstruction ([`crate::dept::budget`]); `None`: `photons`.
    pub auto: Option<AutoPhotons>,
    /// Camera samples per pixel. Default 16.
    pub spp: u32,
    /// Target element count along the scene diagonal. Default 100.
    pub elements: f32,
    /// Longest specular chain of eye rays. Default 8.
    pub max_specular_depth: u32,
    /// Past frames kept (longest temporal window = window + 1 frames). Default 8.
    pub window: u32,
    /// "Enough photons" for an element side, after which no further frames or neighbours
    /// are pooled: at least this many photons **and** a standard error below `weber` times
    /// the side's total irradiance (direct included, estimated from the frame's first-hit
    /// photons as in [`crate::dept::budget`]). Default 64.
    pub target_photons: u32,
    /// Luminance contrast (Weber fraction) below which an element's own noise is
    /// invisible, so pooling stops. Default 0.02 (the stopping rule's threshold). A pure
    /// count (the first version: 64 photons) left 12.5 % noise on every element that
    /// reached it, which with a few hundred thousand photons per frame was most of them,
    /// unfiltered: noisier than the Gaussian baseline at equal photons.
    pub weber: f32,
    /// Energy test: standard deviations of difference that mean "the lighting changed".
    /// Default 3.
    pub change_threshold: f32,
    /// Temporal Gaussian σ in frames. Default 4.
    pub temporal_sigma: f32,
    /// Spatial filter radius in element sizes. Default 2.5.
    pub radius: f32,
    /// Range kernel width in noise standard deviations. Default 2.
    pub kappa: f32,
    /// Below this many photons the range kernel is dropped (plain Gaussian). Default 8.
    pub min_photons: u32,
    /// Seed of the photon and camera streams. Default 0.
    pub seed: u64,
}

impl Default for SpacetimeSettings {
    fn default() -> Self {
        SpacetimeSettings {
            photons: 100_000,
            auto: None,
            spp: 16,
            elements: 100.0,
            max_specular_depth: 8,
            window: 8,
            target_photons: 64,
            weber: 0.02,
            change_threshold: 3.0,
            temporal_sigma: 4.0,
            radius: 2.5,
            kappa: 2.0,
            min_photons: 8,
            seed: 0,
        }
    }
}

impl SpacetimeSettings {
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

/// One past frame's sums.
struct HistoryFrame {
    frame: u32,
    photons: FramePhotons,
    area: Vec<f32>,
}

/// The `spacetime-dept` sequence renderer.
pub struct SpacetimeDept {
    pub settings: SpacetimeSettings,
    mesh: Option<ElementMesh>,
    history: VecDeque<HistoryFrame>,
}

impl SpacetimeDept {
    pub fn new(settings: SpacetimeSettings) -> Self {
        SpacetimeDept {
            settings,
            mesh: None,
            history: VecDeque::new(),
        }
    }

    fn dept_settings(&self) -> DeptSettings {
        let s = &self.settings;
        DeptSettings {
            photons: s.photons,
            spp: s.spp,
            elements: s.elements,
            max_specular_depth: s.max_specular_depth,
            seed: s.seed,
            ..Default::default()
        }
    }

    /// True when an element side with `count` photons, luminance irradiance `e`, standard
    /// error `sigma` and direct irradiance `direct` needs no more photons.
    #[inline]
    fn enough(&self, count: u32, e: f32, sigma: f32, direct: f32) -> bool {
        let s = &self.settings;
        count >= s.target_photons && sigma <= s.weber * (e + direct).max(0.0)
    }

    /// Temporal pooling of one field (indirect or caustic) over the history (newest
    /// last): returns pooled sums as accumulators plus the pooled areas. Frames may have
    /// different photon counts (stopping rule): each frame's sums are divided by its own
    /// count, so the returned accumulators are per unit photon (`photons = 1`).
    fn pool(
        &self,
        field: impl Fn(&FramePhotons) -> &ElementAccumulators + Sync,
        direct: &[f32],
    ) -> (ElementAccumulators, Vec<f32>) {
        let s = &self.settings;
        let cur = self.history.back().expect("current frame in history");
        let acc = field(&cur.photons);
        let n_slots = acc.flux.len();
        let inv_n = 1.0 / acc.photons.max(1) as f32;
        let inv2s2 = 1.0 / (2.0 * s.temporal_sigma.max(1e-3).powi(2));
        let pool_slot = |slot: usize| {
            let a0 = cur.area[slot / 2];
            let (mut phi, mut a, mut cnt, mut sq) = (
                acc.flux[slot] * inv_n,
                a0,
                acc.count[slot],
                acc.flux_sq[slot] * inv_n * inv_n,
            );
            for past in self.history.iter().rev().skip(1) {
                if a <= 0.0 || self.enough(cnt, luminance(phi) / a, sq.sqrt() / a, direct[slot]) {
                    break;
                }
                let p = field(&past.photons);
                let inv_k = 1.0 / p.photons.max(1) as f32;
                let ak = past.area[slot / 2];
                if ak <= 0.0 {
                    break;
                }
                // Energy test against the window so far.
                let e_win = luminance(phi) / a;
                let e_k = luminance(p.flux[slot]) * inv_k / ak;
                let var = sq / (a * a) + (p.flux_sq[slot] * inv_k * inv_k) / (ak * ak);
                let diff = (e_k - e_win).abs();
                if diff > s.change_threshold * var.sqrt() + 1e-6 * e_win.max(e_k) {
                    break;
                }
                let dt = (cur.frame - past.frame) as f32;
                let w = (-dt * dt * inv2s2).exp();
                phi += p.flux[slot] * (w * inv_k);
                a += ak * w;
                cnt += p.count[slot];
                sq += p.flux_sq[slot] * (w * inv_k) * (w * inv_k);
            }
            (phi, cnt, sq, a)
        };
        // Per-slot work is independent: parallel chunks, concatenated in order.
        let rows = parallel::map_chunks(n_slots, 4096, |r| r.map(pool_slot).collect::<Vec<_>>());
        let mut out = ElementAccumulators::new(n_slots / 2);
        out.photons = 1;
        let mut area = Vec::with_capacity(n_slots);
        for (slot, (phi, cnt, sq, a)) in rows.into_iter().flatten().enumerate() {
            out.flux[slot] = phi;
            out.count[slot] = cnt;
            out.flux_sq[slot] = sq;
            area.push(a);
        }
        (out, area)
    }

    /// Spatial completion of pooled sums: bilateral over neighbours for elements short of
    /// `target_photons`, their own estimate otherwise. Returns irradiance per slot.
    /// Also returns the standard error of each luminance estimate, with `prior` (per unit
    /// photon, see [`crate::dept::reconstruct::filter_with_sigma`]) added to every Σφ².
    #[allow(clippy::too_many_arguments)]
    fn complete(
        &self,
        pooled: &ElementAccumulators,
        area: &[f32],
        fe: &FrameElements,
        nb: &Neighbours,
        prior: f32,
        direct: &[f32],
    ) -> (Vec<Rgb>, Vec<f32>) {
        let s = &self.settings;
        let inv_n = 1.0 / pooled.photons.max(1) as f32;
        let est = |slot: usize| {
            if area[slot] > 0.0 {
                luminance(pooled.flux[slot]) * inv_n / area[slot]
            } else {
                0.0
            }
        };
        let sig = |slot: usize| {
            if area[slot] > 0.0 {
                pooled.flux_sq[slot].sqrt() * inv_n / area[slot]
            } else {
                0.0
            }
        };
        let sigma_s = 0.5 * nb.radius;
        let inv2s2 = 1.0 / (2.0 * sigma_s * sigma_s).max(1e-12);
        let n = fe.area.len();
        let rows = parallel::map_chunks(n, 1024, |range| {
            let mut out = Vec::with_capacity(2 * range.len());
            for e in range {
                for side in 0..2 {
                    let se = 2 * e + side;
                    if area[se] > 0.0 && self.enough(pooled.count[se], est(se), sig(se), direct[se])
                    {
                        out.push(if area[se] > 0.0 {
                            (
                                pooled.flux[se] * (inv_n / area[se]),
                                (pooled.flux_sq[se] + prior).sqrt() * inv_n / area[se],
                            )
                        } else {
                            (Rgb::ZERO, 0.0)
                        });
                        continue;
                    }
                    let relax = pooled.count[se] < s.min_photons;
                    let (mut num, mut den, mut sq) = (Rgb::ZERO, 0.0f32, 0.0f32);
                    for &(j, d2) in nb.of(e) {
                        let sj = 2 * j as usize + side;
                        let w = range_weight(est(se), est(sj), sig(se), sig(sj), s.kappa, relax)
                            * (-d2 * inv2s2).exp();
                        num += pooled.flux[sj] * w;
                        den += area[sj] * w;
                        sq += (pooled.flux_sq[sj] + prior) * w * w;
                    }
                    out.push(if den > 0.0 {
                        (num * (inv_n / den), sq.sqrt() * inv_n / den)
                    } else {
                        (Rgb::ZERO, 0.0)
                    });
                }
            }
            out
        });
        rows.into_iter().flatten().unzip()
    }
}

impl SequenceRenderer for SpacetimeDept {
    fn name(&self) -> &'static str {
        "spacetime-dept"
    }

    fn render_frame(
        &mut self,
        source: &mut chronolux_core::scene::source::FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let scene = source.frame(frame);
        let scene = &*scene;
        let s = self.settings.clone();
        if !self.mesh.as_ref().is_some_and(|m| m.matches(scene)) {
            self.mesh = Some(ElementMesh::build(scene, s.elements));
            self.history.clear();
        }
        let mesh = self.mesh.take().expect("mesh");
        let fe = FrameElements::new(scene, &mesh);
        // Frames must arrive in increasing order; a jump back restarts the history.
        if self.history.back().is_some_and(|h| h.frame >= frame) {
            self.history.clear();
        }
        self.history.push_back(HistoryFrame {
            frame,
            photons: FramePhotons::new(mesh.element_count()),
            area: fe.area.clone(),
        });
        while self.history.len() > s.window as usize + 1 {
            self.history.pop_front();
        }
        let nb = Neighbours::new(&fe, s.radius * mesh.element_size);
        // Fixed count: photons `frame·N ..`; stopping rule: the first of
        // `frame·max_photons ..`, in batches, judged on the space-time reconstruction.
        let (base, mut total) = match s.auto {
            None => (frame as u64 * s.photons, s.photons),
            Some(a) => (
                frame as u64 * a.max_photons,
                a.batch.clamp(1, a.max_photons.max(1)),
            ),
        };
        let (ind, cau) = loop {
            let cur = &mut self.history.back_mut().expect("current frame").photons;
            let done = cur.photons();
            deposit_more_photons(scene, &mesh, base + done..base + total, s.seed, cur);
            let inv_n = 1.0 / cur.photons().max(1) as f32;
            let prior_i = prior_sq(&cur.indirect) * inv_n * inv_n;
            let prior_c = prior_sq(&cur.caustic) * inv_n * inv_n;
            let (direct, _) = filtered_irradiance_sigma(
                &mesh,
                &cur.direct,
                &fe,
                Filter::Gaussian { radius: 2.5 },
            );
            let direct = luminances(&direct);
            let (ind, ind_area) = self.pool(|p| &p.indirect, &direct);
            let (cau, cau_area) = self.pool(|p| &p.caustic, &direct);
            let (ind, si) = self.complete(&ind, &ind_area, &fe, &nb, prior_i, &direct);
            let (cau, sc) = self.complete(&cau, &cau_area, &fe, &nb, prior_c, &direct);
            let Some(rule) = s.auto else {
                break (ind, cau);
            };
            let cur = &self.history.back().expect("current frame").photons;
            let a = assess_frame(&rule, &mesh, &fe, cur, &ind, &cau, &si, &sc);
            log::debug!(
                "spacetime-dept frame {frame}: {total} photons, {:.1} % of the power-weighted surface above the {} contrast threshold, {} photons predicted",
                100.0 * a.fraction_above,
                rule.weber,
                a.predicted_photons
            );
            match next_total(&rule, total, &a) {
                Some(t) => total = t,
                None => break (ind, cau),
            }
        };
        let photon_rays = self
            .history
            .back()
            .expect("current frame")
            .photons
            .stats
            .rays;
        let indirect = ElementSolution::from_elements(&mesh, &fe, &ind);
        let caustic = ElementSolution::from_elements(&mesh, &fe, &cau);
        let mut img = render_view(
            &self.dept_settings(),
            scene,
            frame,
            &mesh,
            &indirect,
            &caustic,
            progress,
        );
        img.stats.rays += photon_rays;
        self.mesh = Some(mesh);
        img
    }

    fn photons_last_frame(&self) -> Option<u64> {
        self.history.back().map(|h| h.photons.photons())
    }
}
