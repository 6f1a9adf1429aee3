//! The `[[annotations]]` table: each note's title its own, its pin in range, the part it names
//! in the scene, its links web addresses (so that no link runs a script or opens a local file),
//! its pose one the camera can take, and its images PNG or JPEG files that are what their names
//! say. Also [`check_part`], which the variants use too.

use super::camera::check_pose;
use super::{Ctx, LoadedObject, check_point, unknown};
use crate::assets::extension;
use crate::error::{Result, SceneError};
use crate::scene_file::SceneFile;
use std::collections::BTreeSet;

/// `key` names an object (`name`) or a part of one (`object/part`).
pub(super) fn check_part(
    ctx: &Ctx,
    place: &str,
    objects: &[LoadedObject],
    key: &str,
) -> Result<()> {
    let (object, group) = match key.split_once('/') {
        Some((o, g)) => (o, Some(g)),
        None => (key, None),
    };
    let o = objects.iter().find(|o| o.name == object).ok_or_else(|| {
        ctx.invalid(place, unknown("object", object, objects.iter().map(|o| o.name.as_str())))
    })?;
    if let Some(g) = group
        && !o.mesh.groups.iter().any(|x| x.name == g)
    {
        return Err(ctx.invalid(
            place,
            unknown("mesh part", g, o.mesh.groups.iter().map(|x| x.name.as_str())),
        ));
    }
    Ok(())
}

/// The longest link an annotation may hold, in bytes.
const MAX_LINK_BYTES: usize = 2048;

/// Every annotation: a title of its own, its pin in range, its part in the scene, its links
/// web addresses (so that no link runs a script or opens a local file), its pose one the
/// camera can take.
pub(super) fn check_annotations(
    ctx: &Ctx,
    file: &SceneFile,
    objects: &[LoadedObject],
) -> Result<()> {
    let mut seen = BTreeSet::new();
    for (i, a) in file.annotations.iter().enumerate() {
        let place = format!("annotations[{i}]");
        if a.title.trim().is_empty() {
            return Err(ctx.invalid(format!("{place}.title"), "a note needs a title"));
        }
        if !seen.insert(a.title.as_str()) {
            return Err(ctx.invalid(
                format!("{place}.title"),
                format!("a second note titled `{}`; give each note its own title", a.title),
            ));
        }
        check_point(ctx, &format!("{place}.position"), a.position)?;
        if let Some(part) = &a.part {
            check_part(ctx, &format!("{place}.part"), objects, part)?;
        }
        for (k, link) in a.links.iter().enumerate() {
            let web = link.starts_with("https://") || link.starts_with("http://");
            if !web || link.len() > MAX_LINK_BYTES || link.chars().any(char::is_whitespace) {
                return Err(ctx.invalid(
                    format!("{place}.links[{k}]"),
                    format!(
                        "`{}` is not a web address; give an https:// (or http://) address of at most {MAX_LINK_BYTES} bytes, without spaces",
                        link.chars().take(80).collect::<String>().escape_debug()
                    ),
                ));
            }
        }
        if let Some(pose) = &a.pose {
            check_pose(ctx, &format!("{place}.pose"), pose)?;
        }
        check_note_images(ctx, &place, &a.images)?;
    }
    Ok(())
}

/// A note's images: at most [`note_image::MAX_PER_NOTE`], each a PNG or JPEG file that is what
/// its name says.
fn check_note_images(ctx: &Ctx, place: &str, images: &[String]) -> Result<()> {
    use crate::note_image;
    if images.len() > note_image::MAX_PER_NOTE {
        return Err(ctx.invalid(
            format!("{place}.images"),
            format!(
                "{} images; a note holds at most {}: link the rest as documents",
                images.len(),
                note_image::MAX_PER_NOTE
            ),
        ));
    }
    for (k, reference) in images.iter().enumerate() {
        let place = format!("{place}.images[{k}]");
        let kind = extension(reference);
        if !note_image::EXTENSIONS.contains(&kind.as_str()) {
            return Err(ctx.invalid(
                place,
                format!("`{reference}`: a note's image is a .png, .jpg or .jpeg file"),
            ));
        }
        let bytes = ctx.assets.read(reference, &place)?;
        let shown = ctx.assets.display_path(reference);
        if bytes.len() > note_image::MAX_BYTES {
            return Err(SceneError::invalid(
                &shown,
                place,
                format!(
                    "{} bytes; a note's image may have at most {}: send a smaller copy",
                    bytes.len(),
                    note_image::MAX_BYTES
                ),
            ));
        }
        if note_image::media_type(&kind, &bytes).is_none() {
            return Err(SceneError::invalid(&shown, place, note_image::not_an_image(&kind)));
        }
    }
    Ok(())
}
