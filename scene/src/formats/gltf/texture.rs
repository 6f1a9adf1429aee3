//! A glTF material's base colour photo (`pbrMetallicRoughness.baseColorTexture`): its image
//! from a buffer view (in a .glb), a `data:` URI or a file beside the model, and the texture
//! coordinate set and `KHR_texture_transform` it is laid on with. restauro takes it as detail
//! over the measured spectrum the part is bound to, as it takes a material's `texture`.

use crate::error::{Result, SceneError};
use crate::formats::gltf::mesh::External;
use crate::texture::{Texture, decode};
use base64::Engine as _;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// A material's photo and how its texture coordinates are read.
pub struct Photo {
    pub texture: Arc<Texture>,
    /// The TEXCOORD_n set it is laid on with.
    pub set: u32,
    /// `KHR_texture_transform`, baked into the coordinates as they are read.
    pub transform: Option<UvTransform>,
}

/// `KHR_texture_transform`: uv' = T·R·S·uv (offset, rotation about the origin, scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
}

impl UvTransform {
    /// The extension's matrix applied: u' = cos·sx·u + sin·sy·v + ox, v' = −sin·sx·u +
    /// cos·sy·v + oy (KHR_texture_transform, "Overview").
    pub fn apply(&self, [u, v]: [f32; 2]) -> [f32; 2] {
        let (s, c) = self.rotation.sin_cos();
        let (su, sv) = (self.scale[0] * u, self.scale[1] * v);
        [c * su + s * sv + self.offset[0], -s * su + c * sv + self.offset[1]]
    }
}

/// The images decoded so far, by index: a photo shared by many materials is decoded once.
pub type Decoded = HashMap<usize, Arc<Texture>>;

/// The base colour photo of `material`, if it has one.
pub fn base_colour_photo(
    material: &gltf::Material,
    buffers: &[Vec<u8>],
    path: &Path,
    (external, max_pixels): (External<'_>, u64),
    decoded: &mut Decoded,
) -> Result<Option<Photo>> {
    let Some(info) = material.pbr_metallic_roughness().base_color_texture() else {
        return Ok(None);
    };
    let image = info.texture().source();
    let texture = match decoded.get(&image.index()) {
        Some(t) => t.clone(),
        None => {
            let place = format!("image {}", image.index());
            let bytes = image_bytes(&image, buffers, path, external)?;
            let kind = sniff(&bytes).ok_or_else(|| {
                SceneError::invalid(
                    path,
                    &place,
                    "not a PNG or JPEG image; restauro reads those two",
                )
            })?;
            let t = Arc::new(decode(&bytes, kind, path, max_pixels)?);
            decoded.insert(image.index(), t.clone());
            t
        }
    };
    let transform = info.texture_transform();
    let set = transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
    let transform = transform.map(|t| UvTransform {
        offset: t.offset(),
        rotation: t.rotation(),
        scale: t.scale(),
    });
    Ok(Some(Photo { texture, set, transform }))
}

/// The image's file bytes: a slice of a buffer view, a `data:` URI, or a file beside the model.
fn image_bytes(
    image: &gltf::Image,
    buffers: &[Vec<u8>],
    path: &Path,
    external: External<'_>,
) -> Result<Vec<u8>> {
    let place = format!("image {}", image.index());
    match image.source() {
        gltf::image::Source::View { view, .. } => {
            let buffer = buffers.get(view.buffer().index());
            let range = view.offset()..view.offset().saturating_add(view.length());
            buffer.and_then(|b| b.get(range)).map(<[u8]>::to_vec).ok_or_else(|| {
                SceneError::invalid(path, place, "its buffer view lies outside its buffer")
            })
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(rest) => {
                let data = rest.split_once(";base64,").map(|(_, d)| d).ok_or_else(|| {
                    SceneError::invalid(path, &place, "a data: URI that is not base64")
                })?;
                base64::engine::general_purpose::STANDARD
                    .decode(data)
                    .map_err(|e| SceneError::invalid(path, &place, format!("bad base64 data: {e}")))
            }
            None => external(&crate::formats::gltf::mesh::external_path(uri, path, image.index())?),
        },
    }
}

/// The format of an image by its signature (ISO/IEC 15948 §5.2, ITU-T T.81 §B.1.1.2).
fn sniff(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(&[0x89, b'P', b'N', b'G']) {
        Some("png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("jpg")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The extension's own example: offset (0, 1), rotation π/2, scale (0.5, 0.5) takes the
    /// texture's corner (1, 0) to (0, 0.5).
    #[test]
    fn the_transform_is_offset_rotation_scale() {
        let t = UvTransform {
            offset: [0.0, 1.0],
            rotation: std::f32::consts::FRAC_PI_2,
            scale: [0.5, 0.5],
        };
        let [u, v] = t.apply([1.0, 0.0]);
        assert!(u.abs() < 1e-6 && (v - 0.5).abs() < 1e-6, "({u}, {v})");
    }
}
