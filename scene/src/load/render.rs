//! The `[render]` table: samples per pixel and the depth of a path, each within the limits that
//! protect the machine ([`Limits`]).

use super::{Ctx, Limits};
use crate::error::Result;

/// The render settings: at least one sample per pixel, and no more samples or bounces than the
/// limits allow.
pub(super) fn check_render(ctx: &Ctx, limits: &Limits) -> Result<()> {
    let r = &ctx.file.render;
    if r.samples_per_pixel == 0 || r.samples_per_pixel > limits.max_samples_per_pixel {
        return Err(ctx.limit(
            "render.samples_per_pixel",
            u64::from(r.samples_per_pixel),
            u64::from(limits.max_samples_per_pixel),
            "use 1 or more, or raise the limit with --max-spp",
        ));
    }
    // 0 is no cap: the roulette ends paths, at a cost bounded in expectation.
    if r.max_depth > limits.max_depth {
        return Err(ctx.limit(
            "render.max_depth",
            u64::from(r.max_depth),
            u64::from(limits.max_depth),
            "use fewer bounces (0: no cap, the roulette ends paths), or raise the limit with --max-depth",
        ));
    }
    if let Err(problem) = crate::scene_file::check_noise_target(r.noise_target) {
        return Err(ctx.invalid("render.noise_target", problem));
    }
    Ok(())
}
