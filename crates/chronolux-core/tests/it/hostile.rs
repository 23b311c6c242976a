//! Geometry no real scene has, which fuzzing fed to the frame builder.

use chronolux_core::accel::{Blas, MAX_COORD, TriRef};
use chronolux_core::math::Vec3;

#[test]
fn huge_coordinates_are_left_out_of_the_bvh_instead_of_breaking_it() {
    // A vertex at −1.7e38 (a flipped exponent bit in a mutated GLB) overflowed obvhs' area
    // arithmetic and tripped its assertion (bvh2_to_cwbvh.rs:365); now the triangle is
    // left out and the rest is built.
    let t = |g: u32, v: [Vec3; 3]| {
        (
            TriRef {
                geometry: g,
                triangle: 0,
            },
            v,
        )
    };
    let mut items = vec![
        t(0, [Vec3::ZERO, Vec3::X, Vec3::Y]),
        t(1, [Vec3::new(-1.7e38, 0.0, 0.0), Vec3::X, Vec3::Y]),
        t(2, [Vec3::splat(2.0 * MAX_COORD), Vec3::X, Vec3::Y]),
    ];
    for i in 0..40 {
        let o = Vec3::new(i as f32, 2.0, 0.0);
        items.push(t(3 + i, [o, o + Vec3::X, o + Vec3::Y]));
    }
    let blas = Blas::build(&items, false);
    assert!(blas.bounds.max.max_element() < 100.0, "{:?}", blas.bounds);
    assert!(blas.bounds.min.min_element() >= 0.0, "{:?}", blas.bounds);
}
