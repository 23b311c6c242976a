//! Selective photon tracing: the Halton group bound (Eq. 1 of Dmitriev et al. 2002) on the
//! generated points, exact signed deposits, the solution after draining against a fresh
//! pass, no stale shadow, the pilots' miss rate, and the per-frame budget.

use chronolux_core::color::luminance;
use chronolux_core::sampling::qmc::halton;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::stage::{caustic, demo};
use chronolux_render::framework::sequence::SequenceRenderer;
use chronolux_render::kernels::elements::element_map::FrameElements;
use chronolux_render::techniques::spt::groups::{COHERENT_DIMS, GroupLayout, toroidal_distance};
use chronolux_render::techniques::spt::pool::{Budget, SignedAccumulators, SptState};
use chronolux_render::techniques::spt::{Order, Reshoot, Spt, SptSettings};
use std::sync::Arc;

fn settings(photons: u64) -> SptSettings {
    SptSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1,
            ..SptSettings::default().common
        },
        photons,
        group_size: 32,
        elements: 30.0,
        ..Default::default()
    }
}

/// Frames `a` and `b` of `desc` at 24 fps (tiny images: only the photons matter).
fn two_frames(
    desc: chronolux_core::scene::desc::SceneDesc,
    a: u32,
    b: u32,
) -> (Arc<FrameScene>, Arc<FrameScene>) {
    let mut src = crate::source(desc, 16, 16, 24.0, vec![a, b]);
    (src.frame(a), src.frame(b))
}

/// Eq. 1: with `N_g = Π b_j^k_j`, every member `r + m·N_g` of group `r` lies within
/// `b_j^-k_j` of member 0 in coherent dimension `j` — as the photon kernel generates the
/// points (scrambled, seed 3), on the torus. Tolerance 2e-6: the kernel's points are
/// `f32` (the radical inverse and the shift are each rounded once, ≤ 6e-8 each); the
/// smallest cell here is 1/13. Checked for every group and member of two layouts (area
/// light: six dimensions; punctual light: four), and the bound is not vacuous: some pair
/// of members spreads over more than half the cell in every coherent dimension.
#[test]
fn every_group_satisfies_equation_1_on_the_generated_points() {
    for (layout, used) in [
        (GroupLayout::choose(300_000, 64, [true; 6]), [true; 6]),
        (
            GroupLayout::choose(100_000, 32, [false, false, true, true, true, true]),
            [false, false, true, true, true, true],
        ),
    ] {
        assert!(layout.groups * layout.members >= 90_000);
        let mut spread = [0.0f64; 6];
        for r in 0..layout.groups {
            for (j, &dim) in COHERENT_DIMS.iter().enumerate() {
                if layout.exponents[j] == 0 {
                    assert!(!used[j] || layout.cell_width(j) == 1.0);
                    continue;
                }
                let w = layout.cell_width(j);
                let x0 = halton(dim, layout.photon(r, 0), 3) as f64;
                for m in 1..layout.members {
                    let x = halton(dim, layout.photon(r, m), 3) as f64;
                    let d = toroidal_distance(x, x0);
                    assert!(
                        d < w + 2e-6,
                        "group {r} member {m} dim {dim}: {d} ≥ b^-k = {w}"
                    );
                    spread[j] = spread[j].max(d / w);
                }
            }
        }
        for (j, sp) in spread.iter().enumerate() {
            if layout.exponents[j] > 0 {
                assert!(*sp > 0.5, "dim {j}: spread {sp}");
            }
        }
    }
}

fn max_abs_flux(a: &SignedAccumulators) -> f64 {
    a.flux()
        .iter()
        .flat_map(|f| f.iter().map(|x| x.abs()))
        .fold(0.0, f64::max)
}

/// Re-shooting every group in an unchanged scene subtracts each photon's old deposits
/// and adds the same new ones: the sums return to themselves up to `f64` rounding. Each
/// side's sum sees at most ~2·10⁵ additions and subtractions here, each off by at most
/// 2⁻⁵³ of the running sum: ≤ 3·10⁻¹¹ of the largest sum; the tolerance is 10⁻⁹ of it.
/// Counts are integers and must be equal exactly. An update with an unchanged scene
/// queues nothing.
#[test]
fn reshooting_in_an_unchanged_scene_leaves_the_solution_equal() {
    let (a, _) = two_frames(demo(), 0, 1);
    let mut st = SptState::new(a.clone(), settings(60_000));
    let before = st.solution.clone();
    let u = st.update(a.clone(), &FrameDelta::between(&a, &a), Budget::ALL);
    assert_eq!(u.groups_invalidated, 0);
    assert_eq!(u.photons_traced, 0);
    st.requeue(0..st.layout.groups);
    let d = st.drain(Budget::ALL);
    assert_eq!(d.groups_reshot, st.layout.groups);
    assert_eq!(st.queue_len(), 0);
    for (x, y) in [
        (&before.direct, &st.solution.direct),
        (&before.indirect, &st.solution.indirect),
        (&before.caustic, &st.solution.caustic),
    ] {
        assert_eq!(x.count(), y.count());
        let tol = 1e-9 * max_abs_flux(x);
        for (p, q) in x.flux().iter().zip(&y.flux()) {
            for c in 0..3 {
                assert!((p[c] - q[c]).abs() <= tol, "{} vs {}", p[c], q[c]);
            }
        }
        let tol_sq = 1e-9 * x.flux_sq().iter().fold(0.0, |m: f64, v| m.max(*v));
        for (p, q) in x.flux_sq().iter().zip(&y.flux_sq()) {
            assert!((p - q).abs() <= tol_sq);
        }
    }
}

/// Per element side: (indirect + caustic luminance flux sum, its Σφ², area) of a state.
fn displayed(st: &SptState) -> (Vec<f64>, Vec<f64>, Vec<f32>) {
    let s = &st.solution;
    let flux = (0..s.indirect.len())
        .map(|k| s.indirect.lum(k) + s.caustic.lum(k))
        .collect();
    let sq = (0..s.indirect.len())
        .map(|k| s.indirect.flux_sq[k] + s.caustic.flux_sq[k])
        .collect();
    let fe = FrameElements::new(st.scene(), &st.mesh);
    (flux, sq, fe.area)
}

/// The demo's block jumps from its first to its last position (frame 0 → 48).
///
/// **Miss rate** (item 3): right after the pilots, a full re-trace ([`SptState::audit`])
/// counts the groups with a changed photon that are not queued. With the pilots alone (the
/// paper's detector, `scan_paths = false`) the rate is printed, not bounded — it is what
/// it is for this pool (60k photons, 1260 groups of 48, 3 pilots each) and is reported in
/// BENCHMARKS.md; with the scan of the stored paths (the default) it must be 0: the scan is
/// complete by construction (a path changes only if it touched a changed instance, light or
/// material, or now meets a changed instance, i.e. crosses its new bounds).
///
/// **Correctness** (item 5): after the queue is drained, per element side the displayed
/// (indirect + caustic) flux is tested against a fresh pass of the same photons in the
/// new scene, with the fresh pass's own standard error there, `√Σφ²`: sides beyond 3
/// standard errors may hold at most 1 % of the displayed power (a difference below 3σ
/// cannot be told from the fresh pass's noise; 1 % allows the few sides where a stale
/// photon lands on an otherwise nearly empty side), and the total displayed power must
/// agree within 1 % (its own relative standard error with 60k photons is ≈ 0.5 %). With
/// the default detector the pool is then exactly the fresh pool (every record equal), so
/// the test has all of its margin.
#[test]
fn after_draining_the_solution_equals_a_fresh_pass_of_the_new_scene() {
    let (a, b) = two_frames(demo(), 0, 48);
    let mesh = chronolux_render::kernels::elements::element_map::ElementMesh::build(&a, 30.0);
    let fresh = SptState::new_on_mesh(b.clone(), settings(60_000), mesh.clone());
    let (f_f, sq_f, area) = displayed(&fresh);
    let total: f64 = f_f.iter().map(|x| x.max(0.0)).sum();
    for (scan, pilots) in [(false, true), (true, true), (true, false)] {
        let s = SptSettings {
            scan_paths: scan,
            trace_pilots: pilots,
            reshoot: if pilots {
                Reshoot::Flagged
            } else {
                Reshoot::Photon
            },
            ..settings(60_000)
        };
        let mut st = SptState::new_on_mesh(a.clone(), s, mesh.clone());
        let changes = FrameDelta::between(&a, &b);
        let inv = st.invalidate(b.clone(), &changes);
        assert_eq!(inv.groups_by_pilots > 0, pilots);
        assert_eq!(inv.pilots_traced > 0, pilots);
        let audit = st.audit();
        eprintln!(
            "block jump, scan_paths={scan}, pilots={pilots}: {} of {} groups invalidated ({} by {} pilots, {} by the path scan); audit: {audit:?}",
            inv.groups_invalidated,
            st.layout.groups,
            inv.groups_by_pilots,
            inv.pilots_traced,
            inv.groups_by_scan
        );
        assert!(audit.stale_groups > 0);
        if scan {
            assert_eq!(audit.missed_groups, 0);
        }
        st.drain(Budget::ALL);
        assert_eq!(st.queue_len(), 0);
        let stale = (0..st.layout.photons())
            .filter(|&i| st.record(i) != fresh.record(i))
            .count() as u64;
        assert_eq!(stale, if scan { 0 } else { audit.missed_photons });
        let (f_s, _, _) = displayed(&st);
        let total_s: f64 = f_s.iter().map(|x| x.max(0.0)).sum();
        let mut beyond = 0.0;
        for k in 0..f_f.len() {
            if area[k / 2] > 0.0 && (f_s[k] - f_f[k]).abs() > 3.0 * sq_f[k].sqrt() {
                beyond += f_f[k].max(f_s[k]).max(0.0);
            }
        }
        eprintln!(
            "  after draining: {stale} stale photons; total displayed power {total_s:.1} vs fresh {total:.1}; power on sides beyond 3σ: {:.3} %",
            100.0 * beyond / total
        );
        if scan {
            assert!((total - total_s).abs() <= 0.01 * total);
            assert!(beyond <= 0.01 * total);
        }
    }
}

/// Groups re-shot by the pilots are exactly up to date: after draining, every photon of
/// a group that was queued equals its fresh trace in the new scene (bit for bit: same
/// deterministic kernel, same scene).
#[test]
fn queued_groups_are_exactly_up_to_date_after_draining() {
    let (a, b) = two_frames(demo(), 0, 48);
    let mut st = SptState::new(a.clone(), settings(30_000));
    st.invalidate(b.clone(), &FrameDelta::between(&a, &b));
    let queued: std::collections::HashSet<u64> = (0..st.layout.groups)
        .filter(|&g| {
            // A group is queued iff it is re-shot by the drain below; probe via audit-free
            // comparison after draining instead: record which groups differ now.
            (0..st.layout.members).any(|m| {
                let i = st.layout.photon(g, m);
                m >= st.pilots && {
                    let (r, _) =
                        chronolux_render::techniques::spt::pool::trace_record(&b, &st.mesh, i, 0);
                    &r != st.record(i)
                }
            })
        })
        .collect();
    let audit = st.audit();
    st.drain(Budget::ALL);
    let mut fixed = 0;
    for &g in &queued {
        let all_fresh = (0..st.layout.members).all(|m| {
            let i = st.layout.photon(g, m);
            let (r, _) = chronolux_render::techniques::spt::pool::trace_record(&b, &st.mesh, i, 0);
            &r == st.record(i)
        });
        fixed += all_fresh as u64;
    }
    // Every stale group is fixed except the missed ones.
    assert_eq!(fixed + audit.missed_groups, queued.len() as u64);
}

/// No stale light: in the caustic scene an occluder hangs under the lamp in frame 4 and
/// is gone (under the floor) in frame 3. Updating a frame-4 pool to frame 3 and draining
/// must leave no shadow: on the floor under the occluder's footprint the direct-photon
/// flux (the sharpest shadow) and the displayed indirect flux equal a fresh frame-3
/// pass's within 4 of the fresh region sum's standard errors (√Σφ², so a 4σ band: a
/// 1-in-16000 false alarm for Gaussian noise); and the shadow was real: in frame 4 the
/// region held less than half of frame 3's direct flux.
#[test]
fn a_removed_occluder_leaves_no_shadow_behind() {
    let (shown, gone) = two_frames(caustic(), 4, 3);
    let mut st = SptState::new(shown.clone(), settings(60_000));
    let fe = FrameElements::new(&gone, &st.mesh);
    // Floor sides (normal up, y ≈ 0) within the occluder's footprint (|x|, |z| < 0.2).
    let region: Vec<usize> = (0..fe.area.len())
        .filter(|&e| {
            let c = fe.centroid[e];
            fe.normal[e].y > 0.9 && c.y.abs() < 1e-3 && c.x.abs() < 0.2 && c.z.abs() < 0.2
        })
        .map(|e| 2 * e)
        .collect();
    assert!(region.len() > 10, "{} floor sides", region.len());
    let sum = |a: &SignedAccumulators| -> (f64, f64) {
        region
            .iter()
            .fold((0.0, 0.0), |(s, q), &k| (s + a.lum(k), q + a.flux_sq[k]))
    };
    let (shadowed, _) = sum(&st.solution.direct);
    let u = st.update(
        gone.clone(),
        &FrameDelta::between(&shown, &gone),
        Budget::ALL,
    );
    assert_eq!(st.queue_len(), 0);
    eprintln!("occluder removed: {u:?}");
    let fresh = SptState::new_on_mesh(gone.clone(), settings(60_000), st.mesh.clone());
    let (d_s, _) = sum(&st.solution.direct);
    let (d_f, dq) = sum(&fresh.solution.direct);
    let stale = (0..st.layout.photons())
        .filter(|&i| st.record(i) != fresh.record(i))
        .count();
    assert_eq!(stale, 0, "the path scan misses nothing");
    assert!(
        shadowed < 0.5 * d_f,
        "no shadow to begin with: {shadowed} vs {d_f}"
    );
    assert!(
        (d_s - d_f).abs() <= 4.0 * dq.sqrt(),
        "direct flux under the removed occluder {d_s} vs fresh {d_f} (σ {})",
        dq.sqrt()
    );
    let (i_s, _) = sum(&st.solution.indirect);
    let (i_f, iq) = sum(&fresh.solution.indirect);
    assert!(
        (i_s - i_f).abs() <= 4.0 * iq.sqrt(),
        "indirect flux {i_s} vs fresh {i_f} (σ {})",
        iq.sqrt()
    );
}

/// The per-frame budget: with a budget of 0.5 % of the pool per frame, the demo's moving
/// block invalidates more than fits, the rest is carried over (reported), each frame
/// traces at most budget + pilots photons, and the random and scratch orders run — with
/// groups and with single photons in the queue.
#[test]
fn the_frame_budget_carries_groups_over_and_reports_them() {
    for (order, reshoot) in [
        (Order::Priority, Reshoot::Flagged),
        (Order::Random, Reshoot::Flagged),
        (Order::Scratch, Reshoot::Flagged),
        (Order::Priority, Reshoot::Photon),
        (Order::Random, Reshoot::Photon),
    ] {
        let mut src = crate::source(demo(), 16, 16, 24.0, (0..3).collect());
        let s = SptSettings {
            budget_fraction: 0.005,
            order,
            reshoot,
            trace_pilots: reshoot == Reshoot::Flagged,
            ..settings(30_000)
        };
        let mut spt = Spt::new(s);
        let mut carried = Vec::new();
        for f in 0..3 {
            let out = spt.render_frame(&mut src, f, &|_| {});
            let r = &out.report;
            let z = r["pool"].as_u64().unwrap();
            if f > 0 {
                assert!(!r["rebuilt"].as_bool().unwrap());
                let traced = r["photons_traced"].as_u64().unwrap();
                let pilots = r["pilots_traced"].as_u64().unwrap();
                assert!(traced <= pilots + (0.005f64 * z as f64).ceil() as u64);
            }
            carried.push(r["groups_carried_over"].as_u64().unwrap());
            assert!(out.pixels.iter().all(|p| p.is_finite()));
        }
        assert!(carried[2] > 0, "{order:?}: {carried:?}");
        if order == Order::Scratch {
            // A scratch restart renders with the photons shot so far only.
            let st = spt.state().unwrap();
            assert!(st.photons_in_solution() < st.layout.photons());
        }
    }
}

/// The pool after a change and a full drain (demo's block jump), with and without pilots,
/// with groups or single photons in the queue, in priority and random order: every
/// stored path equals the fresh trace of the new scene (bit for bit: the scan is
/// complete and the kernel deterministic), so skipping the pilots changes nothing in the
/// final pool; the sums agree with the fresh pool's to `f64` rounding (each side's sum
/// sees ≲ 2·10⁵ additions and removals, each off by ≤ 2⁻⁵³ of the running sum: ≤ 3·10⁻¹¹ of
/// the largest sum; tolerance 10⁻⁹ of it), counts exactly. Per-photon re-shooting
/// without pilots traces fewer photons than the pilot mode's pilots plus flagged photons.
#[test]
fn skipping_the_pilots_leaves_the_final_pool_identical() {
    let (a, b) = two_frames(demo(), 0, 48);
    let mesh = chronolux_render::kernels::elements::element_map::ElementMesh::build(&a, 30.0);
    let fresh = SptState::new_on_mesh(b.clone(), settings(60_000), mesh.clone());
    let changes = FrameDelta::between(&a, &b);
    let mut traced = Vec::new();
    for (pilots, reshoot, order) in [
        (true, Reshoot::Flagged, Order::Priority),
        (false, Reshoot::Flagged, Order::Priority),
        (false, Reshoot::Photon, Order::Priority),
        (false, Reshoot::Photon, Order::Random),
        (true, Reshoot::Photon, Order::Priority),
    ] {
        let s = SptSettings {
            trace_pilots: pilots,
            reshoot,
            order,
            ..settings(60_000)
        };
        let mut st = SptState::new_on_mesh(a.clone(), s, mesh.clone());
        let u = st.update(b.clone(), &changes, Budget::ALL);
        assert_eq!(st.queue_len(), 0);
        assert_eq!(st.queued_photons(), 0);
        traced.push(u.photons_traced);
        let stale = (0..st.layout.photons())
            .filter(|&i| st.record(i) != fresh.record(i))
            .count();
        assert_eq!(stale, 0, "pilots={pilots} {reshoot:?} {order:?}");
        for (x, y) in [
            (&fresh.solution.direct, &st.solution.direct),
            (&fresh.solution.indirect, &st.solution.indirect),
            (&fresh.solution.caustic, &st.solution.caustic),
        ] {
            assert_eq!(x.count(), y.count());
            let tol = 1e-9 * max_abs_flux(x);
            for (p, q) in x.flux().iter().zip(&y.flux()) {
                for c in 0..3 {
                    assert!((p[c] - q[c]).abs() <= tol, "{} vs {}", p[c], q[c]);
                }
            }
        }
    }
    eprintln!(
        "photons traced (pilots, flagged, photon, photon random, photon + pilots): {traced:?}"
    );
    assert!(traced[2] < traced[0]);
    assert_eq!(
        traced[2], traced[3],
        "the same flagged photons in either order"
    );
}

/// Determinism: per-photon updates in steps of a small budget give bit-identical sums and
/// paths on 1 and 2 threads (photons are traced in parallel but applied in queue order).
#[test]
fn per_photon_updates_do_not_depend_on_the_thread_count() {
    let (a, b) = two_frames(demo(), 0, 48);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut st = SptState::new(a.clone(), settings(30_000));
                let mut u = st.update(
                    b.clone(),
                    &FrameDelta::between(&a, &b),
                    Budget {
                        photons: 300,
                        time: None,
                    },
                );
                let mut partial = Vec::new();
                while st.queue_len() > 0 {
                    partial.push(st.solution.indirect.flux());
                    u = st.drain(Budget {
                        photons: 700,
                        time: None,
                    });
                }
                let recs: Vec<_> = (0..st.layout.photons())
                    .map(|i| st.record(i).clone())
                    .collect();
                (partial, st.solution.clone(), recs, u.photons_traced)
            })
    };
    let (p1, s1, r1, _) = run(1);
    let (p2, s2, r2, _) = run(2);
    assert!(p1.len() > 2, "{} steps", p1.len());
    assert_eq!(p1, p2);
    assert_eq!(r1, r2);
    for (x, y) in [
        (&s1.direct, &s2.direct),
        (&s1.indirect, &s2.indirect),
        (&s1.caustic, &s2.caustic),
    ] {
        assert_eq!(x.flux(), y.flux());
        assert_eq!(x.count(), y.count());
        assert_eq!(x.flux_sq(), y.flux_sq());
    }
}

/// Bias while the queue drains (per block of elements): after re-shooting the first
/// half of the flagged photons in priority order, the solution is a mix of old and new
/// paths, but every photon is in it exactly once — the per-side counts of direct,
/// indirect and caustic deposits equal the counts of the stored records (no photon is
/// lost or counted twice by the signed bookkeeping), and after the rest is re-shot each
/// 4×4×4 block of the room (sum over its element sides) holds the fresh pool's displayed
/// flux within 4 standard errors of the fresh block sum (√Σφ²) plus 10⁻⁹ of the total
/// (rounding): here it is exactly the fresh pool, so the band is not used up.
#[test]
fn a_half_drained_pool_counts_every_photon_once_and_ends_unbiased_per_block() {
    let (a, b) = two_frames(demo(), 0, 48);
    let mesh = chronolux_render::kernels::elements::element_map::ElementMesh::build(&a, 30.0);
    let mut st = SptState::new_on_mesh(a.clone(), settings(60_000), mesh.clone());
    st.invalidate(b.clone(), &FrameDelta::between(&a, &b));
    let q = st.queued_photons();
    assert!(q > 100, "{q} queued photons");
    st.drain(Budget {
        photons: q / 2,
        time: None,
    });
    assert_eq!(st.queued_photons(), q - q / 2);
    let mut counts = [
        vec![0i64; st.solution.direct.len()],
        vec![0i64; st.solution.direct.len()],
        vec![0i64; st.solution.direct.len()],
    ];
    for i in 0..st.layout.photons() {
        for v in &st.record(i).vertices {
            if v.slot != u32::MAX {
                counts[v.kind as usize][v.slot as usize] += 1;
            }
        }
    }
    assert_eq!(counts[0], st.solution.direct.count());
    assert_eq!(counts[1], st.solution.indirect.count());
    assert_eq!(counts[2], st.solution.caustic.count());
    st.drain(Budget::ALL);
    let fresh = SptState::new_on_mesh(b.clone(), settings(60_000), mesh);
    let fe = FrameElements::new(&b, &st.mesh);
    let block = |k: usize| {
        let c = fe.centroid[k / 2];
        let cell =
            |x: f32, lo: f32, hi: f32| (((x - lo) / (hi - lo) * 4.0).floor() as i32).clamp(0, 3);
        (cell(c.x, -1.0, 1.0) * 16 + cell(c.y, 0.0, 2.0) * 4 + cell(c.z, -1.0, 1.0)) as usize
    };
    let (f_s, _, _) = displayed(&st);
    let (f_f, sq_f, _) = displayed(&fresh);
    let total: f64 = f_f.iter().map(|x| x.max(0.0)).sum();
    let (mut bs, mut bf, mut bq) = (vec![0.0; 64], vec![0.0; 64], vec![0.0; 64]);
    for k in 0..f_f.len() {
        let j = block(k);
        bs[j] += f_s[k];
        bf[j] += f_f[k];
        bq[j] += sq_f[k];
    }
    for j in 0..64 {
        assert!(
            (bs[j] - bf[j]).abs() <= 4.0 * bq[j].sqrt() + 1e-9 * total,
            "block {j}: {} vs fresh {} (σ {})",
            bs[j],
            bf[j],
            bq[j].sqrt()
        );
    }
}

/// The eye pass: a frame of the demo is finite, non-black, and its mean lies within 10 %
/// of `dept-spatial`'s on the same frame (same elements, filter and camera samples;
/// differences: glossy reflections traced instead of read from the elements, other
/// photons. 10 % is loose on purpose: it catches a lost or doubled term — indirect light
/// is ~30 % of the image — not the methods' small differences).
#[test]
fn the_eye_pass_agrees_with_dept_spatial_on_the_mean() {
    use chronolux_render::framework::integrator::Integrator;
    use chronolux_render::kernels::elements::{Dept, DeptSettings};
    let mut src = crate::source(demo(), 48, 48, 24.0, vec![0]);
    let scene = src.frame(0);
    let mut spt = Spt::new(SptSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 16,
            ..settings(100_000).common
        },
        ..settings(100_000)
    });
    let a = spt.render_frame(&mut src, 0, &|_| {});
    let b = Dept::new(DeptSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 16,
            ..DeptSettings::spatial().common
        },
        photons: 100_000,
        elements: 30.0,
        ..DeptSettings::spatial()
    })
    .render(&scene, 0, &|_| {});
    let mean = |px: &[chronolux_core::color::Rgb]| {
        px.iter().map(|p| luminance(*p) as f64).sum::<f64>() / px.len() as f64
    };
    let (ma, mb) = (mean(&a.pixels), mean(&b.pixels));
    eprintln!("mean luminance: spt {ma}, dept-spatial {mb}");
    assert!(ma > 0.0 && (ma - mb).abs() <= 0.1 * mb);
}

/// The culled path scan (`scan_bounds`: path summaries first, then each segment's padded
/// box before the slab test) flags exactly the photons the full scan flags, and the
/// incremental screen coverage equals a full recomputation, on several changes of the
/// demo: the block jump (frames 0 → 48), a small step (0 → 1) and back (48 → 0), each on
/// a freshly shot pool, and a second change (24 → 48) after a first (0 → 24) was drained
/// (re-shot records and summaries scanned). Exact equality: the same tests on the same
/// stored data.
#[test]
fn the_culled_scan_flags_exactly_what_the_full_scan_flags() {
    use chronolux_render::techniques::spt::pool::{COVERAGE_GRID, screen_coverage};
    for frames in [vec![0, 48], vec![0, 1], vec![48, 0], vec![0, 24, 48]] {
        let scenes: Vec<Arc<FrameScene>> = {
            let mut src = crate::source(demo(), 16, 16, 24.0, frames.clone());
            frames.iter().map(|&f| src.frame(f)).collect()
        };
        let mesh =
            chronolux_render::kernels::elements::element_map::ElementMesh::build(&scenes[0], 30.0);
        let flags = |cull: bool| {
            let s = SptSettings {
                scan_bounds: cull,
                restart_fraction: 1.0,
                ..settings(20_000)
            };
            let mut st = SptState::new_on_mesh(scenes[0].clone(), s, mesh.clone());
            let mut u = Default::default();
            for w in scenes.windows(2) {
                if st.queue_len() > 0 {
                    st.drain(Budget::ALL);
                }
                u = st.invalidate(w[1].clone(), &FrameDelta::between(&w[0], &w[1]));
            }
            let f: Vec<u64> = (0..st.layout.photons())
                .filter(|&i| st.flagged(i))
                .collect();
            (f, u, st.coverage().to_vec())
        };
        let (full, uf, _) = flags(false);
        let (culled, uc, cov) = flags(true);
        eprintln!(
            "frames {frames:?}: {} flagged; candidates {} culled vs {} full",
            full.len(),
            uc.scan_candidates,
            uf.scan_candidates
        );
        assert!(!full.is_empty());
        assert_eq!(full, culled);
        assert!(uc.scan_candidates < uf.scan_candidates);
        let last = scenes.last().unwrap();
        assert_eq!(cov, screen_coverage(last, &mesh, COVERAGE_GRID));
    }
}

/// The summaries' quantized points never rule out a crossing the exact test accepts: for
/// 10 000 random paths (one to eight vertices, every fifth with an escape ray) and 1 000
/// random boxes inside the grid, with a third of the coordinates snapped onto the same
/// few values (so segments run along box faces, where rounding would show), every path
/// that `crosses` a box passes [`QuantGrid::may_cross`] on that box grown by
/// [`QuantGrid::grow`], and the test rules out most of the paths that do not cross (it is
/// not vacuous). Exact: a superset property, no tolerance.
#[test]
fn the_quantized_summary_keeps_every_crossing_of_the_exact_test() {
    use chronolux_core::geometry::Bounds3;
    use chronolux_core::math::Vec3;
    use chronolux_core::sampling::hash_words;
    use chronolux_render::techniques::spt::pool::{
        PathSummary, PhotonRecord, QuantGrid, RecVertex,
    };
    let mut n = 0u64;
    let mut next = move || {
        n += 1;
        (hash_words(&[n, 0x5eed]) >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut point = |lo: f32, hi: f32, snap: bool| {
        let mut c = || {
            let x = lo + (hi - lo) * next();
            if snap { (x * 4.0).round() / 4.0 } else { x }
        };
        Vec3::new(c(), c(), c())
    };
    let vertex = |p: Vec3| RecVertex {
        p,
        instance: 0,
        material: 0,
        tri: chronolux_core::accel::TriRef {
            geometry: 0,
            triangle: 0,
        },
        slot: 0,
        kind: 1,
        power: chronolux_core::color::Rgb::splat(1.0),
    };
    let recs: Vec<PhotonRecord> = (0..10_000u64)
        .map(|k| {
            let snap = k % 3 == 0;
            PhotonRecord {
                light: 0,
                origin: point(-1.0, 1.0, snap),
                vertices: (0..1 + (k % 8) as usize)
                    .map(|_| vertex(point(-1.0, 1.0, snap)))
                    .collect(),
                escape: if k % 5 == 0 {
                    point(-1.0, 1.0, false)
                } else {
                    Vec3::ZERO
                },
            }
        })
        .collect();
    let grid = QuantGrid::over(&recs);
    let sums: Vec<PathSummary> = recs
        .iter()
        .map(|r| PathSummary::of(r, Some(&grid)))
        .collect();
    assert!(sums.iter().all(|s| s.quantized));
    let (mut crossing, mut ruled_out, mut missing) = (0u64, 0u64, 0u64);
    for k in 0..1_000u64 {
        let (a, b) = (point(-0.9, 0.9, k % 3 == 0), point(-0.9, 0.9, k % 3 == 0));
        let bx = Bounds3 {
            min: a.min(b),
            max: a.max(b),
        };
        let grown = [grid.grow(&bx)];
        assert!(grid.contains(&grown[0]));
        for (r, s) in recs.iter().zip(&sums) {
            let may = grid.may_cross(s, &grown);
            if r.crosses(&[bx]) {
                crossing += 1;
                assert!(may, "{r:?} crosses {bx:?} but its quantized points do not");
            } else {
                missing += 1;
                ruled_out += !may as u64;
            }
        }
    }
    assert!(crossing > 10_000, "{crossing} crossings");
    assert!(
        ruled_out as f64 > 0.9 * missing as f64,
        "{ruled_out} of {missing} ruled out"
    );
}
