//! Images are bit-identical whatever the thread count (each pixel has its own sample
//! stream; tiles are merged in a fixed order).

use crate::frame0;
use chronolux_core::scene::testing::furnace;
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::kernels::path::{PathSettings, PathTracer};

#[test]
fn bit_identical_across_thread_counts() {
    let scene = frame0(furnace(0.7, 0.3), 40, 24);
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 8,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let render = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| pt.render(&scene, 3, &|_| {}))
    };
    let (a, b, c) = (render(1), render(2), render(3));
    assert!(
        a.pixels
            .iter()
            .zip(&b.pixels)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    assert!(
        a.pixels
            .iter()
            .zip(&c.pixels)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    assert_eq!(a.stats, b.stats);
}

#[test]
fn bit_identical_across_tile_sizes() {
    use chronolux_render::framework::integrator::render_camera_rays_tiled;
    let scene = frame0(furnace(0.6, 0.4), 37, 21);
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 4,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let a = render_camera_rays_tiled(&pt, &scene, 1, 4, 9, 16, &|_| {});
    for tile in [1, 5, 64] {
        let b = render_camera_rays_tiled(&pt, &scene, 1, 4, 9, tile, &|_| {});
        assert!(
            a.pixels
                .iter()
                .zip(&b.pixels)
                .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits)),
            "tile {tile}"
        );
    }
}
