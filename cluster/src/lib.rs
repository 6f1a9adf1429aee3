//! A farm as its client sees it: the `restauro` command line's link to a coordinator
//! ([`client`]: connect, upload a scene's files, submit, watch, fetch the results), the embedded
//! local cluster its demo, render and studio commands start ([`local`]), and progress as a person
//! follows it ([`progress`]). Every call returns a [`ClusterError`] that says what was being done.

pub mod client;
pub mod error;
pub mod local;
pub mod progress;

pub use client::{
    Client, connect, connect_as, fetch, read_status, refused, runtime, submit, upload, watch,
};
pub use error::ClusterError;
pub use local::LocalCluster;
