//! Matrices: 4×4, row-major, acting on column vectors, in f64 so deep hierarchies stay exact;
//! and the 3-vector helpers the builder and the primitives share.

pub(super) type Mat = [[f64; 4]; 4];
pub(super) type V3 = [f64; 3];

pub(super) const IDENTITY: Mat =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

pub(super) fn mul(a: &Mat, b: &Mat) -> Mat {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum()))
}

pub(super) fn translation(t: V3) -> Mat {
    let mut m = IDENTITY;
    for k in 0..3 {
        m[k][3] = t[k];
    }
    m
}

pub(super) fn scaling(s: V3) -> Mat {
    let mut m = IDENTITY;
    for k in 0..3 {
        m[k][k] = s[k];
    }
    m
}

/// The rotation of `angle` radians about `axis` (right-handed, §4.4.5's SFRotation); a zero
/// axis is no rotation.
pub(super) fn rotation(axis: V3, angle: f64) -> Mat {
    let len = dot(axis, axis).sqrt();
    if len == 0.0 || !len.is_finite() {
        return IDENTITY;
    }
    let [x, y, z] = axis.map(|a| a / len);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0.0],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0.0],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

pub(super) fn apply_point(m: &Mat, p: V3) -> V3 {
    std::array::from_fn(|i| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3])
}

pub(super) fn apply_linear(m: &[[f64; 3]; 3], v: V3) -> V3 {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

pub(super) fn linear(m: &Mat) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[i][j]))
}

pub(super) fn det3(m: &[[f64; 3]; 3]) -> f64 {
    dot(m[0], cross(m[1], m[2]))
}

/// The cofactor matrix, `det · (M⁻¹)ᵀ`: it carries normals through `M` even when `M` is
/// singular, and differs from the inverse transpose only by the factor `det`.
pub(super) fn cofactor(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
            m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
        })
    })
}

/// Whether a number is finite as a 32-bit float, which the mesh stores.
pub(super) fn fits_f32(x: f64) -> bool {
    x.is_finite() && x.abs() <= f32::MAX as f64
}

pub(super) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub(super) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(super) fn normalized(v: V3) -> Option<V3> {
    let len = dot(v, v).sqrt();
    (len > 0.0 && len.is_finite()).then(|| v.map(|x| x / len))
}

/// The rotation nearest a linear map, by Gram–Schmidt on its columns (exact for rotations
/// times uniform scales, the usual case; good enough for a camera otherwise).
pub(super) fn rotation_part(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let column = |j: usize| [m[0][j], m[1][j], m[2][j]];
    let Some(x) = normalized(column(0)) else { return linear(&IDENTITY) };
    let y = sub(column(1), x.map(|c| c * dot(x, column(1))));
    let Some(y) = normalized(y) else { return linear(&IDENTITY) };
    let z = cross(x, y);
    std::array::from_fn(|i| [x[i], y[i], z[i]])
}

/// A rotation matrix as an axis and angle (via a unit quaternion, stable near 0 and π).
pub(super) fn axis_angle(r: &[[f64; 3]; 3]) -> (V3, f64) {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        [0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
        [(r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s]
    } else if r[1][1] > r[2][2] {
        let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
        [(r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s]
    } else {
        let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
        [(r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s]
    };
    let v = [q[1], q[2], q[3]];
    let len = dot(v, v).sqrt();
    if len.is_nan() || len <= 1e-12 || !q[0].is_finite() {
        return ([0.0, 0.0, 1.0], 0.0);
    }
    (v.map(|c| c / len), 2.0 * len.atan2(q[0]))
}

// ---------------------------------------------------------------------------------------------
