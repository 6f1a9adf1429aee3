//! Walking the four-wide BVH: closest hit (children visited nearest first, and a box beyond the
//! closest hit so far skipped when it comes off the stack) and any hit (the first triangle that
//! blocks ends the walk).

use super::leaf::Leaf4;
use super::{Bvh4, INNER, Node};
use glam::{Vec3A, Vec4};

/// Entries the traversal stack holds on the thread's stack; a deeper tree (a pathological
/// mesh) walks with a stack on the heap instead.
const STACK: usize = 64;

/// One child waiting to be visited: a node, or a leaf's triangles, and where the ray enters it.
#[derive(Clone, Copy, Debug)]
struct Entry {
    t_near: f32,
    child: u32,
    count: u32,
}

impl Entry {
    const ROOT: Entry = Entry { t_near: 0.0, child: 0, count: INNER };
    /// What a fresh stack holds: all zeros, so that making one is a memset (a stack of `ROOT`s
    /// took a fifth of a shadow ray's time to fill).
    const ZERO: Entry = Entry { t_near: 0.0, child: 0, count: 0 };
}

/// A ray as the four-lane tests want it: its origin, direction and reciprocal direction in every
/// lane, and per axis which of a node's two planes it meets first (by the sign of its
/// direction).
#[derive(Clone, Copy, Debug)]
pub(super) struct BoxRay {
    pub(super) origin: [Vec4; 3],
    pub(super) direction: [Vec4; 3],
    inverse: [Vec4; 3],
    near: [usize; 3],
    far: [usize; 3],
}

impl BoxRay {
    fn new(origin: Vec3A, direction: Vec3A) -> Self {
        let mut ray = BoxRay {
            origin: [Vec4::ZERO; 3],
            direction: [Vec4::ZERO; 3],
            inverse: [Vec4::ZERO; 3],
            near: [0; 3],
            far: [0; 3],
        };
        for axis in 0..3 {
            // 1/±0 is ±∞: a ray parallel to an axis never crosses its planes.
            let inverse = 1.0 / direction[axis];
            let backwards = usize::from(inverse.is_sign_negative());
            ray.origin[axis] = Vec4::splat(origin[axis]);
            ray.direction[axis] = Vec4::splat(direction[axis]);
            ray.inverse[axis] = Vec4::splat(inverse);
            ray.near[axis] = 2 * axis + backwards;
            ray.far[axis] = 2 * axis + 1 - backwards;
        }
        ray
    }

    /// Where the ray enters each of the node's four boxes, and a bit per box it passes through
    /// within [0, `t_max`]: the slab test (Kay & Kajiya 1986) in four lanes.
    #[inline(always)]
    fn enter(&self, node: &Node, t_max: f32) -> (Vec4, u32) {
        let b = &node.bounds;
        let x0 = (b[self.near[0]] - self.origin[0]) * self.inverse[0];
        let y0 = (b[self.near[1]] - self.origin[1]) * self.inverse[1];
        let z0 = (b[self.near[2]] - self.origin[2]) * self.inverse[2];
        let x1 = (b[self.far[0]] - self.origin[0]) * self.inverse[0];
        let y1 = (b[self.far[1]] - self.origin[1]) * self.inverse[1];
        let z1 = (b[self.far[2]] - self.origin[2]) * self.inverse[2];
        // A ray parallel to a face it lies in gives 0 × ∞ = NaN for that axis. SSE's min and max
        // return their second operand when either is NaN, so each axis comes first and the
        // running bound second: a NaN axis then leaves the box open along it, never shut.
        let t_near = z0.max(y0.max(x0.max(Vec4::ZERO)));
        let t_far = z1.min(y1.min(x1.min(Vec4::splat(t_max))));
        (t_near, t_near.cmple(t_far).bitmask())
    }
}

impl Bvh4 {
    /// The closest triangle the ray from `origin` along `direction` meets in [0, `t_max`): its
    /// slot (BVH order) and distance.
    #[inline]
    pub fn closest(&self, origin: Vec3A, direction: Vec3A, t_max: f32) -> Option<(usize, f32)> {
        let ray = BoxRay::new(origin, direction);
        self.on_stack(Entry::ZERO, |stack| self.closest_with(stack, &ray, t_max))
    }

    /// Whether any triangle meets the ray in [0, `t_max`).
    #[inline]
    pub fn any_hit(&self, origin: Vec3A, direction: Vec3A, t_max: f32) -> bool {
        let ray = BoxRay::new(origin, direction);
        self.on_stack(0, |stack| self.any_hit_with(stack, &ray, t_max))
    }

    /// Runs `walk` with a traversal stack deep enough for this tree (each level leaves at most
    /// three children waiting): on the thread's stack, or on the heap for a pathological tree.
    #[inline(always)]
    fn on_stack<T: Copy, R>(&self, zero: T, walk: impl FnOnce(&mut [T]) -> R) -> R {
        let need = 3 * self.depth + 1;
        if need <= STACK { walk(&mut [zero; STACK]) } else { walk(&mut vec![zero; need]) }
    }

    #[inline(always)]
    fn closest_with(
        &self,
        stack: &mut [Entry],
        ray: &BoxRay,
        mut t_max: f32,
    ) -> Option<(usize, f32)> {
        let mut hit = None;
        let mut top = 0;
        let mut current = Entry::ROOT;
        loop {
            if current.count == INNER {
                let node = &self.nodes[current.child as usize];
                let (t_near, mask) = ray.enter(node, t_max);
                let (children, n) = nearest_first(node, t_near, mask);
                if n > 0 {
                    // The nearest is visited now, the others wait, the farthest deepest.
                    for &child in children[1..n].iter().rev() {
                        stack[top] = child;
                        top += 1;
                    }
                    current = children[0];
                    continue;
                }
            } else {
                for leaf in self.leaves_of(current.child, current.count) {
                    if let Some((slot, t)) = leaf.closest(ray, t_max) {
                        t_max = t;
                        hit = Some((slot as usize, t));
                    }
                }
            }
            // The next waiting child the ray reaches before its closest hit so far.
            loop {
                if top == 0 {
                    return hit;
                }
                top -= 1;
                if stack[top].t_near <= t_max {
                    current = stack[top];
                    break;
                }
            }
        }
    }

    /// The stack holds inner nodes only: a leaf is tested as soon as the ray is found to enter
    /// it, since any hit ends the walk.
    #[inline(always)]
    fn any_hit_with(&self, stack: &mut [u32], ray: &BoxRay, t_max: f32) -> bool {
        let mut top = 1;
        stack[0] = 0;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let (_, mut mask) = ray.enter(node, t_max);
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let (child, count) = (node.child[i], node.count[i]);
                if count == INNER {
                    stack[top] = child;
                    top += 1;
                } else if self.leaves_of(child, count).iter().any(|leaf| leaf.any(ray, t_max)) {
                    return true;
                }
            }
        }
        false
    }

    /// The four-lane leaves, from `first`, holding a leaf child's `count` triangles.
    #[inline(always)]
    fn leaves_of(&self, first: u32, count: u32) -> &[Leaf4] {
        let first = first as usize;
        &self.leaves[first..first + count.div_ceil(4) as usize]
    }
}

/// The children whose bit is set in `mask`, sorted by where the ray enters them (a stable
/// insertion sort: ties keep the node's order, so the walk is the same on every machine).
#[inline(always)]
fn nearest_first(node: &Node, t_near: Vec4, mut mask: u32) -> ([Entry; 4], usize) {
    let t_near = t_near.to_array();
    let mut children = [Entry::ROOT; 4];
    let mut n = 0;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let entry = Entry { t_near: t_near[i], child: node.child[i], count: node.count[i] };
        let mut at = n;
        while at > 0 && children[at - 1].t_near > entry.t_near {
            children[at] = children[at - 1];
            at -= 1;
        }
        children[at] = entry;
        n += 1;
    }
    (children, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node whose first child is the box from `lo` to `hi`, the others unused.
    fn node_of(lo: Vec3A, hi: Vec3A) -> Node {
        let mut node = Node::EMPTY;
        for axis in 0..3 {
            node.bounds[2 * axis][0] = lo[axis];
            node.bounds[2 * axis + 1][0] = hi[axis];
        }
        node
    }

    /// A ray that runs in the plane of a box's face (0 × ∞ in the slab test) enters the box, and
    /// a flat box (a floor's) is entered by a ray through it; the unused slots never are.
    #[test]
    fn a_ray_along_a_face_enters_and_an_empty_slot_never_does() {
        let cube = node_of(Vec3A::ZERO, Vec3A::ONE);
        let along_top = BoxRay::new(Vec3A::new(-1.0, 0.5, 1.0), Vec3A::X);
        assert_eq!(along_top.enter(&cube, f32::INFINITY).1, 0b0001);
        let above = BoxRay::new(Vec3A::new(-1.0, 0.5, 1.001), Vec3A::X);
        assert_eq!(above.enter(&cube, f32::INFINITY).1, 0);
        let floor = node_of(Vec3A::new(0.0, 0.0, 2.0), Vec3A::new(1.0, 1.0, 2.0));
        let down = BoxRay::new(Vec3A::new(0.5, 0.5, 3.0), Vec3A::NEG_Z);
        let (t_near, mask) = down.enter(&floor, f32::INFINITY);
        assert_eq!((mask, t_near.x), (0b0001, 1.0));
        assert_eq!(down.enter(&floor, 0.5).1, 0, "beyond the reach");
    }
}
