//! # sora: physically based spectral atmospheric scattering
//!
//! The library behind the `sora` tool. It computes the spectral radiance and
//! colour of a planet's sky from the physics of its air and aerosols,
//! following Nakai & Sakai, "Atmospheric Scattering Simulation using Computer
//! Graphics" (see `../shared/paper/NOTES.md` for its equations and misprints),
//! and going beyond it (all orders of scattering, Mie aerosols, any planet).
//!
//! The front door is [`Sky`]: build it once from an [`Atmosphere`], the sun,
//! the eye, the wavelengths and the choice of physics ([`Scattering`]) and
//! method ([`Method`]), then ask it for the radiance of one view or many,
//! or for an image:
//!
//! ```
//! # fn main() -> sora::Result<()> {
//! use sora::{Atmosphere, Camera, ImageSettings, Sky, ViewDirection};
//! use sora::colour::{Observer, SpectrumToXyz};
//! let atmosphere = Atmosphere::preset("earth-clear")?;
//! let sky = Sky::builder(&atmosphere).sun_deg(30.0, 180.0).build()?;
//! let north = sky.radiance(ViewDirection::new(20.0, 0.0)?)?;
//! for (nm, l) in sky.wavelengths().wavelengths_nm().zip(north.radiance_w_m2_sr_nm.values()) {
//!     println!("{nm} nm: {l:.4e} W m^-2 sr^-1 nm^-1");
//! }
//! let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::Cie1931TwoDegree);
//! let xyz = sky.render_xyz(&ImageSettings::new(Camera::Fisheye, 32, 32), &to_xyz, &|_| {})?;
//! # assert_eq!(xyz.len(), 32 * 32);
//! # Ok(())
//! # }
//! ```
//!
//! `examples/spectrum.rs` and `examples/image.rs` are the same two jobs as
//! programs (an almucantar, a PNG).
//!
//! The pipeline, and the module of each stage:
//! 1. [`spectrum`]: wavelengths, spectra as functions and as samples, the sun;
//! 2. [`atmosphere`]: the planet, its species (Rayleigh air, ozone,
//!    parametric and Mie aerosols), their profiles, atmosphere files and
//!    presets, and their optics on a wavelength grid;
//! 3. [`mie`] (the `sora-mie` crate): aerosol optics from Mie theory;
//! 4. [`geometry`] and [`camera`]: the spherical planet, directions as users
//!    give them (elevation, azimuth clockwise from north), and which
//!    direction each pixel sees;
//! 5. [`sky`]: the [`Sky`], where single scattering (the paper's eq. 4-5)
//!    and multiple scattering are composed, for views and images, as
//!    scalar light or as Stokes vectors ([`Polarisation`]);
//! 6. `transport/`, the engine underneath it, private to the crate:
//!    single scattering, its reference march and its tables; the
//!    multiple-scattering field; the Monte Carlo path tracer. [`Sky`] is
//!    its interface; its reference tests live beside it;
//! 7. [`colour`]: spectral radiance -> CIE XYZ -> RGB (paper §4, eq. 6),
//!    exposure and gamut mapping;
//! 8. [`output`]: images on disk (PNG, OpenEXR), written atomically; the only
//!    module that touches files.
//!
//! Beside the pipeline: [`input`] (bounded reading of text inputs),
//! [`table`] (the one reader of numeric CSV tables),
//! [`sun_position`] (the sun's position from a time and a place, NREL's
//! SPA), [`inversion`] (aerosol retrieval from measured radiances, the
//! forward model being the [`Sky`]), [`engine_tables`] (the tables a
//! real-time shader reads to draw a sora sky, `docs/engine-tables.md`) and
//! [`error`].
//!
//! Units are SI unless a name says otherwise (`wavelength_nm`). The library
//! has no global state and prints nothing.

#![warn(missing_docs)]

pub use sora_mie as mie;

pub mod atmosphere;
pub mod camera;
pub mod colour;
pub mod engine_tables;
pub mod error;
pub mod geometry;
pub mod input;
pub mod inversion;
mod linear_algebra;
pub mod output;
mod parallel;
pub mod sky;
pub mod spectrum;
pub mod sun_position;
pub mod table;
pub(crate) mod transport;

pub use atmosphere::Atmosphere;
pub use camera::Camera;
pub use error::{Error, Result};
pub use geometry::ViewDirection;
pub use sky::{
    AerialPerspective, FastTableSize, ImageSettings, Irradiance, Method,
    MultipleScatteringSettings, Plane, Polarisation, Scattering, Sky, SkyBuilder, SkyRadiance,
    Stokes, TABLE_VIEW_COUNT,
};
pub use spectrum::WavelengthGrid;
pub use sun_position::{SunPosition, UtcTime};
