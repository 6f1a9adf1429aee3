//! Asset bundles: a scene and every file it refers to, content-addressed by BLAKE3.
//!
//! In a bundle's canonical scene every file reference is `blake3:<hash>.<extension>` (the
//! extension keeps the format), and the scene is serialised as JSON in a fixed order (struct
//! fields in declaration order, maps sorted). Two scenes that say the same thing — whatever
//! their file names, comments or layout — have the same canonical form and so one identity,
//! and a coordinator and its workers move each file once, by hash.

use crate::assets::{Assets, BundleAssets, FolderAssets, extension};
use crate::error::{Result, SceneError};
use crate::load::{Limits, LoadedScene, load, read_scene_file};
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

/// Bundle the scene file at `path` and everything it refers to (or read the bundle an archive
/// at `path` holds, see `archive`).
pub fn bundle_scene(path: &Path, limits: &Limits) -> Result<Bundle> {
    if crate::archive::is_archive(path) {
        return crate::archive::read_archive(path, limits);
    }
    let mut scene = read_scene_file(path, limits)?;
    let assets = FolderAssets::new(path, limits.max_file_bytes)?;
    let mut files = BTreeMap::new();
    let mut add = |reference: &mut String, place: String| -> Result<()> {
        let mut bytes = assets.read(reference, &place)?;
        if extension(reference) == "gltf" {
            // One file in the bundle: the model with its separate buffers embedded.
            let shown = assets.display_path(reference);
            let beside = |uri: &str| {
                assets.read(&crate::assets::sibling(reference, uri), &place).map_err(|e| {
                    SceneError::invalid(&shown, format!("buffer `{uri}`"), e.to_string())
                })
            };
            bytes = crate::gltf_mesh::embed_buffers(&bytes, &shown, &beside)?;
        }
        let hash = blake3::hash(&bytes).to_hex().to_string();
        *reference = format!("blake3:{hash}.{}", extension(reference));
        files.insert(hash, bytes);
        Ok(())
    };
    for (name, s) in scene.spectra.iter_mut() {
        if let SpectrumSource::File { file, .. } = s {
            add(file, format!("spectra.{name}"))?;
        }
    }
    for (i, o) in scene.objects.iter_mut().enumerate() {
        add(&mut o.mesh, format!("objects[{i}].mesh"))?;
    }
    for (i, l) in scene.lights.iter_mut().enumerate() {
        if let Light::Point { ies: Some(r), .. } | Light::Spot { ies: Some(r), .. } = l {
            add(r, format!("lights[{i}].ies"))?;
        }
    }
    Ok(Bundle { scene, files })
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
        let mut out = Vec::new();
        for s in scene.spectra.values_mut() {
            if let SpectrumSource::File { file, .. } = s {
                out.push(file);
            }
        }
        out.extend(scene.objects.iter_mut().map(|o| &mut o.mesh));
        for l in &mut scene.lights {
            if let Light::Point { ies: Some(r), .. } | Light::Spot { ies: Some(r), .. } = l {
                out.push(r);
            }
        }
        out
    }

    /// Every file reference in the scene.
    pub fn references(&self) -> Vec<String> {
        let mut out = Vec::new();
        for s in self.scene.spectra.values() {
            if let SpectrumSource::File { file, .. } = s {
                out.push(file.clone());
            }
        }
        out.extend(self.scene.objects.iter().map(|o| o.mesh.clone()));
        for l in &self.scene.lights {
            if let Light::Point { ies: Some(r), .. } | Light::Spot { ies: Some(r), .. } = l {
                out.push(r.clone());
            }
        }
        out
    }
}
