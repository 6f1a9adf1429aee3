//! Bearer tokens and protocol versions, checked before any request reaches a service.
//!
//! Clients and workers hold different tokens: a client token opens the `Render` service only, a
//! worker token the `Work` service only. A missing or unknown token is UNAUTHENTICATED; the other
//! role's token is PERMISSION_DENIED (authenticated, but forbidden). Tokens are compared in
//! constant time (through their BLAKE3 hashes), so timing tells nothing of them.

use crate::error::FarmError;
use restauro_proto::{PROTOCOL_HEADER, PROTOCOL_VERSION};
use tonic::{Request, Status};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Client,
    Worker,
}

impl Role {
    fn name(self) -> &'static str {
        match self {
            Role::Client => "client",
            Role::Worker => "worker",
        }
    }
}

/// The two tokens, as hashes.
#[derive(Clone)]
pub struct Tokens {
    client: blake3::Hash,
    worker: blake3::Hash,
}

impl Tokens {
    pub fn new(client: &str, worker: &str) -> Self {
        Self { client: blake3::hash(client.as_bytes()), worker: blake3::hash(worker.as_bytes()) }
    }

    /// The interceptor of the service that `role` may call.
    pub fn interceptor(
        &self,
        role: Role,
    ) -> impl FnMut(Request<()>) -> Result<Request<()>, Status> + Clone + use<> {
        let tokens = self.clone();
        move |request: Request<()>| {
            tokens.check(role, &request)?;
            Ok(request)
        }
    }

    fn check(&self, role: Role, request: &Request<()>) -> Result<(), Status> {
        let metadata = request.metadata();
        let version = metadata.get(PROTOCOL_HEADER).and_then(|v| v.to_str().ok());
        let bearer = metadata
            .get("authorization")
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "));
        Ok(self.authorize(role, version, bearer)?)
    }

    /// Checks a caller's protocol version and bearer token for `role`'s door (the same check
    /// for every transport).
    pub fn authorize(
        &self,
        role: Role,
        version: Option<&str>,
        bearer: Option<&str>,
    ) -> Result<(), FarmError> {
        let version = version.and_then(|v| v.parse::<u32>().ok());
        if version != Some(PROTOCOL_VERSION) {
            let theirs = version.map_or("none".to_owned(), |v| v.to_string());
            return Err(FarmError::ProtocolVersion {
                theirs,
                ours: PROTOCOL_VERSION,
                role: role.name(),
            });
        }
        let token = bearer.ok_or(FarmError::NoToken { role: role.name() })?;
        self.authorize_token(role, token)
    }

    /// Checks a bearer token for `role`'s door (the studio's, which has no protocol header).
    pub fn authorize_token(&self, role: Role, token: &str) -> Result<(), FarmError> {
        let hash = blake3::hash(token.as_bytes());
        let (mine, other) = match role {
            Role::Client => (self.client, self.worker),
            Role::Worker => (self.worker, self.client),
        };
        // blake3::Hash compares in constant time.
        if hash == mine {
            Ok(())
        } else if hash == other {
            let other_role = match role {
                Role::Client => Role::Worker,
                Role::Worker => Role::Client,
            };
            Err(FarmError::WrongRole { held: other_role.name(), needed: role.name() })
        } else {
            Err(FarmError::BadToken { role: role.name() })
        }
    }

    /// The key of the studio's session cookies: derived from the client token, so that a
    /// cookie outlives a coordinator restart and dies with the token.
    pub fn session_key(&self) -> [u8; 32] {
        blake3::derive_key("restauro studio session cookie v1", self.client.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(token: Option<&str>, version: Option<&str>) -> Request<()> {
        let mut r = Request::new(());
        if let Some(t) = token {
            r.metadata_mut().insert("authorization", format!("Bearer {t}").parse().unwrap());
        }
        if let Some(v) = version {
            r.metadata_mut().insert(PROTOCOL_HEADER, v.parse().unwrap());
        }
        r
    }

    #[test]
    fn each_role_opens_only_its_own_service() {
        let t = Tokens::new("client-secret", "worker-secret");
        let v = PROTOCOL_VERSION.to_string();
        let v = Some(v.as_str());
        assert!(t.check(Role::Client, &request(Some("client-secret"), v)).is_ok());
        assert!(t.check(Role::Worker, &request(Some("worker-secret"), v)).is_ok());
        let code = |role, token| t.check(role, &request(token, v)).unwrap_err().code();
        assert_eq!(code(Role::Client, Some("worker-secret")), tonic::Code::PermissionDenied);
        assert_eq!(code(Role::Worker, Some("client-secret")), tonic::Code::PermissionDenied);
        assert_eq!(code(Role::Client, None), tonic::Code::Unauthenticated);
        assert_eq!(code(Role::Worker, Some("guess")), tonic::Code::Unauthenticated);
        let old = t.check(Role::Worker, &request(Some("worker-secret"), Some("0"))).unwrap_err();
        assert_eq!(old.code(), tonic::Code::FailedPrecondition);
        assert!(old.message().contains("protocol version 0"), "{}", old.message());
    }
}
