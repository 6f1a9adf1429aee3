//! The procedural scenes, each generated as the text of its files.

pub mod aosta;
pub mod photo_block;
pub mod relief;
pub mod samples;
