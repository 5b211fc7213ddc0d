//! Readers of measured sky radiances: text in, [`Measurements`](crate::inversion::Measurements) out.
//!
//! Three kinds of input, as issue 16 asks; every reader works on `&str`
//! (reading the file is the caller's business) and names the input (`what`)
//! and the 1-based line in its errors.
//!
//! ## (a) sora's own CSV
//!
//! [`parse_sky_radiance_csv`]: a header naming the seven columns
//! `wavelength_nm, sun_elevation_deg, sun_azimuth_deg, view_elevation_deg,
//! view_azimuth_deg, radiance_w_m2_sr_nm, uncertainty_w_m2_sr_nm` in any
//! order, then one measurement a line; radiances in W m^-2 sr^-1 nm^-1,
//! angles in degrees (elevation above the horizon, azimuth clockwise from
//! north), `#` comments and blank lines ignored. Measured optical depths
//! come in a second file, [`parse_optical_depth_csv`]: `wavelength_nm,
//! aerosol_optical_depth, uncertainty`, one wavelength a line, each at a
//! wavelength that has sky radiances.
//!
//! ## (b) AERONET version 3
//!
//! AERONET (<https://aeronet.gsfc.nasa.gov>) distributes its Cimel sun
//! photometers' sky scans as comma-separated text; no Rust crate reads
//! them, so the readers here are hand-written from the layouts of public
//! files (`tests/data/aeronet/README.md` says which). [`parse_aeronet_sky`]
//! reads the raw almucantar (`.alm`, web service product `ALM15`/`ALM20`)
//! and principal-plane (`.ppl`, `PPL15`/`PPL20`) files; both have a few
//! free-text lines, then a header line
//!
//! ```text
//! AERONET_Site,Date(dd:mm:yyyy),Time(hh:mm:ss),Instrument_Number,Nominal_Wavelength(nm),
//! Exact_Wavelength(um),Solar_Zenith_Angle(Degrees),Sky_Scan_Type,-6.000000,-5.000000,...
//! ```
//!
//! then one line per wavelength per scan, one radiance per angle column.
//! The angle columns are the bare numbers; newer files put a line of
//! section names (`Radiance_for_Azimuth_Angle_in_Degrees(uW/cm^2/sr/nm)`,
//! `Scattering_Angle_for_Nominal_Azimuth_Angle(Degrees)`) next to the
//! header, and then only the radiance section is read. Conventions:
//!
//! * Units: microwatts per square centimetre, per steradian, per nanometre;
//!   1 uW cm^-2 = 1e-6 W / 1e-4 m^2, so a radiance is multiplied by
//!   [`AERONET_RADIANCE_TO_W_M2_SR_NM`] = 0.01.
//! * `-999` (any spelling: `-999`, `-999.`, `-999.000000`), `N/A` and an
//!   empty cell are missing values and are skipped; the `<br>` and
//!   `<html>` wrapping of the web service's output is ignored.
//! * Almucantar: the angles are azimuths relative to the sun's, at the
//!   sun's elevation (`90 - Solar_Zenith_Angle`); the positive (`pos`) and
//!   negative (`neg`) columns are the scan's two branches, to either side
//!   of the sun. The files do not say which side is which; for a
//!   horizontally uniform atmosphere (sora's) the two branches are mirror
//!   images, so it does not matter: a positive angle is taken as clockwise,
//!   view azimuth = sun azimuth + angle.
//! * Principal plane: the angles are offsets from the sun along its
//!   vertical circle, negative below the sun (towards the horizon on the
//!   sun's side), positive above it, through the zenith and down the other
//!   side (no document found says so; a real file fixes the sign: its scan
//!   at solar zenith angle 73 deg goes to +150 deg, which is above the
//!   horizon only this way, and is brighter at -6 than at +6 deg).
//!   View zenith angle = solar zenith angle - offset; a negative one is on
//!   the side opposite the sun.
//! * The files give the solar zenith angle (per row: each wavelength is
//!   scanned at its own moment) but not the solar azimuth; the sun is put
//!   at azimuth [`AERONET_SUN_AZIMUTH_DEG`] = 180 deg (or at a
//!   `Solar_Azimuth_Angle...` column's value, should a file have one).
//!   Only the views' azimuths relative to the sun's matter to sora's
//!   forward model.
//! * Wavelengths are the nominal ones (`Nominal_Wavelength(nm)`: 440, 675,
//!   870, 1020, in newer instruments also 380, 500, 1640); the exact ones
//!   differ by a few nanometres at most. Channels outside the model's
//!   280..=1100 nm (1640 nm) are left out, and said so.
//! * A scan is the rows of one date and scan type taken within
//!   [`AERONET_SCAN_WINDOW_S`] of its first row, each wavelength once.
//! * Points closer to the sun than [`MIN_SCATTERING_ANGLE_DEG`](crate::inversion::MIN_SCATTERING_ANGLE_DEG) (AERONET
//!   measures from 2 deg) and principal-plane points below the horizon are
//!   left out, and counted in the notes; a direction measured twice in one
//!   scan (AERONET repeats the near-sun angles; 180 and -180 deg are one
//!   direction) is averaged.
//! * Each radiance's 1-sigma uncertainty is `relative_uncertainty` times
//!   the radiance (AERONET quotes about 5 % for its sky calibration).
//! * A scan left with no usable radiance is dropped and named in
//!   [`AeronetSky::notes`]; a file with no usable scan is an error.
//!
//! [`parse_aeronet_aod`] reads the direct-sun aerosol optical depth file
//! (`.lev15`, `.lev20`, web service `AOD15`/`AOD20`): free-text lines, then a
//! header with `Date(dd:mm:yyyy)`, `Time(hh:mm:ss)` and one `AOD_<n>nm`
//! column per channel (`AOD_1640nm` ... `AOD_340nm`), `-999` where a channel
//! was not measured. Version 2 files (`Version 2 Direct Sun Algorithm`)
//! read the same way: their header has `Date(dd-mm-yy)` (the rows are
//! `dd:mm:yyyy` all the same), `Time(hh:mm:ss)` and `AOT_<n>` columns
//! (`AOT_1640` ... `AOT_340`), `-9999.` where a channel was not measured. [`attach_nearest_optical_depths`] gives each sky scan
//! the optical depths measured nearest to it in time, within
//! [`AOD_MATCH_WINDOW_S`], at the scan's own wavelengths (interpolated in
//! log-log, the Angstrom law, between the nearest channels either side
//! when the channel itself is missing).
//!
//! ## (c) A normalised spectrum in one direction
//!
//! [`parse_normalised_spectrum_csv`] reads `wavelength_nm,
//! relative_radiance` measured in one direction (as in the paper's Fig. 2)
//! into a [`RadianceScale::Relative`](crate::inversion::RadianceScale::Relative) set. What it can tell: only the
//! spectral shape of the sky in that one direction, that is the colour of
//! the mixture of Rayleigh and aerosol scattering there. With the absolute
//! level gone and a single scattering angle, the aerosol's amount, its size
//! (through its Angstrom exponent) and its phase function at that angle
//! trade off against each other: at most one aerosol parameter (an optical
//! depth with the size fixed, or an Angstrom exponent with the amount
//! fixed) can be fitted, and its uncertainty must come out large (ozone,
//! the ground's albedo and multiple scattering colour the same spectrum).
//! It cannot give a size distribution, an absorption, or the amount and
//! size together.

mod aeronet;
mod csv;

pub use aeronet::{
    AERONET_AOD_UNCERTAINTY, AERONET_RADIANCE_TO_W_M2_SR_NM, AERONET_SCAN_WINDOW_S,
    AERONET_SUN_AZIMUTH_DEG, AOD_MATCH_WINDOW_S, AeronetInversion, AeronetInversionChannel,
    AeronetOpticalDepths, AeronetScan, AeronetSky, AeronetSkyScan, AeronetTime,
    attach_nearest_optical_depths, parse_aeronet_aod, parse_aeronet_inversion, parse_aeronet_sky,
};
pub use csv::{
    NORMALISED_SPECTRUM_COLUMNS, OPTICAL_DEPTH_COLUMNS, SKY_RADIANCE_COLUMNS, SkyGeometry,
    parse_normalised_spectrum_csv, parse_optical_depth_csv, parse_sky_radiance_csv,
};
