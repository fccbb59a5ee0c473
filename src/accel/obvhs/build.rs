//! BVH construction: obvhs PLOC, reinsertion and CWBVH conversion, robust to coincident primitives.
//!
//! PLOC merges mutual nearest neighbours in Morton order. Among primitives with identical bounds
//! every candidate costs the same, obvhs' tie-break (`cost <= best`: the farthest candidate) makes
//! mutual agreements rare (about one per pass), and the build degrades to O(n²) passes × work
//! (8k / 16k / 32k identical faces took 2.4 / 9.8 / 39.6 s). So primitives with bit-identical
//! bounds are grouped first (one O(n log n) sort), PLOC runs over one representative per group, and
//! each representative's leaf is replaced by a balanced subtree over its group, split by index
//! (O(n)). Geometry and boxes are unchanged: only the topology inside a group is chosen here, and a
//! group's boxes all equal the group's box, so no split of it could lower the SAH cost anyway.
//!
//! Invariants: the result holds every input primitive exactly once; children follow their parent in
//! `Bvh2::nodes` (sibling pairs start at odd indices), as PLOC's output does.

use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::PlocBuilder;
use obvhs::BvhBuildParams;

/// Primitives grouped by identical bounds: group `g` holds `members[starts[g]..starts[g + 1]]`
/// (ascending primitive ids) with box `boxes[g]`; groups are ordered by their first member.
pub(super) struct Groups {
    boxes: Vec<Aabb>,
    members: Vec<u32>,
    starts: Vec<usize>,
}

fn key(b: &Aabb) -> [u32; 6] {
    // + 0.0 maps −0.0 to +0.0, so that equal boxes get equal keys
    let (lo, hi) = (b.min + 0.0, b.max + 0.0);
    [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z].map(f32::to_bits)
}

/// Groups primitives whose boxes are bit-identical (after −0 → +0).
pub(super) fn group_identical(aabbs: &[Aabb]) -> Groups {
    let mut order: Vec<u32> = (0..aabbs.len() as u32).collect();
    order.sort_unstable_by_key(|&i| (key(&aabbs[i as usize]), i));
    let mut runs: Vec<(usize, usize)> = Vec::new(); // (start, end) into `order`
    let mut s = 0;
    for e in 1..=order.len() {
        if e == order.len() || key(&aabbs[order[e] as usize]) != key(&aabbs[order[s] as usize]) {
            runs.push((s, e));
            s = e;
        }
    }
    runs.sort_unstable_by_key(|&(s, _)| order[s]);
    let mut g = Groups { boxes: Vec::with_capacity(runs.len()), members: Vec::new(), starts: vec![0] };
    g.members.reserve(aabbs.len());
    for (s, e) in runs {
        g.boxes.push(aabbs[order[s] as usize]);
        g.members.extend_from_slice(&order[s..e]);
        g.starts.push(g.members.len());
    }
    g
}

/// Builds the CWBVH over `aabbs` (primitive id = index).
pub(super) fn build_cwbvh(aabbs: &[Aabb], params: BvhBuildParams) -> CwBvh {
    let groups = group_identical(aabbs);
    let reps = &groups.boxes;
    let mut bvh2 = PlocBuilder::with_capacity(reps.len()).build(
        params.ploc_search_distance,
        reps,
        (0..reps.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    if reps.len() < aabbs.len() {
        bvh2 = graft(&bvh2, &groups);
    }
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false)
}

/// A node to write: its slot in the new tree and what it covers.
enum Todo {
    /// A node of the representatives' tree.
    Rep { old: usize, new: usize, depth: usize },
    /// A balanced subtree over `prims[lo..hi]` with box `aabb`.
    Run { lo: usize, hi: usize, aabb: Aabb, new: usize, depth: usize },
}

/// Replaces each leaf of the representatives' tree `reps` by a balanced subtree over its groups'
/// members (one primitive per leaf).
pub(super) fn graft(reps: &Bvh2, g: &Groups) -> Bvh2 {
    let n = g.members.len();
    let mut nodes: Vec<Bvh2Node> = Vec::with_capacity(2 * n);
    let mut prims: Vec<u32> = Vec::with_capacity(n); // leaf members, then primitive_indices
    let mut out_indices: Vec<u32> = Vec::with_capacity(n);
    nodes.push(Bvh2Node::default());
    let mut stack = vec![Todo::Rep { old: 0, new: 0, depth: 1 }];
    let mut max_depth = 1;
    let pair = |nodes: &mut Vec<Bvh2Node>| {
        let first = nodes.len();
        nodes.extend([Bvh2Node::default(); 2]);
        first
    };
    while let Some(todo) = stack.pop() {
        match todo {
            Todo::Rep { old, new, depth } => {
                let node = reps.nodes[old];
                if node.is_leaf() {
                    let lo = prims.len();
                    let (f, c) = (node.first_index as usize, node.prim_count as usize);
                    for &r in &reps.primitive_indices[f..f + c] {
                        let r = r as usize;
                        prims.extend_from_slice(&g.members[g.starts[r]..g.starts[r + 1]]);
                    }
                    stack.push(Todo::Run { lo, hi: prims.len(), aabb: *node.aabb(), new, depth });
                } else {
                    let first = pair(&mut nodes);
                    nodes[new] = Bvh2Node::new(*node.aabb(), 0, first as u32);
                    let c = node.first_index as usize;
                    stack.push(Todo::Rep { old: c, new: first, depth: depth + 1 });
                    stack.push(Todo::Rep { old: c + 1, new: first + 1, depth: depth + 1 });
                }
            }
            Todo::Run { lo, hi, aabb, new, depth } => {
                max_depth = max_depth.max(depth);
                if hi - lo == 1 {
                    nodes[new] = Bvh2Node::new(aabb, 1, out_indices.len() as u32);
                    out_indices.push(prims[lo]);
                } else {
                    let first = pair(&mut nodes);
                    nodes[new] = Bvh2Node::new(aabb, 0, first as u32);
                    let mid = lo + (hi - lo) / 2;
                    stack.push(Todo::Run { lo, hi: mid, aabb, new: first, depth: depth + 1 });
                    stack.push(Todo::Run { lo: mid, hi, aabb, new: first + 1, depth: depth + 1 });
                }
            }
        }
    }
    Bvh2 {
        nodes,
        primitive_indices: out_indices,
        max_depth: DEFAULT_MAX_STACK_DEPTH.max(max_depth + 1),
        children_are_ordered_after_parents: true,
        ..Default::default()
    }
}
