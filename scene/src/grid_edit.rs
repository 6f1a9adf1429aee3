//! Edits of the scene's calculation grids (`[[grids]]`), as the studio makes them: a grid saved
//! under its name (a rectangle may be given by the distance between its points instead of its
//! divisions), renamed, deleted. A saved grid is checked alone first, exactly as the scene
//! file's grids are ([`crate::grid::resolve_grids`]), so a refusal names the edit's own field
//! (`grid.divisions`, `spacing_m`) rather than a place in the file.

use crate::error::{Result, SceneError};
use crate::grid::resolve_grids;
use crate::scene_file::{Grid, SceneFile};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A grid (`[[grids]]`) saved under its name, replacing a grid of that name. With `spacing_m`,
/// a rectangle's `divisions` are those that put its points that far apart or closer: ⌈|u|/s⌉
/// along u and ⌈|v|/s⌉ along v.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SaveGrid {
    pub grid: Grid,
    #[serde(default)]
    pub spacing_m: Option<f64>,
}

/// A grid given another name; refused when that name is taken.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenameGrid {
    pub name: String,
    pub to: String,
}

/// A grid removed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeleteGrid {
    pub name: String,
}

/// Where an edit's refusals say they come from.
const PLACE: &str = "edit";

fn refuse(field: &str, problem: impl Into<String>) -> SceneError {
    SceneError::invalid(Path::new(PLACE), field, problem)
}

/// Saves `e.grid` (its divisions from `e.spacing_m` when given) in place of the grid of its
/// name, or after the others.
pub fn save_grid(scene: &mut SceneFile, e: &SaveGrid) -> Result<String> {
    let mut grid = e.grid.clone();
    if let Some(spacing_m) = e.spacing_m {
        grid.divisions = Some(divisions_for(&grid, spacing_m)?);
    }
    check(&grid)?;
    let summary = match scene.grids.iter_mut().find(|g| g.name == grid.name) {
        Some(old) => {
            *old = grid;
            format!("grid `{}` changed", e.grid.name)
        }
        None => {
            scene.grids.push(grid);
            format!("grid `{}` added", e.grid.name)
        }
    };
    Ok(summary)
}

/// The divisions that space a rectangle's points `spacing_m` apart or closer.
fn divisions_for(grid: &Grid, spacing_m: f64) -> Result<Vec<u32>> {
    if !(spacing_m.is_finite() && spacing_m > 0.0) {
        return Err(refuse(
            "spacing_m",
            format!(
                "{spacing_m} m; give the distance between the grid's points in metres, more \
                 than 0 (e.g. 0.5)"
            ),
        ));
    }
    if grid.divisions.is_some() || grid.points.is_some() {
        return Err(refuse(
            "spacing_m",
            "a spacing sets a rectangle's divisions: give `spacing_m` or `grid.divisions`, and \
             no `grid.points`",
        ));
    }
    let (Some(u), Some(v)) = (grid.u, grid.v) else {
        return Err(refuse("grid.u", "a spacing needs the rectangle's edges `u` and `v` (m)"));
    };
    let cells = |edge: [f64; 3]| {
        let length_m = edge.iter().map(|c| c * c).sum::<f64>().sqrt();
        // Past u32, resolve_grids refuses the count anyway (MAX_GRID_POINTS).
        (length_m / spacing_m).ceil().clamp(1.0, f64::from(u32::MAX)) as u32
    };
    Ok(vec![cells(u), cells(v)])
}

/// Checks `grid` alone as the scene file's grids are checked, its refusals placed in the
/// edit's field (`grid.…`) instead of `grids[0].…`.
fn check(grid: &Grid) -> Result<()> {
    match resolve_grids(Path::new(PLACE), std::slice::from_ref(grid)) {
        Ok(_) => Ok(()),
        Err(SceneError::Invalid { path, place, problem }) => {
            let field = place.strip_prefix("grids[0]").unwrap_or(&place);
            Err(SceneError::Invalid { path, place: format!("grid{field}"), problem })
        }
        Err(other) => Err(other),
    }
}

/// Renames grid `e.name` to `e.to`.
pub fn rename_grid(scene: &mut SceneFile, e: &RenameGrid) -> Result<String> {
    if scene.grids.iter().any(|g| g.name == e.to) {
        return Err(refuse("to", format!("a grid named `{}` exists; choose another name", e.to)));
    }
    let at = position(scene, &e.name)?;
    let mut grid = scene.grids[at].clone();
    grid.name.clone_from(&e.to);
    check(&grid).map_err(|err| match err {
        SceneError::Invalid { path, place, problem } if place == "grid.name" => {
            SceneError::Invalid { path, place: "to".into(), problem }
        }
        other => other,
    })?;
    scene.grids[at] = grid;
    Ok(format!("grid `{}` renamed `{}`", e.name, e.to))
}

/// Removes grid `e.name`.
pub fn delete_grid(scene: &mut SceneFile, e: &DeleteGrid) -> Result<String> {
    let at = position(scene, &e.name)?;
    scene.grids.remove(at);
    Ok(format!("grid `{}` deleted", e.name))
}

/// Where grid `name` is; refused with the names there are when there is none.
fn position(scene: &SceneFile, name: &str) -> Result<usize> {
    scene.grids.iter().position(|g| g.name == name).ok_or_else(|| {
        let names = scene.grids.iter().map(|g| g.name.as_str());
        refuse("name", crate::load::unknown("grid", name, names))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> SceneFile {
        let text = include_str!("../tests/data/edit/aosta.toml");
        crate::load::parse_scene(text, Path::new("aosta.toml")).unwrap()
    }

    fn save(json: &str) -> Result<String> {
        let e: SaveGrid = serde_json::from_str(json).unwrap();
        save_grid(&mut scene(), &e)
    }

    fn field(r: Result<String>) -> String {
        match r.unwrap_err() {
            SceneError::Invalid { place, .. } => place,
            other => panic!("{other}"),
        }
    }

    #[test]
    fn a_spacing_gives_the_divisions_and_the_grid_is_saved_renamed_and_deleted() {
        let mut s = scene();
        let e: SaveGrid = serde_json::from_str(
            r#"{"grid":{"name":"portal","origin":[0,0,0.85],"u":[4.1,0,0],"v":[0,2,0]},"spacing_m":0.5}"#,
        )
        .unwrap();
        save_grid(&mut s, &e).unwrap();
        assert_eq!(s.grids.len(), 1);
        assert_eq!(s.grids[0].divisions, Some(vec![9, 4]));
        save_grid(&mut s, &e).unwrap();
        assert_eq!(s.grids.len(), 1, "saved again under its name: replaced");
        let rename = RenameGrid { name: "portal".into(), to: "nave floor".into() };
        rename_grid(&mut s, &rename).unwrap();
        assert_eq!(s.grids[0].name, "nave floor");
        let gone = delete_grid(&mut s, &DeleteGrid { name: "portal".into() }).unwrap_err();
        assert!(gone.to_string().contains("`nave floor`"), "{gone}");
        delete_grid(&mut s, &DeleteGrid { name: "nave floor".into() }).unwrap();
        assert_eq!(s, scene());
    }

    #[test]
    fn bad_grids_are_refused_naming_the_field() {
        let rect = r#""name":"a","origin":[0,0,0],"u":[1,0,0],"v":[0,1,0]"#;
        assert_eq!(field(save(&format!(r#"{{"grid":{{{rect}}},"spacing_m":0}}"#))), "spacing_m");
        assert_eq!(field(save(&format!(r#"{{"grid":{{{rect}}},"spacing_m":-1}}"#))), "spacing_m");
        assert_eq!(
            field(save(&format!(r#"{{"grid":{{{rect},"divisions":[0,2]}}}}"#))),
            "grid.divisions"
        );
        assert_eq!(
            field(save(&format!(r#"{{"grid":{{{rect}}},"spacing_m":0.00001}}"#))),
            "grid.divisions"
        );
        assert_eq!(
            field(save(r#"{"grid":{"name":"a","points":[[0,0,1]],"normal":[0,0,0]}}"#)),
            "grid.normal"
        );
        assert_eq!(
            field(save(r#"{"grid":{"name":"../a","points":[[0,0,1]],"normal":[0,0,1]}}"#)),
            "grid.name"
        );
        let mut s = scene();
        let e = serde_json::from_str(&format!(r#"{{"grid":{{{rect}}},"spacing_m":0.5}}"#)).unwrap();
        save_grid(&mut s, &e).unwrap();
        let to_bad = RenameGrid { name: "a".into(), to: "".into() };
        assert_eq!(field(rename_grid(&mut s, &to_bad).map(|_| String::new())), "to");
    }
}
