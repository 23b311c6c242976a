//! DEPT: element bookkeeping on moving objects, the filters, convergence to the path
//! tracer on a static diffuse scene, determinism.

use crate::{block_errors, blocks, frame0};
use chronolux_core::color::Rgb;
use chronolux_core::math::Vec3;
use chronolux_core::scene::desc::{
    Animation, AnimationId, Channel, ChannelTarget, Interpolation, LightDesc, LightId, LightKind,
    Material, MaterialId, Mesh, MeshId, Node, NodeId, Primitive, SceneDesc, Trs,
};
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
use chronolux_core::scene::stage::cornell_box;
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::kernels::elements::element_map::{
    ElementAccumulators, ElementMesh, FrameElements, slot,
};
use chronolux_render::kernels::elements::reconstruct::{
    ElementSolution, Filter, filtered_irradiance,
};
use chronolux_render::kernels::elements::{Dept, DeptSettings};
use chronolux_render::kernels::path::{PathSettings, PathTracer};
use chronolux_render::kernels::photon::trace_photons;
use std::sync::Arc;

/// On the static diffuse Cornell box, `dept` converges to the path tracer up to the
/// element discretisation bias.
///
/// How the bound is obtained: the bias of density estimation on elements is the
/// one-ring vertex averaging (a kernel about two elements wide, see
/// `dept::reconstruct`); it is measured by rendering at two element resolutions. At 10
/// elements per diagonal the blocks next to the lamp are off by ~19 % (the lamp's
/// back-side light trapped between lamp and ceiling is averaged into the visible ceiling
/// around it); at 100 the error there drops to ~1 % while the remaining block errors
/// (≤ 5 %, at the same blocks for 25, 50 and 100 elements, and with 1e5 or 4e6 photons) do
/// not depend on the resolution or the photon count. They are the *reference's* noise
/// (`diagnose_cornell_block_errors`): rare bright paths through the 1 % gap that the
/// two-sided lamp lights make two 1024-spp path-traced images with different seeds differ
/// by up to 8 % per block, in the same blocks; with a one-sided lamp dept and the path
/// tracer agree within 0.5 % everywhere. So at 100 elements the test allows
/// 8 % per 8×8 block and 1.5 % on the image mean (measured: 4.8 % and 0.35 %), and checks
/// that the coarse mesh is at least twice as wrong (the bias does shrink with h).
/// Photon noise at 1e6 photons and the reference's noise (1024 spp) are below 0.5 % per
/// block.
#[test]
fn dept_converges_to_path_tracing_on_the_cornell_box() {
    let scene = frame0(cornell_box(), 32, 32);
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1024,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let reference = blocks(&pt.render(&scene, 0, &|_| {}).pixels, 32, 8);
    let run = |elements: f32| {
        let d = Dept::new(DeptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 64,
                ..DeptSettings::default().common
            },
            elements,
            photons: 1_000_000,
            ..Default::default()
        });
        let img = d.render(&scene, 0, &|_| {});
        assert_eq!(img.invalid_samples, 0);
        block_errors(&img.pixels, &reference, 32)
    };
    let (fine_max, fine_mean) = run(100.0);
    let (coarse_max, _) = run(10.0);
    assert!(
        fine_max < 0.08 && fine_mean < 0.015,
        "100 elements: block error {fine_max}, mean error {fine_mean}"
    );
    assert!(
        coarse_max > 2.0 * fine_max,
        "bias should shrink with the element size: {coarse_max} vs {fine_max}"
    );
}

/// `desc` with every triangle of its non-emissive primitives split uniformly into `n²`
/// (positions, normals and UVs interpolated): the same surfaces as a finely tessellated
/// model.
fn tessellated(mut desc: SceneDesc, n: u32) -> SceneDesc {
    let emissive: Vec<bool> = desc
        .materials
        .iter()
        .map(|m| m.emissive != Rgb::ZERO)
        .collect();
    for mesh in &mut desc.meshes {
        for prim in &mut mesh.primitives {
            if prim.material.is_some_and(|m| emissive[m.0 as usize]) {
                continue;
            }
            let mut out = Primitive {
                positions: Vec::new(),
                normals: prim.normals.as_ref().map(|_| Vec::new()),
                uvs: prim.uvs.as_ref().map(|_| Vec::new()),
                material: prim.material,
                ..Default::default()
            };
            for tri in &prim.indices {
                let base = out.positions.len() as u32;
                // Grid vertex (i, j), i + j ≤ n, at barycentrics (i/n, j/n).
                let id = |i: u32, j: u32| base + i * (n + 1) - i * i.saturating_sub(1) / 2 + j;
                for i in 0..=n {
                    for j in 0..=n - i {
                        let (b1, b2) = (i as f32 / n as f32, j as f32 / n as f32);
                        let w = [1.0 - b1 - b2, b1, b2];
                        let mix3 =
                            |v: &[Vec3]| (0..3).map(|k| v[tri[k] as usize] * w[k]).sum::<Vec3>();
                        out.positions.push(mix3(&prim.positions));
                        if let (Some(o), Some(v)) = (&mut out.normals, &prim.normals) {
                            o.push(mix3(v).normalize());
                        }
                        if let (Some(o), Some(v)) = (&mut out.uvs, &prim.uvs) {
                            o.push((0..3).map(|k| v[tri[k] as usize] * w[k]).sum());
                        }
                    }
                }
                for i in 0..n {
                    for j in 0..n - i {
                        out.indices.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                        if i + j + 2 <= n {
                            out.indices
                                .push([id(i + 1, j + 1), id(i, j + 1), id(i + 1, j)]);
                        }
                    }
                }
            }
            *prim = out;
        }
    }
    desc
}

/// A finely tessellated model gets elements of the size its photons were budgeted for,
/// not one per triangle: the Cornell box with every wall and block triangle split into
/// 48² (36 → 41k triangles, each 1/48 of the original's edge, below half the element size
/// at 25 elements per diagonal) gets at most as many elements as the coarse box (its
/// clusters are cubes of 0.7 h, area ≈ h²/2, the split triangles' elements h²/4 … h²/2;
/// the bound allows 1.5× for partial cubes along the edges). DEPT on it agrees with the
/// path tracer as well as on the coarse box: the same surfaces at the same element size
/// give the same reconstruction bias, up to the clusters' shape (cubes, not triangles
/// along the walls' edges). Measured: worst 8×8 block 0.49 % on both, image mean 0.112 %
/// coarse and 0.114 % fine; the bounds allow the fine mesh 1.25× the coarse one's errors
/// plus 0.2 % (block) and 0.1 % (mean) for the two renders' independent noise (photons
/// at 1e6 land on different elements; the eye pass's 64 spp).
#[test]
fn dept_clusters_a_finely_tessellated_model_and_agrees_with_the_coarse_one() {
    let coarse = frame0(cornell_box(), 32, 32);
    let fine = frame0(tessellated(cornell_box(), 48), 32, 32);
    let elements = 25.0;
    let (mc, mf) = (
        ElementMesh::build(&coarse, elements),
        ElementMesh::build(&fine, elements),
    );
    assert_eq!(mc.cluster_count(), 0);
    assert!(mf.triangle_count() > 1000 * mc.triangle_count() / 2);
    assert!(
        mf.element_count() as f64 <= 1.5 * mc.element_count() as f64,
        "fine mesh: {} elements ({} clusters) on {} triangles; coarse: {}",
        mf.element_count(),
        mf.cluster_count(),
        mf.triangle_count(),
        mc.element_count()
    );
    // The fine mesh's element areas add up to the coarse mesh's (the same surfaces).
    let total = |s, m| {
        FrameElements::new(s, m)
            .area
            .iter()
            .map(|&a| a as f64)
            .sum::<f64>()
    };
    let (ac, af) = (total(&coarse, &mc), total(&fine, &mf));
    assert!((af - ac).abs() < 1e-4 * ac, "areas {af} vs {ac}");
    // A constant field stays constant through the clusters' vertex interpolation.
    let fe = FrameElements::new(&fine, &mf);
    let flat = vec![Rgb::splat(2.0); 2 * mf.element_count()];
    let sol = ElementSolution::from_elements(&mf, &fe, &flat);
    assert!(
        sol.vertex
            .iter()
            .all(|v| *v == Rgb::ZERO || (v.y - 2.0).abs() < 1e-5)
    );
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1024,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let reference = blocks(&pt.render(&coarse, 0, &|_| {}).pixels, 32, 8);
    let run = |scene| {
        let d = Dept::new(DeptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 64,
                ..DeptSettings::default().common
            },
            elements,
            photons: 1_000_000,
            ..Default::default()
        });
        let img = d.render(scene, 0, &|_| {});
        assert_eq!(img.invalid_samples, 0);
        block_errors(&img.pixels, &reference, 32)
    };
    let ((cmax, cmean), (fmax, fmean)) = (run(&coarse), run(&fine));
    eprintln!("coarse: block {cmax} mean {cmean}; fine: block {fmax} mean {fmean}");
    assert!(
        fmax <= 1.25 * cmax + 0.002 && fmean <= 1.25 * cmean + 0.001,
        "fine: block error {fmax}, mean {fmean}; coarse: {cmax}, {cmean}"
    );
}

/// A quad and a spot light on one animated node (moving +2 in x over 1 s), and a static
/// wall far behind: the configuration around the quad moves rigidly, so photon i hits the
/// same element of the quad in every frame, at a point moved by the translation.
fn moving_quad() -> SceneDesc {
    let quad = |z: f32, s: f32| Primitive {
        positions: vec![
            Vec3::new(-s, -s, z),
            Vec3::new(s, -s, z),
            Vec3::new(s, s, z),
            Vec3::new(-s, s, z),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material: Some(MaterialId(0)),
        ..Default::default()
    };
    SceneDesc {
        nodes: vec![
            Node {
                name: "moving".into(),
                mesh: Some(MeshId(0)),
                light: Some(LightId(0)),
                ..Default::default()
            },
            Node {
                name: "wall".into(),
                mesh: Some(MeshId(1)),
                transform: Trs {
                    translation: Vec3::new(0.0, 0.0, -10.0),
                    ..Default::default()
                },
                ..Default::default()
            },
        ],
        roots: vec![NodeId(0), NodeId(1)],
        meshes: vec![
            Mesh {
                name: "quad".into(),
                primitives: vec![quad(-1.0, 0.5)],
                weights: vec![],
            },
            Mesh {
                name: "wall".into(),
                primitives: vec![quad(0.0, 20.0)],
                weights: vec![],
            },
        ],
        materials: vec![Material::diffuse("white", Rgb::splat(0.5))],
        lights: vec![LightDesc {
            name: "spot".into(),
            color: Rgb::ONE,
            intensity: 1.0,
            kind: LightKind::Spot {
                inner_cone: 0.2,
                outer_cone: 0.35,
            },
        }],
        animations: vec![Animation {
            name: "slide".into(),
            channels: vec![Channel {
                node: NodeId(0),
                target: ChannelTarget::Translation,
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: vec![0.0, 0.0, 0.0, 2.0, 0.0, 0.0],
                components: 3,
            }],
        }],
        ..Default::default()
    }
}

#[test]
fn photons_on_a_moving_object_stay_on_its_elements() {
    let mut b = FrameBuilder::new(
        Arc::new(moving_quad()),
        Some(AnimationId(0)),
        CameraChoice::First,
        8,
        8,
    )
    .unwrap();
    let f0 = b.build(0.0);
    let f1 = b.build(0.5);
    let mesh = ElementMesh::build(&f0, 60.0);
    assert!(mesh.matches(&f1));
    let moving = |f: &chronolux_core::scene::frame::FrameScene| {
        trace_photons(f, 0..5000, 1, |h| {
            (h.bounces == 0 && h.tri.geometry == 0)
                .then(|| (h.index, mesh.locate(h.tri, h.b1, h.b2).element, h.p))
        })
        .0
    };
    let (h0, h1) = (moving(&f0), moving(&f1));
    assert!(h0.len() > 4000, "the spot should light the quad");
    assert_eq!(h0.len(), h1.len());
    let shift = Vec3::new(1.0, 0.0, 0.0);
    let (e0, e1) = (
        FrameElements::new(&f0, &mesh),
        FrameElements::new(&f1, &mesh),
    );
    for (a, b) in h0.iter().zip(&h1) {
        assert_eq!((a.0, a.1), (b.0, b.1), "photon {} changed element", a.0);
        assert!((b.2 - a.2 - shift).length() < 1e-4);
        let e = a.1 as usize;
        assert!((e1.centroid[e] - e0.centroid[e] - shift).length() < 1e-4);
        assert!((e1.area[e] - e0.area[e]).abs() < 1e-6 * e0.area[e].max(1e-6));
    }
    // The element's world position follows the object: its centroid is within one
    // element of the photon's hit point in both frames.
    for (h, fe) in [(&h0, &e0), (&h1, &e1)] {
        for p in h.iter().take(200) {
            assert!((fe.centroid[p.1 as usize] - p.2).length() < mesh.element_size);
        }
    }
}

/// A flat 2×2 quad meshed into small elements, with an irradiance field `field(x)`
/// written into its accumulators as if `photons_per_element` photons had landed on each.
fn synthetic(
    field: impl Fn(f32) -> f32,
    photons_per_element: u32,
) -> (ElementMesh, FrameElements, ElementAccumulators) {
    let scene = frame0(moving_quad(), 8, 8);
    let mesh = ElementMesh::build(&scene, 400.0);
    let fe = FrameElements::new(&scene, &mesh);
    let mut acc = ElementAccumulators::new(mesh.element_count());
    acc.photons = 1;
    for e in 0..mesh.element_count() {
        let s = slot(e as u32, true);
        let phi = field(fe.centroid[e].x) * fe.area[e];
        acc.flux[s] = Rgb::splat(phi);
        acc.count[s] = photons_per_element;
        acc.flux_sq[s] = phi * phi / photons_per_element as f32;
    }
    (mesh, fe, acc)
}

#[test]
fn bilateral_filter_keeps_a_step_sharp_and_a_constant_unchanged() {
    let bilateral = Filter::Bilateral {
        radius: 3.0,
        kappa: 2.0,
        min_photons: 8,
    };
    let gaussian = Filter::Gaussian { radius: 3.0 };
    // Only the moving quad (geometry 0, z = −1) is looked at.
    let on_quad = |fe: &FrameElements, e: usize| fe.centroid[e].z > -1.5;
    let (mesh, fe, acc) = synthetic(|_| 3.0, 50);
    for f in [bilateral, gaussian] {
        let out = filtered_irradiance(&mesh, &acc, &fe, f);
        for e in (0..mesh.element_count()).filter(|&e| on_quad(&fe, e)) {
            let v = out[slot(e as u32, true)].x;
            assert!((v - 3.0).abs() < 1e-4, "{f:?}: constant became {v}");
        }
    }
    let step = |x: f32| if x < 0.0 { 1.0 } else { 10.0 };
    let (mesh, fe, acc) = synthetic(step, 50);
    let out_b = filtered_irradiance(&mesh, &acc, &fe, bilateral);
    let out_g = filtered_irradiance(&mesh, &acc, &fe, gaussian);
    let (mut worst_b, mut worst_g) = (0.0f32, 0.0f32);
    for e in (0..mesh.element_count()).filter(|&e| on_quad(&fe, e)) {
        let want = step(fe.centroid[e].x);
        let s = slot(e as u32, true);
        worst_b = worst_b.max((out_b[s].x - want).abs() / want);
        worst_g = worst_g.max((out_g[s].x - want).abs() / want);
    }
    // Noise σ = value/√50 ≈ 14 %: the range kernel at κ = 2 gives a 1-vs-10 neighbour
    // weight exp(−81/(2·4·(0.02+2))) ≈ 7e-3, so the step stays within a few percent.
    assert!(worst_b < 0.05, "bilateral blurred the step by {worst_b}");
    assert!(
        worst_g > 0.5,
        "the Gaussian should blur it (sanity): {worst_g}"
    );
    // Elements with fewer photons than min_photons fall back to the plain Gaussian.
    let (mesh, fe, acc) = synthetic(step, 2);
    let out_r = filtered_irradiance(&mesh, &acc, &fe, bilateral);
    let g2 = filtered_irradiance(&mesh, &acc, &fe, gaussian);
    assert_eq!(out_r, g2);
}

#[test]
fn dept_is_bit_identical_across_thread_counts() {
    let scene = frame0(cornell_box(), 24, 16);
    let d = Dept::new(DeptSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 2,
            ..DeptSettings::bilateral().common
        },
        photons: 30_000,
        elements: 30.0,
        ..DeptSettings::bilateral()
    });
    let render = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| d.render(&scene, 2, &|_| {}))
    };
    let (a, b) = (render(1), render(3));
    let bits = |v: &[glam::Vec3]| -> Vec<[u32; 3]> {
        v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
    };
    assert_eq!(bits(&a.pixels), bits(&b.pixels));
    assert_eq!(a.stats, b.stats);
}

/// On a static scene the space-time estimate pools frames: after 5 frames of 1e5 photons
/// its indirect light is closer to a 1e6-photon `dept` solution (same elements, same
/// camera samples, so the difference is indirect-light noise and filtering bias only)
/// than frame-by-frame `dept` with 1e5 photons, and it stays within the Cornell bound of
/// `dept_converges_to_path_tracing_on_the_cornell_box` against the path tracer (the
/// filters add no visible bias on this diffuse scene: the energy test keeps whole static
/// windows and the bilateral range kernel stops at the lamp's edge).
#[test]
fn spacetime_dept_pools_frames_on_a_static_scene() {
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::techniques::spacetime_dept::{SpacetimeDept, SpacetimeSettings};
    let scene = frame0(cornell_box(), 32, 32);
    let mut src = crate::source(cornell_box(), 32, 32, 24.0, (0..5).collect());
    let (spp, elements) = (16, 50.0);
    // Per-pixel light not pooled: the comparison below relies on the same camera samples.
    let mut st = SpacetimeDept::new(SpacetimeSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            ..SpacetimeSettings::default().common
        },
        elements,
        photons: 100_000,
        light_history: 0,
        // The sliding window's pooling is what is tested (a still scene would otherwise
        // read the still solution: `spacetime_dept_reads_one_still_solution_...`).
        still_set: false,
        ..Default::default()
    });
    let mut last = None;
    for f in 0..5 {
        last = Some(st.render_frame(&mut src, f, &|_| {}));
    }
    let st_img = last.unwrap();
    let dept = |photons: u64| {
        Dept::new(DeptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp,
                ..DeptSettings::default().common
            },
            elements,
            photons,
            ..Default::default()
        })
        .render(&scene, 4, &|_| {})
    };
    let (fine, coarse) = (dept(1_000_000), dept(100_000));
    let rms = |a: &[glam::Vec3]| {
        let s: f64 = a
            .iter()
            .zip(&fine.pixels)
            .map(|(x, y)| ((*x - *y).length_squared() / 3.0) as f64)
            .sum();
        (s / a.len() as f64).sqrt()
    };
    let (e_st, e_dept) = (rms(&st_img.pixels), rms(&coarse.pixels));
    assert!(
        e_st < 0.7 * e_dept,
        "space-time rms {e_st} vs frame-by-frame {e_dept}"
    );
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1024,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let reference = blocks(&pt.render(&scene, 0, &|_| {}).pixels, 32, 8);
    let (max, mean) = block_errors(&st_img.pixels, &reference, 32);
    assert!(max < 0.08 && mean < 0.015, "block {max}, mean {mean}");
}

/// `max_depth` (segments from the camera, the path tracer's and Mitsuba's convention): on
/// the Cornell box every surface is seen straight from the camera, where the depth limit
/// of `dept`'s elements is exact (`dept::view`, "Path depth"), so `dept` with `max_depth
/// = D` converges to the path tracer with the same D. Bounds as in
/// `dept_converges_to_path_tracing_on_the_cornell_box` (same scene, photons, elements and
/// reference samples): 8 % per 8×8 block, 1.5 % on the image mean. D = 2 is direct light
/// only (the elements must add nothing), D = 3 one indirect bounce. The test can tell:
/// unlimited `dept` is off from the path tracer at D = 3 by the light of longer paths,
/// measured 11 % of the mean (> 5 % asserted; the depth-limited runs: 0.14–0.16 %).
/// `spacetime-dept`, which shares the photon deposit and the eye pass, is checked at
/// D = 3 over a static 5-frame window with the bounds of
/// `spacetime_dept_pools_frames_on_a_static_scene`.
#[test]
fn dept_max_depth_agrees_with_path_tracing_at_that_depth() {
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::techniques::spacetime_dept::{SpacetimeDept, SpacetimeSettings};
    let scene = frame0(cornell_box(), 32, 32);
    let pt = |d: u32| {
        let img = PathTracer::new(PathSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 1024,
                max_depth: Some(d),
                ..PathSettings::default().common
            },
            ..Default::default()
        })
        .render(&scene, 0, &|_| {});
        blocks(&img.pixels, 32, 8)
    };
    let dept = |d: Option<u32>| {
        let img = Dept::new(DeptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 64,
                max_depth: d,
                ..DeptSettings::default().common
            },
            elements: 100.0,
            photons: 1_000_000,
            ..Default::default()
        })
        .render(&scene, 0, &|_| {});
        assert_eq!(img.invalid_samples, 0);
        img.pixels
    };
    let three = pt(3);
    for (d, reference) in [(2, pt(2)), (3, three.clone())] {
        let (max, mean) = block_errors(&dept(Some(d)), &reference, 32);
        eprintln!("max_depth {d}: block error {max:.4}, mean error {mean:.4}");
        assert!(
            max < 0.08 && mean < 0.015,
            "max_depth {d}: block error {max}, mean error {mean}"
        );
    }
    let (_, unlimited) = block_errors(&dept(None), &three, 32);
    eprintln!("unlimited against max_depth 3: mean error {unlimited:.4}");
    assert!(unlimited > 0.05, "unlimited vs depth 3: {unlimited}");

    let mut src = crate::source(cornell_box(), 32, 32, 24.0, (0..5).collect());
    let mut st = SpacetimeDept::new(SpacetimeSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 16,
            max_depth: Some(3),
            ..SpacetimeSettings::default().common
        },
        elements: 50.0,
        photons: 100_000,
        ..Default::default()
    });
    let mut last = None;
    for f in 0..5 {
        last = Some(st.render_frame(&mut src, f, &|_| {}));
    }
    let (max, mean) = block_errors(&last.unwrap().pixels, &three, 32);
    eprintln!("spacetime-dept, max_depth 3: block error {max:.4}, mean error {mean:.4}");
    assert!(max < 0.08 && mean < 0.015, "block {max}, mean {mean}");
}

/// The stopping rule: the photon count it picks grows as the Weber threshold tightens
/// (σ ∝ 1/√N: halving the threshold needs about 4× the photons, within the batch
/// granularity and the [total + batch, 2·total] step clamp), stays within [batch, cap],
/// and the frame's solution then meets the criterion it was stopped on.
#[test]
fn stopping_rule_shoots_more_photons_for_a_tighter_threshold() {
    use chronolux_render::kernels::elements::budget::AutoPhotons;
    let scene = frame0(cornell_box(), 16, 16);
    let solve = |weber: f32| {
        let rule = AutoPhotons {
            weber,
            batch: 10_000,
            max_photons: 2_000_000,
            ..Default::default()
        };
        let d = Dept::new(DeptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 1,
                ..DeptSettings::spatial().common
            },
            elements: 30.0,
            auto: Some(rule),
            ..DeptSettings::spatial()
        });
        d.solve(&scene, 0).photons.photons()
    };
    let (loose, tight) = (solve(0.04), solve(0.02));
    assert!(
        (10_000..=2_000_000).contains(&loose) && (10_000..=2_000_000).contains(&tight),
        "{loose} {tight}"
    );
    let ratio = tight as f64 / loose as f64;
    assert!(
        (2.0..=8.0).contains(&ratio),
        "halving the threshold: {loose} → {tight} photons (×{ratio:.2})"
    );
}

/// `FrameScene::geometry_instance` names the instance that carries each geometry: moving
/// the quad's node moves that instance's transform, and the element mesh follows it.
#[test]
fn geometry_instance_carries_the_moving_node() {
    let desc = Arc::new(moving_quad());
    let mut b = FrameBuilder::new(desc, Some(AnimationId(0)), CameraChoice::First, 8, 8).unwrap();
    let (s0, s1) = (b.build(0.0), b.build(1.0));
    assert_eq!(s0.geometry_instance.len(), s0.geometry.len());
    let xf0 = s0.geometry_transforms();
    let xf1 = s1.geometry_transforms();
    let moved: Vec<f32> = xf0
        .iter()
        .zip(&xf1)
        .map(|(a, b)| (b.translation - a.translation).x)
        .collect();
    assert!(
        moved.iter().any(|d| (d - 2.0).abs() < 1e-4),
        "no geometry moved by +2: {moved:?}"
    );
    assert!(moved.iter().any(|d| d.abs() < 1e-6), "the wall is static");
}

/// Per element side: indirect + caustic luminance irradiance of `frame` of `desc` from
/// `photons` photons, Gaussian-filtered as `dept-spatial`, on `mesh`, and its power
/// weight (area × irradiance).
fn fine_irradiance(
    src: &mut chronolux_core::scene::source::FrameSource,
    mesh: &ElementMesh,
    frame: u32,
    photons: u64,
) -> Vec<f32> {
    use chronolux_render::kernels::elements::element_map::deposit_photons;
    let scene = src.frame(frame);
    let fe = FrameElements::new(&scene, mesh);
    let p = deposit_photons(&scene, mesh, 0..photons, 7);
    let g = Filter::Gaussian { radius: 2.5 };
    let a = filtered_irradiance(mesh, &p.indirect, &fe, g);
    let b = filtered_irradiance(mesh, &p.caustic, &fe, g);
    a.iter()
        .zip(&b)
        .map(|(x, y)| chronolux_core::color::luminance(*x + *y))
        .collect()
}

/// Power-weighted fraction of `sides` (slot, weight) for which `bad(slot)` holds.
fn weighted_fraction(sides: &[(usize, f32)], bad: impl Fn(usize) -> bool) -> f32 {
    let total: f32 = sides.iter().map(|s| s.1).sum();
    sides.iter().filter(|s| bad(s.0)).map(|s| s.1).sum::<f32>() / total.max(1e-30)
}

/// The centred window on an abrupt change: in the built-in caustic scene an occluder
/// enters between frames 3 and 4 (a STEP key), shadowing the glass sphere (its caustic
/// vanishes) and the middle of the room. Element sides whose indirect + caustic light
/// changes visibly at the step (by more than 30 % between frames 3 and 4, in a 200k-photon
/// frame-by-frame solution) must not pool frames across it: at most 5 % of their power
/// may have frame 3's window reach frame 4 or frame 4's reach frame 3 (measured 0.2 % and
/// 0.1 % with these settings, 0.0 % and 0.1 % with the former `change_radius` 5; the
/// margin is for the 3σ test's misses, which grow as photons per side fall). On the far
/// side of the step, where nothing visible changes, frame 3 keeps frames 0–2 for ≥ 80 %
/// of the power of the sides whose light changes by < 5 % (measured 96.6 %, 88 % with
/// `change_radius` 5: the spatially pooled statistic also cuts sides within
/// `change_radius` elements of a change, and the sphere moves).
#[test]
fn spacetime_window_stops_at_an_abrupt_change_and_spans_static_frames() {
    use chronolux_core::scene::stage::{CAUSTIC_OCCLUDER_TIME, caustic};
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::techniques::spacetime_dept::{SpacetimeDept, SpacetimeSettings};
    const { assert!(3.0 / 24.0 < CAUSTIC_OCCLUDER_TIME && CAUSTIC_OCCLUDER_TIME < 4.0 / 24.0) };
    let elements = 30.0;
    let frames: Vec<u32> = (0..8).collect();
    let mut src = crate::source(caustic(), 8, 8, 24.0, frames.clone());
    let mut st = SpacetimeDept::new(SpacetimeSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1,
            ..SpacetimeSettings::default().common
        },
        elements,
        photons: 40_000,
        window: 4,
        ..Default::default()
    });
    let mut info = Vec::new();
    for &f in &frames {
        st.render_frame(&mut src, f, &|_| {});
        info.push(st.info.clone().expect("frame info"));
    }
    let mesh = ElementMesh::build(&src.frame(0), elements);
    let (e3, e4) = (
        fine_irradiance(&mut src, &mesh, 3, 200_000),
        fine_irradiance(&mut src, &mesh, 4, 200_000),
    );
    let area = &info[3].area;
    let (mut changed, mut steady) = (Vec::new(), Vec::new());
    for s in 0..e3.len() {
        let (a, b) = (e3[s], e4[s]);
        let w = area[s / 2] * a.max(b);
        if !(w > 0.0) {
            continue;
        }
        if (a - b).abs() > 0.3 * a.max(b) {
            changed.push((s, w));
        } else if (a - b).abs() < 0.05 * a.max(b) {
            steady.push((s, w));
        }
    }
    assert!(
        changed.len() > 50,
        "the occluder should change the light of many sides"
    );
    let smear_into_before = weighted_fraction(&changed, |s| info[3].window[s].1 >= 4);
    let smear_into_after = weighted_fraction(&changed, |s| info[4].window[s].0 <= 3);
    eprintln!(
        "changed sides pooled across the step: {:.1} % (frame 3), {:.1} % (frame 4)",
        100.0 * smear_into_before,
        100.0 * smear_into_after
    );
    assert!(
        smear_into_before <= 0.05 && smear_into_after <= 0.05,
        "changed light pooled across the step: {:.1} % of frame 3's power, {:.1} % of frame 4's",
        100.0 * smear_into_before,
        100.0 * smear_into_after
    );
    // Far from the step, frame 3 keeps the frames before it: sides whose light changes
    // by less than 5 % at the step (the spatially pooled statistic also cuts sides within
    // `change_radius` of a change, and the sphere moves, so not all of them) mostly pool
    // frames 0–3.
    let short3 = weighted_fraction(&steady, |s| info[3].window[s].0 != 0);
    eprintln!(
        "steady sides of frame 3 without frames 0–2: {:.1} %",
        100.0 * short3
    );
    assert!(
        short3 <= 0.2,
        "steady sides lost frames before the step: {:.1} %",
        100.0 * short3
    );
}

/// On a static scene the centred window is whole: 2K + 1 frames around a middle frame,
/// cut short only by the ends of the render list, for at least 95 % of the power (the
/// change test runs ~10 tests per side at 3σ and a 2 % visibility threshold, so a few
/// sides cut by noise are expected: measured ≤ 1.7 % per frame with the default
/// `change_radius` 2.5, ≤ 0.5 % with 5; 5 % is the margin).
#[test]
fn spacetime_window_is_whole_on_a_static_scene() {
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::techniques::spacetime_dept::{SpacetimeDept, SpacetimeSettings};
    let frames: Vec<u32> = (0..9).collect();
    let mut src = crate::source(cornell_box(), 8, 8, 24.0, frames.clone());
    let mut st = SpacetimeDept::new(SpacetimeSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 1,
            ..SpacetimeSettings::default().common
        },
        elements: 30.0,
        photons: 40_000,
        window: 3,
        // The sliding window's change test is what is tested.
        still_set: false,
        ..Default::default()
    });
    for f in frames {
        st.render_frame(&mut src, f, &|_| {});
        let info = st.info.as_ref().expect("frame info");
        let whole = (f.saturating_sub(3), (f + 3).min(8));
        let sides: Vec<(usize, f32)> = (0..info.window.len())
            .map(|s| {
                (
                    s,
                    info.area[s / 2] * chronolux_core::color::luminance(info.irradiance[s]),
                )
            })
            .filter(|s| s.1 > 0.0)
            .collect();
        let cut = weighted_fraction(&sides, |s| info.window[s] != whole);
        eprintln!(
            "frame {f}: {:.2} % of the power with a cut window",
            100.0 * cut
        );
        assert!(
            cut <= 0.05,
            "frame {f}: {:.1} % of the power with a cut window",
            100.0 * cut
        );
    }
}

/// Pixels of `scene` whose centre and four corners all see the material `name` first
/// (interior pixels of an object: no anti-aliasing against its background).
fn pixels_of_material(scene: &chronolux_core::scene::frame::FrameScene, name: &str) -> Vec<usize> {
    pixels_where(scene, |m| m == name)
}

/// Pixels of `scene` whose centre and four corners all see a material whose name passes
/// `keep`.
fn pixels_where(
    scene: &chronolux_core::scene::frame::FrameScene,
    keep: impl Fn(&str) -> bool,
) -> Vec<usize> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let sees = |x: f32, y: f32| {
        let ray = scene.camera.generate_ray(glam::Vec2::new(x, y));
        scene.intersect(&ray).is_some_and(|hit| {
            let si = scene.interaction(&hit, &ray);
            keep(&scene.materials[si.material as usize].name)
        })
    };
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32, y as f32);
            let corners = [
                (0.5, 0.5),
                (0.01, 0.01),
                (0.99, 0.01),
                (0.01, 0.99),
                (0.99, 0.99),
            ];
            if corners.iter().all(|(dx, dy)| sees(fx + dx, fy + dy)) {
                out.push((y * w + x) as usize);
            }
        }
    }
    out
}

/// The pixel indices (row-major) of each 8×8 block of a `w`×`w` image, `w` a multiple of 8,
/// blocks in row-major order.
fn blocks_8x8(w: u32) -> Vec<Vec<usize>> {
    let (w, n) = (w as usize, w as usize / 8);
    (0..n * n)
        .map(|k| {
            let (bx, by) = (k % n, k / n);
            (0..64)
                .map(|j| (by * 8 + j / 8) * w + bx * 8 + j % 8)
                .collect()
        })
        .collect()
}

/// Mean (channel average) of each group of pixels, from two independent renders `a`, `b`:
/// the groups' means of (a + b)/2 and their standard errors, from the per-pixel estimate
/// (a − b)²/4 of the variance of (a + b)/2 (unbiased for independent renders).
fn group_means(a: &[glam::Vec3], b: &[glam::Vec3], groups: &[Vec<usize>]) -> Vec<(f64, f64)> {
    let v = |p: glam::Vec3| ((p.x + p.y + p.z) / 3.0) as f64;
    groups
        .iter()
        .map(|g| {
            let n = g.len() as f64;
            let (mut s, mut var) = (0.0, 0.0);
            for &i in g {
                let (x, y) = (v(a[i]), v(b[i]));
                s += 0.5 * (x + y);
                var += 0.25 * (x - y) * (x - y);
            }
            (s / n, var.sqrt() / n)
        })
        .collect()
}

/// The demo's rough-metal sphere (GGX α = 0.09) reflects the room: `dept` continues eye
/// paths through it to the next diffuse surface and agrees with the path tracer there,
/// where reading the elements as uniform light at the sphere itself (`max_glossy = 0`,
/// the old view) gives a flat grey ball that does not.
///
/// Compared: the mean of the sphere's interior pixels in 4 horizontal bands (the upper
/// bands reflect the ceiling and the lamp, the lower ones the lit floor), each method
/// rendered twice with independent seeds, which gives every band's standard error.
/// Tolerance per band: 4 standard errors of the difference (noise; 4 bands, so a false
/// failure has probability < 3·10⁻⁴) plus `BIAS` of the path tracer's value, the element
/// bias of what the sphere reflects (see the constant).
#[test]
fn dept_metal_sphere_agrees_with_path_tracing() {
    let scene = frame0(chronolux_core::scene::stage::demo(), 64, 64);
    let sphere = pixels_of_material(&scene, "metal");
    assert!(sphere.len() >= 40, "{} sphere pixels", sphere.len());
    let path = |seed| {
        PathTracer::new(PathSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 512,
                seed,
                ..PathSettings::default().common
            },
            ..Default::default()
        })
        .render(&scene, 0, &|_| {})
        .pixels
    };
    let dept = |seed, max_glossy| {
        let img = Dept::new(DeptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 128,
                seed,
                ..DeptSettings::spatial().common
            },
            photons: 1_000_000, // The bias allowance below is derived at 100 elements per diagonal.
            elements: 100.0,
            max_glossy,
            ..DeptSettings::spatial()
        })
        .render(&scene, 0, &|_| {});
        assert_eq!(img.invalid_samples, 0);
        img.pixels
    };
    // 4 horizontal bands of equal pixel count, top to bottom.
    let bands: Vec<Vec<usize>> = sphere
        .chunks(sphere.len().div_ceil(4))
        .map(<[usize]>::to_vec)
        .collect();
    let reference = group_means(&path(1), &path(2), &bands);
    let glossy = group_means(&dept(1, 2), &dept(2, 2), &bands);
    let flat = group_means(&dept(1, 0), &dept(2, 0), &bands);
    // Bias allowance: what the sphere reflects is read from the elements at the next
    // diffuse hit; on the Cornell box (one-sided lamp) `dept` at 100 elements agrees
    // with the path tracer within 0.5 % per block and 1.5 % on the image mean
    // (`dept_converges_to_path_tracing_on_the_cornell_box`, its documentation), and the
    // spatial Gaussian (2.5 elements) adds its blur at the room's corners: 5 %.
    const BIAS: f64 = 0.05;
    let mut flat_fails = 0;
    for (k, ((r, g), f)) in reference.iter().zip(&glossy).zip(&flat).enumerate() {
        let tol = |x: &(f64, f64)| 4.0 * (x.1 * x.1 + r.1 * r.1).sqrt() + BIAS * r.0;
        eprintln!(
            "band {k}: path {:.4} ± {:.4}, dept {:.4} ± {:.4}, flat {:.4} ± {:.4}",
            r.0, r.1, g.0, g.1, f.0, f.1
        );
        assert!(
            (g.0 - r.0).abs() <= tol(g),
            "band {k}: dept {} vs path {} (tolerance {})",
            g.0,
            r.0,
            tol(g)
        );
        if (f.0 - r.0).abs() > tol(f) {
            flat_fails += 1;
        }
    }
    // The test can tell: the flat reading fails it.
    assert!(
        flat_fails > 0,
        "the flat reading passes too: the test cannot tell"
    );
}

/// `spacetime-dept` pools each pixel's light over past frames only where the animation
/// leaves its paths unchanged: on the demo at 4 fps (the glossy cube moves 0.15 room
/// half-widths per frame, so its shadow and its pixels change from frame to frame) the
/// direct light of frame 6, pooled over frames 0–6, agrees per 8×8 block with a
/// 256-spp render of frame 6 alone — a wrongly pooled pixel would carry the cube or its
/// shadow from an earlier frame. Compared: the pixels that see a diffuse surface in
/// frame 6 (the rough metal's and the glossy cube's light-sampled highlights are
/// heavy-tailed at a few samples: a two-seed standard error misses their rare large
/// values, and own-frame 4-spp renders of them alone were measured 4.8 standard errors
/// off over six seeds). Tolerance: 4 standard errors of the difference per block (each
/// method rendered with two seeds; ≤ 16 blocks, so a false failure has probability
/// < 10⁻³); no bias term, since pooled samples of an unchanged pixel have the same
/// distribution as the frame's own. And it does pool: more than twice the frame's own
/// samples on average, fewer than all 7 frames' (the moving cube's surroundings are
/// refused).
#[test]
fn spacetime_dept_reuses_pixel_light_only_where_nothing_changed() {
    pooled_light_agrees_with_the_frames_own(chronolux_core::scene::stage::demo());
}

/// The demo lit by a sun instead of its lamp (ceiling and lamp removed; a directional
/// light from above and behind the camera, 21° off the vertical towards the back wall):
/// a sun has no position, so before its shadow rays were bounded by a half-cylinder
/// towards it (`dept::reuse`), no pixel pooled light while the cube moved. Now the same
/// test as the lamp-lit demo's above: pooled where the cube stays off a pixel's camera
/// and shadow rays (more than twice the frame's own samples on average: it failed there
/// before, with exactly the frame's own 4), and in agreement with the frame's own light
/// per 8×8 block (a cube or shadow carried from an earlier frame would not be).
#[test]
fn spacetime_dept_pools_sunlight_where_the_moving_cube_stays_off_the_shadow_rays() {
    let mut d = chronolux_core::scene::stage::demo();
    let drop: Vec<NodeId> = (0..d.nodes.len() as u32)
        .map(NodeId)
        .filter(|n| ["ceiling", "ceiling_light"].contains(&d.nodes[n.0 as usize].name.as_str()))
        .collect();
    assert_eq!(drop.len(), 2, "the demo's ceiling and lamp");
    d.roots.retain(|r| !drop.contains(r));
    // A light shines along its node's −Z: turned by −1.2 rad about +X it travels along
    // (0, −0.93, −0.36), down and towards the back wall.
    d.add_light(
        "sun",
        3.0,
        LightKind::Directional,
        Trs {
            rotation: glam::Quat::from_rotation_x(-1.2),
            ..Default::default()
        },
    );
    pooled_light_agrees_with_the_frames_own(d);
}

fn pooled_light_agrees_with_the_frames_own(desc: SceneDesc) {
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::techniques::spacetime_dept::{SpacetimeDept, SpacetimeSettings};
    let (w, spp) = (32u32, 4u32);
    let run = |seed: u64, light_history: u32, spp: u32| {
        let mut src = crate::source(desc.clone(), w, w, 4.0, (0..7).collect());
        let mut st = SpacetimeDept::new(SpacetimeSettings {
            common: chronolux_render::registry::CommonSettings {
                spp,
                seed,
                ..SpacetimeSettings::default().common
            },
            light_history, // At least `light_history`: the pixel light pooled is limited to `window`.
            window: 8,
            elements: 30.0,
            photons: 5_000,
            ..Default::default()
        });
        let mut last = None;
        for f in 0..7 {
            last = Some(st.render_frame(&mut src, f, &|_| {}));
        }
        last.unwrap()
    };
    let (a, b) = (run(1, 8, spp), run(2, 8, spp));
    let pooled = a.report["light_spp"].as_f64().unwrap();
    assert!(
        pooled > 2.0 * spp as f64 && pooled < 7.0 * spp as f64,
        "mean light samples per pixel {pooled}"
    );
    let (ra, rb) = (run(1, 0, 256), run(2, 0, 256));
    let direct = |img: &chronolux_render::framework::integrator::RenderedFrame| {
        img.light.as_ref().unwrap().direct.clone()
    };
    let scene6 = crate::source(desc.clone(), w, w, 4.0, vec![6]).frame(6);
    let diffuse = pixels_where(&scene6, |m| {
        !["metal", "glass", "glossy_orange"].contains(&m)
    });
    let blocks: Vec<Vec<usize>> = blocks_8x8(w)
        .into_iter()
        .map(|b| {
            b.into_iter()
                .filter(|i| diffuse.contains(i))
                .collect::<Vec<usize>>()
        })
        .filter(|b| b.len() >= 16)
        .collect();
    assert!(blocks.len() >= 12, "{} blocks", blocks.len());
    let reused = group_means(&direct(&a), &direct(&b), &blocks);
    let alone = group_means(&direct(&ra), &direct(&rb), &blocks);
    // Under a delta light (the sun) a pixel's only noise is where its samples land (lit or
    // in shadow), and the two seeds' 256-sample renders of a shadow-edge pixel can agree to
    // the bit: its two-seed spread is then 0 and says nothing of the pooled estimate's
    // noise. For such pixels (equal in both seeds, neither dark nor at the block's
    // brightest) the noise of a mean of at least `spp` samples of values in [0, max] is
    // bounded by max / (2 √spp): added in quadrature, per block.
    let (dr, drb) = (direct(&ra), direct(&rb));
    let v = |p: glam::Vec3| ((p.x + p.y + p.z) / 3.0) as f64;
    let edge_floor: Vec<f64> = blocks
        .iter()
        .map(|g| {
            let max = g.iter().map(|&i| v(dr[i])).fold(0.0, f64::max);
            let edges = g
                .iter()
                .filter(|&&i| {
                    let (x, y) = (v(dr[i]), v(drb[i]));
                    x == y && x > 1e-3 * max && x < 0.999 * max
                })
                .count();
            max * (edges as f64 / (4.0 * spp as f64)).sqrt() / g.len() as f64
        })
        .collect();
    // Plus f32 rounding: a fully lit pixel is a sum of up to 256 equal samples divided by
    // their count (relative error ≲ 256 · 2⁻²⁴ ≈ 1.5·10⁻⁵), and the two means of such a
    // block differ by that alone.
    let tolerance = |k: usize, x: &(f64, f64), r: &(f64, f64)| {
        4.0 * (x.1 * x.1 + r.1 * r.1 + edge_floor[k] * edge_floor[k]).sqrt() + 2e-5 * r.0.abs()
    };
    for (k, (x, r)) in reused.iter().zip(&alone).enumerate() {
        eprintln!(
            "block {k}: pooled {:.5} ± {:.5}, alone {:.5} ± {:.5}, edge floor {:.5}, z {:.2}",
            x.0,
            x.1,
            r.0,
            r.1,
            edge_floor[k],
            4.0 * (x.0 - r.0) / tolerance(k, x, r)
        );
    }
    for (k, (x, r)) in reused.iter().zip(&alone).enumerate() {
        let tol = tolerance(k, x, r);
        assert!(
            (x.0 - r.0).abs() <= tol,
            "block {k}: pooled {} vs alone {} (tolerance {tol})",
            x.0,
            r.0
        );
    }
}

/// Neighbour lists carried from frame to frame (`Neighbours::update`: only rows within
/// the radius of a moving element are rebuilt) are identical, row order and squared
/// distances bit for bit, to lists built from scratch, on the caustic stage whose sphere
/// moves and whose occluder enters (frames 0 → 1 → 4 → 5 → 0, steps of one and three
/// frames and back), and they rebuild some rows but not all (the room is static; the
/// sphere and the occluder are large at 30 elements per diagonal: 37–53 % measured).
#[test]
fn neighbour_lists_updated_across_frames_equal_rebuilt_ones() {
    use chronolux_core::scene::stage::caustic;
    use chronolux_render::kernels::elements::reconstruct::Neighbours;
    let mut src = crate::source(caustic(), 8, 8, 24.0, (0..6).collect());
    let mesh = ElementMesh::build(&src.frame(0), 30.0);
    for radius in [2.5, 5.0] {
        let r = radius * mesh.element_size;
        let mut fe_old = FrameElements::new(&src.frame(0), &mesh);
        let mut nb = Neighbours::new(&fe_old, r);
        for g in [1, 4, 5, 0] {
            let fe = FrameElements::new(&src.frame(g), &mesh);
            let updated = nb.clone().update(&fe_old, &fe);
            let fresh = Neighbours::new(&fe, r);
            let n = fe.area.len();
            for e in 0..n {
                let bits = |row: &[(u32, f32)]| -> Vec<(u32, u32)> {
                    row.iter().map(|&(j, d2)| (j, d2.to_bits())).collect()
                };
                assert_eq!(
                    bits(updated.of(e)),
                    bits(fresh.of(e)),
                    "radius {radius}, frame {g}, element {e}"
                );
                let gb = |g: &[f32]| g.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(gb(updated.gauss(e)), gb(fresh.gauss(e)));
            }
            eprintln!(
                "radius {radius}, frame {g}: {} of {n} rows rebuilt",
                updated.rebuilt()
            );
            assert!(
                updated.rebuilt() > 0 && updated.rebuilt() < n,
                "radius {radius}, frame {g}: {} of {n} rows rebuilt",
                updated.rebuilt()
            );
            (fe_old, nb) = (fe, updated);
        }
    }
}

/// The temporal range kernel of `spacetime-dept` (`temporal_weight`, κ = 2, temporal
/// Gaussian σ = 8 frames, whole centred windows of 2K + 1 frames):
/// - **a step of any size is smeared by at most a noise-sized amount**: output frame f
///   just before a noise-free step Δ (all frames after f at 1 + Δ, the rest at 1, each
///   frame's statistic with variance σ², so σ_Δ = √2 σ) pools
///   `Σ_after g r Δ / Σ g r`, and since `Δ · exp(−Δ² / 2κ²σ_Δ²) ≤ κ σ_Δ e^(−1/2)` for every
///   Δ, its error is at most `κ σ_Δ e^(−1/2) · Σ_after g / Σ_before g` (the derived bound,
///   checked for Δ from 0.1 σ_Δ to 1000 σ_Δ), where flat weights smear Δ · Σ_after g / Σ g;
///   beyond 10 σ_Δ the range kernel's smear is below 1e-3 of the flat one
///   (`exp(−100 / 8)` ≈ 4e-6 per frame);
/// - **static light keeps ~1/N noise**: pooled values with noise σ_x per frame and a change
///   statistic with independent noise (it is pooled over ~20 elements, so nearly
///   independent of one element's sums) have variance `σ_x² Σg² / (Σg)² · E[r²] / E[r]²`
///   with `E[r] = 1/√(1 + 1/κ²)`, `E[r²] = 1/√(1 + 2/κ²)` (r = exp(−z²/2κ²), z ~ N(0, 1)):
///   1.05 σ_x² / N for κ = 2, so the variance still falls as 1/N with the window. Checked
///   over 20 000 trials for N = 5, 9, 17 within ±8 % (Monte-Carlo error of a variance over
///   20 000 trials ≈ √(2/20000) = 1 %; the formula ignores that the centre frame's weight
///   is 1 and that all weights share S_f: 0.6 % measured in a Python model).
#[test]
fn temporal_range_kernel_bounds_a_step_and_keeps_static_noise_falling_as_one_over_n() {
    use chronolux_core::sampling::rng::Pcg32;
    use chronolux_render::techniques::spacetime_dept::temporal_weight;
    let (kappa, sigma_t) = (2.0f32, 8.0f32);
    let gauss = |dt: f32| (-dt * dt / (2.0 * sigma_t * sigma_t)).exp();
    // Step.
    let k = 8usize;
    let n = 2 * k + 1;
    let sigma = 0.02f32;
    let sigma_d = 2f32.sqrt() * sigma;
    let g: Vec<f32> = (0..n).map(|i| gauss(i as f32 - k as f32)).collect();
    let (before, after): (f32, f32) = (g[..=k].iter().sum(), g[k + 1..].iter().sum());
    let bound = kappa * sigma_d * (-0.5f32).exp() * after / before;
    for step in 0..=40 {
        let delta = sigma_d * 10f32.powf(-1.0 + step as f32 / 10.0);
        let s: Vec<f32> = (0..n)
            .map(|i| if i > k { 1.0 + delta } else { 1.0 })
            .collect();
        let w: Vec<f32> = (0..n)
            .map(|i| temporal_weight(g[i], (s[i], sigma * sigma), (s[k], sigma * sigma), kappa))
            .collect();
        let pooled: f32 = w.iter().zip(&s).map(|(a, b)| a * b).sum::<f32>() / w.iter().sum::<f32>();
        let (smear, flat) = (pooled - 1.0, delta * after / (before + after));
        assert!(
            smear <= bound * 1.0001 + 1e-6,
            "Δ = {:.2} σ_Δ: smear {smear} above the bound {bound}",
            delta / sigma_d
        );
        if delta >= 10.0 * sigma_d {
            assert!(
                smear < 1e-3 * flat,
                "Δ = {:.1} σ_Δ: smear {smear}",
                delta / sigma_d
            );
        }
    }
    // Static light.
    let mut rng = Pcg32::new(17, 3);
    let mut normal = move || {
        let (u1, u2) = (rng.next_f32().max(1e-7), rng.next_f32());
        (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
    };
    let (sx, ss) = (0.05f32, 0.02f32);
    let er = 1.0 / (1.0 + 1.0 / (kappa * kappa) as f64).sqrt();
    let er2 = 1.0 / (1.0 + 2.0 / (kappa * kappa) as f64).sqrt();
    for k in [2usize, 4, 8] {
        let n = 2 * k + 1;
        let g: Vec<f32> = (0..n).map(|i| gauss(i as f32 - k as f32)).collect();
        let (sg, sg2) = (
            g.iter().map(|&x| x as f64).sum::<f64>(),
            g.iter().map(|&x| (x * x) as f64).sum::<f64>(),
        );
        let predicted = (sx * sx) as f64 * sg2 / (sg * sg) * er2 / (er * er);
        let trials = 20_000;
        let (mut m, mut m2) = (0.0f64, 0.0f64);
        for _ in 0..trials {
            let x: Vec<f32> = (0..n).map(|_| 1.0 + sx * normal()).collect();
            let s: Vec<f32> = (0..n).map(|_| 1.0 + ss * normal()).collect();
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for i in 0..n {
                let w = temporal_weight(g[i], (s[i], ss * ss), (s[k], ss * ss), kappa) as f64;
                num += w * x[i] as f64;
                den += w;
            }
            let p = num / den;
            m += p;
            m2 += p * p;
        }
        let mean = m / trials as f64;
        let var = m2 / trials as f64 - mean * mean;
        let ratio = var / predicted;
        eprintln!(
            "N = {n}: variance × N / σ² = {:.3} (predicted {:.3}), ratio {ratio:.3}",
            var * n as f64 / (sx * sx) as f64,
            predicted * n as f64 / (sx * sx) as f64
        );
        assert!((0.92..=1.08).contains(&ratio), "N = {n}: ratio {ratio}");
        assert!(
            (mean - 1.0).abs() < 4.0 * (var / trials as f64).sqrt(),
            "N = {n}: static light biased: {mean}"
        );
    }
}

/// The adaptive spatial support of `spacetime-dept` (`adaptive_sigma2`) follows the
/// photon density: on the Cornell floor with photons spread at density ρ on one half and
/// 2.25 ρ on the other, chosen so that the σ₀ kernel holds `target / 1.5` and
/// `1.5 · target` photons (a Gaussian over a plane of density ρ holds ρ · 2πσ₀²), the
/// support grows to σ² = 1.5 σ₀² on the sparse half and shrinks to σ₀² / 1.5 on the dense
/// half (σ² ∝ 1 / density: the kernel then holds `target` photons on both), within 10 %
/// at elements farther than the list radius from the density step and the walls (the
/// lists are cut at 2√2 σ₀, which drops e^(−4) = 1.8 % of the Gaussian's mass, and the
/// sum over element centroids approximates the integral to a few %). An element side
/// with no photons around it gets the widest support, `ADAPTIVE_RANGE` · σ₀².
#[test]
fn adaptive_support_follows_the_photon_density() {
    use chronolux_render::kernels::elements::reconstruct::{
        ADAPTIVE_LIST_RADIUS, ADAPTIVE_RANGE, Neighbours, adaptive_sigma2,
    };
    let scene = frame0(cornell_box(), 8, 8);
    let mesh = ElementMesh::build(&scene, 50.0);
    let fe = FrameElements::new(&scene, &mesh);
    let sigma0 = 1.25 * mesh.element_size;
    let r_list = 2.0 * sigma0 * ADAPTIVE_LIST_RADIUS;
    let nb = Neighbours::new(&fe, r_list);
    let floor_y = (0..fe.area.len())
        .filter(|&e| fe.normal[e].y > 0.99 && fe.area[e] > 0.0)
        .map(|e| fe.centroid[e].y)
        .fold(f32::INFINITY, f32::min);
    let floor: Vec<usize> = (0..fe.area.len())
        .filter(|&e| {
            fe.normal[e].y > 0.99 && fe.area[e] > 0.0 && (fe.centroid[e].y - floor_y).abs() < 1e-4
        })
        .collect();
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &e in &floor {
        lo = lo.min(fe.centroid[e]);
        hi = hi.max(fe.centroid[e]);
    }
    let xmid = 0.5 * (lo.x + hi.x);
    let target = 32.0f32;
    let rho = target / (1.5 * std::f32::consts::TAU * sigma0 * sigma0);
    let mut count = vec![0.0f32; 2 * fe.area.len()];
    for &e in &floor {
        let d = if fe.centroid[e].x < xmid {
            rho
        } else {
            2.25 * rho
        };
        count[2 * e] = d * fe.area[e];
        count[2 * e + 1] = d * fe.area[e];
    }
    let s2 = adaptive_sigma2(&nb, &count, sigma0, target);
    let interior = |e: usize| {
        let c = fe.centroid[e];
        (c.x - xmid).abs() > r_list
            && c.x - lo.x > r_list
            && hi.x - c.x > r_list
            && c.z - lo.z > r_list
            && hi.z - c.z > r_list
    };
    let (mut sparse, mut dense) = (0, 0);
    for &e in floor.iter().filter(|&&e| interior(e)) {
        let (f, want) = if fe.centroid[e].x < xmid {
            sparse += 1;
            (s2[2 * e] / (sigma0 * sigma0), 1.5)
        } else {
            dense += 1;
            (s2[2 * e] / (sigma0 * sigma0), 1.0 / 1.5)
        };
        assert!(
            (f / want - 1.0).abs() < 0.1,
            "element {e} at x = {}: σ²/σ₀² = {f}, expected {want}",
            fe.centroid[e].x
        );
    }
    assert!(
        sparse > 20 && dense > 20,
        "{sparse} {dense} interior elements"
    );
    // No photons anywhere near (the ceiling): the widest support.
    let ceiling = (0..fe.area.len())
        .find(|&e| fe.normal[e].y < -0.99 && fe.area[e] > 0.0)
        .expect("a ceiling element");
    assert_eq!(s2[2 * ceiling], ADAPTIVE_RANGE * sigma0 * sigma0);
}

/// Under a sky (InterpolationTest, made Lambertian, has no lights: the default environment
/// is added), the DEPT eye pass takes direct light at a diffuse surface by MIS of a light
/// sample and the BSDF sample (light samples alone were noisy for a sky: BENCHMARKS.md,
/// "Issue 17: the default"). Both halves are unbiased for the direct light, so its mean per 8×8 block
/// agrees with the path tracer's direct light (same split convention) within 4 standard
/// errors of the difference (each method rendered with two seeds; 16 blocks, so a false
/// failure has probability < 10⁻³) and no bias term. A missing half of the MIS (weights
/// summing to less than 1) or a double count (more than 1) shifts every lit block by the
/// BSDF-sampled share of the sky, far beyond that.
#[test]
fn dept_direct_light_under_a_sky_agrees_with_path_tracing() {
    let Some(path) = chronolux_core::testing::shared_file("scenes/InterpolationTest.glb") else {
        return;
    };
    let mut desc = chronolux_io::gltf::load(&path).unwrap();
    assert!(desc.environment.is_some(), "the default sky");
    // Lambertian only (no specular layer), so that the camera rays' first hits are read as
    // diffuse surfaces, where the MIS is (a glossy surface continues the path instead).
    for m in &mut desc.materials {
        m.specular = 0.0;
        m.metallic = 0.0;
    }
    let w = 32u32;
    let scene = frame0(desc, w, w);
    let direct = |img: chronolux_render::framework::integrator::RenderedFrame| {
        img.light.expect("a light split").direct
    };
    let pt = |seed| {
        direct(
            PathTracer::new(PathSettings {
                common: chronolux_render::registry::CommonSettings {
                    spp: 256,
                    seed,
                    ..PathSettings::default().common
                },
                ..Default::default()
            })
            .render(&scene, 0, &|_| {}),
        )
    };
    let dept = |seed| {
        let img = Dept::new(DeptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 64,
                seed,
                ..DeptSettings::spatial().common
            },
            photons: 20_000,
            ..DeptSettings::spatial()
        })
        .render(&scene, 0, &|_| {});
        assert_eq!(img.invalid_samples, 0);
        direct(img)
    };
    let blocks = blocks_8x8(w);
    let reference = group_means(&pt(1), &pt(2), &blocks);
    let ours = group_means(&dept(1), &dept(2), &blocks);
    for (k, (x, r)) in ours.iter().zip(&reference).enumerate() {
        let tol = 4.0 * (x.1 * x.1 + r.1 * r.1).sqrt();
        eprintln!(
            "block {k}: dept {:.5} ± {:.5}, path {:.5} ± {:.5}",
            x.0, x.1, r.0, r.1
        );
        assert!(
            (x.0 - r.0).abs() <= tol,
            "block {k}: dept {} vs path {} (tolerance {tol})",
            x.0,
            r.0
        );
    }
}

/// `spacetime-dept` renders a frame as `path` only where it cannot gain (module doc,
/// "When it renders as `path`"), decided from the animation and the path probe alone:
/// - the demo's sliding block alone under a uniform sky (the room, lamp and spheres
///   removed): no per-pixel light can be pooled while the block moves under a light at
///   infinity, and a convex object under a sky has no indirect light at all (every ray
///   leaving it reaches the sky, which counts as direct), so the probe's variance ratio
///   is exactly 1 and every frame is `path`'s frame bit for bit, with `rendered_as`
///   "path" in its report;
/// - the demo itself (lamp-lit, static camera): every frame can pool light with its
///   neighbours, so none is probed; its frame 0 rendered alone has no frame to pool
///   with, is probed and stays `spacetime-dept` (the room's interreflection and the
///   glass sphere's caustic make path tracing's noise several times its direct light's:
///   3.5 measured at 96², the limit is 1.1).
#[test]
fn spacetime_dept_renders_as_path_only_where_the_probe_finds_nothing_to_gain() {
    use chronolux_core::light::Environment;
    use chronolux_core::scene::stage::demo;
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::kernels::probe::MAX_PATH_RATIO;
    use chronolux_render::techniques::spacetime_dept::{SpacetimeDept, SpacetimeSettings};
    let (w, spp, seed) = (24u32, 4u32, 7u64);
    let settings = SpacetimeSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            seed,
            ..SpacetimeSettings::default().common
        },
        photons: 2_000,
        elements: 20.0,
        ..Default::default()
    };
    let mut sky = demo();
    for n in &mut sky.nodes {
        if n.name != "sliding_cube" {
            n.mesh = None;
        }
        n.light = None;
    }
    sky.lights.clear();
    sky.environment = Some(Environment::uniform(Rgb::new(0.8, 0.9, 1.0)));
    let frames: Vec<u32> = (0..4).collect();
    let mut src = crate::source(sky, w, w, 24.0, frames.clone());
    let mut st = SpacetimeDept::new(settings.clone());
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            seed,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let mut lit = 0usize;
    for &f in &frames {
        let img = st.render_frame(&mut src, f, &|_| {});
        let p = &img.report["path_probe"];
        assert_eq!(p["rendered_as"], "path", "frame {f}: {p}");
        let ratio = p["variance_ratio"].as_f64().unwrap();
        assert!((ratio - 1.0).abs() < 1e-9, "frame {f}: ratio {ratio}");
        let reference = pt.render(&src.frame(f), f, &|_| {});
        assert_eq!(
            crate::bits(&img.pixels),
            crate::bits(&reference.pixels),
            "frame {f}"
        );
        lit += img.pixels.iter().filter(|p| p.x > 0.0).count();
    }
    assert!(lit > 0, "the block is in view");

    // The demo: every frame can pool light with its neighbours, so none is probed.
    let mut src = crate::source(demo(), w, w, 24.0, frames.clone());
    let mut st = SpacetimeDept::new(settings.clone());
    for &f in &frames[..3] {
        let img = st.render_frame(&mut src, f, &|_| {});
        assert!(
            !img.report.contains_key("path_probe"),
            "frame {f} can pool light but was probed"
        );
        assert!(
            img.report.contains_key("photons"),
            "frame {f} traced no photons"
        );
    }
    // Its frame 0 alone: nothing to pool with, so it is probed, and stays.
    let mut src = crate::source(demo(), w, w, 24.0, vec![0]);
    let img = SpacetimeDept::new(settings).render_frame(&mut src, 0, &|_| {});
    let p = &img.report["path_probe"];
    assert_eq!(p["rendered_as"], "spacetime-dept", "{p}");
    assert!(
        p["variance_ratio"].as_f64().unwrap() > MAX_PATH_RATIO,
        "{p}"
    );
    assert!(img.report.contains_key("photons"));
}

/// Settings of the still-set tests: a small window so that the sliding solution's window
/// (2K + 1 = 5 frames) is whole in the middle of a 9-frame list, flat temporal weights
/// (σ = 10⁶ frames: every weight is exactly 1 in f32), no per-pixel light reuse.
fn still_settings(
    still_set: bool,
) -> chronolux_render::techniques::spacetime_dept::SpacetimeSettings {
    use chronolux_render::techniques::spacetime_dept::SpacetimeSettings;
    SpacetimeSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 2,
            ..SpacetimeSettings::default().common
        },
        elements: 30.0,
        photons: 20_000,
        window: 2,
        temporal_sigma: 1e6,
        light_history: 0,
        path_probe: false,
        still_set,
        ..Default::default()
    }
}

/// Under a camera that moves through a still set (`builtin:flythrough`: the dolly's camera,
/// nothing else moving) every frame reads one still solution (module documentation of
/// `spacetime_dept`, "Still sets"): traced in the first frame only, the same element
/// irradiance bit for bit in every frame, with the whole window's photons (2K + 1 = 5
/// frames of 20k). It is the sliding window's estimate: the middle frame's sliding
/// window pools frames 2..=6, i.e. photons 40k..140k with weight 1, the still solution
/// photons 0..100k of the same scene, so the two are independent estimates with equal
/// photon counts and the same filters. Their power-weighted mean relative difference per
/// element side is bounded by the noise of two such estimates: each side's estimate has a
/// relative standard error ≈ 1/√(photons it pools) (after the spatial filter, ≥ 30 photons
/// on the lit sides: σ_rel ≲ 0.18, difference of two ≲ 0.26), so the power-weighted mean of
/// |Δ|/E is below 0.26·√(2/π) ≈ 0.21 for unbiased estimates (measured 0.039) — a biased
/// still solution (wrong normalisation, e.g. counting 1 frame's photons for 5) would be off
/// by a factor, ≥ 0.8 of E. The totals (power over all sides) agree much closer: ≤ 3 %
/// (≥ 10⁴ indirect deposits each, σ_rel ≈ 1 %, 3σ; measured 0.4 %).
#[test]
fn spacetime_dept_reads_one_still_solution_under_a_moving_camera() {
    use chronolux_core::color::luminance;
    use chronolux_core::scene::stage::flythrough;
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::techniques::spacetime_dept::SpacetimeDept;
    let frames: Vec<u32> = (0..9).collect();
    let run = |still: bool| {
        let mut src = crate::source(flythrough(), 16, 16, 24.0, frames.clone());
        let mut st = SpacetimeDept::new(still_settings(still));
        let mut out = Vec::new();
        for &f in &frames {
            let img = st.render_frame(&mut src, f, &|_| {});
            let info = st.info.clone().expect("frame info");
            out.push((img, info));
        }
        out
    };
    let still = run(true);
    for (f, (img, info)) in still.iter().enumerate() {
        let r = &img.report["still_set"];
        assert_eq!(r["photons"], 100_000, "frame {f}: {r}");
        assert_eq!(r["traced_here"], f == 0, "frame {f}: {r}");
        let bits: Vec<[u32; 3]> = info
            .irradiance
            .iter()
            .map(|c| c.to_array().map(f32::to_bits))
            .collect();
        let first: Vec<[u32; 3]> = still[0]
            .1
            .irradiance
            .iter()
            .map(|c| c.to_array().map(f32::to_bits))
            .collect();
        assert_eq!(bits, first, "frame {f}: the still solution changed");
    }
    let sliding = run(false);
    assert!(sliding[4].0.report.get("still_set").is_none());
    let (a, b) = (&still[4].1, &sliding[4].1);
    let (mut w, mut d, mut ta, mut tb) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for s in 0..a.irradiance.len() {
        let (ea, eb) = (
            luminance(a.irradiance[s]) as f64,
            luminance(b.irradiance[s]) as f64,
        );
        let area = a.area[s / 2] as f64;
        ta += area * ea;
        tb += area * eb;
        if eb > 0.0 {
            w += area * eb;
            d += area * (ea - eb).abs();
        }
    }
    let (mean_rel, total_rel) = (d / w, (ta - tb).abs() / tb);
    eprintln!("still vs sliding: power-weighted |Δ|/E {mean_rel:.4}, totals {total_rel:.4}");
    assert!(mean_rel < 0.21, "{mean_rel}");
    assert!(total_rel < 0.03, "{total_rel}");
}

/// The still solution depends only on the set, so a farm segment (its render list starts
/// later, with context frames) renders a frame bit for bit as the single run does, and so
/// does a run on another thread count.
#[test]
fn spacetime_still_solution_is_the_same_in_a_segment_and_on_any_thread_count() {
    use chronolux_core::scene::stage::flythrough;
    use chronolux_render::framework::sequence::SequenceRenderer;
    use chronolux_render::techniques::spacetime_dept::SpacetimeDept;
    let render = |list: Vec<u32>, threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut src = crate::source(flythrough(), 16, 16, 24.0, list.clone());
                let mut st = SpacetimeDept::new(still_settings(true));
                let mut img = None;
                for &f in list.iter().filter(|&&f| f <= 5) {
                    img = Some(st.render_frame(&mut src, f, &|_| {}));
                }
                img.expect("frame 5 rendered")
            })
    };
    let single = render((0..12).collect(), 1);
    let segment = render((3..9).collect(), 1);
    let threads = render((0..12).collect(), 3);
    assert!(single.report.get("still_set").is_some());
    assert_eq!(crate::bits(&single.pixels), crate::bits(&segment.pixels));
    assert_eq!(crate::bits(&single.pixels), crate::bits(&threads.pixels));
}
