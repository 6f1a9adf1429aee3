//! Collapsing obvhs's binary BVH into four children a node: each wide node takes its binary
//! node's two children and repeatedly opens the inner child of largest surface area until it has
//! four (the greedy surface-area collapse of Wald, Benthin & Boulos 2008, "Getting rid of
//! packets", which Embree's BVH4 builder also follows). The binary tree's leaves are kept as
//! they are.

use super::leaf::Leaf4;
use super::{INNER, Node};
use obvhs::bvh2::Bvh2;
use obvhs::triangle::Triangle;

/// The wide nodes (the root first), the leaves, and the tree's depth in wide nodes. A binary
/// leaf of n triangles becomes ⌈n/4⌉ consecutive four-lane leaves.
pub(super) fn collapse(bvh2: &Bvh2, tris: &[Triangle]) -> (Vec<Node>, Vec<Leaf4>, usize) {
    let mut nodes = vec![Node::EMPTY];
    let mut leaves = Vec::new();
    let mut depth = 1;
    // (wide node to fill, the binary node it stands for, its depth)
    let mut work = vec![(0usize, 0u32, 1usize)];
    while let Some((at, binary, level)) = work.pop() {
        depth = depth.max(level);
        let mut node = Node::EMPTY;
        for (slot, &child) in widest_children(bvh2, binary).iter().flatten().enumerate() {
            let b = &bvh2.nodes[child as usize];
            let (lo, hi) = (b.aabb.min, b.aabb.max);
            for axis in 0..3 {
                node.bounds[2 * axis][slot] = lo[axis];
                node.bounds[2 * axis + 1][slot] = hi[axis];
            }
            if b.prim_count == 0 {
                node.child[slot] = nodes.len() as u32;
                node.count[slot] = INNER;
                work.push((nodes.len(), child, level + 1));
                nodes.push(Node::EMPTY);
            } else {
                node.child[slot] = leaves.len() as u32;
                node.count[slot] = b.prim_count;
                add_leaves(&mut leaves, bvh2, tris, b.first_index, b.prim_count);
            }
        }
        nodes[at] = node;
    }
    (nodes, leaves, depth)
}

/// The up to four binary nodes one wide node holds for binary node `index`: its two children,
/// with the largest inner one opened into its own two while there is room. A leaf root stands
/// alone (a scene of a few triangles).
fn widest_children(bvh2: &Bvh2, index: u32) -> [Option<u32>; 4] {
    let node = &bvh2.nodes[index as usize];
    let mut kids = [None; 4];
    if node.prim_count != 0 {
        kids[0] = Some(index);
        return kids;
    }
    kids[0] = Some(node.first_index);
    kids[1] = Some(node.first_index + 1);
    for free in 2..4 {
        let largest = kids[..free]
            .iter()
            .enumerate()
            .filter_map(|(i, k)| k.map(|k| (i, &bvh2.nodes[k as usize])))
            .filter(|(_, n)| n.prim_count == 0)
            .max_by(|(_, a), (_, b)| a.aabb.half_area().total_cmp(&b.aabb.half_area()));
        let Some((i, opened)) = largest else { break };
        kids[i] = Some(opened.first_index);
        kids[free] = Some(opened.first_index + 1);
    }
    kids
}

/// The triangles of slots `first..first + count`, four to a leaf.
fn add_leaves(leaves: &mut Vec<Leaf4>, bvh2: &Bvh2, tris: &[Triangle], first: u32, count: u32) {
    for start in (first..first + count).step_by(4) {
        let end = (start + 4).min(first + count);
        let four = bvh2.primitive_indices[start as usize..end as usize].iter();
        leaves.push(Leaf4::new(four.map(|&i| &tris[i as usize]), start));
    }
}
