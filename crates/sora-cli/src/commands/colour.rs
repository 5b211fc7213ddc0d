//! `sora colour`: the colour of a spectrum read from a CSV file: CIE XYZ,
//! chromaticity, linear RGB and the display colour, optionally as a swatch
//! image.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use sora::colour::SpectrumToXyz;
use sora::output::output_target;
use sora::output::{
    ChannelKind, DisplayImage, ExrOptions, LinearImage, OutputFormat, write_exr, write_png,
};
use sora::spectrum::{Spectrum, TabulatedSpectrum, WavelengthGrid};

use crate::arguments::ColourOptions;

/// The colour of a spectrum: CIE XYZ, chromaticity xy, linear RGB and the
/// display colour.
///
/// The CSV has a header line and two columns, wavelength_nm and the spectral
/// value (e.g. radiance in W m^-2 sr^-1 nm^-1); lines starting with # are
/// comments. The spectrum is interpolated linearly at the wavelengths of
/// --wavelengths and integrated with the paper's rule
/// X = sum L(lambda) xbar(lambda) step (no 683 lm/W factor).
///
/// Example:
///   sora colour sky.csv --swatch sky.png
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub struct ColourArgs {
    /// The spectrum, a CSV file wavelength_nm,value ("-" reads stdin)
    #[arg(value_name = "SPECTRUM.csv")]
    spectrum: PathBuf,

    /// Wavelengths to integrate on, start:stop:step in nm (within 280-2500; colour uses 360-830)
    #[arg(long, value_name = "START:STOP:STEP", default_value = "380:780:20")]
    wavelengths: WavelengthGrid,

    #[command(flatten)]
    colour: ColourOptions,

    /// Also write a 64 x 64 swatch of the colour: .png (display colour) or
    /// .exr (linear RGB, unexposed); as sora render -o: a symbolic link is
    /// followed, a directory or a read-only file is refused
    #[arg(long, value_name = "FILE")]
    swatch: Option<PathBuf>,
}

pub fn run(args: ColourArgs) -> anyhow::Result<()> {
    // Checked before any work (`sora::output::output_target`).
    let swatch = match &args.swatch {
        Some(path) => Some((
            OutputFormat::from_path(path)?,
            output_target(path, "--swatch")?,
        )),
        None => None,
    };
    let name = args.spectrum.display().to_string();
    let text = if args.spectrum.as_os_str() == "-" {
        sora::input::read_text_from(std::io::stdin(), "stdin")?
    } else {
        sora::input::read_text(&args.spectrum)?
    };
    let table = TabulatedSpectrum::parse_csv(&text, &name)?;
    let sampled = Spectrum::Tabulated(table)
        .sample_at_wavelengths(&args.wavelengths)
        .with_context(|| format!("{name} on the grid {}", args.wavelengths))?;
    let xyz = SpectrumToXyz::new(&args.wavelengths, args.colour.observer)
        .to_xyz(&sampled)
        .with_context(|| name.clone())?;
    let mapping = args.colour.display_mapping()?;
    let colour_space = mapping.encoding.colour_space();
    let linear = colour_space.linear_rgb_from_xyz(xyz);
    let [display] = mapping.to_u8(&[xyz])?[..] else {
        unreachable!("one pixel in, one out")
    };

    println!(
        "spectrum     {name}: {} samples on {} nm, observer {}",
        sampled.len(),
        args.wavelengths,
        args.colour.observer
    );
    println!("XYZ          {:.9e} {:.9e} {:.9e}", xyz.x, xyz.y, xyz.z);
    match xyz.chromaticity_xy() {
        Some([x, y]) => println!("xy           {x:.6} {y:.6}"),
        None => println!("xy           undefined (black)"),
    }
    println!(
        "linear RGB   {:.9e} {:.9e} {:.9e}   ({}, unexposed)",
        linear.r,
        linear.g,
        linear.b,
        colour_space.name()
    );
    println!(
        "display      #{:02x}{:02x}{:02x}   ({}, exposure {}, gamut {})",
        display[0],
        display[1],
        display[2],
        mapping.encoding,
        args.colour.exposure,
        mapping.gamut_mapping.name()
    );
    println!(
        "luminance    {:.6e} cd/m^2 if the spectrum is radiance in W m^-2 sr^-1 nm^-1 (683 Y)",
        xyz.luminance_cd_m2()
    );

    if let (Some((format, target)), Some(path)) = (&swatch, &args.swatch) {
        const SIZE: usize = 64;
        match format {
            OutputFormat::Png => {
                let data = display.repeat(SIZE * SIZE);
                write_png(target, &DisplayImage::new(SIZE, SIZE, data)?)?;
            }
            OutputFormat::Exr => {
                let pixel = [linear.r as f32, linear.g as f32, linear.b as f32];
                let image =
                    LinearImage::new(SIZE, SIZE, ChannelKind::Rgb, vec![pixel; SIZE * SIZE])?;
                write_exr(target, &image, ExrOptions::default())?;
            }
        }
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
