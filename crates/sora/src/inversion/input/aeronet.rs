//! The AERONET readers: version 3 sky scans ([`parse_aeronet_sky`]) and
//! direct-sun optical depths ([`parse_aeronet_aod`], also version 2), their
//! matching in time ([`attach_nearest_optical_depths`]), and the network's
//! own version 2 inversion products ([`parse_aeronet_inversion`]); the
//! conventions are in the [parent module](super)'s docs.

use crate::error::{Error, Result};
use crate::inversion::measurements::{
    MAX_RETRIEVAL_WAVELENGTH_NM as MAX_WAVELENGTH_NM, MIN_SCATTERING_ANGLE_DEG, Measurements,
    OpticalDepthMeasurement, RadianceScale, SkyRadianceMeasurement, list_nm, scattering_angle_deg,
};
use crate::spectrum::MIN_WAVELENGTH_NM;

use super::csv::check_relative_uncertainty;

/// AERONET radiance unit (uW cm^-2 sr^-1 nm^-1) in W m^-2 sr^-1 nm^-1:
/// 1e-6 W per 1e-4 m^2.
pub const AERONET_RADIANCE_TO_W_M2_SR_NM: f64 = 1e-2;

/// The sun's azimuth given to AERONET scans, whose files do not have it
/// (no `Solar_Azimuth_Angle` column in any file seen), degrees clockwise
/// from north.
pub const AERONET_SUN_AZIMUTH_DEG: f64 = 180.0;

/// Rows of one date and scan type within this time of a scan's first row
/// belong to that scan (one wavelength after the other), seconds.
pub const AERONET_SCAN_WINDOW_S: i64 = 15 * 60;

/// An optical depth measured further than this from a sky scan is not
/// attached to it, seconds. AERONET's own inversions take the direct-sun
/// measurements of the same sequence, minutes apart; half an hour allows
/// for a cloud-screened gap while the aerosol has seldom changed much.
pub const AOD_MATCH_WINDOW_S: i64 = 30 * 60;

/// The 1-sigma uncertainty given to AERONET optical depths: the network's
/// stated 0.01 (0.01-0.02 for field instruments) in the visible and near
/// infrared.
pub const AERONET_AOD_UNCERTAINTY: f64 = 0.01;

/// AERONET's missing value.
const AERONET_MISSING: f64 = -999.0;

/// AERONET version 2's "not measured" (`-9999.`).
const AERONET_V2_MISSING: f64 = -9999.0;

/// Which AERONET sky scan a file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AeronetScan {
    /// Azimuth scan at the sun's elevation (`.alm`).
    Almucantar,
    /// Elevation scan in the sun's vertical plane (`.ppl`).
    PrincipalPlane,
}

impl AeronetScan {
    fn name(self) -> &'static str {
        match self {
            AeronetScan::Almucantar => "almucantar",
            AeronetScan::PrincipalPlane => "principal plane",
        }
    }

    /// Whether a `Sky_Scan_Type` cell names this kind (`Almucantar`,
    /// `Principal Plane`, `Principal_Plane`).
    fn matches(self, cell: &str) -> bool {
        let cell: String = cell
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .collect::<String>()
            .to_ascii_lowercase();
        match self {
            AeronetScan::Almucantar => cell == "almucantar",
            AeronetScan::PrincipalPlane => cell == "principalplane",
        }
    }
}

/// A date and time as AERONET writes them (UTC).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct AeronetTime {
    /// Year.
    pub year: i32,
    /// Month, 1..=12.
    pub month: u32,
    /// Day of the month, 1..=31.
    pub day: u32,
    /// Seconds since midnight.
    pub second_of_day: u32,
}

impl AeronetTime {
    /// Parses `dd:mm:yyyy` (or `dd-mm-yyyy`, older files) and `hh:mm:ss`.
    fn parse(date: &str, time: &str) -> Option<AeronetTime> {
        let date: Vec<&str> = date.trim().split([':', '-']).collect();
        let time: Vec<&str> = time.trim().split(':').collect();
        let [day, month, year] = date.as_slice() else {
            return None;
        };
        let [hours, minutes, seconds] = time.as_slice() else {
            return None;
        };
        let (day, month, year) = (day.parse().ok()?, month.parse().ok()?, year.parse().ok()?);
        let (hours, minutes, seconds): (u32, u32, u32) = (
            hours.parse().ok()?,
            minutes.parse().ok()?,
            seconds.parse().ok()?,
        );
        if !(1..=12).contains(&month) || !(1..=31).contains(&day) {
            return None;
        }
        if hours > 23 || minutes > 59 || seconds > 60 {
            return None;
        }
        Some(AeronetTime {
            year,
            month,
            day,
            second_of_day: hours * 3600 + minutes * 60 + seconds,
        })
    }

    /// Seconds since 1970-01-01 00:00 UTC.
    pub fn unix_seconds(&self) -> i64 {
        // The calendar of the sun's position (proleptic Gregorian).
        let days = crate::sun_position::days_from_civil(i64::from(self.year), self.month, self.day);
        days * 86_400 + i64::from(self.second_of_day)
    }
}

impl std::fmt::Display for AeronetTime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = self.second_of_day;
        write!(
            f,
            "{:04}-{:02}-{:02} {:02}:{:02}:{:02}",
            self.year,
            self.month,
            self.day,
            s / 3600,
            s / 60 % 60,
            s % 60
        )
    }
}

/// One AERONET sky scan: all its wavelengths, as [`Measurements`].
#[derive(Debug, Clone, PartialEq)]
pub struct AeronetSkyScan {
    /// The time of the scan's first row.
    pub time: AeronetTime,
    /// The site (`AERONET_Site`), empty when the file has no such column.
    pub site: String,
    /// The radiances in W m^-2 sr^-1 nm^-1, labelled `site date time kind`;
    /// optical depths come from [`attach_nearest_optical_depths`].
    pub measurements: Measurements,
}

/// What [`parse_aeronet_sky`] read.
#[derive(Debug, Clone, PartialEq)]
pub struct AeronetSky {
    /// The usable scans, in the file's order.
    pub scans: Vec<AeronetSkyScan>,
    /// What was left out and why, one line each (dropped scans, channels
    /// outside the model's range, points inside the sun's aureole or below
    /// the horizon), for the caller to show.
    pub notes: Vec<String>,
}

/// The direct-sun aerosol optical depths of one AERONET measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct AeronetOpticalDepths {
    /// When.
    pub time: AeronetTime,
    /// The site (`AERONET_Site` or `AERONET_Site_Name`, or version 2's
    /// `Location=` line), empty when the file has none of them.
    pub site: String,
    /// `(nominal wavelength nm, aerosol optical depth)`, the channels
    /// measured (`-999` left out), in the file's column order.
    pub optical_depths: Vec<(f64, f64)>,
}

/// The lines of an AERONET file, 1-based, split at commas, and the index
/// of the header (the first line naming `Date(` and `Time(`).
struct AeronetText<'a> {
    lines: Vec<(usize, Vec<&'a str>)>,
    header: usize,
}

impl<'a> AeronetText<'a> {
    fn new(text: &'a str, what: &str, expected: &str) -> Result<AeronetText<'a>> {
        let lines: Vec<(usize, Vec<&str>)> = text
            .lines()
            .enumerate()
            .map(|(i, line)| (i + 1, split_aeronet_line(line)))
            .collect();
        let header = lines
            .iter()
            .position(|(_, cells)| {
                cells.iter().any(|c| c.starts_with("Date("))
                    && cells.iter().any(|c| c.starts_with("Time("))
            })
            .ok_or_else(|| {
                Error::parse(
                    what,
                    0,
                    format!(
                        "no header line with Date(dd:mm:yyyy) and Time(hh:mm:ss): not an AERONET {expected} file"
                    ),
                )
            })?;
        Ok(AeronetText { lines, header })
    }

    fn header_cells(&self) -> &[&'a str] {
        &self.lines[self.header].1
    }

    fn column(&self, what: &str, prefix: &str) -> Result<usize> {
        self.optional_column(prefix).ok_or_else(|| {
            Error::parse(
                what,
                self.lines[self.header].0,
                format!("the header has no {prefix}... column"),
            )
        })
    }

    fn optional_column(&self, prefix: &str) -> Option<usize> {
        self.header_cells()
            .iter()
            .position(|c| c.starts_with(prefix))
    }

    /// Data lines after the header (and after `skip` more lines): neither
    /// empty nor markup left by the web service (`<`...).
    fn data_lines(&self, skip: usize) -> impl Iterator<Item = &(usize, Vec<&'a str>)> {
        self.lines[self.header + 1 + skip..]
            .iter()
            .filter(|(_, cells)| {
                let first = cells.first().copied().unwrap_or("");
                !(cells.iter().all(|c| c.is_empty())
                    || first.starts_with('<')
                    || first.starts_with('#'))
            })
    }
}

/// A line's cells, without the `<br>` line breaks and the `<html><body>`
/// wrapping that the web service's output has unless asked not to.
fn split_aeronet_line(line: &str) -> Vec<&str> {
    let mut line = line.trim();
    while let Some(rest) = line.strip_suffix("<br>") {
        line = rest.trim_end();
    }
    for wrapper in ["</body></html>", "</div>"] {
        line = line.strip_suffix(wrapper).unwrap_or(line).trim_end();
    }
    for wrapper in ["<html><body><div>", "<html><body>"] {
        line = line.strip_prefix(wrapper).unwrap_or(line).trim_start();
    }
    crate::table::cells(line)
}

fn cell<'a>(cells: &[&'a str], index: usize) -> &'a str {
    cells.get(index).copied().unwrap_or("")
}

/// A number cell: `Ok(None)` for AERONET's `-999` (or an empty or `N/A`
/// cell).
fn aeronet_number(
    cells: &[&str],
    index: usize,
    name: &str,
    what: &str,
    line: usize,
) -> Result<Option<f64>> {
    let text = cell(cells, index);
    if text.is_empty() || text == "N/A" {
        return Ok(None);
    }
    match text.parse::<f64>() {
        Ok(v) if v == AERONET_MISSING || v == AERONET_V2_MISSING => Ok(None),
        Ok(v) if v.is_finite() => Ok(Some(v)),
        _ => Err(Error::parse(
            what,
            line,
            format!("{name} = '{text}' is not a number"),
        )),
    }
}

fn aeronet_time(
    cells: &[&str],
    date: usize,
    time: usize,
    what: &str,
    line: usize,
) -> Result<AeronetTime> {
    AeronetTime::parse(cell(cells, date), cell(cells, time)).ok_or_else(|| {
        Error::parse(
            what,
            line,
            format!(
                "date '{}' and time '{}' are not dd:mm:yyyy and hh:mm:ss",
                cell(cells, date),
                cell(cells, time)
            ),
        )
    })
}

/// The radiance columns of a sky file: `(column, angle deg)`.
fn radiance_columns(text: &AeronetText, what: &str) -> Result<(Vec<(usize, f64)>, usize)> {
    let header = text.header_cells();
    // Newer files name sections (radiances, then scattering angles) on a
    // line next to the header; take the radiance section only.
    let is_section_line = |cells: &[&str]| {
        cells
            .iter()
            .any(|c| c.starts_with("Radiance_for") || c.starts_with("Scattering_Angle_for"))
    };
    let before = text.header.checked_sub(1).map(|i| &text.lines[i].1);
    let after = text.lines.get(text.header + 1).map(|(_, cells)| cells);
    let (sections, skip) = match (before, after) {
        (_, Some(cells)) if is_section_line(cells) => (Some(cells), 1),
        (Some(cells), _) if is_section_line(cells) => (Some(cells), 0),
        _ => (None, 0),
    };
    let mut columns = Vec::new();
    let mut section = "";
    for (i, name) in header.iter().enumerate() {
        if let Some(sections) = sections {
            let s = cell(sections, i);
            if !s.is_empty() {
                section = s;
            }
        }
        // `6.000000`, or `..._6.000` when the section is in the name.
        let (prefix, number) = match name.rsplit_once('_') {
            Some((prefix, number)) if number.parse::<f64>().is_ok() => (prefix, number),
            _ => ("", *name),
        };
        let Ok(angle) = number.parse::<f64>() else {
            continue;
        };
        let in_radiances = if sections.is_some() {
            section.starts_with("Radiance")
        } else {
            prefix.is_empty() || prefix.starts_with("Radiance")
        };
        if in_radiances && angle.is_finite() {
            columns.push((i, angle));
        }
    }
    if columns.is_empty() {
        return Err(Error::parse(
            what,
            text.lines[text.header].0,
            "the header has no angle columns (6.000000, -6.000000, ...): no usable angles",
        ));
    }
    Ok((columns, skip))
}

/// One row of a sky file, before grouping.
struct SkyRow {
    line: usize,
    time: AeronetTime,
    site: String,
    scan_type: String,
    wavelength_nm: f64,
    solar_zenith_deg: f64,
    /// The file's solar azimuth if it has one, else [`AERONET_SUN_AZIMUTH_DEG`].
    sun_azimuth_deg: f64,
    /// `(angle deg, radiance uW cm^-2 sr^-1 nm^-1)`, -999 left out.
    radiances: Vec<(f64, f64)>,
}

/// Reads an AERONET version 3 almucantar or principal-plane file (layout
/// and conventions in the module docs) into one [`Measurements`] per scan,
/// radiances in W m^-2 sr^-1 nm^-1 with uncertainties
/// `relative_uncertainty` times themselves.
///
/// Scans of another kind in the same file (AERONET's `Hybrid` scans) are
/// left out and noted. An error names the line (a cell that is not a
/// number, a date that is not one) or, when no scan is usable, why.
pub fn parse_aeronet_sky(
    text: &str,
    kind: AeronetScan,
    what: &str,
    relative_uncertainty: f64,
) -> Result<AeronetSky> {
    check_relative_uncertainty(relative_uncertainty)?;
    let file = AeronetText::new(text, what, kind.name())?;
    let date = file.column(what, "Date(")?;
    let time = file.column(what, "Time(")?;
    let wavelength = file.column(what, "Nominal_Wavelength")?;
    let zenith = file.column(what, "Solar_Zenith_Angle")?;
    let azimuth = file.optional_column("Solar_Azimuth_Angle");
    let scan_type = file.optional_column("Sky_Scan_Type");
    let site = file.optional_column("AERONET_Site");
    let (angles, skip) = radiance_columns(&file, what)?;

    let mut notes = Vec::new();
    let mut rows = Vec::new();
    let mut other_kinds = std::collections::BTreeMap::<String, usize>::new();
    let mut out_of_range = std::collections::BTreeSet::<String>::new();
    for (line, cells) in file.data_lines(skip) {
        let line = *line;
        let scan_type = scan_type.map_or(String::new(), |i| cell(cells, i).to_string());
        if !scan_type.is_empty() && !kind.matches(&scan_type) {
            *other_kinds.entry(scan_type).or_default() += 1;
            continue;
        }
        let time = aeronet_time(cells, date, time, what, line)?;
        let wavelength_nm =
            aeronet_number(cells, wavelength, "Nominal_Wavelength(nm)", what, line)?
                .ok_or_else(|| Error::parse(what, line, "the wavelength is missing (-999)"))?;
        if !(MIN_WAVELENGTH_NM..=MAX_WAVELENGTH_NM).contains(&wavelength_nm) {
            out_of_range.insert(wavelength_nm.to_string());
            continue;
        }
        let Some(solar_zenith_deg) =
            aeronet_number(cells, zenith, "Solar_Zenith_Angle", what, line)?
        else {
            notes.push(format!(
                "line {line}: no solar zenith angle (-999); row left out"
            ));
            continue;
        };
        let sun_azimuth_deg = match azimuth {
            Some(i) => aeronet_number(cells, i, "Solar_Azimuth_Angle", what, line)?,
            None => None,
        }
        .unwrap_or(AERONET_SUN_AZIMUTH_DEG);
        let mut radiances = Vec::new();
        for &(column, angle) in &angles {
            if let Some(radiance) = aeronet_number(
                cells,
                column,
                &format!("the radiance at {angle} deg"),
                what,
                line,
            )? {
                radiances.push((angle, radiance));
            }
        }
        rows.push(SkyRow {
            line,
            time,
            site: site.map_or(String::new(), |i| cell(cells, i).to_string()),
            scan_type,
            wavelength_nm,
            solar_zenith_deg,
            sun_azimuth_deg,
            radiances,
        });
    }
    for (other, count) in &other_kinds {
        notes.push(format!(
            "{count} rows of '{other}' scans left out: this reads {} scans",
            kind.name()
        ));
    }
    if !out_of_range.is_empty() {
        notes.push(format!(
            "channels at {} nm left out: outside the model's {MIN_WAVELENGTH_NM}..={MAX_WAVELENGTH_NM} nm",
            out_of_range.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }

    let mut scans = Vec::new();
    for group in group_scans(rows) {
        let first = &group[0];
        let label = format!(
            "{}{} {}",
            if first.site.is_empty() {
                String::new()
            } else {
                format!("{} ", first.site)
            },
            first.time,
            kind.name()
        );
        let (sky, near_sun, below_horizon) = scan_measurements(&group, kind, relative_uncertainty);
        if near_sun > 0 {
            notes.push(format!(
                "{label}: {near_sun} points closer than {MIN_SCATTERING_ANGLE_DEG} deg to the sun left out"
            ));
        }
        if below_horizon > 0 {
            notes.push(format!(
                "{label}: {below_horizon} points below the horizon left out"
            ));
        }
        if sky.is_empty() {
            notes.push(format!(
                "{label} (lines {}-{}): dropped, no usable radiance (all -999 or inside the sun's aureole)",
                first.line,
                group[group.len() - 1].line
            ));
            continue;
        }
        let measurements = Measurements {
            label,
            sky,
            optical_depths: Vec::new(),
            scale: RadianceScale::Absolute,
        };
        measurements.validate()?;
        scans.push(AeronetSkyScan {
            time: first.time,
            site: first.site.clone(),
            measurements,
        });
    }
    if scans.is_empty() {
        let why = if notes.is_empty() {
            "the file has no data rows".to_string()
        } else {
            notes.join("; ")
        };
        return Err(Error::parse(
            what,
            0,
            format!("no usable {} scan: {why}", kind.name()),
        ));
    }
    Ok(AeronetSky { scans, notes })
}

/// Splits rows into scans: a new scan starts at a new date or scan type, a
/// row more than [`AERONET_SCAN_WINDOW_S`] after the scan's first, or a
/// wavelength the scan already has.
fn group_scans(rows: Vec<SkyRow>) -> Vec<Vec<SkyRow>> {
    let mut groups: Vec<Vec<SkyRow>> = Vec::new();
    for row in rows {
        let joins = groups.last().is_some_and(|group| {
            let first = &group[0];
            let dt = row.time.unix_seconds() - first.time.unix_seconds();
            (first.time.year, first.time.month, first.time.day)
                == (row.time.year, row.time.month, row.time.day)
                && first.scan_type == row.scan_type
                && first.site == row.site
                && (0..=AERONET_SCAN_WINDOW_S).contains(&dt)
                && !group.iter().any(|r| r.wavelength_nm == row.wavelength_nm)
        });
        if joins {
            groups.last_mut().unwrap().push(row);
        } else {
            groups.push(vec![row]);
        }
    }
    groups
}

/// The measurements of one scan, with the counts of points left out near
/// the sun and below the horizon.
fn scan_measurements(
    group: &[SkyRow],
    kind: AeronetScan,
    relative_uncertainty: f64,
) -> (Vec<SkyRadianceMeasurement>, usize, usize) {
    let (mut near_sun, mut below_horizon) = (0, 0);
    let mut sky = Vec::new();
    for row in group {
        let sun_elevation_deg = 90.0 - row.solar_zenith_deg;
        let sun_azimuth_deg = row.sun_azimuth_deg;
        // Directions, each once: an angle measured twice (AERONET repeats
        // the near-sun ones), or 180 and -180, is averaged (sum, count).
        let mut by_direction: Vec<(f64, f64, f64, u32)> = Vec::new();
        for &(angle, radiance) in &row.radiances {
            let (view_elevation_deg, view_azimuth_deg) = match kind {
                AeronetScan::Almucantar => (sun_elevation_deg, sun_azimuth_deg + angle),
                AeronetScan::PrincipalPlane => {
                    let view_zenith = row.solar_zenith_deg - angle;
                    if view_zenith >= 0.0 {
                        (90.0 - view_zenith, sun_azimuth_deg)
                    } else {
                        (90.0 + view_zenith, sun_azimuth_deg + 180.0)
                    }
                }
            };
            let view_azimuth_deg = view_azimuth_deg.rem_euclid(360.0);
            if !(0.0..=90.0).contains(&view_elevation_deg) {
                below_horizon += 1;
                continue;
            }
            let scattering = scattering_angle_deg(
                sun_elevation_deg,
                sun_azimuth_deg,
                view_elevation_deg,
                view_azimuth_deg,
            );
            if scattering < MIN_SCATTERING_ANGLE_DEG {
                near_sun += 1;
                continue;
            }
            let same = |e: f64, a: f64| {
                (e - view_elevation_deg).abs() < 1e-9 && (a - view_azimuth_deg).abs() < 1e-9
            };
            match by_direction.iter_mut().find(|(e, a, _, _)| same(*e, *a)) {
                Some(entry) => {
                    entry.2 += radiance;
                    entry.3 += 1;
                }
                None => by_direction.push((view_elevation_deg, view_azimuth_deg, radiance, 1)),
            }
        }
        for (view_elevation_deg, view_azimuth_deg, sum, count) in by_direction {
            let radiance = sum / f64::from(count) * AERONET_RADIANCE_TO_W_M2_SR_NM;
            sky.push(SkyRadianceMeasurement {
                wavelength_nm: row.wavelength_nm,
                sun_elevation_deg,
                sun_azimuth_deg,
                view_elevation_deg,
                view_azimuth_deg,
                radiance_w_m2_sr_nm: radiance,
                uncertainty_w_m2_sr_nm: relative_uncertainty * radiance,
            });
        }
    }
    (sky, near_sun, below_horizon)
}

/// Reads an AERONET version 3 or version 2 direct-sun optical depth file
/// (layouts in the module docs): one entry per line, the `AOD_<n>nm` (or
/// `AOT_<n>`) channels measured.
/// Lines with no channel measured are left out; an error names the line.
pub fn parse_aeronet_aod(text: &str, what: &str) -> Result<Vec<AeronetOpticalDepths>> {
    let file = AeronetText::new(text, what, "optical depth")?;
    let date = file.column(what, "Date(")?;
    let time = file.column(what, "Time(")?;
    let site = file
        .header_cells()
        .iter()
        .position(|c| *c == "AERONET_Site" || *c == "AERONET_Site_Name");
    let channels: Vec<(usize, f64)> = file
        .header_cells()
        .iter()
        .enumerate()
        .filter_map(|(i, name)| {
            // Version 3: AOD_440nm; version 2: AOT_440 (not AOT_440-Total
            // and the like of other products, which do not parse).
            let nm = match name.strip_prefix("AOD_") {
                Some(rest) => rest.strip_suffix("nm")?,
                None => name.strip_prefix("AOT_")?,
            };
            Some((i, nm.parse::<f64>().ok()?))
        })
        .collect();
    if channels.is_empty() {
        return Err(Error::parse(
            what,
            file.lines[file.header].0,
            "the header has no AOD_<n>nm (version 3) or AOT_<n> (version 2) columns: not an AERONET optical depth file",
        ));
    }
    // Version 2 names its site once, on a `Location=<site>,long=...` line
    // above the header, instead of in a column.
    let location = file.lines[..file.header]
        .iter()
        .flat_map(|(_, cells)| cells.iter())
        .find_map(|c| c.strip_prefix("Location="))
        .unwrap_or("");
    let mut entries = Vec::new();
    for (line, cells) in file.data_lines(0) {
        let time = aeronet_time(cells, date, time, what, *line)?;
        let mut optical_depths = Vec::new();
        for &(column, nm) in &channels {
            if let Some(aod) = aeronet_number(cells, column, &format!("AOD_{nm}nm"), what, *line)? {
                optical_depths.push((nm, aod));
            }
        }
        if !optical_depths.is_empty() {
            entries.push(AeronetOpticalDepths {
                time,
                site: site.map_or(location.to_string(), |i| cell(cells, i).to_string()),
                optical_depths,
            });
        }
    }
    if entries.is_empty() {
        return Err(Error::parse(
            what,
            0,
            "no optical depth measured (no rows, or all -999)",
        ));
    }
    Ok(entries)
}

/// The optical depth at `wavelength_nm` from one AERONET entry: the
/// channel itself, or the Angstrom law (log-log) between the nearest
/// channels either side; `None` when neither exists or a value is not > 0
/// (the log needs it).
fn optical_depth_at(entry: &AeronetOpticalDepths, wavelength_nm: f64) -> Option<f64> {
    if let Some(&(_, aod)) = entry
        .optical_depths
        .iter()
        .find(|(nm, _)| *nm == wavelength_nm)
    {
        return Some(aod);
    }
    let below = entry
        .optical_depths
        .iter()
        .filter(|(nm, _)| *nm < wavelength_nm)
        .max_by(|a, b| a.0.total_cmp(&b.0))?;
    let above = entry
        .optical_depths
        .iter()
        .filter(|(nm, _)| *nm > wavelength_nm)
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    if below.1 <= 0.0 || above.1 <= 0.0 {
        return None;
    }
    let t = (wavelength_nm / below.0).ln() / (above.0 / below.0).ln();
    Some((below.1.ln() + t * (above.1 / below.1).ln()).exp())
}

/// Gives each scan the optical depths of the AERONET entry of its site
/// (when both name one) nearest to it in time, if within
/// [`AOD_MATCH_WINDOW_S`], at each of the scan's
/// wavelengths that it has or brackets (uncertainty
/// [`AERONET_AOD_UNCERTAINTY`]); replaces the scan's optical depths. Returns
/// one note per scan left without (or with only some) optical depths.
pub fn attach_nearest_optical_depths(
    scans: &mut [AeronetSkyScan],
    optical_depths: &[AeronetOpticalDepths],
) -> Vec<String> {
    let mut notes = Vec::new();
    for scan in scans.iter_mut() {
        let label = &scan.measurements.label;
        let t = scan.time.unix_seconds();
        let same_site = |entry: &&AeronetOpticalDepths| {
            entry.site.is_empty() || scan.site.is_empty() || entry.site == scan.site
        };
        let nearest = optical_depths
            .iter()
            .filter(same_site)
            .min_by_key(|entry| (entry.time.unix_seconds() - t).abs());
        let Some(entry) =
            nearest.filter(|e| (e.time.unix_seconds() - t).abs() <= AOD_MATCH_WINDOW_S)
        else {
            notes.push(format!(
                "{label}: no optical depth of this site within {} min; fitted from the sky radiances alone",
                AOD_MATCH_WINDOW_S / 60
            ));
            scan.measurements.optical_depths.clear();
            continue;
        };
        let wavelengths = scan.measurements.wavelengths_nm();
        let mut missing = Vec::new();
        scan.measurements.optical_depths = wavelengths
            .iter()
            .filter_map(|&nm| {
                let aod = optical_depth_at(entry, nm);
                if aod.is_none() {
                    missing.push(nm);
                }
                Some(OpticalDepthMeasurement {
                    wavelength_nm: nm,
                    aerosol_optical_depth: aod?,
                    uncertainty: AERONET_AOD_UNCERTAINTY,
                })
            })
            .collect();
        if !missing.is_empty() {
            notes.push(format!(
                "{label}: no optical depth at {} nm in the measurement of {}",
                list_nm(&missing),
                entry.time
            ));
        }
    }
    notes
}

// ---------------------------------------------------------------------------
// AERONET version 2 inversion products (the network's own retrievals)
// ---------------------------------------------------------------------------

/// One channel of an AERONET inversion: the network's retrieved optics at
/// that wavelength (`None` where the file has `-9999.`: version 2 level 2.0
/// gives n, k and the albedo only when tau(440) >= 0.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AeronetInversionChannel {
    /// The wavelength the columns are named by, nm (`REFR(1018)`: 1018).
    pub wavelength_nm: f64,
    /// `REFR(<nm>)`.
    pub refractive_index_real: Option<f64>,
    /// `REFI(<nm>)`.
    pub refractive_index_imaginary: Option<f64>,
    /// `SSA<nm>-T`.
    pub single_scattering_albedo: Option<f64>,
    /// `AOTExt<nm>-T`: the retrieval's total extinction optical depth.
    pub extinction_optical_depth: Option<f64>,
}

/// One row of an AERONET version 2 inversion product file (`Level 1.5` or
/// `2.0 Almucantar Retrievals, Version 2`; all points or daily averages).
#[derive(Debug, Clone, PartialEq)]
pub struct AeronetInversion {
    /// When.
    pub time: AeronetTime,
    /// The site (the `Locations=` entry of the first line).
    pub site: String,
    /// Per channel, in the order of the file's `REFR(<nm>)` columns.
    pub channels: Vec<AeronetInversionChannel>,
    /// The volume size distribution dV/d ln r, um^3 um^-2, at the radii
    /// (um) that name its columns (22 from 0.05 to 15 um), `(radius,
    /// value)`; bins with `-9999.` left out.
    pub size_distribution: Vec<(f64, f64)>,
    /// `VolCon-T`: the total volume concentration, um^3 um^-2.
    pub volume_concentration_um3_um2: Option<f64>,
}

/// Reads an AERONET version 2 inversion product file: a line
/// `dd:mm:yyyy,Locations=<site>,long=...`, `Level <l> Almucantar
/// Retrievals, Version 2`, the product's name, then the header
/// `Date(dd-mm-yyyy),Time(hh:mm:ss),...` and one row per retrieval (the
/// dates of the rows are `dd:mm:yyyy`). What it takes: `REFR(<nm>)`,
/// `REFI(<nm>)`, `SSA<nm>-T`, `AOTExt<nm>-T`, the size distribution's
/// columns (named by their radius in um) and `VolCon-T`; a file with other
/// products' columns only (`Spectral Flux`) gives rows without channels.
/// Version 3's inversion files name their columns otherwise and are not
/// read here.
pub fn parse_aeronet_inversion(text: &str, what: &str) -> Result<Vec<AeronetInversion>> {
    let file = AeronetText::new(text, what, "inversion")?;
    let preamble = &file.lines[..file.header];
    if !preamble.iter().any(|(_, cells)| {
        cells
            .iter()
            .any(|c| c.contains("Retrievals, Version 2") || *c == "Version 2")
    }) {
        return Err(Error::parse(
            what,
            file.lines[file.header].0,
            "no `... Retrievals, Version 2` line above the header: not an AERONET version 2 inversion file",
        ));
    }
    let site = preamble
        .iter()
        .flat_map(|(_, cells)| cells.iter())
        .find_map(|c| c.strip_prefix("Locations="))
        .unwrap_or("")
        .to_string();
    let date = file.column(what, "Date(")?;
    let time = file.column(what, "Time(")?;
    let header = file.header_cells();
    let named = |name: &str| header.iter().position(|c| *c == name);
    let wavelengths: Vec<(String, f64)> = header
        .iter()
        .filter_map(|c| {
            let nm = c.strip_prefix("REFR(")?.strip_suffix(')')?;
            Some((nm.to_string(), nm.parse::<f64>().ok()?))
        })
        .collect();
    let bins: Vec<(usize, f64)> = header
        .iter()
        .enumerate()
        .filter_map(|(i, c)| {
            let radius = c.parse::<f64>().ok()?;
            (radius > 0.0).then_some((i, radius))
        })
        .collect();
    let volume = named("VolCon-T");
    let mut rows = Vec::new();
    for (line, cells) in file.data_lines(0) {
        let number = |column: Option<usize>, name: &str| -> Result<Option<f64>> {
            column.map_or(Ok(None), |i| aeronet_number(cells, i, name, what, *line))
        };
        let mut channels = Vec::new();
        for (nm, wavelength_nm) in &wavelengths {
            let column = |name: String| -> Result<Option<f64>> { number(named(&name), &name) };
            channels.push(AeronetInversionChannel {
                wavelength_nm: *wavelength_nm,
                refractive_index_real: column(format!("REFR({nm})"))?,
                refractive_index_imaginary: column(format!("REFI({nm})"))?,
                single_scattering_albedo: column(format!("SSA{nm}-T"))?,
                extinction_optical_depth: column(format!("AOTExt{nm}-T"))?,
            });
        }
        let mut size_distribution = Vec::new();
        for &(column, radius_um) in &bins {
            if let Some(v) = number(Some(column), header[column])? {
                size_distribution.push((radius_um, v));
            }
        }
        rows.push(AeronetInversion {
            time: aeronet_time(cells, date, time, what, *line)?,
            site: site.clone(),
            channels,
            size_distribution,
            volume_concentration_um3_um2: number(volume, "VolCon-T")?,
        });
    }
    if rows.is_empty() {
        return Err(Error::parse(what, 0, "no retrieval rows after the header"));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(result: Result<impl std::fmt::Debug>) -> String {
        result.unwrap_err().to_string()
    }

    #[test]
    fn aeronet_time_parses_both_date_spellings() {
        let t = AeronetTime::parse("03:01:2019", "11:11:49").unwrap();
        assert_eq!(t.to_string(), "2019-01-03 11:11:49");
        assert_eq!(AeronetTime::parse("03-01-2019", "11:11:49"), Some(t));
        // 2019-01-03 00:00 UTC is 1546473600 s after the epoch.
        assert_eq!(t.unix_seconds(), 1_546_473_600 + 11 * 3600 + 11 * 60 + 49);
        assert!(AeronetTime::parse("2019-01-03", "11:11").is_none());
        assert!(AeronetTime::parse("32:01:2019", "11:11:49").is_none());
    }

    /// A small almucantar file in the older version 3 layout (synthetic
    /// numbers): one scan at two wavelengths, a 1640 nm row, a second scan
    /// all -999.
    const ALM: &str = "\
AERONET Version 3;
Version 3: Raw Almucantar
AERONET_Site,Date(dd:mm:yyyy),Time(hh:mm:ss),Instrument_Number,Nominal_Wavelength(nm),Exact_Wavelength(um),Solar_Zenith_Angle(Degrees),Sky_Scan_Type,0.000000,2.000000,6.000000,-6.000000,30.000000,-30.000000,6.000000
Site_A,10:06:2020,09:00:00,100,440,0.4402,60.000000,Almucantar,-999.,500.0,20.0,22.0,5.0,-999.000000,21.0
Site_A,10:06:2020,09:03:00,100,675,0.6751,59.500000,Almucantar,-999.,300.0,10.0,10.0,2.0,2.2,-999
Site_A,10:06:2020,09:04:00,100,1640,1.6400,59.400000,Almucantar,-999.,300.0,10.0,10.0,2.0,2.2,10.0
Site_A,10:06:2020,11:00:00,100,440,0.4402,40.000000,Almucantar,-999.,-999.,-999.,-999.,-999.,-999.,-999.
";

    #[test]
    fn almucantar_groups_scans_converts_units_and_skips_missing() {
        let sky = parse_aeronet_sky(ALM, AeronetScan::Almucantar, "f.alm", 0.05).unwrap();
        assert_eq!(sky.scans.len(), 1, "{:?}", sky.notes);
        let scan = &sky.scans[0];
        assert_eq!(scan.site, "Site_A");
        assert_eq!(
            scan.measurements.label,
            "Site_A 2020-06-10 09:00:00 almucantar"
        );
        assert_eq!(scan.measurements.wavelengths_nm(), [440.0, 675.0]);
        let at = |nm: f64, azimuth: f64| {
            scan.measurements
                .sky
                .iter()
                .find(|m| m.wavelength_nm == nm && (m.view_azimuth_deg - azimuth).abs() < 1e-9)
                .copied()
        };
        // 6 deg measured twice at 440 nm: averaged, then uW cm^-2 -> W m^-2.
        let m = at(440.0, 186.0).unwrap();
        assert!((m.radiance_w_m2_sr_nm - 0.205).abs() < 1e-12);
        assert!((m.uncertainty_w_m2_sr_nm - 0.05 * 0.205).abs() < 1e-12);
        assert_eq!(m.view_elevation_deg, 30.0);
        assert_eq!(m.sun_elevation_deg, 30.0);
        assert_eq!(m.sun_azimuth_deg, AERONET_SUN_AZIMUTH_DEG);
        // Negative angles on the other side of the sun.
        assert!((at(440.0, 174.0).unwrap().radiance_w_m2_sr_nm - 0.22).abs() < 1e-12);
        assert!((at(440.0, 210.0).unwrap().radiance_w_m2_sr_nm - 0.05).abs() < 1e-12);
        // -999 skipped: no -30 deg at 440 nm.
        assert!(at(440.0, 150.0).is_none());
        assert!((at(675.0, 150.0).unwrap().radiance_w_m2_sr_nm - 0.022).abs() < 1e-12);
        // 675 nm at its own sun elevation.
        assert_eq!(at(675.0, 150.0).unwrap().sun_elevation_deg, 30.5);
        // 2 deg of azimuth at 30 deg elevation is 1.7 deg from the sun.
        assert!(at(440.0, 182.0).is_none());
        assert_eq!(scan.measurements.sky.len(), 3 + 4);
        let notes = sky.notes.join("\n");
        assert!(notes.contains("1640 nm left out"), "{notes}");
        assert!(notes.contains("2 points closer than 3 deg"), "{notes}");
        assert!(
            notes.contains("Site_A 2020-06-10 11:00:00 almucantar (lines 7-7): dropped"),
            "{notes}"
        );
        scan.measurements.validate().unwrap();
    }

    #[test]
    fn principal_plane_angles_go_from_below_the_sun_over_the_zenith() {
        let ppl = "\
AERONET_Site,Date(dd:mm:yyyy),Time(hh:mm:ss),Instrument_Number,Nominal_Wavelength(nm),Exact_Wavelength(um),Solar_Zenith_Angle(Degrees),Sky_Scan_Type,-6.000000,0.000000,6.000000,90.000000,150.000000,
Site_B,03:01:2019,11:11:49,620,870,0.8700,72.000000,Principal Plane,22.0,-999.000000,11.0,0.09,0.5
";
        let sky = parse_aeronet_sky(ppl, AeronetScan::PrincipalPlane, "f.ppl", 0.05).unwrap();
        let m = &sky.scans[0].measurements;
        assert_eq!(m.sky.len(), 4);
        let view = |i: usize| (m.sky[i].view_elevation_deg, m.sky[i].view_azimuth_deg);
        // -6: below the sun (elevation 18 - 6), sun's side.
        assert!((view(0).0 - 12.0).abs() < 1e-9 && view(0).1 == 180.0);
        assert!((view(1).0 - 24.0).abs() < 1e-9 && view(1).1 == 180.0);
        // +90 from zenith angle 72: 18 deg past the zenith, opposite side.
        assert!((view(2).0 - 72.0).abs() < 1e-9 && view(2).1 == 0.0);
        assert!((view(3).0 - 12.0).abs() < 1e-9 && view(3).1 == 0.0);
        assert!((m.sky[2].scattering_angle_deg() - 90.0).abs() < 1e-9);
        assert!((m.sky[3].radiance_w_m2_sr_nm - 0.005).abs() < 1e-12);
        // An almucantar reader given this file leaves the scans out.
        let e = error(parse_aeronet_sky(
            ppl,
            AeronetScan::Almucantar,
            "f.ppl",
            0.05,
        ));
        assert!(
            e.contains("no usable almucantar scan") && e.contains("'Principal Plane'"),
            "{e}"
        );
    }

    #[test]
    fn aeronet_bad_files_are_one_line_errors() {
        let e = error(parse_aeronet_sky(
            "just,some,text\n1,2,3\n",
            AeronetScan::Almucantar,
            "x.alm",
            0.05,
        ));
        assert!(
            e.contains("x.alm") && e.contains("not an AERONET almucantar file"),
            "{e}"
        );
        let all_missing = "Date(dd:mm:yyyy),Time(hh:mm:ss),Nominal_Wavelength(nm),Solar_Zenith_Angle(Degrees),6.0,-6.0\n\
                           10:06:2020,09:00:00,440,60,-999.,-999.\n";
        let e = error(parse_aeronet_sky(
            all_missing,
            AeronetScan::Almucantar,
            "x.alm",
            0.05,
        ));
        assert!(
            e.contains("no usable almucantar scan") && e.contains("all -999"),
            "{e}"
        );
        let no_angles = "Date(dd:mm:yyyy),Time(hh:mm:ss),Nominal_Wavelength(nm),Solar_Zenith_Angle(Degrees)\n\
                         10:06:2020,09:00:00,440,60\n";
        let e = error(parse_aeronet_sky(
            no_angles,
            AeronetScan::Almucantar,
            "x.alm",
            0.05,
        ));
        assert!(e.contains("no usable angles"), "{e}");
        let negative = "Date(dd:mm:yyyy),Time(hh:mm:ss),Nominal_Wavelength(nm),Solar_Zenith_Angle(Degrees),10.0,-10.0\n\
                        10:06:2020,09:00:00,440,60,-5,3\n";
        let e = error(parse_aeronet_sky(
            negative,
            AeronetScan::Almucantar,
            "x.alm",
            0.05,
        ));
        assert!(
            e.contains("negative radiance") && e.contains("440 nm"),
            "{e}"
        );
        let bad_date = "Date(dd:mm:yyyy),Time(hh:mm:ss),Nominal_Wavelength(nm),Solar_Zenith_Angle(Degrees),10.0\n\
                        2020-06-10,09:00:00,440,60,3\n";
        let e = error(parse_aeronet_sky(
            bad_date,
            AeronetScan::Almucantar,
            "x.alm",
            0.05,
        ));
        assert!(e.contains("line 2") && e.contains("not dd:mm:yyyy"), "{e}");
    }

    #[test]
    fn a_solar_azimuth_column_is_used_when_there_is_one() {
        let alm = "Date(dd:mm:yyyy),Time(hh:mm:ss),Nominal_Wavelength(nm),Solar_Zenith_Angle(Degrees),Solar_Azimuth_Angle(Degrees),10.0,-10.0\n\
                   10:06:2020,09:00:00,440,60,100,5.0,4.0\n";
        let sky = parse_aeronet_sky(alm, AeronetScan::Almucantar, "a.alm", 0.05).unwrap();
        let m = &sky.scans[0].measurements;
        assert_eq!(m.sky[0].sun_azimuth_deg, 100.0);
        assert_eq!(m.sky[0].view_azimuth_deg, 110.0);
        assert_eq!(m.sky[1].view_azimuth_deg, 90.0);
    }

    #[test]
    fn web_service_markup_and_n_a_are_ignored() {
        let alm = "<html><body><div>AERONET Version 3;<br>\n\
Date(dd:mm:yyyy),Time(hh:mm:ss),Nominal_Wavelength(nm),Solar_Zenith_Angle(Degrees),10.0,-10.0,20.0<br>\n\
10:06:2020,09:00:00,440,60,5.0,N/A,4.0<br>\n\
</div></body></html>\n";
        let sky = parse_aeronet_sky(alm, AeronetScan::Almucantar, "w.alm", 0.05).unwrap();
        let m = &sky.scans[0].measurements;
        assert_eq!(m.sky.len(), 2);
        assert!((m.sky[1].radiance_w_m2_sr_nm - 0.04).abs() < 1e-12);
    }

    #[test]
    fn newer_layout_reads_only_the_radiance_section() {
        let alm = "\
AERONET Version 3;
Radiance_for_Azimuth_Angle_in_Degrees(uW/cm^2/sr/nm),,,,,,,,,,,,,Scattering_Angle_for_Nominal_Azimuth_Angle(Degrees),
AERONET_Site,Date(dd:mm:yyyy),Time(hh:mm:ss),Instrument_Number,Nominal_Wavelength(nm),Exact_Wavelength(um),Solar_Zenith_Angle(Degrees),Sky_Scan_Type,Latitude(Degrees),Longitude(Degrees),Elevation(m),10.000,-10.000,10.000,-10.000
Site_C,10:06:2020,09:00:00,1,500,0.5,60,Almucantar,45.0,7.0,300.0,8.0,9.0,8.7,8.7
";
        let sky = parse_aeronet_sky(alm, AeronetScan::Almucantar, "c.alm", 0.05).unwrap();
        let m = &sky.scans[0].measurements;
        assert_eq!(m.sky.len(), 2);
        assert!((m.sky[0].radiance_w_m2_sr_nm - 0.08).abs() < 1e-12);
        assert!((m.sky[1].radiance_w_m2_sr_nm - 0.09).abs() < 1e-12);
    }

    const AOD: &str = "\
AERONET Version 3;
Site_A
Version 3: AOD Level 1.5
The following data are cloud cleared (synthetic test rows).
Contact: PI=nobody; PI Email=nobody@example.org
All Points,UNITS can be found at,,, https://aeronet.gsfc.nasa.gov/new_web/units.html
AERONET_Site,Date(dd:mm:yyyy),Time(hh:mm:ss),Day_of_Year,AOD_1020nm,AOD_870nm,AOD_675nm,AOD_500nm,AOD_440nm,Precipitable_Water(cm),Exact_Wavelengths_of_AOD(um)_440nm
Site_A,10:06:2020,08:20:00,162,0.05,0.06,0.08,0.10,0.12,1.5,0.4402
Site_A,10:06:2020,09:10:00,162,0.06,-999.000000,0.09,0.11,0.13,1.5,0.4402
Site_A,10:06:2020,12:00:00,162,-999.,-999.,-999.,-999.,-999.,1.5,0.4402
";

    #[test]
    fn aod_file_parses_channels_and_skips_missing() {
        let entries = parse_aeronet_aod(AOD, "f.lev15").unwrap();
        assert_eq!(entries.len(), 2);
        assert_eq!(entries[0].optical_depths.len(), 5);
        assert_eq!(entries[0].optical_depths[4], (440.0, 0.12));
        assert_eq!(entries[1].optical_depths.len(), 4);
        assert!(entries[1].optical_depths.iter().all(|&(nm, _)| nm != 870.0));
        assert_eq!(entries[1].time.to_string(), "2020-06-10 09:10:00");
        let e = error(parse_aeronet_aod(
            "Date(dd:mm:yyyy),Time(hh:mm:ss),x\n",
            "a",
        ));
        assert!(
            e.contains("no AOD_<n>nm (version 3) or AOT_<n> (version 2) columns"),
            "{e}"
        );
    }

    #[test]
    fn nearest_aod_is_attached_and_missing_channels_interpolated() {
        let mut sky = parse_aeronet_sky(ALM, AeronetScan::Almucantar, "f.alm", 0.05).unwrap();
        let entries = parse_aeronet_aod(AOD, "f.lev15").unwrap();
        let notes = attach_nearest_optical_depths(&mut sky.scans, &entries);
        assert!(notes.is_empty(), "{notes:?}");
        let depths = &sky.scans[0].measurements.optical_depths;
        // 09:10 is nearer to 09:00 than 08:20.
        assert_eq!(depths.len(), 2);
        assert_eq!(depths[0].wavelength_nm, 440.0);
        assert_eq!(depths[0].aerosol_optical_depth, 0.13);
        assert_eq!(depths[1].aerosol_optical_depth, 0.09);
        assert_eq!(depths[0].uncertainty, AERONET_AOD_UNCERTAINTY);
        sky.scans[0].measurements.validate().unwrap();

        // 870 nm missing in the nearest entry: Angstrom law between 675 and 1020.
        let entry = &entries[1];
        let tau = optical_depth_at(entry, 870.0).unwrap();
        let alpha = -(0.06f64 / 0.09).ln() / (1020.0f64 / 675.0).ln();
        assert!((tau - 0.09 * (870.0f64 / 675.0).powf(-alpha)).abs() < 1e-12);
        assert!(optical_depth_at(entry, 380.0).is_none());

        // Too far in time: none attached, and said so.
        let late: Vec<AeronetOpticalDepths> = entries
            .iter()
            .map(|e| AeronetOpticalDepths {
                time: AeronetTime {
                    second_of_day: e.time.second_of_day + 3 * 3600,
                    ..e.time
                },
                ..e.clone()
            })
            .collect();
        let notes = attach_nearest_optical_depths(&mut sky.scans, &late);
        assert!(sky.scans[0].measurements.optical_depths.is_empty());
        assert!(
            notes[0].contains("no optical depth of this site within 30 min"),
            "{notes:?}"
        );
    }

    #[test]
    fn aeronet_times_count_seconds_by_the_suns_calendar() {
        let at = |year, month, day, second_of_day| AeronetTime {
            year,
            month,
            day,
            second_of_day,
        };
        // `date -u -d 2019-07-31T12:00:00Z +%s` and the leap day of 2000.
        assert_eq!(at(2019, 7, 31, 43_200).unix_seconds(), 1_564_574_400);
        assert_eq!(at(2000, 2, 29, 0).unix_seconds(), 951_782_400);
        assert_eq!(at(1970, 1, 1, 1).unix_seconds(), 1);
    }

    /// The real version 2 inversion sample (Karlsruhe, daily average of
    /// 23 March 2005, level 2.0; tests/data/aeronet/README.md): the
    /// channels' optical depths, n and k missing as the file has them, and
    /// the 22-bin size distribution, whose trapezoid integral over ln r is
    /// the file's own total volume concentration (0.056, to its rounding).
    #[test]
    fn version_2_inversion_file_parses() {
        let text = include_str!("../../../tests/data/aeronet/inv_v2_karlsruhe_20050323.dubovikday");
        let rows = parse_aeronet_inversion(text, "inv").unwrap();
        assert_eq!(rows.len(), 1);
        let row = &rows[0];
        assert_eq!(row.site, "Karlsruhe");
        assert_eq!(row.time.to_string(), "2005-03-23 00:00:00");
        let wavelengths: Vec<f64> = row.channels.iter().map(|c| c.wavelength_nm).collect();
        assert_eq!(wavelengths, [440.0, 675.0, 870.0, 1018.0]);
        let depths: Vec<Option<f64>> = row
            .channels
            .iter()
            .map(|c| c.extinction_optical_depth)
            .collect();
        assert_eq!(
            depths,
            [
                Some(0.298250),
                Some(0.161350),
                Some(0.108300),
                Some(0.083750)
            ]
        );
        for c in &row.channels {
            assert_eq!(c.refractive_index_real, None);
            assert_eq!(c.refractive_index_imaginary, None);
            assert_eq!(c.single_scattering_albedo, None);
        }
        assert_eq!(row.size_distribution.len(), 22);
        assert_eq!(row.size_distribution[0], (0.05, 0.000335));
        assert_eq!(row.size_distribution[21], (15.0, 0.000272));
        let h = (15.0f64 / 0.05).ln() / 21.0;
        let volume: f64 = row
            .size_distribution
            .iter()
            .enumerate()
            .map(|(i, (_, v))| {
                if i == 0 || i == 21 {
                    v * h / 2.0
                } else {
                    v * h
                }
            })
            .sum();
        let stated = row.volume_concentration_um3_um2.unwrap();
        assert_eq!(stated, 0.056);
        assert!((volume - stated).abs() < 0.0006, "{volume}");
        // A version 3 or other file is refused in one line.
        let error = parse_aeronet_inversion(
            "Date(dd:mm:yyyy),Time(hh:mm:ss),AOD_440nm\n01:01:2020,00:00:00,0.1\n",
            "v3",
        )
        .unwrap_err()
        .to_string();
        assert!(
            error.contains("not an AERONET version 2 inversion file"),
            "{error}"
        );
    }
}
