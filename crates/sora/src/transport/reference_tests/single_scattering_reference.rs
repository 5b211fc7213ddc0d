//! Single scattering against independent radiative-transfer numbers:
//! `data/clear_sky_radiance.csv` (atmosphere `clear-sky-reference`, flat
//! sun of 1 W m^-2 nm^-1, black ground): the spherical column
//! `L_single_spherical` (planet radius 6360 km) and the plane-parallel
//! column `L_single_plane_parallel` (approximated by a planet of radius
//! 6.36e9 m, as the issue asks).

use crate::atmosphere::{Atmosphere, Planet};
use crate::geometry::direction_from_elevation_azimuth;
use crate::spectrum::{SampledSpectrum, Spectrum, WavelengthGrid};
use crate::transport::{Observation, SingleScatteringSky, SunColumns};

use super::reference_data::{ReferenceRow as Row, reference_rows};

fn sky(atmosphere: &Atmosphere, sun_elevation_deg: f64) -> SingleScatteringSky {
    let observation = Observation {
        observer_altitude_m: 0.0,
        sun_elevation_deg,
        sun_azimuth_deg: 0.0,
    };
    SingleScatteringSky::new(atmosphere, &WavelengthGrid::paper(), observation).unwrap()
}

/// Worst relative error of the fast path (exact sun columns) and of the
/// reference path over all rows, against the column `pick`.
fn worst_errors(atmosphere: &Atmosphere, pick: fn(&Row) -> f64) -> (f64, f64) {
    let grid = WavelengthGrid::paper();
    let rows: Vec<Row> = reference_rows()
        .into_iter()
        .filter(|r| r.ground_albedo == 0.0)
        .collect();
    let (mut worst_fast, mut worst_reference): (f64, f64) = (0.0, 0.0);
    for sun_elevation in [36.0, 60.0] {
        let sky = sky(atmosphere, sun_elevation);
        let mut scratch = sky.scratch();
        let mut fast = SampledSpectrum::zeros(grid.len());
        let mut geometries: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.sun_elevation_deg == sun_elevation)
            .map(|r| (r.view_elevation_deg, r.relative_azimuth_deg))
            .collect();
        geometries.dedup();
        for (view_elevation, relative_azimuth) in geometries {
            let view = direction_from_elevation_azimuth(view_elevation, relative_azimuth);
            sky.compute_radiance(view, SunColumns::Exact, &mut scratch, &mut fast);
            let reference = sky.compute_radiance_reference(view, 4000, 800);
            for row in rows.iter().filter(|r| {
                r.sun_elevation_deg == sun_elevation
                    && r.view_elevation_deg == view_elevation
                    && r.relative_azimuth_deg == relative_azimuth
            }) {
                let i = ((row.wavelength_nm - grid.start_nm()) / grid.step_nm()).round() as usize;
                let expected = pick(row);
                let e_fast = (fast[i] / expected - 1.0).abs();
                let e_ref = (reference[i] / expected - 1.0).abs();
                if e_fast > 2e-3 || e_ref > 2e-3 {
                    eprintln!(
                        "sun {sun_elevation} view {view_elevation} rel {relative_azimuth} {} nm: fast {e_fast:.2e} reference {e_ref:.2e}",
                        row.wavelength_nm
                    );
                }
                worst_fast = worst_fast.max(e_fast);
                worst_reference = worst_reference.max(e_ref);
            }
        }
    }
    (worst_fast, worst_reference)
}

#[test]
fn spherical_single_scattering_matches_within_half_a_percent() {
    let atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    let (fast, reference) = worst_errors(&atmosphere, |r| r.single_spherical);
    eprintln!("spherical: worst relative error fast {fast:.3e}, reference {reference:.3e}");
    assert!(fast < 5e-3, "fast path {fast}");
    assert!(reference < 5e-3, "reference path {reference}");
}

#[test]
fn plane_parallel_single_scattering_matches_within_half_a_percent() {
    let mut atmosphere = Atmosphere::preset("clear-sky-reference").unwrap();
    atmosphere.planet = Planet::new(6.36e9, 100e3, Spectrum::Constant(0.0)).unwrap();
    let (fast, reference) = worst_errors(&atmosphere, |r| r.single_plane_parallel);
    eprintln!("plane-parallel: worst relative error fast {fast:.3e}, reference {reference:.3e}");
    assert!(fast < 5e-3, "fast path {fast}");
    assert!(reference < 5e-3, "reference path {reference}");
}
