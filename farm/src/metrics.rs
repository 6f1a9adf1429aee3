//! The coordinator's Prometheus metrics. The scheduler's counts are kept by the scheduler itself
//! (`scheduler::Totals`, `scheduler::Gauges`) and copied in at each scrape; what happens at the
//! service edge (bytes, render and Retinex times) is recorded where it happens.
//!
//! `restauro_tiles_queued` is the signal to scale workers on: tiles waiting for a lease over all
//! running jobs.

use crate::scheduler::{Gauges, Totals};
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::{Registry, Unit};
use restauro_ops::metric::{register, tile_render_histogram};

pub struct Metrics {
    registry: Registry,
    tiles_queued: Gauge,
    tiles_leased: Gauge,
    workers_connected: Gauge,
    jobs_unfinished: Gauge,
    /// 1 while the store cannot be written.
    pub store_failing: Gauge,
    /// 1 while the object store cannot be written.
    pub objects_failing: Gauge,
    leases_total: Counter,
    tiles_done_total: Counter,
    tiles_requeued_total: Counter,
    lease_expiries_total: Counter,
    workers_lost_total: Counter,
    /// The render time workers report per tile.
    pub tile_render_seconds: Histogram,
    /// The Retinex stage of each finished job.
    pub retinex_seconds: Histogram,
    /// Tile results received from workers.
    pub tile_bytes_received: Counter,
    /// Scene assets uploaded by clients.
    pub asset_bytes_received: Counter,
    /// Scene assets sent to workers.
    pub asset_bytes_sent: Counter,
    /// Result files sent to clients.
    pub result_bytes_sent: Counter,
    /// Tile checks whose second rendering agreed with the first.
    pub tile_checks_agreed: Counter,
    /// Tile checks whose second rendering differed (a third worker settles each).
    pub tile_checks_disputed: Counter,
    /// Disputes that three differing renderings left undecided.
    pub tile_checks_undecided: Counter,
    /// Workers quarantined for rendering a tile differently from two others.
    pub workers_quarantined: Counter,
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

impl Metrics {
    pub fn new() -> Self {
        let mut registry = Registry::with_prefix("restauro");
        let r = &mut registry;
        let gauge = |r: &mut Registry, name: &str, help: &str| {
            register(r, name, help, None, Gauge::default())
        };
        let counter = |r: &mut Registry, name: &str, help: &str| {
            register(r, name, help, None, Counter::default())
        };
        let bytes = |r: &mut Registry, name: &str, help: &str| {
            register(r, name, help, Some(Unit::Bytes), Counter::default())
        };
        let tiles_queued =
            gauge(r, "tiles_queued", "Tiles waiting for a lease over all running jobs");
        let tiles_leased = gauge(r, "tiles_leased", "Tiles leased to workers now");
        let workers_connected = gauge(r, "workers_connected", "Workers registered and heard from");
        let jobs_unfinished =
            gauge(r, "jobs_unfinished", "Jobs queued, running or being assembled");
        let store_failing =
            gauge(r, "store_failing", "1 while the store cannot be written (a full disk)");
        let objects_failing = gauge(
            r,
            "objects_failing",
            "1 while the object store (--objects) cannot be written (a full bucket)",
        );
        let leases_total = counter(r, "leases", "Leases granted");
        let tiles_done_total = counter(r, "tiles_done", "Tiles completed");
        let tiles_requeued_total = counter(
            r,
            "tiles_requeued",
            "Tiles put back in their queue (expired, failed, handed back, or lost with a worker)",
        );
        let lease_expiries_total =
            counter(r, "lease_expiries", "Leases that ran past the lease timeout");
        let workers_lost_total =
            counter(r, "workers_lost", "Workers dropped for silence past the heartbeat timeout");
        let tile_render_seconds = register(
            r,
            "tile_render",
            "Render time per tile, as workers report it",
            Some(Unit::Seconds),
            tile_render_histogram(),
        );
        let retinex_seconds = register(
            r,
            "retinex",
            "Retinex time per finished job",
            Some(Unit::Seconds),
            Histogram::new(exponential_buckets(0.05, 2.0, 12)),
        );
        let tile_bytes_received = bytes(r, "tile_received", "Tile results received from workers");
        let asset_bytes_received = bytes(r, "asset_received", "Scene assets uploaded by clients");
        let asset_bytes_sent = bytes(r, "asset_sent", "Scene assets sent to workers");
        let result_bytes_sent = bytes(r, "result_sent", "Result files sent to clients");
        let tile_checks_agreed = counter(
            r,
            "tile_checks_agreed",
            "Tiles rendered a second time on another worker, with the same bytes",
        );
        let tile_checks_disputed = counter(
            r,
            "tile_checks_disputed",
            "Tiles whose second rendering on another worker differed (a third settles it)",
        );
        let tile_checks_undecided = counter(
            r,
            "tile_checks_undecided",
            "Disputed tiles whose third rendering matched neither of the first two",
        );
        let workers_quarantined = counter(
            r,
            "workers_quarantined",
            "Workers quarantined for rendering a tile differently from two other workers",
        );
        Self {
            registry,
            tile_checks_agreed,
            tile_checks_disputed,
            tile_checks_undecided,
            workers_quarantined,
            tiles_queued,
            tiles_leased,
            workers_connected,
            jobs_unfinished,
            store_failing,
            objects_failing,
            leases_total,
            tiles_done_total,
            tiles_requeued_total,
            lease_expiries_total,
            workers_lost_total,
            tile_render_seconds,
            retinex_seconds,
            tile_bytes_received,
            asset_bytes_received,
            asset_bytes_sent,
            result_bytes_sent,
        }
    }

    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// Copies the scheduler's state in, before a scrape.
    pub fn update(&self, gauges: Gauges, totals: Totals, jobs_unfinished: u64) {
        let set = |g: &Gauge, v: u64| {
            g.set(i64::try_from(v).unwrap_or(i64::MAX));
        };
        set(&self.tiles_queued, gauges.queued);
        set(&self.tiles_leased, gauges.leased);
        set(&self.workers_connected, gauges.workers);
        set(&self.jobs_unfinished, jobs_unfinished);
        // The scheduler's totals only grow; the counters follow them.
        let follow = |c: &Counter, v: u64| {
            c.inc_by(v.saturating_sub(c.get()));
        };
        follow(&self.leases_total, totals.leased);
        follow(&self.tiles_done_total, totals.done);
        follow(&self.tiles_requeued_total, totals.requeued);
        follow(&self.lease_expiries_total, totals.lease_expiries);
        follow(&self.workers_lost_total, totals.workers_lost);
    }
}
