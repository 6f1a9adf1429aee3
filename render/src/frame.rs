//! Where and how rays leave a surface: a local frame about its normal, in which BSDFs and
//! sampled directions are expressed, and the point lifted off it that the rays start from.
//! The integrators, the calculation grids' sensors, the soiling's exposure rays and the shadow
//! rays through glass all leave surfaces this way.

use glam::Vec3A;

/// A local frame around a normal (Duff et al., "Building an orthonormal basis, revisited",
/// JCGT 6(1), 2017).
#[derive(Clone, Copy)]
pub(crate) struct Frame {
    x: Vec3A,
    y: Vec3A,
    z: Vec3A,
}

impl Frame {
    #[inline]
    pub(crate) fn new(n: Vec3A) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            x: Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            y: Vec3A::new(b, sign + n.y * n.y * a, -n.y),
            z: n,
        }
    }
    #[inline]
    pub(crate) fn to_local(self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }
    #[inline]
    pub(crate) fn to_world(self, v: Vec3A) -> Vec3A {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

/// `point` lifted off its surface along the unit `normal`, against self-intersection in f32.
#[inline]
pub fn lift_along(point: Vec3A, normal: Vec3A) -> Vec3A {
    let scale = 1.0 + point.abs().max_element();
    point + normal * (2e-5 * scale)
}
