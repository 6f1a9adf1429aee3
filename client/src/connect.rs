//! Talking to a coordinator as the user does: the client token (from a file, else the
//! environment), and the coordinator's texts as a terminal may show them. Shared by the
//! commands that render through a cluster (`render`, `submit` and the job commands, `demo`).

use anyhow::{Context, Result, bail};
use std::path::Path;

/// The client token from a file, else RESTAURO_TOKEN.
pub fn client_token(file: Option<&Path>) -> Result<String> {
    let token = match file {
        Some(path) => std::fs::read_to_string(path)
            .with_context(|| format!("reading the token file {}", path.display()))?,
        None => std::env::var("RESTAURO_TOKEN").unwrap_or_default(),
    };
    let token = token.trim().to_owned();
    if token.is_empty() {
        bail!("no client token: give --token-file FILE or set RESTAURO_TOKEN");
    }
    Ok(token)
}

/// A text from the coordinator as a terminal may show it: control characters escaped, so no
/// name can move the cursor, clear the screen or begin a new line.
pub fn shown(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() })
        .collect()
}

#[cfg(test)]
mod tests {
    /// Defect 6: a name with terminal escapes and newlines was printed raw by `restauro jobs`.
    #[test]
    fn texts_from_the_coordinator_cannot_drive_the_terminal() {
        let shown = super::shown("evil\u{1b}[2J\nname\r\u{7}");
        assert!(!shown.chars().any(char::is_control), "{shown:?}");
        assert_eq!(shown, "evil\\u{1b}[2J\\nname\\r\\u{7}");
        assert_eq!(super::shown("façade sud"), "façade sud");
    }
}
