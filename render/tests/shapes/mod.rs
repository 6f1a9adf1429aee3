//! Meshes the tracer's tests share, as OBJ text.

use std::f64::consts::PI;
use std::fmt::Write as _;

/// A unit sphere of 96 × 48 facets, wound to face inwards.
pub fn inward_sphere() -> String {
    let mut obj = String::new();
    let (nu, nv) = (96usize, 48usize);
    for j in 0..=nv {
        let t = PI * j as f64 / nv as f64;
        for i in 0..nu {
            let p = 2.0 * PI * i as f64 / nu as f64;
            let _ = writeln!(obj, "v {} {} {}", t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let a = j * nu + i + 1;
            let b = j * nu + (i + 1) % nu + 1;
            let (c, d) = (a + nu, b + nu);
            // Wound to face inwards.
            let _ = writeln!(obj, "f {a} {b} {d} {c}");
        }
    }
    obj
}
