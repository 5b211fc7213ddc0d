//! The radiance of a few views at full precision: the reference the Python
//! package's tests compare against (`crates/sora-python/tests`), since the
//! command line prints ten significant digits.
//!
//! ```sh
//! cargo run --release -p sora --example radiance_values -- \
//!     earth-clear 30 180 multiple fast 380:780:20 90,0 30,0 10,270
//! ```
//!
//! Arguments: preset, sun elevation and azimuth (deg), `single` or
//! `multiple`, `fast`, `reference` or `path-tracing:SAMPLES:SEED`, the
//! wavelength grid (start:stop:step, nm), then views as
//! `ELEVATION,AZIMUTH` (deg). The light is the library's default
//! (`sora::Polarisation::for_method`: polarised, scalar for `reference`),
//! as Python's. Prints one line per view: its angles and its
//! radiance per wavelength (W m^-2 sr^-1 nm^-1), each number in Rust's
//! shortest form that reads back to the same double.

use sora::{Atmosphere, Method, Scattering, Sky, ViewDirection, WavelengthGrid};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arguments: Vec<String> = std::env::args().skip(1).collect();
    let [
        preset,
        sun_elevation,
        sun_azimuth,
        scattering,
        method,
        grid,
        views @ ..,
    ] = arguments.as_slice()
    else {
        return Err(
            "usage: radiance_values PRESET SUN_EL SUN_AZ single|multiple METHOD GRID EL,AZ..."
                .into(),
        );
    };
    let scattering = match scattering.as_str() {
        "single" => Scattering::Single,
        _ => Scattering::multiple(),
    };
    let method = match method.split(':').collect::<Vec<_>>().as_slice() {
        ["fast"] => Method::Fast,
        ["reference"] => Method::REFERENCE_DEFAULT,
        ["path-tracing", samples, seed] => Method::PathTracing {
            samples: samples.parse()?,
            seed: seed.parse()?,
        },
        _ => return Err(format!("unknown method '{method}'").into()),
    };
    let atmosphere = Atmosphere::preset(preset)?;
    let sky = Sky::builder(&atmosphere)
        .sun_deg(sun_elevation.parse()?, sun_azimuth.parse()?)
        .wavelengths(grid.parse::<WavelengthGrid>()?)
        .scattering(scattering)
        .method(method)
        .build()?;
    let views = views
        .iter()
        .map(|view| {
            let (elevation, azimuth) = view.split_once(',').ok_or("a view is EL,AZ")?;
            Ok(ViewDirection::new(elevation.parse()?, azimuth.parse()?)?)
        })
        .collect::<Result<Vec<_>, Box<dyn std::error::Error>>>()?;
    for (view, radiance) in views.iter().zip(sky.radiances(&views)?) {
        let values: Vec<String> = radiance
            .radiance_w_m2_sr_nm
            .values()
            .iter()
            .map(|v| format!("{v:e}"))
            .collect();
        println!(
            "{:e} {:e} {}",
            view.elevation_deg(),
            view.azimuth_deg(),
            values.join(" ")
        );
    }
    Ok(())
}
