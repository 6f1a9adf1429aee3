//! A lease as it leaves the coordinator and comes back: the scheduler's lease, the tile's
//! rectangle, the run (epoch) that granted it, and a ticket — a keyed BLAKE3 hash of all of it
//! and of the holder's identity (a secret the worker registered with, and keeps for its life)
//! under a secret that never leaves the coordinator's store. A worker can therefore only report,
//! fail or hand back tiles it was given, whatever it puts in a message, and nobody else can:
//! the ticket only verifies with the identity of the session that presents it. A coordinator
//! restarted on the same store still recognises the leases its previous run granted (their
//! epoch is older and their ticket verifies), so their results are not rendered again — when
//! the worker that was given them, registered again with its identity, delivers them.

use crate::ids::{JobId, WorkerId};
use restauro_proto as pb;
use restauro_proto::convert::WireError;
use restauro_scene::plan::Rect;

/// Signs and checks the leases of one run of the coordinator.
#[derive(Clone)]
pub struct LeaseSigner {
    secret: [u8; 32],
    epoch: u64,
}

/// What a lease names, as signed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LeaseClaim {
    pub job: JobId,
    pub tile: u32,
    pub attempt: u32,
    pub epoch: u64,
    pub holder: WorkerId,
    pub ticket: [u8; 32],
}

impl LeaseSigner {
    pub fn new(secret: [u8; 32], epoch: u64) -> Self {
        Self { secret, epoch }
    }

    /// This run's epoch.
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    fn ticket(&self, c: &Fields<'_>) -> [u8; 32] {
        let Fields { job, tile, attempt, epoch, holder, identity } = *c;
        let mut h = blake3::Hasher::new_keyed(&self.secret);
        // The job id is length-prefixed, so no two leases hash the same bytes.
        h.update(&(job.len() as u64).to_le_bytes());
        h.update(job.as_bytes());
        h.update(&tile.to_le_bytes());
        h.update(&attempt.to_le_bytes());
        h.update(&epoch.to_le_bytes());
        h.update(&holder.0.to_le_bytes());
        h.update(identity);
        *h.finalize().as_bytes()
    }

    /// A lease of this run to the worker of `identity` (its registration's digest), for the
    /// wire.
    pub fn grant(
        &self,
        lease: &crate::scheduler::Lease,
        rect: Rect,
        frame: u32,
        identity: &[u8; 32],
    ) -> pb::Lease {
        let ticket = self.ticket(&Fields {
            job: &lease.job,
            tile: lease.tile,
            attempt: lease.attempt,
            epoch: self.epoch,
            holder: lease.worker,
            identity,
        });
        pb::Lease {
            job_id: lease.job.to_string(),
            tile: lease.tile,
            attempt: lease.attempt,
            rect: Some(rect.into()),
            epoch: self.epoch,
            holder: lease.worker.0,
            ticket: ticket.to_vec(),
            frame,
        }
    }

    /// Whether the claim's ticket is the one this store's secret gives its fields and the
    /// identity of the worker presenting it (compared in constant time).
    pub fn verify(&self, c: &LeaseClaim, identity: &[u8; 32]) -> bool {
        let expected = self.ticket(&Fields {
            job: &c.job,
            tile: c.tile,
            attempt: c.attempt,
            epoch: c.epoch,
            holder: c.holder,
            identity,
        });
        blake3::Hash::from(expected) == blake3::Hash::from(c.ticket)
    }

    /// The scheduler's lease a claim of this run names.
    pub fn lease(&self, c: &LeaseClaim) -> crate::scheduler::Lease {
        crate::scheduler::Lease {
            job: c.job.clone(),
            tile: c.tile,
            attempt: c.attempt,
            worker: c.holder,
        }
    }
}

/// What a ticket signs.
#[derive(Clone, Copy)]
struct Fields<'a> {
    job: &'a str,
    tile: u32,
    attempt: u32,
    epoch: u64,
    holder: WorkerId,
    identity: &'a [u8; 32],
}

/// The digest a worker's identity is kept and signed as.
pub fn identity_digest(identity: &[u8; 32]) -> [u8; 32] {
    *blake3::hash(identity).as_bytes()
}

impl TryFrom<&pb::Lease> for LeaseClaim {
    type Error = WireError;
    fn try_from(l: &pb::Lease) -> Result<Self, WireError> {
        let ticket = <[u8; 32]>::try_from(l.ticket.as_slice())
            .map_err(|_| WireError::new("lease.ticket", "not the 32 bytes the lease came with"))?;
        Ok(LeaseClaim {
            job: JobId::from(l.job_id.as_str()),
            tile: l.tile,
            attempt: l.attempt,
            epoch: l.epoch,
            holder: WorkerId(l.holder),
            ticket,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheduler::Lease;

    #[test]
    fn only_a_granted_lease_verifies_and_the_next_run_still_knows_it() {
        let run1 = LeaseSigner::new([3; 32], 1);
        let lease = Lease { job: "j".into(), tile: 4, attempt: 2, worker: WorkerId(9) };
        let (holder, other) = (identity_digest(&[7; 32]), identity_digest(&[8; 32]));
        let wire = run1.grant(&lease, Rect { x: 0, y: 0, width: 8, height: 8 }, 0, &holder);
        let claim = LeaseClaim::try_from(&wire).unwrap();
        assert!(run1.verify(&claim, &holder));
        assert_eq!(run1.lease(&claim), lease);
        // Another worker's identity does not verify it, in this run or the next.
        assert!(!run1.verify(&claim, &other));
        assert!(!LeaseSigner::new([3; 32], 2).verify(&claim, &other));
        // The next run on the same store (same secret, next epoch) verifies it for its holder.
        assert!(LeaseSigner::new([3; 32], 2).verify(&claim, &holder));
        // Another store's secret does not, nor any change of a field.
        assert!(!LeaseSigner::new([4; 32], 1).verify(&claim, &holder));
        for forged in [
            LeaseClaim { tile: 5, ..claim.clone() },
            LeaseClaim { attempt: 3, ..claim.clone() },
            LeaseClaim { holder: WorkerId(8), ..claim.clone() },
            LeaseClaim { epoch: 2, ..claim.clone() },
            LeaseClaim { job: "k".into(), ..claim.clone() },
        ] {
            assert!(!run1.verify(&forged, &holder), "{forged:?}");
        }
        let short = pb::Lease { ticket: vec![0; 31], ..wire };
        assert_eq!(LeaseClaim::try_from(&short).unwrap_err().field, "lease.ticket");
    }
}
