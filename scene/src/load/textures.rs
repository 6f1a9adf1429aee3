//! The materials' photo textures: each image (PNG or JPEG) read and decoded once, however many
//! materials and states use it, within the pixel limit; glass refused a texture; every white
//! patch checked to lie in the photo it white-balances.

use super::{Ctx, Limits};
use crate::assets::extension;
use crate::error::Result;
use crate::scene_file::{self, MaterialModel};
use std::collections::BTreeMap;

/// Every material's photo textures (the base one and the states'), decoded once each.
pub(super) fn load_textures(
    ctx: &Ctx,
    limits: &Limits,
) -> Result<BTreeMap<String, std::sync::Arc<crate::texture::Texture>>> {
    let mut out: BTreeMap<String, std::sync::Arc<crate::texture::Texture>> = BTreeMap::new();
    for (name, m) in &ctx.file.materials {
        let states = [("", m.texture.as_ref(), m.white_patch)].into_iter().chain(
            [("degraded", &m.degraded), ("cleaned", &m.cleaned)].map(|(st, o)| {
                let o = o.as_ref();
                (st, o.and_then(|o| o.texture.as_ref()), o.and_then(|o| o.white_patch))
            }),
        );
        for (state, reference, patch) in states {
            let at = match state {
                "" => format!("materials.{name}"),
                s => format!("materials.{name}.{s}"),
            };
            let Some(reference) = reference else {
                if patch.is_some() && !state.is_empty() {
                    return Err(ctx.invalid(
                        format!("{at}.white_patch"),
                        "the patch lies in the state's own photo, and it has none; give the \
                         state a `texture`, or put `white_patch` on the material",
                    ));
                }
                continue;
            };
            let place = format!("{at}.texture");
            if m.model == MaterialModel::Glass {
                return Err(
                    ctx.invalid(place, "glass takes no texture; give it to the stone behind")
                );
            }
            if let Some(texture) = out.get(reference) {
                check_white_patch(ctx, &at, texture, patch)?;
                continue;
            }
            let ext = extension(reference);
            if !crate::texture::EXTENSIONS.contains(&ext.as_str()) {
                return Err(ctx.invalid(
                    place,
                    format!("`{reference}`: `.{ext}` is not an image restauro reads; use a PNG or JPEG file"),
                ));
            }
            let bytes = ctx.assets.read(reference, &place)?;
            let shown = ctx.assets.display_path(reference);
            let texture = crate::texture::decode(&bytes, &ext, &shown, limits.max_pixels)?;
            check_white_patch(ctx, &at, &texture, patch)?;
            out.insert(reference.clone(), std::sync::Arc::new(texture));
        }
    }
    Ok(out)
}

/// A grey patch (`{at}.white_patch`) that white-balances `texture`, checked against it.
fn check_white_patch(
    ctx: &Ctx,
    at: &str,
    texture: &crate::texture::Texture,
    patch: Option<scene_file::PixelRect>,
) -> Result<()> {
    let Some(patch) = patch else { return Ok(()) };
    texture
        .check_patch(patch)
        .map_err(|problem| ctx.invalid(format!("{at}.white_patch"), problem.to_string()))
}
