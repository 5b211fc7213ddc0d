//! The colour stage against references (issue 2, item 3):
//! - CIE D65 integrates to the CIE white point, and to sRGB (1, 1, 1);
//! - the clear-sky case (a) spectra integrate to the XYZ and linear sRGB of
//!   an independent computation (`data/sky_case_a_xyz_srgb.csv`) to 1e-5;
//! - out-of-gamut, black and invalid spectra are handled as documented;
//! - the matrices and the sRGB curve round-trip, and 8-bit values are the
//!   IEC formula's.
//!
//! Data files (copies with a `# source:` line) are embedded with
//! `include_str!`, so the tests read no files at run time.

use crate::colour::{
    DisplayEncoding, DisplayMapping, Exposure, GamutMapping, LinearRgb, Observer, RgbColourSpace,
    SpectrumToXyz, TransferCurve, Xyz,
};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};
use crate::table::NumericTable;

const D65_CSV: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/cie_d65_relative_spd_5nm.csv"
));
const SKY_RADIANCE_CSV: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/clear_sky_radiance.csv"
));
const SKY_CASE_A_COLOUR_CSV: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/sky_case_a_xyz_srgb.csv"
));

fn column_index(table: &NumericTable, name: &str) -> usize {
    table
        .column_names
        .iter()
        .position(|column| column == name)
        .unwrap_or_else(|| panic!("no column {name} in {:?}", table.column_names))
}

/// D65's relative spectral power at each wavelength of `grid` (which must
/// fall on the table's 5 nm rows).
fn d65_on(grid: &WavelengthGrid) -> SampledSpectrum {
    let table = NumericTable::parse(D65_CSV, "D65").unwrap();
    let values = grid
        .wavelengths_nm()
        .map(|nm| {
            table
                .rows
                .iter()
                .find(|row| row[0] == nm)
                .unwrap_or_else(|| panic!("D65 has no row at {nm} nm"))[1]
        })
        .collect();
    SampledSpectrum::from_values(values)
}

/// XYZ of D65 normalised to Y = 100.
fn d65_white_point(grid: &WavelengthGrid, observer: Observer) -> Xyz {
    let xyz = SpectrumToXyz::new(grid, observer)
        .to_xyz(&d65_on(grid))
        .unwrap();
    xyz.scaled(100.0 / xyz.y)
}

/// The grid for D65: CIE 015's abridged range and step, 380-780 nm every
/// 5 nm, on the table's own rows (no interpolation of the illuminant).
fn d65_grid() -> WavelengthGrid {
    WavelengthGrid::new(380.0, 780.0, 5.0).unwrap()
}

#[test]
fn d65_with_the_two_degree_observer_is_the_cie_white_point() {
    let white = d65_white_point(&d65_grid(), Observer::Cie1931TwoDegree);
    // CIE 015:2018's D65 white point, 2-degree: (95.04, 100.00, 108.88).
    assert!((white.x - 95.04).abs() <= 0.05, "{white:?}");
    assert!((white.z - 108.88).abs() <= 0.05, "{white:?}");
    // Measured: (95.0430, 100, 108.8801).
    assert!((white.x - 95.0430).abs() < 1e-4 && (white.z - 108.8801).abs() < 1e-4);
    // Starting at 360 nm adds the near-UV rows, where z̄ is not yet 0: Z rises
    // by 0.017 (to 108.897), still within the CIE value's rounding.
    let wider = d65_white_point(
        &WavelengthGrid::new(360.0, 780.0, 5.0).unwrap(),
        Observer::Cie1931TwoDegree,
    );
    assert!((wider.x - 95.04).abs() <= 0.05 && (wider.z - 108.88).abs() <= 0.05);
    assert!(wider.z > white.z + 0.01, "{wider:?}");
}

#[test]
fn d65_with_the_ten_degree_observer_is_the_cie_ten_degree_white_point() {
    let white = d65_white_point(&d65_grid(), Observer::Cie1964TenDegree);
    // CIE 015:2018's D65 white point, 10-degree: (94.81, 100.00, 107.32).
    assert!((white.x - 94.81).abs() <= 0.05, "{white:?}");
    assert!((white.z - 107.32).abs() <= 0.05, "{white:?}");
}

#[test]
fn d65_is_srgb_white() {
    let white = d65_white_point(&d65_grid(), Observer::Cie1931TwoDegree).scaled(0.01);
    let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(white);
    for component in rgb.to_array() {
        assert!((component - 1.0).abs() < 1e-3, "{rgb:?}");
    }
    // Through the whole display stage D65 at Y = 1 is full white.
    let mapping = DisplayMapping {
        exposure: Exposure::Fixed(1.0),
        ..DisplayMapping::default()
    };
    assert_eq!(mapping.to_u8(&[white]).unwrap(), [[255, 255, 255]]);
}

/// One row of `sky_case_a_xyz_srgb.csv`.
struct SkyColourReference {
    quantity: String,
    ground_albedo: f64,
    xyz: [f64; 3],
    xy: [f64; 2],
    linear_srgb: [f64; 3],
    linear_srgb_over_y: [f64; 3],
}

fn sky_colour_references() -> Vec<SkyColourReference> {
    let mut lines = SKY_CASE_A_COLOUR_CSV
        .lines()
        .filter(|line| !line.trim().is_empty() && !line.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "quantity",
            "ground_albedo",
            "X",
            "Y",
            "Z",
            "x",
            "y",
            "R_lin",
            "G_lin",
            "B_lin",
            "R_lin_over_Y",
            "G_lin_over_Y",
            "B_lin_over_Y"
        ]
    );
    lines
        .map(|line| {
            let fields: Vec<&str> = line.split(',').collect();
            let number = |i: usize| fields[i].trim().parse::<f64>().unwrap();
            SkyColourReference {
                quantity: fields[0].to_string(),
                ground_albedo: number(1),
                xyz: [number(2), number(3), number(4)],
                xy: [number(5), number(6)],
                linear_srgb: [number(7), number(8), number(9)],
                linear_srgb_over_y: [number(10), number(11), number(12)],
            }
        })
        .collect()
}

/// The case (a) radiance (sun 36°, view 17°, relative azimuth 140°) of
/// `column` at `ground_albedo`, on the paper grid.
fn case_a_spectrum(column: &str, ground_albedo: f64) -> SampledSpectrum {
    let table = NumericTable::parse(SKY_RADIANCE_CSV, "clear-sky radiance").unwrap();
    let [sun, view, azimuth, albedo, lambda] = [
        "sun_elev_deg",
        "view_elev_deg",
        "rel_azimuth_deg",
        "ground_albedo",
        "lambda_nm",
    ]
    .map(|name| column_index(&table, name));
    let value = column_index(&table, column);
    let rows: Vec<&Vec<f64>> = table
        .rows
        .iter()
        .filter(|row| {
            row[sun] == 36.0
                && row[view] == 17.0
                && row[azimuth] == 140.0
                && row[albedo] == ground_albedo
        })
        .collect();
    let grid = WavelengthGrid::paper();
    assert_eq!(rows.len(), grid.len());
    for (row, nm) in rows.iter().zip(grid.wavelengths_nm()) {
        assert_eq!(row[lambda], nm);
    }
    SampledSpectrum::from_values(rows.iter().map(|row| row[value]).collect())
}

fn assert_relative(got: f64, want: f64, tolerance: f64, what: &str) {
    let error = (got / want - 1.0).abs();
    assert!(
        error <= tolerance,
        "{what}: {got} vs {want}, relative error {error:e}"
    );
}

#[test]
fn clear_sky_case_a_matches_the_reference_xyz_and_linear_srgb() {
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let references = sky_colour_references();
    // Three radiance columns at albedo 0 and 0.3.
    assert_eq!(references.len(), 6);
    let mut worst = 0.0f64;
    for reference in &references {
        // The reference's L_single is the plane-parallel single scattering.
        let column = match reference.quantity.as_str() {
            "L_single" => "L_single_plane_parallel",
            "L_single_spherical" => "L_single_spherical",
            "L_multi" => "L_multi_plane_parallel",
            other => panic!("unexpected quantity {other}"),
        };
        let what = format!("{} albedo {}", reference.quantity, reference.ground_albedo);
        let xyz = to_xyz
            .to_xyz(&case_a_spectrum(column, reference.ground_albedo))
            .unwrap();
        let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(xyz);
        for (got, want) in xyz.to_array().into_iter().zip(reference.xyz) {
            assert_relative(got, want, 1e-5, &format!("{what} XYZ"));
            worst = worst.max((got / want - 1.0).abs());
        }
        for (got, want) in rgb.to_array().into_iter().zip(reference.linear_srgb) {
            assert_relative(got, want, 1e-5, &format!("{what} linear sRGB"));
            worst = worst.max((got / want - 1.0).abs());
        }
        // Six-decimal columns: within half a unit of their last digit.
        let xy = xyz.chromaticity_xy().unwrap();
        for (got, want) in xy.into_iter().zip(reference.xy) {
            assert!(
                (got - want).abs() <= 5e-7 + 1e-12,
                "{what} xy: {got} vs {want}"
            );
        }
        for (got, want) in rgb.to_array().into_iter().zip(reference.linear_srgb_over_y) {
            let got = got / xyz.y;
            assert!(
                (got - want).abs() <= 5e-7 + 1e-12,
                "{what} RGB/Y: {got} vs {want}"
            );
        }
    }
    // The references have 9 significant digits; the published matrix
    // reproduces them to rounding (measured 3e-9), the exact-primaries matrix
    // would be off by 1.8e-4.
    assert!(worst < 1e-8, "worst relative error {worst:e}");
}

#[test]
fn the_exactly_derived_srgb_matrix_would_fail_the_sky_reference() {
    // Why the published IEC matrix is used: the matrix computed from the
    // primaries and D65 (Lindbloom's 3.2404542, ...; here to 7 digits)
    // misses the reference by more than 1e-5.
    let exact = [
        [3.2409699, -1.5373832, -0.4986108],
        [-0.9692436, 1.8759675, 0.0415551],
        [0.0556301, -0.2039770, 1.0569715],
    ];
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let reference = &sky_colour_references()[0];
    let xyz = to_xyz
        .to_xyz(&case_a_spectrum("L_multi_plane_parallel", 0.0))
        .unwrap()
        .to_array();
    let r = exact[0][0] * xyz[0] + exact[0][1] * xyz[1] + exact[0][2] * xyz[2];
    assert!((r / reference.linear_srgb[0] - 1.0).abs() > 1e-4);
}

/// A spectrum on the paper grid that is `value` at `wavelength_nm` only.
fn monochromatic(wavelength_nm: f64, value: f64) -> SampledSpectrum {
    let grid = WavelengthGrid::paper();
    let mut spectrum = SampledSpectrum::zeros(grid.len());
    let index = grid
        .wavelengths_nm()
        .position(|nm| nm == wavelength_nm)
        .unwrap();
    spectrum[index] = value;
    spectrum
}

#[test]
fn monochromatic_700_nm_is_out_of_gamut_and_mapped_as_documented() {
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let srgb = RgbColourSpace::Srgb;
    let xyz = to_xyz.to_xyz(&monochromatic(700.0, 1.0)).unwrap();
    let rgb = srgb.linear_rgb_from_xyz(xyz);
    assert!(rgb.r > 0.0 && rgb.g < 0.0 && rgb.b < 0.0, "{rgb:?}");

    // Clip: negative components become 0.
    let clipped = GamutMapping::Clip.apply(rgb, srgb);
    assert_eq!(clipped, LinearRgb::new(rgb.r, 0.0, 0.0));

    // Preserve hue: desaturated toward grey at the same luminance, so the
    // most negative component (G) reaches 0, nothing is negative, red dominates.
    let mapped = GamutMapping::PreserveHue.apply(rgb, srgb);
    assert_eq!(mapped.g, 0.0, "{mapped:?}");
    assert!(mapped.b >= 0.0 && mapped.r > mapped.b, "{mapped:?}");
    assert!((srgb.luminance(mapped) / xyz.y - 1.0).abs() < 1e-12);
    // Its chromaticity lies between the spectral colour's and the white's.
    let [x_mono, _] = xyz.chromaticity_xy().unwrap();
    let [x_mapped, _] = srgb.xyz_from_linear_rgb(mapped).chromaticity_xy().unwrap();
    assert!(
        x_mapped < x_mono && x_mapped > 0.3127,
        "{x_mapped} {x_mono}"
    );

    // Over range as well: 100 times brighter, then scaled down by its max.
    let bright = GamutMapping::PreserveHue.apply(rgb.scaled(100.0), srgb);
    assert_eq!(bright.max_component(), 1.0);
    assert_eq!(bright.g, 0.0);
    assert!((bright.b / bright.r - mapped.b / mapped.r).abs() < 1e-12);

    // Through the display stage, in both modes: no negative or NaN bytes,
    // a pure red byte for Clip.
    for gamut_mapping in GamutMapping::ALL {
        let mapping = DisplayMapping {
            exposure: Exposure::Fixed(1.0),
            gamut_mapping,
            encoding: DisplayEncoding::Srgb,
        };
        let [bytes] = mapping.to_u8(&[xyz]).unwrap()[..] else {
            panic!()
        };
        assert!(
            bytes[0] > bytes[2] && bytes[1] == 0,
            "{gamut_mapping}: {bytes:?}"
        );
        if gamut_mapping == GamutMapping::Clip {
            assert_eq!(bytes[1..], [0, 0]);
        }
    }
}

#[test]
fn monochromatic_400_nm_has_negative_green() {
    let to_xyz = SpectrumToXyz::new(&WavelengthGrid::paper(), Observer::Cie1931TwoDegree);
    let xyz = to_xyz.to_xyz(&monochromatic(400.0, 1.0)).unwrap();
    let rgb = RgbColourSpace::Srgb.linear_rgb_from_xyz(xyz);
    assert!(rgb.g < 0.0 && rgb.b > rgb.r && rgb.r > 0.0, "{rgb:?}");
    let mapped = GamutMapping::PreserveHue.apply(rgb, RgbColourSpace::Srgb);
    assert_eq!(mapped.g, 0.0);
    assert!(mapped.min_component() >= 0.0);
}

#[test]
fn a_zero_spectrum_is_black_in_every_mode() {
    let grid = WavelengthGrid::paper();
    for observer in Observer::ALL {
        let xyz = SpectrumToXyz::new(&grid, observer)
            .to_xyz(&SampledSpectrum::zeros(grid.len()))
            .unwrap();
        assert_eq!(xyz, Xyz::BLACK);
        for exposure in [
            Exposure::default(),
            Exposure::Auto { key: 0.5 },
            Exposure::Fixed(3.0),
        ] {
            for gamut_mapping in GamutMapping::ALL {
                for encoding in [DisplayEncoding::Srgb, DisplayEncoding::PAPER_DEFAULT] {
                    let mapping = DisplayMapping {
                        exposure,
                        gamut_mapping,
                        encoding,
                    };
                    let image = [xyz; 4];
                    let linear = mapping.display_linear_rgb(&image).unwrap();
                    assert!(linear.iter().all(|rgb| *rgb == LinearRgb::BLACK));
                    assert_eq!(mapping.to_u8(&image).unwrap(), [[0u8; 3]; 4]);
                    assert_eq!(mapping.to_u16(&image).unwrap(), [[0u16; 3]; 4]);
                }
            }
        }
    }
}

#[test]
fn nan_infinite_negative_and_misfit_spectra_are_rejected() {
    let grid = WavelengthGrid::paper();
    let to_xyz = SpectrumToXyz::new(&grid, Observer::Cie1931TwoDegree);
    for (bad, wavelength) in [
        (f64::NAN, "560 nm"),
        (-0.5, "560 nm"),
        (f64::NEG_INFINITY, "560 nm"),
    ] {
        let mut spectrum = SampledSpectrum::constant(grid.len(), 0.1);
        spectrum[9] = bad;
        let message = to_xyz.to_xyz(&spectrum).unwrap_err().to_string();
        assert!(
            message.contains("sample 9") && message.contains(wavelength),
            "{message}"
        );
    }
    assert!(to_xyz.to_xyz(&SampledSpectrum::zeros(22)).is_err());
}

#[test]
fn xyz_to_rgb_to_xyz_round_trips() {
    let samples = [
        Xyz::new(0.9505, 1.0, 1.089),
        Xyz::new(2.50182473, 2.55049991, 4.47045481),
        Xyz::new(0.0114, 0.0041, 0.0),
        Xyz::new(1e-6, 3e-7, 2e-6),
        Xyz::new(40.0, 12.0, 0.5),
    ];
    for space in RgbColourSpace::ALL {
        for xyz in samples {
            let back = space.xyz_from_linear_rgb(space.linear_rgb_from_xyz(xyz));
            for (got, want) in back.to_array().into_iter().zip(xyz.to_array()) {
                let scale = want.abs().max(1.0);
                assert!(
                    (got - want).abs() <= 1e-12 * scale,
                    "{space}: {xyz:?} -> {back:?}"
                );
            }
        }
    }
}

#[test]
fn srgb_transfer_curve_round_trips_and_gives_the_iec_bytes() {
    let curve = TransferCurve::Srgb;
    for linear in [0.0, 1e-4, 0.002, 0.0031, 0.01, 0.18, 0.5, 0.9, 1.0] {
        let back = curve.decode(curve.encode(linear));
        assert!((back - linear).abs() <= 1e-15, "{linear} -> {back}");
    }
    // From IEC 61966-2-1: V = 12.92 L (L <= 0.0031308) else 1.055 L^(1/2.4) - 0.055;
    // 255 V = 0, 10.31, 117.65, 187.52, 255.
    let bytes: Vec<u8> = [0.0, 0.0031308, 0.18, 0.5, 1.0]
        .into_iter()
        .map(|v| DisplayEncoding::Srgb.encode_u8(LinearRgb::new(v, v, v))[1])
        .collect();
    assert_eq!(bytes, [0, 10, 118, 188, 255]);
}
