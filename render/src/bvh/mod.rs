//! The tracer's acceleration structure: a four-wide BVH whose node tests one ray against four
//! children's boxes at once in SSE lanes (glam's `Vec4`), built by collapsing the binary BVH that
//! obvhs builds (PLOC with reinsertion).
//!
//! Why not obvhs's own CWBVH traversal: 70 % of a render's time went there (issue 21's note,
//! issue 37), in a single-ray loop that decompresses each quantized node in scalar code. A wide
//! node of full-precision boxes laid out as structure-of-arrays is the layout of Embree's BVH4 and
//! tinybvh's `BVH4_CPU`, which published measurements put at 1.4–2× a plain CWBVH kernel
//! (`../shared/notes/tracing-speed.md`). SSE2 is the x86-64 baseline, so every machine runs the
//! same instructions and a farm's images agree bit for bit without run-time dispatch.

mod collapse;
mod leaf;
mod traverse;

use glam::Vec4;
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::triangle::Triangle;
use std::time::Duration;

use leaf::Leaf4;

/// A child slot's `count` when it holds an inner node rather than a leaf's triangles.
const INNER: u32 = u32::MAX;

/// Four children's boxes as lanes, and what each child is.
///
/// `bounds` holds min x, max x, min y, max y, min z, max z, each across the four children, so
/// that a ray picks its near and far plane per axis once (by the sign of its direction) and tests
/// all four boxes with twelve lane operations. An unused slot has the empty box (+∞ to −∞),
/// which no ray enters.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node {
    bounds: [Vec4; 6],
    /// An inner child's node index, or its leaf's first [`Leaf4`].
    child: [u32; 4],
    /// [`INNER`] for an inner child, else the leaf's triangle count (0 for an unused slot).
    count: [u32; 4],
}

impl Node {
    const EMPTY: Node = Node {
        bounds: [
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
        ],
        child: [0; 4],
        count: [0; 4],
    };
}

/// The four-wide BVH over a scene's triangles.
#[derive(Debug)]
pub struct Bvh4 {
    nodes: Vec<Node>,
    leaves: Vec<Leaf4>,
    /// For each triangle slot, the index of the caller's triangle it is (BVH order). A large
    /// triangle split before the build sits in more than one leaf, so in more than one slot.
    pub primitive_indices: Vec<u32>,
    /// The caller's triangles, each counted once.
    triangle_count: usize,
    /// The longest root-to-leaf path, in nodes: it sizes the traversal stack.
    depth: usize,
}

impl Bvh4 {
    /// Builds the binary BVH with obvhs (`params`: [`build_params`] for the tracer) and
    /// collapses it to four children a node.
    pub fn build(tris: &[Triangle], params: BvhBuildParams) -> Self {
        let bvh2: Bvh2 =
            obvhs::bvh2::builder::build_bvh2_from_tris(tris, params, &mut Duration::default());
        let (nodes, leaves, depth) = collapse::collapse(&bvh2, tris);
        Bvh4 {
            nodes,
            leaves,
            primitive_indices: bvh2.primitive_indices,
            triangle_count: tris.len(),
            depth,
        }
    }

    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
            + self.leaves.len() * size_of::<Leaf4>()
            + self.primitive_indices.len() * size_of::<u32>()
    }

    /// The triangles the BVH was built over, each counted once.
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

/// The build the tracer uses: obvhs's slow build (large triangles' boxes split before PLOC, a
/// wider PLOC search, more reinsertion), leaves of at most four triangles, the four a [`Leaf4`]
/// tests at once. Measured against the medium build with `restauro bench tracer` and
/// `restauro bench mesh` (issue 37): about a fifth more rays per CPU-second on the blocks scene
/// and 5 % on the facade, for 1.8× the build time (0.67 s for 500 k triangles).
pub fn build_params() -> BvhBuildParams {
    BvhBuildParams { max_prims_per_leaf: 4, ..BvhBuildParams::slow_build() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;
    use obvhs::ray::Ray;
    use obvhs::rt_triangle::RtTriangle;
    use restauro_spectral::keyed_random::KeyedRng;

    /// Random small triangles in a 10 m cube, and a floor and walls lying in axis planes, as a
    /// building's are (their boxes have no thickness).
    fn soup(rng: &mut KeyedRng, count: usize) -> Vec<Triangle> {
        let mut point = |scale: f32| {
            Vec3A::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale - scale / 2.0
        };
        let mut tris: Vec<Triangle> = (0..count)
            .map(|_| {
                let c = point(10.0);
                Triangle { v0: c + point(1.0), v1: c + point(1.0), v2: c + point(1.0) }
            })
            .collect();
        let quad = |a: Vec3A, b: Vec3A, c: Vec3A, d: Vec3A| {
            [Triangle { v0: a, v1: b, v2: c }, Triangle { v0: a, v1: c, v2: d }]
        };
        let v = Vec3A::new;
        tris.extend(quad(v(-6., -6., -5.), v(6., -6., -5.), v(6., 6., -5.), v(-6., 6., -5.)));
        tris.extend(quad(v(2., -6., -5.), v(2., 6., -5.), v(2., 6., 5.), v(2., -6., 5.)));
        tris
    }

    /// The closest of every triangle, each tested alone by obvhs's own intersection.
    fn brute_force(tris: &[RtTriangle], ray: &Ray) -> Option<(usize, f32)> {
        let hits = tris.iter().enumerate().map(|(i, t)| (i, t.intersect(ray)));
        hits.filter(|(_, t)| t.is_finite()).min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// The same distance, to the rounding of two ways of computing it.
    fn same(a: Option<f32>, b: Option<f32>) -> bool {
        match (a, b) {
            (Some(a), Some(b)) => (a - b).abs() <= 1e-5 * a.max(1.0),
            (a, b) => a == b,
        }
    }

    /// Rays from random points in random directions, and along the axes (whose reciprocal
    /// direction is infinite in two lanes), some with a finite reach.
    fn rays(rng: &mut KeyedRng) -> Vec<Ray> {
        let axes = [Vec3A::X, Vec3A::NEG_X, Vec3A::Y, Vec3A::NEG_Y, Vec3A::Z, Vec3A::NEG_Z];
        (0..3000)
            .map(|i| {
                let mut r = || rng.next_f32() * 14.0 - 7.0;
                let o = Vec3A::new(r(), r(), r());
                let d =
                    if i % 2 == 0 { Vec3A::new(r(), r(), r()).normalize() } else { axes[i % 6] };
                Ray::new(o, d, 0.0, if i % 5 == 0 { 4.0 } else { f32::INFINITY })
            })
            .collect()
    }

    #[test]
    fn closest_and_any_hits_are_those_of_every_triangle_tested() {
        let mut rng = KeyedRng::new(37);
        let tris = soup(&mut rng, 3000);
        let bvh = Bvh4::build(&tris, build_params());
        let placed: Vec<RtTriangle> =
            bvh.primitive_indices.iter().map(|&i| RtTriangle::from(&tris[i as usize])).collect();
        assert!(bvh.node_count() > 3000 / 4 / 4, "{} nodes", bvh.node_count());
        let (mut hits, mut axis_hits) = (0, 0);
        for (i, ray) in rays(&mut rng).iter().enumerate() {
            let found = bvh.closest(ray.origin, ray.direction, ray.tmax);
            let expected = brute_force(&placed, ray);
            assert!(same(found.map(|h| h.1), expected.map(|h| h.1)), "ray {i}: {ray:?}");
            let blocked = bvh.any_hit(ray.origin, ray.direction, ray.tmax);
            assert_eq!(blocked, expected.is_some(), "ray {i}: {ray:?}");
            hits += usize::from(expected.is_some());
            axis_hits += usize::from(expected.is_some() && i % 2 == 1);
        }
        assert!(hits > 1000 && axis_hits > 300, "{hits} hits, {axis_hits} along the axes");
    }

    #[test]
    fn a_single_triangle_is_a_leaf_under_the_root() {
        let v = Vec3A::new;
        let tris = [Triangle { v0: v(0., 0., 0.), v1: v(1., 0., 0.), v2: v(0., 1., 0.) }];
        let bvh = Bvh4::build(&tris, build_params());
        let inf = f32::INFINITY;
        assert_eq!(bvh.closest(v(0.2, 0.2, 1.0), -Vec3A::Z, inf), Some((0, 1.0)));
        assert!(bvh.any_hit(v(0.2, 0.2, 1.0), -Vec3A::Z, 1.5));
        assert!(
            !bvh.any_hit(v(0.2, 0.2, 1.0), -Vec3A::Z, 1.0),
            "a hit exactly at the reach does not block"
        );
        assert_eq!(bvh.closest(v(2.0, 0.2, 1.0), -Vec3A::Z, inf), None);
        assert!(!bvh.any_hit(v(2.0, 0.2, 1.0), -Vec3A::Z, inf));
    }
}
