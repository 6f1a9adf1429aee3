//! Bearer tokens, read from a file (a mounted Secret, a systemd credential) or else from an
//! environment variable — never from the command line, where other users could read them.

use crate::error::{OpsError, Result};
use std::path::Path;

/// The token in `file`, else in the environment variable `variable`; refuses an empty one and
/// says which flag or variable to set.
pub fn read_token(file: Option<&Path>, variable: &str, flag: &str) -> Result<String> {
    let token = match file {
        Some(path) => std::fs::read_to_string(path)
            .map_err(|error| OpsError::TokenFile { path: path.to_owned(), error })?,
        None => std::env::var(variable).unwrap_or_default(),
    };
    let token = token.trim().to_owned();
    if token.is_empty() {
        return Err(OpsError::NoToken { flag: flag.to_owned(), variable: variable.to_owned() });
    }
    Ok(token)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A variable no environment sets, so the fallback finds nothing.
    const UNSET: &str = "RESTAURO_TEST_TOKEN_NEVER_SET";

    #[test]
    fn a_token_file_is_read_and_trimmed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("worker.token");
        std::fs::write(&path, "  s3cret\n").unwrap();
        assert_eq!(read_token(Some(&path), UNSET, "--token-file").unwrap(), "s3cret");
    }

    #[test]
    fn an_empty_token_names_the_flag_and_the_variable() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("empty.token");
        std::fs::write(&path, " \n\t\n").unwrap();
        for file in [Some(path.as_path()), None] {
            let message = read_token(file, UNSET, "--token-file").unwrap_err().to_string();
            assert_eq!(message, format!("no token: give --token-file FILE or set {UNSET}"));
        }
    }

    #[test]
    fn a_missing_token_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("absent.token");
        // As a binary prints it: the error and its cause.
        let error =
            anyhow::Error::from(read_token(Some(&path), UNSET, "--token-file").unwrap_err());
        let message = format!("{error:#}");
        assert!(
            message.starts_with(&format!("reading the token file {}:", path.display())),
            "{message}"
        );
    }
}
