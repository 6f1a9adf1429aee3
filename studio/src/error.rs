//! The studio's one error type, [`StudioError`], and its one mapping to an HTTP answer: a
//! status and the message as `{"error": "…"}`, which the page shows as it is. A refusal of the
//! farm's passes through unchanged ([`StudioError::Farm`]); its HTTP status is the counterpart
//! of the farm's gRPC code (as in Google's HTTP mapping of gRPC codes), so both doors refuse
//! the same thing the same way. The gRPC mapping itself is the farm's (`FarmError::code`).

use axum::http::StatusCode;
use restauro_farm::error::FarmError;
use restauro_scene::SceneError;

#[derive(Debug, thiserror::Error)]
pub enum StudioError {
    /// What the farm refused or failed at, as the gRPC door says it too.
    #[error(transparent)]
    Farm(#[from] FarmError),

    /// A studio request without a valid client token or session.
    #[error(
        "not signed in: give the client token (the page asks for it; a program sends \
         `authorization: Bearer <token>`)"
    )]
    NotSignedIn,

    /// A change sent to the studio from another site's page (cross-site request forgery).
    #[error(
        "refused: this change comes from a page at {origin}, not from the studio at {expected}; \
         open the studio's own address"
    )]
    CrossOrigin { origin: String, expected: String },

    /// A studio request whose body or path does not say what it must.
    #[error("invalid request: {0}")]
    Request(String),

    /// A sequence the scene cannot make (a step of zero, an unknown view, the sun never up,
    /// more frames than the limit), in the words of its expansion.
    #[error("{0}")]
    Sequence(SceneError),

    #[error("no such page `{0}` in the studio")]
    NoSuchPage(String),

    #[error("no image {0} is kept by this coordinator; attach it to the note again")]
    NoSuchImage(String),

    /// The studio's own fault (a picture that does not encode, a task that panicked).
    #[error("internal error: {0}")]
    Internal(String),

    // What stops the studio from serving: the coordinator does not start. Each says what it was
    // doing, and keeps the failure beneath as its source, as the log shows it.
    #[error("reading the TLS certificate chain")]
    TlsChain(#[source] tokio_rustls::rustls::pki_types::pem::Error),

    #[error("reading the TLS private key")]
    TlsKey(#[source] tokio_rustls::rustls::pki_types::pem::Error),

    #[error("the TLS protocol versions")]
    TlsVersions(#[source] tokio_rustls::rustls::Error),

    #[error("the TLS certificate and key do not go together")]
    TlsPair(#[source] tokio_rustls::rustls::Error),

    #[error("listening for the studio on {addr}")]
    Listen { addr: std::net::SocketAddr, source: std::io::Error },

    /// The bound listener's own address (an I/O error of the operating system's).
    #[error(transparent)]
    LocalAddr(std::io::Error),
}

pub type Result<T, E = StudioError> = std::result::Result<T, E>;

/// A scene that does not parse or load: the farm's refusal, as a submission's would be.
impl From<SceneError> for StudioError {
    fn from(e: SceneError) -> Self {
        StudioError::Farm(e.into())
    }
}

/// A request field the farm's types cannot hold (a job id that is not one).
impl From<restauro_proto::convert::WireError> for StudioError {
    fn from(e: restauro_proto::convert::WireError) -> Self {
        StudioError::Farm(e.into())
    }
}

/// A blocking task that panicked or was cancelled: the studio's own fault, said as such.
impl From<tokio::task::JoinError> for StudioError {
    fn from(e: tokio::task::JoinError) -> Self {
        StudioError::Internal(e.to_string())
    }
}

impl StudioError {
    /// The HTTP status of the studio's answer.
    pub fn http_status(&self) -> StatusCode {
        use StudioError as E;
        match self {
            E::Farm(e) => status_of(e.code()),
            E::NotSignedIn => StatusCode::UNAUTHORIZED,
            E::CrossOrigin { .. } => StatusCode::FORBIDDEN,
            E::Request(_) | E::Sequence(_) => StatusCode::BAD_REQUEST,
            E::NoSuchPage(_) | E::NoSuchImage(_) => StatusCode::NOT_FOUND,
            E::Internal(_)
            | E::TlsChain(_)
            | E::TlsKey(_)
            | E::TlsVersions(_)
            | E::TlsPair(_)
            | E::Listen { .. }
            | E::LocalAddr(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }
}

/// The HTTP counterpart of a gRPC code.
fn status_of(code: tonic::Code) -> StatusCode {
    use tonic::Code;
    match code {
        // A job that is not done yet has no result to give: that is a conflict of state.
        Code::FailedPrecondition => StatusCode::CONFLICT,
        Code::Aborted => StatusCode::CONFLICT,
        Code::Unauthenticated => StatusCode::UNAUTHORIZED,
        Code::PermissionDenied => StatusCode::FORBIDDEN,
        Code::InvalidArgument => StatusCode::BAD_REQUEST,
        Code::NotFound => StatusCode::NOT_FOUND,
        Code::ResourceExhausted => StatusCode::TOO_MANY_REQUESTS,
        Code::Unavailable => StatusCode::SERVICE_UNAVAILABLE,
        Code::DeadlineExceeded => StatusCode::REQUEST_TIMEOUT,
        _ => StatusCode::INTERNAL_SERVER_ERROR,
    }
}

/// The one conversion of the studio's errors to an HTTP answer: the status of
/// [`StudioError::http_status`] and the message as `{"error": "…"}`.
impl axum::response::IntoResponse for StudioError {
    fn into_response(self) -> axum::response::Response {
        #[derive(serde::Serialize)]
        struct Body {
            error: String,
        }
        (self.http_status(), axum::Json(Body { error: self.to_string() })).into_response()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refusal_of_the_farm_keeps_its_words_and_takes_the_status_of_its_code() {
        let e = StudioError::from(FarmError::TooManyJobs { open: 3 });
        assert_eq!(e.http_status(), StatusCode::TOO_MANY_REQUESTS);
        assert!(e.to_string().contains("--max-jobs"), "{e}");
        let e = StudioError::from(FarmError::NoSuchScene("abc".into()));
        assert_eq!(e.http_status(), StatusCode::NOT_FOUND);
        assert_eq!(e.to_string(), FarmError::NoSuchScene("abc".into()).to_string());
        assert_eq!(StudioError::NotSignedIn.http_status(), StatusCode::UNAUTHORIZED);
    }
}
