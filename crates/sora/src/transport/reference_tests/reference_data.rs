//! What several reference tests share: the rows of
//! `data/clear_sky_radiance.csv` (independent radiative-transfer numbers for
//! the atmosphere `clear-sky-reference`; provenance on the file's first
//! line). Each test file uses the columns it needs.

use crate::table::NumericTable;

/// One row: a wavelength, a geometry, a ground albedo and three radiances
/// per unit top-of-atmosphere solar irradiance, sr^-1 (W m^-2 sr^-1 nm^-1
/// for a flat sun of 1 W m^-2 nm^-1).
pub(super) struct ReferenceRow {
    pub(super) wavelength_nm: f64,
    pub(super) sun_elevation_deg: f64,
    pub(super) view_elevation_deg: f64,
    /// View azimuth minus sun azimuth, degrees.
    pub(super) relative_azimuth_deg: f64,
    pub(super) ground_albedo: f64,
    /// Single scattering, plane-parallel (quadrature).
    pub(super) single_plane_parallel: f64,
    /// Single scattering, spherical planet of radius 6360 km (quadrature).
    pub(super) single_spherical: f64,
    /// All orders, plane-parallel (DISORT, 32 streams).
    pub(super) multiple_plane_parallel: f64,
}

/// Every row of `data/clear_sky_radiance.csv`, in the file's order.
pub(super) fn reference_rows() -> Vec<ReferenceRow> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/clear_sky_radiance.csv"
    ))
    .unwrap();
    let table = NumericTable::parse(&text, "clear_sky_radiance.csv").unwrap();
    let col = |name: &str| table.column_names.iter().position(|c| c == name).unwrap();
    let (wl, sun, view, rel, albedo) = (
        col("lambda_nm"),
        col("sun_elev_deg"),
        col("view_elev_deg"),
        col("rel_azimuth_deg"),
        col("ground_albedo"),
    );
    let (single_pp, single_sph, multi_pp) = (
        col("L_single_plane_parallel"),
        col("L_single_spherical"),
        col("L_multi_plane_parallel"),
    );
    table
        .rows
        .iter()
        .map(|r| ReferenceRow {
            wavelength_nm: r[wl],
            sun_elevation_deg: r[sun],
            view_elevation_deg: r[view],
            relative_azimuth_deg: r[rel],
            ground_albedo: r[albedo],
            single_plane_parallel: r[single_pp],
            single_spherical: r[single_sph],
            multiple_plane_parallel: r[multi_pp],
        })
        .collect()
}

/// The distinct geometries of `rows`, in the file's order:
/// (ground albedo, sun elevation deg, view elevation deg, relative azimuth
/// deg). The file lists each geometry's wavelengths together.
pub(super) fn reference_geometries(rows: &[ReferenceRow]) -> Vec<(f64, f64, f64, f64)> {
    let mut geometries: Vec<(f64, f64, f64, f64)> = rows
        .iter()
        .map(|r| {
            (
                r.ground_albedo,
                r.sun_elevation_deg,
                r.view_elevation_deg,
                r.relative_azimuth_deg,
            )
        })
        .collect();
    geometries.dedup();
    geometries
}

/// The corrected Coulson tables (`tests/data/coulson_rayleigh_toa.csv`):
/// columns albedo, mu, phi_deg, I, Q, U, 14 rows (checked here).
pub(crate) fn coulson_table() -> crate::table::NumericTable {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/coulson_rayleigh_toa.csv"
    ))
    .unwrap();
    let table = crate::table::NumericTable::parse(&text, "coulson_rayleigh_toa.csv").unwrap();
    assert_eq!(
        table.column_names,
        ["albedo", "mu", "phi_deg", "I", "Q", "U"]
    );
    assert_eq!(table.rows.len(), 14);
    table
}
