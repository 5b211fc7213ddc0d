//! `sora`: the command-line face of the sora library.
//!
//! A thin binary: it parses arguments (clap), turns them into validated
//! library types (see [`arguments`]), calls the library, and prints or
//! writes the result. Errors end the process with a one-line message on
//! stderr and exit status 1; argument errors exit with status 2 (clap).
//! One rule for values out of range: exit status 1 and the library's
//! one-line message, whichever parser saw them first (an out-of-range
//! `--wavelengths` grid, parsed by clap, is status 1 as an out-of-range
//! `--sun-elevation`, checked later, is); only text that does not parse,
//! unknown options and options that exclude each other are status 2.

mod arguments;
mod commands;
mod csv;
mod estimate;
mod fit_plot;
mod json;
mod polarisation_maps;
mod progress;

use clap::{Parser, Subcommand};

/// Physically based spectral sky simulator: spectra, aerosol optics and colour
/// of a planet's sky, computed from the physics of its air and aerosols.
#[derive(Debug, Parser)]
#[command(name = "sora", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Colour(commands::colour::ColourArgs),
    Mie(commands::mie::MieArgs),
    Atmosphere(commands::atmosphere::AtmosphereArgs),
    Spectrum(commands::spectrum::SpectrumArgs),
    Render(commands::render::RenderArgs),
    Irradiance(commands::irradiance::IrradianceArgs),
    Retrieve(commands::retrieve::RetrieveArgs),
    SelfTest(commands::self_test::SelfTestArgs),
    Tables(commands::tables::TablesArgs),
}

fn main() {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => {
            if let Some(message) = out_of_range_argument(&error) {
                eprintln!("error: {message}");
                std::process::exit(1);
            }
            error.exit()
        }
    };
    let result = match cli.command {
        Command::Colour(args) => commands::colour::run(args),
        Command::Mie(args) => commands::mie::run(args),
        Command::Atmosphere(args) => commands::atmosphere::run(args),
        Command::Spectrum(args) => commands::spectrum::run(args),
        Command::Render(args) => commands::render::run(args),
        Command::Irradiance(args) => commands::irradiance::run(args),
        Command::Retrieve(args) => commands::retrieve::run(args),
        Command::SelfTest(args) => commands::self_test::run(args),
        Command::Tables(args) => commands::tables::run(args),
    };
    if let Err(error) = result {
        if is_broken_pipe(&error) {
            // The reader went away (`sora spectrum ... | head`): as
            // ripgrep does, stop quietly; there is no one left to tell.
            return;
        }
        eprintln!("error: {error:#}");
        std::process::exit(1);
    }
}

/// The one-line message of an argument that parsed but whose value the
/// library refused as out of range (`sora::Error::OutOfRange`), naming the
/// option; None for every other argument error (clap's, status 2).
fn out_of_range_argument(error: &clap::Error) -> Option<String> {
    use clap::error::{ContextKind, ContextValue};
    use std::error::Error as _;
    let library = error.source()?.downcast_ref::<sora::Error>()?;
    if !matches!(library, sora::Error::OutOfRange { .. }) {
        return None;
    }
    let option = match error.get(ContextKind::InvalidArg) {
        Some(ContextValue::String(option)) => option.split_whitespace().next()?.to_string(),
        _ => return None,
    };
    Some(format!("{option}: {library}"))
}

/// Whether `error` comes from writing to a pipe whose reader has closed it.
fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
