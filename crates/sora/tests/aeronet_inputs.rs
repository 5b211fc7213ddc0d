//! The retrieval's readers on AERONET version 3 sample files
//! (`tests/data/aeronet/`, provenance in its README): units converted,
//! -999 skipped, the principal plane's signed angles and the almucantar's
//! two branches placed in the sky, scans grouped, the nearest optical
//! depths of the same site attached.

use sora::inversion::{
    AeronetScan, MIN_SCATTERING_ANGLE_DEG, attach_nearest_optical_depths, parse_aeronet_aod,
    parse_aeronet_sky,
};

const PPL: &str = include_str!("data/aeronet/ppl_arm_graciosa_20190103.ppl");
const ALM: &str = include_str!("data/aeronet/alm_synthetic_karlsruhe_20050321.alm");
const AOD: &str = include_str!("data/aeronet/aod_karlsruhe_20050321.lev15");
const AOD_V2: &str = include_str!("data/aeronet/aod_v2_zvenigorod_20060916.lev20");

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1e-12)
}

/// The real principal-plane row: 1020 nm, solar zenith angle 72.85 deg.
#[test]
fn real_principal_plane_row_lands_in_the_right_directions() {
    let sky = parse_aeronet_sky(PPL, AeronetScan::PrincipalPlane, "graciosa.ppl", 0.05).unwrap();
    assert_eq!(sky.scans.len(), 1);
    let scan = &sky.scans[0];
    assert_eq!(scan.site, "ARM_Graciosa");
    assert_eq!(
        scan.measurements.label,
        "ARM_Graciosa 2019-01-03 11:11:49 principal plane"
    );
    let m = &scan.measurements;
    assert_eq!(m.wavelengths_nm(), [1020.0]);
    let sun_elevation = 90.0 - 72.852854;
    assert!(
        m.sky
            .iter()
            .all(|s| close(s.sun_elevation_deg, sun_elevation))
    );
    // Nothing inside the 3 deg exclusion, nothing below the horizon.
    assert!(
        m.sky
            .iter()
            .all(|s| s.scattering_angle_deg() >= MIN_SCATTERING_ANGLE_DEG)
    );
    assert!(m.sky.iter().all(|s| s.view_elevation_deg >= 0.0));
    let find = |elevation: f64, azimuth: f64| {
        m.sky
            .iter()
            .find(|s| {
                (s.view_elevation_deg - elevation).abs() < 1e-6
                    && (s.view_azimuth_deg - azimuth).abs() < 1e-6
            })
            .unwrap_or_else(|| panic!("no view at ({elevation}, {azimuth})"))
    };
    // -6: below the sun, on its side: 22.964095 uW cm^-2 sr^-1 nm^-1.
    let below = find(sun_elevation - 6.0, 180.0);
    assert!(close(below.radiance_w_m2_sr_nm, 0.22964095));
    assert!(close(below.uncertainty_w_m2_sr_nm, 0.05 * 0.22964095));
    // +90: 17.15 deg past the zenith, on the side opposite the sun.
    let past_zenith = find(90.0 - (90.0 - 72.852854), 0.0);
    assert!(close(past_zenith.radiance_w_m2_sr_nm, 0.00078597));
    assert!((past_zenith.scattering_angle_deg() - 90.0).abs() < 1e-9);
    // +6 measured twice (10.981215, 10.975812): averaged.
    let above = find(sun_elevation + 6.0, 180.0);
    assert!(close(
        above.radiance_w_m2_sr_nm,
        0.5 * (10.981215 + 10.975812) * 0.01
    ));
    // The brightest point left is 3 deg or more from the sun: -3 deg.
    let brightest = m
        .sky
        .iter()
        .map(|s| s.radiance_w_m2_sr_nm)
        .fold(0.0, f64::max);
    assert!(brightest <= 0.36746262 + 1e-12);
    let notes = sky.notes.join("\n");
    assert!(
        notes.contains("closer than 3 deg to the sun left out"),
        "{notes}"
    );
}

#[test]
fn synthetic_almucantar_groups_one_scan_and_notes_what_it_left_out() {
    let sky = parse_aeronet_sky(ALM, AeronetScan::Almucantar, "karlsruhe.alm", 0.05).unwrap();
    assert_eq!(sky.scans.len(), 1, "{:?}", sky.notes);
    let m = &sky.scans[0].measurements;
    assert_eq!(m.label, "Karlsruhe 2005-03-21 16:30:00 almucantar");
    assert_eq!(m.wavelengths_nm(), [440.0, 675.0, 870.0, 1020.0]);
    m.validate().unwrap();
    // 39 angle columns: the sun (-999), 6 within 3 deg of it at this sun
    // elevation (+-2, +-2.5, +-3 deg of azimuth at 10.7 deg elevation), 3
    // repeated directions (6, -6, 180 = -180); 1020 nm also lacks 45 deg.
    let count = |nm: f64| m.sky.iter().filter(|s| s.wavelength_nm == nm).count();
    assert_eq!(
        [count(440.0), count(675.0), count(870.0), count(1020.0)],
        [29, 29, 29, 28]
    );
    // The almucantar is at the sun's elevation, each wavelength its own.
    for s in &m.sky {
        assert_eq!(s.view_elevation_deg, s.sun_elevation_deg);
    }
    let at_440 = m
        .sky
        .iter()
        .find(|s| s.wavelength_nm == 440.0)
        .unwrap()
        .sun_elevation_deg;
    assert!(close(at_440, 90.0 - 79.3));
    // Both branches, +90 and -90 deg from the sun: 7.205719 uW cm^-2 ...
    for azimuth in [270.0, 90.0] {
        let s = m
            .sky
            .iter()
            .find(|s| s.wavelength_nm == 440.0 && (s.view_azimuth_deg - azimuth).abs() < 1e-9)
            .unwrap();
        assert!(close(s.radiance_w_m2_sr_nm, 0.07205719));
    }
    let notes = sky.notes.join("\n");
    assert!(notes.contains("channels at 1640 nm left out"), "{notes}");
    assert!(
        notes.contains("1 rows of 'Hybrid' scans left out"),
        "{notes}"
    );
    assert!(
        notes.contains("Karlsruhe 2005-03-21 17:10:00 almucantar (lines 7-7): dropped"),
        "{notes}"
    );
}

#[test]
fn real_aod_row_is_attached_to_the_scan_of_its_site_nearest_in_time() {
    let entries = parse_aeronet_aod(AOD, "karlsruhe.lev15").unwrap();
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[1].site, "Karlsruhe");
    // Channels measured in the real row: 1020, 870, 675, 500, 440, 380, 340.
    let nm: Vec<f64> = entries[1].optical_depths.iter().map(|d| d.0).collect();
    assert_eq!(nm, [1020.0, 870.0, 675.0, 500.0, 440.0, 380.0, 340.0]);

    let mut alm = parse_aeronet_sky(ALM, AeronetScan::Almucantar, "karlsruhe.alm", 0.05).unwrap();
    let notes = attach_nearest_optical_depths(&mut alm.scans, &entries);
    assert!(notes.is_empty(), "{notes:?}");
    let m = &alm.scans[0].measurements;
    // 16:35:13 (5 min away) rather than 16:02:00 (28 min away).
    let depths: Vec<(f64, f64)> = m
        .optical_depths
        .iter()
        .map(|d| (d.wavelength_nm, d.aerosol_optical_depth))
        .collect();
    assert_eq!(
        depths,
        [
            (440.0, 0.252361),
            (675.0, 0.220243),
            (870.0, 0.217887),
            (1020.0, 0.217930)
        ]
    );
    m.validate().unwrap();

    // Another site's optical depths are not attached, and that is said.
    let mut ppl =
        parse_aeronet_sky(PPL, AeronetScan::PrincipalPlane, "graciosa.ppl", 0.05).unwrap();
    let notes = attach_nearest_optical_depths(&mut ppl.scans, &entries);
    assert!(ppl.scans[0].measurements.optical_depths.is_empty());
    assert!(
        notes[0].starts_with("ARM_Graciosa 2019-01-03 11:11:49 principal plane: no optical depth"),
        "{notes:?}"
    );
}

/// A real version 2 row: `AOT_<n>` columns, `-9999.` where not measured,
/// the site on the `Location=` line, `dd:mm:yyyy` under a
/// `Date(dd-mm-yy)` header.
#[test]
fn version_2_optical_depths_are_read() {
    let entries = parse_aeronet_aod(AOD_V2, "zvenigorod.lev20").unwrap();
    assert_eq!(entries.len(), 1);
    let entry = &entries[0];
    assert_eq!(entry.site, "Zvenigorod");
    assert_eq!(
        (
            entry.time.year,
            entry.time.month,
            entry.time.day,
            entry.time.second_of_day
        ),
        (2006, 9, 16, 0)
    );
    // Measured: 1020, 870, 675, 500, 440, 380, 340 nm (1640, 667, 555,
    // 551, 532, 531, 490, 443 and 412 are -9999.).
    assert_eq!(
        entry.optical_depths,
        [
            (1020.0, 0.036045),
            (870.0, 0.036734),
            (675.0, 0.039337),
            (500.0, 0.064670),
            (440.0, 0.069614),
            (380.0, 0.083549),
            (340.0, 0.092204)
        ]
    );
}
