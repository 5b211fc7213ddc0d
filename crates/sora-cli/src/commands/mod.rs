//! One module per subcommand: its clap arguments and its `run`.

pub mod atmosphere;
pub mod colour;
pub mod irradiance;
pub mod mie;
pub mod render;
pub mod retrieve;
pub mod self_test;
pub mod spectrum;
pub mod tables;
