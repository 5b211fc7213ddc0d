//! `sora colour`: (being written).

use clap::Args;

/// Colour of a spectrum.
#[derive(Debug, Args)]
pub struct ColourArgs {}

pub fn run(_args: ColourArgs) -> anyhow::Result<()> {
    anyhow::bail!("not yet available")
}
