//! The photon pool, its signed element solution, the pilots, the queue of invalid groups
//! and the update step ([`SptState`]).

use super::groups::{GroupLayout, used_dims};
use super::{Order, SptSettings};
use crate::kernels::elements::element_map::{
    ElementAccumulators, ElementMesh, FrameElements, slot,
};
use crate::kernels::photon::{PhotonStats, segment_hits_box, trace_photon_path};
use chronolux_core::accel::TriRef;
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::geometry::Bounds3;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::hash_words;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// No slot / no light.
const NONE: u32 = u32::MAX;

/// Deposit kinds (which accumulator a deposit goes to).
const DIRECT: u8 = 0;
const INDIRECT: u8 = 1;
const CAUSTIC: u8 = 2;

/// One vertex of a stored photon path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecVertex {
    /// World position of the hit.
    pub p: Vec3,
    pub instance: u32,
    pub material: u32,
    pub tri: TriRef,
    /// Element side deposited on, `NONE` for a delta (purely specular) vertex.
    pub slot: u32,
    pub kind: u8,
    pub power: Rgb,
}

/// A photon's path as last shot: what it touched and what it deposited.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonRecord {
    /// Emitting light (`NONE`: nothing emitted).
    pub light: u32,
    /// Where the photon left the light.
    pub origin: Vec3,
    pub vertices: Vec<RecVertex>,
    /// Direction of the last segment when it left the scene without a hit (zero when the
    /// path ended at a vertex or emitted nothing).
    pub escape: Vec3,
}

impl PhotonRecord {
    /// The path touches something `changes` reports changed (its light, the instance or
    /// the material of a vertex).
    ///
    /// `selection_changed`: the light selection probabilities differ between the two
    /// scenes (some light's power changed), which changes every photon's light choice
    /// and power: then every path that left a light touches the change.
    pub fn touches(&self, changes: &FrameDelta, selection_changed: bool) -> bool {
        (self.light != NONE && (selection_changed || changes.light_changed(self.light as usize)))
            || self.vertices.iter().any(|v| {
                changes.instance_changed(v.instance as usize)
                    || changes.material_changed(v.material as usize)
            })
    }

    /// Some segment of the path (emission point → vertices → escape ray) passes through
    /// one of `boxes` (conservative: a segment that crosses a box may miss what is in it).
    pub fn crosses(&self, boxes: &[Bounds3]) -> bool {
        if self.light == NONE || boxes.is_empty() {
            return false;
        }
        let mut a = self.origin;
        for v in &self.vertices {
            if boxes.iter().any(|b| segment_hits_box(a, v.p - a, 1.0, b)) {
                return true;
            }
            a = v.p;
        }
        self.escape != Vec3::ZERO
            && boxes
                .iter()
                .any(|b| segment_hits_box(a, self.escape, f32::INFINITY, b))
    }

    /// The two paths differ: another light, another vertex count, another instance,
    /// material, triangle, element side or deposit kind at some vertex, or a power that
    /// differs by more than `tol` relative to the larger one.
    pub fn differs(&self, o: &PhotonRecord, tol: f32) -> bool {
        self.light != o.light
            || self.vertices.len() != o.vertices.len()
            || self.vertices.iter().zip(&o.vertices).any(|(a, b)| {
                a.instance != b.instance
                    || a.material != b.material
                    || a.tri != b.tri
                    || a.slot != b.slot
                    || a.kind != b.kind
                    || {
                        let d = (a.power - b.power).abs().max_element();
                        d > tol * a.power.max_element().max(b.power.max_element())
                    }
            })
    }
}

/// Traces photon `i` in `scene` and records its path on `mesh`'s elements.
pub fn trace_record(
    scene: &FrameScene,
    mesh: &ElementMesh,
    i: u64,
    seed: u64,
) -> (PhotonRecord, PhotonStats) {
    let mut rec = PhotonRecord {
        light: NONE,
        origin: Vec3::ZERO,
        vertices: Vec::new(),
        escape: Vec3::ZERO,
    };
    let mut verts = Vec::new();
    let mut escape = Vec3::ZERO;
    let stats = trace_photon_path(
        scene,
        i,
        seed,
        |l, ray| {
            rec.light = l as u32;
            rec.origin = ray.o;
        },
        |v| {
            let h = &v.hit;
            let (s, kind) = if v.deposited {
                let e = mesh.locate(h.tri, h.b1, h.b2).element;
                let kind = if !h.is_indirect() {
                    DIRECT
                } else if h.caustic {
                    CAUSTIC
                } else {
                    INDIRECT
                };
                (slot(e, h.wi.dot(h.ng) >= 0.0) as u32, kind)
            } else {
                (NONE, DIRECT)
            };
            verts.push(RecVertex {
                p: h.p,
                instance: h.instance,
                material: v.material,
                tri: h.tri,
                slot: s,
                kind,
                power: h.power,
            });
        },
        |ray| escape = ray.d,
    );
    rec.vertices = verts;
    rec.escape = escape;
    (rec, stats)
}

/// Traces photons `indices` in parallel; records in the order of `indices`.
pub fn trace_records(
    scene: &FrameScene,
    mesh: &ElementMesh,
    indices: &[u64],
    seed: u64,
) -> (Vec<PhotonRecord>, PhotonStats) {
    let chunks = parallel::map_chunks(indices.len(), 256, |r| {
        let mut st = PhotonStats::default();
        let v: Vec<PhotonRecord> = indices[r]
            .iter()
            .map(|&i| {
                let (rec, s) = trace_record(scene, mesh, i, seed);
                st += s;
                rec
            })
            .collect();
        (v, st)
    });
    let mut out = Vec::with_capacity(indices.len());
    let mut stats = PhotonStats::default();
    for (v, s) in chunks {
        out.extend(v);
        stats += s;
    }
    (out, stats)
}

/// Per element side photon sums that accept negative deposits.
///
/// Sums are kept in `f64` and a removed photon subtracts exactly the values it added (its
/// stored deposits), so the sums always describe the photons currently in the solution:
/// `count` is their number on the side (a removal decrements it) and `flux_sq` their
/// Σ luminance(φ)², the same noise estimate as for unsigned sums
/// ([`crate::kernels::elements::reconstruct`]) — a removal does not add variance, it takes the removed
/// photon's term out. Adding and removing the same deposit returns every sum to its old
/// value up to one `f64` rounding per operation (relative 1e-16).
#[derive(Clone, Debug)]
pub struct SignedAccumulators {
    pub flux: Vec<[f64; 3]>,
    pub count: Vec<i64>,
    pub flux_sq: Vec<f64>,
}

impl SignedAccumulators {
    pub fn new(elements: usize) -> Self {
        SignedAccumulators {
            flux: vec![[0.0; 3]; 2 * elements],
            count: vec![0; 2 * elements],
            flux_sq: vec![0.0; 2 * elements],
        }
    }

    /// Adds (`sign = 1`) or removes (`sign = −1`) one deposit.
    #[inline]
    pub fn deposit(&mut self, slot: usize, power: Rgb, sign: f64) {
        let f = &mut self.flux[slot];
        f[0] += sign * power.x as f64;
        f[1] += sign * power.y as f64;
        f[2] += sign * power.z as f64;
        self.count[slot] += sign as i64;
        let l = luminance(power) as f64;
        self.flux_sq[slot] += sign * l * l;
    }

    /// The sums as the (unsigned, `f32`) accumulators the reconstruction reads, for
    /// `photons` photons in the solution. Tiny negative leftovers of cancellation are
    /// clamped to 0 (a side's true sum of positive photon powers is never negative).
    pub fn to_accumulators(&self, photons: u64) -> ElementAccumulators {
        ElementAccumulators {
            flux: self
                .flux
                .iter()
                .map(|f| Rgb::new(f[0] as f32, f[1] as f32, f[2] as f32).max(Rgb::ZERO))
                .collect(),
            count: self.count.iter().map(|&c| c.max(0) as u32).collect(),
            flux_sq: self.flux_sq.iter().map(|&s| s.max(0.0) as f32).collect(),
            photons,
        }
    }

    /// Luminance of the flux sum of a side.
    #[inline]
    pub fn lum(&self, slot: usize) -> f64 {
        let f = self.flux[slot];
        0.2126 * f[0] + 0.7152 * f[1] + 0.0722 * f[2]
    }
}

/// The element solution of the pool: one signed accumulator per deposit kind.
#[derive(Clone, Debug)]
pub struct Solution {
    pub direct: SignedAccumulators,
    pub indirect: SignedAccumulators,
    pub caustic: SignedAccumulators,
}

impl Solution {
    pub fn new(elements: usize) -> Self {
        Solution {
            direct: SignedAccumulators::new(elements),
            indirect: SignedAccumulators::new(elements),
            caustic: SignedAccumulators::new(elements),
        }
    }

    /// Adds or removes every deposit of a record.
    pub fn apply(&mut self, rec: &PhotonRecord, sign: f64) {
        for v in &rec.vertices {
            if v.slot == NONE {
                continue;
            }
            let acc = match v.kind {
                DIRECT => &mut self.direct,
                INDIRECT => &mut self.indirect,
                _ => &mut self.caustic,
            };
            acc.deposit(v.slot as usize, v.power, sign);
        }
    }
}

/// A limit on how much one call of [`SptState::drain`] re-shoots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Budget {
    /// Most photons traced (0: no limit). Whole groups only: a limit smaller than a
    /// group re-shoots nothing (a budget is never exceeded).
    pub photons: u64,
    /// Most wall-clock time (checked between batches of groups; `None`: no limit).
    pub time: Option<Duration>,
}

impl Budget {
    /// Photons this budget still allows after `traced` in a drain started at `t0`
    /// (`u64::MAX` without a photon limit), or `None` once its time is up.
    fn room(&self, t0: Instant, traced: u64) -> Option<u64> {
        if self.time.is_some_and(|t| t0.elapsed() >= t) {
            return None;
        }
        Some(if self.photons == 0 {
            u64::MAX
        } else {
            self.photons.saturating_sub(traced)
        })
    }

    /// No limit: drain the whole queue.
    pub const ALL: Budget = Budget {
        photons: 0,
        time: None,
    };
    /// Nothing: only the pilots of [`SptState::update`] are traced.
    pub const NONE: Budget = Budget {
        photons: 0,
        time: Some(Duration::ZERO),
    };
}

/// What one update (or drain) did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct UpdateStats {
    /// Pilot photons re-traced.
    pub pilots_traced: u64,
    /// Groups newly marked invalid (pilots and path scan; in scratch order, all groups).
    pub groups_invalidated: u64,
    /// Groups whose pilots saw the change.
    pub groups_by_pilots: u64,
    /// Groups only the scan of the stored paths found (`scan_paths`).
    pub groups_by_scan: u64,
    /// Groups re-shot.
    pub groups_reshot: u64,
    /// Groups still queued afterwards (carried over to the next update).
    pub groups_queued: u64,
    /// Photons traced (pilots included).
    pub photons_traced: u64,
    /// Closest-hit rays cast.
    pub rays: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl std::ops::AddAssign<&UpdateStats> for UpdateStats {
    fn add_assign(&mut self, o: &UpdateStats) {
        self.pilots_traced += o.pilots_traced;
        self.groups_invalidated += o.groups_invalidated;
        self.groups_by_pilots += o.groups_by_pilots;
        self.groups_by_scan += o.groups_by_scan;
        self.groups_reshot += o.groups_reshot;
        self.groups_queued = o.groups_queued;
        self.photons_traced += o.photons_traced;
        self.rays += o.rays;
        self.seconds += o.seconds;
    }
}

/// The result of [`SptState::audit`]: what a full re-trace finds stale.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Audit {
    /// Groups with at least one photon whose stored path differs from its path in the
    /// current scene.
    pub stale_groups: u64,
    /// Of those, groups not queued: changed, but their pilots did not see it (misses).
    pub missed_groups: u64,
    /// `missed_groups / stale_groups` (0 when nothing is stale).
    pub miss_rate: f64,
    /// Stale photons in missed groups.
    pub missed_photons: u64,
    /// Stale photons in all.
    pub stale_photons: u64,
}

/// Side length of the grid of primary rays that estimates each element's screen coverage.
pub const COVERAGE_GRID: u32 = 64;

/// The state of selective photon tracing: a fixed pool of `Z` photons on an element mesh,
/// each photon's last path, the signed element solution, and the queue of invalid groups.
///
/// Made for incremental use: [`SptState::update`] takes the next version of the scene
/// with what changed (an animation frame, or an edit in a viewer), traces the pilots and
/// queues the groups they invalidate, then drains the queue within a budget;
/// [`SptState::drain`] continues between updates, [`SptState::queue_len`] says how much
/// is left. Groups queued by one change and not yet re-shot stay queued across later
/// changes (their stored paths, whatever scene they were traced in, are what is removed
/// when they are re-shot).
pub struct SptState {
    pub settings: SptSettings,
    pub layout: GroupLayout,
    pub mesh: ElementMesh,
    scene: Arc<FrameScene>,
    /// Photon `i`'s last path (`i < Z`).
    records: Vec<PhotonRecord>,
    pub solution: Solution,
    /// Per group: its photons are in the solution (false only while a scratch restart
    /// has not reached it).
    in_solution: Vec<bool>,
    /// Photons currently in the solution (the `N` of `Φ / (N·A)`).
    photons_in_solution: u64,
    /// Pilots per group (members `0 .. pilots` of each group).
    pub pilots: u64,
    /// Per photon: the path scan found its stored path possibly stale (with
    /// [`SptSettings::per_photon`]: the photon is in the queue).
    flagged: Vec<bool>,
    /// Per photon, with [`SptSettings::per_photon`]: its order key (larger first).
    pkey: Vec<f64>,
    /// Per group, with [`SptSettings::per_photon`]: its photons in the queue.
    pending: Vec<u32>,
    /// Groups with a photon in the queue, with [`SptSettings::per_photon`].
    queued_groups: u64,
    /// Whether the pilots are current (traced in the current scene); false after a
    /// scratch restart.
    pilots_current: bool,
    queued: Vec<bool>,
    /// Order key of each group (larger first).
    key: Vec<f64>,
    /// Queued groups (with [`SptSettings::per_photon`]: queued photons) sorted by
    /// ascending key (the next one is last).
    queue: Vec<u32>,
    /// Number of updates made (varies the random order between changes).
    epoch: u64,
    /// Screen coverage of each element side (pixels of the coverage grid).
    coverage: Vec<f32>,
}

impl SptState {
    /// Shoots the whole pool in `scene`, on an element mesh built from it.
    pub fn new(scene: Arc<FrameScene>, settings: SptSettings) -> SptState {
        let mesh = ElementMesh::build(&scene, settings.elements_per_diagonal());
        Self::new_on_mesh(scene, settings, mesh)
    }

    /// Shoots the whole pool in `scene` on a given element mesh (element ids of another
    /// state's mesh, for comparisons; it must [match](ElementMesh::matches) `scene`).
    pub fn new_on_mesh(
        scene: Arc<FrameScene>,
        settings: SptSettings,
        mesh: ElementMesh,
    ) -> SptState {
        assert!(mesh.matches(&scene), "element mesh of another topology");
        let layout = GroupLayout::choose(
            settings.photons,
            settings.group_size.max(1),
            used_dims(&scene),
        );
        let n = layout.photons();
        let pilots = ((settings.pilot_fraction as f64 * layout.members as f64).round() as u64)
            .clamp(1, layout.members);
        let indices: Vec<u64> = (0..n).collect();
        let (records, _) = trace_records(&scene, &mesh, &indices, settings.common.seed);
        let mut solution = Solution::new(mesh.element_count());
        for r in &records {
            solution.apply(r, 1.0);
        }
        let g = layout.groups as usize;
        let coverage = vec![0.0; 2 * mesh.element_count()];
        let mut s = SptState {
            settings,
            layout,
            mesh,
            scene,
            records,
            solution,
            in_solution: vec![true; g],
            photons_in_solution: n,
            pilots,
            flagged: vec![false; n as usize],
            pkey: Vec::new(),
            pending: vec![0; g],
            queued_groups: 0,
            pilots_current: true,
            queued: vec![false; g],
            key: vec![0.0; g],
            queue: Vec::new(),
            epoch: 0,
            coverage,
        };
        if s.settings.per_photon() {
            s.pkey = vec![0.0; n as usize];
        }
        s.coverage = screen_coverage(&s.scene, &s.mesh, COVERAGE_GRID);
        s
    }

    /// The scene the solution is (being brought) up to date with.
    pub fn scene(&self) -> &Arc<FrameScene> {
        &self.scene
    }

    /// Groups waiting to be re-shot (with [`SptSettings::per_photon`]: groups with a
    /// photon waiting).
    pub fn queue_len(&self) -> usize {
        if self.settings.per_photon() {
            self.queued_groups as usize
        } else {
            self.queue.len()
        }
    }

    /// Photons waiting to be re-shot: the queued photons with
    /// [`SptSettings::per_photon`], else the members of the queued groups that their
    /// re-shooting will trace.
    pub fn queued_photons(&self) -> u64 {
        if self.settings.per_photon() {
            return self.queue.len() as u64;
        }
        let only_flagged =
            self.settings.scan_paths && self.settings.reshoot == super::Reshoot::Flagged;
        let skip = if self.pilots_current { self.pilots } else { 0 };
        let n = self.layout.groups;
        self.queue
            .iter()
            .map(|&g| {
                (skip..self.layout.members)
                    .filter(|&m| {
                        let i = g as u64 + m * n;
                        !only_flagged || !self.in_solution[g as usize] || self.flagged[i as usize]
                    })
                    .count() as u64
            })
            .sum()
    }

    /// Photons currently in the solution.
    pub fn photons_in_solution(&self) -> u64 {
        self.photons_in_solution
    }

    /// Photon `i`'s stored path.
    pub fn record(&self, i: u64) -> &PhotonRecord {
        &self.records[i as usize]
    }

    /// Whether `scene` can update this state (same geometry topology and light count:
    /// element ids and light indices carry over). Otherwise build a new state.
    pub fn accepts(&self, scene: &FrameScene) -> bool {
        self.mesh.matches(scene) && scene.lights.len() == self.scene.lights.len()
    }

    /// Takes `scene` as the new current scene (`changes`: what differs from the current
    /// one, [`FrameDelta::between`]), traces the pilots and queues the groups they
    /// invalidate, then re-shoots queued groups within `budget`.
    pub fn update(
        &mut self,
        scene: Arc<FrameScene>,
        changes: &FrameDelta,
        budget: Budget,
    ) -> UpdateStats {
        let mut st = self.invalidate(scene, changes);
        let d = self.drain(budget);
        st += &d;
        st
    }

    /// The first half of [`SptState::update`]: new scene, pilots, queue.
    pub fn invalidate(&mut self, scene: Arc<FrameScene>, changes: &FrameDelta) -> UpdateStats {
        let t0 = Instant::now();
        assert!(
            self.accepts(&scene),
            "SptState::invalidate: topology changed"
        );
        let selection_changed = (0..scene.lights.len())
            .any(|l| scene.light_sampler.pmf(l) != self.scene.light_sampler.pmf(l));
        self.scene = scene;
        self.epoch += 1;
        self.coverage = screen_coverage(&self.scene, &self.mesh, COVERAGE_GRID);
        let mut st = UpdateStats::default();
        let groups = self.layout.groups;
        if self.settings.order == Order::Scratch {
            // Recomputation from scratch: empty solution, every group queued in index
            // order (the key makes group 0 come first).
            self.solution = Solution::new(self.mesh.element_count());
            self.in_solution.iter_mut().for_each(|b| *b = false);
            self.photons_in_solution = 0;
            self.pilots_current = false;
            for g in 0..groups as usize {
                self.queued[g] = true;
                self.key[g] = -(g as f64);
            }
            st.groups_invalidated = groups;
        } else if !changes.is_static() {
            let tol = self.settings.path_tolerance;
            let mut change = vec![0.0f64; groups as usize];
            let phi0 = self.flux_floor();
            let mut invalid = vec![false; groups as usize];
            let use_pilots = self.settings.uses_pilots();
            if use_pilots {
                let pilots: Vec<u64> = (0..groups)
                    .flat_map(|g| (0..self.pilots).map(move |m| (g, m)))
                    .map(|(g, m)| self.layout.photon(g, m))
                    .collect();
                let (new, ps) =
                    trace_records(&self.scene, &self.mesh, &pilots, self.settings.common.seed);
                st.pilots_traced = pilots.len() as u64;
                st.photons_traced += pilots.len() as u64;
                st.rays += ps.rays;
                for (&i, rec) in pilots.iter().zip(new) {
                    let g = self.layout.group_of(i) as usize;
                    let old = &self.records[i as usize];
                    let differs = old.differs(&rec, tol);
                    if differs
                        || old.touches(changes, selection_changed)
                        || rec.touches(changes, selection_changed)
                    {
                        invalid[g] = true;
                    }
                    if differs {
                        change[g] += self.perceived_change(old, &rec, phi0);
                    }
                    if *old != rec {
                        // The pilot itself is brought up to date at once (also when it differs
                        // by less than the tolerance: the pool stays exactly current).
                        if self.in_solution[g] {
                            self.solution.apply(old, -1.0);
                            self.solution.apply(&rec, 1.0);
                        }
                        self.records[i as usize] = rec;
                    }
                }
                self.pilots_current = true;
                st.groups_by_pilots = invalid.iter().filter(|&&b| b).count() as u64;
            } else {
                // No pilots: they are re-shot like any other photon (the scan covers them).
                self.pilots_current = false;
            }
            let per_photon = self.settings.per_photon();
            if self.settings.scan_paths {
                // Every stored path that touched a change, or whose segments cross the
                // new bounds of a changed instance, is (possibly) stale: its group goes
                // into the queue too, with the change its removal makes as its weight.
                // `changes` is from the pool's previous scene to `self.scene` (frame 1).
                let boxes = changes.changed_bounds_in(1);
                let z = self.records.len();
                // Pilots are current already when traced above.
                let first_non_pilot = if use_pilots {
                    (self.pilots * groups) as usize
                } else {
                    0
                };
                let hits = parallel::map_chunks(z, 4096, |r| {
                    r.filter(|&i| {
                        let rec = &self.records[i];
                        i >= first_non_pilot
                            && (rec.touches(changes, selection_changed) || rec.crosses(&boxes))
                    })
                    .collect::<Vec<usize>>()
                });
                let empty = PhotonRecord::default();
                for i in hits.into_iter().flatten() {
                    let g = i % groups as usize;
                    if !invalid[g] {
                        invalid[g] = true;
                        st.groups_by_scan += 1;
                    }
                    let c = self.perceived_change(&self.records[i], &empty, phi0);
                    if per_photon {
                        let k = match self.settings.order {
                            Order::Random => self.random_key(i as u64, 0x0050_4854),
                            _ => c + 1e-30,
                        };
                        self.enqueue_photon(i, k);
                    } else {
                        self.flagged[i] = true;
                    }
                    change[g] += c;
                }
            }
            for g in 0..groups as usize {
                if !invalid[g] {
                    continue;
                }
                st.groups_invalidated += 1;
                if per_photon {
                    // Queued photon by photon above.
                    continue;
                }
                let k = match self.settings.order {
                    Order::Random => {
                        (hash_words(&[
                            self.settings.common.seed,
                            self.epoch,
                            g as u64,
                            0x0053_5054,
                        ]) >> 11) as f64
                    }
                    // A tiny floor keeps groups that touched a change without a visible
                    // difference in the queue (last).
                    _ => change[g] + 1e-30,
                };
                if self.queued[g] {
                    if self.settings.order != Order::Random {
                        self.key[g] += k;
                    }
                } else {
                    self.queued[g] = true;
                    self.key[g] = k;
                }
            }
        }
        self.sort_queue();
        st.groups_queued = self.queue.len() as u64;
        st.seconds = t0.elapsed().as_secs_f64();
        st
    }

    /// A random order key for photon or group `i` in this epoch (`tag` tells the uses apart).
    fn random_key(&self, i: u64, tag: u64) -> f64 {
        (hash_words(&[self.settings.common.seed, self.epoch, i, tag]) >> 11) as f64
    }

    /// Puts photon `i` in the queue with key `k` ([`SptSettings::per_photon`]); one already
    /// there keeps its random key, or adds `k` to its priority.
    fn enqueue_photon(&mut self, i: usize, k: f64) {
        if self.flagged[i] {
            if self.settings.order != Order::Random {
                self.pkey[i] += k;
            }
            return;
        }
        self.flagged[i] = true;
        self.pkey[i] = k;
        let g = i % self.layout.groups as usize;
        self.pending[g] += 1;
        if self.pending[g] == 1 {
            self.queued[g] = true;
            self.queued_groups += 1;
        }
    }

    /// Perceptual size of the change from path `old` to `new`: over the element sides
    /// whose displayed (indirect and caustic) flux changes, Σ |ΔΦ| / (Φ + Φ₀) · (c + c₀):
    /// a Weber contrast against the side's current total flux Φ (direct photons included,
    /// they mask indirect changes; Φ₀ = 1 % of the mean per-side flux keeps dark sides
    /// finite), weighted by the side's screen coverage `c` in pixels of the coverage grid
    /// (`c₀ = 0.1`: sides off screen still count a little, their light reaches the screen
    /// by further bounces).
    fn perceived_change(&self, old: &PhotonRecord, new: &PhotonRecord, phi0: f64) -> f64 {
        let mut out = 0.0;
        let sol = &self.solution;
        let mut one = |rec: &PhotonRecord, sign: f64| {
            for v in &rec.vertices {
                if v.slot == NONE || v.kind == DIRECT {
                    continue;
                }
                let s = v.slot as usize;
                let total = sol.direct.lum(s) + sol.indirect.lum(s) + sol.caustic.lum(s);
                let c = self.coverage[s] as f64 + 0.1;
                out += sign.abs() * luminance(v.power) as f64 / (total.max(0.0) + phi0) * c;
            }
        };
        one(old, -1.0);
        one(new, 1.0);
        out
    }

    /// `Φ₀` of [`Self::perceived_change`]: 1 % of the mean flux sum per element side.
    fn flux_floor(&self) -> f64 {
        let s = &self.solution;
        let n = s.direct.flux.len().max(1);
        let t: f64 = (0..n)
            .map(|k| s.direct.lum(k) + s.indirect.lum(k) + s.caustic.lum(k))
            .sum();
        (0.01 * t / n as f64).max(1e-30)
    }

    /// Queues `groups` for re-shooting (ahead of every queued group in priority order,
    /// with a fresh random key in random order) whatever their pilots say: for a caller
    /// that knows better (a viewer's "refresh", tests).
    pub fn requeue(&mut self, groups: impl IntoIterator<Item = u64>) {
        if self.settings.per_photon() {
            for g in groups {
                for m in 0..self.layout.members {
                    let i = self.layout.photon(g, m);
                    let k = match self.settings.order {
                        Order::Random => self.random_key(i, 0x0052_4551),
                        _ => f64::MAX,
                    };
                    if self.flagged[i as usize] {
                        self.pkey[i as usize] = k;
                    } else {
                        self.enqueue_photon(i as usize, k);
                    }
                }
            }
            self.sort_queue();
            return;
        }
        for g in groups {
            for m in 0..self.layout.members {
                self.flagged[self.layout.photon(g, m) as usize] = true;
            }
            let g = g as usize;
            self.queued[g] = true;
            self.key[g] = match self.settings.order {
                Order::Random => {
                    (hash_words(&[self.settings.common.seed, self.epoch, g as u64, 0x0052_4551])
                        >> 11) as f64
                }
                _ => f64::MAX,
            };
        }
        self.sort_queue();
    }

    fn sort_queue(&mut self) {
        if self.settings.per_photon() {
            self.queue = (0..self.flagged.len() as u32)
                .filter(|&i| self.flagged[i as usize])
                .collect();
            let key = &self.pkey;
            self.queue
                .sort_by(|a, b| key[*a as usize].total_cmp(&key[*b as usize]).then(b.cmp(a)));
            return;
        }
        self.queue = (0..self.layout.groups as u32)
            .filter(|&g| self.queued[g as usize])
            .collect();
        let key = &self.key;
        self.queue
            .sort_by(|a, b| key[*a as usize].total_cmp(&key[*b as usize]).then(b.cmp(a)));
    }

    /// Re-shoots queued groups in queue order within `budget`, one group after the other
    /// (photons of a batch of groups are traced in parallel and applied in queue order,
    /// so the result does not depend on the thread count).
    pub fn drain(&mut self, budget: Budget) -> UpdateStats {
        if self.settings.per_photon() {
            return self.drain_photons(budget);
        }
        let t0 = Instant::now();
        let mut st = UpdateStats::default();
        let members = self.layout.members;
        let skip = if self.pilots_current { self.pilots } else { 0 };
        let threads = rayon::current_num_threads() as u64;
        let n_groups = self.layout.groups;
        // Only the flagged photons of a group when the flags are complete (path scan on,
        // `reshoot = flagged`) and the group is in the solution; else the whole group.
        let only_flagged =
            self.settings.scan_paths && self.settings.reshoot == super::Reshoot::Flagged;
        loop {
            if self.queue.is_empty() {
                break;
            }
            let Some(room) = budget.room(t0, st.photons_traced) else {
                break;
            };
            // Whole groups in queue order, about 4096 photons per thread between time
            // checks, never past the photon budget.
            let mut groups: Vec<u32> = Vec::new();
            let mut indices: Vec<u64> = Vec::new();
            while let Some(&g) = self.queue.last() {
                let gi = g as usize;
                let before = indices.len();
                for m in skip..members {
                    let i = g as u64 + m * n_groups;
                    if !only_flagged || !self.in_solution[gi] || self.flagged[i as usize] {
                        indices.push(i);
                    }
                }
                if indices.len() as u64 > room {
                    indices.truncate(before);
                    break;
                }
                groups.push(self.queue.pop().unwrap());
                if indices.len() as u64 >= 4096 * threads {
                    break;
                }
            }
            if groups.is_empty() {
                break;
            }
            let (recs, ps) =
                trace_records(&self.scene, &self.mesh, &indices, self.settings.common.seed);
            st.rays += ps.rays;
            st.photons_traced += indices.len() as u64;
            for (&i, rec) in indices.iter().zip(recs) {
                let g = self.layout.group_of(i) as usize;
                if self.in_solution[g] {
                    self.solution.apply(&self.records[i as usize], -1.0);
                }
                self.solution.apply(&rec, 1.0);
                self.records[i as usize] = rec;
                self.flagged[i as usize] = false;
            }
            for &g in &groups {
                let g = g as usize;
                if !self.in_solution[g] {
                    // A scratch restart reaching this group: its pilots too were traced
                    // above (skip = 0); the group now counts in the solution.
                    self.in_solution[g] = true;
                    self.photons_in_solution += members;
                }
                self.queued[g] = false;
                self.key[g] = 0.0;
            }
            st.groups_reshot += groups.len() as u64;
        }
        if self.queue.is_empty() && !self.pilots_current {
            self.pilots_current = true;
        }
        st.groups_queued = self.queue.len() as u64;
        st.seconds = t0.elapsed().as_secs_f64();
        st
    }

    /// [`SptState::drain`] when the queue holds photons ([`SptSettings::per_photon`]):
    /// photons in queue order, traced in parallel in batches of about 4096 per thread,
    /// applied in queue order (the result does not depend on the thread count). The photon
    /// budget is met exactly.
    fn drain_photons(&mut self, budget: Budget) -> UpdateStats {
        let t0 = Instant::now();
        let mut st = UpdateStats::default();
        let threads = rayon::current_num_threads() as u64;
        let batch = 4096 * threads;
        let n_groups = self.layout.groups as usize;
        loop {
            if self.queue.is_empty() {
                break;
            }
            let Some(room) = budget.room(t0, st.photons_traced) else {
                break;
            };
            let take = room.min(batch).min(self.queue.len() as u64) as usize;
            if take == 0 {
                break;
            }
            let indices: Vec<u64> = (0..take)
                .map(|_| self.queue.pop().expect("queue holds `take` photons") as u64)
                .collect();
            let (recs, ps) =
                trace_records(&self.scene, &self.mesh, &indices, self.settings.common.seed);
            st.rays += ps.rays;
            st.photons_traced += indices.len() as u64;
            for (&i, rec) in indices.iter().zip(recs) {
                let i = i as usize;
                self.solution.apply(&self.records[i], -1.0);
                self.solution.apply(&rec, 1.0);
                self.records[i] = rec;
                self.flagged[i] = false;
                let g = i % n_groups;
                self.pending[g] -= 1;
                if self.pending[g] == 0 {
                    self.queued[g] = false;
                    self.queued_groups -= 1;
                    st.groups_reshot += 1;
                }
            }
        }
        if self.queue.is_empty() && !self.pilots_current {
            self.pilots_current = true;
        }
        st.groups_queued = self.queued_groups;
        st.seconds = t0.elapsed().as_secs_f64();
        st
    }

    /// Re-traces every photon in the current scene and compares with the stored paths:
    /// stale groups, and of them those not queued (missed by their pilots). Costs a full
    /// pass; for tests and `--set audit=true`.
    pub fn audit(&self) -> Audit {
        let n = self.layout.photons();
        let indices: Vec<u64> = (0..n).collect();
        let (recs, _) = trace_records(&self.scene, &self.mesh, &indices, self.settings.common.seed);
        let g = self.layout.groups as usize;
        let mut stale = vec![0u64; g];
        for (i, rec) in recs.iter().enumerate() {
            if self.in_solution[i % g] && self.records[i].differs(rec, self.settings.path_tolerance)
            {
                stale[i % g] += 1;
            }
        }
        let mut a = Audit::default();
        for (k, &s) in stale.iter().enumerate() {
            if s > 0 {
                a.stale_groups += 1;
                a.stale_photons += s;
                if !self.queued[k] {
                    a.missed_groups += 1;
                    a.missed_photons += s;
                }
            }
        }
        a.miss_rate = if a.stale_groups > 0 {
            a.missed_groups as f64 / a.stale_groups as f64
        } else {
            0.0
        };
        a
    }

    /// The element sums as the reconstruction reads them: (direct, indirect, caustic).
    pub fn accumulators(
        &self,
    ) -> (
        ElementAccumulators,
        ElementAccumulators,
        ElementAccumulators,
    ) {
        let n = self.photons_in_solution;
        (
            self.solution.direct.to_accumulators(n),
            self.solution.indirect.to_accumulators(n),
            self.solution.caustic.to_accumulators(n),
        )
    }

    /// World-space element data of the current scene.
    pub fn frame_elements(&self) -> FrameElements {
        FrameElements::new(&self.scene, &self.mesh)
    }
}

/// Screen coverage of each element side of `mesh` (indexed by [`slot`]): an `n × n` grid of
/// primary rays through pixel centres of `scene`'s camera, counted on the side each hits
/// first.
pub fn screen_coverage(scene: &FrameScene, mesh: &ElementMesh, n: u32) -> Vec<f32> {
    let cam = &scene.camera;
    let rows = parallel::map_chunks(n as usize, 4, |r| {
        let mut hits = Vec::new();
        for y in r {
            for x in 0..n {
                let raster = Vec2::new(
                    (x as f32 + 0.5) / n as f32 * cam.width as f32,
                    (y as f32 + 0.5) / n as f32 * cam.height as f32,
                );
                let ray = cam.generate_ray(raster);
                if let Some(h) = scene.intersect(&ray) {
                    let si = scene.interaction(&h, &ray);
                    let e = mesh.locate(h.tri, h.b1, h.b2).element;
                    hits.push(slot(e, -ray.d.dot(si.ng) >= 0.0));
                }
            }
        }
        hits
    });
    let mut c = vec![0.0f32; 2 * mesh.element_count()];
    for s in rows.into_iter().flatten() {
        c[s] += 1.0;
    }
    c
}
