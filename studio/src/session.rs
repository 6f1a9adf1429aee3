//! Who may use the studio: the client token, sent as `authorization: Bearer <token>` by a
//! program, or exchanged once (`POST /api/session`) for a session cookie by the page. The worker
//! token opens nothing here.
//!
//! The cookie is `<issued unix seconds>.<keyed BLAKE3 of them>`, under a key derived from the
//! client token ([`Tokens::session_key`]): nothing is kept on the server, a cookie survives a
//! coordinator restart, and changing the token ends every session. It is `HttpOnly` (no script
//! reads it) and `SameSite=Strict` (no other site's page sends it); a change (any method but GET)
//! authorised by the cookie must also come with an `Origin` that is the studio's own, against
//! cross-site request forgery (OWASP's "verifying origin with standard headers").

use crate::error::{Result, StudioError};
use axum::http::{HeaderMap, Method, header};
use restauro_farm::auth::{Role, Tokens};
use std::time::{SystemTime, UNIX_EPOCH};

/// The cookie's name.
pub const COOKIE: &str = "restauro_session";
/// How long a session lasts, in seconds: a working day and a half.
pub const SESSION_S: u64 = 36 * 3600;

/// Checks requests and issues cookies.
#[derive(Clone)]
pub struct Gate {
    tokens: Tokens,
    key: [u8; 32],
    /// Whether the studio is served over TLS (then the cookie is `Secure`).
    pub tls: bool,
}

fn now_s() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs())
}

impl Gate {
    pub fn new(tokens: Tokens, tls: bool) -> Self {
        let key = tokens.session_key();
        Self { tokens, key, tls }
    }

    /// Exchanges the client token for a `Set-Cookie` value; another token is refused as the
    /// gRPC door refuses it.
    pub fn sign_in(&self, token: &str) -> Result<String> {
        self.tokens.authorize_token(Role::Client, token)?;
        Ok(self.cookie(now_s()))
    }

    /// The `Set-Cookie` value of a session issued at `issued_s`.
    fn cookie(&self, issued_s: u64) -> String {
        let value = format!("{issued_s}.{}", self.mac(issued_s));
        let secure = if self.tls { "; Secure" } else { "" };
        format!("{COOKIE}={value}; Path=/; HttpOnly; SameSite=Strict; Max-Age={SESSION_S}{secure}")
    }

    /// The `Set-Cookie` value that ends a session.
    pub fn sign_out(&self) -> String {
        format!("{COOKIE}=; Path=/; HttpOnly; SameSite=Strict; Max-Age=0")
    }

    fn mac(&self, issued_s: u64) -> blake3::Hash {
        blake3::keyed_hash(&self.key, format!("session:{issued_s}").as_bytes())
    }

    /// Whether the request may go on: a valid client bearer token, or a live session cookie
    /// (and, for a change, the studio's own `Origin`).
    pub fn check(&self, method: &Method, headers: &HeaderMap) -> Result<()> {
        if let Some(token) = bearer(headers) {
            return Ok(self.tokens.authorize_token(Role::Client, token)?);
        }
        if !self.valid_cookie(headers) {
            return Err(StudioError::NotSignedIn);
        }
        if method != Method::GET && method != Method::HEAD {
            same_origin(headers)?;
        }
        Ok(())
    }

    fn valid_cookie(&self, headers: &HeaderMap) -> bool {
        let Some(value) = cookie(headers, COOKIE) else { return false };
        let Some((issued, mac)) = value.split_once('.') else { return false };
        let (Ok(issued_s), Ok(mac)) = (issued.parse::<u64>(), blake3::Hash::from_hex(mac)) else {
            return false;
        };
        let now = now_s();
        // blake3::Hash compares in constant time.
        mac == self.mac(issued_s) && issued_s <= now + 60 && now < issued_s + SESSION_S
    }
}

fn bearer(headers: &HeaderMap) -> Option<&str> {
    headers.get(header::AUTHORIZATION)?.to_str().ok()?.strip_prefix("Bearer ")
}

/// The value of cookie `name`, if the request carries it.
fn cookie<'a>(headers: &'a HeaderMap, name: &str) -> Option<&'a str> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|pair| pair.trim().split_once('='))
        .find(|(k, _)| *k == name)
        .map(|(_, v)| v)
}

/// A change must come from a page of this studio: its `Origin` names the host the request was
/// sent to. A request without `Origin` is refused too (every browser sends it on POST).
pub fn same_origin(headers: &HeaderMap) -> Result<()> {
    let host = headers.get(header::HOST).and_then(|v| v.to_str().ok()).unwrap_or("");
    let origin = headers.get(header::ORIGIN).and_then(|v| v.to_str().ok()).unwrap_or("none");
    let own = origin
        .strip_prefix("http://")
        .or_else(|| origin.strip_prefix("https://"))
        .is_some_and(|rest| !host.is_empty() && rest == host);
    if own {
        Ok(())
    } else {
        Err(StudioError::CrossOrigin { origin: origin.to_owned(), expected: host.to_owned() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;
    use restauro_farm::error::FarmError;

    fn gate() -> Gate {
        Gate::new(Tokens::new("client-secret", "worker-secret"), false)
    }

    fn headers(pairs: &[(header::HeaderName, &str)]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for (k, v) in pairs {
            h.append(k.clone(), HeaderValue::from_str(v).unwrap());
        }
        h
    }

    fn cookie_value(set_cookie: &str) -> String {
        set_cookie.split(';').next().unwrap().to_owned()
    }

    #[test]
    fn the_client_token_signs_in_and_the_cookie_opens_the_studio() {
        let g = gate();
        let set = g.sign_in("client-secret").unwrap();
        assert!(set.contains("HttpOnly") && set.contains("SameSite=Strict"), "{set}");
        let h = headers(&[(header::COOKIE, &format!("theme=dark; {}", cookie_value(&set)))]);
        assert!(g.check(&Method::GET, &h).is_ok());
        // A tampered cookie, an old one and one from the future are not sessions.
        let issued: u64 =
            cookie_value(&set)[COOKIE.len() + 1..].split('.').next().unwrap().parse().unwrap();
        for forged in [
            format!("{COOKIE}={}.{}", issued + 1, g.mac(issued)),
            cookie_value(&g.cookie(issued - SESSION_S - 1)),
            cookie_value(&g.cookie(issued + 3600)),
            format!("{COOKIE}=garbage"),
        ] {
            let h = headers(&[(header::COOKIE, &forged)]);
            assert!(matches!(g.check(&Method::GET, &h), Err(StudioError::NotSignedIn)), "{forged}");
        }
        // Another token's key makes other cookies.
        let other = Gate::new(Tokens::new("another-client", "worker-secret"), false);
        let h = headers(&[(header::COOKIE, &cookie_value(&set))]);
        assert!(other.check(&Method::GET, &h).is_err());
    }

    #[test]
    fn the_worker_token_and_a_guess_are_refused() {
        let g = gate();
        assert!(matches!(
            g.sign_in("worker-secret"),
            Err(StudioError::Farm(FarmError::WrongRole { .. }))
        ));
        assert!(matches!(g.sign_in("guess"), Err(StudioError::Farm(FarmError::BadToken { .. }))));
        let h = headers(&[(header::AUTHORIZATION, "Bearer worker-secret")]);
        assert_eq!(g.check(&Method::GET, &h).unwrap_err().http_status(), 403);
        let h = headers(&[(header::AUTHORIZATION, "Bearer client-secret")]);
        assert!(g.check(&Method::POST, &h).is_ok(), "a program's bearer token needs no Origin");
        assert_eq!(g.check(&Method::GET, &HeaderMap::new()).unwrap_err().http_status(), 401);
    }

    #[test]
    fn a_change_by_cookie_must_come_from_the_studio_itself() {
        let g = gate();
        let c = cookie_value(&g.sign_in("client-secret").unwrap());
        let host = (header::HOST, "127.0.0.1:8080");
        let ok = headers(&[
            (header::COOKIE, &c),
            host.clone(),
            (header::ORIGIN, "http://127.0.0.1:8080"),
        ]);
        assert!(g.check(&Method::POST, &ok).is_ok());
        for origin in ["http://evil.example", "http://127.0.0.1:8081", "null"] {
            let h = headers(&[(header::COOKIE, &c), host.clone(), (header::ORIGIN, origin)]);
            let e = g.check(&Method::POST, &h).unwrap_err();
            assert_eq!(e.http_status(), 403, "{origin}");
            assert!(e.to_string().contains(origin), "{e}");
        }
        let h = headers(&[(header::COOKIE, &c), host]);
        assert!(g.check(&Method::DELETE, &h).is_err(), "no Origin on a change");
    }
}
