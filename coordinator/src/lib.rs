//! restauro-coordinator: jobs, tile scheduling, leases, framebuffer assembly, the display
//! pipeline, persistence and the gRPC/HTTP services.
//!
//! Empty until the cluster issue. It never links the tracer (restauro-worker).
