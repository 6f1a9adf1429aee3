//! An OBJ's material library (`mtllib`, a Wavefront MTL file) as photogrammetry exports it:
//! each `usemtl` part's photo (`map_Kd`), laid on by the file's `vt` coordinates as detail over
//! the spectrum the scene binds the part to (like a glTF's `baseColorTexture`). The library is
//! found beside the OBJ and its photos beside the library; one that cannot be read is a note
//! (the part is drawn in its scene material), a photo that is not a PNG or JPEG a refusal. The
//! library's colours (`Kd`) are not used: the scene's spectra replace them.
//!
//! In a bundle, the `mtllib` and `map_Kd` lines name the files by hash ([`embed`]), so the
//! bundle carries them.

use crate::assets::{Assets, extension, sibling, utf8_text};
use crate::error::{Result, SceneError};
use crate::mesh::Mesh;
use crate::texture::{Texture, decode};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// A line's keyword and the rest of it (OBJ and MTL alike: words split at whitespace).
fn statement(line: &str) -> (&str, &str) {
    let line = line.trim();
    line.split_once(char::is_whitespace).unwrap_or((line, ""))
}

/// The value of `line` if it is the statement `keyword` with a value.
fn value_of<'a>(line: &'a str, keyword: &str) -> Option<&'a str> {
    let (k, value) = statement(line);
    (k == keyword && !value.trim().is_empty()).then_some(value)
}

/// The files an OBJ's `mtllib` lines name, in order (a line may name several).
fn library_names(obj: &str) -> Vec<String> {
    obj.lines()
        .filter_map(|l| value_of(l, "mtllib"))
        .flat_map(|rest| rest.split_whitespace().map(file_name))
        .collect()
}

/// A file name as exporters write it: Windows separators turned to `/`.
fn file_name(name: &str) -> String {
    name.replace('\\', "/")
}

/// The image file of a `map_Kd` value: its last word, after any options (`-s 1 1 1`, `-clamp
/// on`, …; MTL names the file last).
fn photo_of(value: &str) -> String {
    file_name(value.split_whitespace().last().unwrap_or(value))
}

/// The photo (`map_Kd`) of each material of an MTL text, by material name. Read here rather
/// than by tobj, whose MTL reader panics on a colour with fewer than three numbers: only two
/// statements matter, `newmtl name` and `map_Kd [options] file`.
fn photos(mtl: &str, path: &Path) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    let mut material: Option<String> = None;
    for (i, line) in mtl.lines().enumerate() {
        let (keyword, value) = statement(line);
        match keyword {
            "newmtl" => material = Some(value.trim().to_owned()),
            "map_Kd" if !value.trim().is_empty() => match &material {
                Some(name) => out.push((name.clone(), photo_of(value))),
                None => {
                    return Err(SceneError::invalid(
                        path,
                        format!("line {}", i + 1),
                        "a `map_Kd` before any `newmtl`: name the material first",
                    ));
                }
            },
            _ => {}
        }
    }
    Ok(out)
}

/// Lays the library's photos on the parts of `mesh`, read through `assets` beside the OBJ
/// `reference`; the notes of what could not be read.
pub fn apply(
    mesh: &mut Mesh,
    obj: &str,
    reference: &str,
    assets: &dyn Assets,
    place: &str,
    max_pixels: u64,
) -> Result<Vec<String>> {
    let obj_path = assets.display_path(reference);
    let mut notes = Vec::new();
    let mut by_part: HashMap<String, (String, String)> = HashMap::new();
    for library in library_names(obj) {
        let Ok(file) = sibling(reference, &library) else { continue };
        let bytes = match assets.read(&file, place) {
            Ok(bytes) => bytes,
            Err(e) => {
                notes.push(format!(
                    "{}: mtllib {library} is not read ({e}): its photos are not laid on",
                    obj_path.display()
                ));
                continue;
            }
        };
        let shown = assets.display_path(&file);
        for (material, photo) in photos(&utf8_text(bytes, &shown)?, &shown)? {
            by_part.entry(material).or_insert((file.clone(), photo));
        }
    }
    let mut decoded: HashMap<String, Arc<Texture>> = HashMap::new();
    for group in &mut mesh.groups {
        let Some((library, photo)) = by_part.get(&group.name) else { continue };
        let Ok(file) = sibling(library, photo) else { continue };
        if let Some(texture) = decoded.get(&file) {
            group.photo = Some(texture.clone());
            continue;
        }
        let shown = assets.display_path(&file);
        match assets.read(&file, place) {
            Ok(bytes) => {
                // A refusal names the library, which chose the file, and the photo.
                let texture =
                    decode(&bytes, &extension(&file), &shown, max_pixels).map_err(|e| {
                        let place = format!("map_Kd of `{}`", group.name);
                        SceneError::invalid(assets.display_path(library), place, e.to_string())
                    })?;
                let texture = Arc::new(texture);
                decoded.insert(file, texture.clone());
                group.photo = Some(texture);
            }
            Err(e) => notes.push(format!(
                "{}: the photo {photo} of `{}` is not read ({e}): the part has no photo",
                assets.display_path(library).display(),
                group.name
            )),
        }
    }
    Ok(notes)
}

/// The files on disk beside an OBJ in `folder` that its libraries name (the libraries and
/// their photos), relative to `folder`: what must travel with the OBJ when it is copied.
pub fn companions(obj: &str, folder: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for library in library_names(obj) {
        let Ok(text) = std::fs::read_to_string(folder.join(&library)) else { continue };
        for (_, photo) in photos(&text, Path::new(&library)).unwrap_or_default() {
            if let Ok(file) = sibling(&library, &photo)
                && folder.join(&file).is_file()
            {
                out.push(file);
            }
        }
        out.push(library);
    }
    out.sort();
    out.dedup();
    out
}

/// The OBJ text with its `mtllib` lines naming each library by the hash reference `store`
/// gives it (and each library's `map_Kd` lines naming their photos the same way), for a
/// bundle. Libraries and photos that cannot be read are left as they are named (the loader
/// notes them); the text is unchanged when it names none.
pub fn embed(
    obj: &str,
    reference: &str,
    assets: &dyn Assets,
    place: &str,
    store: &mut dyn FnMut(Vec<u8>, &str) -> String,
) -> Result<String> {
    if library_names(obj).is_empty() {
        return Ok(obj.to_owned());
    }
    let mut out = String::with_capacity(obj.len());
    for line in obj.split_inclusive('\n') {
        let Some(rest) = value_of(line, "mtllib") else {
            out.push_str(line);
            continue;
        };
        let (mut names, mut embedded) = (Vec::new(), false);
        for library in rest.split_whitespace().map(file_name) {
            let read = sibling(reference, &library).ok().and_then(|file| {
                let bytes = assets.read(&file, place).ok()?;
                Some((file, bytes))
            });
            let Some((file, bytes)) = read else {
                names.push(library);
                continue;
            };
            let shown = assets.display_path(&file);
            let text = utf8_text(bytes, &shown)?;
            // A library without photos is not needed (its colours are not used).
            if photos(&text, &shown)?.is_empty() {
                names.push(library);
                continue;
            }
            let text = embed_photos(&text, &file, assets, place, store);
            names.push(store(text.into_bytes(), "mtl"));
            embedded = true;
        }
        match embedded {
            true => out.push_str(&format!("mtllib {}\n", names.join(" "))),
            false => out.push_str(line),
        }
    }
    Ok(out)
}

/// An MTL text with each `map_Kd` file that can be read named by its hash reference.
fn embed_photos(
    mtl: &str,
    reference: &str,
    assets: &dyn Assets,
    place: &str,
    store: &mut dyn FnMut(Vec<u8>, &str) -> String,
) -> String {
    let mut out = String::with_capacity(mtl.len());
    for line in mtl.split_inclusive('\n') {
        let Some(value) = value_of(line, "map_Kd") else {
            out.push_str(line);
            continue;
        };
        let photo = photo_of(value);
        let read = sibling(reference, &photo).ok().and_then(|file| assets.read(&file, place).ok());
        match read {
            Some(bytes) => {
                let options: Vec<&str> = value.split_whitespace().collect();
                let options = options[..options.len().saturating_sub(1)].join(" ");
                let named = store(bytes, &extension(&photo));
                let sep = if options.is_empty() { "" } else { " " };
                out.push_str(&format!("map_Kd {options}{sep}{named}\n"));
            }
            None => out.push_str(line),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_and_photo_names_are_read_as_exporters_write_them() {
        let obj = "# Agisoft\nmtllib model.mtl\nmtllib a.mtl b.mtl\nv 0 0 0\n";
        assert_eq!(library_names(obj), ["model.mtl", "a.mtl", "b.mtl"]);
        assert_eq!(photo_of(" -s 1 1 1 -clamp on textures\\block_0.jpg"), "textures/block_0.jpg");
        assert_eq!(photo_of("  photo.png "), "photo.png");
    }
}
