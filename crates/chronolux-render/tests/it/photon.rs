//! The photon kernel: energy conservation (closed furnace, every light kind), replay by
//! index, determinism across thread counts.

use crate::frame0;
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::math::{Quat, Vec3};
use chronolux_core::scene::desc::{
    LightDesc, LightId, LightKind, Material, MaterialId, Mesh, MeshId, Node, NodeId, Primitive,
    SceneDesc, Trs,
};
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::scene::testing::{furnace, uv_sphere};
use chronolux_render::kernels::photon::{
    PhotonHit, trace_photon, trace_photons, trace_photons_within,
};

/// Σ power of all reported hits per emitted photon, and of hits with ≥ 1 bounce.
fn deposited(scene: &FrameScene, n: u64) -> (f64, f64) {
    let (hits, _) = trace_photons(scene, 0..n, 7, |h: &PhotonHit| {
        Some((luminance(h.power) as f64, h.bounces))
    });
    let all = hits.iter().map(|h| h.0).sum::<f64>() / n as f64;
    let ind = hits.iter().filter(|h| h.1 > 0).map(|h| h.0).sum::<f64>() / n as f64;
    (all, ind)
}

/// Inside a closed diffuse sphere of albedo a, every photon entering the interior is
/// deposited at each hit until absorbed: Σ deposits = Φ_in / (1 − a), i.e. the absorbed
/// power (1 − a)·Σ deposits equals the emitted power Φ_in; photons that bounced at least
/// once carry Φ_in·a/(1 − a). The furnace's emitter is two-sided: half of its power
/// Φ = Σ light powers leaves through the outside of the sphere and never hits anything.
#[test]
fn closed_furnace_absorbs_exactly_the_emitted_power() {
    for a in [0.5f32, 0.8] {
        let scene = frame0(furnace(a, 1.0), 8, 8);
        let phi: f64 = scene
            .lights
            .iter()
            .map(|l| l.power(scene.scene_radius) as f64)
            .sum();
        let phi_in = 0.5 * phi;
        let (all, ind) = deposited(&scene, 100_000);
        let a = a as f64;
        // Relative standard deviation of one photon's deposit count (geometric with mean
        // 1/(1−a)) is √a; over 1e5 photons the standard error is ≤ 0.3%, and the Halton
        // points do better than random. 1% = more than 3 standard errors.
        let absorbed = (1.0 - a) * all;
        assert!(
            (absorbed - phi_in).abs() < 0.01 * phi_in,
            "a={a}: absorbed {absorbed} vs emitted inward {phi_in}"
        );
        let want_ind = phi_in * a / (1.0 - a);
        assert!(
            (ind - want_ind).abs() < 0.015 * want_ind,
            "a={a}: indirect {ind} vs {want_ind}"
        );
    }
}

/// A closed sphere of albedo `a` around a punctual light at its centre.
fn sphere_with_light(a: f32, kind: LightKind, rotation: Quat) -> SceneDesc {
    let mut prim: Primitive = uv_sphere(1.0, 48, 24, true);
    prim.material = Some(MaterialId(0));
    SceneDesc {
        nodes: vec![
            Node {
                name: "sphere".into(),
                mesh: Some(MeshId(0)),
                ..Default::default()
            },
            Node {
                name: "light".into(),
                light: Some(LightId(0)),
                transform: Trs {
                    rotation,
                    ..Default::default()
                },
                ..Default::default()
            },
        ],
        roots: vec![NodeId(0), NodeId(1)],
        meshes: vec![Mesh {
            name: "sphere".into(),
            primitives: vec![prim],
            weights: vec![],
        }],
        materials: vec![Material::diffuse("white", Rgb::splat(a))],
        lights: vec![LightDesc {
            name: "l".into(),
            color: Rgb::ONE,
            intensity: 2.0,
            kind,
        }],
        ..Default::default()
    }
}

/// Point and spot lights inside a closed sphere: absorbed power = light power.
#[test]
fn punctual_lights_in_a_closed_sphere_conserve_power() {
    let a = 0.6f32;
    for kind in [
        LightKind::Point,
        LightKind::Spot {
            inner_cone: 0.3,
            outer_cone: 0.6,
        },
    ] {
        let scene = frame0(sphere_with_light(a, kind, Quat::from_rotation_x(0.4)), 8, 8);
        assert_eq!(scene.lights.len(), 1);
        let phi = scene.lights[0].power(scene.scene_radius) as f64;
        let (all, _) = deposited(&scene, 100_000);
        let absorbed = (1.0 - a as f64) * all;
        assert!(
            (absorbed - phi).abs() < 0.01 * phi,
            "{kind:?}: absorbed {absorbed} vs power {phi}"
        );
    }
}

/// A directional light of irradiance E straight down onto a lone 2×2 floor deposits E·4
/// on it; what the floor reflects escapes (nothing above it), so no photon bounces.
#[test]
fn directional_light_deposits_irradiance_times_area() {
    let mut desc = sphere_with_light(
        0.5,
        LightKind::Directional,
        Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
    );
    let quad = Primitive {
        positions: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ],
        indices: vec![[0, 2, 1], [0, 3, 2]],
        material: Some(MaterialId(0)),
        ..Default::default()
    };
    desc.meshes[0].primitives = vec![quad];
    let scene = frame0(desc, 8, 8);
    let (all, ind) = deposited(&scene, 50_000);
    let want = 2.0 * 4.0 * luminance(Rgb::ONE) as f64;
    assert!(
        (all - want).abs() < 0.01 * want,
        "deposited {all} want {want}"
    );
    assert_eq!(ind, 0.0);
}

/// Photon i re-traced alone gives exactly the hits it gave inside a parallel batch, and
/// batches are bit-identical for any thread count.
#[test]
fn photons_replay_by_index_and_ignore_thread_count() {
    let scene = frame0(chronolux_core::scene::stage::cornell_box(), 8, 8);
    let key = |h: &PhotonHit| {
        (
            h.index,
            h.tri,
            h.b1.to_bits(),
            h.b2.to_bits(),
            h.power.to_array().map(f32::to_bits),
            h.bounces,
            h.caustic,
        )
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| trace_photons(&scene, 1000..21_000, 3, |h| Some(key(h))))
    };
    let (a, sa) = run(1);
    let (b, sb) = run(3);
    assert_eq!(a, b);
    assert_eq!(sa, sb);
    assert!(a.len() > 20_000);
    for i in [1000u64, 1234, 20_999] {
        let mut alone = Vec::new();
        trace_photon(&scene, i, 3, |h| alone.push(key(h)));
        let batch: Vec<_> = a.iter().filter(|h| h.0 == i).cloned().collect();
        assert_eq!(alone, batch, "photon {i}");
    }
}

/// A depth-limited photon walk reports exactly the unlimited walk's hits of at most that
/// many bounces (same numbers, same order, same powers: the walk is cut, not changed) and
/// traces fewer rays: in the closed furnace of albedo 0.8 a photon bounces 4 times on
/// average before Russian roulette ends it, so a cap of 1 saves most of its rays.
#[test]
fn a_depth_limited_walk_reports_the_unlimited_walks_first_hits_and_traces_fewer_rays() {
    let scene = frame0(furnace(0.8, 1.0), 8, 8);
    let key = |h: &PhotonHit| Some((h.index, h.bounces, h.p.to_array(), h.power.to_array()));
    let (all, full) = trace_photons(&scene, 0..20_000, 5, key);
    for cap in [0u32, 1, 3] {
        let (capped, stats) = trace_photons_within(&scene, 0..20_000, 5, cap, key);
        let expect: Vec<_> = all.iter().filter(|h| h.1 <= cap).cloned().collect();
        assert!(!expect.is_empty());
        assert!(capped == expect, "cap {cap}: the hits differ");
        assert!(
            stats.rays < full.rays,
            "cap {cap}: {} rays of {}",
            stats.rays,
            full.rays
        );
    }
}
