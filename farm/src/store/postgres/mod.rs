//! The store in PostgreSQL (`--store postgres://USER[:PASSWORD]@HOST[:PORT]/DATABASE`): the same
//! tables as the file store, in a database a site already runs, backs up and replicates.
//!
//! * **TLS** as libpq's `sslmode` and `sslrootcert` say (`tls`): encrypted whenever the server
//!   offers it, the certificate checked with `sslmode=verify-full`.
//!
//! * **Schema.** Versioned migrations (`MIGRATIONS`), applied in one transaction under an
//!   exclusive lock of `restauro_schema`, so two coordinators starting together apply each once;
//!   a database of a newer schema than this release knows is refused, naming both versions.
//! * **Group commit** is kept: a batch of finished tiles is one `INSERT … SELECT FROM unnest`
//!   statement, one round trip and one durable commit, whatever its size.
//! * **Durability.** Each call is one transaction, committed before the call returns; a tile is
//!   acknowledged to its worker only after that. Acknowledged commits survive the database's own
//!   failover only if its standby is synchronous (the operators' guide says how).
//! * **A lost connection** (the server restarted, the session terminated) is the store's
//!   problem until a call succeeds on a new connection, opened at the next call; the
//!   coordinator goes on meanwhile, as with a full disk.
//!
//! The farm calls the store from plain threads and from async tasks alike, so every call runs
//! on a thread of its own, on this store's one-thread runtime (`blocking`).

mod tls;

use super::{LeadAttempt, Result, StoreError};
use crate::problem::Problems;
use tokio_postgres::{Client, Config, Transaction};

/// The schema, one migration per entry; a database records the versions it has.
const MIGRATIONS: &[&str] = &[
    // 1: the file store's tables.
    "CREATE TABLE restauro_meta (key text PRIMARY KEY, value bytea NOT NULL);
     CREATE TABLE restauro_jobs (id text PRIMARY KEY, record bytea NOT NULL);
     CREATE TABLE restauro_tiles (job text NOT NULL, tile bigint NOT NULL, data bytea NOT NULL,
                                  PRIMARY KEY (job, tile));
     CREATE TABLE restauro_scene_revisions (scene text NOT NULL, number bigint NOT NULL,
                                            record bytea NOT NULL, PRIMARY KEY (scene, number));
     CREATE TABLE restauro_disputed (job text NOT NULL, tile bigint NOT NULL, data bytea NOT NULL,
                                     PRIMARY KEY (job, tile));
     CREATE TABLE restauro_quarantine (key text PRIMARY KEY, record bytea NOT NULL);",
    // 2: the lead among several coordinators (`lead`): one row, its epoch the fencing token.
    "CREATE TABLE restauro_leader (id smallint PRIMARY KEY CHECK (id = 1), holder text NOT NULL,
                                   epoch bigint NOT NULL, expires_at timestamptz NOT NULL);
     INSERT INTO restauro_leader (id, holder, epoch, expires_at) VALUES (1, '', 0, '-infinity');",
];

type PgResult<T> = std::result::Result<T, tokio_postgres::Error>;

pub struct PgStore {
    /// The URL without its password, for messages.
    shown: String,
    config: Config,
    /// TLS as the URL's `sslmode` says (`tls`).
    tls: tokio_postgres_rustls::MakeRustlsConnect,
    runtime: crate::blocking::Blocking,
    /// `None` before the first call and after a connection was lost.
    client: tokio::sync::Mutex<Option<Client>>,
    /// The lead's own connection: renewing it never waits behind a slow write.
    lead_client: tokio::sync::Mutex<Option<Client>>,
    /// The epoch of the lead this store writes under, once it holds one (0 before): every
    /// write checks it against the lead row's, so a coordinator that lost the lead writes
    /// nothing.
    fence: std::sync::atomic::AtomicU64,
    problem: Problems,
}

/// `url` without the password it may hold.
fn without_password(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else { return url.to_owned() };
    match rest.split_once('@') {
        Some((user, host)) => {
            let user = user.split(':').next().unwrap_or_default();
            format!("{scheme}://{user}@{host}")
        }
        None => url.to_owned(),
    }
}

impl PgStore {
    /// Connects to the database at `url` and brings its schema up to date.
    pub fn connect(url: &str) -> Result<PgStore> {
        let shown = without_password(url);
        let refused = |message: String| StoreError::Postgres { url: shown.clone(), message };
        let (url, tls) = tls::settings(url).map_err(refused)?;
        let mut config: Config = url.parse().map_err(|e| {
            refused(format!(
                "{e}; give postgres://USER[:PASSWORD]@HOST[:PORT]/DATABASE (or key=value pairs)"
            ))
        })?;
        // A transaction left open by a coordinator cut off from the database would hold the
        // lead row's lock, and keep a standby from taking over, until TCP gave up (hours):
        // the server ends any transaction idle this long. The store's transactions are never
        // idle longer than a round trip.
        let options = config.get_options().unwrap_or_default().to_owned();
        config.options(format!("{options} -c idle_in_transaction_session_timeout=2000").trim());
        let runtime = crate::blocking::Blocking::start("store-postgres")
            .map_err(|e| refused(format!("starting its runtime: {e}")))?;
        let store = PgStore {
            shown: shown.clone(),
            config,
            tls,
            runtime,
            client: tokio::sync::Mutex::new(None),
            lead_client: tokio::sync::Mutex::new(None),
            fence: std::sync::atomic::AtomicU64::new(0),
            problem: Problems::of("store"),
        };
        store.call(async |c| migrate(c).await).map_err(|e| match e {
            StoreError::Postgres { message, .. } => match tls::fix(&message) {
                Some(fix) => refused(format!("{message}; {fix}")),
                None => refused(message),
            },
            other => other,
        })?;
        Ok(store)
    }

    /// Runs `f` with the connection (opened first when there is none), on a thread of its own.
    /// A call that finds its connection closed under it (the session terminated, the server
    /// restarted) connects again and runs once more: every call is idempotent (an upsert, a
    /// delete, a read; a run begun twice only skips an epoch). A failure that leaves the
    /// connection closed drops it: the next call connects again.
    fn call<T: Send>(
        &self,
        f: impl AsyncFn(&mut Client) -> PgResult<T> + Send + Sync,
    ) -> Result<T> {
        let outcome = self.on(&self.client, f);
        match outcome {
            Ok(value) => {
                self.problem.succeeded();
                Ok(value)
            }
            Err(e) => {
                let message = error_chain(&e);
                self.problem.failed(&self.shown, &message);
                Err(self.error(message))
            }
        }
    }

    fn error(&self, message: String) -> StoreError {
        StoreError::Postgres { url: self.shown.clone(), message }
    }

    /// Runs `f` on the connection in `slot` (see [`PgStore::call`]).
    fn on<T: Send>(
        &self,
        slot: &tokio::sync::Mutex<Option<Client>>,
        f: impl AsyncFn(&mut Client) -> PgResult<T> + Send + Sync,
    ) -> PgResult<T> {
        self.runtime.run(|| async {
            let mut slot = slot.lock().await;
            let mut again = true;
            loop {
                if slot.as_ref().is_none_or(Client::is_closed) {
                    let (client, connection) = self.config.connect(self.tls.clone()).await?;
                    tokio::spawn(async move {
                        if let Err(e) = connection.await {
                            tracing::warn!("the PostgreSQL store's connection ended: {e}");
                        }
                    });
                    *slot = Some(client);
                }
                let client = slot.as_mut().expect("connected above");
                let outcome = f(client).await;
                if client.is_closed() {
                    *slot = None;
                    if outcome.is_err() && std::mem::take(&mut again) {
                        continue;
                    }
                }
                return outcome;
            }
        })
    }

    /// Runs `f` in one transaction, committed before it returns. Under a lead the
    /// transaction first takes a share lock of the lead row and checks its epoch: a write of a
    /// coordinator whose lead has passed is refused ([`StoreError::Fenced`]), and a standby
    /// taking the lead waits for writes under the old epoch to end, so none lands after it.
    fn transaction<T: Send>(
        &self,
        f: impl AsyncFn(&Transaction<'_>) -> PgResult<T> + Send + Sync,
    ) -> Result<T> {
        let ours = self.fence.load(std::sync::atomic::Ordering::SeqCst);
        let outcome = self.call(async |c: &mut Client| {
            let tx = c.transaction().await?;
            if ours != 0 {
                let sql = "SELECT epoch FROM restauro_leader WHERE id = 1 FOR SHARE";
                let current = tx.query_one(sql, &[]).await?.get::<_, i64>(0) as u64;
                if current != ours {
                    return Ok(Err(current));
                }
            }
            let value = f(&tx).await?;
            tx.commit().await?;
            Ok(Ok(value))
        })?;
        outcome.map_err(|current| StoreError::Fenced { url: self.shown.clone(), ours, current })
    }

    pub fn problem(&self) -> Option<String> {
        self.problem.describe(&self.shown)
    }

    /// Under a lead, the run's epoch is the lead's (taking the lead counted it).
    pub fn begin_run(&self, new_secret: [u8; 32]) -> Result<([u8; 32], u64)> {
        let lead = self.fence.load(std::sync::atomic::Ordering::SeqCst);
        self.transaction(async |tx| {
            tx.batch_execute("LOCK TABLE restauro_meta IN EXCLUSIVE MODE").await?;
            let value = async |key: &str| {
                let sql = "SELECT value FROM restauro_meta WHERE key = $1";
                let row = tx.query_opt(sql, &[&key]).await?;
                Ok::<_, tokio_postgres::Error>(row.map(|r| r.get::<_, Vec<u8>>(0)))
            };
            let secret = match value("secret").await? {
                Some(v) if v.len() == 32 => <[u8; 32]>::try_from(v).expect("32 bytes"),
                _ => new_secret,
            };
            let last = value("epoch")
                .await?
                .and_then(|v| <[u8; 8]>::try_from(v).ok())
                .map_or(0, u64::from_le_bytes);
            let epoch = if lead != 0 { lead } else { last + 1 };
            let put = "INSERT INTO restauro_meta (key, value) VALUES ($1, $2)
                       ON CONFLICT (key) DO UPDATE SET value = EXCLUDED.value";
            tx.execute(put, &[&"secret", &&secret[..]]).await?;
            tx.execute(put, &[&"epoch", &&epoch.to_le_bytes()[..]]).await?;
            Ok((secret, epoch))
        })
    }

    pub fn put_job(&self, id: &str, record: &[u8]) -> Result<()> {
        self.execute(
            "INSERT INTO restauro_jobs (id, record) VALUES ($1, $2)
             ON CONFLICT (id) DO UPDATE SET record = EXCLUDED.record",
            &[&id, &record],
        )
    }

    pub fn jobs(&self) -> Result<Vec<(String, Vec<u8>)>> {
        self.pairs("SELECT id, record FROM restauro_jobs ORDER BY id")
    }

    pub fn put_revision(&self, scene: &str, number: u32, record: &[u8]) -> Result<()> {
        self.execute(
            "INSERT INTO restauro_scene_revisions (scene, number, record) VALUES ($1, $2, $3)
             ON CONFLICT (scene, number) DO UPDATE SET record = EXCLUDED.record",
            &[&scene, &i64::from(number), &record],
        )
    }

    pub fn revisions(&self) -> Result<Vec<(String, u32, Vec<u8>)>> {
        self.call(async |c| {
            let sql = "SELECT scene, number, record FROM restauro_scene_revisions
                       ORDER BY scene, number";
            let rows = c.query(sql, &[]).await?;
            Ok(rows.iter().map(|r| (r.get(0), r.get::<_, i64>(1) as u32, r.get(2))).collect())
        })
    }

    /// One statement for the whole batch. A tile twice in a batch (a result sent again) is
    /// stored once, its last bytes: one statement cannot update a row twice.
    pub fn put_tiles(&self, tiles: &[(&str, u32, &[u8])]) -> Result<()> {
        let mut last = std::collections::BTreeMap::new();
        for &(job, tile, data) in tiles {
            last.insert((job, tile), data);
        }
        let jobs: Vec<&str> = last.keys().map(|k| k.0).collect();
        let indices: Vec<i64> = last.keys().map(|k| i64::from(k.1)).collect();
        let data: Vec<&[u8]> = last.values().copied().collect();
        self.execute(
            "INSERT INTO restauro_tiles (job, tile, data)
             SELECT * FROM unnest($1::text[], $2::bigint[], $3::bytea[])
             ON CONFLICT (job, tile) DO UPDATE SET data = EXCLUDED.data",
            &[&jobs, &indices, &data],
        )
    }

    pub fn finished_tiles(&self, job: &str) -> Result<Vec<u32>> {
        self.call(async |c| {
            let sql = "SELECT tile FROM restauro_tiles WHERE job = $1 ORDER BY tile";
            let rows = c.query(sql, &[&job]).await?;
            Ok(rows.iter().map(|r| r.get::<_, i64>(0) as u32).collect())
        })
    }

    pub fn tile(&self, job: &str, tile: u32) -> Result<Option<Vec<u8>>> {
        self.bytes("SELECT data FROM restauro_tiles WHERE job = $1 AND tile = $2", job, tile)
    }

    pub fn remove_tiles(&self, job: &str) -> Result<()> {
        self.transaction(async |tx| {
            tx.execute("DELETE FROM restauro_tiles WHERE job = $1", &[&job]).await?;
            tx.execute("DELETE FROM restauro_disputed WHERE job = $1", &[&job]).await?;
            Ok(())
        })
    }

    pub fn remove_tile_range(&self, job: &str, tiles: std::ops::Range<u32>) -> Result<()> {
        if tiles.is_empty() {
            return Ok(());
        }
        self.execute(
            "DELETE FROM restauro_tiles WHERE job = $1 AND tile >= $2 AND tile < $3",
            &[&job, &i64::from(tiles.start), &i64::from(tiles.end)],
        )
    }

    pub fn remove_tile_list(&self, job: &str, tiles: &[u32]) -> Result<()> {
        let tiles: Vec<i64> = tiles.iter().map(|&t| i64::from(t)).collect();
        self.transaction(async |tx| {
            for table in ["restauro_tiles", "restauro_disputed"] {
                let sql = format!("DELETE FROM {table} WHERE job = $1 AND tile = ANY($2)");
                tx.execute(&sql, &[&job, &tiles]).await?;
            }
            Ok(())
        })
    }

    pub fn put_disputed(&self, job: &str, tile: u32, data: &[u8]) -> Result<()> {
        self.execute(
            "INSERT INTO restauro_disputed (job, tile, data) VALUES ($1, $2, $3)
             ON CONFLICT (job, tile) DO UPDATE SET data = EXCLUDED.data",
            &[&job, &i64::from(tile), &data],
        )
    }

    pub fn disputed(&self, job: &str, tile: u32) -> Result<Option<Vec<u8>>> {
        self.bytes("SELECT data FROM restauro_disputed WHERE job = $1 AND tile = $2", job, tile)
    }

    pub fn remove_disputed(&self, job: &str, tile: u32) -> Result<()> {
        self.execute(
            "DELETE FROM restauro_disputed WHERE job = $1 AND tile = $2",
            &[&job, &i64::from(tile)],
        )
    }

    pub fn put_quarantine(&self, key: &str, record: &[u8]) -> Result<()> {
        self.execute(
            "INSERT INTO restauro_quarantine (key, record) VALUES ($1, $2)
             ON CONFLICT (key) DO UPDATE SET record = EXCLUDED.record",
            &[&key, &record],
        )
    }

    pub fn quarantine(&self) -> Result<Vec<(String, Vec<u8>)>> {
        self.pairs("SELECT key, record FROM restauro_quarantine ORDER BY key")
    }

    /// Takes the lead for `ttl` unless another coordinator holds it: its epoch is one more
    /// than any lead's or run's before (the runs' count is kept in step), and from now on
    /// this store's writes are fenced by it. By the database's clock.
    pub fn try_lead(&self, holder: &str, ttl: std::time::Duration) -> Result<LeadAttempt> {
        let ttl_ms = ttl.as_millis() as f64;
        let attempt = self.on_lead(async |c: &mut Client| {
            let tx = c.transaction().await?;
            tx.batch_execute("SET LOCAL lock_timeout = '1s'").await?;
            let sql = "SELECT holder, epoch, CASE WHEN expires_at <= now() THEN 0
                              ELSE extract(epoch FROM expires_at - now()) * 1000 END::float8
                       FROM restauro_leader WHERE id = 1 FOR UPDATE";
            let row = tx.query_one(sql, &[]).await?;
            let (held_by, epoch, left_ms) =
                (row.get::<_, String>(0), row.get::<_, i64>(1), row.get::<_, f64>(2));
            if left_ms > 0.0 && held_by != holder {
                return Ok(LeadAttempt::HeldBy { holder: held_by, for_ms: left_ms as u64 });
            }
            let sql = "SELECT value FROM restauro_meta WHERE key = 'epoch'";
            let runs = tx
                .query_opt(sql, &[])
                .await?
                .and_then(|r| <[u8; 8]>::try_from(r.get::<_, Vec<u8>>(0)).ok())
                .map_or(0, i64::from_le_bytes);
            let next = epoch.max(runs) + 1;
            let sql = "UPDATE restauro_leader SET holder = $1, epoch = $2,
                              expires_at = now() + $3 * interval '1 millisecond' WHERE id = 1";
            tx.execute(sql, &[&holder, &next, &ttl_ms]).await?;
            let sql = "INSERT INTO restauro_meta (key, value) VALUES ('epoch', $1)
                       ON CONFLICT (key) DO UPDATE SET value = EXCLUDED.value";
            tx.execute(sql, &[&&next.to_le_bytes()[..]]).await?;
            tx.commit().await?;
            Ok(LeadAttempt::Led { epoch: next as u64 })
        })?;
        if let LeadAttempt::Led { epoch } = attempt {
            self.fence.store(epoch, std::sync::atomic::Ordering::SeqCst);
        }
        Ok(attempt)
    }

    /// Extends the lead of `epoch` by `ttl` from now (the database's clock): whether it was
    /// still this coordinator's.
    pub fn renew_lead(&self, holder: &str, epoch: u64, ttl: std::time::Duration) -> Result<bool> {
        let ttl_ms = ttl.as_millis() as f64;
        let renewed = self.on_lead(async |c: &mut Client| {
            let sql =
                "UPDATE restauro_leader SET expires_at = now() + $3 * interval '1 millisecond'
                       WHERE id = 1 AND holder = $1 AND epoch = $2 AND expires_at > now()";
            c.execute(sql, &[&holder, &(epoch as i64), &ttl_ms]).await
        });
        Ok(renewed? == 1)
    }

    /// Gives the lead of `epoch` up at once, so a standby need not wait for it to lapse.
    pub fn release_lead(&self, holder: &str, epoch: u64) -> Result<()> {
        let released = self.on_lead(async |c: &mut Client| {
            // The holder cleared too, so a renewal still in flight cannot take it back.
            let sql = "UPDATE restauro_leader SET expires_at = '-infinity', holder = ''
                       WHERE id = 1 AND holder = $1 AND epoch = $2";
            c.execute(sql, &[&holder, &(epoch as i64)]).await
        });
        released.map(drop)
    }

    /// Runs `f` on the lead's own connection. Its failures are not the store's problem (the
    /// lead's watchdog acts on them): they are only returned.
    fn on_lead<T: Send>(
        &self,
        f: impl AsyncFn(&mut Client) -> PgResult<T> + Send + Sync,
    ) -> Result<T> {
        self.on(&self.lead_client, f).map_err(|e| self.error(error_chain(&e)))
    }

    /// One statement, in a transaction of its own.
    fn execute(
        &self,
        sql: &str,
        params: &[&(dyn tokio_postgres::types::ToSql + Sync)],
    ) -> Result<()> {
        if self.fence.load(std::sync::atomic::Ordering::SeqCst) == 0 {
            return self.call(async |c| c.execute(sql, params).await.map(drop));
        }
        self.transaction(async |tx| tx.execute(sql, params).await.map(drop))
    }

    /// Every row of two columns, text and bytes.
    fn pairs(&self, sql: &str) -> Result<Vec<(String, Vec<u8>)>> {
        self.call(async |c| {
            Ok(c.query(sql, &[]).await?.iter().map(|r| (r.get(0), r.get(1))).collect())
        })
    }

    /// The bytes of one (job, tile) row, if any.
    fn bytes(&self, sql: &str, job: &str, tile: u32) -> Result<Option<Vec<u8>>> {
        self.call(async |c| {
            Ok(c.query_opt(sql, &[&job, &i64::from(tile)]).await?.map(|r| r.get(0)))
        })
    }
}

/// Brings the schema up to date (see the module doc).
async fn migrate(c: &mut Client) -> PgResult<()> {
    c.batch_execute(
        "CREATE TABLE IF NOT EXISTS restauro_schema (
             version integer PRIMARY KEY,
             applied_at timestamptz NOT NULL DEFAULT now())",
    )
    .await?;
    let tx = c.transaction().await?;
    tx.batch_execute("LOCK TABLE restauro_schema IN EXCLUSIVE MODE").await?;
    let row = tx.query_one("SELECT coalesce(max(version), 0) FROM restauro_schema", &[]).await?;
    let current = row.get::<_, i32>(0).max(0) as usize;
    for (index, sql) in MIGRATIONS.iter().enumerate().skip(current) {
        tx.batch_execute(sql).await?;
        let version = index as i32 + 1;
        tx.execute("INSERT INTO restauro_schema (version) VALUES ($1)", &[&version]).await?;
        tracing::info!(version, "the PostgreSQL store's schema migrated");
    }
    tx.commit().await?;
    if current > MIGRATIONS.len() {
        tracing::warn!(
            database = current,
            known = MIGRATIONS.len(),
            "the PostgreSQL store's schema is newer than this release knows"
        );
    }
    Ok(())
}

/// An error with its causes, as the log and the caller see it.
fn error_chain(e: &tokio_postgres::Error) -> String {
    let mut out = e.to_string();
    if let Some(db) = e.as_db_error() {
        out = format!("{}: {}", db.code().code(), db.message());
    }
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        let text = s.to_string();
        if !out.contains(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
        source = s.source();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_url_is_shown_without_its_password() {
        assert_eq!(
            without_password("postgres://farm:s3cret@db.example:5432/restauro"),
            "postgres://farm@db.example:5432/restauro"
        );
        assert_eq!(without_password("postgres://db/restauro"), "postgres://db/restauro");
    }

    #[test]
    fn a_malformed_url_is_refused_naming_the_form() {
        let Err(e) = PgStore::connect("postgres://farm:pw@db:notaport/x") else {
            panic!("a port that is not a number was taken")
        };
        let e = e.to_string();
        assert!(e.contains("postgres://farm@db:notaport/x") && !e.contains("pw"), "{e}");
        assert!(e.contains("postgres://USER[:PASSWORD]@HOST[:PORT]/DATABASE"), "{e}");
    }
}
