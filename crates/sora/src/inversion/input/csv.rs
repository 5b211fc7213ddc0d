//! sora's own CSV inputs, read through [`NumericTable`]: sky radiances
//! ([`parse_sky_radiance_csv`]), optical depths
//! ([`parse_optical_depth_csv`]) and a normalised spectrum in one direction
//! ([`parse_normalised_spectrum_csv`]); the formats are in the
//! [parent module](super)'s docs.

use crate::error::{Error, Result};
use crate::inversion::measurements::{
    MAX_RETRIEVAL_WAVELENGTH_NM as MAX_WAVELENGTH_NM, Measurements, OpticalDepthMeasurement,
    RadianceScale, SkyRadianceMeasurement,
};
use crate::spectrum::MIN_WAVELENGTH_NM;
use crate::table::NumericTable;

/// The columns of the sky radiance CSV, in the order.
pub const SKY_RADIANCE_COLUMNS: [&str; 7] = [
    "wavelength_nm",
    "sun_elevation_deg",
    "sun_azimuth_deg",
    "view_elevation_deg",
    "view_azimuth_deg",
    "radiance_w_m2_sr_nm",
    "uncertainty_w_m2_sr_nm",
];

/// The columns of the optical depth CSV.
pub const OPTICAL_DEPTH_COLUMNS: [&str; 3] =
    ["wavelength_nm", "aerosol_optical_depth", "uncertainty"];

/// The columns of the normalised spectrum CSV.
pub const NORMALISED_SPECTRUM_COLUMNS: [&str; 2] = ["wavelength_nm", "relative_radiance"];

/// Indices of `columns` in the table's header, in the order of `columns`;
/// an error names the missing or unexpected column.
fn column_indices(table: &NumericTable, columns: &[&str], what: &str) -> Result<Vec<usize>> {
    let expected = columns.join(",");
    for name in &table.column_names {
        if !columns.contains(&name.as_str()) {
            return Err(Error::parse(
                what,
                0,
                format!("unexpected column '{name}': the header must name {expected}"),
            ));
        }
    }
    columns
        .iter()
        .map(|column| {
            let matches: Vec<usize> = (0..table.column_names.len())
                .filter(|&i| table.column_names[i] == *column)
                .collect();
            match matches.as_slice() {
                [i] => Ok(*i),
                [] => Err(Error::parse(
                    what,
                    0,
                    format!("no column '{column}': the header must name {expected}"),
                )),
                _ => Err(Error::parse(what, 0, format!("column '{column}' twice"))),
            }
        })
        .collect()
}

/// Reads the sky radiance CSV (format in the module docs) into a set of
/// absolute radiances labelled `what`, without optical depths, and checks
/// it ([`Measurements::validate`]); an error names the line.
pub fn parse_sky_radiance_csv(text: &str, what: &str) -> Result<Measurements> {
    let table = NumericTable::parse(text, what)?;
    let index = column_indices(&table, &SKY_RADIANCE_COLUMNS, what)?;
    let scale = RadianceScale::Absolute;
    let mut sky = Vec::with_capacity(table.rows.len());
    for (row, &line) in table.rows.iter().zip(&table.line_numbers) {
        let measurement = SkyRadianceMeasurement {
            wavelength_nm: row[index[0]],
            sun_elevation_deg: row[index[1]],
            sun_azimuth_deg: row[index[2]],
            view_elevation_deg: row[index[3]],
            view_azimuth_deg: row[index[4]],
            radiance_w_m2_sr_nm: row[index[5]],
            uncertainty_w_m2_sr_nm: row[index[6]],
        };
        if let Some(problem) = measurement.problem(scale) {
            return Err(Error::parse(what, line, problem));
        }
        sky.push(measurement);
    }
    let measurements = Measurements {
        label: what.to_string(),
        sky,
        optical_depths: Vec::new(),
        scale,
    };
    measurements.validate()?;
    Ok(measurements)
}

/// Reads the optical depth CSV (`wavelength_nm, aerosol_optical_depth,
/// uncertainty`, any order): each value checked, each wavelength once. That
/// the wavelengths match the sky radiances' is checked when they are put
/// into a [`Measurements`] ([`Measurements::validate`]).
pub fn parse_optical_depth_csv(text: &str, what: &str) -> Result<Vec<OpticalDepthMeasurement>> {
    let table = NumericTable::parse(text, what)?;
    let index = column_indices(&table, &OPTICAL_DEPTH_COLUMNS, what)?;
    let mut depths: Vec<OpticalDepthMeasurement> = Vec::with_capacity(table.rows.len());
    for (row, &line) in table.rows.iter().zip(&table.line_numbers) {
        let depth = OpticalDepthMeasurement {
            wavelength_nm: row[index[0]],
            aerosol_optical_depth: row[index[1]],
            uncertainty: row[index[2]],
        };
        if let Some(problem) = depth.problem() {
            return Err(Error::parse(what, line, problem));
        }
        if !(MIN_WAVELENGTH_NM..=MAX_WAVELENGTH_NM).contains(&depth.wavelength_nm) {
            return Err(Error::parse(
                what,
                line,
                format!(
                    "wavelength {} nm is outside the model's {MIN_WAVELENGTH_NM}..={MAX_WAVELENGTH_NM} nm",
                    depth.wavelength_nm
                ),
            ));
        }
        if depths
            .iter()
            .any(|d| d.wavelength_nm == depth.wavelength_nm)
        {
            return Err(Error::parse(
                what,
                line,
                format!("a second optical depth at {} nm", depth.wavelength_nm),
            ));
        }
        depths.push(depth);
    }
    Ok(depths)
}

// ---------------------------------------------------------------------------
// (c) A normalised spectrum in one direction
// ---------------------------------------------------------------------------

/// The sun and the view of a single-direction measurement, degrees
/// (elevation above the horizon, azimuth clockwise from north).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkyGeometry {
    /// Sun elevation.
    pub sun_elevation_deg: f64,
    /// Sun azimuth.
    pub sun_azimuth_deg: f64,
    /// View elevation.
    pub view_elevation_deg: f64,
    /// View azimuth.
    pub view_azimuth_deg: f64,
}

/// Reads a spectrum measured in one direction and known only up to a
/// factor (`wavelength_nm, relative_radiance`, any order, values > 0) into
/// a [`RadianceScale::Relative`] set labelled `what`, each value's
/// uncertainty `relative_uncertainty` times itself. What such a spectrum
/// can and cannot tell is in the module docs.
pub fn parse_normalised_spectrum_csv(
    text: &str,
    what: &str,
    geometry: SkyGeometry,
    relative_uncertainty: f64,
) -> Result<Measurements> {
    check_relative_uncertainty(relative_uncertainty)?;
    let table = NumericTable::parse(text, what)?;
    let index = column_indices(&table, &NORMALISED_SPECTRUM_COLUMNS, what)?;
    let scale = RadianceScale::Relative;
    let mut sky: Vec<SkyRadianceMeasurement> = Vec::with_capacity(table.rows.len());
    for (row, &line) in table.rows.iter().zip(&table.line_numbers) {
        let (wavelength_nm, value) = (row[index[0]], row[index[1]]);
        if value <= 0.0 {
            return Err(Error::parse(
                what,
                line,
                format!("relative radiance {value} at {wavelength_nm} nm must be > 0"),
            ));
        }
        if sky.iter().any(|m| m.wavelength_nm == wavelength_nm) {
            return Err(Error::parse(
                what,
                line,
                format!("a second value at {wavelength_nm} nm"),
            ));
        }
        let measurement = SkyRadianceMeasurement {
            wavelength_nm,
            sun_elevation_deg: geometry.sun_elevation_deg,
            sun_azimuth_deg: geometry.sun_azimuth_deg,
            view_elevation_deg: geometry.view_elevation_deg,
            view_azimuth_deg: geometry.view_azimuth_deg,
            radiance_w_m2_sr_nm: value,
            uncertainty_w_m2_sr_nm: relative_uncertainty * value,
        };
        if let Some(problem) = measurement.problem(scale) {
            return Err(Error::parse(what, line, problem));
        }
        sky.push(measurement);
    }
    if sky.len() < 2 {
        return Err(Error::parse(
            what,
            0,
            "a relative spectrum needs at least 2 wavelengths (one value only fixes the unknown factor)",
        ));
    }
    let measurements = Measurements {
        label: what.to_string(),
        sky,
        optical_depths: Vec::new(),
        scale,
    };
    measurements.validate()?;
    Ok(measurements)
}

pub(super) fn check_relative_uncertainty(relative_uncertainty: f64) -> Result<()> {
    if relative_uncertainty.is_finite() && relative_uncertainty > 0.0 {
        Ok(())
    } else {
        Err(Error::out_of_range(
            "relative_uncertainty",
            relative_uncertainty,
            "1",
            "> 0 (e.g. 0.05 for 5 %)",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "wavelength_nm,sun_elevation_deg,sun_azimuth_deg,view_elevation_deg,\
                          view_azimuth_deg,radiance_w_m2_sr_nm,uncertainty_w_m2_sr_nm";

    fn sky_csv(rows: &str) -> String {
        format!("# test\n{HEADER}\n{rows}")
    }

    fn error(result: Result<impl std::fmt::Debug>) -> String {
        result.unwrap_err().to_string()
    }

    #[test]
    fn sky_csv_parses_rows_in_any_column_order() {
        let m = parse_sky_radiance_csv(
            &sky_csv("440,30,180,30,90,0.05,0.0025\n\n# comment\n675,30,180,60,0,0.02,0.001\n"),
            "sky.csv",
        )
        .unwrap();
        assert_eq!(m.label, "sky.csv");
        assert_eq!(m.scale, RadianceScale::Absolute);
        assert_eq!(m.sky.len(), 2);
        assert_eq!(m.sky[1].view_elevation_deg, 60.0);
        assert_eq!(m.sky[1].radiance_w_m2_sr_nm, 0.02);
        assert_eq!(m.wavelengths_nm(), [440.0, 675.0]);

        let shuffled = "radiance_w_m2_sr_nm,uncertainty_w_m2_sr_nm,wavelength_nm,sun_elevation_deg,\
                        sun_azimuth_deg,view_elevation_deg,view_azimuth_deg\n0.05,0.0025,440,30,180,30,90\n";
        let s = parse_sky_radiance_csv(shuffled, "s").unwrap();
        assert_eq!(s.sky[0], m.sky[0]);
    }

    #[test]
    fn sky_csv_errors_name_the_problem_and_line() {
        let e = error(parse_sky_radiance_csv(
            "wavelength_nm,radiance\n440,1\n",
            "f.csv",
        ));
        assert!(
            e.contains("f.csv") && e.contains("unexpected column 'radiance'"),
            "{e}"
        );
        let e = error(parse_sky_radiance_csv(
            &sky_csv("440,30,180,30,90,0.05,0.0025\n440,30,180,20,90,-0.01,0.0025\n"),
            "f.csv",
        ));
        assert!(
            e.contains("line 4")
                && e.contains("negative radiance")
                && e.contains("440 nm, view elevation 20 deg, azimuth 90 deg"),
            "{e}"
        );
        let e = error(parse_sky_radiance_csv(
            &sky_csv("440,30,180,30,181,0.05,0.0025\n"),
            "f",
        ));
        assert!(
            e.contains("line 3") && e.contains("from the sun's centre"),
            "{e}"
        );
        let e = error(parse_sky_radiance_csv(
            &sky_csv("440,30,180,-5,90,0.05,0.0025\n"),
            "f",
        ));
        assert!(e.contains("below the horizon is the ground"), "{e}");
        let e = error(parse_sky_radiance_csv(
            &sky_csv("1640,30,180,30,90,0.05,0.0025\n"),
            "f",
        ));
        assert!(e.contains("1640 nm is outside"), "{e}");
        let e = error(parse_sky_radiance_csv(
            &sky_csv("440,30,180,30,90,0.05,0\n"),
            "f",
        ));
        assert!(
            e.contains("uncertainty 0") && e.contains("must be > 0"),
            "{e}"
        );
        let e = error(parse_sky_radiance_csv(
            &sky_csv("440,30,180,30,90,0.05,x\n"),
            "f",
        ));
        assert!(
            e.contains("line 3") && e.contains("not a finite number"),
            "{e}"
        );
        let e = error(parse_sky_radiance_csv(&format!("{HEADER}\n"), "f"));
        assert!(e.contains("no rows"), "{e}");
    }

    #[test]
    fn optical_depth_csv_parses_and_checks() {
        let d = parse_optical_depth_csv(
            "uncertainty,wavelength_nm,aerosol_optical_depth\n0.01,440,0.2\n0.01,675,0.1\n",
            "aod.csv",
        )
        .unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(d[1].wavelength_nm, 675.0);
        assert_eq!(d[1].aerosol_optical_depth, 0.1);
        let e = error(parse_optical_depth_csv(
            "wavelength_nm,aerosol_optical_depth,uncertainty\n440,-0.1,0.01\n",
            "aod.csv",
        ));
        assert!(
            e.contains("line 2") && e.contains("negative aerosol optical depth"),
            "{e}"
        );
        let e = error(parse_optical_depth_csv(
            "wavelength_nm,aerosol_optical_depth,uncertainty\n440,0.1,0.01\n440,0.2,0.01\n",
            "aod.csv",
        ));
        assert!(
            e.contains("line 3") && e.contains("second optical depth at 440 nm"),
            "{e}"
        );
    }

    #[test]
    fn normalised_spectrum_is_relative_in_one_direction() {
        let geometry = SkyGeometry {
            sun_elevation_deg: 40.0,
            sun_azimuth_deg: 180.0,
            view_elevation_deg: 90.0,
            view_azimuth_deg: 0.0,
        };
        let m = parse_normalised_spectrum_csv(
            "wavelength_nm,relative_radiance\n400,1.0\n500,0.8\n600,0.5\n",
            "fig2",
            geometry,
            0.05,
        )
        .unwrap();
        assert_eq!(m.scale, RadianceScale::Relative);
        assert_eq!(m.sky.len(), 3);
        assert!((m.sky[1].uncertainty_w_m2_sr_nm - 0.04).abs() < 1e-12);
        assert!(m.sky.iter().all(|s| s.view_elevation_deg == 90.0));
        let e = error(parse_normalised_spectrum_csv(
            "wavelength_nm,relative_radiance\n400,1.0\n500,0\n",
            "fig2",
            geometry,
            0.05,
        ));
        assert!(e.contains("line 3") && e.contains("must be > 0"), "{e}");
        let e = error(parse_normalised_spectrum_csv(
            "wavelength_nm,relative_radiance\n400,1.0\n",
            "fig2",
            geometry,
            0.05,
        ));
        assert!(e.contains("at least 2 wavelengths"), "{e}");
        let e = error(parse_normalised_spectrum_csv(
            "wavelength_nm,relative_radiance\n400,1.0\n500,0.8\n",
            "fig2",
            geometry,
            0.0,
        ));
        assert!(e.contains("relative_uncertainty"), "{e}");
    }
}
