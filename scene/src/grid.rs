//! Calculation grids resolved: each `[[grids]]` table of the scene file becomes its list of
//! sensor points and the one direction they face, checked once (a name of its own, finite
//! points, a normal that is not zero, a bounded number of points).
//!
//! A rectangle's points are the centres of its cells, row by row along `v`: point (i, j), for
//! i < divisions[0] and j < divisions[1], is `origin + (i + ½)/n_u · u + (j + ½)/n_v · v` at
//! index `j · n_u + i`.

use crate::error::{Result, SceneError};
use crate::scene_file::Grid;
use glam::DVec3;
use std::collections::BTreeSet;
use std::path::Path;

/// The most points of all the scene's grids together: a million sensors is a large floor at a
/// centimetre; beyond it a grid is a mistake of units.
pub const MAX_GRID_POINTS: usize = 1_000_000;

/// A grid ready to compute.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedGrid {
    pub name: String,
    /// The sensors (m), in the order of the output files.
    pub points: Vec<[f64; 3]>,
    /// The unit direction every sensor faces.
    pub normal: [f64; 3],
    /// For a rectangle: its cells along u and along v (the points are `n_u` wide, row-major).
    pub divisions: Option<[u32; 2]>,
    /// For a rectangle: the area of one cell (m²), what each point's illuminance stands for
    /// when a flux is summed over the grid.
    pub cell_area_m2: Option<f64>,
}

/// Resolves and checks every grid of the scene file at `path`.
pub fn resolve_grids(path: &Path, grids: &[Grid]) -> Result<Vec<ResolvedGrid>> {
    let mut names = BTreeSet::new();
    let mut total = 0usize;
    let mut out = Vec::with_capacity(grids.len());
    for (i, g) in grids.iter().enumerate() {
        let place = format!("grids[{i}]");
        let invalid = |field: &str, problem: String| {
            SceneError::invalid(path, format!("{place}{field}"), problem)
        };
        if g.name.trim().is_empty() || g.name.contains(['/', '\\']) || g.name.starts_with('.') {
            let problem = format!(
                "`{}` cannot name a grid's files; give a name of letters, digits, - or _",
                g.name
            );
            return Err(invalid(".name", problem));
        }
        if !names.insert(g.name.as_str()) {
            let problem = format!("a second grid named `{}`; give each grid its own name", g.name);
            return Err(invalid(".name", problem));
        }
        let grid = resolve_one(g, &invalid)?;
        total += grid.points.len();
        if total > MAX_GRID_POINTS {
            let problem = format!(
                "the grids have more than {MAX_GRID_POINTS} points together; use fewer divisions \
                 (check the units: restauro works in metres)"
            );
            return Err(invalid(".divisions", problem));
        }
        out.push(grid);
    }
    Ok(out)
}

fn resolve_one(g: &Grid, invalid: &dyn Fn(&str, String) -> SceneError) -> Result<ResolvedGrid> {
    let rectangle = [g.origin.is_some(), g.u.is_some(), g.v.is_some(), g.divisions.is_some()];
    let (points, divisions, spanned) = match (&g.points, rectangle) {
        (Some(_), r) if r.iter().any(|&x| x) => {
            let problem = "give either `points` or `origin`, `u`, `v` and `divisions`, not both";
            return Err(invalid("", problem.into()));
        }
        (Some(points), _) => {
            if points.is_empty() {
                return Err(invalid(".points", "no points; give at least one [x, y, z]".into()));
            }
            if points.len() > MAX_GRID_POINTS {
                let problem = format!("{} points; at most {MAX_GRID_POINTS}", points.len());
                return Err(invalid(".points", problem));
            }
            (points.clone(), None, None)
        }
        (None, [true, true, true, true]) => rectangle_points(g, invalid)?,
        (None, _) => {
            let problem = "a grid needs `origin`, `u`, `v` and `divisions` (a rectangle), or \
                           `points` and `normal`";
            return Err(invalid("", problem.into()));
        }
    };
    for (k, p) in points.iter().enumerate() {
        if !p.iter().all(|x| x.is_finite() && x.abs() <= crate::limits::MAX_COORDINATE_M) {
            let field =
                if divisions.is_some() { ".origin".to_owned() } else { format!(".points[{k}]") };
            let problem = format!(
                "{p:?} is out of range; every coordinate must be finite and within ±{:e} m",
                crate::limits::MAX_COORDINATE_M
            );
            return Err(invalid(&field, problem));
        }
    }
    let normal = match (g.normal, spanned) {
        (Some(n), _) => DVec3::from_array(n),
        (None, Some(n)) => n,
        (None, None) => {
            let problem = "a list of points needs the `normal` its sensors face".into();
            return Err(invalid(".normal", problem));
        }
    };
    let unit = normal.normalize_or_zero();
    if !unit.is_finite() || unit == DVec3::ZERO {
        let problem = if g.normal.is_some() {
            format!("{:?} has no direction; give a vector that is not zero", normal.to_array())
        } else {
            "u and v are parallel, so they span no surface; give two edges at an angle".into()
        };
        return Err(invalid(".normal", problem));
    }
    let cell_area_m2 = divisions
        .zip(spanned)
        .map(|([n_u, n_v], n)| n.length() / (f64::from(n_u) * f64::from(n_v)));
    Ok(ResolvedGrid {
        name: g.name.clone(),
        points,
        normal: unit.to_array(),
        divisions,
        cell_area_m2,
    })
}

/// The points, the cells each way, u × v.
type Rectangle = (Vec<[f64; 3]>, Option<[u32; 2]>, Option<DVec3>);

/// The centres of a rectangle's cells, and u × v.
fn rectangle_points(g: &Grid, invalid: &dyn Fn(&str, String) -> SceneError) -> Result<Rectangle> {
    let (Some(origin), Some(u), Some(v), Some(divisions)) = (g.origin, g.u, g.v, &g.divisions)
    else {
        unreachable!("checked by the caller")
    };
    let &[n_u, n_v] = divisions.as_slice() else {
        let problem = format!(
            "{} numbers; give two, the cells along u and along v, e.g. [8, 8]",
            divisions.len()
        );
        return Err(invalid(".divisions", problem));
    };
    let count = u64::from(n_u) * u64::from(n_v);
    if n_u == 0 || n_v == 0 || count > MAX_GRID_POINTS as u64 {
        let problem = format!(
            "{n_u} × {n_v} cells; give 1 to {MAX_GRID_POINTS} cells in all, at least 1 each way"
        );
        return Err(invalid(".divisions", problem));
    }
    let (o, u, v) = (DVec3::from_array(origin), DVec3::from_array(u), DVec3::from_array(v));
    if !(u.is_finite() && v.is_finite()) || u == DVec3::ZERO || v == DVec3::ZERO {
        let problem = "an edge of the rectangle is zero or not finite; give u and v in metres";
        return Err(invalid(".u", problem.into()));
    }
    let mut points = Vec::with_capacity(count as usize);
    for j in 0..n_v {
        for i in 0..n_u {
            let (s, t) =
                ((f64::from(i) + 0.5) / f64::from(n_u), (f64::from(j) + 0.5) / f64::from(n_v));
            points.push((o + s * u + t * v).to_array());
        }
    }
    Ok((points, Some([n_u, n_v]), Some(u.cross(v))))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(toml: &str) -> Result<Vec<ResolvedGrid>> {
        #[derive(serde::Deserialize)]
        struct File {
            grids: Vec<Grid>,
        }
        let f: File = toml::from_str(toml).expect("parses");
        resolve_grids(Path::new("scene.toml"), &f.grids)
    }

    #[test]
    fn a_rectangle_has_a_point_at_the_centre_of_each_cell() {
        let g = grid(
            "[[grids]]\nname = \"floor\"\norigin = [0, 0, 0]\nu = [4, 0, 0]\nv = [0, 2, 0]\n\
             divisions = [4, 2]\n",
        )
        .unwrap();
        let g = &g[0];
        assert_eq!(g.points.len(), 8);
        assert_eq!(g.points[0], [0.5, 0.5, 0.0]);
        assert_eq!(g.points[3], [3.5, 0.5, 0.0]);
        assert_eq!(g.points[4], [0.5, 1.5, 0.0]);
        assert_eq!(g.normal, [0.0, 0.0, 1.0]);
        assert_eq!(g.divisions, Some([4, 2]));
        assert_eq!(g.cell_area_m2, Some(1.0));
    }

    #[test]
    fn a_list_of_points_needs_its_normal_and_bad_grids_are_refused_by_field() {
        let ok = grid("[[grids]]\nname = \"a\"\npoints = [[0, 0, 1]]\nnormal = [0, 0, -2]\n");
        assert_eq!(ok.unwrap()[0].normal, [0.0, 0.0, -1.0]);
        let cases = [
            ("name = \"a\"\npoints = [[0, 0, 1]]\n", "grids[0].normal"),
            ("name = \"a\"\npoints = [[0, 0, 1]]\nnormal = [0, 0, 0]\n", "grids[0].normal"),
            ("name = \"a\"\npoints = []\nnormal = [0, 0, 1]\n", "grids[0].points"),
            ("name = \"../x\"\npoints = [[0, 0, 1]]\nnormal = [0, 0, 1]\n", "grids[0].name"),
            (
                "name = \"a\"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [2, 0, 0]\ndivisions = [1, 1]\n",
                "grids[0].normal",
            ),
            (
                "name = \"a\"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ndivisions = [0, 1]\n",
                "grids[0].divisions",
            ),
            (
                "name = \"a\"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ndivisions = [3]\n",
                "grids[0].divisions",
            ),
            (
                "name = \"a\"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\n\
                 divisions = [2000, 2000]\n",
                "grids[0].divisions",
            ),
            ("name = \"a\"\norigin = [0, 0, 0]\nnormal = [0, 0, 1]\n", "grids[0]"),
            ("name = \"a\"\npoints = [[1e300, 0, 0]]\nnormal = [0, 0, 1]\n", "grids[0].points[0]"),
        ];
        for (body, place) in cases {
            let e = grid(&format!("[[grids]]\n{body}")).unwrap_err();
            match e {
                SceneError::Invalid { place: p, .. } => assert_eq!(p, place, "{body}"),
                other => panic!("{body}: {other}"),
            }
        }
        let twice = "[[grids]]\nname = \"a\"\npoints = [[0, 0, 1]]\nnormal = [0, 0, 1]\n";
        let e = grid(&format!("{twice}{twice}")).unwrap_err();
        assert!(e.to_string().contains("a second grid named `a`"), "{e}");
    }
}
