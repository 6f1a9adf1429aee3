//! Edits of a scene, as the studio makes them: each changes the scene file (the one source of
//! truth) in one place, and the changed file is then checked exactly as a file on disk is
//! ([`crate::load::load`]), so an edit can never make a scene that `scene check` would refuse.
//!
//! An edit names what it changes by the names the file uses (a material, a view), and a name
//! that does not exist is refused with the names that do.

use crate::error::{Result, SceneError};
pub use crate::grid_edit::{DeleteGrid, RenameGrid, SaveGrid};
use crate::scene_file::{
    Annotation, Light, MaterialModel, SceneFile, SiteTime, SpectrumSource, Variant, View,
};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One change to a scene. As JSON, an object whose `edit` names the kind (`material`, `sun`,
/// `save-view`, …: [`KINDS`]) beside the kind's own fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "edit", rename_all = "kebab-case")]
pub enum Edit {
    Material(MaterialEdit),
    Sun(SunEdit),
    SaveView(SaveView),
    DeleteView(DeleteView),
    SaveAnnotation(SaveAnnotation),
    DeleteAnnotation(DeleteAnnotation),
    SaveVariant(SaveVariant),
    RenameVariant(RenameVariant),
    DeleteVariant(DeleteVariant),
    SaveLight(SaveLight),
    DeleteLight(DeleteLight),
    SaveGrid(SaveGrid),
    RenameGrid(RenameGrid),
    DeleteGrid(DeleteGrid),
}

/// A material's surface in one of its states (`base` unless given): a shipped spectrum by its
/// name (`restauro color --list`) or a measured one sent as a file (`file`, the reference the
/// studio gave it, named in `[spectra]` after `file_name`), the reflection model, the roughness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialEdit {
    pub material: String,
    #[serde(default)]
    pub state: Option<String>,
    #[serde(default)]
    pub spectrum: Option<String>,
    #[serde(default)]
    pub file: Option<String>,
    #[serde(default)]
    pub file_name: Option<String>,
    /// With `file`: hold its end values where it stops short of 380 or 780 nm.
    #[serde(default)]
    pub extrapolate: bool,
    #[serde(default)]
    pub model: Option<MaterialModel>,
    #[serde(default)]
    pub roughness: Option<f64>,
}

/// The sun placed by its site and a local date and time (its direction then follows from
/// NREL's solar position algorithm, as for any scene with a `site`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunEdit {
    pub latitude_deg: f64,
    pub longitude_deg: f64,
    #[serde(default)]
    pub height_m: f64,
    /// RFC 3339 with the site's UTC offset, e.g. `2026-12-21T17:00:00+01:00`.
    pub datetime: String,
}

/// A view saved under its name (replacing a view of that name).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SaveView {
    pub view: View,
}

/// A saved view removed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeleteView {
    pub name: String,
}

/// A note pinned to the model, saved under its title (replacing a note of that title).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SaveAnnotation {
    pub annotation: Annotation,
}

/// A note removed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeleteAnnotation {
    pub title: String,
}

/// A hypothesis (`[variants.NAME]`) saved under its name, replacing one of that name: the
/// state of everything, and of the objects and parts named in `states`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SaveVariant {
    pub name: String,
    /// `base`, `degraded` or `cleaned`.
    #[serde(default = "base")]
    pub state: String,
    /// Per object name, or per `object/part`, the state.
    #[serde(default)]
    pub states: std::collections::BTreeMap<String, String>,
}

fn base() -> String {
    "base".to_owned()
}

/// A hypothesis given another name; refused when that name is taken.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenameVariant {
    pub name: String,
    pub to: String,
}

/// A hypothesis removed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeleteVariant {
    pub name: String,
}

/// A light (`[[lights]]`) as the scene file gives it, in place of light `index` (counted
/// from 0 in the file's order), or added after the others without one. Its `spectrum` is a
/// name in `[spectra]`, or `cie:NAME` for a CIE illuminant (A, D65, F11, `daylight:4000`,
/// `blackbody:3000`, …) that the edit adds to `[spectra]` as `cie_NAME`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SaveLight {
    #[serde(default)]
    pub index: Option<usize>,
    pub light: Light,
}

/// Light `index` removed (a scene keeps at least one light).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeleteLight {
    pub index: usize,
}

/// The kinds of edit, as `edit` names them.
pub const KINDS: [&str; 14] = [
    "material",
    "sun",
    "save-view",
    "delete-view",
    "save-annotation",
    "delete-annotation",
    "save-variant",
    "rename-variant",
    "delete-variant",
    "save-light",
    "delete-light",
    "save-grid",
    "rename-grid",
    "delete-grid",
];

/// The longest name of a hypothesis, in characters.
pub const MAX_VARIANT_NAME: usize = 64;

/// Where an edit's refusals say they come from.
const PLACE: &str = "edit";

fn refuse(field: &str, problem: impl Into<String>) -> SceneError {
    SceneError::invalid(Path::new(PLACE), field, problem)
}

impl Edit {
    /// Applies the edit to `scene`; what changed, in a few words (a revision's summary). The
    /// caller checks the whole scene afterwards.
    pub fn apply(&self, scene: &mut SceneFile) -> Result<String> {
        match self {
            Edit::Material(e) => {
                let state = e.state.as_deref().unwrap_or("base");
                known_material(scene, &e.material)?;
                let spectrum = match (&e.spectrum, &e.file) {
                    (Some(_), Some(_)) => {
                        return Err(refuse("file", "give a shipped spectrum or a file, not both"));
                    }
                    (Some(stem), None) => Some(library_spectrum(scene, stem)?),
                    (None, Some(file)) => {
                        let name = e.file_name.as_deref().unwrap_or("measured");
                        Some(file_spectrum(scene, file, name, e.extrapolate)?)
                    }
                    (None, None) => None,
                };
                material_edit(scene, &e.material, state, spectrum, e.model, e.roughness)
            }
            Edit::Sun(e) => {
                let site = SiteTime {
                    latitude_deg: e.latitude_deg,
                    longitude_deg: e.longitude_deg,
                    height_m: e.height_m,
                    datetime: e.datetime.clone(),
                };
                Ok(sun_edit(scene, site))
            }
            Edit::SaveView(SaveView { view }) => {
                save(&mut scene.views, view, |v| &v.name);
                Ok(format!("view `{}` saved", view.name))
            }
            Edit::DeleteView(DeleteView { name }) => {
                delete(&mut scene.views, name, |v| &v.name).map_err(|names| {
                    refuse("name", crate::load::unknown("view", name, names.into_iter()))
                })?;
                Ok(format!("view `{name}` deleted"))
            }
            Edit::SaveAnnotation(SaveAnnotation { annotation }) => {
                if let Some(k) = annotation.images.iter().position(|r| !r.starts_with("blake3:")) {
                    return Err(refuse(
                        &format!("annotation.images[{k}]"),
                        "send the image to the studio first; give the reference it answers",
                    ));
                }
                save(&mut scene.annotations, annotation, |a| &a.title);
                Ok(format!("note `{}` saved", annotation.title))
            }
            Edit::DeleteAnnotation(DeleteAnnotation { title }) => {
                delete(&mut scene.annotations, title, |a| &a.title).map_err(|titles| {
                    refuse("title", crate::load::unknown("note", title, titles.into_iter()))
                })?;
                Ok(format!("note `{title}` deleted"))
            }
            Edit::SaveVariant(SaveVariant { name, state, states }) => {
                check_variant_name(name, "name")?;
                let variant = Variant { state: state.clone(), states: states.clone() };
                scene.variants.insert(name.clone(), variant);
                Ok(format!("hypothesis `{name}` saved"))
            }
            Edit::RenameVariant(RenameVariant { name, to }) => {
                check_variant_name(to, "to")?;
                if scene.variants.contains_key(to) {
                    return Err(refuse(
                        "to",
                        format!("a hypothesis named `{to}` exists; choose another name"),
                    ));
                }
                let variant = take_variant(scene, name)?;
                scene.variants.insert(to.clone(), variant);
                Ok(format!("hypothesis `{name}` renamed `{to}`"))
            }
            Edit::DeleteVariant(DeleteVariant { name }) => {
                take_variant(scene, name)?;
                Ok(format!("hypothesis `{name}` deleted"))
            }
            Edit::SaveLight(SaveLight { index, light }) => save_light(scene, *index, light),
            Edit::DeleteLight(DeleteLight { index }) => {
                light_index(scene, *index)?;
                let gone = scene.lights.remove(*index);
                Ok(format!("light {index} ({}) deleted", light_kind(&gone)))
            }
            Edit::SaveGrid(e) => crate::grid_edit::save_grid(scene, e),
            Edit::RenameGrid(e) => crate::grid_edit::rename_grid(scene, e),
            Edit::DeleteGrid(e) => crate::grid_edit::delete_grid(scene, e),
        }
    }
}

fn light_kind(light: &Light) -> &'static str {
    match light {
        Light::Point { .. } => "point",
        Light::Spot { .. } => "spot",
        Light::Sun { .. } => "sun",
        Light::Sky { .. } => "sky",
        Light::Area { .. } => "area",
    }
}

/// Refuses an index past the scene's lights.
fn light_index(scene: &SceneFile, index: usize) -> Result<()> {
    if index < scene.lights.len() {
        return Ok(());
    }
    let n = scene.lights.len();
    Err(refuse(
        "index",
        format!("the scene has {n} lights (0 to {}); no light {index}", n.max(1) - 1),
    ))
}

fn save_light(scene: &mut SceneFile, index: Option<usize>, light: &Light) -> Result<String> {
    let mut light = light.clone();
    let spectrum = match &mut light {
        Light::Point { spectrum, .. }
        | Light::Spot { spectrum, .. }
        | Light::Sun { spectrum, .. }
        | Light::Sky { spectrum, .. }
        | Light::Area { spectrum, .. } => spectrum,
    };
    if let Some(name) = spectrum.strip_prefix("cie:") {
        let key = format!("cie_{}", name.replace(|c: char| !c.is_ascii_alphanumeric(), "_"));
        let source = SpectrumSource::Illuminant { illuminant: name.to_owned() };
        match scene.spectra.get(&key) {
            Some(s) if *s != source => {
                return Err(refuse(
                    "light.spectrum",
                    format!("`{key}` in [spectra] is another spectrum"),
                ));
            }
            _ => scene.spectra.insert(key.clone(), source),
        };
        *spectrum = key;
    }
    let kind = light_kind(&light);
    match index {
        Some(i) => {
            light_index(scene, i)?;
            scene.lights[i] = light;
            Ok(format!("light {i} ({kind}) changed"))
        }
        None => {
            scene.lights.push(light);
            Ok(format!("light {} ({kind}) added", scene.lights.len() - 1))
        }
    }
}

/// A hypothesis's name: the `NAME` of `[variants.NAME]` and of `restauro render --variant`, so
/// printable, on one line, and short.
fn check_variant_name(name: &str, field: &str) -> Result<()> {
    if name.trim().is_empty() {
        return Err(refuse(field, "a hypothesis needs a name, e.g. `cleaned`"));
    }
    if name.chars().count() > MAX_VARIANT_NAME {
        return Err(refuse(field, format!("at most {MAX_VARIANT_NAME} characters")));
    }
    if name.chars().any(char::is_control) || name.trim() != name {
        return Err(refuse(
            field,
            "no control characters, and no spaces at either end: the name is typed after \
             `restauro render --variant`",
        ));
    }
    Ok(())
}

/// Removes hypothesis `name`, refusing a name the scene does not have with those it has.
fn take_variant(scene: &mut SceneFile, name: &str) -> Result<Variant> {
    scene.variants.remove(name).ok_or_else(|| {
        let names = scene.variants.keys().map(String::as_str);
        refuse("name", crate::load::unknown("hypothesis", name, names))
    })
}

/// Puts `item` in `list`, in place of the item of the same name.
fn save<T: Clone>(list: &mut Vec<T>, item: &T, name: impl Fn(&T) -> &String) {
    match list.iter_mut().find(|x| name(x) == name(item)) {
        Some(old) => *old = item.clone(),
        None => list.push(item.clone()),
    }
}

/// Removes the item named `key` from `list`; the names there are when there is none.
fn delete<'a, T>(
    list: &'a mut Vec<T>,
    key: &str,
    name: impl Fn(&T) -> &String,
) -> std::result::Result<(), Vec<&'a str>> {
    let before = list.len();
    list.retain(|x| name(x) != key);
    if list.len() < before {
        return Ok(());
    }
    Err(list.iter().map(|x| name(x).as_str()).collect())
}

/// Refuses a material the scene does not have, with those it has.
fn known_material(scene: &SceneFile, material: &str) -> Result<()> {
    if scene.materials.contains_key(material) {
        return Ok(());
    }
    let names = scene.materials.keys().map(String::as_str);
    Err(refuse("material", crate::load::unknown("material", material, names)))
}

/// `key`: the `[spectra]` name of the new spectrum, already added.
fn material_edit(
    scene: &mut SceneFile,
    material: &str,
    state: &str,
    key: Option<String>,
    model: Option<MaterialModel>,
    roughness: Option<f64>,
) -> Result<String> {
    if state == "base" && key.is_none() && model.is_none() && roughness.is_none() {
        return Err(refuse("material", "nothing to change: give spectrum, model or roughness"));
    }
    let m = scene.materials.get_mut(material).expect("known_material checked it");
    let mut changed = Vec::new();
    if state == "base" {
        if let Some(key) = &key {
            m.reflectance.clone_from(key);
            changed.push(format!("spectrum {key}"));
        }
        if let Some(model) = model {
            m.model = model;
            changed.push(format!("{model:?}"));
        }
        if let Some(r) = roughness {
            m.roughness = Some(r);
            changed.push(format!("roughness {r}"));
        }
        return Ok(format!("{material}: {}", changed.join(", ")));
    }
    let surface = match state {
        "degraded" => &mut m.degraded,
        "cleaned" => &mut m.cleaned,
        other => {
            return Err(refuse(
                "state",
                format!("unknown state `{}`; use base, degraded or cleaned", other.escape_debug()),
            ));
        }
    };
    if model.is_some() {
        return Err(refuse("model", "a state changes the surface, not the model; edit the base"));
    }
    let surface = surface.get_or_insert_with(Default::default);
    if let Some(key) = &key {
        surface.reflectance = Some(key.clone());
        changed.push(format!("spectrum {key}"));
    }
    if let Some(r) = roughness {
        surface.roughness = Some(r);
        changed.push(format!("roughness {r}"));
    }
    Ok(format!("{material} ({state}): {}", changed.join(", ")))
}

/// The scene's name for the shipped spectrum `stem`: the one that already names it, or a new
/// entry (named by the stem, or the stem with a number when another spectrum has that name).
/// The `[spectra]` name of a measured spectrum sent as a file (added, named after its file,
/// unless the scene has it already).
fn file_spectrum(
    scene: &mut SceneFile,
    file: &str,
    file_name: &str,
    extrapolate: bool,
) -> Result<String> {
    if !file.starts_with("blake3:") || !file.ends_with(".csv") {
        return Err(refuse(
            "file",
            "send the spectrum to the studio first; give the reference it answers",
        ));
    }
    let source = SpectrumSource::File { file: file.to_owned(), extrapolate };
    if let Some((key, _)) = scene.spectra.iter().find(|(_, s)| **s == source) {
        return Ok(key.clone());
    }
    let stem: String = file_name
        .trim_end_matches(".csv")
        .trim_end_matches(".txt")
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' })
        .take(64)
        .collect();
    let stem = if stem.is_empty() { "measured".to_owned() } else { stem };
    Ok(new_spectrum(scene, &stem, source))
}

/// Adds `source` to `[spectra]` under `stem`, or `stem-2`, … when that is taken: the name.
fn new_spectrum(scene: &mut SceneFile, stem: &str, source: SpectrumSource) -> String {
    let key = std::iter::once(stem.to_owned())
        .chain((2..).map(|n| format!("{stem}-{n}")))
        .find(|k| !scene.spectra.contains_key(k))
        .expect("an unused name exists");
    scene.spectra.insert(key.clone(), source);
    key
}

fn library_spectrum(scene: &mut SceneFile, stem: &str) -> Result<String> {
    if restauro_spectral::library::text(stem).is_none() {
        let close = restauro_spectral::library::suggest(stem);
        let hint = if close.is_empty() {
            "see `restauro color --list`".to_owned()
        } else {
            format!("did you mean {}?", close.join(", "))
        };
        return Err(refuse(
            "spectrum",
            format!("no shipped spectrum is named `{}`; {hint}", stem.escape_debug()),
        ));
    }
    let shipped = SpectrumSource::Library(stem.to_owned());
    if let Some((key, _)) = scene.spectra.iter().find(|(_, s)| **s == shipped) {
        return Ok(key.clone());
    }
    Ok(new_spectrum(scene, stem, shipped))
}

/// Puts the scene's sun at `site` (its direction from the site and time from now on), or adds
/// a clear-day sun there when the scene has none.
fn sun_edit(scene: &mut SceneFile, site: SiteTime) -> String {
    let summary = format!(
        "sun at {:.4}°, {:.4}° on {}",
        site.latitude_deg, site.longitude_deg, site.datetime
    );
    for light in &mut scene.lights {
        if let Light::Sun { site: s, azimuth_deg, elevation_deg, .. } = light {
            *s = Some(site);
            *azimuth_deg = None;
            *elevation_deg = None;
            return summary;
        }
    }
    let daylight = SpectrumSource::Illuminant { illuminant: "D55".into() };
    let spectrum = match scene.spectra.iter().find(|(_, s)| **s == daylight) {
        Some((key, _)) => key.clone(),
        None => {
            let key = std::iter::once("sunlight".to_owned())
                .chain((2..).map(|n| format!("sunlight-{n}")))
                .find(|k| !scene.spectra.contains_key(k))
                .expect("an unused name exists");
            scene.spectra.insert(key.clone(), daylight);
            key
        }
    };
    scene.lights.push(Light::Sun {
        illuminance_lux: None,
        preset: Some(crate::scene_file::SunPreset::Sun),
        azimuth_deg: None,
        elevation_deg: None,
        site: Some(site),
        spectrum,
    });
    summary
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The demo's Aosta facade, as restauro-demo generates it (its test `fixtures` keeps the
    /// file so).
    fn scene() -> SceneFile {
        let text = include_str!("../tests/data/edit/aosta.toml");
        crate::load::parse_scene(text, Path::new("aosta.toml")).unwrap()
    }

    fn edit(json: &str) -> Edit {
        serde_json::from_str(json).unwrap()
    }

    #[test]
    fn a_shipped_spectrum_is_added_once_and_bound_to_the_state() {
        let mut s = scene();
        let e = edit(
            r#"{"edit":"material","material":"travertine","spectrum":"travertine_particulate_fine__eco_travertine1"}"#,
        );
        e.apply(&mut s).unwrap();
        let key = &s.materials["travertine"].reflectance;
        assert_eq!(
            s.spectra[key],
            SpectrumSource::Library("travertine_particulate_fine__eco_travertine1".into())
        );
        let spectra = s.spectra.len();
        e.apply(&mut s).unwrap();
        assert_eq!(s.spectra.len(), spectra, "the same spectrum is not added twice");
        edit(r#"{"edit":"material","material":"travertine","state":"degraded","spectrum":"carbon_black_soot_proxy__usgs_GDS68"}"#)
            .apply(&mut s)
            .unwrap();
        let degraded = s.materials["travertine"].degraded.as_ref().unwrap();
        let key = degraded.reflectance.as_ref().unwrap();
        assert_eq!(
            s.spectra[key],
            SpectrumSource::Library("carbon_black_soot_proxy__usgs_GDS68".into())
        );
    }

    #[test]
    fn unknown_names_are_refused_with_the_names_that_exist() {
        let mut s = scene();
        let e = edit(
            r#"{"edit":"material","material":"travertin","spectrum":"marble_white_solid__eco_ward95"}"#,
        );
        let message = e.apply(&mut s).unwrap_err().to_string();
        assert!(message.contains("did you mean `travertine`"), "{message}");
        let e = edit(r#"{"edit":"material","material":"travertine","spectrum":"travertine_tufa"}"#);
        let message = e.apply(&mut s).unwrap_err().to_string();
        assert!(message.contains("travertine_tufa_solid__eco_ward73"), "{message}");
        let e = edit(
            r#"{"edit":"material","material":"travertine","state":"polished","roughness":0.2}"#,
        );
        assert!(e.apply(&mut s).unwrap_err().to_string().contains("unknown state `polished`"));
        let e = edit(r#"{"edit":"delete-view","name":"portal"}"#);
        assert!(e.apply(&mut s).unwrap_err().to_string().contains("view"));
        assert_eq!(s, scene(), "a refused edit changes nothing");
    }

    #[test]
    fn the_sun_takes_the_site_and_time_in_place_of_a_direction() {
        let mut s = scene();
        edit(r#"{"edit":"sun","latitude_deg":45.7371,"longitude_deg":7.3228,"datetime":"2026-12-21T17:00:00+01:00"}"#)
            .apply(&mut s)
            .unwrap();
        let suns: Vec<&Light> =
            s.lights.iter().filter(|l| matches!(l, Light::Sun { .. })).collect();
        assert_eq!(suns.len(), 1);
        let Light::Sun { site: Some(site), azimuth_deg: None, elevation_deg: None, .. } = suns[0]
        else {
            panic!("{:?}", suns[0]);
        };
        assert_eq!(site.datetime, "2026-12-21T17:00:00+01:00");
    }

    #[test]
    fn views_are_saved_replaced_and_deleted_by_name() {
        let mut s = scene();
        let view = |x: f64| {
            format!(
                r#"{{"edit":"save-view","view":{{"name":"portal","position":[{x},-10,1.6],"target":[0,0,2]}}}}"#
            )
        };
        edit(&view(1.0)).apply(&mut s).unwrap();
        edit(&view(2.0)).apply(&mut s).unwrap();
        assert_eq!(s.views.len(), 1);
        assert_eq!(s.views[0].position, [2.0, -10.0, 1.6]);
        edit(r#"{"edit":"delete-view","name":"portal"}"#).apply(&mut s).unwrap();
        assert!(s.views.is_empty());
    }

    #[test]
    fn hypotheses_are_saved_renamed_and_deleted_and_bad_names_refused() {
        let mut s = scene();
        edit(r#"{"edit":"save-variant","name":"portal first","state":"degraded","states":{"facade/travertine":"cleaned"}}"#)
            .apply(&mut s)
            .unwrap();
        let v = &s.variants["portal first"];
        assert_eq!(v.state_for("facade", "travertine"), "cleaned");
        assert_eq!(v.state_for("facade", "mortar"), "degraded");
        let message = edit(r#"{"edit":"rename-variant","name":"portal first","to":"cleaned"}"#)
            .apply(&mut s.clone())
            .unwrap_err()
            .to_string();
        assert!(message.contains("a hypothesis named `cleaned` exists"), "{message}");
        edit(r#"{"edit":"rename-variant","name":"portal first","to":"campaign 1"}"#)
            .apply(&mut s)
            .unwrap();
        assert!(s.variants.contains_key("campaign 1") && !s.variants.contains_key("portal first"));
        let message = edit(r#"{"edit":"delete-variant","name":"campain 1"}"#)
            .apply(&mut s.clone())
            .unwrap_err()
            .to_string();
        assert!(message.contains("did you mean `campaign 1`"), "{message}");
        edit(r#"{"edit":"delete-variant","name":"campaign 1"}"#).apply(&mut s).unwrap();
        assert_eq!(s, scene(), "saved, renamed and deleted: as it was");
        for bad in ["", "  ", " lead", "line\\nbreak", &"x".repeat(65)] {
            let json = format!(r#"{{"edit":"save-variant","name":"{bad}"}}"#);
            let message = edit(&json).apply(&mut s).unwrap_err().to_string();
            assert!(message.contains("edit: name"), "{bad:?}: {message}");
        }
        assert_eq!(s, scene(), "a refused name changes nothing");
    }
}
