//! restauro-coordinator: the coordinator process. [`server`] opens the farm's doors
//! (restauro-farm's gRPC services, restauro-studio's web page and API, and the metrics and
//! health endpoint) on their listeners, with their limits and TLS, and stops them together.

pub mod server;
