//! What a retrieval is given: measured sky radiances in known directions,
//! and optionally the aerosol optical depths a sun photometer measured
//! from the direct beam at the same time.
//!
//! Directions are the user's (elevation above the horizon, azimuth
//! clockwise from north, degrees), as everywhere in sora; radiances are
//! spectral, W m^-2 sr^-1 nm^-1, for the sun of the atmosphere they are
//! compared with (a measured radiance is divided by nothing: its sun is the
//! real one at that date, see `RadianceScale`). Readers of text formats
//! (the CSV of the issue, AERONET version 3 files) live in `input.rs`;
//! [`Measurements::validate`] checks what any of them produced.

/// One measured sky radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyRadianceMeasurement {
    /// Wavelength, nm.
    pub wavelength_nm: f64,
    /// Sun elevation at the time of the measurement, degrees.
    pub sun_elevation_deg: f64,
    /// Sun azimuth, degrees clockwise from north.
    pub sun_azimuth_deg: f64,
    /// View elevation, degrees.
    pub view_elevation_deg: f64,
    /// View azimuth, degrees clockwise from north.
    pub view_azimuth_deg: f64,
    /// Measured radiance, W m^-2 sr^-1 nm^-1 (or relative units when the
    /// set's scale is [`RadianceScale::Relative`]).
    pub radiance_w_m2_sr_nm: f64,
    /// Its 1-sigma uncertainty, same unit.
    pub uncertainty_w_m2_sr_nm: f64,
}

/// One aerosol optical depth measured from the direct sun.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpticalDepthMeasurement {
    /// Wavelength, nm.
    pub wavelength_nm: f64,
    /// Vertical aerosol extinction optical depth (no Rayleigh, no gases).
    pub aerosol_optical_depth: f64,
    /// Its 1-sigma uncertainty (AERONET's: about 0.01).
    pub uncertainty: f64,
}

/// Whether radiances are absolute or known only up to one factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RadianceScale {
    /// Calibrated radiances, W m^-2 sr^-1 nm^-1.
    #[default]
    Absolute,
    /// Radiances up to one unknown factor for the whole set (a normalised
    /// spectrum, as in the paper's Fig. 2): the retrieval fits the factor
    /// too, so only the shapes (spectral and angular) carry information.
    Relative,
}

/// Everything measured in one scan.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Measurements {
    /// A label for outputs (an AERONET scan's date and time, a file name).
    pub label: String,
    /// Sky radiances, any order.
    pub sky: Vec<SkyRadianceMeasurement>,
    /// Direct-sun aerosol optical depths (may be empty).
    pub optical_depths: Vec<OpticalDepthMeasurement>,
    /// Absolute or relative radiances.
    pub scale: RadianceScale,
}
