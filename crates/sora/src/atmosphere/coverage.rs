//! # Which wavelengths an atmosphere's tables cover
//!
//! One validation step across keys, run before any optics are computed
//! ([`Atmosphere::compute_optics`]): every table that the optics interpolate
//! in wavelength must cover the whole wavelength grid, and a table that
//! does not is named together with the grid, in one line:
//!
//! - `planet.ground_albedo` (a table),
//! - the sun's spectrum (`sun.spectrum`, a built-in table or `sun.csv_file`),
//! - a Mie species' `scattering.mie.refractive_index` (a table or a
//!   built-in one, e.g. Wolff's Mars dust, 263-2480 nm),
//! - an absorbing gas' `absorption.cross_section_m2` (a table), and the
//!   band table of `[gases]` (200-4000 nm).
//!
//! No extrapolation: a table says nothing outside its rows, and a
//! wavelength grid past them is a mistake in one of the two (a grid chosen
//! for another atmosphere, or a table cut short).

use super::{Atmosphere, SpeciesModel};
use crate::error::{Error, Result};
use crate::mie::refractive_index::RefractiveIndexModel;
use crate::spectrum::{Spectrum, WavelengthGrid};

use super::ozone::AbsorptionCrossSection;

/// Checks that every wavelength table of `atmosphere` covers `grid` (see
/// the module docs); the error names the table's key, its range and the grid.
pub(crate) fn check_grid_coverage(atmosphere: &Atmosphere, grid: &WavelengthGrid) -> Result<()> {
    let (needed_lo, needed_hi) = (grid.start_nm(), grid.stop_nm());
    let check = |key: &str, (lo, hi): (f64, f64)| {
        if needed_lo < lo || needed_hi > hi {
            // Two choices that cannot work together: the table and the grid.
            Err(Error::Unsupported(format!(
                "{key} covers {lo}-{hi} nm but the wavelength grid {grid} spans {needed_lo}-{needed_hi} nm: choose a grid within {lo}-{hi} nm, or extend the table"
            )))
        } else {
            Ok(())
        }
    };
    if let Spectrum::Tabulated(table) = atmosphere.planet.ground_albedo() {
        check("planet.ground_albedo", table.range_nm())?;
    }
    let solar = atmosphere.sun.spectrum();
    if let Spectrum::Tabulated(table) = solar.irradiance_w_m2_nm() {
        check(
            &format!("sun.spectrum ({})", solar.name()),
            table.range_nm(),
        )?;
    }
    for (index, species) in atmosphere.species.iter().enumerate() {
        let path = format!("species[{index}] ({})", species.name);
        match &species.model {
            SpeciesModel::Mie(mie) => {
                if let RefractiveIndexModel::Tabulated(table) = &mie.refractive_index {
                    check(
                        &format!("{path}: scattering.mie.refractive_index"),
                        table.wavelength_range_nm(),
                    )?;
                }
            }
            SpeciesModel::AbsorbingGas(gas) => match &gas.cross_section {
                AbsorptionCrossSection::Tabulated(table) => check(
                    &format!("{path}: absorption.cross_section_m2"),
                    table.range_nm(),
                )?,
                AbsorptionCrossSection::Band(band) => {
                    check(&format!("{path}: its band table"), band.range_nm())?
                }
                AbsorptionCrossSection::Binned(_) => {}
            },
            SpeciesModel::Rayleigh(_) | SpeciesModel::ParametricAerosol(_) => {}
        }
    }
    Ok(())
}
