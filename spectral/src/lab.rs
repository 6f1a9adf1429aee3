//! CIE 1976 L*a*b* (CIELAB), CIE 15:2004 §8.2.1, and its polar form L*C*h.

use crate::colorimetry::Xyz;
use serde::Serialize;

/// A CIELAB colour. `l` is lightness L* (0 black … 100 white), `a` the red–green and `b` the
/// yellow–blue opponent coordinates a*, b*.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lab {
    pub l: f64,
    pub a: f64,
    pub b: f64,
}

/// CIE 15:2004 Eq. 8.3: the cube-root compression with its linear segment near black.
/// δ = 6/29, so the break point is (6/29)³ ≈ 0.008856 and the slope (29/6)²/3 ≈ 7.787.
fn f(t: f64) -> f64 {
    const DELTA: f64 = 6.0 / 29.0;
    if t > DELTA * DELTA * DELTA { t.cbrt() } else { t / (3.0 * DELTA * DELTA) + 4.0 / 29.0 }
}

impl Lab {
    pub const fn new(l: f64, a: f64, b: f64) -> Self {
        Self { l, a, b }
    }

    /// CIELAB of `xyz` relative to the reference white `white` (both on the same scale, e.g.
    /// Y = 100 for the perfect reflecting diffuser under the illuminant).
    pub fn from_xyz(xyz: Xyz, white: Xyz) -> Self {
        let fx = f(xyz.x / white.x);
        let fy = f(xyz.y / white.y);
        let fz = f(xyz.z / white.z);
        Self { l: 116.0 * fy - 16.0, a: 500.0 * (fx - fy), b: 200.0 * (fy - fz) }
    }

    /// The inverse of [`Lab::from_xyz`].
    pub fn to_xyz(self, white: Xyz) -> Xyz {
        const DELTA: f64 = 6.0 / 29.0;
        let finv = |t: f64| {
            if t > DELTA { t * t * t } else { 3.0 * DELTA * DELTA * (t - 4.0 / 29.0) }
        };
        let fy = (self.l + 16.0) / 116.0;
        let fx = fy + self.a / 500.0;
        let fz = fy - self.b / 200.0;
        Xyz::new(white.x * finv(fx), white.y * finv(fy), white.z * finv(fz))
    }

    /// Chroma C*ab = √(a*² + b*²).
    pub fn chroma(self) -> f64 {
        self.a.hypot(self.b)
    }

    /// Hue angle h_ab in degrees, 0 ≤ h < 360.
    pub fn hue_deg(self) -> f64 {
        let h = self.b.atan2(self.a).to_degrees();
        if h < 0.0 { h + 360.0 } else { h }
    }

    /// The CIE 1976 colour difference ΔE*ab (Euclidean distance). Prefer
    /// [`crate::ciede2000::ciede2000`] for judging differences; this is here for reference.
    pub fn delta_e76(self, other: Lab) -> f64 {
        ((self.l - other.l).powi(2) + (self.a - other.a).powi(2) + (self.b - other.b).powi(2))
            .sqrt()
    }
}
