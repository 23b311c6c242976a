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

#[test]
fn a_ploc_tree_deeper_than_obvhs_stack_gets_a_median_tree_that_loses_nothing() {
    // `tests/data/deep-ploc-blas.f32`: the 188 triangles (9 little-endian f32 each, world
    // space) of the skinned mesh of `chronolux-io/tests/data/fuzz-rigged-shear-skin.glb`
    // (RiggedSimple.glb with a node matrix entry of 4294967295, found by the mutation
    // fuzzer) at its first frame. PLOC builds a CWBVH over them at least 32 levels deep,
    // beyond obvhs' traversal stack (its debug validation asserted; a release build would
    // drop subtrees). The build must notice and use the median split, and every ray must
    // find what a brute-force test over all triangles finds.
    use chronolux_core::accel::build::Builder;
    use chronolux_core::accel::{Accel, Instance};
    use chronolux_core::geometry::{PreparedTriangle, Ray};
    use chronolux_core::sampling::rng::Pcg32;
    use std::sync::Arc;
    let bytes = include_bytes!("../data/deep-ploc-blas.f32");
    let f: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let items: Vec<(TriRef, [Vec3; 3])> = f
        .chunks_exact(9)
        .enumerate()
        .map(|(i, t)| {
            (
                TriRef {
                    geometry: 0,
                    triangle: i as u32,
                },
                [
                    Vec3::new(t[0], t[1], t[2]),
                    Vec3::new(t[3], t[4], t[5]),
                    Vec3::new(t[6], t[7], t[8]),
                ],
            )
        })
        .collect();
    assert_eq!(items.len(), 188);
    // Filtered (`accept`) traversal lets a ray look for one triangle alone: a subtree the
    // traversal lost would make its triangles unfindable.
    let blas = Arc::new(Blas::build(&items, true));
    assert_eq!(blas.builder, Builder::MedianFallback);
    let accel = Accel::new(vec![Instance::new(
        blas,
        chronolux_core::math::Affine3A::IDENTITY,
    )]);
    // The skin collapses 149 of the 188 triangles to zero area; f32 Möller–Trumbore gives
    // meaningless hits on such slivers, so the rays aim at the others: from random points
    // of a box around the mesh to random points on triangle k, accepting only triangle k,
    // the traversal must find k at the t the triangle alone gives (same function, same
    // ray: equal bit for bit).
    let mut rng = Pcg32::new(7, 0);
    let (lo, hi) = (Vec3::new(-2.0, -6.0, -2.0), Vec3::new(2.0, 6.0, 2.0));
    let mut checked = 0;
    for (k, (r, v)) in items.iter().enumerate() {
        if (v[1] - v[0]).cross(v[2] - v[0]).length() < 1e-6 {
            continue;
        }
        let tri = PreparedTriangle::new(v[0], v[1], v[2]);
        for _ in 0..200 {
            let o = lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let (a, b) = (rng.next_f32(), rng.next_f32());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let d = (v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b - o).normalize();
            let Some((t, _, _)) = tri.intersect(o.into(), d.into(), f32::INFINITY) else {
                continue; // grazing: the point rounded off the triangle
            };
            let hit = accel.intersect(&Ray::new(o, d), |q, _, _| q == *r);
            let hit = hit.unwrap_or_else(|| panic!("triangle {k} not found from {o:?}"));
            assert_eq!((hit.tri, hit.t), (*r, t));
            checked += 1;
        }
    }
    assert!(checked > 5_000, "only {checked} rays checked");
}
