//! The banded gases' direct beam against a line-by-line reference (issue 36).
//!
//! `data/gas_line_by_line_reference.csv` (written by
//! `scripts/gases/make_lbl_reference.py` from HITRAN 2016 lines through the
//! U.S. Standard Atmosphere 1976, a spherical shell of radius 6360 km)
//! holds the direct-beam transmittance T of the O2 A band averaged over 10
//! and 20 nm bands, for the sun at 60 and 15 degrees. Here sora's is computed for the
//! same cases: the direct normal irradiance of a Rayleigh atmosphere (the
//! same U.S. standard air, radius 6360 km) with `[gases]` (the O2 and CO2
//! bands, no water) over that of the atmosphere without, summed over the
//! k-terms by the sky itself, averaged over the 1 nm samples whose bands
//! tile the band, and also read at the band's centre on a grid of the
//! band's width (what one sample of a 10 or 20 nm grid gives). The error is
//! in units of the reference's absorption 1 - T.

use sora::spectrum::WavelengthGrid;
use sora::{Atmosphere, Sky};

const REFERENCE: &str = include_str!("data/gas_line_by_line_reference.csv");
const AIR: &str = include_str!("data/atmosphere_us-standard-1976-rayleigh.toml");

/// One row of the reference.
struct Case {
    lo_nm: f64,
    hi_nm: f64,
    gas: String,
    elevation_deg: f64,
    transmittance: f64,
}

fn reference() -> Vec<Case> {
    let mut lines = REFERENCE
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (lo, hi, gas, elevation, t) = (
        column("band_lo_nm"),
        column("band_hi_nm"),
        column("gas"),
        column("sun_elevation_deg"),
        column("transmittance"),
    );
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            Case {
                lo_nm: f[lo].parse().unwrap(),
                hi_nm: f[hi].parse().unwrap(),
                gas: f[gas].to_string(),
                elevation_deg: f[elevation].parse().unwrap(),
                transmittance: f[t].parse().unwrap(),
            }
        })
        .collect()
}

/// The U.S. standard Rayleigh air on sora's Earth radius, with `gases` as
/// its `[gases]` table when given.
fn atmosphere(gases: Option<&str>) -> Atmosphere {
    let air = AIR.replace("radius_m = 6370e3", "radius_m = 6360e3");
    assert!(air.contains("radius_m = 6360e3"));
    let text = match gases {
        Some(table) => format!("{air}\n[gases]\n{table}\n"),
        None => air,
    };
    Atmosphere::from_toml_str(&text).unwrap()
}

/// sora's direct-beam transmittance of `gases` alone on `grid`, sun at
/// `elevation_deg`.
fn gas_transmittance(gases: &str, grid: WavelengthGrid, elevation_deg: f64) -> Vec<f64> {
    let direct = |atmosphere: &Atmosphere| {
        Sky::builder(atmosphere)
            .sun_deg(elevation_deg, 180.0)
            .wavelengths(grid)
            .build()
            .unwrap()
            .direct_normal_irradiance()
    };
    let (with, without) = (direct(&atmosphere(Some(gases))), direct(&atmosphere(None)));
    (0..grid.len()).map(|i| with[i] / without[i]).collect()
}

/// sora against one reference case: (band mean, band centre) transmittance.
/// The band mean is the plain mean of the 1 nm samples whose bands (each
/// sample stands for the 1 nm around it) tile the band; the band centre is
/// the one sample of a grid of the band's width there (what a user on a
/// 10 nm grid gets at that wavelength).
fn sora_case(case: &Case) -> (f64, f64) {
    let gases = match case.gas.as_str() {
        "O2" => "precipitable_water_cm = 0",
        other => panic!("no sora case for gas {other}"),
    };
    let grid = WavelengthGrid::new(case.lo_nm + 0.5, case.hi_nm - 0.5, 1.0).unwrap();
    let t = gas_transmittance(gases, grid, case.elevation_deg);
    let mean = t.iter().sum::<f64>() / t.len() as f64;
    let width = case.hi_nm - case.lo_nm;
    let centre = 0.5 * (case.lo_nm + case.hi_nm);
    let one = WavelengthGrid::new(centre, centre, width).unwrap();
    let centre = gas_transmittance(gases, one, case.elevation_deg)[0];
    (mean, centre)
}

/// Error of `t` in units of the reference's absorption, percent.
fn error_percent(t: f64, reference: f64) -> f64 {
    100.0 * ((1.0 - t) - (1.0 - reference)) / (1.0 - reference)
}

/// Each case: the reference's 1 - T and sora's 1 - T (band mean, band
/// centre), printed as a table.
fn comparison() -> Vec<(Case, f64, f64)> {
    println!("band nm   sun  ref 1-T  sora 1-T (mean, centre)  error % of 1-T (mean, centre)");
    reference()
        .into_iter()
        .map(|case| {
            let (mean, centre) = sora_case(&case);
            println!(
                "{}-{} {:>4} {:.4}  {:.4} {:.4}  {:+.1} {:+.1}",
                case.lo_nm,
                case.hi_nm,
                case.elevation_deg,
                1.0 - case.transmittance,
                1.0 - mean,
                1.0 - centre,
                error_percent(mean, case.transmittance),
                error_percent(centre, case.transmittance)
            );
            (case, mean, centre)
        })
        .collect()
}

#[test]
fn the_reference_is_a_curve_of_growth_and_sora_reads_it() {
    // The reference's own physics: each band absorbs more for the lower sun,
    // but less than in proportion to the air mass (its strong lines are
    // saturated); the band of the P branch (760-770 nm) absorbs most. sora's
    // transmittances are computed for every case and lie in (0, 1), lower
    // for the lower sun.
    let rows = comparison();
    assert_eq!(rows.len(), 14);
    let air_mass = |e: f64| 1.0 / e.to_radians().sin();
    for pair in rows.chunks(2) {
        let [(high, sora_high, _), (low, sora_low, _)] = pair else {
            unreachable!()
        };
        assert_eq!((high.elevation_deg, low.elevation_deg), (60.0, 15.0));
        assert_eq!((high.lo_nm, high.hi_nm), (low.lo_nm, low.hi_nm));
        let ratio = (1.0 - low.transmittance) / (1.0 - high.transmittance);
        assert!(
            ratio > 1.2 && ratio < air_mass(15.0) / air_mass(60.0),
            "{}-{} nm: {ratio}",
            low.lo_nm,
            low.hi_nm
        );
        assert!(0.0 < *sora_low && sora_low < sora_high && *sora_high < 1.0);
    }
    let ten = |c: &Case| c.hi_nm - c.lo_nm == 10.0;
    let core = rows.iter().filter(|(c, ..)| c.lo_nm == 760.0 && ten(c));
    for (case, ..) in core {
        let others = rows
            .iter()
            .filter(|(c, ..)| ten(c) && c.lo_nm != 760.0 && c.elevation_deg == case.elevation_deg);
        for (other, ..) in others {
            assert!(case.transmittance < other.transmittance);
        }
    }
}

/// The first "Done when" of issue 36 for the O2 A band: sora's band-mean
/// direct beam within 2 % of the line-by-line absorption. sora's O2 in
/// 749.5-780 nm is k-terms fitted to the same lines (`atmosphere/o2_a_band.rs`:
/// 0.5 nm bins, each with five weights and coefficients of its own,
/// re-sorted into each sample's band and fitted there with the band's own
/// five weights), so it does (measured; suns 60 and 15 degrees, error in %
/// of the reference's 1 - T):
///
/// ```text
/// band nm   ref 1-T          sora band mean   error          one sample of a grid of the band's width
/// 755-765   0.309 0.433      0.309 0.432      -0.1 -0.1 %    -0.1 -0.1 %
/// 760-770   0.344 0.502      0.344 0.501      -0.1 -0.2 %    -0.1 -0.2 %
/// 765-775   0.066 0.116      0.065 0.115      -0.1 -0.4 %    -0.1 -0.4 %
/// 740-760   0.015 0.021      0.015 0.021      -0.1 -0.3 %    -0.1 -0.3 %
/// 750-770   0.187 0.272      0.187 0.272      -0.1 -0.2 %    -0.1 -0.2 %
/// 760-780   0.173 0.253      0.173 0.253      -0.1 -0.2 %    -0.1 -0.2 %
/// 770-790   0.0006 0.0019    0.0006 0.0019    -0.3 -1.0 %    -0.3 -1.0 %
/// ```
///
/// One sample of a 10 or 20 nm grid is within 0.4 % where 1 - T > 0.01 and
/// 1.0 % for 770-790 nm (1 - T 0.002: the bins' fits err up to 0.67 % of
/// max(1 - T, 0.001), absolute errors of a few 1e-6 there): its terms carry the
/// band's own weights (with the five weights shared by every wavelength a
/// 10 nm sample erred up to 4.4 % and a 20 nm one up to 19 % against its
/// bins), and the bins their own (with shared weights the bin at the R
/// branch's head, 759.5-760 nm, erred 5.6 %). That bar, 1.5 %, is the
/// second assertion. Before the k-terms (the SPECTRL2 band model, point samples,
/// trapezoid mean): -43/-30 %, -41/-30 % and +57/+62 % for the 10 nm bands.
#[test]
fn o2_a_band_within_two_percent_of_line_by_line() {
    let (mut worst, mut worst_centre): (f64, f64) = (0.0, 0.0);
    for (case, mean, centre) in comparison() {
        worst = worst.max(error_percent(mean, case.transmittance).abs());
        worst_centre = worst_centre.max(error_percent(centre, case.transmittance).abs());
    }
    println!(
        "worst band-mean error: {worst:.1} % of 1 - T; one sample of a 10 or 20 nm grid: {worst_centre:.1} %"
    );
    assert!(worst < 2.0, "{worst:.1} % of 1 - T");
    assert!(
        worst_centre < 1.5,
        "one sample of a 10 or 20 nm grid: {worst_centre:.1} % of 1 - T"
    );
}
