//! The one error type of restauro-scene. Every message names the file, the place in it (line
//! and column, field, face or element) and what to do.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file that cannot be read at all. The I/O error is worded into the message (see
    /// [`io_problem`]) and deliberately not exposed as the error's `source`: callers that print
    /// the whole chain (`anyhow`'s `{:#}`) would otherwise say it twice.
    #[error("{}: {}", path.display(), io_problem(error))]
    Io { path: PathBuf, error: std::io::Error },

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
    pub fn io(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        SceneError::Io { path: path.into(), error }
    }

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

/// An I/O error in plain words, with what to do: the operating system's own text (which
/// carries its error number) only for the kinds without a better wording.
pub fn io_problem(error: &std::io::Error) -> String {
    use std::io::ErrorKind::*;
    match error.kind() {
        NotFound => "the file does not exist; check the path (and the current folder)".into(),
        PermissionDenied => "permission denied; make the file readable".into(),
        IsADirectory => "this is a folder, not a file; give the file inside it".into(),
        UnexpectedEof => "the file ends early (it is truncated); copy it again".into(),
        InvalidData => format!("{error}; save the file as UTF-8 text"),
        _ => format!("cannot read the file ({error})"),
    }
}

pub type Result<T, E = SceneError> = std::result::Result<T, E>;
