//! The one error type of restauro-scene. Every message names the file, the place in it (line
//! and column, field, face or element) and what to do.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file that cannot be read at all.
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },

    /// A syntax error with a position (VRML97, IES, EULUMDAT, TOML).
    #[error("{}:{line}:{column}: {problem}", path.display())]
    Syntax { path: PathBuf, line: usize, column: usize, problem: String },

    /// A file that parses but whose content is wrong; `place` says where (a field, a face, an
    /// element), `problem` what is wrong and what to do.
    #[error("{}: {place}: {problem}", path.display())]
    Invalid { path: PathBuf, place: String, problem: String },

    /// A limit that protects the machine; says which limit and how to change it.
    #[error("{}: {what} is {value}, over the limit of {limit}; {fix}", path.display())]
    Limit { path: PathBuf, what: String, value: u64, limit: u64, fix: String },
}

impl SceneError {
    pub fn invalid(
        path: impl Into<PathBuf>,
        place: impl Into<String>,
        problem: impl Into<String>,
    ) -> Self {
        SceneError::Invalid { path: path.into(), place: place.into(), problem: problem.into() }
    }

    pub fn syntax(
        path: impl Into<PathBuf>,
        line: usize,
        column: usize,
        problem: impl Into<String>,
    ) -> Self {
        SceneError::Syntax { path: path.into(), line, column, problem: problem.into() }
    }
}

pub type Result<T, E = SceneError> = std::result::Result<T, E>;
