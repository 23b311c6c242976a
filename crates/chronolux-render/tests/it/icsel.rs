//! `ic-selective` (issue 13): the per-direction store, selection by age, no stale hits,
//! per-stratum agreement with a frame-by-frame gather, no accumulation of error.

use crate::pmic::cornell_moving;
use crate::{bits, block_errors, blocks};
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::math::Frame;
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::desc::SceneDesc;
use chronolux_render::framework::integrator::RenderedFrame;
use chronolux_render::framework::sequence::SequenceRenderer;
use chronolux_render::kernels::gather::precomputed::GroupMaps;
use chronolux_render::kernels::gather::{PmIcSettings, frame_maps, gather_ray_hit, photon_base};
use chronolux_render::techniques::ic_selective::store::{
    MemoryStore, PagedStore, StrataStore, Stratum,
};
use chronolux_render::techniques::ic_selective::{
    IcSelective, IcSelectiveSettings, cast_stratum, cast_stratum_terms, select_by_age, stratum_dir,
};
use chronolux_render::techniques::pm_ic::PmIc;

/// Small settings: few photons, one camera sample, a 6 × 18 gather.
fn small(photons: u64, m: u32, n: u32) -> PmIcSettings {
    PmIcSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1,
            ..PmIcSettings::default().common
        },
        photons,
        gather_m: m,
        gather_n: n,
        ..Default::default()
    }
}

fn selective(pmic: PmIcSettings, paged: bool) -> IcSelective {
    IcSelective::new(
        IcSelectiveSettings {
            pmic,
            paged,
            // Tiny pages (one record each) and two of them in memory: every frame evicts.
            page_kb: 1,
            cache_pages: 2,
            ..Default::default()
        },
        "ic-selective",
    )
    .unwrap()
}

/// The cube of `cornell_moving` going back and forth: x from −0.3 to 0.1 and back every
/// 2 s (48 frames at 24 fps), for 5 s.
fn back_and_forth() -> SceneDesc {
    let mut d = cornell_moving();
    let ch = &mut d.animations[0].channels[0];
    ch.times = vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    ch.values = [-0.3f32, 0.1, -0.3, 0.1, -0.3, 0.1]
        .iter()
        .flat_map(|&x| [x, 0.2, 0.2])
        .collect();
    d
}

/// `cornell_moving` with a warm point light (1.5 cd, as `scripts/make_moving_light_scene.py`'s)
/// under the ceiling moving 1.2 along x in the first second, while the ceiling lamp stays;
/// with `cube_moves` the cube slides as in `cornell_moving`, else it stays at its start.
fn moving_light(cube_moves: bool) -> SceneDesc {
    use chronolux_core::scene::desc::{Channel, ChannelTarget, Interpolation, LightKind, Trs};
    use chronolux_core::scene::stage::ROOM_HALF;
    let mut d = cornell_moving();
    if !cube_moves {
        let v = d.animations[0].channels[0].values[..3].to_vec();
        d.animations[0].channels[0].values = [v.clone(), v].concat();
    }
    let y = 2.0 * ROOM_HALF - 0.3;
    let node = d.add_light(
        "warm",
        1.5,
        LightKind::Point,
        Trs {
            translation: chronolux_core::math::Vec3::new(-0.6, y, 0.2),
            ..Default::default()
        },
    );
    d.lights.last_mut().unwrap().color = Rgb::new(1.0, 0.85, 0.6);
    d.animations[0].channels.push(Channel {
        node,
        target: ChannelTarget::Translation,
        interpolation: Interpolation::Linear,
        times: vec![0.0, 1.0],
        values: vec![-0.6, y, 0.2, 0.6, y, 0.2],
        components: 3,
    });
    d
}

fn strata_bits(v: &[Stratum]) -> Vec<(Vec<u32>, u32, u32, u32)> {
    v.iter()
        .map(|s| {
            let vecs = [s.l, s.x, s.ns, s.w].into_iter().chain(s.terms);
            (
                vecs.flat_map(|c| c.to_array().map(f32::to_bits)).collect(),
                s.dist.to_bits(),
                s.hit,
                s.cast,
            )
        })
        .collect()
}

/// The paged store round-trips every block bit for bit through evictions (pages of two
/// records, two pages in memory, 20 records written), never-written slots read empty,
/// and it never holds more than its bound in memory.
#[test]
fn paged_store_round_trips_through_eviction() {
    let spr = 5;
    let block = |slot: u32| -> Vec<Stratum> {
        (0..spr)
            .map(|i| Stratum {
                l: Rgb::new(slot as f32, i as f32 * 0.5, -1.0e-30),
                dist: if i % 3 == 0 { f32::INFINITY } else { i as f32 },
                hit: if i % 3 == 0 {
                    Stratum::NO_HIT
                } else {
                    slot ^ i as u32
                },
                cast: slot + 7,
                x: Rgb::new(0.25, slot as f32, -(i as f32)),
                ns: Rgb::new(0.0, -1.0, i as f32 * 1e-3),
                w: Rgb::new(1.0 / (1 + slot) as f32, 2.0, 3.0),
                terms: std::array::from_fn(|g| Rgb::splat((slot * 10 + g as u32) as f32 + 0.125)),
            })
            .collect()
    };
    let mut p = PagedStore::new(spr, 2 * spr * Stratum::BYTES, 2, None).unwrap();
    let mut m = MemoryStore::new(spr);
    for slot in (0..20).rev() {
        p.write(slot, &block(slot));
        m.write(slot, &block(slot));
    }
    let (mut a, mut b) = (vec![Stratum::EMPTY; spr], vec![Stratum::EMPTY; spr]);
    for slot in [3, 17, 0, 19, 8, 25] {
        p.read(slot, &mut a);
        m.read(slot, &mut b);
        assert_eq!(strata_bits(&a), strata_bits(&b), "slot {slot}");
    }
    p.read(25, &mut a);
    assert_eq!(strata_bits(&a), strata_bits(&vec![Stratum::EMPTY; spr]));
    let st = p.stats();
    assert!(st.page_writes > 0 && st.page_reads > 0, "{st:?}");
    assert!(
        st.peak_resident_bytes <= 2 * p.page_bytes() as u64,
        "{st:?}"
    );
}

/// Selection by age: `n` distinct strata; inclusion frequencies over many draws match
/// `min(1, c·w)`. With 20 000 draws a frequency's standard error is ≤ √(0.25/20000) =
/// 0.0035; the bound 0.02 is over 5 of them.
#[test]
fn selection_by_age_has_the_stated_inclusion_probabilities() {
    let w: Vec<f64> = vec![0.0, 1.0, 1.0, 2.0, 3.0, 5.0, 8.0, 40.0, 1.0, 2.0];
    let n = 4;
    // Expected: 40 is certain (4·40 ≥ 63); then 3 among the rest (total 23): 3·8 ≥ 23,
    // so 8 is certain too; then 2 among total 15: c = 2/15.
    let mut expect = vec![0.0f64; w.len()];
    expect[7] = 1.0;
    expect[6] = 1.0;
    for k in [1, 2, 3, 4, 5, 8, 9] {
        expect[k] = w[k] * 2.0 / 15.0;
    }
    let draws = 20_000;
    let mut freq = vec![0.0f64; w.len()];
    let mut rng = Pcg32::new(7, 9);
    for _ in 0..draws {
        let s = select_by_age(&w, n, &mut rng);
        assert_eq!(s.len(), n);
        assert!(s.windows(2).all(|p| p[0] < p[1]), "distinct, sorted: {s:?}");
        for k in s {
            freq[k] += 1.0 / draws as f64;
        }
    }
    for (k, (f, e)) in freq.iter().zip(&expect).enumerate() {
        assert!((f - e).abs() < 0.02, "stratum {k}: {f} vs {e}");
    }
}

/// Paged and in-memory stores give bit-identical images (every frame of a moving-cube
/// sequence, with a page cache so small that it evicts all the time).
#[test]
fn paged_and_memory_stores_give_identical_images() {
    let frames = [0u32, 1, 2, 3];
    let run = |paged: bool| {
        let mut r = selective(small(5_000, 6, 18), paged);
        let mut src = crate::source(cornell_moving(), 16, 16, 24.0, frames.to_vec());
        let imgs: Vec<RenderedFrame> = frames
            .iter()
            .map(|&f| r.render_frame(&mut src, f, &|_| {}))
            .collect();
        (imgs, r.store_stats())
    };
    let ((a, sa), (b, sb)) = (run(true), run(false));
    for (f, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(
            bits(&x.pixels) == bits(&y.pixels),
            "frame {f}: paged and memory stores differ"
        );
    }
    assert!(sa.page_writes > 0 && sa.page_reads > 0, "{sa:?}");
    assert_eq!(sb.page_reads, 0);
    assert_eq!(sa.record_writes, sb.record_writes);
}

/// `cornell_moving`'s cube sliding and turning about y by 45° per second (as
/// cornell-moving's cube turns): its world box is then larger than the cube.
fn turning_cube() -> SceneDesc {
    let mut d = cornell_moving();
    let node = d.animations[0].channels[0].node;
    let h = 22.5f32.to_radians();
    d.animations[0]
        .channels
        .push(chronolux_core::scene::desc::Channel {
            node,
            target: chronolux_core::scene::desc::ChannelTarget::Rotation,
            interpolation: chronolux_core::scene::desc::Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![0.0, 0.0, 0.0, 1.0, 0.0, h.sin(), 0.0, h.cos()],
            components: 4,
        });
    d
}

/// No stale geometry: after every frame of the sliding, turning cube, (a) every stratum whose hit is
/// the cube was cast in that frame (the cube moves every frame), and (b) every stratum
/// cast earlier, re-traced in this frame along its own direction, hits the same instance
/// at the same distance, bit for bit (so neither the cube moving into nor out of a
/// direction is missed). Also the priority refresh is exercised, and so is the exact
/// test behind the box test (some segments met the cube's box but not the cube, and were
/// left to the refresh by age: (b) checks they were right to be).
#[test]
fn strata_reached_by_a_moving_object_are_recast_in_that_frame() {
    let frames: Vec<u32> = (0..6).collect();
    let s = small(5_000, 6, 18);
    let mut r = selective(s.clone(), false);
    let mut src = crate::source(turning_cube(), 16, 16, 24.0, frames.clone());
    let (s0, s1) = (src.frame(0), src.frame(1));
    let cube = FrameDelta::between(&s0, &s1)
        .dynamic_instances()
        .iter()
        .position(|c| *c)
        .expect("the cube moves") as u32;
    let mut priority = 0;
    let mut box_only = 0;
    let mut checked = 0;
    for &f in &frames {
        let out = r.render_frame(&mut src, f, &|_| {});
        priority += out.report["strata_priority"].as_u64().unwrap();
        box_only += out.report["strata_box_only"].as_u64().unwrap();
        let scene = src.frame(f);
        let recs = r.records().to_vec();
        for (i, rec) in recs.iter().enumerate() {
            let strata = r.strata(i);
            if f > 0 && rec.instance == cube {
                assert!(
                    strata.iter().all(|t| t.cast == f),
                    "frame {f}: record {i} on the cube was kept, not rebuilt"
                );
            }
            let fr = Frame::from_normal(rec.n);
            for (k, t) in strata.iter().enumerate() {
                if f > 0 && t.hit == cube {
                    assert_eq!(t.cast, f, "frame {f}: record {i} stratum {k} saw the cube");
                }
                if t.cast < f {
                    let (d, _) = stratum_dir(&s, &fr, rec.id, k, t.cast);
                    let mut rng = Pcg32::new(0, 0);
                    let now = gather_ray_hit::<
                        chronolux_render::kernels::gather::photon_map::PhotonMap,
                    >(&scene, &s, &[], rec.p, rec.n, d, &mut rng)
                    .map(|(_, dist, inst)| (dist.max(1e-6).to_bits(), inst))
                    .unwrap_or((f32::INFINITY.to_bits(), Stratum::NO_HIT));
                    assert_eq!(
                        now,
                        (t.dist.to_bits(), t.hit),
                        "frame {f}: record {i} stratum {k} (cast {}) is stale",
                        t.cast
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(priority > 0, "no priority refresh happened");
    assert!(box_only > 0, "the exact test never spared a stratum");
    assert!(checked > 1000, "only {checked} kept strata checked");
}

/// χ² bound at p = 0.001 for 1..=12 degrees of freedom.
const CHI2_999: [f64; 12] = [
    10.83, 13.82, 16.27, 18.47, 20.52, 22.46, 24.32, 26.12, 27.88, 29.59, 31.26, 32.91,
];

/// The paper's check: after 40 frames of the moving-cube animation, the per-stratum
/// radiance of a record agrees statistically with a frame-by-frame gather at the same
/// place in the same frame (frame 40's photon map, independent jitter). Per θ-ring `j`,
/// the paired differences `d_k` (luminance, selective − fresh) over the ring's N strata
/// give `z_j = mean/(sd/√N)`; without staleness each is ≈ N(0, 1) (a t with N − 1 = 23
/// degrees of freedom), so `Σ z_j²` ≈ χ² with one degree per ring; the bound is its
/// 0.1 % quantile (the t's heavier tails make the test ≈ 0.3 % rather than 0.1 % per
/// record). Checked on the three longest-lived records.
#[test]
fn record_strata_agree_with_a_fresh_gather_after_40_frames() {
    let (m, n) = (8u32, 24u32);
    let s = small(20_000, m, n);
    let frames: Vec<u32> = (0..=40).collect();
    let mut r = selective(s.clone(), true);
    let mut src = crate::source(cornell_moving(), 16, 16, 24.0, frames.clone());
    let mut first_ids = 0;
    for &f in &frames {
        let out = r.render_frame(&mut src, f, &|_| {});
        if f == 0 {
            first_ids = out.report["records_added"].as_u64().unwrap();
        }
    }
    let scene = src.frame(40);
    let maps = frame_maps(&scene, &s, photon_base(&s, 40));
    let st = &r.settings;
    assert!(st.light_terms, "the default reads the light groups' maps");
    let groups = GroupMaps::build(
        &scene,
        &s,
        photon_base(&s, 40),
        st.precompute_stride,
        st.precompute_k,
    );
    let recs = r.records().to_vec();
    let mut order: Vec<usize> = (0..recs.len())
        .filter(|&i| recs[i].id < first_ids)
        .collect();
    order.sort_by_key(|&i| recs[i].id);
    assert!(
        order.len() >= 3,
        "records of frame 0 alive at frame 40: {}",
        order.len()
    );
    for &i in &order[..3] {
        let rec = recs[i];
        let strata = r.strata(i);
        let ages: Vec<u32> = strata.iter().map(|t| 40 - t.cast).collect();
        assert!(
            ages.iter().any(|&a| a > 0) && ages.iter().all(|&a| a < 40),
            "record {i}: every stratum should have been refreshed since frame 0, not all now"
        );
        let fresh: Vec<Stratum> = (0..strata.len())
            .map(|k| {
                cast_stratum_terms(&scene, &s, &groups, rec.p, rec.n, u64::MAX - rec.id, k, 40)
            })
            .collect();
        // The k-NN estimate of the global map along the same directions: what the
        // precomputed lookup replaces (printed, not tested: its blur differs).
        let knn: f64 = (0..strata.len())
            .map(|k| {
                let t = cast_stratum(
                    &scene,
                    &s,
                    &maps.global,
                    rec.p,
                    rec.n,
                    u64::MAX - rec.id,
                    k,
                    40,
                );
                luminance(t.l) as f64
            })
            .sum();
        let mut chi2 = 0.0f64;
        let mut dof = 0;
        for j in 0..m as usize {
            let d: Vec<f64> = (0..n as usize)
                .map(|k| {
                    let i = j * n as usize + k;
                    luminance(strata[i].l) as f64 - luminance(fresh[i].l) as f64
                })
                .collect();
            let mean = d.iter().sum::<f64>() / n as f64;
            let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n as f64 - 1.0);
            if var > 0.0 {
                chi2 += mean * mean / (var / n as f64);
                dof += 1;
            }
        }
        let mean_age = ages.iter().sum::<u32>() as f64 / ages.len() as f64;
        let pre: f64 = fresh.iter().map(|t| luminance(t.l) as f64).sum();
        eprintln!(
            "record {i} (id {}, at {}): chi2 {chi2:.2} with {dof} dof, mean age {mean_age:.1}; \
             fresh sum {pre:.4} precomputed, {knn:.4} k-NN",
            rec.id, rec.p
        );
        assert!(dof > 0, "record {i}: no radiance at all");
        assert!(
            chi2 < CHI2_999[dof - 1],
            "record {i}: χ² {chi2:.2} over the 0.1 % bound {} ({dof} dof)",
            CHI2_999[dof - 1]
        );
    }
}

/// Mean absolute difference of two images over the mean of the second.
fn rel_diff(a: &RenderedFrame, b: &RenderedFrame) -> f64 {
    let num: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| ((*x - *y).abs().element_sum()) as f64)
        .sum();
    let den: f64 = b.pixels.iter().map(|y| y.element_sum() as f64).sum();
    num / den
}

/// No accumulation: over 100 frames of the cube going back and forth (period 48 frames),
/// the difference between `ic-selective` and `pm-ic` frame by frame (same photons, same
/// camera samples: only the indirect light differs) is no larger one period later. The
/// windows (frames 5, 10, …, 45 and the same phases 48 frames later) see the same scene
/// configurations; with independent gather noise their means (nine frames each) differ
/// by sampling only: measured 2026-12-02 (printed), the per-frame differences have a
/// coefficient of variation of 0.43, so a nine-frame mean one of ≈ 0.14 and the ratio of
/// two such means a standard error of ≈ 0.2 (measured ratio 1.07); the bound 1.5 is 2.5
/// of those. An error that grew with the age of the cache (linearly from frame 0) would
/// show a ratio of ≈ 2.5 (mean frame 73 against 25).
#[test]
fn error_against_pm_ic_does_not_grow_over_100_frames() {
    let s = small(5_000, 6, 18);
    let frames: Vec<u32> = (0..100).collect();
    let mut sel = selective(s.clone(), true);
    let mut base = PmIc {
        settings: s.clone(),
        name: "pm-ic",
    };
    let mut src = crate::source(back_and_forth(), 12, 12, 24.0, frames.clone());
    let early: Vec<u32> = (1..=9).map(|k| 5 * k).collect();
    let late: Vec<u32> = early.iter().map(|f| f + 48).collect();
    let mut diff = std::collections::HashMap::new();
    for &f in &frames {
        let a = sel.render_frame(&mut src, f, &|_| {});
        if early.contains(&f) || late.contains(&f) {
            let b = base.render_frame(&mut src, f, &|_| {});
            diff.insert(f, rel_diff(&a, &b));
        }
    }
    let mean = |v: &[u32]| v.iter().map(|f| diff[f]).sum::<f64>() / v.len() as f64;
    let (e, l) = (mean(&early), mean(&late));
    let mut all: Vec<_> = diff.iter().map(|(f, d)| (*f, *d)).collect();
    all.sort_by_key(|x| x.0);
    eprintln!(
        "early {e:.4}, late {l:.4}, ratio {:.3}; per frame {all:?}",
        l / e
    );
    assert!(l <= 1.5 * e, "error grew: early {e:.4}, late {l:.4}");
}

fn cube_settings() -> PmIcSettings {
    PmIcSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 8,
            ..PmIcSettings::default().common
        },
        photons: 60_000,
        ..Default::default()
    }
}

/// Renders `desc`'s frames `0..=12` with `ic-selective` (32 × 32, `cube_settings`,
/// `light_terms` as given) and frames 4, 8, 12 with `pm-ic`; per frame the largest
/// relative 8 × 8 block difference, the image mean's, and `ic-selective`'s reports.
fn against_pm_ic(desc: SceneDesc, light_terms: bool) -> Vec<(f64, f64, RenderedFrame)> {
    let keep = [4u32, 8, 12];
    let mut sel = IcSelective::new(
        IcSelectiveSettings {
            pmic: cube_settings(),
            paged: false,
            light_terms,
            ..Default::default()
        },
        "ic-selective",
    )
    .unwrap();
    let mut base = PmIc {
        settings: cube_settings(),
        name: "pm-ic",
    };
    let frames: Vec<u32> = (0..=12).collect();
    let mut src = crate::source(desc.clone(), 32, 32, 24.0, frames.clone());
    let a: Vec<RenderedFrame> = frames
        .iter()
        .filter_map(|&f| {
            let img = sel.render_frame(&mut src, f, &|_| {});
            keep.contains(&f).then_some(img)
        })
        .collect();
    let mut src = crate::source(desc, 32, 32, 24.0, keep.to_vec());
    let b: Vec<RenderedFrame> = keep
        .iter()
        .map(|&f| base.render_frame(&mut src, f, &|_| {}))
        .collect();
    a.into_iter()
        .zip(&b)
        .zip(keep)
        .map(|((x, y), f)| {
            let (max, mean) = block_errors(&x.pixels, &blocks(&y.pixels, 32, 8), 32);
            eprintln!(
                "frame {f}: block {max:.4}, mean {mean:.4}, report {:?}",
                x.report
            );
            (max, mean, x)
        })
        .collect()
}

/// Bias against the frame-by-frame baseline: after 4, 8 and 12 frames of the moving cube,
/// each 8 × 8 block of `ic-selective` agrees with `pm-ic`'s image of the same frame (same
/// photons, same camera samples: only the cache and the gather hits' radiance differ).
/// Where the tolerance comes from: both carry the interpolation bound (≤ 1.5 a² of the
/// indirect irradiance, ≤ 3 % of a block, `pmic.rs`'s Cornell test) and the frozen gather
/// noise (≤ 2.5 % of a block) independently, so ≤ 11 % per block between them (the
/// tolerance of the `ic-static-dynamic` test on the same scene); the staleness of strata
/// not re-cast (radiance up to ≈ 1/refresh = 10 frames old where the change did not cross
/// their ray) is inside that margin here (measured 2026-12-07 with the global map: blocks
/// within 1.4–2.1 %, means within 0.2–0.3 %), and the records kept from the eye pass add
/// nothing new (Ward's interpolation, as every other point). The precomputed irradiance
/// (`light_terms`, the default) changes only the map's blur at the gather hits, whose
/// share `pmic.rs` bounds by the interpolation term (≤ 2.5 % of a block for `pm-ic`); the
/// lookup at most doubles the kernel's support ([`GroupMaps`]' doc), so at most fourfold
/// a second-order blur: up to 7.5 % more per block, 18 % in all. On the image mean the
/// per-record noise averages out and a blur moves light rather than adding it (only the
/// corners' boundary bias remains): 3 %. The eye pass's kept gathers are exercised (some
/// frame adds records from it).
#[test]
fn ic_selective_agrees_with_pm_ic_per_block_on_a_moving_cube() {
    let out = against_pm_ic(cornell_moving(), true);
    for (f, (max, mean, _)) in out.iter().enumerate() {
        assert!(
            *max < 0.18 && *mean < 0.03,
            "frame {}: block {max}, mean {mean}",
            4 * (f + 1)
        );
    }
    let from_eye: u64 = out
        .iter()
        .map(|x| x.2.report["records_from_eye"].as_u64().unwrap())
        .sum();
    assert!(
        from_eye > 0 || out[0].2.report["unstored_gathers"].as_u64().unwrap() == 0,
        "no record was kept from the eye pass"
    );
}

/// The same with the moving point light as well (the issue-41 scene): every frame
/// re-reads the point light's terms of the strata it does not re-cast instead of
/// re-casting every stratum; the tolerance is the moving cube's (above) plus the
/// staleness of the other group's terms, which is the cube's kind (kept where the change
/// did not cross the ray), not a new one: the point light's terms are never stale. And the
/// 2026-12-07 path (`light_terms = false`: every stratum re-cast in every frame here) within
/// the cube test's original 11 %. Measured 2026-12-08: blocks within 1.2–2.2 %, means
/// within 0.03–0.22 % (the cube alone: 1.3–2.2 %, 0.11–0.20 %; the global-map path 1.1–1.6 %,
/// 0.02–0.24 %).
#[test]
fn ic_selective_agrees_with_pm_ic_per_block_under_a_moving_light() {
    let out = against_pm_ic(moving_light(true), true);
    for (f, (max, mean, x)) in out.iter().enumerate() {
        let frame = 4 * (f + 1);
        assert!(
            *max < 0.18 && *mean < 0.03,
            "frame {frame}: block {max}, mean {mean}"
        );
        assert_eq!(
            x.report["recast_all"], "",
            "frame {frame} re-cast every stratum"
        );
        assert!(
            x.report["strata_reread"].as_u64().unwrap() > 0,
            "frame {frame} re-read no term"
        );
    }
    for (f, (max, mean, x)) in against_pm_ic(moving_light(true), false).iter().enumerate() {
        let frame = 4 * (f + 1);
        assert!(
            *max < 0.11 && *mean < 0.03,
            "frame {frame} (global map): block {max}, mean {mean}"
        );
        assert_eq!(x.report["recast_all"], "lights");
    }
}

/// `pm-ic` with the precomputed estimator (`precompute_stride = 4`, the maps `ic-selective`
/// reads) against `pm-ic`'s k-NN estimate, frames 0 and 6 of the moving-light scene at
/// 32 × 32: the same photons, camera samples and gather directions and chains (the same
/// `gather_at`, generic over what it reads), so only the radiance read at the gather hits differs. Where the
/// tolerance comes from: the same bound as `ic-selective` against `pm-ic` above (each
/// image's interpolation and gather noise, ≤ 11 % per block between two caches, plus up to
/// 7.5 % for the precomputed lookup's wider support), 3 % on the image mean. Measured
/// 2026-12-08 (printed): blocks within 0.96–1.21 %, means within 0.27–0.30 %. And the reports
/// say which estimator ran.
#[test]
fn pm_ic_with_precomputed_irradiance_agrees_with_its_knn_estimate_per_block() {
    let frames = [0u32, 6];
    let run = |stride: u32| {
        let mut pm = PmIc {
            settings: PmIcSettings {
                precompute_stride: stride,
                ..cube_settings()
            },
            name: "pm-ic",
        };
        let mut src = crate::source(moving_light(true), 32, 32, 24.0, frames.to_vec());
        frames
            .iter()
            .map(|&f| pm.render_frame(&mut src, f, &|_| {}))
            .collect::<Vec<_>>()
    };
    let (pre, knn) = (run(4), run(0));
    for ((x, y), f) in pre.iter().zip(&knn).zip(frames) {
        let (max, mean) = block_errors(&x.pixels, &blocks(&y.pixels, 32, 8), 32);
        eprintln!("frame {f}: block {max:.4}, mean {mean:.4}");
        assert!(
            max < 0.18 && mean < 0.03,
            "frame {f}: block {max}, mean {mean}"
        );
        assert!(x.report["precomputed_points"].as_u64().unwrap() > 0);
        assert_eq!(x.report["light_groups"], 2);
        assert!(y.report.get("precomputed_points").is_none());
    }
}

/// Bit-identical images and reports (timings aside) for 1 and 3 threads over four frames
/// of the moving cube under the moving point light (light groups' maps with precomputed
/// irradiance, terms re-read), with the eye pass's gathers kept as records (their order in the
/// parallel eye pass must not matter) and the paged store evicting; and the same again
/// on 2 threads with no buffer for the eye pass's strata (`eye_buffer_mb = 0`: every
/// kept gather is cast again after the pass, which must give the same strata).
#[test]
fn ic_selective_is_deterministic_across_thread_counts() {
    let render = |threads: usize, buffer_mb: u32| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut r = selective(small(5_000, 6, 18), true);
                r.settings.eye_buffer_mb = buffer_mb;
                let frames = [0u32, 1, 2, 3];
                let mut src = crate::source(moving_light(true), 24, 24, 24.0, frames.to_vec());
                frames
                    .iter()
                    .map(|&f| r.render_frame(&mut src, f, &|_| {}))
                    .collect::<Vec<_>>()
            })
    };
    let (a, b, c) = (render(1, 64), render(3, 64), render(2, 0));
    let untimed = |r: &RenderedFrame| {
        r.report
            .iter()
            .filter(|(k, _)| !k.starts_with("seconds"))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect::<Vec<_>>()
    };
    let (mut from_eye, mut reread) = (0, 0);
    for (f, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(bits(&x.pixels) == bits(&y.pixels), "frame {f} differs");
        assert_eq!(untimed(x), untimed(y), "frame {f}'s report differs");
        from_eye += x.report["records_from_eye"].as_u64().unwrap();
        reread += x.report["strata_reread"].as_u64().unwrap();
    }
    assert!(reread > 0, "no light term was re-read");
    for (f, (x, z)) in a.iter().zip(&c).enumerate() {
        assert!(
            bits(&x.pixels) == bits(&z.pixels),
            "frame {f} differs without the eye buffer"
        );
        assert_eq!(untimed(x), untimed(z), "frame {f}'s report differs");
    }
    assert!(from_eye > 0, "the eye pass's gathers were not exercised");
}

/// The eye pass's gathers kept as records serve later frames: over frames 1–5 of the
/// moving cube (still camera) far fewer gathers are made in the eye pass than with
/// `store_eye_gathers = false` (`pm-ic`'s unstored gathers, frame by frame), and the
/// first frame's are the same in both (nothing kept yet). Measured 2026-12-08 (32 × 32,
/// 8 spp, precomputed irradiance): 24, 15, 13, 8, 10 against 63, 50, 48, 49, 51 (with the
/// global map, 2026-12-07: 25, 14, 14, 9, 9 against 62, 50, 47, 50, 49); those left are
/// mostly on the moving cube, whose records are dropped every frame.
#[test]
fn kept_eye_gathers_serve_later_frames() {
    let run = |keep: bool| {
        let mut pmic = small(5_000, 6, 18);
        pmic.common.spp = 8;
        let mut r = IcSelective::new(
            IcSelectiveSettings {
                pmic,
                paged: false,
                store_eye_gathers: keep,
                ..Default::default()
            },
            "ic-selective",
        )
        .unwrap();
        let frames: Vec<u32> = (0..6).collect();
        let mut src = crate::source(cornell_moving(), 32, 32, 24.0, frames.clone());
        frames
            .iter()
            .map(|&f| {
                let img = r.render_frame(&mut src, f, &|_| {});
                img.report["unstored_gathers"].as_u64().unwrap()
            })
            .collect::<Vec<_>>()
    };
    let (kept, fresh) = (run(true), run(false));
    eprintln!("eye-pass gathers per frame: kept {kept:?}, not kept {fresh:?}");
    assert_eq!(kept[0], fresh[0]);
    let (k, f): (u64, u64) = (kept[1..].iter().sum(), fresh[1..].iter().sum());
    assert!(f > 0 && 2 * k < f, "kept {kept:?}, not kept {fresh:?}");
}

/// A frame where only a light moved re-reads only that light's terms: the cube held
/// still, the point light moving, frame 1 after frame 0. Nothing is re-cast but the
/// refresh by age (no geometry changed: no priority stratum, no record rebuilt), the
/// point light's group is the only one re-read, and the counts are those derivable from
/// the store: every stratum of a refreshed record is re-cast by age (cast in frame 1),
/// or has a hit and had exactly its point-light term re-read, or hit nothing. The
/// re-read strata keep their hit point, weight and the ceiling lamp's term bit for bit;
/// their point-light term is `w · E` read from frame 1's map at that point.
#[test]
fn a_frame_where_only_a_light_moved_rereads_only_its_terms() {
    let s = small(5_000, 6, 18);
    let spr = 6 * 18;
    let mut r = selective(s.clone(), false);
    let frames = vec![0u32, 1];
    let mut src = crate::source(moving_light(false), 16, 16, 24.0, frames.clone());
    r.render_frame(&mut src, 0, &|_| {});
    let before: std::collections::HashMap<u64, Vec<Stratum>> = (0..r.records().len())
        .map(|i| (r.records()[i].id, r.strata(i)))
        .collect();
    let out = r.render_frame(&mut src, 1, &|_| {});
    let rep = &out.report;
    eprintln!("{rep:?}");
    let u = |k: &str| rep[k].as_u64().unwrap();
    assert_eq!(rep["recast_all"], "");
    assert_eq!(
        rep["light_groups"], 2,
        "the lamp's triangles and the point light"
    );
    assert_eq!(rep["groups_reread"], serde_json::json!([false, true]));
    assert_eq!(u("strata_priority"), 0);
    assert_eq!(u("records_rebuilt"), 0);
    let terms = rep["terms_reread"].as_array().unwrap();
    assert_eq!(terms[0], 0, "the lamp's terms were re-read");
    assert_eq!(terms[1].as_u64().unwrap(), u("strata_reread"));
    let scene = src.frame(1);
    let st = &r.settings;
    let maps = GroupMaps::build(
        &scene,
        &s,
        photon_base(&s, 1),
        st.precompute_stride,
        st.precompute_k,
    );
    let (mut recast, mut reread, mut no_hit, mut refreshed, mut changed) = (0, 0, 0, 0, 0);
    for i in 0..r.records().len() {
        let Some(old) = before.get(&r.records()[i].id) else {
            continue;
        };
        refreshed += 1;
        for (t, o) in r.strata(i).iter().zip(old) {
            if t.cast == 1 {
                recast += 1;
            } else if t.hit == Stratum::NO_HIT {
                assert_eq!(t, o);
                no_hit += 1;
            } else {
                reread += 1;
                let same = |a: Rgb, b: Rgb| {
                    a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
                };
                assert!(same(t.x, o.x) && same(t.w, o.w) && t.dist == o.dist && t.cast == o.cast);
                assert!(same(t.terms[0], o.terms[0]), "the lamp's term changed");
                let hit = chronolux_render::kernels::gather::precomputed::GatherHit {
                    x: t.x,
                    ns: t.ns,
                    w: t.w,
                    dist: t.dist,
                    instance: t.hit,
                };
                assert!(same(t.terms[1], maps.term(1, &hit)));
                assert!(same(t.l, t.terms.iter().copied().sum()));
                changed += u64::from(!same(t.terms[1], o.terms[1]));
            }
        }
    }
    assert_eq!(refreshed, u("records_refreshed"));
    assert_eq!(recast, u("strata_by_age"));
    assert_eq!(reread, u("strata_reread"));
    assert_eq!(recast + reread + no_hit, refreshed * spr as u64);
    assert!(
        reread > 0 && 2 * changed > reread,
        "{changed} of {reread} point-light terms changed"
    );
}
