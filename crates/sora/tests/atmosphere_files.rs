//! Malformed atmosphere files: each gets a one-line error that names the
//! problem (the key as a path, the value, its unit and the allowed range,
//! or the TOML line), and no input makes the loader panic.

use sora::atmosphere::Atmosphere;
use sora::spectrum::WavelengthGrid;

/// A valid file with one species of each kind; the cases below break it.
const VALID: &str = r#"name = "test planet"

[planet]
radius_m = 6360e3
atmosphere_height_m = 100e3
ground_albedo = 0.1

[sun]
spectrum = "flat"
irradiance_w_m2_nm = 1.0

[[species]]
name = "air"
number_density_m3 = 2.5e25
profile.exponential.scale_height_m = 8000
scattering.rayleigh = { gas = "air", depolarization = true }

[[species]]
name = "haze"
optical_depth = 0.1
reference_wavelength_nm = 550
profile.exponential.scale_height_m = 1200
scattering.parametric = { angstrom_exponent = 1.3, single_scattering_albedo = 0.9, phase.henyey_greenstein.g = 0.7 }

[[species]]
name = "dust"
number_density_m3 = 2.0e6
profile.exponential.scale_height_m = 11000
scattering.mie.refractive_index = { wavelength_nm = [321, 440, 500, 600, 700, 800], n = [1.49, 1.50, 1.50, 1.50, 1.50, 1.50], k = [0.0127, 0.0077, 0.0055, 0.0017, 0.0009, 0.0011] }
scattering.mie.size_distribution.lognormal = { median_radius_um = 0.5, geometric_std_dev = 1.5, min_radius_um = 0.45, max_radius_um = 0.56 }
scattering.mie.phase = "paper-hg"

[[species]]
name = "ozone"
column_dobson_units = 300
profile.tent = { peak_altitude_m = 25e3, half_width_m = 15e3 }
absorption.gas = "ozone"
"#;

/// `VALID` with `from` replaced by `to` (which must occur exactly once).
fn edit(from: &str, to: &str) -> String {
    assert_eq!(VALID.matches(from).count(), 1, "'{from}' must occur once");
    VALID.replacen(from, to, 1)
}

fn load_error(text: &str) -> String {
    match Atmosphere::from_toml_str(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn the_valid_file_loads_and_computes() {
    let atmosphere = Atmosphere::from_toml_str(VALID).unwrap();
    assert_eq!(atmosphere.species.len(), 4);
    let optics = atmosphere.compute_optics(&WavelengthGrid::paper()).unwrap();
    assert_eq!(optics.species.len(), 4);
}

#[test]
fn malformed_files_get_one_line_errors_naming_the_problem() {
    let cases: Vec<(String, &[&str])> = vec![
        // TOML syntax and types: the line.
        (edit("[planet]", "[planet"), &["atmosphere file, line 3:"]),
        (
            edit("name = \"test planet\"", "name = \"test planet"),
            &["line 1"],
        ),
        (
            edit("radius_m = 6360e3", "radius_m = 6360e3 6360e3"),
            &["line 4"],
        ),
        (
            format!("colour = \"blue\"\n{VALID}"),
            &["line 1", "unknown field `colour`"],
        ),
        (
            edit("scale_height_m = 8000", "scale_heigth_m = 8000"),
            &[
                "line 15",
                "unknown field `scale_heigth_m`",
                "scale_height_m",
            ],
        ),
        (
            edit("ground_albedo = 0.1", "ground_albedo = 0.1\nsize = 3"),
            &["line 7", "unknown field `size`"],
        ),
        (
            edit("radius_m = 6360e3", "radius_m = \"big\""),
            &["line 4", "invalid type: string \"big\""],
        ),
        (
            edit("radius_m = 6360e3\n", ""),
            &["missing field `radius_m`"],
        ),
        (
            edit(
                "[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\nground_albedo = 0.1\n",
                "",
            ),
            &["missing field `planet`"],
        ),
        (String::new(), &["missing field `name`"]),
        (
            "\u{0}\u{1}binary".to_string(),
            &["atmosphere file, line 1:"],
        ),
        (
            edit(
                "profile.tent = { peak_altitude_m = 25e3, half_width_m = 15e3 }\n",
                "",
            ),
            &["missing field `profile`"],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.henyey_greenstein.g = \"forward\"",
            ),
            &["line 23", "invalid type"],
        ),
        // Planet and sun values: key, value, unit, allowed range.
        (
            edit("radius_m = 6360e3", "radius_m = -6360e3"),
            &["planet.radius_m = -6.36e6 m is out of range: allowed 1e5..=1e10 m"],
        ),
        (
            edit("radius_m = 6360e3", "radius_m = 1e11"),
            &["planet.radius_m = 1e11 m"],
        ),
        (
            edit("radius_m = 6360e3", "radius_m = nan"),
            &["planet.radius_m = NaN m"],
        ),
        (
            edit("atmosphere_height_m = 100e3", "atmosphere_height_m = -1000"),
            &[
                "planet.atmosphere_height_m = -1000 m",
                "allowed 1e3..=1e6 m",
            ],
        ),
        (
            edit("ground_albedo = 0.1", "ground_albedo = 1.5"),
            &["planet.ground_albedo = 1.5 is out of range: allowed 0..=1"],
        ),
        (
            edit(
                "ground_albedo = 0.1",
                "ground_albedo = { wavelength_nm = [700, 400], albedo = [0.1, 0.2] }",
            ),
            &["planet.ground_albedo", "400 nm follows 700 nm"],
        ),
        (
            edit(
                "ground_albedo = 0.1",
                "ground_albedo = { wavelength_nm = [400, 700], albedo = [0.1, -0.2] }",
            ),
            &["planet.ground_albedo.albedo[1] = -0.2"],
        ),
        (
            edit("ground_albedo = 0.1", "ground_albedo = \"grass\""),
            &["line 6", "a number, or an array or table of numbers"],
        ),
        (
            edit("spectrum = \"flat\"", "spectrum = \"blackbody\""),
            &[
                "sun.spectrum: 'blackbody' is not a known spectrum",
                "astm-e490",
            ],
        ),
        (
            edit("irradiance_w_m2_nm = 1.0\n", ""),
            &["sun.irradiance_w_m2_nm: is required with spectrum = \"flat\""],
        ),
        (
            edit("irradiance_w_m2_nm = 1.0", "irradiance_w_m2_nm = -1.0"),
            &["sun.irradiance_w_m2_nm = -1 W m^-2 nm^-1"],
        ),
        (
            edit(
                "spectrum = \"flat\"\nirradiance_w_m2_nm = 1.0",
                "spectrum = \"csv\"",
            ),
            &["sun.csv_file: is required with spectrum = \"csv\""],
        ),
        (
            edit(
                "spectrum = \"flat\"\nirradiance_w_m2_nm = 1.0",
                "spectrum = \"csv\"\ncsv_file = \"sun.csv\"",
            ),
            &["sun.csv_file: cannot read it", "sun.csv"],
        ),
        (
            edit(
                "irradiance_w_m2_nm = 1.0",
                "irradiance_w_m2_nm = 1.0\nangular_diameter_deg = 90",
            ),
            &["sun.angular_diameter_deg = 90 deg is out of range"],
        ),
        (
            edit(
                "irradiance_w_m2_nm = 1.0",
                "irradiance_w_m2_nm = 1.0\nirradiance_scale = 0",
            ),
            &["sun.irradiance_scale = 0 is out of range: allowed > 0"],
        ),
        // Species: structure.
        (
            edit("name = \"haze\"", "name = \"air\""),
            &["species[1].name: 'air' is already the name of species[0]"],
        ),
        (
            edit("name = \"haze\"", "name = \" \""),
            &["species[1].name: must not be empty"],
        ),
        (
            edit(
                "profile.exponential.scale_height_m = 1200",
                "profile.exponential.scale_height_m = 1200\nprofile.tent = { peak_altitude_m = 1, half_width_m = 1 }",
            ),
            &["species[1].profile: give exactly one of exponential, tent, layers, table"],
        ),
        (
            edit(
                "absorption.gas = \"ozone\"",
                "absorption.gas = \"ozone\"\nscattering.rayleigh.gas = \"air\"",
            ),
            &["species[3]: give either scattering or absorption, not both"],
        ),
        (
            edit("absorption.gas = \"ozone\"\n", ""),
            &["species[3]: needs an optical model"],
        ),
        (
            edit(
                "scattering.rayleigh = { gas = \"air\", depolarization = true }",
                "scattering.rayleigh = { gas = \"air\" }\nscattering.parametric = { angstrom_exponent = 1, single_scattering_albedo = 1, phase.henyey_greenstein.g = 0 }",
            ),
            &["species[0].scattering: give exactly one of rayleigh, mie, parametric"],
        ),
        // Profiles.
        (
            edit("scale_height_m = 8000", "scale_height_m = -8000"),
            &[
                "species[0].profile.exponential.scale_height_m = -8000 m is out of range: allowed > 0",
            ],
        ),
        (
            edit("scale_height_m = 8000", "scale_height_m = inf"),
            &["species[0].profile.exponential.scale_height_m = inf m"],
        ),
        (
            edit("half_width_m = 15e3", "half_width_m = 0"),
            &["species[3].profile.tent.half_width_m = 0 m"],
        ),
        (
            edit("peak_altitude_m = 25e3", "peak_altitude_m = 500e3"),
            &[
                "species[3].profile: the profile has no density between the ground and the top of the atmosphere (100000 m)",
            ],
        ),
        (
            edit(
                "profile.exponential.scale_height_m = 8000",
                "profile.table = { altitude_m = [0, 50e3], relative_density = [1, 0.01] }",
            ),
            &[
                "species[0].profile.table.altitude_m[1] = 50000 m",
                "must reach the top of the atmosphere",
            ],
        ),
        (
            edit(
                "profile.exponential.scale_height_m = 8000",
                "profile.table = { altitude_m = [0, 100e3], relative_density = [1, 0] }",
            ),
            &["species[0].profile.table.relative_density[1] = 0 is out of range: allowed > 0"],
        ),
        (
            edit(
                "profile.exponential.scale_height_m = 8000",
                "profile.layers = { altitude_m = [0, 5e3, 2e3], relative_density = [1, 1, 0] }",
            ),
            &[
                "species[0].profile.layers.altitude_m[2] = 2000 m",
                "altitudes must increase",
            ],
        ),
        (
            edit(
                "profile.exponential.scale_height_m = 8000",
                "profile.layers = { altitude_m = [0, 5e3], relative_density = [1] }",
            ),
            &[
                "species[0].profile.layers: altitude_m and relative_density need the same number of rows",
            ],
        ),
        // Amounts.
        (
            edit("number_density_m3 = 2.5e25", "number_density_m3 = -2.5e25"),
            &["species[0].number_density_m3 = -2.5e25 m^-3 is out of range"],
        ),
        (
            edit("number_density_m3 = 2.5e25\n", ""),
            &["species[0].number_density_m3: is required for a Rayleigh gas"],
        ),
        (
            edit("optical_depth = 0.1\n", ""),
            &["species[1].reference_wavelength_nm: goes with optical_depth"],
        ),
        (
            edit("optical_depth = 0.1\nreference_wavelength_nm = 550\n", ""),
            &["species[1].optical_depth: is required for a parametric aerosol"],
        ),
        (
            edit("reference_wavelength_nm = 550\n", ""),
            &["species[1].reference_wavelength_nm: is required with optical_depth"],
        ),
        (
            edit("optical_depth = 0.1", "optical_depth = -0.1"),
            &["species[1].optical_depth = -0.1 is out of range: allowed 0..=1000"],
        ),
        (
            edit("column_dobson_units = 300", "column_dobson_units = -300"),
            &["species[3].column_dobson_units = -300 DU"],
        ),
        (
            edit(
                "number_density_m3 = 2.5e25",
                "number_density_m3 = 2.5e25\ncolumn_dobson_units = 3",
            ),
            &["species[0].column_dobson_units: is not used by a scattering species"],
        ),
        (
            edit(
                "number_density_m3 = 2.0e6",
                "number_density_m3 = 2.0e6\noptical_depth = 1\nreference_wavelength_nm = 550",
            ),
            &["species[2]: a Mie aerosol needs exactly one of number_density_m3 or optical_depth"],
        ),
        (
            edit(
                "column_dobson_units = 300",
                "column_dobson_units = 300\nnumber_density_m3 = 1e18",
            ),
            &[
                "species[3]: an absorbing gas needs exactly one of column_dobson_units, column_molecules_cm2 or number_density_m3",
            ],
        ),
        // Rayleigh.
        (
            edit("gas = \"air\", depolarization = true", "gas = \"nitrogen\""),
            &[
                "species[0].scattering.rayleigh.gas: 'nitrogen' is not a known gas: use \"air\" or \"co2\"",
            ],
        ),
        (
            edit(
                "gas = \"air\", depolarization = true",
                "gas = \"air\", coefficient_per_m = 1e-5",
            ),
            &[
                "species[0].scattering.rayleigh: give either gas (physical) or coefficient_per_m (parametric), not both",
            ],
        ),
        (
            edit(
                "gas = \"air\", depolarization = true",
                "gas = \"air\", wavelength_exponent = 4",
            ),
            &["species[0].scattering.rayleigh.wavelength_exponent: is not used by a Rayleigh gas"],
        ),
        // Parametric aerosol.
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.henyey_greenstein.g = 1.2",
            ),
            &[
                "species[1].scattering.parametric.phase.henyey_greenstein.g = 1.2 is out of range: allowed -1 < g < 1",
            ],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.cornette_shanks.g = -1",
            ),
            &["species[1].scattering.parametric.phase.cornette_shanks.g = -1"],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.tabulated = { angle_deg = [0, 90, 170], value = [3, 1, 1] }",
            ),
            &[
                "species[1].scattering.parametric.phase.tabulated.angle_deg: must run from 0 to 180 deg (got 0 to 170 deg)",
            ],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.tabulated = { angle_deg = [0, 90, 60, 180], value = [3, 1, 1, 1] }",
            ),
            &[
                "species[1].scattering.parametric.phase.tabulated.angle_deg[2]: angles must increase, but 60 deg follows 90 deg",
            ],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.tabulated = { angle_deg = [0, 90, 180], value = [3, -1, 1] }",
            ),
            &[
                "species[1].scattering.parametric.phase.tabulated.value[1] = -1 is out of range: allowed >= 0",
            ],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.tabulated = { angle_deg = [0, 180], value = [3, 1, 1] }",
            ),
            &[
                "species[1].scattering.parametric.phase.tabulated: angle_deg and value need the same length, at least 2 (got 2 and 3)",
            ],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.tabulated = { angle_deg = [0, 180], value = [0, 0] }",
            ),
            &["species[1].scattering.parametric.phase.tabulated.value"],
        ),
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.henyey_greenstein.g = 0.7, phase.tabulated = { angle_deg = [0, 180], value = [1, 1] }",
            ),
            &[
                "species[1].scattering.parametric.phase: give exactly one of henyey_greenstein, cornette_shanks, tabulated",
            ],
        ),
        (
            edit(
                "single_scattering_albedo = 0.9",
                "single_scattering_albedo = 1.5",
            ),
            &[
                "species[1].scattering.parametric.single_scattering_albedo = 1.5 is out of range: allowed 0..=1",
            ],
        ),
        (
            edit("phase.henyey_greenstein.g = 0.7", "phase.isotropic = {}"),
            &["line 23", "unknown field `isotropic`"],
        ),
        // Mie.
        (
            edit("wavelength_nm = [321, 440, 500, 600, 700, 800], ", ""),
            &[
                "species[2].scattering.mie.refractive_index.wavelength_nm: is required when n and k are arrays",
            ],
        ),
        (
            edit(
                "[321, 440, 500, 600, 700, 800]",
                "[321, 440, 500, 500, 700, 800]",
            ),
            &[
                "species[2].scattering.mie.refractive_index",
                "500 nm is followed by 500 nm",
            ],
        ),
        (
            edit(
                "k = [0.0127, 0.0077, 0.0055, 0.0017, 0.0009, 0.0011]",
                "k = [0.0127, -0.0077, 0.0055, 0.0017, 0.0009, 0.0011]",
            ),
            &["species[2].scattering.mie.refractive_index.k[1] = -0.0077"],
        ),
        (
            edit("n = [1.49, 1.50, 1.50, 1.50, 1.50, 1.50]", "n = 1.5"),
            &[
                "species[2].scattering.mie.refractive_index: n and k must both be numbers (constant) or both arrays (tabulated)",
            ],
        ),
        (
            edit("geometric_std_dev = 1.5", "geometric_std_dev = 0.9"),
            &[
                "species[2].scattering.mie.size_distribution.lognormal.geometric_std_dev = 0.9 is out of range: allowed >= 1.0001",
            ],
        ),
        (
            edit(
                "min_radius_um = 0.45, max_radius_um = 0.56",
                "min_radius_um = 0.56, max_radius_um = 0.45",
            ),
            &[
                "species[2].scattering.mie.size_distribution.lognormal.max_radius_um = 0.45 um",
                "> min_radius_um (0.56)",
            ],
        ),
        (
            edit(", max_radius_um = 0.56", ""),
            &[
                "species[2].scattering.mie.size_distribution.lognormal: give both min_radius_um and max_radius_um",
            ],
        ),
        (
            edit(
                "median_radius_um = 0.5, geometric_std_dev = 1.5, min_radius_um = 0.45, max_radius_um = 0.56",
                "median_radius_um = 60, geometric_std_dev = 3",
            ),
            &[
                "species[2].scattering.mie.size_distribution.lognormal: particles up to",
                "sora handles up to 100 um",
            ],
        ),
        (
            edit(
                "median_radius_um = 0.5, geometric_std_dev = 1.5",
                "median_radius_um = 0.5, effective_variance = 0.3",
            ),
            &[
                "species[2].scattering.mie.size_distribution.lognormal: give median_radius_um and geometric_std_dev, or effective_radius_um and effective_variance",
            ],
        ),
        (
            edit(
                "scattering.mie.phase = \"paper-hg\"",
                "scattering.mie.phase = \"rayleigh\"",
            ),
            &["species[2].scattering.mie.phase: 'rayleigh' is not a phase mode"],
        ),
        (
            edit(
                "scattering.mie.refractive_index = { wavelength_nm = [321, 440, 500, 600, 700, 800], n = [1.49, 1.50, 1.50, 1.50, 1.50, 1.50], k = [0.0127, 0.0077, 0.0055, 0.0017, 0.0009, 0.0011] }",
                "scattering.mie.refractive_index.builtin = \"moon-dust\"",
            ),
            &[
                "species[2].scattering.mie.refractive_index.builtin: 'moon-dust' is not a built-in table",
            ],
        ),
        (
            edit(
                "number_density_m3 = 2.0e6",
                "optical_depth = 0.5\nreference_wavelength_nm = 880",
            ),
            &[
                "species[2].reference_wavelength_nm = 880 nm is out of range: allowed within the refractive-index table, 321..=800 nm",
            ],
        ),
        // An irradiance scale that made the solar irradiance infinite
        // (issue 17, the 50,000-file mutation campaign).
        (
            edit(
                "irradiance_w_m2_nm = 1.0",
                "irradiance_w_m2_nm = 1.0\nirradiance_scale = 1e308",
            ),
            &["sun.irradiance_scale = 1e308 is out of range: allowed > 0 and <= 1e4"],
        ),
        // Keys that need each other (issue 17, checks across keys).
        (
            edit(
                "phase.henyey_greenstein.g = 0.7",
                "phase.henyey_greenstein = {}",
            ),
            &["line 23", "missing field `g`"],
        ),
        (
            edit(
                "optical_depth = 0.1\nreference_wavelength_nm = 550\n",
                "optical_depth = 0.1\n",
            ),
            &["species[1].reference_wavelength_nm: is required with optical_depth"],
        ),
        (
            edit(
                "number_density_m3 = 2.0e6",
                "number_density_m3 = 2.0e6\noptical_depth = 0.3",
            ),
            &["species[2]: a Mie aerosol needs exactly one of number_density_m3 or optical_depth"],
        ),
        (
            edit(
                "number_density_m3 = 2.5e25",
                "number_density_m3 = 2.5e25\noptical_depth = 0.1",
            ),
            &["species[0].optical_depth: is not used by a Rayleigh gas"],
        ),
        // Vanishing widths (issue 17: v_eff = 1e-30 made the radius
        // quadrature allocate until the process aborted).
        (
            edit(
                "geometric_std_dev = 1.5",
                "geometric_std_dev = 1.00000000000001",
            ),
            &[
                "species[2].scattering.mie.size_distribution.lognormal.geometric_std_dev = 1.00000000000001",
                ">= 1.0001 (narrower populations are not resolved)",
            ],
        ),
        (
            edit(
                "median_radius_um = 0.5, geometric_std_dev = 1.5,",
                "effective_radius_um = 1.5, effective_variance = 1e-30,",
            ),
            &[
                "species[2].scattering.mie.size_distribution.lognormal.effective_variance = 1e-30",
                ">= 1e-8",
            ],
        ),
        (
            edit(
                "lognormal = { median_radius_um = 0.5, geometric_std_dev = 1.5,",
                "gamma = { effective_radius_um = 1.5, effective_variance = 5e-324,",
            ),
            &[
                "species[2].scattering.mie.size_distribution.gamma.effective_variance = 5e-324",
                ">= 1e-8",
            ],
        ),
        // Absorbing gas.
        (
            edit("absorption.gas = \"ozone\"", "absorption.gas = \"methane\""),
            &["species[3].absorption.gas: 'methane' has no built-in cross-section"],
        ),
        (
            edit(
                "absorption.gas = \"ozone\"",
                "absorption = { wavelength_nm = [400, 700], cross_section_m2 = [1e-25, -1e-25] }",
            ),
            &["species[3].absorption.cross_section_m2[1] = -1e-25 m^2"],
        ),
    ];
    assert!(cases.len() >= 30, "{} cases", cases.len());
    // Collect every mismatch, so that one run shows them all.
    let mut failures = Vec::new();
    for (text, expected) in &cases {
        let message = load_error(text);
        if message.contains('\n') {
            failures.push(format!("not one line: {message}"));
        }
        for fragment in *expected {
            if !message.contains(fragment) {
                failures.push(format!("expected '{fragment}' in: {message}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Tables that must cover the wavelength grid are checked in one step
/// before the optics are computed (`atmosphere/coverage.rs`), and the error
/// names the table's key and the grid: the two that disagree.
#[test]
fn tables_that_do_not_cover_the_grid_are_named() {
    let grid = WavelengthGrid::paper();
    let cases = [
        (
            edit(
                "ground_albedo = 0.1",
                "ground_albedo = { wavelength_nm = [400, 700], albedo = [0.1, 0.2] }",
            ),
            "planet.ground_albedo covers 400-700 nm but the wavelength grid 380:780:20 spans 380-780 nm: choose a grid within 400-700 nm, or extend the table",
        ),
        (
            edit(
                "[321, 440, 500, 600, 700, 800]",
                "[321, 440, 500, 600, 700, 750]",
            ),
            "species[2] (dust): scattering.mie.refractive_index covers 321-750 nm but the wavelength grid 380:780:20 spans 380-780 nm",
        ),
        (
            edit(
                "absorption.gas = \"ozone\"",
                "absorption = { wavelength_nm = [400, 700], cross_section_m2 = [1e-25, 1e-25] }",
            ),
            "species[3] (ozone): absorption.cross_section_m2 covers 400-700 nm but the wavelength grid 380:780:20",
        ),
    ];
    for (text, expected) in cases {
        let atmosphere = Atmosphere::from_toml_str(&text).unwrap();
        let message = atmosphere.compute_optics(&grid).unwrap_err().to_string();
        assert!(
            message.contains(expected),
            "expected '{expected}' in: {message}"
        );
        assert!(!message.contains('\n'));
    }
    // A solar spectrum read from a CSV that stops short of the grid; and a
    // built-in refractive-index table (Wolff's Mars dust, 263-2480 nm) is
    // fine on any grid of sora's 360-830 nm.
    let text = edit(
        "spectrum = \"flat\"\nirradiance_w_m2_nm = 1.0",
        "spectrum = \"csv\"\ncsv_file = \"short.csv\"",
    );
    let atmosphere = Atmosphere::from_toml_str_with_files(&text, &mut |_: &str| {
        Ok("wavelength_nm,irradiance_w_m2_nm\n400,1.5\n900,1.5\n".to_string())
    })
    .unwrap();
    let message = atmosphere.compute_optics(&grid).unwrap_err().to_string();
    assert!(
        message.starts_with("sun.spectrum (")
            && message
                .contains("covers 400-900 nm but the wavelength grid 380:780:20 spans 380-780 nm"),
        "{message}"
    );
    let mars = Atmosphere::preset("mars-dust").unwrap();
    assert!(mars.compute_optics(&"360:830:470".parse().unwrap()).is_ok());
}

/// A column of 1e-308 m (found by `atmosphere_mutations.rs`: with an
/// optical depth it made an infinite coefficient) is refused when the file
/// is read, naming the key; the optics' own check for infinite
/// coefficients stays behind it.
#[test]
fn coefficients_that_overflow_are_refused() {
    let paper_earth = sora::atmosphere::presets::find_preset("paper-earth")
        .unwrap()
        .toml;
    assert_eq!(
        paper_earth.matches("atmosphere_height_m = 100e3").count(),
        1
    );
    let text = paper_earth.replace(
        "atmosphere_height_m = 100e3",
        "atmosphere_height_m = 1e-308",
    );
    let message = Atmosphere::from_toml_str(&text).unwrap_err().to_string();
    assert!(
        message
            .contains("planet.atmosphere_height_m = 1e-308 m is out of range: allowed 1e3..=1e6 m"),
        "{message}"
    );
}

/// Files may name a solar spectrum CSV; the caller supplies its text.
#[test]
fn a_solar_csv_is_read_through_the_callers_closure() {
    let text = edit(
        "spectrum = \"flat\"\nirradiance_w_m2_nm = 1.0",
        "spectrum = \"csv\"\ncsv_file = \"sun.csv\"",
    );
    let mut asked = Vec::new();
    let atmosphere = Atmosphere::from_toml_str_with_files(&text, &mut |path: &str| {
        asked.push(path.to_string());
        Ok("wavelength_nm,irradiance_w_m2_nm\n300,1.5\n900,1.5\n".to_string())
    })
    .unwrap();
    assert_eq!(asked, ["sun.csv"]);
    let optics = atmosphere.compute_optics(&WavelengthGrid::paper()).unwrap();
    assert_eq!(optics.solar_irradiance_w_m2_nm.values(), &[1.5; 21]);
    let e = Atmosphere::from_toml_str_with_files(&text, &mut |_: &str| {
        Ok("wavelength_nm,irradiance_w_m2_nm\n400,1\n".to_string())
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("sun.csv"), "{e}");
}

/// No input panics: every truncation of the valid file, every line
/// removed, and every number replaced by awkward values either loads (and
/// then computes or fails cleanly on a cheap grid) or fails with one line.
#[test]
fn no_input_panics() {
    let grid: WavelengthGrid = "450:650:100".parse().unwrap();
    let try_load = |text: &str| match Atmosphere::from_toml_str(text) {
        Ok(atmosphere) => {
            if let Err(e) = atmosphere.compute_optics(&grid) {
                assert!(!e.to_string().contains('\n'), "{e}");
            }
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "{e}"),
    };
    for (i, _) in VALID.char_indices().step_by(7) {
        try_load(&VALID[..i]);
    }
    let lines: Vec<&str> = VALID.lines().collect();
    for skip in 0..lines.len() {
        let text: Vec<&str> = lines
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != skip)
            .map(|(_, l)| *l)
            .collect();
        try_load(&text.join("\n"));
    }
    // Replace each number in turn.
    let bytes = VALID.as_bytes();
    let mut starts = Vec::new();
    for i in 0..bytes.len() {
        let starts_number = bytes[i].is_ascii_digit()
            && (i == 0
                || !(bytes[i - 1].is_ascii_alphanumeric()
                    || bytes[i - 1] == b'.'
                    || bytes[i - 1] == b'_'));
        if starts_number {
            starts.push(i);
        }
    }
    for &start in &starts {
        let end = start
            + VALID[start..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+'))
                .unwrap_or(VALID.len() - start);
        for replacement in [
            "0", "-1", "1e308", "-1e308", "nan", "inf", "1e-300", "\"x\"", "true", "[]", "{}",
        ] {
            let text = format!("{}{}{}", &VALID[..start], replacement, &VALID[end..]);
            try_load(&text);
        }
    }
}

/// An AERONET-style bimodal volume distribution, dV/dlnr (um^3/um^2) at
/// the network's 22 radii (0.05-15 um, log-spaced): fine mode r_v 0.15 um,
/// s 0.45, V 0.03; coarse r_v 2.8 um, s 0.65, V 0.05.
fn aeronet_table() -> (Vec<f64>, Vec<f64>) {
    let radii: Vec<f64> = (0..22)
        .map(|i| 0.05 * (15.0f64 / 0.05).powf(i as f64 / 21.0))
        .collect();
    let values = radii
        .iter()
        .map(|&r| {
            [(0.03, 0.15, 0.45), (0.05, 2.8, 0.65)]
                .iter()
                .map(|&(v, r_v, s): &(f64, f64, f64)| {
                    let z = (r / r_v).ln() / s;
                    v / ((2.0 * std::f64::consts::PI).sqrt() * s) * (-0.5 * z * z).exp()
                })
                .sum()
        })
        .collect();
    (radii, values)
}

/// `VALID` with the dust replaced by a tabulated species of index
/// 1.45 + 0.005i and amount keys `amount` (a line, or empty).
fn with_tabulated_dust(radii: &[f64], values: &[f64], amount: &str) -> String {
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:e}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    VALID.replacen(
        "number_density_m3 = 2.0e6\nprofile.exponential.scale_height_m = 11000\nscattering.mie.refractive_index = { wavelength_nm = [321, 440, 500, 600, 700, 800], n = [1.49, 1.50, 1.50, 1.50, 1.50, 1.50], k = [0.0127, 0.0077, 0.0055, 0.0017, 0.0009, 0.0011] }\nscattering.mie.size_distribution.lognormal = { median_radius_um = 0.5, geometric_std_dev = 1.5, min_radius_um = 0.45, max_radius_um = 0.56 }\nscattering.mie.phase = \"paper-hg\"",
        &format!(
            "{amount}\nprofile.exponential.scale_height_m = 1500\nscattering.mie.refractive_index = {{ n = 1.45, k = 0.005 }}\nscattering.mie.size_distribution.tabulated = {{ radius_um = [{}], dv_dlnr_um3_per_um2 = [{}] }}",
            list(radii),
            list(values)
        ),
        1,
    )
}

/// A measured table's column volume is its amount: the species' optical
/// depth is the column number N = integral dV/dlnr / (4/3 pi r^3) dlnr
/// times the per-particle extinction cross-section, at every wavelength;
/// with `optical_depth` given instead, that optical depth is reached. The
/// atmosphere computes the whole grid with one radius rule shared by its
/// wavelengths (different panels from the one-wavelength rule here): the
/// two agree to 2e-8 (1.5e-7 at the 560-nm reference), hence 1e-6.
#[test]
fn a_tabulated_size_distribution_sets_its_own_amount() {
    use sora::mie::Complex64;
    use sora::mie::distribution::{
        RadiusQuadratureSettings, SizeDistribution, TabulatedVolumeDistribution,
    };
    use sora::mie::ensemble::compute_ensemble_cross_sections;
    let (radii, values) = aeronet_table();
    let text = with_tabulated_dust(&radii, &values, "");
    assert!(text.contains("tabulated"), "the edit must apply");
    let atmosphere = Atmosphere::from_toml_str(&text).unwrap();
    let grid = WavelengthGrid::paper();
    let optics = atmosphere.compute_optics(&grid).unwrap();
    let tau = optics.species[2].optical_depth_extinction();
    let table = TabulatedVolumeDistribution::from_micrometres(&radii, &values).unwrap();
    let column_number_per_m2 = table.column_number_per_m2_from_um3_per_um2();
    let distribution = SizeDistribution::tabulated_volume(table);
    for (i, wavelength_nm) in grid.wavelengths_nm().enumerate().step_by(5) {
        let c_ext = compute_ensemble_cross_sections(
            wavelength_nm,
            Complex64::new(1.45, 0.005),
            &distribution,
            &RadiusQuadratureSettings::cross_sections(),
        )
        .unwrap()
        .extinction_cross_section_m2;
        let expected = column_number_per_m2 * c_ext;
        assert!(
            (tau.values()[i] / expected - 1.0).abs() < 1e-6,
            "{wavelength_nm} nm: {} vs {expected}",
            tau.values()[i]
        );
        // A sane aerosol optical depth for 0.08 um^3/um^2 (AERONET sites: 0.05-0.5).
        assert!((0.02..1.0).contains(&expected), "{expected}");
    }
    let scaled = with_tabulated_dust(
        &radii,
        &values,
        "optical_depth = 0.3\nreference_wavelength_nm = 560",
    );
    let optics = Atmosphere::from_toml_str(&scaled)
        .unwrap()
        .compute_optics(&grid)
        .unwrap();
    let tau_560 = optics.species[2].optical_depth_extinction().values()[9];
    assert!((tau_560 / 0.3 - 1.0).abs() < 1e-6, "{tau_560}");
}

#[test]
fn bad_tables_get_one_line_errors_naming_the_key() {
    let key = "species[2].scattering.mie.size_distribution.tabulated";
    let cases: [(&[f64], &[f64], &str); 5] = [
        (
            &[0.1, 0.3, 0.2],
            &[1.0, 1.0, 1.0],
            "radius 2 = 0.2 um is not greater than the one before it (0.3 um)",
        ),
        (
            &[0.1, 0.2, 0.3],
            &[1.0, -0.5, 1.0],
            "value 1 = -0.5 um^3/um^2 is invalid",
        ),
        (&[0.1], &[1.0], "between 2 and"),
        (&[0.1, 0.2], &[1.0, 2.0, 3.0], "got 2 radii and 3 values"),
        (&[0.0, 0.2], &[1.0, 2.0], "radius 0 = 0 um is invalid"),
    ];
    for (radii, values, expected) in cases {
        let message = load_error(&with_tabulated_dust(radii, values, ""));
        assert!(
            message.contains(key) && message.contains(expected) && !message.contains('\n'),
            "{message}"
        );
    }
    // NaN has no TOML literal in a float list here; `nan` is TOML's spelling.
    let nan = with_tabulated_dust(&[0.1, 0.2], &[1.0, 2.0], "").replace("2e0]", "nan]");
    let message = load_error(&nan);
    assert!(message.contains("value 1 = NaN"), "{message}");
    // A log-normal species still needs an amount.
    let message = load_error(&edit("number_density_m3 = 2.0e6\n", ""));
    assert!(
        message.contains("or neither with a tabulated size distribution"),
        "{message}"
    );
}
