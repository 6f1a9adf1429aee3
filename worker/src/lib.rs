//! restauro-worker: the spectral tracer (BVH, camera, sampler, materials, lights, integrators,
//! tile rendering) as a library, and later the worker process that renders leased tiles.
//!
//! Empty until the tracer issue; the crate exists so the workspace has its final shape and the
//! dependency direction (proto, spectral ← scene ← worker) is fixed from the start.
