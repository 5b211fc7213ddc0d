//! `sora tables`: the engine tables of one atmosphere, for a real-time
//! shader (the library's `engine_tables`).

use std::path::PathBuf;

use clap::Args;
use sora::engine_tables::{EngineTableSettings, EngineTables};

use crate::arguments::{AtmosphereSource, library_names};

/// Precompute what a real-time shader needs to draw this atmosphere's sky,
/// the sun's disc, aerial perspective and the irradiance on the ground for
/// any sun elevation from -12 to 90 degrees and any eye altitude inside
/// the atmosphere: a directory of OpenEXR tables (CIE XYZ, 32-bit floats)
/// and manifest.json (units, axes, lookup formulas). The reference shaders
/// (GLSL ES 3.0 and WGSL) are in web/shaders/; docs/engine-tables.md says
/// how to bind and read the tables.
///
/// -o DIR is created, or must be empty, or must hold sora's tables (they
/// are replaced); the files are written together or not at all.
///
/// Example:
///   sora tables --preset earth-clear -o earth-clear-tables
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct TablesArgs {
    #[command(flatten)]
    source: AtmosphereSource,

    /// Wavelengths, start:stop:step in nm (colour uses 360-830)
    #[arg(long, value_name = "START:STOP:STEP", default_value = "380:780:20")]
    wavelengths: sora::spectrum::WavelengthGrid,

    /// Replace the atmosphere's ground albedo by this constant (0..1, Lambertian)
    #[arg(long, value_name = "A")]
    ground_albedo: Option<f64>,

    /// multiple (all orders and the skylight the ground reflects) or single
    #[arg(
        long,
        value_parser = library_names::<sora::Scattering>(&sora::Scattering::NAMES),
        default_value = "multiple"
    )]
    scattering: sora::Scattering,

    /// Sun elevation nodes over -12..90 degrees
    #[arg(long, value_name = "N", default_value_t = EngineTableSettings::default().sun_nodes)]
    sun_nodes: usize,

    /// Eye altitude nodes over the atmosphere's thickness (4: 0, 5.4, 25.5
    /// and 100 km for Earth; a raised eye's sky is read from the march's
    /// tables, which hold it as well as 6 nodes do; more nodes bring the
    /// table's own read (the shaders' soraSkyView) and the irradiance of
    /// a raised point closer between the nodes, each layer costing bake
    /// time)
    #[arg(long, value_name = "N", default_value_t = EngineTableSettings::default().altitude_nodes)]
    altitude_nodes: usize,

    /// View zenith nodes per half (above and below the horizon)
    #[arg(long, value_name = "N", default_value_t = EngineTableSettings::default().zenith_nodes_per_half)]
    zenith_nodes: usize,

    /// Fine cells of the zenith axis next to the horizon, per half (one
    /// cell of a finer grid each; the coarse cells from the zenith span
    /// two, the wide cells three): the nodes there are the library's own
    /// rows where the grid, 2 (N - 1) - F + W cells, has the images' 127
    /// (N 64, F 21, W 22: paper-mars within 2 % after sunset; or N 78,
    /// F 27, W 0) [default: 21 at the default 64 zenith nodes, 0 (the
    /// plain axis) with another --zenith-nodes]
    #[arg(long, value_name = "F")]
    zenith_fine_cells: Option<usize>,

    /// Wide cells of the zenith axis per half, between the coarse cells
    /// from the zenith and the fine cells (F + W at most N - 1) [default:
    /// 22 at the default 64 zenith nodes, 0 with another --zenith-nodes]
    #[arg(long, value_name = "W")]
    zenith_wide_cells: Option<usize>,

    /// View azimuth nodes over 0..180 degrees from the sun
    #[arg(long, value_name = "N", default_value_t = EngineTableSettings::default().azimuth_nodes)]
    azimuth_nodes: usize,

    /// Bake the aerial-perspective march's tables (march.bin: the field's
    /// source per wavelength and what a per-pixel march of the segment
    /// reads; within 2 % of the library at 1-50 km; 29-34 MB; multiple
    /// scattering only) [default]
    #[arg(long, overrides_with = "no_march")]
    march: bool,

    /// Leave out the march's tables (the shaders' aerial perspective then
    /// comes from the sky table, not within 2 %; 19 MB in all)
    #[arg(long, overrides_with = "march")]
    no_march: bool,

    /// Aerial-perspective table: view zenith nodes per half (0, with the
    /// other two 0, for none: the default; e.g. 8 8 6)
    #[arg(long, value_name = "N", default_value_t = EngineTableSettings::default().aerial_nodes.0)]
    aerial_zenith_nodes: usize,

    /// Aerial-perspective table: view azimuth nodes over 0..180 degrees (0: none)
    #[arg(long, value_name = "N", default_value_t = EngineTableSettings::default().aerial_nodes.1)]
    aerial_azimuth_nodes: usize,

    /// Aerial-perspective table: distance nodes, the nearest to the ray's end (0: none)
    #[arg(long, value_name = "N", default_value_t = EngineTableSettings::default().aerial_nodes.2)]
    aerial_distance_nodes: usize,

    /// Table file format (exr)
    #[arg(long, value_name = "FORMAT", default_value = "exr")]
    format: String,

    /// Output directory
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    output: PathBuf,
}

pub fn run(args: TablesArgs) -> anyhow::Result<()> {
    if args.format != "exr" {
        anyhow::bail!(
            "--format {}: unknown table format (sora writes exr)",
            args.format
        );
    }
    // The default fine and wide cells are those of the default zenith
    // nodes (their grid is the images' 127 cells); another count of
    // nodes gets the plain axis unless told.
    let defaults = EngineTableSettings::default();
    let (fine, wide) = if args.zenith_nodes == defaults.zenith_nodes_per_half {
        defaults.zenith_cells()
    } else {
        (0, 0)
    };
    let settings = EngineTableSettings {
        sun_nodes: args.sun_nodes,
        altitude_nodes: args.altitude_nodes,
        zenith_nodes_per_half: args.zenith_nodes,
        zenith_fine_cells_per_half: args.zenith_fine_cells.unwrap_or(fine),
        zenith_wide_cells_per_half: args.zenith_wide_cells.unwrap_or(wide),
        azimuth_nodes: args.azimuth_nodes,
        aerial_nodes: (
            args.aerial_zenith_nodes,
            args.aerial_azimuth_nodes,
            args.aerial_distance_nodes,
        ),
        march: !args.no_march,
        ..EngineTableSettings::default()
    };
    settings.validate()?;
    sora::engine_tables::check_output_directory(&args.output)?;
    let mut atmosphere = args.source.load()?;
    if let Some(albedo) = args.ground_albedo {
        atmosphere.planet = atmosphere
            .planet
            .with_ground_albedo(sora::spectrum::Spectrum::Constant(albedo))
            .map_err(|e| anyhow::anyhow!("--ground-albedo: {e}"))?;
    }
    let sky = sora::Sky::builder(&atmosphere)
        .wavelengths(args.wavelengths)
        .scattering(args.scattering)
        .build()?;
    let start = std::time::Instant::now();
    let bar = crate::progress::bar(
        1000,
        "{spinner} baking tables [{bar:40}] {percent}%, {eta} left",
    );
    let tables = EngineTables::bake(&sky, &settings, &|fraction| {
        bar.set_position((1000.0 * fraction).round() as u64)
    })?;
    bar.finish_and_clear();
    let baked = start.elapsed().as_secs_f64();
    tables.write(&args.output)?;
    eprintln!(
        "baked the tables in {baked:.2} s ({:.1} MB as a GPU holds them), wrote {}",
        tables.size_bytes() as f64 / 1e6,
        args.output.display()
    );
    Ok(())
}
