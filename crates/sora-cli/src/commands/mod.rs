//! One module per subcommand: its clap arguments and its `run`.

pub mod atmosphere;
pub mod colour;
pub mod mie;
