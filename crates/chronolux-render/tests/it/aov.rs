//! Render passes: analytic values on the moving quad of the blur tests (an emitter 8 px
//! wide, orthographic camera, moving +16 px per frame), determinism, every technique.

use chronolux_render::framework::aov::{DEPTH_MISS, PassSet, render_aovs};

/// The blur tests' scene: 64×4 pixels, the quad at z = −1 seen through an orthographic
/// camera at the origin, its centre at raster x = 32 at frame 1 (1 fps), +16 px per frame.
fn quad_frames() -> chronolux_core::scene::source::FrameSource {
    crate::source(
        super::blur::moving_quad_seen(true),
        64,
        4,
        1.0,
        vec![0, 1, 2],
    )
}

#[test]
fn passes_of_the_moving_quad_are_exact() {
    let mut src = quad_frames();
    let (prev, cur, next) = (src.frame(0), src.frame(1), src.frame(2));
    let all = PassSet::parse("all").unwrap();
    let a = render_aovs(&cur, Some(&prev), Some(&next), 1, 0, all);
    // Pixels 29..=34 are inside the quad (raster 28..36) for every jittered sample;
    // 0..=20 and 44..=63 are background in every sample.
    for y in 0..4usize {
        for x in 29..=34usize {
            let k = y * 64 + x;
            // Depth: the quad plane is 1 unit in front of the camera (orthographic rays
            // start on the camera plane): exact up to f32 rounding.
            assert!((a.depth[k] - 1.0).abs() < 1e-5, "depth {x}: {}", a.depth[k]);
            // A black emitter (base colour 0): albedo 0; its normal faces the camera (+z).
            assert_eq!(a.albedo[k], chronolux_core::color::Rgb::ZERO);
            assert!(
                (a.normal[k].z - 1.0).abs() < 1e-5,
                "normal {:?}",
                a.normal[k]
            );
            // Motion: the quad moves 4 world units per frame = 16 px (raster = 4x + 32);
            // f32 rounding of the projections only.
            assert!(
                (a.motion_next[k].x - 16.0).abs() < 1e-3,
                "{:?}",
                a.motion_next[k]
            );
            assert!(
                (a.motion_prev[k].x + 16.0).abs() < 1e-3,
                "{:?}",
                a.motion_prev[k]
            );
            assert!(a.motion_next[k].y.abs() < 1e-3 && a.motion_prev[k].y.abs() < 1e-3);
        }
        for x in (0..=20).chain(44..64) {
            let k = y * 64 + x;
            assert_eq!(a.depth[k], DEPTH_MISS);
            assert_eq!(a.normal[k], chronolux_core::math::Vec3::ZERO);
            assert_eq!(a.motion_next[k], chronolux_core::math::Vec2::ZERO);
        }
    }
    // No neighbour: no motion.
    let b = render_aovs(&cur, None, None, 1, 0, all);
    assert!(
        b.motion_next
            .iter()
            .all(|m| *m == chronolux_core::math::Vec2::ZERO)
    );
    // Only what was asked for.
    let only = render_aovs(&cur, None, None, 1, 0, PassSet::parse("depth").unwrap());
    assert!(only.albedo.is_empty() && only.normal.is_empty() && only.motion_next.is_empty());
    assert_eq!(only.depth, a.depth);
}

#[test]
fn passes_do_not_depend_on_the_thread_count_and_see_albedo_on_the_demo() {
    let mut src = crate::source(
        chronolux_core::scene::stage::demo(),
        32,
        32,
        24.0,
        vec![3, 4, 5],
    );
    let (p, c, n) = (src.frame(3), src.frame(4), src.frame(5));
    let all = PassSet::parse("all").unwrap();
    let pool = |t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    };
    let a = pool(1).install(|| render_aovs(&c, Some(&p), Some(&n), 4, 7, all));
    let b = pool(2).install(|| render_aovs(&c, Some(&p), Some(&n), 4, 7, all));
    assert_eq!(a.albedo, b.albedo);
    assert_eq!(a.normal, b.normal);
    assert_eq!(a.depth, b.depth);
    assert_eq!(a.motion_prev, b.motion_prev);
    // The room fills the image but for its front edge, which shows the black background
    // on the image border (the black frame of the demo's images): every pixel inside the
    // border sees the room (some of a border pixel's samples may all miss). Albedos are
    // reflectances in [0, 1] and normals unit (up to the antialiasing average at edges, ≤ 1).
    for y in 1..31 {
        for x in 1..31 {
            assert!(
                a.depth[y * 32 + x] < DEPTH_MISS,
                "pixel ({x}, {y}) sees no surface"
            );
        }
    }
    for (al, nm) in a.albedo.iter().zip(&a.normal) {
        assert!((0.0..=1.0).contains(&al.x) && (0.0..=1.0).contains(&al.y));
        assert!(nm.length() <= 1.0 + 1e-4);
    }
    // The demo's block moves: some pixels have motion, the static walls none.
    assert!(a.motion_next.iter().any(|m| m.length() > 0.1));
    assert!(a.motion_next.iter().filter(|m| m.length() == 0.0).count() > 32 * 32 / 2);
}
