//! # Inversion: from measured sky radiances back to the aerosol
//!
//! (Work in progress: the measurements' types and their readers come
//! first.)
//!
//! [`measurements`] holds what a retrieval is given and checks it
//! ([`Measurements::validate`]); [`input`] reads it from text: sora's own
//! CSV, AERONET version 3 almucantar, principal-plane and optical depth
//! files, and a normalised spectrum in one direction.

pub mod input;
pub mod measurements;

pub use input::{
    AeronetOpticalDepths, AeronetScan, AeronetSky, AeronetSkyScan, AeronetTime, SkyGeometry,
    attach_nearest_optical_depths, parse_aeronet_aod, parse_aeronet_sky,
    parse_normalised_spectrum_csv, parse_optical_depth_csv, parse_sky_radiance_csv,
};
pub use measurements::{
    MIN_SCATTERING_ANGLE_DEG, Measurements, OpticalDepthMeasurement, RadianceScale,
    SkyRadianceMeasurement,
};
