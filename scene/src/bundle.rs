//! Asset bundles: a scene and every file it refers to, content-addressed by BLAKE3.
//!
//! In a bundle's canonical scene every file reference is `blake3:<hash>.<extension>` (the
//! extension keeps the format), and the scene is serialised as JSON in a fixed order (struct
//! fields in declaration order, maps sorted). Two scenes that say the same thing — whatever
//! their file names, comments or layout — have the same canonical form and so one identity,
//! and a coordinator and its workers move each file once, by hash.

use crate::assets::{Assets, BundleAssets, extension};
use crate::error::{Result, SceneError};
use crate::load::{Limits, LoadedScene, load};
use crate::scene_file::{Light, SceneFile, SpectrumSource};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A scene with its files.
#[derive(Clone, Debug, PartialEq)]
pub struct Bundle {
    /// The scene with its references replaced by hashes.
    pub scene: SceneFile,
    /// File bytes by BLAKE3 hash (hex).
    pub files: BTreeMap<String, Vec<u8>>,
}

/// Bundle the scene file at `path` with the files of its folder; files named by URL are
/// refused (restauro-assets's `bundle_scene` fetches them, and reads archives too).
pub fn bundle_folder(path: &Path, limits: &Limits) -> Result<Bundle> {
    let (scene, assets) = crate::load::open_folder(path, limits)?;
    bundle_files(scene, &assets, limits)
}

/// Bundle `scene` with the files `assets` holds (a folder, whose URLs are fetched once; see
/// restauro-assets for a scene folder or archive on disk).
pub fn bundle_files(mut scene: SceneFile, assets: &dyn Assets, limits: &Limits) -> Result<Bundle> {
    let mut files = BTreeMap::new();
    let mut included = Vec::new();
    let mut add = |reference: &mut String, place: String| -> Result<()> {
        let mut bytes = assets.read(reference, &place)?;
        bytes =
            embed_nested(reference, bytes, (assets, &place), limits, &mut files, &mut included)?;
        if extension(reference) == "gltf" {
            // One file in the bundle: the model with its separate buffers embedded.
            let shown = assets.display_path(reference);
            let beside = |uri: &str| {
                let invalid = |e: String| SceneError::invalid(&shown, format!("buffer `{uri}`"), e);
                let file =
                    crate::assets::sibling(reference, uri).map_err(|e| invalid(e.to_string()))?;
                assets.read(&file, &place).map_err(|e| invalid(e.to_string()))
            };
            bytes = crate::formats::gltf::mesh::embed_buffers(&bytes, &shown, &beside)?;
        }
        let hash = blake3::hash(&bytes).to_hex().to_string();
        *reference = format!("blake3:{hash}.{}", extension(reference));
        files.insert(hash, bytes);
        Ok(())
    };
    for (place, reference) in Bundle::placed_references_mut(&mut scene) {
        add(reference, place)?;
    }
    // Every file is named by its hash now: the pins have done their work, and a scene says
    // the same thing whether its files came from a folder or from the web.
    scene.pins.clear();
    included.sort();
    included.dedup();
    scene.included = included;
    Ok(Bundle { scene, files })
}

/// The file `reference` (its `bytes`) with the files it names inside itself — a VRML97
/// world's Inlines, an OBJ's material library and its photos — named by hash, those files
/// added to `files` and listed in `included`.
fn embed_nested(
    reference: &str,
    bytes: Vec<u8>,
    (assets, place): (&dyn Assets, &str),
    limits: &Limits,
    files: &mut BTreeMap<String, Vec<u8>>,
    included: &mut Vec<String>,
) -> Result<Vec<u8>> {
    let mut store = |bytes: Vec<u8>, extension: &str| {
        let hash = blake3::hash(&bytes).to_hex().to_string();
        let named = format!("blake3:{hash}.{extension}");
        files.insert(hash, bytes);
        included.push(named.clone());
        named
    };
    let shown = assets.display_path(reference);
    Ok(match extension(reference).as_str() {
        "wrl" => {
            let text = crate::assets::utf8_text(bytes, &shown)?;
            let source = crate::formats::vrml::inlines_from_assets(assets, place);
            let mut store = |bytes: Vec<u8>| store(bytes, "wrl");
            crate::formats::vrml::embed_inlines(
                &text, &shown, reference, limits, &source, &mut store,
            )?
            .into_bytes()
        }
        "obj" => {
            let text = crate::assets::utf8_text(bytes, &shown)?;
            crate::formats::obj::library::embed(&text, reference, assets, place, &mut store)?
                .into_bytes()
        }
        _ => bytes,
    })
}

impl Bundle {
    /// The canonical form of the scene: JSON, fixed order, references by hash.
    pub fn canonical_json(&self) -> String {
        serde_json::to_string(&self.scene).expect("a scene always serialises")
    }

    /// The scene's identity: the BLAKE3 hash of its canonical form (which names every file by
    /// its own hash).
    pub fn id(&self) -> String {
        blake3::hash(self.canonical_json().as_bytes()).to_hex().to_string()
    }

    /// The files, for reading the bundle as a scene.
    pub fn assets(&self) -> impl Assets + '_ {
        BundleAssets {
            name: PathBuf::from(format!("bundle {}", &self.id()[..16])),
            files: &self.files,
        }
    }

    /// Load the scene from the bundle alone, as a worker does.
    pub fn load(&self, limits: &Limits) -> Result<LoadedScene> {
        load(self.scene.clone(), &self.assets(), limits)
    }

    /// The scene of a canonical form, without its files (to learn which files it needs).
    pub fn parse_manifest(canonical_json: &str) -> Result<SceneFile> {
        serde_json::from_str(canonical_json)
            .map_err(|e| SceneError::invalid(Path::new("bundle"), "canonical scene", e.to_string()))
    }

    /// Rebuild a bundle from its canonical form and files (e.g. received over the network),
    /// checking that every file the scene names is present and intact.
    pub fn from_parts(canonical_json: &str, files: BTreeMap<String, Vec<u8>>) -> Result<Bundle> {
        let name = PathBuf::from("bundle");
        let scene: SceneFile = serde_json::from_str(canonical_json)
            .map_err(|e| SceneError::invalid(&name, "canonical scene", e.to_string()))?;
        let bundle = Bundle { scene, files };
        {
            let assets = bundle.assets();
            for reference in bundle.references() {
                assets.read(&reference, "files")?;
            }
        }
        Ok(bundle)
    }

    /// Every file reference in the scene, to rewrite.
    pub fn references_mut(scene: &mut SceneFile) -> Vec<&mut String> {
        Self::placed_references_mut(scene).into_iter().map(|(_, r)| r).collect()
    }

    /// Every file reference in the scene.
    pub fn references(&self) -> Vec<String> {
        let mut scene = self.scene.clone();
        Self::references_mut(&mut scene).into_iter().map(|r| r.clone()).collect()
    }

    /// Every file reference in the scene, each with where the scene names it
    /// (`objects[2].mesh`), in the scene's order.
    pub fn placed_references_mut(scene: &mut SceneFile) -> Vec<(String, &mut String)> {
        let mut out = Vec::new();
        for (name, s) in &mut scene.spectra {
            if let SpectrumSource::File { file, .. } = s {
                out.push((format!("spectra.{name}"), file));
            }
        }
        for (name, m) in &mut scene.materials {
            if let Some(t) = &mut m.texture {
                out.push((format!("materials.{name}.texture"), t));
            }
            for (state, o) in [("degraded", &mut m.degraded), ("cleaned", &mut m.cleaned)] {
                if let Some(t) = o.as_mut().and_then(|o| o.texture.as_mut()) {
                    out.push((format!("materials.{name}.{state}.texture"), t));
                }
            }
        }
        for (i, m) in scene.maps.iter_mut().enumerate() {
            out.push((format!("maps[{i}].image"), &mut m.image));
        }
        for (i, o) in scene.objects.iter_mut().enumerate() {
            out.push((format!("objects[{i}].mesh"), &mut o.mesh));
        }
        for (i, l) in scene.lights.iter_mut().enumerate() {
            if let Light::Point { ies: Some(r), .. } | Light::Spot { ies: Some(r), .. } = l {
                out.push((format!("lights[{i}].ies"), r));
            }
        }
        for (i, a) in scene.annotations.iter_mut().enumerate() {
            for (k, image) in a.images.iter_mut().enumerate() {
                out.push((format!("annotations[{i}].images[{k}]"), image));
            }
        }
        for (i, file) in scene.included.iter_mut().enumerate() {
            out.push((format!("included[{i}]"), file));
        }
        out
    }
}
