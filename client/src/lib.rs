//! The `restauro` command line as a library, so that tests run exactly what the binary runs.

pub mod cli;
pub mod color;
pub mod compare;
pub mod connect;
pub mod demo;
pub mod illuminance;
pub mod illuminance_day;
pub mod jobs_cmd;
pub mod render;
pub mod retinex;
pub mod scene_cmd;
pub mod scene_new;
pub mod sequence;
pub mod studio_cmd;
