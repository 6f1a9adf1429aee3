//! The sky dome, an extended source: its luminance L_v(ω) (cd/m²) over the directions above
//! the horizon, whose spectral radiance is L_v(ω) · S_e(λ)/Σ K S_e Δλ, and below the horizon
//! the ground's uniform luminance when the scene gives one.
//!
//! It is sampled at a point with normal n by a cosine-weighted direction (pdf cos θ/π), whose
//! estimate of ∫ f L cos θ dω is f · L · π. A CIE general sky, which can be far brighter around
//! the sun than elsewhere, is also sampled by its luminance (a piecewise-constant distribution
//! over 64 × 128 cells of equal solid angle), and the two samples are combined by the balance
//! heuristic of multiple importance sampling (Veach & Guibas 1995): each estimates
//! f · L · cos θ / (p_cos + p_sky), so neither technique's weakness shows.

use glam::Vec3A;
use restauro_scene::cie_sky::GeneralSky;
use restauro_scene::scene_file::SkyModel;
use restauro_spectral::Spectrum;
use std::f32::consts::{PI, TAU};

#[derive(Clone, Debug)]
pub struct Sky {
    /// S_e(λ)/Σ K S_e Δλ: the spectral radiance of one cd/m² (W·sr⁻¹·m⁻²·nm⁻¹).
    pub per_nit: Spectrum,
    /// The luminance at the zenith, cd/m².
    pub zenith_cd_m2: f32,
    pub model: SkyModel,
    general: Option<GeneralSky>,
    ground_cd_m2: f32,
    distribution: Option<Distribution>,
}

/// One direction to sample the sky along: the estimate of ∫ f L cos θ dω it gives is
/// f(direction) · `luminance_cd_m2` · `weight`.
#[derive(Clone, Copy, Debug)]
pub struct SkySample {
    pub direction: Vec3A,
    pub luminance_cd_m2: f32,
    pub weight: f32,
}

impl Sky {
    /// A sky giving `illuminance_lux` on a horizontal surface open to all of it (the ground not
    /// counted): uniform, E_h = π L; CIE overcast, E_h = ∫ L_z (1 + 2 cos θ)/3 · cos θ dω =
    /// 7π L_z / 9; a general sky, E_h = L_z · (D_v/L_z) by quadrature.
    pub fn new(
        illuminance_lux: f64,
        model: SkyModel,
        per_nit: Spectrum,
        general: Option<GeneralSky>,
        ground_cd_m2: f64,
    ) -> Self {
        let zenith = match (model, &general) {
            (SkyModel::Uniform, _) => illuminance_lux / std::f64::consts::PI,
            (SkyModel::CieOvercast, _) => 9.0 * illuminance_lux / (7.0 * std::f64::consts::PI),
            (SkyModel::CieGeneral, Some(g)) => illuminance_lux / g.horizontal_over_zenith(),
            (SkyModel::CieGeneral, None) => 0.0,
        };
        let mut sky = Self {
            per_nit,
            zenith_cd_m2: zenith as f32,
            model,
            general,
            ground_cd_m2: ground_cd_m2 as f32,
            distribution: None,
        };
        if general.is_some() {
            sky.distribution = Some(Distribution::new(&sky));
        }
        sky
    }

    /// The luminance (cd/m²) seen looking along `direction` (unit; +Z up): the ground's below
    /// the horizon.
    #[inline]
    pub fn luminance_cd_m2(&self, direction: Vec3A) -> f32 {
        let cos_theta = direction.z;
        if cos_theta <= 0.0 {
            return self.ground_cd_m2;
        }
        match (self.model, &self.general) {
            (SkyModel::Uniform, _) => self.zenith_cd_m2,
            (SkyModel::CieOvercast, _) => self.zenith_cd_m2 * (1.0 + 2.0 * cos_theta) / 3.0,
            (SkyModel::CieGeneral, Some(g)) => {
                let d = direction.to_array().map(f64::from);
                self.zenith_cd_m2 * g.relative_luminance(d) as f32
            }
            (SkyModel::CieGeneral, None) => 0.0,
        }
    }

    /// The samples at a point of unit `normal`: the cosine-weighted `cosine_direction` (already
    /// drawn), and for a sky sampled by its luminance one more direction drawn with `draw`.
    #[inline]
    pub fn samples(
        &self,
        normal: Vec3A,
        cosine_direction: Vec3A,
        draw: impl FnMut() -> (f32, f32),
    ) -> [Option<SkySample>; 2] {
        let Some(dist) = &self.distribution else {
            let luminance_cd_m2 = self.luminance_cd_m2(cosine_direction);
            return [
                Some(SkySample { direction: cosine_direction, luminance_cd_m2, weight: PI }),
                None,
            ];
        };
        let balanced = |direction: Vec3A| {
            let cos = direction.dot(normal);
            let pdf = cos.max(0.0) / PI + dist.pdf(direction);
            (cos > 0.0 && pdf > 0.0).then(|| SkySample {
                direction,
                luminance_cd_m2: self.luminance_cd_m2(direction),
                weight: cos / pdf,
            })
        };
        [balanced(cosine_direction), balanced(dist.sample(draw))]
    }
}

const ROWS: usize = 64;
const COLUMNS: usize = 128;
const D_MU: f32 = 2.0 / ROWS as f32;
const D_PHI: f32 = TAU / COLUMNS as f32;

/// A piecewise-constant distribution over the sphere, proportional to the sky's luminance at
/// the centre of each of ROWS × COLUMNS cells of equal solid angle (rows of cos θ from −1 to 1,
/// columns of azimuth from +X towards +Y).
#[derive(Clone, Debug)]
struct Distribution {
    /// Each cell's probability over its solid angle, row-major.
    density: Vec<f32>,
    /// The cumulative probability of the rows (ROWS + 1 entries).
    rows: Vec<f32>,
    /// Within each row, the cumulative probability of its cells (COLUMNS + 1 a row).
    columns: Vec<f32>,
}

impl Distribution {
    fn new(sky: &Sky) -> Self {
        let mut weight = vec![0f32; ROWS * COLUMNS];
        for (i, row) in weight.chunks_mut(COLUMNS).enumerate() {
            let mu = -1.0 + (i as f32 + 0.5) * D_MU;
            for (j, w) in row.iter_mut().enumerate() {
                *w = sky.luminance_cd_m2(direction(mu, (j as f32 + 0.5) * D_PHI));
            }
        }
        let total: f32 = weight.iter().sum();
        let scale = if total > 0.0 { 1.0 / total } else { 0.0 };
        let mut rows = Vec::with_capacity(ROWS + 1);
        let mut columns = Vec::with_capacity(ROWS * (COLUMNS + 1));
        let mut row_sum = 0.0;
        rows.push(0.0);
        for row in weight.chunks(COLUMNS) {
            let in_row: f32 = row.iter().sum();
            row_sum += in_row * scale;
            rows.push(row_sum);
            let mut acc = 0.0;
            columns.push(0.0);
            for w in row {
                acc += if in_row > 0.0 { w / in_row } else { 1.0 / COLUMNS as f32 };
                columns.push(acc);
            }
        }
        let density = weight.iter().map(|w| w * scale / (D_MU * D_PHI)).collect();
        Self { density, rows, columns }
    }

    /// The density (per steradian) of `direction` (unit).
    #[inline]
    fn pdf(&self, direction: Vec3A) -> f32 {
        let i = (((direction.z + 1.0) / D_MU) as usize).min(ROWS - 1);
        let phi = direction.y.atan2(direction.x).rem_euclid(TAU);
        let j = ((phi / D_PHI) as usize).min(COLUMNS - 1);
        self.density[i * COLUMNS + j]
    }

    /// A direction drawn from the distribution: a row, a cell in it, a point in the cell.
    #[inline]
    fn sample(&self, mut draw: impl FnMut() -> (f32, f32)) -> Vec3A {
        let (u1, u2) = draw();
        let (s, t) = draw();
        let i =
            (self.rows.partition_point(|&c| c <= u1 * self.rows[ROWS]).max(1) - 1).min(ROWS - 1);
        let row = &self.columns[i * (COLUMNS + 1)..(i + 1) * (COLUMNS + 1)];
        let j = (row.partition_point(|&c| c <= u2 * row[COLUMNS]).max(1) - 1).min(COLUMNS - 1);
        direction(-1.0 + (i as f32 + s) * D_MU, (j as f32 + t) * D_PHI)
    }
}

/// The unit direction of cos θ = `mu` and azimuth `phi` (from +X towards +Y).
#[inline]
fn direction(mu: f32, phi: f32) -> Vec3A {
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    Vec3A::new(s * phi.cos(), s * phi.sin(), mu)
}

#[cfg(test)]
mod tests {
    use super::*;
    use restauro_scene::sun::{SunPosition, direction_to_sun};

    fn clear_sky() -> Sky {
        let sun = direction_to_sun(SunPosition { azimuth_deg: 200.0, elevation_deg: 35.0 });
        let general = GeneralSky::new(15, sun);
        Sky::new(20_000.0, SkyModel::CieGeneral, Spectrum::ONE, Some(general), 0.0)
    }

    /// The density integrates to one over the sphere, and samples land where it is.
    #[test]
    fn the_distribution_is_a_density_and_samples_from_it() {
        let sky = clear_sky();
        let dist = sky.distribution.as_ref().unwrap();
        let integral: f32 = dist.density.iter().sum::<f32>() * D_MU * D_PHI;
        assert!((integral - 1.0).abs() < 1e-4, "{integral}");
        let mut state = 1u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (
                (state >> 40) as f32 / (1u64 << 24) as f32,
                (state >> 16 & 0xFFFFFF) as f32 / (1u64 << 24) as f32,
            )
        };
        for _ in 0..1000 {
            let d = dist.sample(&mut next);
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z > 0.0, "{d}");
            assert!(dist.pdf(d) > 0.0);
        }
    }
}
