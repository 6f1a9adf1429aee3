//! Adaptation through time: the eye that watches a sequence has adapted to the frames before
//! this one, not to this one alone.
//!
//! A seen image adapts to the light the renderer measured (the module above): its white level
//! Y_g and its white Ŵ. An eye that has just come from other light is not there yet. Two
//! mechanisms, each with published time constants, and one state each, carried from frame to
//! frame:
//!
//! - **Level** (light adaptation of the cones). Pattanaik, Tumblin, Yee & Greenberg,
//!   "Time-dependent visual adaptation for fast realistic image display" (SIGGRAPH 2000), model
//!   the cones' neural adaptation as a first-order filter of the adapting luminance with
//!   t₀ = 80 ms:
//!
//!   ```text
//!     L(t + Δt) = L_g + (L(t) − L_g) · e^(−Δt / t₀)
//!   ```
//!
//!   Their slower terms are photopigment bleaching (cones: τ = 110 s, a share L/(L + 2·10⁶ cd/m²)
//!   bleached at equilibrium) and the rods' (τ = 400 s). A white in full sun, about
//!   3·10⁴ cd/m², bleaches the cones by 1.5 %, a change of gain under the seen image's other
//!   uncertainties, so bleaching is left out; the rods enter the seen image only through
//!   CIE 191's mesopic coefficient, which is computed from the adapted level.
//! - **Colour** (chromatic adaptation). Rinner & Gegenfurtner, "Time course of chromatic
//!   adaptation for color appearance and discrimination" (Vision Research 40, 2000), measured
//!   achromatic matches after a step of the light's colour: an instantaneous share of *more than
//!   50 %* (half-life under 10 ms), a photoreceptor share with a half-life of 40–70 ms, and a
//!   slow share with a half-life of about 20 s. The photoreceptor share is complete within a
//!   quarter of a second, under every frame step but a fast walk's; it is counted with the
//!   instantaneous one. The paper's abstract does not split the remainder, so the slow share is
//!   taken as all the rest, 50 %: the most lag their measurements allow. The white the eye
//!   adapts to is then, in CAT16 cone responses of a white of Y = 1,
//!
//!   ```text
//!     ρ_eye = s·ρ_W + (1 − s)·S,   S(t + Δt) = ρ_W + (S(t) − ρ_W) · 2^(−Δt / T½),
//!   ```
//!
//!   with s = 0.5 and T½ = 20 s, and every pixel's own white Ŵ(p) is moved by the cone ratio
//!   ρ_eye / ρ_W (von Kries): the eye's lag is one state for the whole view, its spatial
//!   adaptation the seen image's own.
//!
//! A state within a millionth of the light's is the light's: after steady light for twenty slow
//! half-lives (under seven minutes; after one hour for any step) a frame is seen exactly as the
//! same image alone, and a sun study's frames, an hour or a quarter of one apart, are. The same light in every frame gives the same state, so identical frames.
//! Monte Carlo noise in a frame's white moves the slow half of the colour state by
//! 1 − 2^(−Δt / 20 s) of it: 0.14 % a frame at 25 frames a second.

use crate::colorimetry::Xyz;
use crate::error::{Error, Result};
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// t₀ of the cones' neural adaptation (Pattanaik et al. 2000).
pub const CONE_TIME_CONSTANT_S: f64 = 0.080;
/// The share of chromatic adaptation that is immediate (Rinner & Gegenfurtner 2000: "more than
/// 50 %"; its lower bound, with the photoreceptors' 40–70 ms share counted in).
pub const CHROMATIC_INSTANT_SHARE: f64 = 0.5;
/// The half-life of the slow share of chromatic adaptation (Rinner & Gegenfurtner 2000).
pub const CHROMATIC_HALF_LIFE_S: f64 = 20.0;
/// A state within this share of the light's is the light's: the eye is adapted.
const ADAPTED_WITHIN: f64 = 1e-6;
/// The longest step between two frames taken as time passing (a year); beyond it, or for a
/// negative or non-finite step, the frame is refused (the caller computes steps from frame
/// times).
const MAX_ELAPSED_S: f64 = 3.2e7;

/// The adaptation state of an eye after a frame: what it carries to the next.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EyeState {
    /// The luminance level (cd/m²) the cones are adapted to: the image's white level Y_g when
    /// the light has been steady.
    pub level_cd_m2: f64,
    /// The white of the slow chromatic mechanism, S: CAT16 cone responses of a white of Y = 1.
    pub slow_cones: [f64; 3],
}

/// What an eye brings to a frame: its state after the frame before, and the time since.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeHistory {
    pub before: EyeState,
    pub elapsed_s: f64,
}

/// How far the eye is from a frame's light: the factor on the level it adapts to, and the cone
/// ratio ρ_eye / ρ_W on the white. Both 1 for an eye adapted to the frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lag {
    pub level_ratio: f64,
    pub cone_ratio: [f64; 3],
}

impl Lag {
    /// An eye adapted to the frame: no change to today's seen image.
    pub fn is_none(&self) -> bool {
        self.level_ratio == 1.0 && self.cone_ratio == [1.0; 3]
    }

    /// The matrix that moves a white (XYZ) by the cone ratio: M16⁻¹ · diag(ρ_eye/ρ_W) · M16.
    pub(super) fn white_matrix(&self) -> DMat3 {
        let (m, m_inv) = super::degree::cat16_matrices();
        m_inv * DMat3::from_diagonal(DVec3::from(self.cone_ratio)) * m
    }
}

/// CAT16 cone responses of `white` scaled to Y = 1 (the D65 white's when `white` is black: a
/// view with no light on any surface leaves the colour state where it is neutral).
pub fn cones_of(white: Xyz) -> [f64; 3] {
    let white =
        if white.y > 0.0 && white.y.is_finite() { white } else { crate::appearance::d65_white() };
    let (m, _) = super::degree::cat16_matrices();
    (m * DVec3::new(white.x, white.y, white.z) / white.y).to_array()
}

/// The state an eye adapted to the frame's light is in: level `level_cd_m2`, white `white`.
pub fn adapted(level_cd_m2: f64, white: Xyz) -> EyeState {
    EyeState { level_cd_m2, slow_cones: cones_of(white) }
}

fn check(history: &EyeHistory) -> Result<()> {
    let elapsed = history.elapsed_s;
    if !(elapsed.is_finite() && (0.0..=MAX_ELAPSED_S).contains(&elapsed)) {
        return Err(Error::OutOfRange {
            quantity: "time since the frame before (s)",
            value: elapsed,
            expected: "from 0 to a year, in seconds; frames' times must not go back",
        });
    }
    let before = &history.before;
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !(positive(before.level_cd_m2) && before.slow_cones.iter().all(|&c| positive(c))) {
        return Err(Error::OutOfRange {
            quantity: "the eye's level before the frame (cd/m²)",
            value: before.level_cd_m2,
            expected: "a finite level > 0 and finite cone responses > 0, as a seen frame leaves \
                       them",
        });
    }
    Ok(())
}

/// `light + (before − light) · share`, a state `share` of its step from the light; the light's
/// own value once within a millionth of it (the eye is adapted).
fn towards(light: f64, before: f64, share: f64) -> f64 {
    let state = light + (before - light) * share;
    if (state - light).abs() <= ADAPTED_WITHIN * light.abs() { light } else { state }
}

/// The eye after a frame whose light is `light` (its level and white: [`adapted`]), coming with
/// `history` (none: the frame is seen alone, by an eye adapted to it), and its lag from the
/// frame's light.
pub fn adapt(light: EyeState, history: Option<&EyeHistory>) -> Result<(EyeState, Lag)> {
    let Some(history) = history else {
        return Ok((light, Lag { level_ratio: 1.0, cone_ratio: [1.0; 3] }));
    };
    check(history)?;
    let before = history.before;
    let elapsed_s = history.elapsed_s;
    let level_cd_m2 =
        towards(light.level_cd_m2, before.level_cd_m2, (-elapsed_s / CONE_TIME_CONSTANT_S).exp());
    let slow_share = (-elapsed_s / CHROMATIC_HALF_LIFE_S).exp2();
    let slow_cones: [f64; 3] =
        std::array::from_fn(|i| towards(light.slow_cones[i], before.slow_cones[i], slow_share));
    let s = CHROMATIC_INSTANT_SHARE;
    let cone_ratio: [f64; 3] = std::array::from_fn(|i| {
        let target = light.slow_cones[i];
        (s * target + (1.0 - s) * slow_cones[i]) / target
    });
    let level_ratio = level_cd_m2 / light.level_cd_m2;
    Ok((EyeState { level_cd_m2, slow_cones }, Lag { level_ratio, cone_ratio }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Chromaticity;

    fn light(level: f64, x: f64, y: f64) -> EyeState {
        adapted(level, Chromaticity::new(x, y).to_xyz(1.0))
    }

    #[test]
    fn an_eye_in_steady_light_has_no_lag() {
        let l = light(3000.0, 0.3127, 0.3290);
        for elapsed_s in [0.0, 0.04, 1.0, 3600.0] {
            let (eye, lag) = adapt(l, Some(&EyeHistory { before: l, elapsed_s })).unwrap();
            assert_eq!(eye, l);
            assert!(lag.is_none(), "{lag:?}");
        }
        assert!(adapt(l, None).unwrap().1.is_none());
    }

    #[test]
    fn after_one_half_life_the_slow_colour_state_is_half_way() {
        // From CIE A's white to D65's, 20 s later: the slow state is midway (the half-life's
        // definition), and the eye's white is three quarters of the way in cone terms.
        let (a, d65) = (light(1000.0, 0.44758, 0.40745), light(1000.0, 0.3127, 0.3290));
        let (eye, lag) = adapt(d65, Some(&EyeHistory { before: a, elapsed_s: 20.0 })).unwrap();
        for i in 0..3 {
            let mid = 0.5 * (a.slow_cones[i] + d65.slow_cones[i]);
            assert!((eye.slow_cones[i] - mid).abs() < 1e-12);
            let eye_white = 0.75 * d65.slow_cones[i] + 0.25 * a.slow_cones[i];
            assert!((lag.cone_ratio[i] - eye_white / d65.slow_cones[i]).abs() < 1e-12);
        }
        // The level, 80 ms after a step from 1000 to 2000 cd/m², has gone 1 − 1/e of the way.
        let brighter = light(2000.0, 0.3127, 0.3290);
        let (eye, lag) =
            adapt(brighter, Some(&EyeHistory { before: d65, elapsed_s: 0.08 })).unwrap();
        let expect = 2000.0 - 1000.0 * (-1.0f64).exp();
        assert!((eye.level_cd_m2 - expect).abs() < 1e-9, "{}", eye.level_cd_m2);
        assert!((lag.level_ratio - expect / 2000.0).abs() < 1e-12);
    }

    #[test]
    fn after_long_enough_the_eye_is_the_lights() {
        let (a, d65) = (light(10.0, 0.44758, 0.40745), light(5000.0, 0.3127, 0.3290));
        // 2^(−20) of the step is left after 400 s: below a millionth, so none.
        let (eye, lag) = adapt(d65, Some(&EyeHistory { before: a, elapsed_s: 400.0 })).unwrap();
        assert_eq!(eye, d65);
        assert!(lag.is_none());
        let (_, lag) = adapt(d65, Some(&EyeHistory { before: a, elapsed_s: 60.0 })).unwrap();
        assert!(!lag.is_none());
    }

    #[test]
    fn bad_histories_are_refused() {
        let l = light(100.0, 0.3127, 0.3290);
        for elapsed_s in [-1.0, f64::NAN, f64::INFINITY, 1e9] {
            let e = adapt(l, Some(&EyeHistory { before: l, elapsed_s })).unwrap_err();
            assert!(e.to_string().contains("time since the frame before"), "{e}");
        }
        let before = EyeState { level_cd_m2: 0.0, ..l };
        assert!(adapt(l, Some(&EyeHistory { before, elapsed_s: 1.0 })).is_err());
    }
}
