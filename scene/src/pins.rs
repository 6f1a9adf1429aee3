//! The scene file's `[pins]` table: the content hash each file named by URL must serve, so that
//! a render made from remote files can be made again. Checked here with the rest of the scene
//! file; the files are fetched and checked against their pins by restauro-assets.

use crate::error::{Result, SceneError};
use crate::scene_file::Pin;
use crate::web_url::WebUrl;
use std::collections::BTreeMap;
use std::path::Path;

/// A hash function a pin may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    Sha256,
    Blake3,
}

impl Algorithm {
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Sha256 => "sha256",
            Algorithm::Blake3 => "blake3",
        }
    }
}

/// A checked pin: which hash, and its 64 hexadecimal digits in lower case.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ContentHash {
    pub algorithm: Algorithm,
    pub hex: String,
}

impl std::fmt::Display for ContentHash {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} = \"{}\"", self.algorithm.name(), self.hex)
    }
}

/// Why a pin is not one well-formed hash.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PinError {
    #[error("give one hash: `{{ sha256 = \"…\" }}` or `{{ blake3 = \"…\" }}`")]
    NotOneHash,
    #[error(
        "the {} `{hex}` is not 64 hexadecimal digits; copy it whole from `{}sum`",
        algorithm.name(),
        if *algorithm == Algorithm::Sha256 { "sha256" } else { "b3" }
    )]
    NotHex { algorithm: Algorithm, hex: String },
}

impl TryFrom<&Pin> for ContentHash {
    type Error = PinError;

    fn try_from(pin: &Pin) -> Result<Self, PinError> {
        let (algorithm, hex) = match (&pin.sha256, &pin.blake3) {
            (Some(hex), None) => (Algorithm::Sha256, hex),
            (None, Some(hex)) => (Algorithm::Blake3, hex),
            _ => return Err(PinError::NotOneHash),
        };
        let hex = hex.trim().to_ascii_lowercase();
        if hex.len() != 64 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(PinError::NotHex { algorithm, hex });
        }
        Ok(ContentHash { algorithm, hex })
    }
}

/// The pins of the scene file at `scene_file`, checked: each key a web URL (written as it is
/// compared), each value one well-formed hash.
pub fn check_pins(
    scene_file: &Path,
    pins: &BTreeMap<String, Pin>,
) -> Result<BTreeMap<String, ContentHash>> {
    let mut checked = BTreeMap::new();
    for (url, pin) in pins {
        let place = format!("pins.\"{url}\"");
        let invalid = |problem: String| SceneError::invalid(scene_file, &place, problem);
        let parsed = WebUrl::parse(url).map_err(|e| invalid(e.to_string()))?;
        let hash = ContentHash::try_from(pin).map_err(|e| invalid(e.to_string()))?;
        checked.insert(parsed.to_string(), hash);
    }
    Ok(checked)
}
