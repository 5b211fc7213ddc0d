//! Light transport: how sunlight reaches the eye through the atmosphere.
//!
//! (Being written: single scattering, the paper's eq. 4-5.)

pub mod optical_column;
pub mod quadrature;
pub mod single_scattering;

pub use single_scattering::{
    Observation, SingleScatteringScratch, SingleScatteringSky, SunColumns,
};
