//! The numbers of a glass pane that the scene checks and the renderer uses: the default pane
//! and the most a pane of a given index can transmit.

/// 6 mm of clear float glass transmits 0.88 at normal incidence (n = 1.52).
pub const DEFAULT_THICKNESS_MM: f64 = 6.0;
pub const DEFAULT_TRANSMITTANCE: f64 = 0.88;
pub const DEFAULT_IOR: f64 = 1.52;

/// The reflectance of one face at normal incidence, r = ((n − 1)/(n + 1))² (Fresnel).
pub fn face_reflectance(n: f64) -> f64 {
    ((n - 1.0) / (n + 1.0)).powi(2)
}

/// The most a pane of index `n` can transmit at normal incidence (no absorption), summing the
/// inter-reflections between its faces: (1 − r)²/(1 − r²) = (1 − r)/(1 + r).
pub fn max_transmittance(n: f64) -> f64 {
    let r = face_reflectance(n);
    (1.0 - r) / (1.0 + r)
}

#[cfg(test)]
mod tests {
    /// n = 1.5: r = 0.04, (1 − r)/(1 + r) = 0.96/1.04 = 0.923077.
    #[test]
    fn a_pane_of_index_one_and_a_half_transmits_at_most_0_923() {
        assert!((super::max_transmittance(1.5) - 0.96 / 1.04).abs() < 1e-12);
        assert!((super::face_reflectance(1.5) - 0.04).abs() < 1e-12);
    }
}
