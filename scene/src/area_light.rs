//! Area luminaires: a Lambertian emitting rectangle, checked once. Its luminance L (cd/m²) is
//! the same in every direction on its emitting side; its flux is Φ = π L A (the integral of
//! L cos θ over the hemisphere, times its area), so a luminaire given by its flux has
//! L = Φ/(π A).

use glam::DVec3;

/// The brightest luminance accepted, cd/m²: about the sun's disc (1.6 × 10⁹); beyond it a
/// number is a slip of units.
pub const MAX_LUMINANCE_CD_M2: f64 = 1e10;

/// The rectangle: `corner`, its two edges `u` and `v` (at a right angle), and the unit normal
/// of its emitting side.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    pub corner: [f64; 3],
    pub u: [f64; 3],
    pub v: [f64; 3],
    pub normal: [f64; 3],
}

/// A field (after the light's place, e.g. `u`) and what is wrong with it.
pub type Refusal = (&'static str, String);

impl Panel {
    /// Checks the rectangle: finite and within ±10⁹ m, edges that are not zero and meet at a
    /// right angle, and a `normal` (if given) that picks a side.
    pub fn new(
        corner: [f64; 3],
        u: [f64; 3],
        v: [f64; 3],
        normal: Option<[f64; 3]>,
    ) -> Result<Self, Refusal> {
        let within = |p: [f64; 3]| {
            p.iter().all(|x| x.is_finite() && x.abs() <= crate::limits::MAX_COORDINATE_M)
        };
        for (field, p) in [("corner", corner), ("u", u), ("v", v)] {
            if !within(p) {
                return Err((field, format!("{p:?} is out of range; give metres within ±1e9")));
            }
        }
        let (du, dv) = (DVec3::from_array(u), DVec3::from_array(v));
        if du.length() == 0.0 || dv.length() == 0.0 {
            let field = if du.length() == 0.0 { "u" } else { "v" };
            return Err((
                field,
                "an edge of length 0; give the rectangle's two edges in metres".into(),
            ));
        }
        let cos = du.dot(dv) / (du.length() * dv.length());
        if cos.abs() > 1e-6 {
            let angle = cos.clamp(-1.0, 1.0).acos().to_degrees();
            let problem = format!(
                "u and v meet at {angle:.3}°; an area luminaire is a rectangle, give edges at 90°"
            );
            return Err(("v", problem));
        }
        let spanned = du.cross(dv).normalize();
        let unit = match normal {
            None => spanned,
            Some(n) => {
                let side = DVec3::from_array(n).dot(spanned);
                if !side.is_finite() || side == 0.0 {
                    let problem = format!(
                        "{n:?} does not pick a side of the rectangle; give a direction off its plane"
                    );
                    return Err(("normal", problem));
                }
                spanned * side.signum()
            }
        };
        Ok(Self { corner, u, v, normal: unit.to_array() })
    }

    pub fn area_m2(&self) -> f64 {
        DVec3::from_array(self.u).cross(DVec3::from_array(self.v)).length()
    }
}

/// The luminance a panel is given: `luminance_cd_m2`, or `flux_lm` spread over its area,
/// L = Φ/(π A). The field in the refusal starts with its dot (`.flux_lm`), or is empty.
pub fn luminance(
    panel: &Panel,
    luminance_cd_m2: Option<f64>,
    flux_lm: Option<f64>,
) -> Result<f64, Refusal> {
    let l = match (luminance_cd_m2, flux_lm) {
        (Some(_), Some(_)) => {
            return Err((
                "",
                "give luminance_cd_m2 or flux_lm, not both (one follows from the other)".into(),
            ));
        }
        (None, None) => return Err(("", "give luminance_cd_m2 or flux_lm".into())),
        (Some(l), None) => l,
        (None, Some(lm)) => {
            if !(lm.is_finite() && (0.0..=1e10).contains(&lm)) {
                return Err((
                    ".flux_lm",
                    format!("{lm} is not a luminous flux; give lumens from 0 to 1e10"),
                ));
            }
            lm / (std::f64::consts::PI * panel.area_m2())
        }
    };
    if !(l.is_finite() && (0.0..=MAX_LUMINANCE_CD_M2).contains(&l)) {
        let problem = format!(
            "{l} cd/m² is not a luminance restauro accepts; give 0 to {MAX_LUMINANCE_CD_M2:e}"
        );
        return Err((".luminance_cd_m2", problem));
    }
    Ok(l)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panel_emits_from_the_side_asked_and_its_flux_is_pi_l_a() {
        let down =
            Panel::new([0.0, 0.0, 3.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], Some([0.0, 0.0, -5.0]))
                .unwrap();
        assert_eq!(down.normal, [0.0, 0.0, -1.0]);
        assert_eq!(down.area_m2(), 1.0);
        let up = Panel::new([0.0, 0.0, 3.0], [2.0, 0.0, 0.0], [0.0, 0.5, 0.0], None).unwrap();
        assert_eq!(up.normal, [0.0, 0.0, 1.0]);
        let l = luminance(&up, None, Some(1000.0)).unwrap();
        assert!((std::f64::consts::PI * l * up.area_m2() - 1000.0).abs() < 1e-9);
        assert_eq!(luminance(&up, Some(250.0), None).unwrap(), 250.0);
    }

    #[test]
    fn bad_panels_are_refused_by_field() {
        let p = |c, u, v, n| Panel::new(c, u, v, n).unwrap_err().0;
        let o = [0.0; 3];
        assert_eq!(p(o, [0.0; 3], [0.0, 1.0, 0.0], None), "u");
        assert_eq!(p(o, [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], None), "v");
        assert_eq!(p(o, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], Some([1.0, 0.0, 0.0])), "normal");
        assert_eq!(p([f64::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], None), "corner");
        let panel = Panel::new(o, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], None).unwrap();
        assert_eq!(luminance(&panel, Some(1.0), Some(1.0)).unwrap_err().0, "");
        assert_eq!(luminance(&panel, None, None).unwrap_err().0, "");
        assert_eq!(luminance(&panel, Some(-1.0), None).unwrap_err().0, ".luminance_cd_m2");
        assert_eq!(luminance(&panel, None, Some(f64::INFINITY)).unwrap_err().0, ".flux_lm");
    }
}
