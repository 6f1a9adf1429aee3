//! Objects in S3-compatible storage (`--objects s3://BUCKET/PREFIX`, with the `fleet` feature):
//! the scenes' files and the jobs' results, kept where every coordinator of a fleet finds them,
//! so a standby that takes the lead (`lead`) serves what its predecessor received and wrote.
//!
//! The data folder stays the coordinator's working copy: a file is written there first, then
//! put in the object store before it counts — an asset before its upload is acknowledged, a
//! result before its job (or frame) is done — and a file the folder lacks is fetched from the
//! object store on first use. Without `--objects` the folder is all there is.
//!
//! Finished tiles are not objects: they live in the store (`store`), whose transaction makes a
//! tile's bytes and its being done one write.

#[cfg(feature = "fleet")]
mod http;
#[cfg(feature = "fleet")]
mod s3;

use std::path::Path;

#[derive(Clone, Debug, thiserror::Error)]
pub enum ObjectsError {
    #[error("the object store {url}: {message}")]
    S3 { url: String, message: String },
}

pub type Result<T> = std::result::Result<T, ObjectsError>;

/// Where the coordinator's objects are kept besides its data folder.
pub enum Objects {
    /// Only in the data folder.
    Local,
    #[cfg(feature = "fleet")]
    S3(Box<s3::S3Objects>),
}

impl Objects {
    /// The object store at `url` (`s3://BUCKET[/PREFIX]`), checked reachable; the data folder
    /// alone for `None`.
    pub fn open(url: Option<&str>) -> Result<Objects> {
        match url {
            None => Ok(Objects::Local),
            #[cfg(feature = "fleet")]
            Some(url) => Ok(Objects::S3(Box::new(s3::S3Objects::open(url)?))),
            #[cfg(not(feature = "fleet"))]
            Some(url) => Err(ObjectsError::S3 {
                url: url.to_owned(),
                message: "this coordinator was built without object storage: build it with \
                          `cargo build --release -p restauro --features fleet` (the container \
                          image has it), or leave out --objects to keep files in --data"
                    .into(),
            }),
        }
    }

    /// Whether files are kept beyond the data folder.
    pub fn is_shared(&self) -> bool {
        !matches!(self, Objects::Local)
    }

    /// Puts the file at `path` in the object store as `key` (nothing to do without one).
    pub fn put_file(&self, key: &str, path: &Path) -> Result<()> {
        match self {
            Objects::Local => {
                let _ = (key, path);
                Ok(())
            }
            #[cfg(feature = "fleet")]
            Objects::S3(s3) => s3.put_file(key, path),
        }
    }

    /// Why files cannot be put, while they cannot (a full bucket, a server down).
    pub fn problem(&self) -> Option<String> {
        match self {
            Objects::Local => None,
            #[cfg(feature = "fleet")]
            Objects::S3(s3) => s3.problem(),
        }
    }

    /// Fetches the object `key` into the file `path` (written whole or not at all): whether
    /// there was one.
    pub fn fetch(&self, key: &str, path: &Path) -> Result<bool> {
        match self {
            Objects::Local => {
                let _ = (key, path);
                Ok(false)
            }
            #[cfg(feature = "fleet")]
            Objects::S3(s3) => s3.fetch(key, path),
        }
    }
}

/// The key of a scene's file.
pub fn asset_key(hash: &str) -> String {
    format!("assets/{}", hash.to_ascii_lowercase())
}

/// The key of a job's result file `name` (a path within its results folder).
pub fn result_key(job: &str, name: &str) -> String {
    format!("jobs/{job}/{name}")
}
