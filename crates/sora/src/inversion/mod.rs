//! # Inversion: from measured sky radiances back to the aerosol
//!
//! (Work in progress.)

mod forward;
mod kernels;
pub mod measurements;
pub mod state;

pub use kernels::{MAX_RADIUS_UM, MIN_RADIUS_UM, RADIUS_NODES};
pub use measurements::{
    Measurements, OpticalDepthMeasurement, RadianceScale, SkyRadianceMeasurement,
};
pub use state::{AerosolState, BOUNDS, Bounds, LogNormalMode, PARAMETER_NAMES, PARAMETERS};
