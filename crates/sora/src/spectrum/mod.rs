//! Spectra, kept as three notions (as in pbrt-v4):
//! - [`Spectrum`]: a quantity as a function of wavelength (constant or tabulated);
//! - [`WavelengthGrid`]: the wavelengths a computation samples, with their
//!   quadrature weights (default: the paper's 380-780 nm every 20 nm);
//! - [`SampledSpectrum`]: the values of a quantity at those wavelengths.
//!
//! Plus [`SolarSpectrum`], the sun's spectral irradiance at the top of the
//! atmosphere, and [`Filter`], an instrument channel's spectral response. Wavelengths are in nm (vacuum) throughout.

mod anchors;
mod filter;
mod function;
mod sampled;
mod solar;
mod wavelength_grid;

pub(crate) use anchors::WavelengthAnchors;
pub use filter::{CIMEL_CHANNELS, Filter};
pub use function::{Spectrum, TabulatedSpectrum};
pub use sampled::SampledSpectrum;
pub use solar::SolarSpectrum;
pub use wavelength_grid::{
    MAX_WAVELENGTH_COUNT, MAX_WAVELENGTH_NM, MIN_WAVELENGTH_NM, WavelengthGrid,
};
