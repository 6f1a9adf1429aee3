//! The `[variants]` table: each variant's state (base, degraded or cleaned) and the states it
//! gives objects and parts, which must be in the scene. A material asked for a state it does not
//! have keeps its base state, and a note says so.

use super::annotations::check_part;
use super::{Ctx, LoadedObject};
use crate::error::{Result, SceneError};
use std::collections::BTreeSet;

/// Every variant: known states, for the whole and for each part it names, and each part in the
/// scene; the materials without a state it asks for are noted.
pub(super) fn check_variants(ctx: &mut Ctx, objects: &[LoadedObject]) -> Result<()> {
    let file = ctx.file;
    let states = ["base", "degraded", "cleaned"];
    for (name, v) in &file.variants {
        let place = format!("variants.{name}");
        let check_state = |s: &str| -> Result<()> {
            if states.contains(&s) {
                Ok(())
            } else {
                Err(SceneError::invalid(
                    &ctx.path,
                    &place,
                    format!("unknown state `{s}`; use base, degraded or cleaned"),
                ))
            }
        };
        check_state(&v.state)?;
        for (key, state) in &v.states {
            check_state(state)?;
            check_part(ctx, &place, objects, key)?;
        }
        // Materials asked for a state they do not have keep their base state; say so.
        let mut lacking = BTreeSet::new();
        for o in objects {
            for (g, material) in o.mesh.groups.iter().zip(&o.group_materials) {
                let state = v.state_for(&o.name, &g.name);
                if !file.materials[material].has_state(state) {
                    lacking.insert(format!("{material} ({state})"));
                }
            }
        }
        if !lacking.is_empty() {
            ctx.notes.push(format!(
                "{place}: these materials have no such state and keep their base one: {}",
                lacking.into_iter().collect::<Vec<_>>().join(", ")
            ));
        }
    }
    Ok(())
}
