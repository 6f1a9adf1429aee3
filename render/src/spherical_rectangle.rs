//! Sampling a rectangle by the solid angle it subtends (Ureña, Fajardo & King, "An area-
//! preserving parametrization for spherical rectangles", Computer Graphics Forum 32(4), 2013).
//! Each direction towards the rectangle is equally likely, pdf 1/Ω: from a point close to an
//! area luminaire, the estimate of ∫ L cos θ dω is L · cos θ · Ω, free of the 1/r² that makes
//! sampling by area noisy there.

use glam::Vec3A;
use std::f32::consts::TAU;

/// A rectangle seen from a point, ready to sample: its local frame (x, y along the edges, z
/// away from the rectangle's plane towards the point's side negated) and the spherical
/// rectangle's constants.
pub struct SphericalRectangle {
    origin: Vec3A,
    x: Vec3A,
    y: Vec3A,
    z: Vec3A,
    z0: f32,
    x0: f32,
    x1: f32,
    y0: f32,
    y1: f32,
    b0: f32,
    b1: f32,
    k: f32,
    /// The solid angle, sr.
    pub solid_angle: f32,
}

impl SphericalRectangle {
    /// The rectangle `corner` + s·`u` + t·`v` (u ⟂ v) seen from `origin`; `None` from its plane
    /// or when it subtends no measurable solid angle.
    pub fn new(corner: Vec3A, u: Vec3A, v: Vec3A, origin: Vec3A) -> Option<Self> {
        let (ul, vl) = (u.length(), v.length());
        let (x, y) = (u / ul, v / vl);
        let mut z = x.cross(y);
        let d = corner - origin;
        let mut z0 = d.dot(z);
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        if z0 == 0.0 {
            return None;
        }
        let (x0, y0) = (d.dot(x), d.dot(y));
        let (x1, y1) = (x0 + ul, y0 + vl);
        let corners = [
            Vec3A::new(x0, y0, z0),
            Vec3A::new(x1, y0, z0),
            Vec3A::new(x1, y1, z0),
            Vec3A::new(x0, y1, z0),
        ];
        // The normals of the planes through the origin and each edge, and the interior angles.
        let n: [Vec3A; 4] =
            std::array::from_fn(|i| corners[i].cross(corners[(i + 1) % 4]).normalize());
        let g: [f32; 4] =
            std::array::from_fn(|i| (-n[i].dot(n[(i + 1) % 4])).clamp(-1.0, 1.0).acos());
        let k = TAU - g[2] - g[3];
        let solid_angle = g[0] + g[1] - k;
        (solid_angle > 1e-7 && solid_angle.is_finite()).then_some(Self {
            origin,
            x,
            y,
            z,
            z0,
            x0,
            x1,
            y0,
            y1,
            b0: n[0].z,
            b1: n[2].z,
            k,
            solid_angle,
        })
    }

    /// The point of the rectangle in the direction (u, v) ∈ [0, 1)² picks, each direction with
    /// density 1/Ω.
    pub fn sample(&self, u: f32, v: f32) -> Vec3A {
        let au = u * self.solid_angle + self.k;
        let fu = (au.cos() * self.b0 - self.b1) / au.sin();
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt()).copysign(fu).clamp(-1.0, 1.0);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(1e-12).sqrt()).clamp(self.x0, self.x1);
        let d = (xu * xu + self.z0 * self.z0).sqrt();
        let h0 = self.y0 / (d * d + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d * d + self.y1 * self.y1).sqrt();
        let hv = h0 + v * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-6 { hv * d / (1.0 - hv2).sqrt() } else { self.y1 };
        self.origin + self.x * xu + self.y * yv.clamp(self.y0, self.y1) + self.z * self.z0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The solid angle of a unit square 1 m above its centre: 4 asin(1/3)·… — here against the
    /// closed form for a rectangle seen from above a corner, Ω = asin(sin α sin β) with
    /// tan α = a/h, tan β = b/h, four times for the centre; and every sample lies on the square.
    #[test]
    fn solid_angle_and_samples_on_the_rectangle() {
        let r =
            SphericalRectangle::new(Vec3A::new(-0.5, -0.5, 1.0), Vec3A::X, Vec3A::Y, Vec3A::ZERO)
                .unwrap();
        let quarter = |a: f32, b: f32, h: f32| {
            let (al, be) = ((a / h).atan(), (b / h).atan());
            (al.sin() * be.sin()).asin()
        };
        let expected = 4.0 * quarter(0.5, 0.5, 1.0);
        assert!((r.solid_angle - expected).abs() < 1e-5, "{} against {expected}", r.solid_angle);
        for (u, v) in [(0.0, 0.0), (0.3, 0.7), (0.999, 0.5), (0.5, 0.999)] {
            let p = r.sample(u, v);
            assert!((p.z - 1.0).abs() < 1e-5 && p.x.abs() <= 0.5 + 1e-5 && p.y.abs() <= 0.5 + 1e-5);
        }
        assert!(
            SphericalRectangle::new(Vec3A::ZERO, Vec3A::X, Vec3A::Y, Vec3A::new(0.2, 0.2, 0.0))
                .is_none()
        );
    }
}
