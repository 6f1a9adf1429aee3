//! The worker's Prometheus metrics, served with `--metrics-listen`: what it rendered, how long a
//! tile took, what it moved, and whether it is registered with a coordinator (its readiness).

use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::{Registry, Unit};

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
        let tiles_rendered = Counter::default();
        registry.register("tiles_rendered", "Tiles rendered", tiles_rendered.clone());
        let tiles_delivered = Counter::default();
        registry.register(
            "tiles_delivered",
            "Tile results the coordinator acknowledged",
            tiles_delivered.clone(),
        );
        let tile_render_seconds = Histogram::new(exponential_buckets(0.01, 2.0, 14));
        registry.register_with_unit(
            "tile_render",
            "Render time per tile",
            Unit::Seconds,
            tile_render_seconds.clone(),
        );
        let bytes_sent = Counter::default();
        registry.register_with_unit(
            "sent",
            "Tile results sent and acknowledged",
            Unit::Bytes,
            bytes_sent.clone(),
        );
        let asset_bytes_received = Counter::default();
        registry.register_with_unit(
            "asset_received",
            "Scene assets fetched from the coordinator",
            Unit::Bytes,
            asset_bytes_received.clone(),
        );
        let registered = Gauge::default();
        registry.register(
            "registered",
            "1 while registered with a coordinator",
            registered.clone(),
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

    fn ready(&self) -> Result<(), String> {
        if self.registered.get() == 1 {
            Ok(())
        } else {
            Err("not registered with a coordinator".into())
        }
    }
}
