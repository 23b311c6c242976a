//! One way to build a CWBVH: obvhs' PLOC builder, with a depth guarantee.
//!
//! obvhs traverses a CWBVH with a fixed stack of `TRAVERSAL_STACK_SIZE` = 32 entries
//! (obvhs-0.4.0 `cwbvh/mod.rs`), at most one pending entry per level descended. When the
//! stack is full a push **overwrites the last entry** (`faststack.rs`), so in a deeper tree
//! a ray can silently lose a pending subtree in a release build (a debug build asserts the
//! depth in its own validation, `cwbvh/mod.rs:791`, which fuzzing hit). PLOC orders primitives by 64-bit Morton codes over the
//! set's bounds; when a few primitives are extremely far from the rest (fuzzing found a
//! skinned mesh under a node matrix entry of 4.3e9), all the others share a handful of
//! codes and the greedy pairing can chain them into a tree far deeper than 32.
//!
//! So every build here checks the depth of the CWBVH it made, and when it is not below
//! [`MAX_DEPTH`] builds instead from an object-median binary tree (split at the median
//! centroid along the widest centroid axis, depth `⌈log₂ n⌉`), which the 8-wide collapse
//! can only make shallower: depth ≤ 31 for any n < 2³¹. Ordinary scenes never take the
//! fallback (the tests check that the demo's BVHs are PLOC's); it trades traversal
//! quality for correctness only on pathological inputs.
//!
//! obvhs' own `build_cwbvh*` helpers run the validation (with its depth assertion) in
//! debug builds before a caller could check anything, so this module calls the builder
//! stages itself, in the order those helpers do.

use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use obvhs::cwbvh::{CwBvh, bvh2_to_cwbvh::bvh2_to_cwbvh};
use obvhs::ploc::PlocBuilder;
use obvhs::{Boundable, BvhBuildParams};

/// The traversal stack of obvhs-0.4.0's CWBVH (`TRAVERSAL_STACK_SIZE`, private there).
pub const TRAVERSAL_STACK_SIZE: u32 = 32;

/// Largest CWBVH depth accepted from PLOC (levels below the root); obvhs' own validation
/// requires `depth < TRAVERSAL_STACK_SIZE`.
pub const MAX_DEPTH: u32 = TRAVERSAL_STACK_SIZE - 1;

/// Which builder made a BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    Ploc,
    /// PLOC's tree was too deep; object-median split instead.
    MedianFallback,
    /// Embree's own builder (SAH with spatial splits; [`super::embree`]).
    Embree,
}

/// Builds a CWBVH over `prims` whose depth is below obvhs' traversal stack.
pub fn build_cwbvh<T: Boundable>(prims: &[T], params: BvhBuildParams) -> (CwBvh, Builder) {
    let mut bvh2 = PlocBuilder::with_capacity(prims.len()).build(
        params.ploc_search_distance,
        prims,
        (0..prims.len() as u32).collect::<Vec<_>>(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    let leaf = params.max_prims_per_leaf.clamp(1, 3);
    let cw = bvh2_to_cwbvh(&bvh2, leaf, true, false);
    if depth(&cw) <= MAX_DEPTH {
        return (cw, Builder::Ploc);
    }
    let boxes: Vec<Aabb> = prims.iter().map(|p| p.aabb()).collect();
    let cw = bvh2_to_cwbvh(&median_bvh2(&boxes), leaf, true, false);
    debug_assert!(
        depth(&cw) <= MAX_DEPTH,
        "median BVH too deep: {}",
        depth(&cw)
    );
    (cw, Builder::MedianFallback)
}

/// Levels below the root of the deepest inner node (0 for a root with only leaves), as
/// obvhs' validation counts them.
pub fn depth(bvh: &CwBvh) -> u32 {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut stack = vec![(0u32, 0u32)];
    while let Some((node, d)) = stack.pop() {
        deepest = deepest.max(d);
        let n = &bvh.nodes[node as usize];
        for ch in 0..8 {
            if !n.is_child_empty(ch) && !n.is_leaf(ch) {
                stack.push((n.child_node_index(ch), d + 1));
            }
        }
    }
    deepest
}

/// A binary BVH with one primitive per leaf, split at the median centroid along the
/// widest centroid axis: depth `⌈log₂ n⌉`, whatever the distribution.
fn median_bvh2(boxes: &[Aabb]) -> Bvh2 {
    let n = boxes.len();
    let mut indices: Vec<u32> = (0..n as u32).collect();
    let mut nodes = vec![Bvh2Node::default()];
    if n == 0 {
        return Bvh2::default();
    }
    let mut work = vec![(0usize, 0usize, n)];
    while let Some((node, start, end)) = work.pop() {
        let mut aabb = Aabb::empty();
        let mut centres = Aabb::empty();
        for &i in &indices[start..end] {
            aabb = aabb.union(&boxes[i as usize]);
            centres.extend(boxes[i as usize].center());
        }
        if end - start == 1 {
            nodes[node] = Bvh2Node::new(aabb, 1, start as u32);
            continue;
        }
        let axis = centres.largest_axis();
        let mid = start + (end - start) / 2;
        indices[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            let ca = boxes[a as usize].center_axis(axis);
            let cb = boxes[b as usize].center_axis(axis);
            ca.total_cmp(&cb)
        });
        let left = nodes.len();
        nodes.push(Bvh2Node::default());
        nodes.push(Bvh2Node::default());
        nodes[node] = Bvh2Node::new(aabb, 0, left as u32);
        work.push((left, start, mid));
        work.push((left + 1, mid, end));
    }
    Bvh2 {
        nodes,
        primitive_indices: indices,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    fn unit_box(c: Vec3A) -> Aabb {
        Aabb {
            min: c - Vec3A::splat(0.01),
            max: c + Vec3A::splat(0.01),
        }
    }

    #[test]
    fn median_tree_depth_is_logarithmic() {
        // 10 000 boxes, half of them at one point and a geometric run far away: the
        // shape that chains PLOC. ⌈log₂ 10 000⌉ = 14 binary levels bound the CWBVH depth.
        let mut boxes = Vec::new();
        for i in 0..5000 {
            boxes.push(unit_box(Vec3A::splat(i as f32 * 1e-9)));
        }
        for i in 0..5000 {
            boxes.push(unit_box(Vec3A::new(1.5f32.powi(i % 60), 0.0, 0.0)));
        }
        let cw = bvh2_to_cwbvh(&median_bvh2(&boxes), 1, true, false);
        assert!(depth(&cw) <= 14, "depth {}", depth(&cw));
        // Every primitive is reachable exactly once.
        let mut seen = vec![0u32; boxes.len()];
        for node in &cw.nodes {
            for ch in 0..8 {
                if !node.is_child_empty(ch) && node.is_leaf(ch) {
                    let (first, count) = node.child_primitives(ch);
                    for k in first..first + count {
                        seen[cw.primitive_indices[k as usize] as usize] += 1;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }
}
