//! # Inversion: from measured sky radiances back to the aerosol
//!
//! (Work in progress: the measurements' types come first.)

pub mod measurements;

pub use measurements::{
    Measurements, OpticalDepthMeasurement, RadianceScale, SkyRadianceMeasurement,
};
