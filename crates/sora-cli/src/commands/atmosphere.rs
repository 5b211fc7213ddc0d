//! `sora atmosphere`: (stub, being written).

use clap::Args;

/// Inspect atmospheres: presets and per-wavelength optical depths.
#[derive(Debug, Args)]
pub struct AtmosphereArgs {}

pub fn run(_args: AtmosphereArgs) -> anyhow::Result<()> {
    anyhow::bail!("not yet available")
}
