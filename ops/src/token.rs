//! Bearer tokens, read from a file (a mounted Secret, a systemd credential) or else from an
//! environment variable — never from the command line, where other users could read them.

use anyhow::{Context, Result, bail};
use std::path::Path;

/// The token in `file`, else in the environment variable `variable`; refuses an empty one and
/// says which flag or variable to set.
pub fn read_token(file: Option<&Path>, variable: &str, flag: &str) -> Result<String> {
    let token = match file {
        Some(path) => std::fs::read_to_string(path)
            .with_context(|| format!("reading the token file {}", path.display()))?,
        None => std::env::var(variable).unwrap_or_default(),
    };
    let token = token.trim().to_owned();
    if token.is_empty() {
        bail!("no token: give {flag} FILE or set {variable}");
    }
    Ok(token)
}
