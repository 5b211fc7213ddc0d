//! # sora: physically based spectral atmospheric scattering
//!
//! The library behind the `sora` tool. It computes the spectral radiance and
//! colour of a planet's sky from the physics of its air and aerosols,
//! following Nakai & Sakai, "Atmospheric Scattering Simulation using Computer
//! Graphics" (see `../shared/paper/NOTES.md` for its equations and misprints),
//! and going beyond it.
//!
//! The pipeline, and the module of each stage:
//! 1. [`spectrum`]: wavelengths, spectra as functions and as samples, the sun;
//! 2. [`mie`] (the `sora-mie` crate): aerosol optics from Mie theory;
//! 3. [`geometry`] and [`camera`]: the spherical planet, directions as users
//!    give them (elevation, azimuth clockwise from north), and which
//!    direction each pixel sees;
//! 4. [`colour`]: spectral radiance -> CIE XYZ -> RGB (paper §4, eq. 6),
//!    exposure and gamut mapping;
//! 5. [`output`]: images on disk (PNG, OpenEXR), written atomically; the only
//!    module that touches files.
//!
//! Units are SI unless a name says otherwise (`wavelength_nm`). The library
//! has no global state and prints nothing.

pub use sora_mie as mie;

pub mod atmosphere;
pub mod camera;
pub mod colour;
pub mod error;
pub mod geometry;
pub mod output;
mod parallel;
pub mod render;
pub mod spectrum;
pub mod table;
pub mod transport;

pub use error::{Error, Result};
