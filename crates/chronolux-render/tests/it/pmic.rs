//! `pm-ic` and `ic-static-dynamic`: photon-map estimates, irradiance-cache interpolation
//! and gradients against analytic cases, convergence to the path tracer, determinism.

use crate::frame0;
use crate::{bits, block_errors, blocks};
use chronolux_core::color::Rgb;
use chronolux_core::math::Vec3;
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::scene::stage::cornell_box;
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::kernels::gather::PmIcSettings;
use chronolux_render::kernels::gather::irradiance_cache::{
    Gather, IrradianceCache, Record, gather,
};
use chronolux_render::kernels::gather::photon_map::{
    Lookup, MapFilter, PhotonMap, StoredPhoton, cancel_twins,
};
use chronolux_render::kernels::path::{PathSettings, PathTracer};
use chronolux_render::techniques::pm_ic::PmIc;

fn photon(p: Vec3, flux: f32) -> StoredPhoton {
    StoredPhoton {
        p,
        wi: Vec3::Z,
        n: Vec3::Z,
        flux: Rgb::splat(flux),
    }
}

/// Photons on a regular grid of spacing h (flux 1 each) have irradiance 1/h². Both
/// kernels are normalised over the disc, so the estimate is exact up to the grid's
/// quantisation of the disc: with k = 400 photons the photons on the rim (≈ 2π·√(400/π)
/// ≈ 70, weighted ≤ 1 − 1/κ = 0.09 by the cone, 0 by Epanechnikov) and the kernel's
/// Riemann sum over 400 cells leave well under 2 %.
#[test]
fn photon_map_estimates_a_known_density() {
    let h = 0.01;
    let mut v = Vec::new();
    for i in -100..=100 {
        for j in -100..=100 {
            v.push(photon(Vec3::new(i as f32 * h, j as f32 * h, 0.0), 1.0));
        }
    }
    let map = PhotonMap::build(v);
    for filter in [MapFilter::Cone { k: 1.1 }, MapFilter::Epanechnikov] {
        let l = Lookup {
            k: 400,
            max_radius: 1.0,
            filter,
        };
        for q in [Vec3::ZERO, Vec3::new(0.123, -0.301, 0.0)] {
            let e = map.irradiance(q, Vec3::Z, &l, 0.5).x;
            let rel = (e * h * h - 1.0).abs();
            assert!(rel < 0.02, "{filter:?} at {q}: {e} vs {}", 1.0 / (h * h));
        }
        // From below, nothing (photons arrived on the +z side).
        assert_eq!(map.irradiance(Vec3::ZERO, -Vec3::Z, &l, 0.5), Rgb::ZERO);
    }
}

/// A negative photon and its positive twin cancel exactly: after [`cancel_twins`] the map
/// is the one that never held them, so every estimate is bit-identical.
#[test]
fn negative_photon_cancels_its_twin_exactly() {
    let mut rng = Pcg32::new(3, 4);
    let base: Vec<StoredPhoton> = (0..2000)
        .map(|_| {
            photon(
                Vec3::new(rng.next_f32(), rng.next_f32(), 0.0),
                0.5 + rng.next_f32(),
            )
        })
        .collect();
    let twin = photon(Vec3::new(0.5, 0.5, 0.0), 0.7);
    let mut with = base.clone();
    with.insert(700, twin);
    with.push(twin.negated());
    let kept = cancel_twins(with);
    assert_eq!(kept, base);
    let (a, b) = (PhotonMap::build(base), PhotonMap::build(kept));
    let l = Lookup {
        k: 32,
        max_radius: 1.0,
        filter: MapFilter::Cone { k: 1.1 },
    };
    for q in [Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.2, 0.9, 0.0)] {
        assert_eq!(
            a.irradiance(q, Vec3::Z, &l, 0.3)
                .to_array()
                .map(f32::to_bits),
            b.irradiance(q, Vec3::Z, &l, 0.3)
                .to_array()
                .map(f32::to_bits)
        );
    }
    // A negative photon without its twin stays (it is real: light taken away).
    let lone = cancel_twins(vec![twin.negated()]);
    assert_eq!(lone.len(), 1);
}

/// Plane z = 0 under a point light of intensity I at height h: `E(r) = I h/(h²+r²)^{3/2}`,
/// gradient `−3 I h r/(h²+r²)^{5/2}` along r. Records made lazily (where no record is
/// valid) with the exact value and gradient and `R = h` interpolate to within the
/// second-order Taylor remainder over the validity radius: `½ max|∇²E| (aR)²` with
/// `max|∇²E| = 3I/h⁴` (at r = 0; both the radial and the tangential second derivative are
/// below it), i.e. `1.5 a² I/h²`; a convex combination of extrapolations keeps that bound.
/// Without gradients the error is first order, `|∇E| aR`, and visibly larger.
#[test]
fn cache_interpolates_a_plane_under_a_point_light() {
    let (i0, h, a) = (1.0f32, 1.0f32, 0.2f32);
    let e = |p: Vec3| {
        let r2 = p.x * p.x + p.y * p.y;
        i0 * h / (h * h + r2).powf(1.5)
    };
    let grad = |p: Vec3| {
        Vec3::new(p.x, p.y, 0.0) * (-3.0 * i0 * h / (h * h + p.x * p.x + p.y * p.y).powf(2.5))
    };
    let run = |gradients: bool| {
        let mut cache = IrradianceCache::new(a, 1e-4);
        let mut rng = Pcg32::new(1, 2);
        for _ in 0..20_000 {
            let p = Vec3::new(4.0 * rng.next_f32() - 2.0, 4.0 * rng.next_f32() - 2.0, 0.0);
            if !cache.covers(p, Vec3::Z) {
                let g = if gradients { grad(p) } else { Vec3::ZERO };
                cache.insert(Record {
                    p,
                    n: Vec3::Z,
                    e: Rgb::splat(e(p)),
                    r: h,
                    grad_r: [Vec3::ZERO; 3],
                    grad_t: [g; 3],
                });
            }
        }
        let mut max_err = 0.0f32;
        let mut sum_err = 0.0f32;
        for _ in 0..5000 {
            let p = Vec3::new(3.6 * rng.next_f32() - 1.8, 3.6 * rng.next_f32() - 1.8, 0.0);
            // Lazily, as the renderer does: a point no record serves gets its own.
            if !cache.covers(p, Vec3::Z) {
                let g = if gradients { grad(p) } else { Vec3::ZERO };
                cache.insert(Record {
                    p,
                    n: Vec3::Z,
                    e: Rgb::splat(e(p)),
                    r: h,
                    grad_r: [Vec3::ZERO; 3],
                    grad_t: [g; 3],
                });
            }
            let (v, _) = cache.interpolate(p, Vec3::Z).expect("covered");
            let err = (v.x - e(p)).abs();
            max_err = max_err.max(err);
            sum_err += err;
        }
        (max_err, sum_err / 5000.0, cache.len())
    };
    let (max_g, mean_g, n_g) = run(true);
    let (_, mean_0, _) = run(false);
    let bound = 1.5 * a * a * i0 / (h * h);
    assert!(
        max_g <= bound,
        "max error {max_g} > bound {bound} ({n_g} records)"
    );
    assert!(
        mean_g < 0.5 * mean_0,
        "gradients should help: {mean_g} vs {mean_0}"
    );
}

/// Radiance field for the gradient tests: a plane z = 2 above the origin with radiance
/// `0.1 + exp(−((x − 0.7)² + y²)/0.5)` (smooth, so that finite differences of a finely
/// stratified gather are accurate; a field with sharp edges makes the reference itself
/// jump by whole strata).
fn ceiling(p: Vec3, d: Vec3) -> Option<(Rgb, f32)> {
    if d.z <= 1e-6 {
        return None;
    }
    let t = (2.0 - p.z) / d.z;
    let q = p + d * t;
    let l = 0.1 + (-((q.x - 0.7).powi(2) + q.y * q.y) / 0.5).exp();
    Some((Rgb::splat(l), t))
}

fn gather_centres(p: Vec3, n: Vec3, m: u32, k: u32) -> Gather {
    gather(n, m, k, |_, _| (0.5, 0.5), |d| ceiling(p, d))
}

/// Ward–Heckbert gradients of one gather against central finite differences of the
/// irradiance (from a 256×768 gather, whose own error is far below the tolerances). The
/// gradient formulas discretise boundary integrals over the gather's own strata, a
/// first-order rule: the error halves with each doubling of M and N (measured with the
/// same formulas in a scratch script: 11.6 %, 5.4 %, 2.4 %, 1.0 % of |∇t E| at 6×18 …
/// 48×144; the rotational gradient 1–2 %). So 10 % at the default 12×36 and 3 % at
/// 48×144, and the error must shrink.
#[test]
fn gradients_agree_with_finite_differences() {
    let e_fine = |p: Vec3, n: Vec3| gather_centres(p, n, 256, 768).e.x;
    // δ = 0.05: the f32 sum of 2·10⁵ gather rays rounds at ~1e-5 of E, which a
    // difference over δ = 0.01 would amplify to ~2 % of the gradient; the central
    // difference's own O(δ²) error at 0.05 is 0.1 % (checked in f64).
    let d = 5e-2f32;
    let p0 = Vec3::new(0.0, 0.1, 0.0);
    let fd_t = Vec3::new(
        (e_fine(p0 + Vec3::X * d, Vec3::Z) - e_fine(p0 - Vec3::X * d, Vec3::Z)) / (2.0 * d),
        (e_fine(p0 + Vec3::Y * d, Vec3::Z) - e_fine(p0 - Vec3::Y * d, Vec3::Z)) / (2.0 * d),
        0.0,
    );
    // Rotation about y by δ: n(δ) = (sin δ, 0, cos δ); (n0 × n)·∇r ≈ δ ŷ·∇r.
    let ny = |s: f32| Vec3::new(s.sin(), 0.0, s.cos());
    let fd_r_y = (e_fine(p0, ny(d)) - e_fine(p0, ny(-d))) / (2.0 * d);
    // Rotation about x: n(δ) = (0, −sin δ, cos δ); n0 × dn/dδ = ẑ × (−ŷ) = x̂.
    let nx = |s: f32| Vec3::new(0.0, -s.sin(), s.cos());
    let fd_r_x = (e_fine(p0, nx(d)) - e_fine(p0, nx(-d))) / (2.0 * d);
    let fd_r = Vec3::new(fd_r_x, fd_r_y, 0.0);
    let mut last = f32::INFINITY;
    for (m, k, tol) in [(12, 36, 0.10f32), (48, 144, 0.03)] {
        let g = gather_centres(p0, Vec3::Z, m, k);
        let et = (g.grad_t[0] - fd_t).length() / fd_t.length();
        let er = (g.grad_r[0] - fd_r).length() / fd_r.length();
        assert!(
            et < tol && er < tol && et < last,
            "{m}×{k}: translational {:?} vs {fd_t:?} (rel {et}), rotational {:?} vs {fd_r:?} (rel {er})",
            g.grad_t[0],
            g.grad_r[0]
        );
        last = et;
    }
}

/// On the diffuse Cornell box `pm-ic` converges to the path tracer within its bias.
///
/// Where the bound comes from (see `pmic` module doc): the interpolation bound is
/// `1.5 a² E_ind` (6 % of the indirect irradiance at a = 0.2) and indirect light is at
/// most about half of a block's radiance here (the ceiling around the lamp sees mostly
/// indirect light), so ≤ 3 % of a block; the global map's blur and the gathers' frozen
/// noise (432 rays per record: ≈ 1/√432 ≈ 5 % of E per record before interpolation
/// smooths it, ≤ 2.5 % of a block) add at most as much again; the 1024-spp reference has
/// per-block errors up to 8 % next to the lamp (measured and explained in
/// `dept_converges_to_path_tracing_on_the_cornell_box`, same scene and reference). So
/// 10 % per 8×8 block and, on the image mean where the reference's noise averages out and
/// the bias terms remain, 4 %.
#[test]
fn pm_ic_converges_to_path_tracing_on_the_cornell_box() {
    let scene = frame0(cornell_box(), 32, 32);
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1024,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let reference = blocks(&pt.render(&scene, 0, &|_| {}).pixels, 32, 8);
    let pm = PmIc {
        settings: PmIcSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 64,
                ..PmIcSettings::default().common
            },
            photons: 200_000,
            ..Default::default()
        },
        name: "pm-ic",
    };
    let img = pm.render(&scene, 0, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    let (max, mean) = block_errors(&img.pixels, &reference, 32);
    eprintln!(
        "pm-ic vs path: block {max}, mean {mean}, report {:?}",
        img.report
    );
    assert!(
        max < 0.10 && mean < 0.04,
        "block error {max}, mean error {mean}"
    );
}

/// Bit-identical images for 1 and 2 threads (records are made in a fixed order).
#[test]
fn pm_ic_is_deterministic_across_thread_counts() {
    let scene = frame0(chronolux_core::scene::stage::demo(), 24, 24);
    let pm = PmIc {
        settings: PmIcSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 2,
                ..PmIcSettings::default().common
            },
            photons: 20_000,
            ..Default::default()
        },
        name: "pm-ic",
    };
    let render = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| pm.render(&scene, 1, &|_| {}))
    };
    let (a, b) = (render(1), render(2));
    assert!(
        a.pixels
            .iter()
            .zip(&b.pixels)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    assert_eq!(
        a.report,
        b.report
            .clone()
            .into_iter()
            .map(|(k, v)| {
                // Timings differ; everything else must not.
                if k.starts_with("seconds") {
                    (k.clone(), a.report[&k].clone())
                } else {
                    (k, v)
                }
            })
            .collect()
    );
}

use chronolux_core::scene::desc::{
    Animation, Channel, ChannelTarget, Interpolation, Material, MaterialId, Mesh, MeshId, Node,
    NodeId, SceneDesc, Trs,
};
use chronolux_render::framework::sequence::SequenceRenderer;
use chronolux_render::techniques::ic_static_dynamic::{IcStaticDynamic, IcStaticDynamicSettings};

/// The Cornell box with a small white diffuse cube (half-size 0.2) sliding along x on the
/// floor by 0.4 per second (cornell-moving's configuration in miniature).
pub fn cornell_moving() -> SceneDesc {
    let mut d = cornell_box();
    d.materials.push(Material::diffuse("cube", Rgb::splat(0.8)));
    let mat = MaterialId(d.materials.len() as u32 - 1);
    let mut prim = chronolux_core::scene::stage::cube_primitive(0.2);
    prim.material = Some(mat);
    d.meshes.push(Mesh {
        name: "cube".into(),
        primitives: vec![prim],
        weights: vec![],
    });
    let node = NodeId(d.nodes.len() as u32);
    d.nodes.push(Node {
        name: "cube".into(),
        mesh: Some(MeshId(d.meshes.len() as u32 - 1)),
        transform: Trs {
            translation: Vec3::new(-0.3, 0.2, 0.2),
            ..Default::default()
        },
        ..Default::default()
    });
    d.roots.push(node);
    d.animations.push(Animation {
        name: "slide".into(),
        channels: vec![Channel {
            node,
            target: ChannelTarget::Translation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![-0.3, 0.2, 0.2, 0.1, 0.2, 0.2],
            components: 3,
        }],
    });
    d
}

fn pmic_settings() -> PmIcSettings {
    PmIcSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 8,
            ..PmIcSettings::default().common
        },
        photons: 60_000,
        fixed_photons: true,
        ..Default::default()
    }
}

fn sequence(
    r: &mut dyn SequenceRenderer,
    desc: SceneDesc,
    frames: &[u32],
) -> Vec<chronolux_render::framework::integrator::RenderedFrame> {
    let mut src = crate::source(desc, 32, 32, 24.0, frames.to_vec());
    frames
        .iter()
        .map(|&f| r.render_frame(&mut src, f, &|_| {}))
        .collect()
}

/// On a static animation nothing is dynamic: the static photons are `pm-ic`'s photons
/// (`fixed_photons`), the static cache gets the records `pm-ic` makes, the dynamic map is
/// empty and the blend weight 0 — every frame is bit-identical to `pm-ic`'s (with the
/// same treatment of eye samples no record covers, `fallback_accuracy = 0`: a gather).
/// The same with the precomputed estimator (`precompute_stride = 4`) on both sides: the
/// box has one light group, so `pm-ic`'s group map and the static map's precomputed
/// points are the same photons' estimates.
#[test]
fn ic_static_dynamic_equals_pm_ic_on_a_static_animation() {
    let frames = [0, 1, 2];
    for stride in [0, 4] {
        let settings = PmIcSettings {
            precompute_stride: stride,
            ..pmic_settings()
        };
        let mut a = PmIc {
            settings: settings.clone(),
            name: "pm-ic",
        };
        let mut b = IcStaticDynamic::new(
            IcStaticDynamicSettings {
                pmic: settings,
                fallback_accuracy: 0.0,
                ..Default::default()
            },
            "ic-static-dynamic",
        );
        let ra = sequence(&mut a, cornell_box(), &frames);
        let rb = sequence(&mut b, cornell_box(), &frames);
        for (f, (x, y)) in ra.iter().zip(&rb).enumerate() {
            assert!(
                bits(&x.pixels) == bits(&y.pixels),
                "stride {stride}: frame {f} differs"
            );
            assert_eq!(y.report["dynamic_map_photons"], 0);
        }
        // Records are made once: later frames of the segment add none.
        assert_eq!(rb[1].report["static_records_added"], 0);
    }
}

/// With a moving cube each frame agrees with its own `pm-ic` solution (same photons,
/// cache gathered in the frame itself) within the stated bias: both carry the
/// interpolation bound (≤ 1.5 a² of the indirect irradiance, ≤ 3 % of a block here, see
/// the Cornell test) and the frozen gather noise (≤ 2.5 % of a block), independently, so
/// their difference is bounded by twice that, 11 % per 8×8 block; the correction of the
/// static cache by the dynamic map's density estimate is applied only where the dynamic
/// change is below `influence_high` = 25 % of the static irradiance, and its kernel blur
/// is a fraction of that change. On the image mean the per-record noise averages out:
/// 3 %. The gathered correction (`correction_m = 6`) replaces that blur by a gather of the
/// change over the same photons (the map's blur at the gather hits, as `pm-ic`'s own
/// gathers), and its 108 strata add frozen gather noise of a change ≤ 25 % of the
/// irradiance, inside the same bound. With the precomputed estimator on both sides
/// (`precompute_stride = 4`) each side's gathers read the same kind of blurred estimate,
/// so the bound is the same. Also: the cube is found dynamic, it produces
/// negative photons, and the static records are made once per segment.
#[test]
fn ic_static_dynamic_agrees_with_pm_ic_per_frame_on_a_moving_cube() {
    let frames = [0, 6, 12];
    for (stride, correction_m) in [(0, 0), (0, 6), (4, 6)] {
        let settings = PmIcSettings {
            precompute_stride: stride,
            ..pmic_settings()
        };
        let mut a = PmIc {
            settings: settings.clone(),
            name: "pm-ic",
        };
        let ra = sequence(&mut a, cornell_moving(), &frames);
        let mut b = IcStaticDynamic::new(
            IcStaticDynamicSettings {
                pmic: settings,
                segment: 3,
                correction_m,
                ..Default::default()
            },
            "ic-static-dynamic",
        );
        let rb = sequence(&mut b, cornell_moving(), &frames);
        for (f, (x, y)) in ra.iter().zip(&rb).enumerate() {
            let (max, mean) = block_errors(&y.pixels, &blocks(&x.pixels, 32, 8), 32);
            eprintln!(
                "stride {stride}, correction_m {correction_m}, frame {f}: block {max}, mean {mean}, report {:?}",
                y.report
            );
            assert!(
                max < 0.11 && mean < 0.03,
                "stride {stride}, correction_m {correction_m}, frame {f}: block {max}, mean {mean}"
            );
            assert_eq!(y.report["dynamic_instances"], 1);
            assert!(y.report["negative_photons"].as_u64().unwrap() > 0);
        }
        assert_eq!(rb[1].report["new_segment"], false);
    }
}

/// Bit-identical frames of `ic-static-dynamic` for 1 and 2 threads, with either correction
/// and either gather estimator.
#[test]
fn ic_static_dynamic_is_deterministic_across_thread_counts() {
    for (correction_m, stride) in [(0, 0), (4, 0), (4, 4)] {
        let render = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let mut r = IcStaticDynamic::new(
                        IcStaticDynamicSettings {
                            pmic: PmIcSettings {
                                common: chronolux_render::registry::CommonSettings {
                                    spp: 2,
                                    ..PmIcSettings::default().common
                                },
                                photons: 20_000,
                                fixed_photons: true,
                                precompute_stride: stride,
                                ..Default::default()
                            },
                            segment: 2,
                            correction_m,
                            ..Default::default()
                        },
                        "ic-static-dynamic",
                    );
                    sequence(&mut r, cornell_moving(), &[0, 1, 2])
                })
        };
        let (a, b) = (render(1), render(2));
        for (x, y) in a.iter().zip(&b) {
            assert!(
                bits(&x.pixels) == bits(&y.pixels),
                "correction_m {correction_m}, stride {stride}"
            );
        }
    }
}

/// Only photons whose static paths cross a dynamic object's bounds in the frame are
/// re-traced per frame: every other photon's path in the frame is provably its static
/// path (module doc of `retrace_set`). Checked by re-tracing *every* photon in two frames
/// of the moving cube: each photon outside the set has exactly its static hits and path
/// points, for the global and the caustic stream; and the set is not vacuous (some of
/// its photons change, and it is a small part of all photons).
#[test]
fn photons_outside_the_retrace_set_keep_their_static_paths() {
    use chronolux_core::scene::delta::FrameDelta;
    use chronolux_render::kernels::gather::caustic_seed;
    use chronolux_render::techniques::ic_static_dynamic::{
        Keep, Stream, dynamic_bounds, retrace_set, trace_path,
    };
    let n = 20_000u64;
    let frames = vec![0, 6, 12];
    let mut src = crate::source(cornell_moving(), 32, 32, 24.0, frames.clone());
    let scenes: Vec<_> = frames.iter().map(|&f| src.frame(f)).collect();
    let refs: Vec<&_> = scenes.iter().map(|s| &**s).collect();
    let dynamic = FrameDelta::over(&refs).dynamic_instances();
    assert_eq!(dynamic.iter().filter(|d| **d).count(), 1);
    let stat = scenes[0].without_instances(&dynamic);
    let all: Vec<u32> = (0..n as u32).collect();
    for (seed, keep) in [(7u64, Keep::All), (caustic_seed(7), Keep::Caustic)] {
        let stream = Stream::trace(&stat, n, seed, keep);
        for scene in &scenes[1..] {
            let boxes = dynamic_bounds(scene, &dynamic);
            let set = retrace_set(&stream, &all, &boxes);
            let mut changed = 0;
            let mut next = 0;
            for i in 0..n as u32 {
                let now = trace_path(scene, i as u64, seed, n, keep);
                let before = trace_path(&stat, i as u64, seed, n, keep);
                assert_eq!(before.hits, stream.hits_of(i as usize));
                if next < set.len() && set[next] == i {
                    next += 1;
                    changed += usize::from(now != before);
                } else {
                    assert!(now == before, "photon {i} changed outside the set");
                }
            }
            if keep == Keep::All {
                assert!(
                    changed > 0 && set.len() < n as usize / 4,
                    "{changed} / {}",
                    set.len()
                );
            }
        }
    }
}

/// No seam where the dynamic cache takes over. Along every image row, on its longest run
/// of points on one surface (same instance and normal), the indirect irradiance the eye
/// pass uses is sampled every quarter pixel together with the blend weight β. At the
/// places where β leaves 0 the second difference of the profile must not stand out from
/// the second differences on the same surface where β = 0 (the static cache alone, whose
/// interpolation has its own texture). If the `3m` values at the `m` boundaries of a
/// surface were no different from its `n` reference values (exchangeable), the chance
/// that their largest exceeds the reference's largest is `3m / (n + 3m)`; surfaces with
/// `n ≥ 57m` make that ≤ 5 %, the false-alarm rate accepted for calling a seam
/// visible. A switch to the dynamic cache with a step (or a kink) that stands out of the
/// static texture fails it.
#[test]
fn blend_into_the_dynamic_cache_leaves_no_seam() {
    use chronolux_core::color::luminance;
    use chronolux_core::math::Vec2;
    use std::collections::BTreeMap;
    let (w, h) = (64u32, 64u32);
    let mut r = IcStaticDynamic::new(
        IcStaticDynamicSettings {
            pmic: pmic_settings(),
            segment: 3,
            ..Default::default()
        },
        "ic-static-dynamic",
    );
    let mut src = crate::source(cornell_moving(), w, h, 24.0, vec![0, 6, 12]);
    let step = 0.25f32;
    let per_row = (w as f32 / step) as usize;
    let raster: Vec<Vec2> = (0..h)
        .flat_map(|y| (0..per_row).map(move |i| Vec2::new(step * (i as f32 + 0.5), y as f32 + 0.5)))
        .collect();
    let all = r.profile(&mut src, 6, &raster);
    // Per instance: (reference |Δ²| values, boundary maxima).
    let mut pools: BTreeMap<u32, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
    for prof in all.chunks(per_row) {
        // Longest run of points on one surface (same instance and normal).
        let mut best = (0usize, 0usize);
        let mut start = 0;
        for i in 1..=prof.len() {
            let same = i < prof.len()
                && match (&prof[i - 1], &prof[i]) {
                    (Some(a), Some(b)) => a.0.instance == b.0.instance && a.0.n.dot(b.0.n) > 0.9999,
                    _ => false,
                };
            if !same {
                if i - start > best.1 - best.0 && prof[start].is_some() {
                    best = (start, i);
                }
                start = i;
            }
        }
        if best.1 - best.0 < 8 {
            continue;
        }
        let instance = prof[best.0].expect("run of found points").0.instance;
        let run: Vec<(f32, f64)> = prof[best.0..best.1]
            .iter()
            .map(|p| {
                let (_, beta, e) = p.expect("run of found points");
                (beta, luminance(e) as f64)
            })
            .collect();
        // |Δ²| centred on run index i (1 ≤ i ≤ len − 2).
        let d2 = |i: usize| (run[i + 1].1 - 2.0 * run[i].1 + run[i - 1].1).abs();
        let pool = pools.entry(instance).or_default();
        for i in 1..run.len() - 1 {
            if (i - 1..=i + 1).all(|j| run[j].0 == 0.0) {
                pool.0.push(d2(i));
            }
        }
        // Boundaries: β = 0 on one side, > 0 on the other; the stencils around them.
        for b in 1..run.len() {
            if (run[b - 1].0 == 0.0) != (run[b].0 == 0.0) {
                let at = (b.saturating_sub(1).max(1)..=(b + 1).min(run.len() - 2))
                    .map(d2)
                    .fold(0.0, f64::max);
                pool.1.push(at);
            }
        }
    }
    let mut checked = 0;
    for (instance, (reference, bounds)) in &pools {
        if bounds.is_empty() || reference.len() < 57 * bounds.len() {
            continue;
        }
        let ref_max = reference.iter().cloned().fold(0.0, f64::max);
        let at = bounds.iter().cloned().fold(0.0, f64::max);
        eprintln!(
            "instance {instance}: {} boundaries, largest |Δ²| there {at:.4e}, reference max \
             {ref_max:.4e} (n = {})",
            bounds.len(),
            reference.len()
        );
        assert!(at <= ref_max, "instance {instance}: seam: {at} > {ref_max}");
        checked += 1;
    }
    assert!(
        checked >= 1,
        "no surface crosses the blend: {:?}",
        pools
            .iter()
            .map(|(k, v)| (k, v.0.len(), v.1.len()))
            .collect::<Vec<_>>()
    );
}
