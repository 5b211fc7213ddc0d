//! The retrieval's synthetic validation set (`tests/data/retrieval/`), read
//! for `tests/retrieval.rs` and `benches/retrieval.rs`.

#![allow(dead_code)]

use sora::inversion::{
    MIN_SCATTERING_ANGLE_DEG, Measurements, OpticalDepthMeasurement, SkyRadianceMeasurement,
};

/// A case's true aerosol and optics.
pub struct Truth {
    pub case: usize,
    pub optical_depth_440: f64,
    pub fine_fraction: f64,
    pub n: f64,
    pub k: f64,
    pub fine_effective_radius_um: f64,
    /// At 440, 675, 870 and 1020 nm.
    pub optical_depths: [f64; 4],
    pub albedos: [f64; 4],
}

/// The set's folder (`SORA_RETRIEVAL_DATA` overrides it, for a set made
/// elsewhere).
pub fn data_directory() -> std::path::PathBuf {
    std::env::var_os("SORA_RETRIEVAL_DATA").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/retrieval"),
        std::path::PathBuf::from,
    )
}

fn rows(name: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(data_directory().join(name)).expect("the synthetic set");
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect()
}

/// Every case: its measurements (the radiances 3 degrees or more from the
/// sun, as AERONET's inversion and the readers of its files keep them,
/// and the optical depths given to the retrieval) and its truth.
pub fn cases() -> Vec<(Measurements, Truth)> {
    let radiances = rows("synthetic_almucantars.csv");
    rows("synthetic_truth.csv")
        .into_iter()
        .map(|t| {
            let case = t[0] as usize;
            let mut measurements = Measurements {
                label: format!("case {case}"),
                ..Measurements::default()
            };
            for r in radiances.iter().filter(|r| r[0] as usize == case) {
                let measurement = SkyRadianceMeasurement {
                    wavelength_nm: r[1],
                    sun_elevation_deg: r[2],
                    sun_azimuth_deg: r[3],
                    view_elevation_deg: r[4],
                    view_azimuth_deg: r[5],
                    radiance_w_m2_sr_nm: r[6],
                    uncertainty_w_m2_sr_nm: r[7],
                };
                if measurement.scattering_angle_deg() >= MIN_SCATTERING_ANGLE_DEG {
                    measurements.sky.push(measurement);
                }
            }
            for (w, wavelength_nm) in [440.0, 675.0, 870.0, 1020.0].into_iter().enumerate() {
                measurements.optical_depths.push(OpticalDepthMeasurement {
                    wavelength_nm,
                    aerosol_optical_depth: t[20 + w],
                    uncertainty: 0.01,
                });
            }
            let truth = Truth {
                case,
                optical_depth_440: t[2],
                fine_fraction: t[7],
                n: t[8],
                k: t[9],
                fine_effective_radius_um: t[10],
                optical_depths: [t[12], t[13], t[14], t[15]],
                albedos: [t[16], t[17], t[18], t[19]],
            };
            (measurements, truth)
        })
        .collect()
}
