//! Bidirectional path tracing: closed-form furnace, statistical agreement with the path
//! tracer (the reference) on the demo and on a point-light scene with a glass sphere, and
//! bit-identical images across thread counts.

use crate::frame0;
use chronolux_core::color::Rgb;
use chronolux_core::light::Environment;
use chronolux_core::math::{Quat, Vec3};
use chronolux_core::scene::desc::{
    LightKind, Material, Mesh, MeshId, Node, NodeId, SceneDesc, Trs,
};
use chronolux_core::scene::stage;
use chronolux_core::scene::testing::furnace;
use chronolux_core::testing::{Estimate, block_z_test, channel_means};
use chronolux_render::framework::integrator::{Integrator, RenderedFrame};
use chronolux_render::kernels::bdpt::{Bdpt, BdptSettings, MisHeuristic};
use chronolux_render::kernels::path::{PathSettings, PathTracer};

fn bdpt(spp: u32, max_depth: Option<u32>, mis: MisHeuristic) -> Bdpt {
    Bdpt::new(BdptSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            max_depth,
            ..BdptSettings::default().common
        },
        mis,
        ..Default::default()
    })
}

fn pt(spp: u32, max_depth: Option<u32>) -> PathTracer {
    PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            max_depth,
            ..PathSettings::default().common
        },
        ..Default::default()
    })
}

/// Image mean over pixels and channels, and its standard error from the film's per-pixel
/// variances (pixels are independent: each has its own sample stream; splats add
/// cross-pixel terms whose covariance is neglected, they are a small share).
fn mean_se(img: &RenderedFrame) -> (f64, f64) {
    let n = img.pixels.len() as f64 * 3.0;
    let m = img
        .pixels
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64)
        .sum::<f64>()
        / n;
    let v = img
        .variance
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64)
        .sum::<f64>()
        / (n * n);
    (m, v.sqrt())
}

#[test]
fn furnace_bdpt_converges_to_le_over_one_minus_a() {
    for (a, le) in [(0.5f32, 0.5f32), (0.8, 0.2)] {
        let scene = frame0(furnace(a, le), 16, 16);
        for mis in [MisHeuristic::Power, MisHeuristic::Balance] {
            let img = bdpt(32, None, mis).render(&scene, 0, &|_| {});
            assert_eq!(img.invalid_samples, 0);
            let (m, se) = mean_se(&img);
            let want = (le / (1.0 - a)) as f64;
            // 5 standard errors of the image mean (unbiased estimator, exact closed form
            // for the tessellated closed sphere), plus 1e-4 for float accumulation.
            assert!(
                (m - want).abs() < 5.0 * se + 1e-4,
                "a={a} {mis:?}: mean {m} want {want} (se {se})"
            );
        }
    }
}

#[test]
fn furnace_bdpt_depth_limit_follows_mitsuba_convention() {
    let (a, le) = (0.5f32, 1.0f32);
    let scene = frame0(furnace(a, le), 16, 16);
    for d in 1..=4u32 {
        let img = bdpt(16, Some(d), MisHeuristic::Power).render(&scene, 0, &|_| {});
        let (m, se) = mean_se(&img);
        let want: f64 = (0..d).map(|k| (le * a.powi(k as i32)) as f64).sum();
        assert!(
            (m - want).abs() < 5.0 * se + 1e-4,
            "depth {d}: mean {m} want {want} (se {se})"
        );
    }
}

/// Two unbiased estimates of the same image agree: (1) per-channel image means within 5
/// standard errors of their difference; (2) per-block z-test on 8×8-pixel blocks with
/// Šidák correction at family level 1 % (as peer.rs).
fn assert_agree(a: &RenderedFrame, b: &RenderedFrame, what: &str) {
    let ea = Estimate::new(a.width, a.height, &a.pixels, &a.variance);
    let eb = Estimate::new(b.width, b.height, &b.pixels, &b.variance);
    for (c, m) in channel_means(&ea, &eb).iter().enumerate() {
        assert!(
            (m.a - m.b).abs() < 5.0 * m.se,
            "{what}: channel {c}: {:.5} vs {:.5} (se {:.2e}, z {:.2})",
            m.a,
            m.b,
            m.se,
            m.z()
        );
        eprintln!(
            "{what}: channel {c}: {:.5} vs {:.5}, z = {:.2}",
            m.a,
            m.b,
            m.z()
        );
    }
    block_z_test(&ea, &eb, 8, 0.01).assert_passes(what);
}

/// The demo (area light, glass sphere: caustics; rough metal sphere; glossy cube): BDPT
/// and the path tracer converge to the same image.
#[test]
fn bdpt_agrees_with_path_tracer_on_the_demo() {
    let scene = frame0(stage::demo(), 32, 32);
    let reference = pt(1024, None).render(&scene, 0, &|_| {});
    let img = bdpt(256, None, MisHeuristic::Power).render(&scene, 0, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    assert_agree(&img, &reference, "demo");
    // Without the light-tracing strategies (what stbpt uses under a moving camera) the
    // remaining weights still sum to one: the same image in expectation.
    let no_lt = Bdpt::new(BdptSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 256,
            ..BdptSettings::default().common
        },
        light_tracing: false,
        ..Default::default()
    })
    .render(&scene, 0, &|_| {});
    assert_eq!(no_lt.invalid_samples, 0);
    assert_agree(&no_lt, &reference, "demo without light tracing");
}

/// The demo room lit only by a point light under the ceiling, with a small diffuse shade
/// below it so that the light sees no specular surface (paths light→glass→… have zero
/// probability for the path tracer with a point light, so only then is it a reference);
/// the glass sphere is still seen, lit indirectly, through delta refraction.
fn point_light_glass() -> SceneDesc {
    let mut d = stage::demo();
    for m in &mut d.materials {
        m.emissive = Rgb::ZERO;
    }
    let top = 2.0 * stage::ROOM_HALF;
    d.add_light(
        "point_light",
        3.0,
        LightKind::Point,
        Trs {
            translation: Vec3::new(0.0, top - 0.15, 0.0),
            ..Default::default()
        },
    );
    let mut shade = stage::cube_primitive(1.0);
    d.materials
        .push(Material::diffuse("shade", Rgb::splat(0.6)));
    shade.material = Some(chronolux_core::scene::desc::MaterialId(
        d.materials.len() as u32 - 1,
    ));
    d.meshes.push(Mesh {
        name: "shade".into(),
        primitives: vec![shade],
        weights: vec![],
    });
    let shade_node = NodeId(d.nodes.len() as u32);
    d.nodes.push(Node {
        name: "shade".into(),
        mesh: Some(MeshId(d.meshes.len() as u32 - 1)),
        transform: Trs {
            translation: Vec3::new(0.0, top - 0.25, 0.0),
            rotation: Quat::IDENTITY,
            scale: Vec3::new(0.5, 0.01, 0.5),
        },
        ..Default::default()
    });
    d.roots.push(shade_node);
    d
}

#[test]
fn bdpt_agrees_with_path_tracer_with_a_point_light_and_glass() {
    let scene = frame0(point_light_glass(), 32, 32);
    assert!(scene.lights.iter().all(|l| l.is_delta()));
    let reference = pt(1024, None).render(&scene, 0, &|_| {});
    let img = bdpt(256, None, MisHeuristic::Balance).render(&scene, 0, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    assert_agree(&img, &reference, "point light + glass");
}

#[test]
fn bdpt_bit_identical_across_thread_counts() {
    let scene = frame0(stage::demo(), 40, 24);
    let b = bdpt(4, None, MisHeuristic::Power);
    let render = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| b.render(&scene, 3, &|_| {}))
    };
    let (a, b2, c) = (render(1), render(2), render(3));
    let bits = |i: &RenderedFrame| -> Vec<[u32; 3]> {
        i.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b2));
    assert_eq!(bits(&a), bits(&c));
    assert_eq!(a.stats, b2.stats);
}

/// Lights at infinity: the demo seen with a uniform environment through the room's open
/// side (escaped camera rays, environment light subpaths starting on the scene's disk)
/// plus a spot light (delta position, cone) aimed at the floor away from the spheres.
#[test]
fn bdpt_agrees_with_path_tracer_with_environment_and_spot() {
    environment_and_spot(
        Environment::uniform(Rgb::new(0.6, 0.7, 0.9)),
        "environment + spot",
    );
}

/// The same with the default light of an unlit file: a sky-to-ground gradient (light
/// sampling, emission from infinity and escaped rays all see the direction-dependent
/// radiance) and a backdrop that only camera rays see.
#[test]
fn bdpt_agrees_with_path_tracer_with_gradient_environment_and_backdrop() {
    environment_and_spot(
        chronolux_core::scene::desc::default_environment(),
        "gradient environment + backdrop + spot",
    );
}

/// The same with an environment map (a bright patch, a dark ground, rotated): light
/// sampling and emission by the map's luminance, and BDPT's densities of light subpaths
/// from infinity and of escaped camera rays, all follow the map.
#[test]
fn bdpt_agrees_with_path_tracer_with_an_environment_map() {
    let (w, h) = (16usize, 8usize);
    let texels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if y == 2 && (5..8).contains(&x) {
                Rgb::new(30.0, 25.0, 20.0)
            } else if y < h / 2 {
                Rgb::new(0.3, 0.4, 0.8)
            } else {
                Rgb::new(0.15, 0.1, 0.05)
            }
        })
        .collect();
    let map = chronolux_core::light::EnvMap::new(w, h, texels, 1.0, 140.0).unwrap();
    environment_and_spot(Environment::from_map(map, true), "environment map + spot");
}

fn environment_and_spot(env: Environment, what: &str) {
    let mut d = stage::demo();
    d.environment = Some(env);
    d.add_light(
        "spot",
        2.0,
        LightKind::Spot {
            inner_cone: 0.2,
            outer_cone: 0.35,
        },
        Trs {
            // Above the floor's front-left, pointing straight down (local −Z to −Y).
            translation: Vec3::new(-0.5, 1.5, 0.6),
            rotation: Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
            ..Default::default()
        },
    );
    let scene = frame0(d, 32, 32);
    let reference = pt(1024, None).render(&scene, 0, &|_| {});
    let img = bdpt(256, None, MisHeuristic::Power).render(&scene, 0, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    assert_agree(&img, &reference, what);
}

/// Densities next to a delta vertex keep their geometry factor (module doc of `bdpt`,
/// "Densities through delta vertices"): on camera subpaths through the demo's glass and
/// mirror-like lobes, the vertex after a delta vertex has forward area density
/// `1 · |cos θ| / d²` (the delta lobe's density taken as 1, converted as any other), and
/// the vertex before it the same reverse density, where pbrt-v4's convention stores 0
/// (read as 1 in the weights, dropping `|cos θ| / d²`: checked by reverting it, this test
/// fails). Equality to 1e-6 relative: the same f32 operations on the same values.
#[test]
fn densities_after_a_delta_vertex_keep_their_geometry_factor() {
    use chronolux_core::sampling::sampler::PixelSampler;
    use chronolux_core::stats::Stats;
    use chronolux_render::kernels::bdpt::generate_camera_subpath;
    let scene = frame0(stage::demo(), 32, 32);
    let settings = BdptSettings::default();
    let (mut path, mut stats, mut checked) = (Vec::new(), Stats::default(), 0);
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-6 * a.abs().max(b.abs());
    for y in 0..32 {
        for x in 0..32 {
            for i in 0..4 {
                let mut sampler = PixelSampler::new(3, 0, x, y);
                sampler.start_sample(i);
                let raster = glam::Vec2::new(x as f32, y as f32) + sampler.next_2d();
                generate_camera_subpath(
                    &scene,
                    &settings,
                    raster,
                    &mut sampler,
                    &mut path,
                    &mut stats,
                );
                for k in 1..path.len().saturating_sub(1) {
                    let (prev, v, next) = (&path[k - 1], &path[k], &path[k + 1]);
                    if !v.delta || next.infinite {
                        continue;
                    }
                    assert!(
                        close(next.pdf_fwd, v.convert_density(1.0, next)),
                        "forward density after delta vertex {k}"
                    );
                    assert!(
                        close(prev.pdf_rev, v.convert_density(1.0, prev)),
                        "reverse density before delta vertex {k}"
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 100, "only {checked} delta vertices met");
}

/// [`view_split`]'s re-weighting is the MIS weight of the same path seen by another
/// camera, computed from scratch: for every strategy t ≥ 2 of many sampled paths on the
/// dolly's frame 0 (Lambertian walls, a glossy cube, metal and glass), the weight
/// `mis_weight` gives with frame 12's camera vertex in place of frame 0's — x1's density
/// from that camera and, for t ≥ 3, x2's density from x1 under that view (the only camera
/// densities a ratio reads) — equals frame 0's weight times `ViewSplit::reweight` of the
/// three density ratios. Both heuristics. Tolerance: relative 1e-3 (f32 sums of up to a
/// dozen ratios spanning many orders of magnitude, formed in two different orders).
#[test]
fn view_split_reweights_a_path_for_another_camera_exactly() {
    use chronolux_core::sampling::sampler::PixelSampler;
    use chronolux_core::stats::Stats;
    use chronolux_render::kernels::bdpt::{
        Vertex, connect_with, generate_camera_subpath, generate_light_subpath, mis_weight,
        view_split,
    };
    let mut src = crate::source(stage::dolly(), 32, 32, 24.0, vec![0, 12]);
    let (f, g) = (src.frame(0), src.frame(12));
    assert!(f.camera.position() != g.camera.position());
    let eye_g = Vertex::camera(g.camera.position(), Rgb::ONE, false);
    let mut checked = [0usize; 2];
    for mis in [MisHeuristic::Power, MisHeuristic::Balance] {
        let settings = BdptSettings {
            common: chronolux_render::registry::CommonSettings {
                max_depth: Some(6),
                ..BdptSettings::default().common
            },
            mis,
            ..Default::default()
        };
        let mut st = Stats::default();
        let (mut cam, mut light) = (Vec::new(), Vec::new());
        for i in 0..32 * 32u32 {
            let (x, y) = (i % 32, i / 32);
            let mut cs = PixelSampler::new(5, 0, x, y);
            cs.start_sample(0);
            let raster = chronolux_core::math::Vec2::new(x as f32, y as f32) + cs.next_2d();
            generate_camera_subpath(&f, &settings, raster, &mut cs, &mut cam, &mut st);
            let mut ls = PixelSampler::new(6, 0, x, y);
            ls.start_sample(0);
            generate_light_subpath(&f, &settings, &mut ls, &mut light, &mut st);
            let Some(sv) = cam.get(1).and_then(|v| v.surface.as_ref()) else {
                continue;
            };
            if g.camera.project(cam[1].p).is_none() {
                continue;
            }
            // The camera subpath as g's camera would have made it.
            let mut cam_g = cam.clone();
            cam_g[0] = eye_g.clone();
            cam_g[1].pdf_fwd = eye_g.pdf(&g, None, &cam[1]);
            let wo_g = (g.camera.position() - cam[1].p).normalize();
            let (mut k_cont, mut k_light) = (1.0, 1.0);
            if cam.len() > 2 {
                let wi = (cam[2].p - cam[1].p).normalize();
                let (pf, pg) = (sv.bsdf.pdf(sv.wo, wi), sv.bsdf.pdf(wo_g, wi));
                cam_g[2].pdf_fwd = cam[2].pdf_fwd * pg / pf;
                k_cont = pf / pg;
            }
            let rho = cam[1].pdf_fwd / cam_g[1].pdf_fwd;
            let mut ns = PixelSampler::new(7, 0, x, y);
            ns.start_sample(0);
            for t in 2..=cam.len() {
                for s in 0..=light.len() {
                    let Some(c) = connect_with(
                        &f,
                        &settings,
                        &light,
                        &cam,
                        s,
                        t,
                        &mut ns,
                        &mut st,
                        &mut |_| true,
                    ) else {
                        continue;
                    };
                    let sampled = c.sampled.as_ref();
                    let w_f = mis_weight(&f, &settings, &light, &cam, sampled, s, t);
                    let w_g = mis_weight(&g, &settings, &light, &cam_g, sampled, s, t);
                    let split = view_split(&f, &settings, &light, &cam, sampled, s, t).unwrap();
                    if t == 2 && s >= 1 {
                        let q = c.light_point.expect("s ≥ 1");
                        let wl = (q - cam[1].p).normalize();
                        k_light = sv.bsdf.pdf(wo_g, wl) / sv.bsdf.pdf(sv.wo, wl);
                    }
                    let total = split.rest + split.lt + split.cam2 + split.light;
                    let near = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()) + 1e-9;
                    assert!(
                        near(1.0 / total, w_f),
                        "({s}, {t}): split sums to {total}, weight {w_f}"
                    );
                    let kc = if t >= 3 { k_cont } else { 1.0 };
                    let kl = if t == 2 { k_light } else { 1.0 };
                    let w = w_f * split.reweight(rho, kc, kl);
                    assert!(
                        near(w, w_g),
                        "({s}, {t}) at pixel ({x}, {y}): re-weighted {w} against {w_g} \
                         (weight in f {w_f}, split {split:?}, rho {rho}, {kc}, {kl})"
                    );
                    checked[usize::from(w_f != w_g)] += 1;
                }
            }
        }
    }
    // Enough strategies checked, and most of them changed weight with the camera.
    assert!(checked[1] > 1000 && checked[1] > checked[0], "{checked:?}");
}
