//! Registering a process's Prometheus metrics: the one way the coordinator and the workers add a
//! metric to their registry, and the tile render-time buckets they share.

use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::{Metric, Registry, Unit};

/// Registers `metric` as `name` (with its `unit`, when it has one) and returns it. A metric is a
/// shared handle: the value returned and the registry's copy count together.
pub fn register<M: Metric + Clone>(
    registry: &mut Registry,
    name: &str,
    help: &str,
    unit: Option<Unit>,
    metric: M,
) -> M {
    match unit {
        Some(unit) => registry.register_with_unit(name, help, unit, metric.clone()),
        None => registry.register(name, help, metric.clone()),
    }
    metric
}

/// A histogram of render time per tile: 10 ms to 82 s, doubling. The coordinator (times as the
/// workers report them) and each worker (as it measures them) use the same buckets, so their
/// histograms can be compared and summed.
pub fn tile_render_histogram() -> Histogram {
    Histogram::new(exponential_buckets(0.01, 2.0, 14))
}
