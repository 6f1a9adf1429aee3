//! The coordinator's store: what a restart needs to resume without rendering a finished tile
//! again — every job's record, every finished tile's pixels, the scenes' revisions, the
//! quarantined workers, and the run's identity (the secret that signs leases and the count of
//! runs, see `lease`). Scene assets are files beside it (`asset_store`).
//!
//! Two backends with one behaviour:
//! * [`FileStore`], one redb file in the coordinator's data folder: the default, embedded,
//!   nothing to install;
//! * `PgStore`, a PostgreSQL database (`--store postgres://…`, with the `fleet` feature): a
//!   database a site already runs, backs up and replicates, which outlives the coordinator's
//!   machine.
//!
//! A tile is committed before the worker is told it was accepted, so an acknowledged tile is
//! never lost; a crash between the two makes the worker's result look unacknowledged, and the
//! tile is stored a second time with the same bytes (tiles are deterministic).

mod file;
#[cfg(feature = "fleet")]
mod postgres;

pub use file::FileStore;
#[cfg(feature = "fleet")]
pub use postgres::PgStore;
use std::path::PathBuf;

#[derive(Clone, Debug, thiserror::Error)]
pub enum StoreError {
    #[error("store {}: {message}", path.display())]
    Store { path: PathBuf, message: String },
    #[error("the PostgreSQL store {url}: {message}")]
    Postgres { url: String, message: String },
    /// A write of a coordinator whose lead another has taken (`lead`).
    #[error(
        "the PostgreSQL store {url}: this coordinator's lead (epoch {ours}) has passed to epoch \
         {current}, another coordinator's; its writes are refused"
    )]
    Fenced { url: String, ours: u64, current: u64 },
}

pub type Result<T> = std::result::Result<T, StoreError>;

/// How an attempt to take the lead ended (`lead`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LeadAttempt {
    /// This coordinator leads, under this epoch.
    Led { epoch: u64 },
    /// Another coordinator leads, for this many more milliseconds unless it renews.
    HeldBy { holder: String, for_ms: u64 },
}

/// The coordinator's store, on whichever backend it was opened.
pub enum Store {
    File(FileStore),
    #[cfg(feature = "fleet")]
    Postgres(Box<PgStore>),
}

/// Calls the same method on whichever backend the store is.
macro_rules! each_backend {
    ($(
        $(#[$doc:meta])*
        pub fn $name:ident(&self $(, $arg:ident: $ty:ty)*) -> $ret:ty;
    )*) => {
        impl Store {
            $(
                $(#[$doc])*
                pub fn $name(&self $(, $arg: $ty)*) -> $ret {
                    match self {
                        Store::File(s) => s.$name($($arg),*),
                        #[cfg(feature = "fleet")]
                        Store::Postgres(s) => s.$name($($arg),*),
                    }
                }
            )*
        }
    };
}

each_backend! {
    /// Why the store cannot write now, when it cannot.
    pub fn problem(&self) -> Option<String>;
    /// Starts a run of the coordinator on this store: the lease-signing secret (made on the
    /// first run and kept) and this run's epoch, one more than the last run's.
    pub fn begin_run(&self, new_secret: [u8; 32]) -> Result<([u8; 32], u64)>;
    pub fn put_job(&self, id: &str, record: &[u8]) -> Result<()>;
    pub fn jobs(&self) -> Result<Vec<(String, Vec<u8>)>>;
    /// Keeps revision `number` of scene `scene`.
    pub fn put_revision(&self, scene: &str, number: u32, record: &[u8]) -> Result<()>;
    /// Every scene revision: scene id, number and record, by scene and number.
    pub fn revisions(&self) -> Result<Vec<(String, u32, Vec<u8>)>>;
    /// Several finished tiles in one durable transaction (see `group_commit`).
    pub fn put_tiles(&self, tiles: &[(&str, u32, &[u8])]) -> Result<()>;
    /// The indices of a job's finished tiles, ascending.
    pub fn finished_tiles(&self, job: &str) -> Result<Vec<u32>>;
    pub fn tile(&self, job: &str, tile: u32) -> Result<Option<Vec<u8>>>;
    /// Forgets a job's tiles (its results are written; the record stays), and any disputed
    /// rendering of them.
    pub fn remove_tiles(&self, job: &str) -> Result<()>;
    /// Forgets the tiles `tiles` of a job (a sequence's frame whose files are written).
    pub fn remove_tile_range(&self, job: &str, tiles: std::ops::Range<u32>) -> Result<()>;
    /// Forgets some tiles of a job, and any disputed rendering of them (a quarantined
    /// worker's tiles, to be rendered again).
    pub fn remove_tile_list(&self, job: &str, tiles: &[u32]) -> Result<()>;
    /// Keeps a check's rendering of a tile that differed from the stored one.
    pub fn put_disputed(&self, job: &str, tile: u32, data: &[u8]) -> Result<()>;
    pub fn disputed(&self, job: &str, tile: u32) -> Result<Option<Vec<u8>>>;
    pub fn remove_disputed(&self, job: &str, tile: u32) -> Result<()>;
    /// Records a quarantined worker (`key`: its identity key in hex; `record`: why, as JSON).
    pub fn put_quarantine(&self, key: &str, record: &[u8]) -> Result<()>;
    /// Every quarantined worker: its key and its record.
    pub fn quarantine(&self) -> Result<Vec<(String, Vec<u8>)>>;
}

impl Store {
    /// The store in the file `path` (redb), created when new.
    pub fn open(path: &std::path::Path) -> Result<Store> {
        FileStore::open(path).map(Store::File)
    }

    /// The store in the PostgreSQL database at `url`, its schema brought up to date.
    #[cfg(feature = "fleet")]
    pub fn connect(url: &str) -> Result<Store> {
        PgStore::connect(url).map(|s| Store::Postgres(Box::new(s)))
    }

    /// Without the `fleet` feature, a PostgreSQL store is refused, saying how to get one.
    #[cfg(not(feature = "fleet"))]
    pub fn connect(url: &str) -> Result<Store> {
        Err(StoreError::Postgres {
            url: url.split('@').next_back().unwrap_or_default().to_owned(),
            message: "this coordinator was built without PostgreSQL: build it with \
                      `cargo build --release -p restauro --features fleet` (the container image \
                      has it), or leave out --store to keep the store in --data"
                .into(),
        })
    }

    /// Whether coordinators take turns leading on this store (PostgreSQL); a file store has
    /// one coordinator, which always leads.
    pub fn has_leads(&self) -> bool {
        !matches!(self, Store::File(_))
    }

    /// Takes the lead unless another coordinator holds it (`lead`); from then on this store's
    /// writes are fenced by its epoch.
    pub fn try_lead(&self, holder: &str, ttl: std::time::Duration) -> Result<LeadAttempt> {
        match self {
            Store::File(_) => {
                let _ = (holder, ttl);
                Ok(LeadAttempt::Led { epoch: 0 })
            }
            #[cfg(feature = "fleet")]
            Store::Postgres(s) => s.try_lead(holder, ttl),
        }
    }

    /// Renews the lead of `epoch`: whether it was still this coordinator's.
    pub fn renew_lead(&self, holder: &str, epoch: u64, ttl: std::time::Duration) -> Result<bool> {
        match self {
            Store::File(_) => {
                let _ = (holder, epoch, ttl);
                Ok(true)
            }
            #[cfg(feature = "fleet")]
            Store::Postgres(s) => s.renew_lead(holder, epoch, ttl),
        }
    }

    /// Gives the lead of `epoch` up.
    pub fn release_lead(&self, holder: &str, epoch: u64) -> Result<()> {
        match self {
            Store::File(_) => {
                let _ = (holder, epoch);
                Ok(())
            }
            #[cfg(feature = "fleet")]
            Store::Postgres(s) => s.release_lead(holder, epoch),
        }
    }

    /// Takes the assets an earlier release kept in the file store, one at a time, for `keep`
    /// to write elsewhere; each is removed from the store once `keep` succeeded. How many
    /// moved. (No release kept assets in PostgreSQL.)
    pub fn drain_legacy_assets(
        &self,
        keep: impl FnMut(&str, &[u8]) -> std::io::Result<()>,
    ) -> Result<usize> {
        match self {
            Store::File(s) => s.drain_legacy_assets(keep),
            #[cfg(feature = "fleet")]
            Store::Postgres(_) => Ok(0),
        }
    }
}
