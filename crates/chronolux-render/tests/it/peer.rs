//! Agreement with a peer: Mitsuba 3's `path` integrator (max_depth 8, 4096 spp) rendered
//! frame 12 of ../shared/peers/cornell-moving.glb (a Blender-exported animated Cornell
//! box); our path tracer on the same glTF, camera, frame and depth must converge to it.

use chronolux_core::scene::desc::AnimationId;
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
use chronolux_core::testing::{Estimate, block_z_test, channel_means, shared_file};
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::kernels::path::{PathSettings, PathTracer};
use std::sync::Arc;

/// Relative noise of the Mitsuba reference itself, from ../shared/peers/README.md:
/// relMSE ≈ 6.5e-5 for the 4096-spp frames, relMSE = mean (I−R)²/(R²+0.01).
const REF_RELMSE: f64 = 6.5e-5;

#[test]
fn path_tracer_converges_to_the_mitsuba_reference() {
    let (Some(scene_path), Some(ref_path)) = (
        shared_file("peers/cornell-moving.glb"),
        shared_file("peers/mitsuba-refs/mitsuba_f12.exr"),
    ) else {
        return;
    };
    let desc = chronolux_io::gltf::load(&scene_path).unwrap();
    let reference = chronolux_io::image::read_exr(ref_path).unwrap();
    let (w, h) = (reference.width, reference.height);
    let mut builder = FrameBuilder::new(
        Arc::new(desc),
        Some(AnimationId(0)),
        CameraChoice::First,
        w,
        h,
    )
    .unwrap();
    let scene = builder.build(12.0 / 24.0);
    let spp = 32;
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            max_depth: Some(8),
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let img = pt.render(&scene, 12, &|_| {});
    assert_eq!(img.invalid_samples, 0);

    let ours = Estimate::new(w, h, &img.pixels, &img.variance);
    let theirs = Estimate::with_variance(w, h, &reference.pixels, |r| REF_RELMSE * (r * r + 0.01));

    // 1. Image means per channel: the difference must be within 5 standard errors of the
    //    two estimates (ours from our per-pixel variances; the reference's from REF_RELMSE).
    for (c, m) in channel_means(&ours, &theirs).iter().enumerate() {
        let rel = (m.a - m.b).abs() / m.b;
        assert!(
            (m.a - m.b).abs() < 5.0 * m.se,
            "channel {c}: mean {:.5} vs Mitsuba {:.5} (rel {rel:.4}, se {:.2e})",
            m.a,
            m.b,
            m.se
        );
    }

    // 2. Per-block z-test (Mitsuba's test_renders design with Šidák correction at family
    //    level 1 %): 16×16-pixel blocks, so each block mean averages 256 pixels × spp
    //    samples and is close to normal.
    block_z_test(&ours, &theirs, 16, 0.01).assert_passes("peer agreement");
}
