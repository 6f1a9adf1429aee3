//! The worker's Prometheus metrics, served with `--metrics-listen`: what it rendered, how long a
//! tile took, what it moved, and whether it is registered with a coordinator (its readiness).

use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::Histogram;
use prometheus_client::registry::{Registry, Unit};
use restauro_ops::metric::{register, tile_render_histogram};

pub struct WorkerMetrics {
    registry: Registry,
    pub tiles_rendered: Counter,
    pub tiles_delivered: Counter,
    pub tile_render_seconds: Histogram,
    /// Tile results sent and acknowledged.
    pub bytes_sent: Counter,
    /// Scene assets fetched from the coordinator (not those found in the cache).
    pub asset_bytes_received: Counter,
    /// 1 while registered with a coordinator.
    pub registered: Gauge,
}

impl Default for WorkerMetrics {
    fn default() -> Self {
        Self::new()
    }
}

impl WorkerMetrics {
    pub fn new() -> Self {
        let mut registry = Registry::with_prefix("restauro_worker");
        let r = &mut registry;
        let tiles_rendered =
            register(r, "tiles_rendered", "Tiles rendered", None, Counter::default());
        let tiles_delivered = register(
            r,
            "tiles_delivered",
            "Tile results the coordinator acknowledged",
            None,
            Counter::default(),
        );
        let tile_render_seconds = register(
            r,
            "tile_render",
            "Render time per tile",
            Some(Unit::Seconds),
            tile_render_histogram(),
        );
        let bytes_sent = register(
            r,
            "sent",
            "Tile results sent and acknowledged",
            Some(Unit::Bytes),
            Counter::default(),
        );
        let asset_bytes_received = register(
            r,
            "asset_received",
            "Scene assets fetched from the coordinator",
            Some(Unit::Bytes),
            Counter::default(),
        );
        let registered = register(
            r,
            "registered",
            "1 while registered with a coordinator",
            None,
            Gauge::default(),
        );
        Self {
            registry,
            tiles_rendered,
            tiles_delivered,
            tile_render_seconds,
            bytes_sent,
            asset_bytes_received,
            registered,
        }
    }
}

impl restauro_ops::endpoint::Probe for WorkerMetrics {
    fn registry(&self) -> &Registry {
        &self.registry
    }

    fn ready(&self) -> Result<(), restauro_ops::endpoint::NotReady> {
        if self.registered.get() == 1 {
            Ok(())
        } else {
            Err(restauro_ops::endpoint::NotReady("not registered with a coordinator".into()))
        }
    }
}
