//! The sky's spectrum along an almucantar (the circle of sky at the sun's
//! elevation), through the front door: one [`Sky`], many views in one call.
//!
//! ```sh
//! cargo run --release -p sora --example spectrum
//! ```
//!
//! Prints, every 30 degrees of azimuth from the sun, the radiance at 450,
//! 550 and 650 nm (W m^-2 sr^-1 nm^-1) of `earth-clear` with the sun 30
//! degrees up in the south, all orders of scattering.

use sora::{Atmosphere, Sky, ViewDirection, WavelengthGrid};

fn main() -> sora::Result<()> {
    let atmosphere = Atmosphere::preset("earth-clear")?;
    let (sun_elevation_deg, sun_azimuth_deg) = (30.0, 180.0);
    let sky = Sky::builder(&atmosphere)
        .sun_deg(sun_elevation_deg, sun_azimuth_deg)
        .wavelengths(WavelengthGrid::new(450.0, 650.0, 100.0)?)
        .polarisation(sora::Polarisation::Scalar)
        .build()?;
    let views = (0..12)
        .map(|k| ViewDirection::new(sun_elevation_deg, sun_azimuth_deg + 30.0 * k as f64))
        .collect::<sora::Result<Vec<_>>>()?;
    println!("azimuth_from_sun_deg,l450_w_m2_sr_nm,l550_w_m2_sr_nm,l650_w_m2_sr_nm");
    for (k, radiance) in sky.radiances(&views)?.iter().enumerate() {
        let l = radiance.radiance_w_m2_sr_nm.values();
        println!("{},{:.4e},{:.4e},{:.4e}", 30 * k, l[0], l[1], l[2]);
    }
    Ok(())
}
