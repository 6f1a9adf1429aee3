//! An `http://` or `https://` URL, and the URLs a remote file names relative to its own
//! (RFC 3986 §5.2: a glTF's buffer `model.bin`, a VRML97 `Inline`'s `../walls.wrl`).

use http::Uri;

/// An absolute web URL: `http` or `https`, a host, a path; no credentials, no fragment.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WebUrl {
    uri: Uri,
    secure: bool,
}

/// Why a text is not a URL restauro fetches; each message says what is accepted.
#[derive(Debug, thiserror::Error)]
pub enum UrlError {
    #[error("`{text}` is not an absolute URL (https://host/path)")]
    NotAbsolute { text: String },
    #[error(
        "`{text}`: only https:// and http:// URLs are fetched, not {scheme}://; put the file on \
         a web server, or copy it into the scene's folder"
    )]
    Scheme { text: String, scheme: String },
    /// The URL parser's own wording is part of the message, not a `source`: the message is
    /// written whole into a scene error's problem.
    #[error("`{text}` is not a valid URL ({error}); spaces must be written %20")]
    Malformed { text: String, error: http::uri::InvalidUri },
    #[error("`{text}` names no host")]
    NoHost { text: String },
    #[error(
        "`{text}` carries credentials; restauro fetches public files only (the URL would be \
         written into logs and scene files)"
    )]
    Credentials { text: String },
}

/// Whether a scene's file reference is a URL (rather than a path in the scene's folder).
pub fn is_url(reference: &str) -> bool {
    scheme_of(reference).is_some()
}

/// The scheme of an absolute reference (`https` of `https://…`), lower case.
fn scheme_of(reference: &str) -> Option<String> {
    let (scheme, rest) = reference.split_once(':')?;
    let valid = scheme.len() > 1
        && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
        && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
    // `C:\\walls.obj` is a Windows path, not a URL of scheme `c`.
    (valid && rest.starts_with("//")).then(|| scheme.to_ascii_lowercase())
}

impl WebUrl {
    /// Parses an absolute URL; the message says what is wrong and what is accepted.
    pub fn parse(text: &str) -> Result<WebUrl, UrlError> {
        let text_owned = || text.to_owned();
        let without_fragment = text.split('#').next().unwrap_or(text);
        let scheme = scheme_of(without_fragment)
            .ok_or_else(|| UrlError::NotAbsolute { text: text_owned() })?;
        let secure = match scheme.as_str() {
            "https" => true,
            "http" => false,
            other => {
                return Err(UrlError::Scheme { text: text_owned(), scheme: other.to_owned() });
            }
        };
        let uri: Uri = without_fragment
            .parse()
            .map_err(|error| UrlError::Malformed { text: text_owned(), error })?;
        let authority = uri.authority().ok_or_else(|| UrlError::NoHost { text: text_owned() })?;
        if authority.as_str().contains('@') {
            return Err(UrlError::Credentials { text: text_owned() });
        }
        if authority.host().is_empty() {
            return Err(UrlError::NoHost { text: text_owned() });
        }
        Ok(WebUrl { uri, secure })
    }

    /// The URL `reference` names when it appears inside the file at this URL.
    pub fn join(&self, reference: &str) -> Result<WebUrl, UrlError> {
        let reference = reference.split('#').next().unwrap_or(reference);
        if scheme_of(reference).is_some() {
            return WebUrl::parse(reference);
        }
        let scheme = if self.secure { "https" } else { "http" };
        let authority = self.authority();
        if let Some(rest) = reference.strip_prefix("//") {
            return WebUrl::parse(&format!("{scheme}://{rest}"));
        }
        let (path, query) = match reference.split_once('?') {
            Some((p, q)) => (p, Some(q)),
            None => (reference, None),
        };
        let merged = if path.starts_with('/') {
            path.to_owned()
        } else if path.is_empty() {
            self.uri.path().to_owned()
        } else {
            let base = self.uri.path();
            let folder = &base[..base.rfind('/').map_or(0, |i| i + 1)];
            format!("{folder}{path}")
        };
        let query = query.map(|q| format!("?{q}")).unwrap_or_default();
        WebUrl::parse(&format!("{scheme}://{authority}{}{query}", remove_dot_segments(&merged)))
    }

    pub fn is_secure(&self) -> bool {
        self.secure
    }

    /// The host, without brackets for an IPv6 address.
    pub fn host(&self) -> &str {
        let host = self.uri.host().unwrap_or_default();
        host.strip_prefix('[').and_then(|h| h.strip_suffix(']')).unwrap_or(host)
    }

    pub fn port(&self) -> u16 {
        self.uri.port_u16().unwrap_or(if self.secure { 443 } else { 80 })
    }

    /// `host[:port]`, as the `Host` header wants it.
    pub fn authority(&self) -> &str {
        self.uri.authority().map_or("", |a| a.as_str())
    }

    /// The path and query, as the request line wants them.
    pub fn path_and_query(&self) -> &str {
        self.uri.path_and_query().map_or("/", |p| p.as_str())
    }
}

impl std::fmt::Display for WebUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.uri)
    }
}

/// RFC 3986 §5.2.4: `a/b/../c/./d` is `a/c/d`; a path cannot climb above the root.
fn remove_dot_segments(path: &str) -> String {
    let mut out: Vec<&str> = Vec::new();
    let segments: Vec<&str> = path.split('/').collect();
    for (i, segment) in segments.iter().enumerate() {
        let last = i + 1 == segments.len();
        match *segment {
            "." => {
                if last {
                    out.push("");
                }
            }
            ".." => {
                if out.len() > 1 {
                    out.pop();
                }
                if last {
                    out.push("");
                }
            }
            s => out.push(s),
        }
    }
    let joined = out.join("/");
    if joined.starts_with('/') { joined } else { format!("/{joined}") }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The examples of RFC 3986 §5.4.1 that apply to a file's references.
    #[test]
    fn references_resolve_as_rfc_3986_says() {
        let base = WebUrl::parse("http://a/b/c/d;p?q").unwrap();
        for (reference, expected) in [
            ("g", "http://a/b/c/g"),
            ("./g", "http://a/b/c/g"),
            ("g/", "http://a/b/c/g/"),
            ("/g", "http://a/g"),
            ("//g", "http://g/"),
            ("?y", "http://a/b/c/d;p?y"),
            ("g?y", "http://a/b/c/g?y"),
            ("g#s", "http://a/b/c/g"),
            (".", "http://a/b/c/"),
            ("./", "http://a/b/c/"),
            ("..", "http://a/b/"),
            ("../", "http://a/b/"),
            ("../g", "http://a/b/g"),
            ("../..", "http://a/"),
            ("../../g", "http://a/g"),
            ("../../../g", "http://a/g"),
            ("/./g", "http://a/g"),
            ("g.", "http://a/b/c/g."),
            ("..g", "http://a/b/c/..g"),
            ("./../g", "http://a/b/g"),
            ("g/./h", "http://a/b/c/g/h"),
            ("g/../h", "http://a/b/c/h"),
        ] {
            assert_eq!(base.join(reference).unwrap().to_string(), expected, "{reference}");
        }
    }

    #[test]
    fn only_web_urls_without_credentials_are_accepted() {
        assert!(is_url("https://x.org/a.obj"));
        assert!(!is_url("meshes/a.obj"));
        assert!(!is_url("C:\\meshes\\a.obj"));
        let e = WebUrl::parse("ftp://x.org/a.obj").unwrap_err().to_string();
        assert!(e.contains("only https:// and http://"), "{e}");
        let e = WebUrl::parse("https://me:secret@x.org/a.obj").unwrap_err().to_string();
        assert!(e.contains("credentials"), "{e}");
        let base = WebUrl::parse("https://x.org/scan/model.gltf").unwrap();
        let e = base.join("file:///etc/passwd").unwrap_err().to_string();
        assert!(e.contains("not file://"), "{e}");
        let url = WebUrl::parse("https://[::1]:8443/a%20b.obj").unwrap();
        assert_eq!((url.host(), url.port(), url.path_and_query()), ("::1", 8443, "/a%20b.obj"));
    }
}
