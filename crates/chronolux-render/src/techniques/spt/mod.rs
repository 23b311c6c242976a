//! Selective photon tracing (SPT; Dmitriev, Brabec, Myszkowski, Seidel, "Interactive
//! Global Illumination Using Selective Photon Tracing", EGWR 2002): a fixed pool of
//! quasi-random photons is traced once; when the scene changes, only the photons whose
//! paths the change invalidated are re-shot — their old deposits removed, their new paths
//! deposited — on the element mesh of the `dept` family.
//!
//! ## Method
//! - **Pool and groups** ([`groups`]): `Z` photons, photon `i` always from Halton point `i`
//!   ([`crate::kernels::photon`], whose dimension order puts emission — light choice and
//!   point on the light (bases 2, 3), direction (5, 7) — and the first bounce's direction
//!   (11, 13) first). Group `r` is the photons `i ≡ r (mod N_g)`. **Equation 1** of the
//!   paper: when `b_j^k_j` divides `N_g`, two members of a group agree in dimension `j` to
//!   within `b_j^-k_j`; `N_g = Π b_j^k_j` is chosen greedily from `Z / group_size`
//!   (default 64 photons per group), widest cell first, so that a group's photons leave
//!   the light from nearby points in nearby directions and bounce the first time in
//!   nearby directions (a test checks the bound on the generated points).
//! - **Scrambling**: the kernel's per-dimension Cranley–Patterson shift (from the seed)
//!   and nothing else. It adds one constant modulo 1 to every point of a dimension, so
//!   the members of a group, which share an aligned interval of width `b_j^-k_j` before
//!   the shift, stay within that distance on the torus after it (the bound holds for the
//!   toroidal distance); only one group in `b_j^k_j` per dimension has its interval cut by
//!   the wrap at 1. A digit-permuting (Owen/Faure) scrambling would also keep the groups
//!   (it maps aligned intervals to aligned intervals), but the kernel is shared with the
//!   other photon methods and the shift is what they use.
//! - **Signed deposits** ([`pool::SignedAccumulators`]): each photon's last path is
//!   stored (its light, and per vertex the instance, material, triangle, element side,
//!   deposit kind and power); re-shooting a photon subtracts exactly the deposits it
//!   made and adds the new ones, in `f64`, so re-shooting in an unchanged scene returns
//!   the solution to itself up to rounding, and counters and `Σφ²` (the noise estimate)
//!   always describe the photons currently in the solution.
//! - **Pilots** (the paper's detector; traced when `scan_paths = false`, or with
//!   `trace_pilots = true`): members `0 .. p` of every group, `p = max(1,
//!   round(pilot_fraction · Z/N_g))` (default 7 %), are re-traced after every change. A pilot invalidates its
//!   group when its stored (old) or new path touches an instance, light or material that
//!   changed ([`FrameDelta`](chronolux_core::scene::delta::FrameDelta)), or when the two
//!   paths differ (light, vertex count, instance, material, triangle, element side, kind,
//!   or power by more than `path_tolerance` relative). Pilots are brought up to date at
//!   once; [`pool::SptState::audit`] counts the misses (stale groups whose pilots saw
//!   nothing) by re-tracing the whole pool. Measured on the demo's block jump (60k
//!   photons, 1260 groups, 3 pilots each): the pilots find 258 of the 970 stale groups,
//!   a miss rate of 75 % (2228 of 4907 stale photons) — the groups of Eq. 1 are not
//!   coherent enough at this `N_g` for a few pilots to speak for 48 photons.
//! - **Path scan** (`scan_paths`, default on; not in the paper): because every photon's
//!   last path is stored, the photons that a change can affect are known without tracing:
//!   those whose stored path touched a changed instance, light or material, and those with
//!   a segment (emission point → vertices → escape ray) crossing the new bounds of a
//!   changed instance. A path can change only in one of these two ways, so the scan is
//!   complete (miss rate 0, tested) and conservative (a segment may cross a box and miss
//!   what is in it). With it, `reshoot = flagged` (default) re-shoots only the flagged
//!   photons of a queued group instead of all of them (`reshoot = group`, the paper).
//! - **No pilots, single photons** (defaults `trace_pilots = false`, `reshoot =
//!   photon`; not in the paper): with a complete scan the pilots detect nothing the scan
//!   has not found, and they were half of the photons of an update (block jump: 23.1k of
//!   47.0k, capping the CPU speedup over scratch at half the photon speedup). So the scan
//!   alone both finds and ranks: each flagged photon enters the queue by itself, keyed by
//!   the perceived change of removing its stored path (below), and is re-shot when its
//!   turn comes — the unit of re-shooting is the photon, not the Eq.-1 group, whose
//!   members are too incoherent to share a fate (item 2 of BENCHMARKS.md's Issue 11: 8 %
//!   of the photons change, in 80 % of the groups). The final pool is the same with or
//!   without pilots, groups or photons (every record equals its fresh trace: tested).
//! - **Order** ([`Order`]): queued groups (or photons) are re-shot one after the other,
//!   `priority` first by their perceptual change (Σ over the element sides of a path's
//!   indirect and caustic deposits of the Weber contrast of the deposit against the
//!   side's total flux, weighted by the side's screen coverage,
//!   `SptState::perceived_change`: for a group, what its pilots saw change plus the
//!   removal of its flagged photons; for a photon, the removal of its stored path), or
//!   in `random` order (the same queue with random keys), or `scratch`: every change
//!   empties the solution and the pool is shot again from photon 0 (recomputation from
//!   scratch with the same photons).
//! - **Which random order**: with the path scan, `random` re-shoots exactly the flagged
//!   photons, only in another order — it already knows which photons are invalid, so
//!   against it priority can gain only what the order gains. The paper's random
//!   baseline re-traces photons without knowing which are invalid; `chronolux bench
//!   update` measures it separately as `random_pool` (the whole pool in random order,
//!   each photon removed and re-added), and reports both. Measured (BENCHMARKS.md Issue
//!   11, 300k photons, one thread, `--change nudge`): priority and random order re-shoot
//!   the same 11.1k photons, and the visible difference lies on sides most of them touch
//!   (no visible difference after 86 % of them in priority order, 99 % in random order),
//!   so the order gains at most ≈ 1.15× in photons and ≈ 1× in CPU (priority also pays
//!   the coverage and the keys); random over the pool needs ≈ 99 % of the pool to reach
//!   every invalid photon: 11.4× the CPU of priority (jump 5.1–5.5×). ≥ 3× over the
//!   exact-flag `random` would need a change most of whose flagged photons make no
//!   visible difference (off screen or masked by brighter surroundings) — a property of
//!   the change, which no order creates; on these rooms it does not hold.
//! - **Cost of an update** (nudge, CPU ms, 2026-12-08 second run, third A/B): scan
//!   7.9–8.5, keys 2.9, coverage 0.1, trace 14.1–14.4, apply 7.9–8.4 (33.6 in all),
//!   against 267–278 for scratch: 7.9–8.3× (31× in photons). A flagged photon's path is
//!   longer (3.77 rays against 2.30 for the pool), which no bookkeeping removes. Of the
//!   scan, most is now one pass over the 300k summaries (112 B each) with their quantized
//!   segment tests; 5.4k paths reach the exact test, ≈ 450 ns each for those that read
//!   their scattered record.
//! - **Cheap scan** (`scan_bounds`, default on): per photon a contiguous
//!   [`pool::PathSummary`] (padded box of the path, open along its escape ray; instance
//!   and material masks, exact for ≤ 64 of each; its points — up to 8 vertices and an
//!   escape ray's exit from the grid box — on a 16-bit [`pool::QuantGrid`]) and
//!   [`pool::PathPoints`] (the first vertices, in `f32`). The scan tests the quantized
//!   segments against the changed bounds grown by two grid steps (a point moves by at
//!   most half a step), all within the one sequential read of the summaries, and reads
//!   the scattered points or record only for the paths that test cannot rule out (nudge:
//!   5.4k of 300k, from 85k with the box alone); the flags equal the full scan's (tested,
//!   and a brute-force test that the quantized test never rules out a crossing). The
//!   coverage grid keeps its rays and re-traces only those a change can affect (equal to
//!   a full recomputation, tested); coverage and keys are computed only in priority
//!   order; Φ₀ and the side weights of the keys come from one pass over the sums.
//! - **Re-shooting without allocation**: re-shot photons are traced into one vertex
//!   buffer per batch of 256 ([`pool::TracedBatch`]); the removal reads the old record,
//!   the addition the batch, and the record's own vertex buffer is overwritten in place
//!   (it keeps its capacity: no allocation or free per photon) — in the update and in
//!   scratch alike, which is the baseline and gains about as much (nudge, means of four
//!   samples: update 39.5 → 35.3 ms, scratch 301 → 280).
//! - **Tried and not kept** (measured, BENCHMARKS.md Issue 11 and
//!   `bench-results/2026-12-08-spt2/explore`): (1) an index of the stored segments, cell
//!   → photon ids, appended when a photon is re-shot, stale entries left for a lazy
//!   rebuild (3-D DDA; flags equal to the full scan): the nudge's scan fell from 10.6 to
//!   2.0–3.5 ms (candidates 85k → 6–12k) but entering a re-shot photon's segments cost as
//!   much (apply + 6–12 ms at 8–24 cells on the long axis), so the update broke even at
//!   best, and indexing the pool cost about half of shooting it; (2) a 64-bit mask of
//!   4 × 4 × 4 cells per path summary: candidates 85k → 75k only (the floor cells around
//!   the block hold most paths' last vertices), + 2 ms in apply; (3) one 64-byte line per
//!   side for flux, count and Σφ²: no measurable gain in apply, 60 % more memory; (4) a
//!   padded box per segment before the slab test, and a two-pass scan (summaries, then
//!   the candidates as independent reads): scan not faster; (5) `PATH_POINTS` 8: scan
//!   − 0.8 ms, within the noise of the whole update, for 36 B more per photon (the
//!   quantized points do it better).
//! - **Restart** (`restart_fraction`, default 0.5): when the scan flags more than this
//!   fraction of the pool (a lamp moved: all of it), re-shooting each photon (removal,
//!   addition, key) costs more than shooting the pool again, so the update restarts from
//!   scratch (as `order = scratch`), reported as `restarted`.
//! - **Animation**: frame `f + 1` updates frame `f`'s state with the changes between the
//!   two frames, within a per-frame budget (`budget_fraction` of `Z` photons, and/or
//!   `budget_ms`); leftover groups stay queued for the next frame (`groups_queued` in the
//!   frame's report). The eye pass ([`view`]) takes direct light per pixel by
//!   next-event estimation, diffuse indirect light from the (filtered) elements, and
//!   traces glossy reflections on (a reader of the shared eye walk,
//!   [`crate::kernels::eye`]).
//!
//! ## Deviations from Dmitriev et al. 2002
//! - Old paths are not re-traced in the old scene: their deposits are stored and
//!   subtracted. Exact, half the tracing, and it works when a group is re-shot several
//!   changes after it was invalidated (the scene it was last traced in is gone — the
//!   viewer's case).
//! - Deposits go to the elements of [`crate::kernels::elements::element_map`] (per element side,
//!   moving with their object) instead of the paper's per-vertex hit-point mesh; the
//!   solution is reconstructed each frame with the `dept` filter.
//! - The light choice is folded into the first emission coordinate (so multi-light and
//!   area-light scenes keep coherent groups); the paper's scenes use a few point lights.
//! - Priority: the paper orders by the pilots' energy change; here that change is
//!   weighted by screen coverage and taken as a Weber contrast (masking by bright
//!   surroundings, as in Myszkowski's perception-guided rendering).
//! - Pilots are a fixed prefix of each group rather than a random subset.
//! - The path scan, per-photon re-shooting and no pilots above (settings; `--set
//!   scan_paths=false --set reshoot=group` is the paper's detector and granularity).

pub mod groups;
pub mod pool;
pub mod view;

use crate::framework::integrator::{RenderedFrame, render_camera_rays};
use crate::kernels::elements::reconstruct::{ElementSolution, Filter, filtered_irradiance};
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use pool::{Budget, SptState, UpdateStats};
use std::sync::Arc;
use std::time::Duration;

/// In which order queued groups are re-shot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    /// By the perceptual change the pilots saw (largest first).
    Priority,
    /// Random (the paper's baseline).
    Random,
    /// Recompute from scratch: every change empties the solution and re-shoots the pool.
    Scratch,
}

/// What re-shooting a queued group traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reshoot {
    /// Every photon of the group (the paper).
    Group,
    /// Only the photons the path scan flagged (exact when `scan_paths` is on, which makes
    /// the flags complete; with `scan_paths = false` whole groups are re-shot).
    Flagged,
    /// The flagged photons one by one, each in its own place in the order (its own
    /// perceived change, or its own random key): the queue holds photons, not groups.
    /// Needs `scan_paths` (else whole groups are re-shot); `scratch` order re-shoots
    /// groups whatever this says.
    Photon,
}

/// Settings of `spt`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SptSettings {
    /// Camera samples, path depth and seed ([`crate::framework::technique::CommonSettings`]). `spp`:
    /// Camera samples per pixel. Default 16. `seed`: Seed of the photon and camera streams.
    /// Default 0. `max_depth`: not implemented (must stay `None`: the eye walk ends at
    /// `max_specular_depth`)
    #[serde(flatten)]
    pub common: crate::framework::technique::CommonSettings,
    /// Photons in the pool (`Z`, rounded to a multiple of the group count). Default 300 000.
    pub photons: u64,
    /// Target photons per group (`N_g ≈ Z / group_size`). Default 64.
    pub group_size: u64,
    /// Fraction of each group re-traced as pilots after every change. Default 0.07.
    pub pilot_fraction: f32,
    /// Order of re-shooting: `priority`, `random` or `scratch`. Default `priority`.
    pub order: Order,
    /// Photons re-shot per frame, as a fraction of the pool (pilots not counted; 0 = no
    /// photon limit). Default 0.25.
    pub budget_fraction: f64,
    /// Wall-clock milliseconds of re-shooting per frame (0 = no time limit). Default 0.
    pub budget_ms: f64,
    /// Besides the pilots, scan the stored paths: queue the groups of photons whose last
    /// path touched a change or crosses the new bounds of a changed instance (complete:
    /// no stale group is missed). `false`: pilots only, as in the paper. Default true.
    pub scan_paths: bool,
    /// What is re-shot: `photon` (the flagged photons, each queued by itself), `flagged`
    /// (a queued group's flagged photons) or `group` (all of a queued group's photons,
    /// as in the paper). Default `photon`.
    pub reshoot: Reshoot,
    /// Trace the pilots also when the path scan is on (it finds every stale photon
    /// without them; the pilots then only add their observed change to the priority of
    /// their groups). With `scan_paths = false` the pilots are the detector and are
    /// always traced. Default false.
    pub trace_pilots: bool,
    /// Test each stored path's summary (box, instance and material masks: one contiguous
    /// array) before reading its vertices in the path scan; `false`: the full test on
    /// every stored path (the same flags, slower). Default true.
    pub scan_bounds: bool,
    /// When the path scan flags more than this fraction of the pool, the update restarts
    /// from scratch (empty solution, the pool re-shot group by group in index order, as
    /// `order = scratch` does) instead of re-shooting the flagged photons one by one
    /// (each a removal, a new path and a key): reported as `restarted`. 1 = never.
    /// Default 0.5.
    pub restart_fraction: f64,
    /// Relative power difference at which a pilot's path counts as changed. Default 1e-4.
    pub path_tolerance: f32,
    /// Re-trace the whole pool after each update to count the pilots' misses (costly;
    /// reported as `audit`). Default false.
    pub audit: bool,
    /// Target element count along the scene's bounding-box diagonal. 0 (default): chosen
    /// from the pool's photons ([`crate::kernels::elements::element_map::auto_elements`]; 29 at the
    /// default 300k).
    pub elements: f32,
    /// Longest chain of delta bounces followed by eye rays. Default 8.
    pub max_specular_depth: u32,
    /// Most glossy bounces traced by eye rays before reading the elements. Default 2.
    pub max_glossy_depth: u32,
    /// Perceptual roughness below which a specular lobe is traced rather than read from
    /// the elements. Default 0.5.
    pub glossy_roughness: f32,
    /// Filtering of the element estimates (default: `dept-spatial`'s Gaussian, radius 2.5).
    pub filter: Filter,
}

impl Default for SptSettings {
    fn default() -> Self {
        SptSettings {
            common: crate::framework::technique::CommonSettings {
                spp: 16,
                max_depth: None,
                seed: 0,
            },
            photons: 300_000,
            group_size: 64,
            pilot_fraction: 0.07,
            order: Order::Priority,
            budget_fraction: 0.25,
            budget_ms: 0.0,
            scan_paths: true,
            reshoot: Reshoot::Photon,
            trace_pilots: false,
            scan_bounds: true,
            restart_fraction: 0.5,
            path_tolerance: 1e-4,
            audit: false,
            elements: 0.0,
            max_specular_depth: 8,
            max_glossy_depth: 2,
            glossy_roughness: 0.5,
            filter: Filter::Gaussian { radius: 2.5 },
        }
    }
}

impl SptSettings {
    /// Elements per scene diagonal: `elements`, or when 0 the automatic count for the
    /// pool's photons (the photons each element estimate holds).
    pub fn elements_per_diagonal(&self) -> f32 {
        crate::kernels::elements::element_map::elements_per_diagonal(
            self.elements,
            self.photons as f64,
        )
    }

    /// Whether an update traces the pilots: always without the path scan (they are the
    /// detector), with it only when `trace_pilots` asks.
    pub fn uses_pilots(&self) -> bool {
        !self.scan_paths || self.trace_pilots
    }

    /// Whether the queue holds single photons (`reshoot = photon` with the path scan, in
    /// an order other than `scratch`) rather than groups.
    pub fn per_photon(&self) -> bool {
        self.scan_paths && self.reshoot == Reshoot::Photon && self.order != Order::Scratch
    }

    /// The per-frame budget of these settings for a pool of `z` photons.
    pub fn frame_budget(&self, z: u64) -> Budget {
        Budget {
            photons: if self.budget_fraction > 0.0 {
                ((self.budget_fraction * z as f64).ceil() as u64).max(1)
            } else {
                0
            },
            time: (self.budget_ms > 0.0).then(|| Duration::from_secs_f64(self.budget_ms * 1e-3)),
        }
    }
}

/// The reconstructed indirect and caustic fields of a state (with `filter`).
pub fn reconstruct(state: &SptState, filter: Filter) -> (ElementSolution, ElementSolution) {
    let fe = state.frame_elements();
    let (_, ind, cau) = state.accumulators();
    let i = filtered_irradiance(&state.mesh, &ind, &fe, filter);
    let c = filtered_irradiance(&state.mesh, &cau, &fe, filter);
    (
        ElementSolution::from_elements(&state.mesh, &fe, &i),
        ElementSolution::from_elements(&state.mesh, &fe, &c),
    )
}

/// Eye pass of a state in its current scene.
pub fn render_state(
    state: &SptState,
    frame: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    let s = &state.settings;
    let (indirect, caustic) = reconstruct(state, s.filter);
    let v = view::SptView {
        mesh: &state.mesh,
        indirect: &indirect,
        caustic: &caustic,
        max_specular_depth: s.max_specular_depth,
        max_glossy_depth: s.max_glossy_depth,
        glossy_roughness: s.glossy_roughness,
    };
    render_camera_rays(
        &v,
        state.scene(),
        frame,
        s.common.spp,
        s.common.seed,
        progress,
    )
}

/// `spt` as a sequence renderer: frame `f + 1` updates frame `f`'s pool.
pub struct Spt {
    pub settings: SptSettings,
    state: Option<SptState>,
}

impl Spt {
    pub fn new(settings: SptSettings) -> Self {
        Spt {
            settings,
            state: None,
        }
    }

    /// The state after the last frame (for tests and tools).
    pub fn state(&self) -> Option<&SptState> {
        self.state.as_ref()
    }

    /// Brings the state to `scene`: a new pool on the first frame or after a topology
    /// change (`rebuilt`), otherwise an update within the frame budget.
    fn advance(&mut self, scene: Arc<FrameScene>) -> (UpdateStats, bool) {
        match &mut self.state {
            Some(st) if st.accepts(&scene) => {
                let changes = chronolux_core::scene::delta::FrameDelta::between(st.scene(), &scene);
                let budget = self.settings.frame_budget(st.layout.photons());
                (st.update(scene, &changes, budget), false)
            }
            _ => {
                let t0 = std::time::Instant::now();
                let st = SptState::new(scene, self.settings.clone());
                let z = st.layout.photons();
                self.state = Some(st);
                let stats = UpdateStats {
                    photons_traced: z,
                    seconds: t0.elapsed().as_secs_f64(),
                    ..Default::default()
                };
                (stats, true)
            }
        }
    }
}

impl crate::framework::sequence::SequenceRenderer for Spt {
    fn name(&self) -> &'static str {
        "spt"
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let scene = source.frame(frame);
        let (u, rebuilt) = self.advance(scene);
        let st = self.state.as_ref().expect("state after advance");
        let mut out = render_state(st, frame, progress);
        out.stats.rays += u.rays;
        let r = &mut out.report;
        r.insert("photons".into(), st.photons_in_solution().into());
        r.insert("pool".into(), st.layout.photons().into());
        r.insert("groups".into(), st.layout.groups.into());
        r.insert("rebuilt".into(), rebuilt.into());
        r.insert("photons_traced".into(), u.photons_traced.into());
        r.insert("pilots_traced".into(), u.pilots_traced.into());
        r.insert("groups_invalidated".into(), u.groups_invalidated.into());
        r.insert("groups_by_pilots".into(), u.groups_by_pilots.into());
        r.insert("groups_by_scan".into(), u.groups_by_scan.into());
        r.insert("groups_reshot".into(), u.groups_reshot.into());
        r.insert("groups_carried_over".into(), u.groups_queued.into());
        r.insert("update_seconds".into(), u.seconds.into());
        if self.settings.audit && !rebuilt {
            let a = st.audit();
            r.insert(
                "audit".into(),
                serde_json::to_value(a).expect("audit serialises"),
            );
        }
        out
    }
}

/// Registry entry of `spt`.
pub static TECHNIQUE: crate::framework::technique::Preset<SptSettings> =
    crate::framework::technique::Preset {
        name: "spt",
        summary: "selective photon tracing (Dmitriev et al. 2002): a fixed photon pool on mesh elements, only the groups a change invalidates re-shot",
        capabilities: crate::framework::technique::Capabilities {
            motion_blur: false,
            photons: true,
            window: false,
            max_depth: false,
            stateless: false,
            effort: crate::framework::technique::Effort {
                key: "photons",
                per_unit: 1000,
                unit: "thousand photons in the pool",
            },
        },
        quality: &[],
        defaults: SptSettings::default,
        common: |s| &mut s.common,
        build: |s, _, _| Ok(Box::new(Spt::new(s))),
    };
