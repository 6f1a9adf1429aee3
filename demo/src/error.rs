//! What can go wrong while the demo writes its scenes, reads its renders back and writes its
//! sheets and report: one error for the crate, each message naming the file it concerns. The
//! underlying error (the disk's, the image reader's) is the source, so a caller that prints the
//! chain (`restauro` does) shows "cannot write …: <why>".

use restauro_image::ImageError;
use std::io;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// The Aosta scene's folder could not be written ([`crate::scene_files::write_aosta`] names
    /// the file in its message).
    #[error(transparent)]
    AostaScene(io::Error),
    /// The sun study's frames could not be made from the summer scene.
    #[error("the sun study of {}", path.display())]
    SunStudy {
        path: PathBuf,
        #[source]
        source: Box<restauro_scene::SceneError>,
    },
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("cannot create {}", path.display())]
    CreateFolder {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A render's OpenEXR file, fetched from the cluster, could not be read back.
    #[error("reading {}", path.display())]
    ReadImage {
        path: PathBuf,
        #[source]
        source: ImageError,
    },
    /// A contact sheet's PNG could not be written.
    #[error("writing {}", path.display())]
    WriteImage {
        path: PathBuf,
        #[source]
        source: ImageError,
    },
    /// A render the analysis compares is not among those finished (the facade's hypothesis or
    /// the stone experiment's illuminant named).
    #[error("the {0} render is missing")]
    MissingRender(&'static str),
    #[error("the photo block's render is missing")]
    MissingBlock,
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

pub type Result<T> = std::result::Result<T, DemoError>;

#[cfg(test)]
mod tests {
    use super::DemoError;
    use std::error::Error as _;

    /// The caller prints the chain: the file first, then why.
    #[test]
    fn a_write_names_the_file_and_keeps_why_as_its_source() {
        let e = DemoError::Write {
            path: "out/report.md".into(),
            source: std::io::Error::other("disk full"),
        };
        assert_eq!(e.to_string(), "cannot write out/report.md");
        assert_eq!(e.source().map(ToString::to_string).as_deref(), Some("disk full"));
        assert_eq!(DemoError::MissingRender("D65").to_string(), "the D65 render is missing");
    }
}
