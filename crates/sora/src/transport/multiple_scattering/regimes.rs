//! Every switch of the fast method in one place: which piece applies
//! where. The table in the module docs of
//! [`super`](crate::transport::multiple_scattering) lists them with what
//! each piece adds; a test holds the table and these constants to the same
//! values. Each constant says what was measured to set it.

use std::f64::consts::{FRAC_PI_2, PI};

/// The sun zenith angle from which the field's first order is computed in
/// the spherical shell (`spherical_first_order.rs`) and the spherical
/// streams' every order >= 2 is shifted across the sun nodes solved
/// together (`twilight_shift.rs`), degrees; higher suns keep the column's
/// own first order and the first-order shift of the finished field. The
/// two first orders agree there, and the spherical one costs 10 000
/// marched paths per sun node (20-30 ms per node at 21 wavelengths,
/// earth-clear): nothing for a sun higher than about 16 degrees, whose
/// nodes all stop short of 84 degrees.
pub(super) const FIRST_ORDER_SUN_ZENITH_DEG: f64 = 84.0;

/// The sun zenith angle from which the fine first-order moments
/// (`spherical_first_order.rs`) are integrated, rad: 90 degrees, where the
/// sun sets on the ground. Why not earlier: above the horizon the first
/// order has no narrow peak (measured: the fine moments at every
/// spherical sun node moved suns 0 to 5 degrees by at most 0.3 % on Earth
/// and 1 % on mars-dust) and it would cost half again the image's time
/// at sun 5 degrees. Before them nautical twilight was 8-17 % too dark.
pub(super) const FINE_MOMENTS_SUN_ZENITH_RAD: f64 = FRAC_PI_2;

/// The sun zenith angle, degrees, from which the field's sun nodes narrow
/// from the coarse step ([`super::MultipleScatteringSettings::sun_zenith_step_deg`])
/// toward the fine one, reached at [`SUNSET_STEP_END_DEG`]: where the lower
/// atmosphere's sun sets and the field changes fastest (9 solves for a sun
/// 30 degrees high, 18 for 5 degrees).
pub(super) const SUNSET_STEP_START_DEG: f64 = 70.0;

/// The sun zenith angle, degrees, from which the field's sun nodes are
/// the fine step apart ([`super::MultipleScatteringSettings::sunset_sun_zenith_step_deg`]).
pub(super) const SUNSET_STEP_END_DEG: f64 = 85.0;

/// Streams with |mu| below this (within 17 degrees of the horizon) take
/// the spherical paths (`spherical_paths.rs`); steeper ones keep the
/// slab's recursion: at 24 degrees, the lowest of them with 8 streams per
/// hemisphere, the path through the air below 30 km is within 3 % of the
/// slab's, and moving the limit from 0.3 to 0.5 changes no result against
/// the path tracer by more than its noise.
pub(crate) const SPHERICAL_STREAM_COSINE: f64 = 0.3;

/// The lowest sun elevation at a point, degrees, at which the forward-peak
/// term takes the tilted peak beam (`peak_beam.rs`): below it a point's
/// tilted lines no longer reach lit air (the top's horizon dip is 10-14
/// degrees) and delta-M's beam, zero there, is kept.
pub(super) const PEAK_BEAM_LOWEST_ELEVATION_DEG: f64 = -20.0;

/// The highest sun elevation at a point, degrees, with the tilted peak
/// beam: there B / S is 0.99 (mars-dust, 440 nm; 2.5 with the sun on the
/// horizon).
pub(super) const PEAK_BEAM_HIGHEST_ELEVATION_DEG: f64 = 12.0;

/// From this sun elevation at a point, degrees, to
/// [`PEAK_BEAM_HIGHEST_ELEVATION_DEG`] the tilted beam passes linearly back
/// to delta-M's (B / S 0.97 and 0.96 with the sun 4 and 6 degrees up).
pub(super) const PEAK_BEAM_BLEND_START_DEG: f64 = 8.0;

/// How far above the correction column's last lit sun, degrees, its sun
/// stops (`polarisation_correction.rs`). The column's first order is its
/// own, so a sun below acos(R_ground / R_top) under the horizon (10.1
/// degrees on Earth, top 100 km) leaves every level of it in the shadow,
/// and its ratios were (1, 0, 0, 0): the polarised default stepped 9 %
/// onto the scalar value at sun -10.25 (earth-clear, 560 nm). The
/// column's ratio toward the zenith is flat there (earth-clear, 440/560/660
/// nm: 0.898/0.910/0.916 at -9.5 and 0.899/0.910/0.915 at -10) and the
/// vector path tracer's stays near it below (0.896/0.917/0.921 at -10,
/// 0.876/0.918/0.933 at -12; 200 000 paths, the two sharing their paths).
pub(super) const POLARISATION_COLUMN_MARGIN_DEG: f64 = 0.5;

/// From this many degrees below the correction column's last lit sun
/// (see [`POLARISATION_COLUMN_MARGIN_DEG`]; -12.1 on Earth) the column's
/// polarisation is blended toward unpolarised light, its share falling as
/// exp(-d / [`POLARISATION_FADE_SCALE_DEG`]) with d the degrees past this
/// start: deeper in twilight more of the light at the eye has been
/// scattered many times far toward the sun, and the vector path tracer's
/// (I_vector / I_scalar - 1) at the zenith is 0.66, 0.51 and 0.37 of the
/// column's at -14, -16 and -18 (earth-clear, the mean over 440/560/660 nm).
pub(super) const POLARISATION_FADE_START_DEG: f64 = 2.0;

/// The e-folding of the polarised share below the fade's start, degrees
/// of sun (see [`POLARISATION_FADE_START_DEG`]): 6 puts it at 0.72, 0.51
/// and 0.37 at -14, -16 and -18 on Earth.
pub(super) const POLARISATION_FADE_SCALE_DEG: f64 = 6.0;

/// The forward-peak term's k-fold peak kernel G is tabulated up to this
/// angle from the sun, rad, and the term takes its wide-angle form
/// (one scattering by the whole phase function) beyond it
/// (`forward_peak.rs`): the peaks' k-fold spread has no light left there.
pub(super) const PEAK_KERNEL_RADIUS_RAD: f64 = 30.0 * PI / 180.0;

/// From this angle from the sun, rad, to [`PEAK_KERNEL_RADIUS_RAD`] the
/// forward-peak term passes linearly from the kernel to its wide-angle
/// form.
pub(super) const PEAK_KERNEL_BLEND_START_RAD: f64 = 20.0 * PI / 180.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// Every constant of this file, by name.
    fn constants() -> Vec<(&'static str, f64)> {
        vec![
            ("FIRST_ORDER_SUN_ZENITH_DEG", FIRST_ORDER_SUN_ZENITH_DEG),
            ("FINE_MOMENTS_SUN_ZENITH_RAD", FINE_MOMENTS_SUN_ZENITH_RAD),
            ("SUNSET_STEP_START_DEG", SUNSET_STEP_START_DEG),
            ("SUNSET_STEP_END_DEG", SUNSET_STEP_END_DEG),
            ("SPHERICAL_STREAM_COSINE", SPHERICAL_STREAM_COSINE),
            (
                "PEAK_BEAM_LOWEST_ELEVATION_DEG",
                PEAK_BEAM_LOWEST_ELEVATION_DEG,
            ),
            (
                "PEAK_BEAM_HIGHEST_ELEVATION_DEG",
                PEAK_BEAM_HIGHEST_ELEVATION_DEG,
            ),
            ("PEAK_BEAM_BLEND_START_DEG", PEAK_BEAM_BLEND_START_DEG),
            ("PEAK_KERNEL_RADIUS_RAD", PEAK_KERNEL_RADIUS_RAD),
            ("PEAK_KERNEL_BLEND_START_RAD", PEAK_KERNEL_BLEND_START_RAD),
            (
                "POLARISATION_COLUMN_MARGIN_DEG",
                POLARISATION_COLUMN_MARGIN_DEG,
            ),
            ("POLARISATION_FADE_START_DEG", POLARISATION_FADE_START_DEG),
            ("POLARISATION_FADE_SCALE_DEG", POLARISATION_FADE_SCALE_DEG),
        ]
    }

    /// The regime table of the module docs (`mod.rs`): every cell of its
    /// last column that reads "`NAME` = value", as (NAME, value), values of
    /// `_RAD` constants in degrees (written with a degree sign).
    fn table() -> Vec<(String, f64)> {
        let docs = include_str!("mod.rs");
        let mut rows = Vec::new();
        for line in docs.lines().filter(|l| l.starts_with("//! |")) {
            let cells: Vec<&str> = line.trim_start_matches("//!").split('|').collect();
            let last = cells[cells.len() - 2].trim();
            let Some((name, value)) = last.split_once(" = ") else {
                continue;
            };
            let name = name.trim().trim_matches('`');
            let value = value.trim().trim_end_matches('°').trim();
            if let Ok(value) = value.parse::<f64>() {
                rows.push((name.to_string(), value));
            }
        }
        rows
    }

    #[test]
    fn the_regime_table_lists_every_constant_with_its_value() {
        let source = include_str!("regimes.rs");
        let declared = source
            .lines()
            .filter(|l| l.starts_with("pub(super) const ") || l.starts_with("pub(crate) const "))
            .count();
        let constants = constants();
        assert_eq!(
            declared,
            constants.len(),
            "constants() lists every constant"
        );
        let table = table();
        for (name, _) in &table {
            assert!(
                constants.iter().any(|(n, _)| n == name),
                "the table's {name} is a constant of regimes.rs"
            );
        }
        for (name, value) in constants {
            let rows: Vec<f64> = table
                .iter()
                .filter(|(n, _)| n == name)
                .map(|(_, v)| *v)
                .collect();
            assert!(!rows.is_empty(), "{name} is in the table");
            for in_table in rows {
                let in_code = if name.ends_with("_RAD") {
                    value.to_degrees()
                } else {
                    value
                };
                assert!(
                    (in_table - in_code).abs() <= 1e-12 * in_code.abs().max(1.0),
                    "{name}: the table's {in_table} against the code's {in_code}"
                );
            }
        }
    }
}
