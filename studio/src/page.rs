//! The page's files, embedded in the binary: `studio/web/` in the source tree. Plain
//! ES modules, so nothing is built; a change to a file is in the next `cargo build`.

use crate::error::StudioError;
use axum::extract::Path;
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};

/// A file of the page: its path under `/static/` (and under `studio/web/`), as
/// JavaScript.
macro_rules! script {
    ($path:literal) => {
        ($path, "text/javascript; charset=utf-8", include_str!(concat!("../web/", $path)))
    };
}

/// Every file of the page: its path under `/static/`, its type and its bytes. three.js is
/// vendored (see `studio/web/vendor/README.md`).
const FILES: &[(&str, &str, &str)] = &[
    ("studio.css", "text/css; charset=utf-8", include_str!("../web/studio.css")),
    script!("studio.js"),
    script!("api.js"),
    script!("farm.js"),
    script!("viewer.js"),
    script!("material.js"),
    script!("light.js"),
    script!("walk.js"),
    script!("compare.js"),
    script!("notes.js"),
    script!("exposure.js"),
    script!("colour_scale.js"),
    script!("variants.js"),
    script!("painting.js"),
    script!("luminaires.js"),
    script!("grids.js"),
    script!("upload.js"),
    script!("colours.js"),
    script!("panels.js"),
    script!("help.js"),
    script!("layer.js"),
    script!("zoom.js"),
    script!("readout.js"),
    script!("strip.js"),
    script!("sequence.js"),
    script!("vendor/three/three.module.js"),
    script!("vendor/three/three.core.js"),
    script!("vendor/three/addons/controls/OrbitControls.js"),
    script!("vendor/three/addons/loaders/GLTFLoader.js"),
    script!("vendor/three/addons/utils/BufferGeometryUtils.js"),
    script!("vendor/three/addons/utils/SkeletonUtils.js"),
];

const INDEX: &str = include_str!("../web/index.html");

/// Only the page's own files run, and no other site may frame it. `blob:` in `connect-src`:
/// three.js's glTF loader fetches a model's embedded photos from blob URLs it makes itself.
const POLICY: &str = "default-src 'self'; img-src 'self' blob: data:; style-src 'self'; \
                      script-src 'self'; connect-src 'self' blob:; frame-ancestors 'none'; \
                      base-uri 'none'; form-action 'self'";

fn page(kind: &'static str, text: &'static str) -> Response {
    let mut response = text.into_response();
    let h = response.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(kind));
    h.insert(header::CONTENT_SECURITY_POLICY, HeaderValue::from_static(POLICY));
    h.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    h.insert(header::REFERRER_POLICY, HeaderValue::from_static("no-referrer"));
    // The files change with the binary: a page must not mix two releases' modules.
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    response
}

/// `GET /`
pub async fn index() -> Response {
    page("text/html; charset=utf-8", INDEX)
}

/// `GET /static/{file}`
pub async fn file(Path(name): Path<String>) -> Result<Response, StudioError> {
    FILES
        .iter()
        .find(|(path, _, _)| *path == name)
        .map(|(_, kind, text)| page(kind, text))
        .ok_or_else(|| StudioError::NoSuchPage(format!("/static/{}", name.escape_debug())))
}

#[cfg(test)]
mod tests {
    /// Every module of the page's own folder is embedded (a new file left out of [`FILES`]
    /// would load in no browser).
    #[test]
    fn every_file_of_the_page_is_embedded() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("web");
        for entry in std::fs::read_dir(&dir).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            if name.ends_with(".js") || name.ends_with(".css") {
                assert!(
                    super::FILES.iter().any(|(path, _, _)| *path == name),
                    "{name} is not embedded"
                );
            }
        }
    }
}
