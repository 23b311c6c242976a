//! White furnace: inside a closed diffuse sphere of albedo a emitting Le everywhere, the
//! radiance is Le·Σ_{k<D} a^k for paths of at most D segments, Le/(1−a) unlimited.

use crate::{frame0, mean_and_stderr};
use chronolux_core::scene::testing::furnace;
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::kernels::path::{PathSettings, PathTracer};

fn render(a: f32, le: f32, max_depth: Option<u32>, spp: u32) -> (f64, f64) {
    let scene = frame0(furnace(a, le), 16, 16);
    let pt = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            max_depth,
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let img = pt.render(&scene, 0, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    mean_and_stderr(&img.pixels)
}

#[test]
fn furnace_unlimited_depth_converges_to_le_over_one_minus_a() {
    for (a, le) in [(0.5f32, 0.5f32), (0.8, 0.2)] {
        let (m, se) = render(a, le, None, 64);
        let want = (le / (1.0 - a)) as f64;
        // 5 standard errors of the pixel mean (the estimator is unbiased; the closed
        // tessellated sphere has exactly this answer), plus 1e-4 for float accumulation.
        assert!(
            (m - want).abs() < 5.0 * se + 1e-4,
            "a={a}: mean {m} want {want} (se {se})"
        );
    }
}

#[test]
fn furnace_depth_limit_follows_mitsuba_convention() {
    let (a, le) = (0.5f32, 1.0f32);
    for d in 1..=4u32 {
        let (m, se) = render(a, le, Some(d), 32);
        let want: f64 = (0..d).map(|k| (le * a.powi(k as i32)) as f64).sum();
        // Same bound as above; depth 1 is exact (no randomness) so se = 0 there.
        assert!(
            (m - want).abs() < 5.0 * se + 1e-4,
            "depth {d}: mean {m} want {want} (se {se})"
        );
    }
}
