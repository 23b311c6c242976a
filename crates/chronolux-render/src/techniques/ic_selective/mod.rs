//! `ic-selective`: photon mapping with an irradiance cache whose records keep their gather
//! directions between frames and re-cast only a part of them each frame (Tawara,
//! Myszkowski, Seidel, "Exploiting temporal coherence in final gathering for dynamic
//! scenes", CGI 2004; summarised in Tawara et al., SCCG 2004, §3.2).
//!
//! ## Method (per frame `f`)
//! Everything but the final gathering is `pm-ic`'s ([`super`]): the photons of frame `f`
//! (photons `f·N ..`, or `0..N` with `fixed_photons`), the caustic map, the eye pass and
//! the probe pass. The global photons are split by the light group they left and each
//! group's map gets precomputed irradiance (`light_terms`, default;
//! [`crate::kernels::gather::precomputed`], Christensen 1999; below, "Light changes").
//! Each record keeps, per stratum `(j, k)` of its `M × N` gather, a [`Stratum`]: the
//! incident radiance, the hit distance, the instance hit, the frame it was cast in (its
//! **age** is `f` minus that), the vertex its radiance was read at (point, normal,
//! weight) and one **term per light group** (the radiance is their sum), in a
//! [`StrataStore`] (paged on disk by default, see [`store`]). A stratum cast in frame `c`
//! points along the direction of [`stratum_direction`] jittered by numbers hashed from
//! `(seed, c, record id, stratum)`, and its gather ray reads frame `c`'s maps: each
//! group's term is one nearest-neighbour read of its precomputed map (without
//! `light_terms`: one k-NN radiance estimate of frame `c`'s global map).
//!
//! 1. **What changed** since the previous frame rendered: [`FrameDelta::between`].
//! 2. **Records whose own surface changed** (their instance moved or was deformed) are
//!    dropped (their slots freed); the probe pass below makes new ones where the view
//!    needs them — rebuilt at their new place.
//! 3. **Records in use**: the probe points of `f` (as `pm-ic`) mark every record valid at
//!    one of them; the others are dropped (the view no longer needs them).
//! 4. **Refresh** of each record in use (in parallel; the store is read and written in
//!    record order, in chunks of [`CHUNK`] records):
//!    - **priority** strata, re-cast whatever their age: those whose hit instance changed
//!      (moved or deformed), and those whose ray segment (record → hit, or unbounded when
//!      nothing was hit) crosses the world box of a changed instance in the previous or
//!      this frame (an object that moved into or out of the direction) **and** meets the
//!      changed geometry itself in one of the two frames (`exact_priority`, default on:
//!      one any-hit query per such segment against each frame reduced to its changed
//!      instances, [`FrameScene::without_instances`]; both tests are necessary conditions
//!      for the first hit to change, so their conjunction still re-casts every stratum
//!      whose hit changed, checked bit for bit in `tests/it/icsel.rs`); **all** strata
//!      when a material changed (or the light grouping did, or, without `light_terms`,
//!      any light: [`FrameDelta::lights_changed`]), reported as `recast_all`; with
//!      `recast_on_light_change = false` such changes are left to the refresh by age;
//!    - then, up to a budget of `ceil(refresh · M·N)` strata per record (priority ones
//!      count against it), strata chosen **by age**: the refresh probability of a stratum
//!      is proportional to its age, and the strata are drawn without replacement with
//!      exactly those inclusion probabilities (capped at 1) by [`select_by_age`]: strata
//!      whose share of the budget is ≥ 1 are taken (repeatedly, as the remaining budget
//!      shrinks), the others are put in a **random permutation** and systematic sampling
//!      with one random offset walks the cumulative distribution of their refresh
//!      probabilities in that permuted order (randomised systematic sampling with
//!      probability proportional to size, Hartley & Rao 1962). This is our reading of the
//!      paper's "CDF of refresh probability and modified random permutation", whose
//!      exact procedure we could not consult: it refreshes the oldest strata first, a
//!      stratum is never refreshed twice in a frame, and every stratum with age ≥ 1
//!      keeps a non-zero chance;
//!    - **light terms re-read**: in a frame where lights of some groups changed (moved,
//!      or their intensity, colour or cone did: [`FrameDelta::light_changed`], from the
//!      animation), every stratum not re-cast above that hit something keeps its hit
//!      point and weight and re-reads those groups' terms from their maps of this frame
//!      (one nearest-neighbour read each); the other groups' terms are kept (counted as
//!      `strata_reread` and `terms_reread` per group);
//!    - the record's irradiance, harmonic mean distance and gradients are recomputed from
//!      all its strata ([`gather_from_strata`], Ward–Heckbert as `pm-ic`) and the record
//!      remade with `pm-ic`'s radius limits and clamps.
//! 5. **New records** where the probe points are not covered yet: exactly `pm-ic`'s
//!    batched record creation ([`crate::kernels::gather::BATCH`]), every stratum cast in `f`.
//! 6. **The eye pass** reads the cache as `pm-ic` does
//!    ([`crate::kernels::gather::CacheSource`]: Ward's interpolation), marking every
//!    record it reads. A sample point that no record covers (sub-pixel jitter off the
//!    probe points: silhouettes, grazing faces, the far side of an edge) gets a gather
//!    there, as in `pm-ic` (same M × N rays reading the same map), but cast as the strata
//!    of a record (numbers hashed from the point's key; its record id is the key with the
//!    top bit set, so it never meets the ids counted from 0 for probe-point records).
//! 7. **Those gathers become records** (`store_eye_gathers`, default on): sorted by point
//!    key, each is added unless one added before it covers its point; records the eye
//!    pass read stay in use in the next frame even if no probe point needs them (step 3).
//!    From then on they are refreshed like any other record (priority, age), dropped when
//!    their surface changes or neither the probe points nor the eye pass read them.
//!
//! ### Why the exact priority test (issue 41)
//! A box is exact for an axis-aligned box-shaped object, but cornell-moving's cube turns,
//! and a turning cube's world box holds up to twice its cross-section: measured at 64²,
//! 8k photons, frames 5–9, the exact test spares 7 000–11 500 of 32 000–37 000 priority
//! strata per frame (≈ 30 %). Those strata are not free for long, though: the priority set counts
//! against the per-record budget, so the budget's remainder goes to the refresh by age
//! and the strata cast per frame fell by only ≈ 8 % (the cast count is set by the budget
//! wherever the priority set fits in it). What it buys is less staleness at nearly equal
//! cost; the cast count's floor is the budget plus the records rebuilt on the moving
//! object (≈ 76 records, 33 000 strata per frame), which is what is left to cut there.
//!
//! ### Light changes: per-group terms over precomputed irradiance (issue 41)
//! Before, a light change re-cast every stratum: the one global map cannot tell which
//! light a photon came from, and each cast is a 64-photon k-NN radiance estimate (≈ 75 %
//! of `pm-ic`'s time on the moving-light scene, `perf`; ≈ 71 % of this technique's there,
//! measured again 2026-12-08 at 8k photons). Now (Christensen 1999) each light group's
//! photons make their own map with irradiance precomputed once per frame at every
//! `precompute_stride`-th photon, so that a gather ray's lookup is one nearest-neighbour
//! read; strata keep their hit point and one term per group, and a frame where only the
//! point light moved re-reads that group's term of each stratum (a read, no ray, no
//! estimate) and keeps the ceiling lamp's, while strata that changed geometry reached
//! are re-cast as before (the exact test). A re-read term is exact for the hit it is read
//! at: the hit is still the first hit along the stratum's direction (no changed geometry
//! on the segment, else it would have been a priority stratum), and the map read is this
//! frame's.
//!
//! Measured (BENCHMARKS.md, issue 13 / 41, 2026-12-08, 64², 12-frame windows): on the
//! moving-light scene 6.7–8.3× less CPU than `pm-ic` at FLIP 0.075–0.07 (1.25–1.30×
//! before), 3.6× at 0.077; of that, the selective update itself is 1.5× (against this
//! technique with `refresh = 1`, every stratum re-cast each frame with the same maps), the
//! rest is the precomputed estimator, which is both cheaper and less noisy than the
//! 64-photon estimate at a gather hit.
//!
//! **Maps are rebuilt every frame, for every group**, with `pm-ic`'s photon budget
//! (photons `f·N ..`; the light sampler splits it by power, as in `pm-ic`'s one map),
//! rather than keeping an unchanged group's map where its photon paths met no changed
//! geometry: (1) the pass is cheap next to the gathers — tracing the photons and
//! precomputing the estimates (≈ 3 200 at 8k photons) is ≈ 3 % of a steady frame at 4k
//! photons and ≈ 8 % at 8k on the moving-light scene (`seconds_photons`, BENCHMARKS.md);
//! (2) a kept map would be right only for photons whose paths the change missed, so it
//! would need selective photon tracing's path scan and patching (`spt`), for a saving
//! bounded by those few %; (3) fresh photons each frame
//! keep the noise of strata cast in different frames independent, which is what lets the
//! refresh by age average it (a kept map would freeze one noise pattern into every
//! stratum cast while it is kept). An unchanged group's *terms* are kept (that is where
//! the time was); only its map is rebuilt.
//!
//! Bias added: the precomputed lookup's ([`crate::kernels::gather::precomputed`]: the
//! estimate's disc is `pm-ic`'s where the groups' densities are in proportion, and reading
//! `E` at the nearest precomputed photon at most doubles the kernel's support), and
//! `f(wo, n)·E` for the radiance (exact for Lambertian hits). A kept term of an unchanged
//! group is stale in the way a kept stratum always was (a change of radiance at its hit
//! caused by geometry elsewhere), never because of a light change.
//!
//! ### Why step 7 (issue 41)
//! Measured on cornell-moving at 64² (BENCHMARKS.md, issue 13): `pm-ic`'s eye pass makes
//! 290–350 such *unstored gathers* per frame (≈ 125 000 gather rays, more than the whole
//! selective refresh's 90 500 strata), and `ic-selective` made them anew every frame.
//! With a still camera the jittered sample points of frame `f + 1` fall on the same
//! pixels and surfaces as frame `f`'s, so a gather kept as a record (valid radius ≥
//! `r_min_px` pixels) serves them by interpolation; per frame it costs its refresh
//! (`refresh · M·N` strata) instead of a fresh gather at every uncovered point. Measured
//! (64², 8k photons, frames 4–15): 313 gathers in the first frame (85 kept as records),
//! then 52, 44, 26, 8, 5, … 13; the 12 frames took 5.46 CPU s instead of 9.10. It adds no new kind of error: those points
//! are served by Ward's interpolation like every other point (the interpolation bound of
//! [`crate::kernels::gather`]), and the records are invalidated by the animation's
//! [`FrameDelta`] like the others. The order of the misses in the parallel eye pass does
//! not matter: each gather depends only on its point, and they are inserted sorted.
//!
//! All numbers are hashed from `(seed, frame, record id, stratum)` (record ids count the
//! records made, in creation order), records are created in `pm-ic`'s deterministic
//! batches, refreshed independently of each other and written back in record order, so
//! images are **bit-identical for any thread count**, and for either store.
//!
//! ## Bias
//! `pm-ic`'s (see [`super`]), with the gather hits' radiance read from precomputed
//! irradiance (`light_terms`: the blur and the Lambertian reading of "Light changes"
//! above), plus **staleness**: a stratum not re-cast this frame holds
//! the radiance of the frame it was cast in. Geometry changes along a direction (hit
//! object moved, an object moved into or out of it) are always re-cast, so a stale
//! stratum sees the same surface at the same distance; what it can miss is a change of
//! the *radiance* there caused elsewhere (an object moved next to a wall it does not
//! block: indirect shadows, colour bleeding), for about `1/refresh` frames on average.
//! A stratum's value is one unbiased sample of its frame's incident radiance, so the
//! error does not accumulate: after ≈ `1/refresh` frames every stratum is renewed.
//!
//! ## Memory
//! In memory per record: position, normal, the record itself and bookkeeping (≈ 160
//! bytes, plus its entries in the cache's grid, rebuilt each frame); the strata
//! ([`Stratum::BYTES`] = 108 bytes each with the hit point, weight and
//! [`crate::kernels::gather::precomputed::MAX_GROUPS`] terms: 46 KiB per record at
//! 12 × 36) are in the store, whose resident
//! part is bounded by `cache_pages × page_kb` KiB with the paged store (plus one chunk of
//! [`CHUNK`] records' strata being refreshed). The eye pass's
//! gathers (step 6) hold their strata until the pass ends up to `eye_buffer_mb` MiB
//! (default 64, ≈ 6 000 gathers at 12 × 36; cornell-moving at 64² makes ≈ 300 in its
//! first frame); beyond that a miss keeps ≈ 150 bytes and, if it becomes a record, its
//! strata are cast again after the pass (same numbers, same strata).

pub mod store;

use crate::framework::integrator::{RenderedFrame, render_camera_rays};
use crate::kernels::gather::irradiance_cache::{
    CacheParams, Gather, IrradianceCache, Record, gather_from_strata, make_record,
    stratum_direction,
};
use crate::kernels::gather::photon_map::PhotonMap;
use crate::kernels::gather::precomputed::{
    GatherHit, GroupMaps, MAX_GROUPS, gather_hit, light_groups,
};
use crate::kernels::gather::view::{CacheQuery, EyeView, IndirectSource, NoIndirect};
use crate::kernels::gather::{
    BATCH, FrameMaps, PmIcSettings, base_cell, caustic_photons, frame_maps, gather_ray_hit,
    photon_base, point_key, probe_points,
};
use chronolux_core::color::Rgb;
use chronolux_core::geometry::{Bounds3, spawn_ray};
use chronolux_core::math::{Frame, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::hash_words;
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::source::FrameSource;
use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use store::{MemoryStore, PagedStore, StoreStats, StrataStore, Stratum};

/// Records whose strata are read, refreshed and written back together.
pub const CHUNK: usize = 64;

/// Settings of `ic-selective`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IcSelectiveSettings {
    /// Photon mapping, gather and cache settings (as `pm-ic`).
    pub pmic: PmIcSettings,
    /// Fraction of each record's strata re-cast per frame (priority strata included).
    /// Default 0.1 (the paper's).
    pub refresh: f32,
    /// Keep the strata in a paged file (true) or in memory (false). Default true.
    pub paged: bool,
    /// Page size of the paged store, KiB (rounded down to whole records). Default 256.
    pub page_kb: u32,
    /// Pages of the paged store held in memory (LRU). Default 64 (16 MiB at 256 KiB).
    pub cache_pages: u32,
    /// Directory of the paged store's file; empty: the system's temporary directory.
    pub store_dir: String,
    /// Bring light and material changes in at once (true, default: no stale light): with
    /// `light_terms`, a frame where lights changed re-reads the changed groups' terms of
    /// every stratum not re-cast, and one where a material or the light grouping changed
    /// re-casts every stratum; without `light_terms`, every stratum is re-cast when a
    /// light or a material changed. False: such changes are left to the refresh by age
    /// like any other change of radiance at a hit (light lags by about `1/refresh`
    /// frames).
    pub recast_on_light_change: bool,
    /// Keep the gathers the eye pass makes at points no record covers as records (true,
    /// default; see the module doc), or discard them after use as `pm-ic` does (false).
    pub store_eye_gathers: bool,
    /// Most MiB of the eye pass's gathers' strata held until the pass ends (beyond it, a
    /// gather that becomes a record is cast again after the pass). Default 64.
    pub eye_buffer_mb: u32,
    /// Re-cast a stratum whose segment meets a changed instance's box only if it meets
    /// that instance's geometry in the previous or this frame (true, default), or on the
    /// box alone (false).
    pub exact_priority: bool,
    /// Per-light-group photon maps with precomputed irradiance, and per-group terms kept
    /// per stratum (true, default; see the module doc): a frame where only some light
    /// groups changed re-reads those groups' terms of the strata it does not re-cast
    /// (one nearest-neighbour read each); false: one global map read by a k-NN radiance
    /// estimate per cast stratum, and every stratum re-cast when a light changed (the
    /// 2026-12-07 design).
    pub light_terms: bool,
    /// Every how many photons of a group's map the irradiance is precomputed. Default 4.
    pub precompute_stride: u32,
    /// Photons per precomputed estimate, in every group; 0 (default): the global map
    /// lookup's `k` (`pm-ic`'s 64).
    pub precompute_k: u32,
}

impl Default for IcSelectiveSettings {
    fn default() -> Self {
        IcSelectiveSettings {
            pmic: PmIcSettings::default(),
            refresh: 0.1,
            paged: true,
            page_kb: 256,
            cache_pages: 64,
            store_dir: String::new(),
            recast_on_light_change: true,
            store_eye_gathers: true,
            eye_buffer_mb: 64,
            exact_priority: true,
            light_terms: true,
            precompute_stride: 4,
            precompute_k: 0,
        }
    }
}

/// A record kept across frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SelRecord {
    /// Creation number (hashed into its strata's numbers).
    pub id: u64,
    /// Where its strata are in the store.
    pub slot: u32,
    pub p: Vec3,
    pub n: Vec3,
    pub instance: u32,
    /// Pixel footprint at creation (the radius clamps).
    pub footprint: f32,
    /// The record as the cache uses it (from the strata as of the last refresh).
    pub record: Record,
    /// The previous frame's eye pass read it (kept then even if no probe point needs it).
    pub eye_used: bool,
    /// Made from an eye-pass point no record covered (not from a probe point).
    pub from_eye: bool,
}

struct State {
    prev: Arc<FrameScene>,
    records: Vec<SelRecord>,
    store: Box<dyn StrataStore>,
    free: BTreeSet<u32>,
    next_slot: u32,
    next_id: u64,
}

impl State {
    fn alloc(&mut self) -> u32 {
        if let Some(s) = self.free.pop_first() {
            s
        } else {
            self.next_slot += 1;
            self.next_slot - 1
        }
    }
}

/// Step 1 of a frame: what changed since the previous frame rendered, and where.
struct Change {
    /// Per instance: moved or deformed.
    changed: Vec<bool>,
    /// Lights or materials changed and `recast_on_light_change`: every stratum is stale.
    all_stale: bool,
    /// Where the changed instances are in the previous and this frame: the delta's regions
    /// (padded bounds of a moved instance's vertices, of a deformed one's changed
    /// triangles).
    boxes: Vec<Bounds3>,
    /// The previous and this frame with only the changed instances in them (the exact
    /// test of a ray segment against the changed geometry; `None` when nothing changed
    /// or `exact_priority` is off).
    exact: Option<(FrameScene, FrameScene)>,
    /// Per light group (with `light_terms`): some light of the group changed, so the
    /// group's term of every stratum not re-cast is re-read.
    reread: Vec<bool>,
    /// Why every stratum is re-cast (`all_stale`): "materials", "lights" (without
    /// `light_terms`) or "light groups" (the grouping differs from the previous frame's).
    reason: &'static str,
}

/// The phases of [`IcSelective::render`] that update the kept records (the module doc's
/// steps 1 to 5), in order.
impl State {
    fn change_to(
        &self,
        scene: &FrameScene,
        recast_on_light_change: bool,
        exact: bool,
        light_terms: bool,
    ) -> Change {
        let delta = FrameDelta::between(&self.prev, scene);
        let changed = delta.dynamic_instances();
        let (groups, n_groups) = light_groups(scene);
        let mut reread = vec![false; if light_terms { n_groups } else { 0 }];
        let mut reason = "";
        if recast_on_light_change {
            if delta.materials_changed() {
                reason = "materials";
            } else if !light_terms && delta.lights_changed() {
                reason = "lights";
            } else if light_terms && light_groups(&self.prev) != (groups.clone(), n_groups) {
                reason = "light groups";
            } else if light_terms {
                for (l, &g) in groups.iter().enumerate() {
                    if delta.light_changed(l) {
                        reread[g as usize] = true;
                    }
                }
            }
        }
        let all_stale = !reason.is_empty();
        let boxes = delta.changed_bounds();
        let exact = (exact && !boxes.is_empty()).then(|| {
            let still: Vec<bool> = changed.iter().map(|c| !c).collect();
            (
                self.prev.without_instances(&still),
                scene.without_instances(&still),
            )
        });
        Change {
            changed,
            all_stale,
            boxes,
            exact,
            reread,
            reason,
        }
    }

    /// Step 2: takes the records, frees the slots of those on a changed surface and
    /// returns the others.
    fn drop_changed(&mut self, changed: &[bool]) -> Vec<SelRecord> {
        let mut kept = Vec::with_capacity(self.records.len());
        for r in std::mem::take(&mut self.records) {
            if changed.get(r.instance as usize).copied().unwrap_or(true) {
                self.free.insert(r.slot);
            } else {
                kept.push(r);
            }
        }
        kept
    }

    /// Step 3: of `kept`, the records valid at one of this frame's probe `points` or read
    /// by the previous frame's eye pass (the others' slots are freed).
    fn keep_used(
        &mut self,
        kept: Vec<SelRecord>,
        points: &[(u64, CacheQuery)],
        scene: &FrameScene,
        s: &PmIcSettings,
    ) -> Vec<SelRecord> {
        let mut used = vec![false; kept.len()];
        let mut old = IrradianceCache::new(s.cache.accuracy, base_cell(scene));
        for r in &kept {
            old.insert(r.record);
        }
        let hits = parallel::map_chunks(points.len(), 256, |range| {
            let mut ids = Vec::new();
            for (_, q) in &points[range] {
                old.for_valid_indexed(q.p, q.n, |id, _, _| ids.push(id as u32));
            }
            ids
        });
        for id in hits.into_iter().flatten() {
            used[id as usize] = true;
        }
        let mut records = Vec::with_capacity(kept.len());
        for (r, u) in kept.into_iter().zip(used) {
            if u || r.eye_used {
                records.push(r);
            } else {
                self.free.insert(r.slot);
            }
        }
        records
    }

    /// Step 4: refreshes every record's strata (read from the store in chunks of
    /// [`CHUNK`] records, refreshed in parallel, written back); the strata counts and the
    /// seconds spent in the store.
    fn refresh(
        &mut self,
        records: &mut [SelRecord],
        refresh: &Refresh,
        spr: usize,
    ) -> (Counts, f64) {
        let mut counts = Counts::default();
        let mut t_store = 0.0f64;
        for start in (0..records.len()).step_by(CHUNK) {
            let end = (start + CHUNK).min(records.len());
            let ts = Instant::now();
            let blocks: Vec<Vec<Stratum>> = records[start..end]
                .iter()
                .map(|r| {
                    let mut b = vec![Stratum::EMPTY; spr];
                    self.store.read(r.slot, &mut b);
                    b
                })
                .collect();
            t_store += ts.elapsed().as_secs_f64();
            let done = parallel::map_chunks(blocks.len(), 1, |range| {
                let i = range.start;
                let mut b = blocks[i].clone();
                let (rec, c) = refresh.record(&records[start + i], &mut b);
                (b, rec, c)
            });
            let ts = Instant::now();
            for (i, (b, rec, c)) in done.into_iter().enumerate() {
                let r = &mut records[start + i];
                self.store.write(r.slot, &b);
                r.record = rec;
                counts.add(&c);
            }
            t_store += ts.elapsed().as_secs_f64();
        }
        (counts, t_store)
    }

    /// Step 5: new records at the probe points no record covers (pm-ic's batches of
    /// [`BATCH`]), every stratum cast in this frame; the cache of all records, the number
    /// added and the seconds spent in the store.
    fn add_needed(
        &mut self,
        records: &mut Vec<SelRecord>,
        points: &[(u64, CacheQuery)],
        at: &Refresh,
        spr: usize,
    ) -> (IrradianceCache, u64, f64) {
        let (scene, s) = (at.scene, at.s);
        let mut t_store = 0.0f64;
        let mut cache = IrradianceCache::new(s.cache.accuracy, base_cell(scene));
        for r in records.iter() {
            cache.insert(r.record);
        }
        let mut added = 0u64;
        for batch in points.chunks(BATCH) {
            let need: Vec<&(u64, CacheQuery)> = batch
                .iter()
                .filter(|(_, q)| !cache.covers(q.p, q.n))
                .collect();
            if need.is_empty() {
                continue;
            }
            let first_id = self.next_id;
            self.next_id += need.len() as u64;
            let made = parallel::map_chunks(need.len(), 1, |r| {
                let (_, q) = need[r.start];
                let id = first_id + r.start as u64;
                let strata: Vec<Stratum> = (0..spr).map(|i| at.cast(q.p, q.n, id, i)).collect();
                let g = gather_of(s, id, q.n, &strata);
                let rec = record_from(&s.cache, q.p, q.n, q.footprint, &g);
                (id, *q, strata, rec)
            });
            for (id, q, strata, rec) in made {
                let slot = self.alloc();
                let ts = Instant::now();
                self.store.write(slot, &strata);
                t_store += ts.elapsed().as_secs_f64();
                cache.insert(rec);
                records.push(SelRecord {
                    id,
                    slot,
                    p: q.p,
                    n: q.n,
                    instance: q.instance,
                    footprint: q.footprint,
                    record: rec,
                    eye_used: false,
                    from_eye: false,
                });
                added += 1;
            }
        }
        (cache, added, t_store)
    }

    /// Step 7: the eye pass's gathers at points no record covered become records (in the
    /// order of their point keys, each only if the records made before it in that order do
    /// not cover it); every record's `eye_used` is set from the eye pass's reads. The
    /// records added and the seconds spent in the store.
    fn add_from_eye(
        &mut self,
        records: &mut Vec<SelRecord>,
        cache: &mut IrradianceCache,
        used: Vec<AtomicBool>,
        mut misses: Vec<EyeMiss>,
        at: &Refresh,
    ) -> (u64, f64) {
        for (r, u) in records.iter_mut().zip(used) {
            r.eye_used = u.into_inner();
        }
        misses.sort_by(|a, b| {
            a.key
                .cmp(&b.key)
                .then(query_bits(&a.q).cmp(&query_bits(&b.q)))
        });
        let mut kept = Vec::new();
        for m in misses {
            if !cache.covers(m.q.p, m.q.n) {
                cache.insert(m.rec);
                kept.push(m);
            }
        }
        // Strata the eye pass did not buffer (over `eye_buffer_mb`) are cast again: the
        // same numbers, so the same strata bit for bit.
        let spr = (at.s.gather_m.max(1) * at.s.gather_n.max(1)) as usize;
        let redo: Vec<usize> = (0..kept.len())
            .filter(|&i| kept[i].strata.is_empty())
            .collect();
        let recast = parallel::map_chunks(redo.len(), 1, |r| {
            let m = &kept[redo[r.start]];
            (0..spr)
                .map(|i| at.cast(m.q.p, m.q.n, m.id, i))
                .collect::<Vec<Stratum>>()
        });
        for (i, strata) in redo.into_iter().zip(recast) {
            kept[i].strata = strata;
        }
        let (mut added, mut t_store) = (0u64, 0.0f64);
        for m in kept {
            let slot = self.alloc();
            let ts = Instant::now();
            self.store.write(slot, &m.strata);
            t_store += ts.elapsed().as_secs_f64();
            records.push(SelRecord {
                id: m.id,
                slot,
                p: m.q.p,
                n: m.q.n,
                instance: m.q.instance,
                footprint: m.q.footprint,
                record: m.rec,
                eye_used: true,
                from_eye: true,
            });
            added += 1;
        }
        (added, t_store)
    }
}

/// Bits of a query's point and normal (a total order for ties of [`point_key`]).
fn query_bits(q: &CacheQuery) -> [u32; 6] {
    [q.p.x, q.p.y, q.p.z, q.n.x, q.n.y, q.n.z].map(f32::to_bits)
}

/// Record ids of gathers made in the eye pass: the point's key with the top bit set
/// (records made from probe points count from 0, so the two never meet).
const EYE_ID: u64 = 1 << 63;

/// A gather the eye pass made at a point no record covered, kept to become a record.
struct EyeMiss {
    key: u64,
    id: u64,
    q: CacheQuery,
    /// Its strata, or empty when the eye pass's buffer was full (cast again if kept).
    strata: Vec<Stratum>,
    rec: Record,
}

/// The eye pass's irradiance: Ward's interpolation of the frame's cache (as
/// [`CacheSource`]), marking every record it reads; at a point no record covers, a gather
/// cast as strata of a new record (same rays and estimate as `pm-ic`'s unstored gather,
/// numbers from the point's key), kept for [`State::add_from_eye`].
struct SelSource<'a> {
    at: &'a Refresh<'a>,
    cache: &'a IrradianceCache,
    used: Vec<AtomicBool>,
    misses: Mutex<Vec<EyeMiss>>,
    /// Gathers made (whether kept or not).
    gathers: AtomicU64,
    /// Bytes of strata buffered so far, and the most that may be (`eye_buffer_mb`).
    buffered: AtomicUsize,
    buffer_cap: usize,
    /// `store_eye_gathers`: keep the misses (false: `pm-ic`'s unstored gathers).
    keep: bool,
}

impl IndirectSource for SelSource<'_> {
    fn irradiance(&self, _: &FrameScene, q: &CacheQuery) -> Rgb {
        let mut sum = Rgb::ZERO;
        let mut wsum = 0.0f32;
        self.cache.for_valid_indexed(q.p, q.n, |i, rec, eps| {
            self.used[i].store(true, Ordering::Relaxed);
            let w = 1.0 / eps.max(1e-6);
            sum += rec.extrapolate(q.p, q.n) * w;
            wsum += w;
        });
        if wsum > 0.0 {
            return (sum / wsum).max(Rgb::ZERO);
        }
        let (at, s) = (self.at, self.at.s);
        let key = point_key(q.p, q.n);
        let id = key | EYE_ID;
        let spr = (s.gather_m.max(1) * s.gather_n.max(1)) as usize;
        let strata: Vec<Stratum> = (0..spr).map(|i| at.cast(q.p, q.n, id, i)).collect();
        let g = gather_of(s, id, q.n, &strata);
        let rec = record_from(&s.cache, q.p, q.n, q.footprint, &g);
        self.gathers.fetch_add(1, Ordering::Relaxed);
        if self.keep {
            // Which misses keep their strata depends on the threads' order, what is stored
            // does not (a dropped block is cast again, identically, if its record is kept).
            let bytes = strata.len() * std::mem::size_of::<Stratum>();
            let fits = self.buffered.fetch_add(bytes, Ordering::Relaxed) + bytes <= self.buffer_cap;
            let mut m = self.misses.lock().expect("no panic while held");
            m.push(EyeMiss {
                key,
                id,
                q: *q,
                strata: if fits { strata } else { Vec::new() },
                rec,
            });
        }
        g.e
    }
}

/// The strata store `s` asks for: in memory, or paged to a file in `store_dir` (the
/// system's temporary folder when empty).
fn make_store(s: &IcSelectiveSettings) -> Result<Box<dyn StrataStore>, String> {
    let spr = (s.pmic.gather_m.max(1) * s.pmic.gather_n.max(1)) as usize;
    if !s.paged {
        return Ok(Box::new(MemoryStore::new(spr)));
    }
    let dir = (!s.store_dir.is_empty()).then(|| std::path::PathBuf::from(&s.store_dir));
    let shown = dir.clone().unwrap_or_else(std::env::temp_dir);
    let store = PagedStore::new(spr, s.page_kb as usize * 1024, s.cache_pages as usize, dir)
        .map_err(|e| {
            format!(
                "cannot create the paged strata file in {} (store_dir): {e}",
                shown.display()
            )
        })?;
    Ok(Box::new(store))
}

/// The technique.
pub struct IcSelective {
    pub settings: IcSelectiveSettings,
    pub name: &'static str,
    state: Option<State>,
    /// The strata store, made when the technique is built (so that a store folder that
    /// cannot be written is an error before any frame), moved into the state by the first
    /// frame.
    store: Option<Box<dyn StrataStore>>,
}

/// The numbers of stratum `idx` of record `id` cast in frame `cast`: jitter in the
/// stratum, and the stream of the gather ray's delta chain.
fn stratum_rngs(seed: u64, cast: u32, id: u64, idx: usize) -> (f32, f32, Pcg32) {
    let h = hash_words(&[seed, 0x7365_6c65_6374, cast as u64, id, idx as u64]);
    let mut j = Pcg32::new(h, 0x6a69_7474);
    let (xi, psi) = (j.next_f32(), j.next_f32());
    (xi, psi, Pcg32::new(h, 0x6761_7468))
}

/// Direction and `tan θ` of stratum `idx` of a record at normal frame `fr`, as cast in
/// frame `cast`.
pub fn stratum_dir(s: &PmIcSettings, fr: &Frame, id: u64, idx: usize, cast: u32) -> (Vec3, f32) {
    let (m, np) = (s.gather_m.max(1), s.gather_n.max(1));
    let (xi, psi, _) = stratum_rngs(s.common.seed, cast, id, idx);
    stratum_direction(fr, m, np, idx as u32 / np, idx as u32 % np, xi, psi)
}

/// Direction of stratum `idx` of record `id` at normal `n` cast in frame `cast`, and the
/// stream of its gather ray's delta chain (what both casts below draw).
fn stratum_ray(s: &PmIcSettings, n: Vec3, id: u64, idx: usize, cast: u32) -> (Vec3, Pcg32) {
    let (m, np) = (s.gather_m.max(1), s.gather_n.max(1));
    let (xi, psi, rng) = stratum_rngs(s.common.seed, cast, id, idx);
    let fr = Frame::from_normal(n);
    let (dir, _) = stratum_direction(&fr, m, np, idx as u32 / np, idx as u32 % np, xi, psi);
    (dir, rng)
}

/// Casts stratum `idx` of record `id` at (p, n) in frame `frame` (reading `global`, the
/// frame's global map).
#[allow(clippy::too_many_arguments)]
pub fn cast_stratum(
    scene: &FrameScene,
    s: &PmIcSettings,
    global: &PhotonMap,
    p: Vec3,
    n: Vec3,
    id: u64,
    idx: usize,
    frame: u32,
) -> Stratum {
    let (dir, mut rng) = stratum_ray(s, n, id, idx, frame);
    match gather_ray_hit(scene, s, &[global], p, n, dir, &mut rng) {
        Some((l, d, inst)) => Stratum {
            l,
            dist: d.max(1e-6),
            hit: inst,
            cast: frame,
            ..Stratum::EMPTY
        },
        None => Stratum {
            cast: frame,
            ..Stratum::EMPTY
        },
    }
}

/// [`cast_stratum`] reading the light groups' precomputed maps `maps`: the same direction
/// and delta chain, the vertex read kept with its weight and every group's term `w ·
/// E_g(x)`; the radiance is their sum.
#[allow(clippy::too_many_arguments)]
pub fn cast_stratum_terms(
    scene: &FrameScene,
    s: &PmIcSettings,
    maps: &GroupMaps,
    p: Vec3,
    n: Vec3,
    id: u64,
    idx: usize,
    frame: u32,
) -> Stratum {
    let (dir, mut rng) = stratum_ray(s, n, id, idx, frame);
    match gather_hit(scene, s, p, n, dir, &mut rng) {
        Some(hit) => {
            let mut terms = [Rgb::ZERO; MAX_GROUPS];
            for (g, t) in terms.iter_mut().enumerate().take(maps.groups()) {
                *t = maps.term(g, &hit);
            }
            Stratum {
                l: terms.iter().copied().sum(),
                dist: hit.dist.max(1e-6),
                hit: hit.instance,
                cast: frame,
                x: hit.x,
                ns: hit.ns,
                w: hit.w,
                terms,
            }
        }
        None => Stratum {
            cast: frame,
            ..Stratum::EMPTY
        },
    }
}

/// The gather (irradiance, distances, gradients) of a record's strata.
pub fn gather_of(s: &PmIcSettings, id: u64, n: Vec3, strata: &[Stratum]) -> Gather {
    let (m, np) = (s.gather_m.max(1), s.gather_n.max(1));
    let fr = Frame::from_normal(n);
    let l: Vec<_> = strata.iter().map(|t| t.l).collect();
    let r: Vec<_> = strata.iter().map(|t| t.dist).collect();
    let tan: Vec<_> = strata
        .iter()
        .enumerate()
        .map(|(i, t)| stratum_dir(s, &fr, id, i, t.cast).1)
        .collect();
    gather_from_strata(&fr, m, np, &l, &r, &tan)
}

fn record_from(params: &CacheParams, p: Vec3, n: Vec3, footprint: f32, g: &Gather) -> Record {
    let a = params.accuracy.max(1e-6);
    make_record(
        p,
        n,
        g,
        params.r_min_px * footprint / a,
        params.r_max_px * footprint / a,
    )
}

/// Chooses `n` distinct indices of `weights` (those with weight > 0; all of them if there
/// are at most `n`), each with inclusion probability `min(1, c·w)` (`c` such that the
/// probabilities add up to `n`): indices whose share is ≥ 1 are taken first (repeatedly,
/// the largest first when there are more than the budget), the rest by systematic
/// sampling along a random permutation (see the module doc). Returned in increasing
/// order.
pub fn select_by_age(weights: &[f64], n: usize, rng: &mut Pcg32) -> Vec<usize> {
    let mut rest: Vec<usize> = (0..weights.len()).filter(|&k| weights[k] > 0.0).collect();
    if n >= rest.len() {
        return rest;
    }
    let mut chosen = Vec::with_capacity(n);
    loop {
        let left = n - chosen.len();
        if left == 0 {
            chosen.sort_unstable();
            return chosen;
        }
        let total: f64 = rest.iter().map(|&k| weights[k]).sum();
        let (mut sure, other): (Vec<usize>, Vec<usize>) = rest
            .iter()
            .partition(|&&k| left as f64 * weights[k] >= total);
        if sure.is_empty() {
            break;
        }
        if sure.len() >= left {
            sure.sort_by(|&a, &b| weights[b].total_cmp(&weights[a]).then(a.cmp(&b)));
            chosen.extend_from_slice(&sure[..left]);
            chosen.sort_unstable();
            return chosen;
        }
        chosen.extend(sure);
        rest = other;
    }
    for i in (1..rest.len()).rev() {
        let j = ((rng.next_u32() as u64 * (i as u64 + 1)) >> 32) as usize;
        rest.swap(i, j);
    }
    let left = n - chosen.len();
    let total: f64 = rest.iter().map(|&k| weights[k]).sum();
    let step = total / left as f64;
    let mut u = rng.next_f32() as f64 * step;
    let mut cum = 0.0f64;
    let mut picked = 0;
    for &k in &rest {
        cum += weights[k];
        // Every weight is below `step`, so at most one target falls in each interval.
        if picked < left && u < cum {
            chosen.push(k);
            picked += 1;
            u += step;
        }
    }
    chosen.sort_unstable();
    chosen
}

/// Whether the segment `o + t·d`, `t ∈ [0, t_max]`, meets box `b` (slab test).
fn segment_meets(b: &Bounds3, o: Vec3, d: Vec3, t_max: f32) -> bool {
    let (mut t0, mut t1) = (0.0f32, t_max);
    for a in 0..3 {
        let (lo, hi, oa, da) = (b.min[a], b.max[a], o[a], d[a]);
        if da.abs() < 1e-12 {
            if oa < lo || oa > hi {
                return false;
            }
            continue;
        }
        let inv = 1.0 / da;
        let (mut ta, mut tb) = ((lo - oa) * inv, (hi - oa) * inv);
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        t0 = t0.max(ta);
        t1 = t1.min(tb);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Whether the gather segment from the record at (p, n) along `d` up to its old hit
/// distance `dist` (unbounded when nothing was hit) meets a surface of `before` or `now`
/// (the previous and this frame holding only the changed instances): the exact test
/// behind the box test. The segment is that of the gather ray (same origin offset),
/// lengthened by a relative 1e-4 so that a hit exactly at the old distance counts.
fn segment_meets_geometry(
    before: &FrameScene,
    now: &FrameScene,
    p: Vec3,
    n: Vec3,
    d: Vec3,
    dist: f32,
) -> bool {
    let mut ray = spawn_ray(p, n, d);
    ray.tmax = if dist.is_finite() {
        dist * (1.0 + 1e-4) + 1e-6
    } else {
        f32::INFINITY
    };
    before.occluded(&ray) || now.occluded(&ray)
}

/// What a frame's refresh needs to know.
struct Refresh<'a> {
    scene: &'a FrameScene,
    s: &'a PmIcSettings,
    /// What gather rays read: the frame's global map (without `light_terms`) or its
    /// light groups' precomputed maps.
    maps: Reader<'a>,
    frame: u32,
    /// Per light group: re-read that group's term of the strata not re-cast.
    reread: &'a [bool],
    /// Per instance: changed since the previous frame.
    changed: &'a [bool],
    /// Boxes (previous and this frame) of the changed instances, slightly enlarged.
    boxes: &'a [Bounds3],
    /// [`Change::exact`]: segments that meet a box are tested against the changed
    /// geometry itself in both frames.
    exact: Option<&'a (FrameScene, FrameScene)>,
    all_stale: bool,
    budget: usize,
}

/// The maps a frame's gather rays read.
#[derive(Clone, Copy)]
enum Reader<'a> {
    Global(&'a PhotonMap),
    Groups(&'a GroupMaps),
}

#[derive(Clone, Copy, Default)]
struct Counts {
    priority: u64,
    aged: u64,
    /// Segments that met a changed box but not the changed geometry (not re-cast).
    box_only: u64,
    /// Strata not re-cast whose terms of the changed light groups were re-read.
    reread: u64,
    /// Terms re-read, per group.
    terms: [u64; MAX_GROUPS],
}

impl Counts {
    fn add(&mut self, o: &Counts) {
        self.priority += o.priority;
        self.aged += o.aged;
        self.box_only += o.box_only;
        self.reread += o.reread;
        for (a, b) in self.terms.iter_mut().zip(o.terms) {
            *a += b;
        }
    }
}

impl Refresh<'_> {
    /// Stratum `idx` of record `id` at (p, n), cast in this frame.
    fn cast(&self, p: Vec3, n: Vec3, id: u64, idx: usize) -> Stratum {
        match self.maps {
            Reader::Global(g) => cast_stratum(self.scene, self.s, g, p, n, id, idx, self.frame),
            Reader::Groups(m) => {
                cast_stratum_terms(self.scene, self.s, m, p, n, id, idx, self.frame)
            }
        }
    }

    fn record(&self, r: &SelRecord, strata: &mut [Stratum]) -> (Record, Counts) {
        let s = self.s;
        let fr = Frame::from_normal(r.n);
        let mut recast = vec![false; strata.len()];
        let mut counts = Counts::default();
        for (i, t) in strata.iter().enumerate() {
            let prio = self.all_stale
                || (t.hit != Stratum::NO_HIT
                    && self.changed.get(t.hit as usize).copied().unwrap_or(true))
                || (!self.boxes.is_empty() && {
                    let (d, _) = stratum_dir(s, &fr, r.id, i, t.cast);
                    self.boxes.iter().any(|b| segment_meets(b, r.p, d, t.dist))
                        && match self.exact {
                            None => true,
                            Some((before, now)) => {
                                let meets =
                                    segment_meets_geometry(before, now, r.p, r.n, d, t.dist);
                                counts.box_only += u64::from(!meets);
                                meets
                            }
                        }
                });
            if prio {
                recast[i] = true;
                counts.priority += 1;
            }
        }
        let left = self.budget.saturating_sub(counts.priority as usize);
        if left > 0 {
            let w: Vec<f64> = strata
                .iter()
                .zip(&recast)
                .map(|(t, &p)| {
                    if p {
                        0.0
                    } else {
                        self.frame.saturating_sub(t.cast) as f64
                    }
                })
                .collect();
            let mut rng = Pcg32::new(
                hash_words(&[s.common.seed, 0x6167_6573, self.frame as u64, r.id]),
                0x7065_726d,
            );
            for k in select_by_age(&w, left, &mut rng) {
                recast[k] = true;
                counts.aged += 1;
            }
        }
        let reread = self.reread.iter().any(|&c| c);
        for (i, t) in strata.iter_mut().enumerate() {
            if recast[i] {
                *t = self.cast(r.p, r.n, r.id, i);
            } else if reread
                && t.hit != Stratum::NO_HIT
                && let Reader::Groups(maps) = self.maps
            {
                // Only the changed groups' terms; the hit point is still valid (no
                // changed geometry on the segment, or it would be a priority stratum).
                let hit = GatherHit {
                    x: t.x,
                    ns: t.ns,
                    w: t.w,
                    dist: t.dist,
                    instance: t.hit,
                };
                for (g, _) in self.reread.iter().enumerate().filter(|(_, c)| **c) {
                    t.terms[g] = maps.term(g, &hit);
                    counts.terms[g] += 1;
                }
                t.l = t.terms.iter().copied().sum();
                counts.reread += 1;
            }
        }
        let g = gather_of(s, r.id, r.n, strata);
        (record_from(&s.cache, r.p, r.n, r.footprint, &g), counts)
    }
}

impl IcSelective {
    /// The technique with its strata store; an error names the store folder that cannot
    /// hold the paged store's file.
    pub fn new(settings: IcSelectiveSettings, name: &'static str) -> Result<Self, String> {
        if settings.pmic.precompute_stride != 0 {
            return Err(format!(
                "pmic.precompute_stride = {}: {name} chooses its estimator with its own `light_terms` and `precompute_stride`; leave pmic.precompute_stride 0",
                settings.pmic.precompute_stride
            ));
        }
        let store = Some(make_store(&settings)?);
        Ok(IcSelective {
            settings,
            name,
            state: None,
            store,
        })
    }

    /// The records kept now (after the last frame rendered), in cache order.
    pub fn records(&self) -> &[SelRecord] {
        self.state.as_ref().map_or(&[], |st| &st.records)
    }

    /// The strata of record `index` of [`IcSelective::records`].
    pub fn strata(&mut self, index: usize) -> Vec<Stratum> {
        let st = self.state.as_mut().expect("a frame was rendered");
        let mut out = vec![Stratum::EMPTY; st.store.strata_per_record()];
        st.store.read(st.records[index].slot, &mut out);
        out
    }

    /// Traffic of the store so far.
    pub fn store_stats(&self) -> StoreStats {
        self.state
            .as_ref()
            .map(|st| st.store.stats())
            .unwrap_or_default()
    }

    /// Renders frame `frame` (scenes from `source`).
    pub fn render(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let t0 = Instant::now();
        let scene_arc = source.frame(frame);
        let scene = &*scene_arc;
        let s = self.settings.pmic.clone();
        let spr = (s.gather_m.max(1) * s.gather_n.max(1)) as usize;
        let budget = (self.settings.refresh.clamp(0.0, 1.0) as f64 * spr as f64).ceil() as usize;
        if self.state.is_none() {
            let store = self
                .store
                .take()
                .expect("the store is made once, with the technique");
            self.state = Some(State {
                prev: scene_arc.clone(),
                records: Vec::new(),
                store,
                free: BTreeSet::new(),
                next_slot: 0,
                next_id: 0,
            });
        }
        let st = self.state.as_mut().expect("state made");
        // 1. What changed since the previous frame rendered, and where.
        let change = st.change_to(
            scene,
            self.settings.recast_on_light_change,
            self.settings.exact_priority,
            self.settings.light_terms,
        );
        let base = photon_base(&s, frame);
        let (maps, groups) = if self.settings.light_terms {
            // The global stream split by light group, with precomputed irradiance; the
            // caustic map as pm-ic's.
            let g = GroupMaps::build(
                scene,
                &s,
                base,
                self.settings.precompute_stride,
                self.settings.precompute_k,
            );
            let (c, rays) =
                caustic_photons(scene, base..base + s.photons, s.common.seed, s.photons);
            let maps = FrameMaps {
                global: PhotonMap::empty(),
                caustic: PhotonMap::build(c),
                rays: rays + g.rays,
            };
            (maps, Some(g))
        } else {
            (frame_maps(scene, &s, base), None)
        };
        let t_photons = t0.elapsed().as_secs_f64();
        let before = st.records.len();
        // 2. Records on a changed surface are rebuilt (dropped here, made anew below).
        let kept = st.drop_changed(&change.changed);
        let rebuilt = before - kept.len();
        // 3. Records in use: valid at a probe point of this frame.
        let key = hash_words(&[s.common.seed, photon_base(&s, frame), 0x6963]);
        let probe_src = NoIndirect;
        let probe_view = EyeView::new(&s, scene, &maps.caustic, &probe_src);
        let points = probe_points(&probe_view, scene, key);
        let mut records = st.keep_used(kept, &points, scene, &s);
        let unused = before - rebuilt - records.len();
        // 4. Refresh.
        let refresh = Refresh {
            scene,
            s: &s,
            maps: match &groups {
                Some(g) => Reader::Groups(g),
                None => Reader::Global(&maps.global),
            },
            frame,
            reread: &change.reread,
            changed: &change.changed,
            boxes: &change.boxes,
            exact: change.exact.as_ref(),
            all_stale: change.all_stale,
            budget,
        };
        let (counts, mut t_store) = st.refresh(&mut records, &refresh, spr);
        let refreshed = records.len();
        // 5. New records where the view needs them (pm-ic's batches).
        let (mut cache, added, t_add) = st.add_needed(&mut records, &points, &refresh, spr);
        t_store += t_add;
        let reason = change.reason;
        let t_cache = t0.elapsed().as_secs_f64() - t_photons;

        // 6. The eye pass.
        let src = SelSource {
            at: &refresh,
            cache: &cache,
            used: (0..records.len()).map(|_| AtomicBool::new(false)).collect(),
            misses: Mutex::new(Vec::new()),
            gathers: AtomicU64::new(0),
            buffered: AtomicUsize::new(0),
            buffer_cap: self.settings.eye_buffer_mb as usize * (1 << 20),
            keep: self.settings.store_eye_gathers,
        };
        let eye = EyeView::new(&s, scene, &maps.caustic, &src);
        let mut out = render_camera_rays(&eye, scene, frame, s.common.spp, s.common.seed, progress);
        out.stats.rays += maps.rays;
        let SelSource {
            used,
            misses,
            gathers: eye_gathers,
            ..
        } = src;
        let eye_gathers = eye_gathers.into_inner();
        // 7. The eye pass's gathers become records.
        let misses = misses.into_inner().expect("no panic while held");
        let (from_eye, t_eye) = st.add_from_eye(&mut records, &mut cache, used, misses, &refresh);
        t_store += t_eye;
        st.records = records;
        st.prev = scene_arc.clone();
        let stats = st.store.stats();
        let r = &mut out.report;
        r.insert("photons".into(), s.photons.into());
        r.insert("cache_records".into(), st.records.len().into());
        r.insert("records_added".into(), added.into());
        r.insert("records_rebuilt".into(), rebuilt.into());
        r.insert("records_unused_dropped".into(), unused.into());
        r.insert("records_refreshed".into(), refreshed.into());
        r.insert("strata_priority".into(), counts.priority.into());
        r.insert("strata_by_age".into(), counts.aged.into());
        r.insert("strata_box_only".into(), counts.box_only.into());
        r.insert(
            "strata_cast".into(),
            (counts.priority + counts.aged + (added + eye_gathers) * spr as u64).into(),
        );
        r.insert("records_from_eye".into(), from_eye.into());
        // A frame that re-cast every stratum says so, and why (never silently).
        r.insert("recast_all".into(), reason.into());
        r.insert("strata_reread".into(), counts.reread.into());
        r.insert("terms_reread".into(), counts.terms.to_vec().into());
        r.insert("groups_reread".into(), change.reread.clone().into());
        if let Some(g) = &groups {
            r.insert("light_groups".into(), g.groups().into());
            r.insert("group_photons".into(), g.photons.clone().into());
            r.insert("precomputed_points".into(), g.points().into());
        }
        r.insert("unstored_gathers".into(), eye_gathers.into());
        r.insert("seconds_photons".into(), t_photons.into());
        r.insert("seconds_cache".into(), t_cache.into());
        r.insert("seconds_store".into(), t_store.into());
        r.insert(
            "store".into(),
            serde_json::to_value(stats).expect("stats serialise"),
        );
        out
    }
}

impl crate::framework::sequence::SequenceRenderer for IcSelective {
    fn name(&self) -> &'static str {
        self.name
    }

    fn render_frame(
        &mut self,
        source: &mut FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        self.render(source, frame, progress)
    }
}

/// Registry entry of `ic-selective`.
pub static TECHNIQUE: crate::framework::technique::Preset<IcSelectiveSettings> =
    crate::framework::technique::Preset {
        name: "ic-selective",
        summary: "photon mapping with an irradiance cache whose records keep their gather directions (radiance, distance, hit, age) in a paged store and re-cast per frame those that a change reached plus a fraction chosen by age (Tawara et al. 2004)",
        capabilities: crate::framework::technique::Capabilities {
            motion_blur: false,
            photons: false,
            window: false,
            max_depth: false,
            stateless: false,
            effort: crate::framework::technique::Effort {
                key: "photons",
                per_unit: 1000,
                unit: "thousand photons per map and frame",
            },
        },
        quality: &[],
        defaults: IcSelectiveSettings::default,
        common: |s| &mut s.pmic.common,
        build: |s, _, name| Ok(Box::new(IcSelective::new(s, name)?)),
    };
