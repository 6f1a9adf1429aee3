//! The wavelength grid of the paper: 380–780 nm in 5 nm steps, 81 bands, every band on every ray
//! (Rossi, Marini & Rizzi 2004, §2.1). The 5 nm spacing is also the CIE's recommended interval for
//! colorimetric summation (CIE 15:2004 §7.1), so sums over the grid are the CIE's own.

/// The first wavelength of the grid, in nanometres.
pub const LAMBDA_MIN_NM: f64 = 380.0;
/// The last wavelength of the grid, in nanometres.
pub const LAMBDA_MAX_NM: f64 = 780.0;
/// The spacing Δλ of the grid, in nanometres.
pub const STEP_NM: f64 = 5.0;
/// The number of bands: (780 − 380) / 5 + 1.
pub const BANDS: usize = 81;

/// The wavelength of band `i`, in nanometres.
#[inline]
pub const fn wavelength_nm(i: usize) -> f64 {
    LAMBDA_MIN_NM + STEP_NM * i as f64
}

/// All 81 wavelengths of the grid, in nanometres.
pub fn wavelengths_nm() -> [f64; BANDS] {
    std::array::from_fn(wavelength_nm)
}

/// The band whose wavelength is exactly `wavelength_nm`, if it lies on the grid.
pub fn band_of(wavelength_nm: f64) -> Option<usize> {
    let k = (wavelength_nm - LAMBDA_MIN_NM) / STEP_NM;
    let i = k.round();
    ((k - i).abs() < 1e-9 && (0.0..BANDS as f64).contains(&i)).then_some(i as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_spans_380_to_780_in_81_bands() {
        assert_eq!(wavelength_nm(0), 380.0);
        assert_eq!(wavelength_nm(BANDS - 1), 780.0);
        assert_eq!(band_of(555.0), Some(35));
        assert_eq!(band_of(556.0), None);
        assert_eq!(band_of(785.0), None);
        assert_eq!(band_of(375.0), None);
    }
}
