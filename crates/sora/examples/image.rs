//! An all-sky fisheye of a sunset written as a PNG, through the front door.
//!
//! ```sh
//! cargo run --release -p sora --example image -- sunset.png
//! ```
//!
//! `earth-clear` with the sun 3 degrees up in the west, all orders of
//! scattering, 256 x 256 pixels (zenith at the centre, north up, east
//! left), automatic exposure and sRGB, as `sora render` would make it.

use sora::colour::{DisplayMapping, Observer, SpectrumToXyz};
use sora::output::{DisplayImage, write_png};
use sora::{Atmosphere, Camera, ImageSettings, Sky};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "sunset.png".into());
    let atmosphere = Atmosphere::preset("earth-clear")?;
    let sky = Sky::builder(&atmosphere)
        .sun_deg(3.0, 270.0)
        .polarisation(sora::Polarisation::Scalar)
        .build()?;
    let image = ImageSettings::new(Camera::Fisheye, 256, 256);
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::Cie1931TwoDegree);
    let xyz = sky.render_xyz(&image, &to_xyz, &|_| {})?;
    let pixels = DisplayMapping::default().to_u8(&xyz)?.concat();
    write_png(&path, &DisplayImage::new(256, 256, pixels)?)?;
    println!("wrote {path}");
    Ok(())
}
