//! Multiple scattering: sunlight scattered two or more times, and skylight
//! reflected by the ground, added to [`super::single_scattering`]'s
//! radiance (which stays exact and keeps the sun's single scattering and the
//! directly sunlit ground). Spectral on the sky's wavelength grid, for any
//! species list (absorbing gases, Rayleigh, parametric and Mie aerosols)
//! and a Lambertian ground. Radiance in W m^-2 sr^-1 nm^-1.
//!
//! # The method
//! 1. **The diffuse field of a column** (`successive_orders.rs`): the
//!    radiative transfer equation of a plane-parallel column, in discrete
//!    ordinates (double-Gauss, 2n streams), a Fourier series in azimuth (2n
//!    harmonics) and delta-M truncated phase functions
//!    (`phase_fourier.rs`; Wiscombe 1977), on 40 layers
//!    (`vertical_grid.rs`) with a source linear in optical depth within
//!    each: the physics and discretisation of DISORT (Stamnes et al. 1988),
//!    solved by successive orders of scattering with geometric
//!    extrapolation instead of eigenvectors. The sun's beam is attenuated
//!    along its real path through the spherical shell, zero in the planet's
//!    shadow (the pseudo-spherical approximation, Dahlback & Stamnes 1991),
//!    so the field exists for a sun below the horizon too. One solve per
//!    wavelength and per sun zenith angle.
//! 2. **Spherical paths for the near-horizontal streams**
//!    (`spherical_paths.rs`): the streams near the horizon are carried
//!    along their real straight paths through the spherical shells (which
//!    climb out to space instead of running on forever, as a slab's
//!    would), and their light is shifted toward the sun angle of the
//!    columns where it was gathered (`twilight_shift.rs`): the finished
//!    field to first order for a high sun; from the sun zenith angle where
//!    the first order turns spherical (item 3) the columns of all those
//!    sun nodes are solved together, order by order, and each order >= 2
//!    of these streams is read at its shifted sun angle, per azimuth, by
//!    interpolation across the sun nodes linear in the logarithm, averaged
//!    over the mean angle +- its spread, before it is scattered into the
//!    next.
//! 3. **The first order in the sphere** (`spherical_first_order.rs`): at
//!    the low sun nodes the light scattered once that reaches each level
//!    in each stream is marched along the stream's straight path through
//!    the spherical shell, with the planet's shadow tested at every
//!    sample, and the solver's sweeps take it in place of their own first
//!    order (so every higher order is fed by it). After sunset this is
//!    what lights the shadowed air: light scattered in the sunlit layer
//!    toward the sun, far from the point's own column. That light is a
//!    peak a few hundredths wide in the zenith cosine, just above the
//!    sunward horizon; after sunset on the ground its Legendre moments
//!    (all the solver, the views and the tables take from it) are
//!    integrated on a grid graded toward each level's horizon and the
//!    streams' values fitted to them, instead of the streams' own
//!    quadrature.
//! 4. **The sphere as local columns**: the diffuse field at a point x of
//!    the spherical atmosphere is taken to be that of the column at x's
//!    altitude with x's own sun zenith angle, as Bruneton & Neyret (2008)
//!    and Hillaire (2020) parametrise their tables by (r, mu_s). The field
//!    is solved at the sun zenith angles the eye's view rays meet:
//!    [`MultipleScatteringField::compute`] covers every point visible from
//!    the eye (about +-10 degrees around the eye's sun zenith angle on the
//!    ground), 3 degrees apart for a high sun and 0.75 degrees near and
//!    after sunset, where the lower atmosphere's sun sets and the field
//!    changes fastest (9 solves for a sun 30 degrees high, 18 for 5
//!    degrees).
//! 5. **Source-function integration along the real view ray**: with the
//!    scattering source of the diffuse field
//!    J(x, w) = sum_j beta*_sca,j(x) integral p*_j(w.w') L_diffuse(x, w') dw'
//!    (synthesised from the harmonics at the view direction's local zenith
//!    angle and azimuth from the sun),
//!
//!    ```text
//!    L_ms(eye, w) = integral_0^S T*(eye, x) J(x, w) ds
//!                 + [ray ends on the ground] T*(eye, x_g) (A / pi) F_diffuse(x_g)
//!    ```
//!
//!    along the straight ray through the spherical shell, on 16 Gauss
//!    panels as the single-scattering fast path; T* and beta* are delta-M
//!    scaled. This is the TMS method of Nakajima & Tanaka (1988): the scaled
//!    problem supplies orders >= 2, single scattering is computed with the
//!    real phase functions. TMS's single scattering uses the scaled
//!    transmittances T* and T*_sun (light scattered into a forward peak
//!    travels on with the beam); [`super::single_scattering`] uses the real
//!    ones, so the difference is added here as the **forward-peak term**
//!    (`forward_peak.rs`): light scattered k >= 1 times in the truncated
//!    peaks r = p - (1 - f) p* and once by the smooth part,
//!    E sum_j beta_sca,j (1 - f_j) p*_j(theta) integral rho_j (T* T*_sun - T T_sun) ds,
//!    and light scattered only in the peaks, k >= 2 times, spread by the
//!    k-fold convolution of the peak (Legendre moments (r_l / f)^k), each
//!    path counted once: negligible for the reference aerosol (HG g = 0.7,
//!    f = 0.3 %), but a Mie dust's diffraction peak holds f ~ 40 %. Near a
//!    low sun the peaks' light reaching x is not taken along the sun's line
//!    through x but with the last peak scattering at its angle
//!    (`peak_beam.rs`): near the horizon that line is the most attenuated a
//!    point has, and light scattered a few degrees down comes from higher
//!    air. The ground term likewise carries what delta-M moved from the
//!    diffuse to the direct beam (forward-scattered sunlight on the ground,
//!    and the sunlit ground's light forward-scattered toward the eye).
//! 6. **Tables for images**: [`MultipleScatteringTable`] tabulates
//!    ln(J / beta*_sca) over (altitude, sun zenith angle, view zenith angle,
//!    azimuth from the sun), read quadrilinearly, only where view rays can
//!    reach; the sky-view table ([`super::sky_view_table`]) stores the
//!    resulting L_ms per view direction. Views ([`crate::Sky::radiance`],
//!    `sora spectrum`) synthesise J exactly at every node
//!    ([`MultipleScatteringField::compute_radiance`], the obvious path the
//!    table is tested against), from the field's Legendre moments: the
//!    same sums as the table's kernels with the view direction factored
//!    out, so a view costs degrees^2 / 2 products per node and wavelength
//!    (an almucantar of 72 views about as much as the field itself).
//! 7. **Polarisation** (a sky with Stokes vectors, views and images): the
//!    column at the eye's sun is solved again with Stokes vectors
//!    (`vector_successive_orders.rs`, `phase_matrix_fourier.rs`), and the
//!    ratio of its multiply scattered (I, Q, U, V) to its scalar intensity
//!    turns the scaled field's part of each view's L_ms into a Stokes
//!    vector (`polarisation_correction.rs`, tabulated over directions for
//!    images; accuracy in `docs/polarisation.md`); the forward-peak term is
//!    polarised as single scattering through the view's angle
//!    (`forward_peak.rs`).
//!
//! Interpolations between sun zenith angles and altitudes are linear in
//! the logarithm of the (positive) source: across sunset the field falls
//! off exponentially, and a linear blend of two nodes overestimates it.
//!
//! # Regimes
//! Which piece applies where; every switch is a constant of `regimes.rs`,
//! documented there with the measurement that set it (a test holds this
//! table and those constants to the same values).
//!
//! | piece | what it adds | applies when | constant |
//! |---|---|---|---|
//! | plane-parallel successive orders (`successive_orders.rs`) | the diffuse field of one column: delta-M, 2n streams, 2n harmonics | always | - |
//! | pseudo-spherical sun beam | T*_sun along the real path, zero in the shadow | always | - |
//! | spherical paths (`spherical_paths.rs`) | the real path lengths of the near-horizontal streams | streams with \|mu\| below | `SPHERICAL_STREAM_COSINE` = 0.3 |
//! | first-order shift of the finished field (`twilight_shift.rs`) | the near-horizontal light's horizontal displacement, to first order | sun nodes below (zenith, deg) | `FIRST_ORDER_SUN_ZENITH_DEG` = 84 |
//! | every-order shift, nodes solved together (`twilight_shift.rs`) | each order >= 2 of the spherical streams read at its sun angle | sun nodes from (zenith, deg) | `FIRST_ORDER_SUN_ZENITH_DEG` = 84 |
//! | spherical first order (`spherical_first_order.rs`) | the first order marched through the shell, with the shadow | sun nodes from (zenith, deg) | `FIRST_ORDER_SUN_ZENITH_DEG` = 84 |
//! | fine first-order moments | the narrow near-horizon peak of the first order after sunset | sun nodes from (zenith) | `FINE_MOMENTS_SUN_ZENITH_RAD` = 90° |
//! | sunset sun-node spacing | sun nodes narrowing from the coarse to the fine step | from (zenith, deg) | `SUNSET_STEP_START_DEG` = 70 |
//! | sunset sun-node spacing | sun nodes the fine step apart | from (zenith, deg) | `SUNSET_STEP_END_DEG` = 85 |
//! | forward-peak term (`forward_peak.rs`) | what delta-M moved out of single scattering (TMS) | any species with a truncated peak | - |
//! | k-fold peak kernel | the peak-only light, spread by the peak's k-fold convolution | within this of the sun | `PEAK_KERNEL_RADIUS_RAD` = 30° |
//! | kernel to wide-angle blend | linear passage to one scattering by the whole phase function | from this from the sun | `PEAK_KERNEL_BLEND_START_RAD` = 20° |
//! | tilted peak beam (`peak_beam.rs`) | the last peak scattering at its angle | point's sun elevation from (deg) | `PEAK_BEAM_LOWEST_ELEVATION_DEG` = -20 |
//! | tilted peak beam | (as above) | point's sun elevation below (deg) | `PEAK_BEAM_HIGHEST_ELEVATION_DEG` = 12 |
//! | tilted peak beam blend | linear passage back to delta-M's beam | point's sun elevation from (deg) | `PEAK_BEAM_BLEND_START_DEG` = 8 |
//! | polarisation ratio (`polarisation_correction.rs`) | (I, Q, U, V) / I of the orders >= 2 | `Polarisation::Vector`, every sun: one column at the eye's sun, with its own first order and no shift | - |
//!
//! # Why not Hillaire (2020)
//! Hillaire's table of the multiply scattered luminance per (altitude,
//! mu_s), 64 directions per cell and the series 1 / (1 - f_ms), assumes
//! isotropic scattering for every order >= 2. Measured in this solver by
//! replacing the phase functions of orders >= 2 by isotropic ones (the
//! exact single scattering kept): errors against DISORT up to 12 % with a
//! black ground and 34 % with albedo 0.3 on `clear-sky-reference` (its
//! g = 0.7 aerosol sends ground light back up, not down into the sky; the
//! isotropic assumption sends a third of it down). Computing the second
//! order with the real phase functions and keeping the isotropic series
//! for the rest would still leave the third and higher orders (a third of
//! the multiply scattered light in the blue) isotropic. Bruneton's 4D
//! scattering-order tables are too slow at 21 wavelengths on a CPU. The
//! discrete-ordinate field costs about as much per sun zenith angle as
//! Hillaire's table and treats every order with the real phase functions.
//!
//! # Accuracy (measured; the tests named hold it)
//! - Against DISORT (plane-parallel, every row of the clear-sky reference,
//!   single + multiple scattering): worst 0.074 % (black ground) and
//!   0.061 % (albedo 0.3) with the exact synthesis, 0.10 % and 0.14 %
//!   through the tables of an image
//!   (`reference_tests/multiple_scattering_reference.rs`:
//!   `black_ground_matches_disort_at_every_row`,
//!   `bright_ground_matches_disort_at_every_row`).
//! - Against the Monte Carlo path tracer on the spherical planet
//!   (`clear-sky-reference`, 400 000 paths per view, 14 views from the
//!   zenith to 1 degree above the horizon, every wavelength): suns 90 to 10
//!   degrees within 0.9 %; sun 5 degrees within 1.6 %, the worst 1 degree
//!   above the horizon at 380 nm. An eye 10 km up, and a ground of albedo
//!   0.3: within 1.1 % (100 000 paths)
//!   (`spherical_sky_matches_the_path_tracer_within_two_percent`,
//!   `spherical_sky_matches_the_path_tracer_exhaustively`).
//! - Exact Mie phase functions (`earth-hazy`, suns 30 and 5 degrees, views
//!   away from the sun, 400 000 paths): within 1.7 %; `mars-dust` (100 000
//!   paths) within 2 % for a sun 30 degrees high
//!   (`mie_aerosols_match_the_path_tracer_away_from_the_sun`).
//! - Near a low sun (`docs/twilight_survey.md`, 400 000 and 800 000 paths,
//!   standard errors 0.1-0.5 % there; `tests/twilight.rs`:
//!   `near_a_low_sun_with_aerosols_matches_the_path_tracer`,
//!   `the_sun_on_the_horizon_through_dust_matches_the_path_tracer`):
//!   `mars-dust` within 0.8 % of the path tracer 2 to 10 degrees from a sun
//!   10 and 5 degrees high (its orders >= 2 within 1.6 %), `earth-hazy`
//!   within 0.7 % 2 to 5 degrees from a sun 5 degrees high, -1.1 and -0.9 %
//!   at 560 and 680 nm 2 degrees above a sun 2 degrees high. Toward a sun
//!   2 degrees high `mars-dust` is within 2.3 %, `earth-hazy` 2 degrees
//!   along the horizon from it -3.3 and -4.3 % at 560 and 680 nm (+-0.4,
//!   0.9 %). Every one of the 120 values 1 and 2 degrees up within 5
//!   degrees of a sun at 5 to -2 degrees (mars-dust, earth-hazy) is within
//!   3 % + 3 standard errors. The weakest place is `mars-dust` 1 degree up
//!   with the sun on the horizon or 2 degrees down, where the eye sees
//!   almost only multiply scattered light, most of it in the dust's peak:
//!   with 1 600 000 paths (standard errors 0.35-0.8 %) -0.6 to -3.6 %, the
//!   worst at 440 nm. What is missing there is the peak scatterings on the
//!   view's side at their angles (another +1.7 to +3.2 % there, measured,
//!   left out for its cost per pixel).
//! - Civil twilight (`reference_tests/twilight_survey.rs`,
//!   `tests/twilight.rs`: `civil_twilight_matches_the_path_tracer`,
//!   `sun_six_below_matches_the_path_tracer_at_three_wavelengths`,
//!   `twilight_matches_the_path_tracer_over_the_whole_grid`): the zenith
//!   and elevations 5 and 20 degrees at 0, 90 and 180 degrees from the
//!   sun, 440/560/680 nm, suns -2, -4, -6, 800 000 paths: all 189 values
//!   of `earth-clear`, `earth-hazy` and `us-standard-1976-rayleigh` within
//!   3 % + 3 standard errors, the worst -4.5 to -4.8 % at -6 degrees before
//!   the every-order shift (item 2), which moved them by 0 to +3.1 %.
//!   `mars-dust` (400 000 paths): 61 of 63 within, medians +1.7, +3.1,
//!   +4.3 %; the two outside are 5 degrees up away from a sun at -4 at 440
//!   and 560 nm, +22 and +15 % (+-4.7, 3.7), +11 and +8 % with 800 000
//!   paths. The issue's other views (1 degree up at 0-180 degrees from the
//!   sun, 45/135 degrees at 5, 20 and 45 up; 4 presets, suns 10 to -6, 924
//!   values): all 693 earth values within; `mars-dust`'s antisolar horizon
//!   in civil twilight leans bright (+0.4 to +15.7 % 1 degree up,
//!   +-2.2-4.5, within). The single scattering is exact (within 0.1 % of
//!   the paper's double march at 16 000 steps, and of the path tracer's),
//!   the second order within 1-2 % (sun -6, 1 600 000 paths): what remains
//!   is the orders >= 3, a few per cent too dark at 440 nm toward the sun
//!   and at the zenith (the steeper streams' sources are their own
//!   column's, item 4), and 8 streams per hemisphere (16 move the zenith at
//!   -6 degrees by +0.3 to +0.5 %, `nautical_twilight_is_converged_in_the_streams`).
//! - **Deep twilight** (`docs/twilight_survey.md`, against the path
//!   tracer with its directions toward the sunlit air, 1 000 000 paths a
//!   view; the zenith and 5, 20, 45 degrees up at 0, 90, 180 degrees from
//!   the sun, 440/560/680 nm): earth-clear +0.2 to +5.4 %, earth-hazy +1.2
//!   to +7.9 % and us-standard +0.2 to +3.0 % at -8 to -12 degrees; all 180
//!   earth values within 5 % + 3 standard errors (earth-clear's medians
//!   +0.1, -3.4, -2.3 %, earth-hazy's +2.4, +4.1, +4.4 %; the one earth-hazy
//!   value at -12 that 1 000 000 paths put outside is +6.3 % +-3.2 with
//!   3 200 000), us-standard's 30 of 30 within. earth-clear leans dark in
//!   the blue at -10 and -12.
//!
//! The history of these numbers (what each piece changed, measured before
//! and after it) is in `docs/twilight_survey.md`.
//!
//! # Cost (measured, `benches/multiple_scattering.rs`, 2 shared cores)
//! The field is solved per wavelength and sun node, 9 nodes for a sun 30
//! degrees high and 18 for 5 degrees (21 wavelengths, `clear-sky-reference`:
//! the field 0.12 s and the source table 0.08 s at sun 30, 0.22 s and 0.16
//! s at sun 5, before the twilight pieces). The spherical first order adds
//! 20-30 ms per sun node it applies to (10 000 marched paths each;
//! earth-clear, 21 wavelengths), its fine moments and shells about as much
//! again after sunset, and the twilight shift about 0.1 s at 21
//! wavelengths; none of them applies to a sun higher than about 16
//! degrees. An earth-clear 512 x 512 fisheye with `--polarisation off`
//! takes about 1.7 s at sun 5 degrees and 2.1 s at sun -6 on the quiet
//! 2-core machine (peak memory 123 MiB: the field, 20-70 MB at twilight, is
//! kept in the solver's own layout and shared with its source table);
//! `cargo bench --bench multiple_scattering -- twilight` gives 1.91 s
//! (1.86-1.97).
//!
//! # What it approximates
//! - Diffuse light between nearby points travels as in a column of uniform
//!   horizontal layers with one sun zenith angle, except for the
//!   near-horizontal streams' paths and their first-order shift, and for
//!   the spherical first order (Regimes): exact in the
//!   plane-parallel limit, good for a sun above 5 degrees, within a few
//!   per cent in civil twilight. The steeper streams' orders >= 2 still
//!   take their sources from their own column's sun angle (shifting them
//!   too moved no mars-dust twilight view by more than 1.4 %).
//! - Delta-M: orders >= 2 within the phase functions' forward peak of the
//!   sun are smoothed (the aureole itself is single scattering, exact);
//!   the peak-only light of the forward-peak term takes its k-fold
//!   convolution of the peak in the small-angle sense (its paths' legs
//!   all near the sun's line, their mean peak optical depth along the
//!   view ray). The peaks' light reaching a point near a low sun takes
//!   its last scattering at its angle, the earlier ones exactly forward,
//!   and the peak scatterings on the view's side stay exactly forward
//!   (`peak_beam.rs`): with the sun on the horizon, mars-dust 1 degree up
//!   within 5 degrees of it, or 2 degrees below it, is 0.6-3.6 % too
//!   dark (`docs/twilight_survey.md`, its last section).
//! - 2n streams and harmonics, 40 layers, the source linear in optical
//!   depth across a layer, and the tables' interpolations.
//!
//! # Units
//! Radiances W m^-2 sr^-1 nm^-1, irradiances W m^-2 nm^-1, coefficients
//! m^-1 at relative density 1 (as [`crate::atmosphere::AtmosphereOptics`]),
//! altitudes m, angles rad inside (degrees in settings).

mod forward_peak;
mod peak_beam;
mod phase_fourier;
mod phase_matrix_fourier;
mod polarisation_correction;
mod regimes;
mod source_table;
mod spherical_first_order;
mod spherical_paths;
mod successive_orders;
mod twilight_shift;
mod vector_successive_orders;
mod vertical_grid;

pub use source_table::MultipleScatteringTable;

use std::f64::consts::{FRAC_PI_2, PI};
use std::ops::ControlFlow;

use self::forward_peak::ForwardPeak;
use self::peak_beam::{PeakBeam, PeakBeamInputs};
use self::phase_fourier::{
    TruncatedPhase, compute_truncated_phases, normalized_associated_legendre,
};
pub(crate) use self::polarisation_correction::PolarisationTable;
use self::polarisation_correction::{CorrectionInputs, PolarisationCorrection};
use self::regimes::{FIRST_ORDER_SUN_ZENITH_DEG, SUNSET_STEP_END_DEG, SUNSET_STEP_START_DEG};
use self::spherical_first_order::{
    FirstOrderInputs, MomentQuadrature, compute_spherical_first_order,
};
use self::spherical_paths::StreamPaths;
use self::successive_orders::{ColumnSystem, ScaledSpecies, Streams};
use self::vertical_grid::VerticalGrid;
use super::optical_column::{PanelMarch, ProfileCorners, compute_columns_along_ray};
use super::single_scattering::{SingleScatteringSky, SunColumns};
use super::vector_exp::exp_neg_in_place;
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::atmosphere::{AtmosphereOptics, DensityProfile};
use crate::error::{Error, Result};
use crate::geometry::{Vector3, segment_in_atmosphere};

/// Panels of the exact column integrals toward the sun from each level.
const SUN_RAY_PANELS: usize = 12;

/// Altitude and mu nodes of the sun-column table of the spherical first
/// order in the tests' fields: the default image tables' size
/// ([`crate::FastTableSize`]; a sky's field takes its own image tables'
/// size, see [`MultipleScatteringField::compute_with_sun_column_nodes`]).
#[cfg(test)]
const FIRST_ORDER_SUN_COLUMN_NODES: (usize, usize) = (128, 256);

/// Resolution of the multiple-scattering method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultipleScatteringSettings {
    /// Discrete ordinates per hemisphere (the solver has twice as many
    /// streams, Legendre terms and azimuthal harmonics).
    pub streams_per_hemisphere: usize,
    /// Layers of the vertical grid.
    pub layers: usize,
    /// Step between the sun zenith angles at which the field is solved
    /// for a high sun, degrees.
    pub sun_zenith_step_deg: f64,
    /// The step near and below the horizon (zenith angles from
    /// `SUNSET_STEP_END_DEG`, 85 degrees),
    /// where the field changes fastest, degrees.
    pub sunset_sun_zenith_step_deg: f64,
    /// Gauss panels along each view ray.
    pub view_ray_panels: usize,
    /// Source table: view zenith nodes (0..180 degrees).
    pub table_view_zenith_nodes: usize,
    /// Source table: relative azimuth nodes (0..180 degrees).
    pub table_azimuth_nodes: usize,
}

impl Default for MultipleScatteringSettings {
    fn default() -> MultipleScatteringSettings {
        MultipleScatteringSettings {
            streams_per_hemisphere: 8,
            layers: 40,
            sun_zenith_step_deg: 3.0,
            sunset_sun_zenith_step_deg: 0.75,
            view_ray_panels: 16,
            table_view_zenith_nodes: 37,
            table_azimuth_nodes: 19,
        }
    }
}

impl MultipleScatteringSettings {
    /// Checks that every count and step can make a solver: at least one
    /// stream per hemisphere (at most 32), two layers, two panels, two
    /// nodes per table axis, and positive steps.
    pub(crate) fn validate(&self) -> Result<()> {
        let counts = [
            ("streams per hemisphere", self.streams_per_hemisphere, 1, 32),
            ("multiple-scattering layers", self.layers, 2, 10_000),
            ("view-ray panels", self.view_ray_panels, 2, 10_000),
            (
                "source-table view zenith nodes",
                self.table_view_zenith_nodes,
                2,
                10_000,
            ),
            (
                "source-table azimuth nodes",
                self.table_azimuth_nodes,
                2,
                10_000,
            ),
        ];
        for (name, value, low, high) in counts {
            if !(low..=high).contains(&value) {
                return Err(Error::out_of_range(
                    name,
                    value as f64,
                    "",
                    format!("{low}..={high}"),
                ));
            }
        }
        for (name, value) in [
            ("sun zenith step", self.sun_zenith_step_deg),
            ("sunset sun zenith step", self.sunset_sun_zenith_step_deg),
        ] {
            if !(value.is_finite() && value > 0.0 && value <= 90.0) {
                return Err(Error::out_of_range(name, value, "deg", "> 0 and <= 90"));
            }
        }
        Ok(())
    }
}

/// Sun zenith angles at which the field is solved, increasing.
#[derive(Debug, Clone)]
struct SunZenithAxis {
    angles_rad: Vec<f64>,
}

impl SunZenithAxis {
    /// Nodes covering `lowest..=highest` (rad), one of them at `centre`
    /// (the eye's own sun zenith angle, where the nearest and so brightest
    /// part of every view ray is), spaced by `coarse` for a high sun and
    /// narrowing to `fine` from `SUNSET_STEP_START_DEG` (70 degrees) to
    /// `SUNSET_STEP_END_DEG` (85) and beyond, where the
    /// lower atmosphere's sun sets and the field changes fastest; but never
    /// closer than a quarter of the distance from `centre`: far from the
    /// eye's own sun angle lie only the far ends of grazing view rays, high
    /// in thin air.
    fn new(lowest: f64, highest: f64, centre: f64, coarse: f64, fine: f64) -> SunZenithAxis {
        let (start, end) = (
            SUNSET_STEP_START_DEG.to_radians(),
            SUNSET_STEP_END_DEG.to_radians(),
        );
        let centre = centre.clamp(lowest, highest);
        let step = |theta: f64| {
            let t = ((theta - start) / (end - start)).clamp(0.0, 1.0);
            let local = coarse + t * (fine - coarse);
            local
                .max(0.25 * (theta - centre).abs())
                .min(coarse.max(fine))
        };
        let mut below = vec![centre];
        while *below.last().unwrap() > lowest {
            let theta = *below.last().unwrap();
            below.push((theta - step(theta - 0.5 * step(theta))).max(0.0));
            if theta == 0.0 {
                break;
            }
        }
        below.dedup();
        let mut angles_rad: Vec<f64> = below.into_iter().rev().collect();
        while *angles_rad.last().unwrap() < highest {
            let theta = *angles_rad.last().unwrap();
            angles_rad.push(theta + step(theta + 0.5 * step(theta)));
        }
        if angles_rad.len() < 2 {
            angles_rad.push(angles_rad[0] + fine);
        }
        SunZenithAxis { angles_rad }
    }

    fn count(&self) -> usize {
        self.angles_rad.len()
    }

    fn angle(&self, s: usize) -> f64 {
        self.angles_rad[s]
    }

    /// Lower node and fraction for a sun zenith cosine (clamped to the axis).
    fn locate(&self, sun_cosine: f64) -> (usize, f64) {
        let theta = sun_cosine.clamp(-1.0, 1.0).acos();
        let angles = &self.angles_rad;
        let upper = angles.partition_point(|a| *a <= theta);
        let s = upper.clamp(1, angles.len() - 1) - 1;
        let t = (theta - angles[s]) / (angles[s + 1] - angles[s]);
        (s, t.clamp(0.0, 1.0))
    }
}

/// Values below this are treated as zero by the logarithmic
/// interpolations (radiances are ~1e-6..1 W m^-2 sr^-1 nm^-1).
const LOG_FLOOR: f64 = 1e-30;

/// ln R below which the march takes the source as zero: e^-46 = 1e-20
/// W m^-2 sr^-1 nm^-1 (the logarithms' floor is ln 1e-30 = -69), far below
/// the night floor ([`crate::colour::NIGHT_FLOOR_CD_M2`], ~1e-11 in these
/// units).
const DARK_LOG_SOURCE: f64 = -46.0;

/// ln of a non-negative value, floored.
fn floored_log(value: f64) -> f64 {
    value.max(LOG_FLOOR).ln()
}

/// a^(1 - t) b^t for positive a, b: exact for quantities that change
/// exponentially between nodes, as everything does across sunset; linear
/// when an end is zero (a ground that reflects nothing, or has no sun).
fn interpolate_geometrically(a: f64, b: f64, t: f64) -> f64 {
    if a > 0.0 && b > 0.0 {
        ((1.0 - t) * a.ln() + t * b.ln()).exp()
    } else {
        (1.0 - t) * a + t * b
    }
}

/// What the view-ray march needs, shared by the field and its table.
#[derive(Debug, Clone)]
struct ViewRayOptics {
    wavelengths: usize,
    species: usize,
    panels: usize,
    ground_radius_m: f64,
    top_radius_m: f64,
    observer: Vector3,
    sun: Vector3,
    profiles: Vec<DensityProfile>,
    /// Where the profiles have corners: rays are cut there.
    corners: ProfileCorners,
    /// [i * species + j], m^-1 at relative density 1.
    extinction: Vec<f64>,
    scaled_extinction: Vec<f64>,
    scaled_scattering: Vec<f64>,
    sun_axis: SunZenithAxis,
    /// Whether any phase function lost a forward peak to delta-M.
    has_forward_peaks: bool,
    /// The forward-peak term's tables (`forward_peak.rs`).
    forward_peak: ForwardPeak,
    /// Near a low sun, the beam of the peaks' light with the last
    /// scattering at its angle (`peak_beam.rs`), for that term.
    peak_beam: Option<PeakBeam>,
    /// [s * wavelengths + i]: (A / pi)(F*_diffuse + E mu_s (T*_sun - T_sun))
    /// at the ground, W m^-2 sr^-1 nm^-1.
    ground_diffuse: Vec<f64>,
    /// [s * wavelengths + i]: (A / pi) E mu_s T_sun at the ground.
    ground_direct: Vec<f64>,
}

/// Per-ray work space of the march.
#[derive(Debug, Clone)]
pub struct MultipleScatteringScratch {
    /// The view ray's march, and at its current node the species'
    /// relative densities and columns from the eye; the whole ray's
    /// columns after it.
    march: PanelMarch,
    densities: Vec<f64>,
    view_columns: Vec<f64>,
    node_columns: Vec<f64>,
    /// ln R(x, view) per wavelength at the current node (R = J / beta*_sca,
    /// radiance units).
    log_source: Vec<f64>,
    /// Lambda table of the view direction times cos(m phi) (exact
    /// synthesis), [m * streams + l].
    view_legendre: Vec<f64>,
    /// Columns from the current node toward the sun, m.
    sun_columns: Vec<f64>,
    /// Ends of the Gauss panels of the view ray and of a path toward the
    /// sun, m along each.
    view_panel_ends: Vec<f64>,
    sun_panel_ends: Vec<f64>,
    /// The forward-peak integrals of the last ray, species-major
    /// [j * wavelengths + i], m, then the peak-only rows Q and Q X-bar
    /// (`forward_peak.rs`; see [`MultipleScatteringTable::compute_radiance_parts`]).
    forward_integrals: Vec<f64>,
    phase: Vec<f64>,
    forward_radiance: Vec<f64>,
    /// The tilted peak beam B at the current node (`peak_beam.rs`), and
    /// the node's optical depths / transmittances and peak scattering
    /// coefficients and X there ([`ViewRayOptics::add_tilted_forward_peak`]).
    beam: Vec<f64>,
    tilted_depths: Vec<f64>,
    tilted_peak: Vec<f64>,
}

impl MultipleScatteringScratch {
    /// The forward-peak integrals of the last ray: integral rho_j
    /// (T* T*_sun - T T_sun) ds, species-major [j * wavelengths + i], m,
    /// then the peak-only rows Q = integral (sum_j f_j beta_sca,j rho_j)
    /// T T_sun ds and Q X-bar (dimensionless), as
    /// [`MultipleScatteringField::compute_forward_peak_radiance`] takes them.
    pub(crate) fn forward_integrals(&self) -> &[f64] {
        &self.forward_integrals
    }

    /// The forward-peak term of the last ray (zero for a sky without
    /// peaks), W m^-2 sr^-1 nm^-1: the part of the radiance
    /// [`MultipleScatteringField::compute_radiance`] gave that is not the
    /// scaled field's.
    pub(crate) fn forward_radiance(&self) -> &[f64] {
        &self.forward_radiance
    }
}

/// Local geometry of a march node.
#[derive(Debug, Clone, Copy)]
struct NodeGeometry {
    altitude_m: f64,
    sun_cosine: f64,
    view_cosine: f64,
    cos_azimuth: f64,
}

impl ViewRayOptics {
    fn scratch(&self, streams: usize) -> MultipleScatteringScratch {
        let (s, w) = (self.species, self.wavelengths);
        MultipleScatteringScratch {
            march: PanelMarch::new(s),
            densities: vec![0.0; s],
            view_columns: vec![0.0; s],
            node_columns: vec![0.0; s],
            log_source: vec![0.0; w],
            view_legendre: vec![0.0; streams * streams],
            sun_columns: vec![0.0; s],
            view_panel_ends: Vec::with_capacity(self.corners.most_panel_ends(self.panels)),
            sun_panel_ends: Vec::with_capacity(self.corners.most_panel_ends(SUN_RAY_PANELS)),
            forward_integrals: vec![0.0; (s + forward_peak::EXTRA_ROWS) * w],
            phase: vec![0.0; w],
            forward_radiance: vec![0.0; w],
            beam: vec![0.0; w],
            tilted_depths: vec![0.0; 4 * w],
            tilted_peak: vec![0.0; 2 * w],
        }
    }

    /// Adds the forward-peak term of the scratch's integrals along `view`
    /// to `radiance` (`forward_peak.rs`).
    fn add_forward_peak(
        &self,
        optics: &AtmosphereOptics,
        view: Vector3,
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        if !self.has_forward_peaks {
            return;
        }
        self.forward_peak.radiance(
            optics,
            view.dot(self.sun),
            &scratch.forward_integrals,
            &mut scratch.phase,
            &mut scratch.forward_radiance,
        );
        for (r, f) in radiance.iter_mut().zip(&scratch.forward_radiance) {
            *r += f;
        }
    }

    /// Integrates T*(eye, x) beta*_sca(x) R(x) along the view ray, with
    /// `source` writing ln R at each node into `scratch.log_source`, and
    /// adds the ground's diffuse term.
    fn march<F>(
        &self,
        view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
        mut source: F,
    ) where
        F: FnMut(NodeGeometry, &[f64], &mut MultipleScatteringScratch),
    {
        radiance.fill(0.0);
        scratch.forward_integrals.fill(0.0);
        let (w, s) = (self.wavelengths, self.species);
        let Some((enter, exit)) =
            segment_in_atmosphere(self.observer, view, self.ground_radius_m, self.top_radius_m)
        else {
            return;
        };
        let start = self.observer + view * enter;
        let length = exit - enter;
        scratch.view_columns.fill(0.0);
        if length > 0.0 {
            let mut view_ends = std::mem::take(&mut scratch.view_panel_ends);
            self.corners
                .fill_panel_ends(start, view, length, self.panels, &mut view_ends);
            let mut march = std::mem::take(&mut scratch.march);
            march.march(
                &self.profiles,
                self.ground_radius_m,
                (start, view),
                &view_ends,
                |node, node_columns, densities| {
                    scratch.node_columns.copy_from_slice(node_columns);
                    scratch.densities.copy_from_slice(densities);
                    let r = node.point.length();
                    let zenith = node.point * (1.0 / r);
                    let view_cosine = view.dot(zenith).clamp(-1.0, 1.0);
                    let sun_cosine = self.sun.dot(zenith).clamp(-1.0, 1.0);
                    let sines = ((1.0 - view_cosine * view_cosine)
                        * (1.0 - sun_cosine * sun_cosine))
                        .sqrt();
                    let cos_azimuth = if sines > 1e-12 {
                        ((view.dot(self.sun) - view_cosine * sun_cosine) / sines).clamp(-1.0, 1.0)
                    } else {
                        1.0
                    };
                    let geometry = NodeGeometry {
                        altitude_m: r - self.ground_radius_m,
                        sun_cosine,
                        view_cosine,
                        cos_azimuth,
                    };
                    let densities = std::mem::take(&mut scratch.densities);
                    source(geometry, &densities, scratch);
                    scratch.densities = densities;
                    // T*(eye, x) beta*_sca(x) R(x): one exponential per
                    // wavelength for the transmittance and the source.
                    let weight = node.weight;
                    for (i, out) in radiance.iter_mut().enumerate() {
                        let (mut tau, mut scattering) = (0.0, 0.0);
                        for j in 0..s {
                            tau += self.scaled_extinction[i * s + j] * scratch.node_columns[j];
                            scattering += self.scaled_scattering[i * s + j] * scratch.densities[j];
                        }
                        // A source at the logarithms' floor is no light
                        // (the interpolation between a dark node, 1e-30,
                        // and a lit one would otherwise leave numerical
                        // noise in the night sky).
                        if scattering > 0.0 && scratch.log_source[i] > DARK_LOG_SOURCE {
                            *out += weight * scattering * (scratch.log_source[i] - tau).exp();
                        }
                    }
                    // What delta-M moved from single scattering into the
                    // sun's beam and the view's transmittance (see the
                    // module docs, TMS).
                    let lit = self.has_forward_peaks
                        && sun_columns.compute_columns_to_sun(
                            &self.profiles,
                            &self.corners,
                            node.point,
                            self.sun,
                            &mut scratch.sun_panel_ends,
                            &mut scratch.sun_columns,
                        );
                    let share = match &self.peak_beam {
                        Some(beam) if self.has_forward_peaks => {
                            beam.lookup_beam(r, sun_cosine, &mut scratch.beam)
                        }
                        _ => 0.0,
                    };
                    if share > 0.0 {
                        self.add_tilted_forward_peak(weight, lit, share, scratch);
                    } else if lit {
                        for i in 0..w {
                            let (mut scaled, mut exact, mut peak) = (0.0, 0.0, 0.0);
                            for j in 0..s {
                                let column = scratch.node_columns[j] + scratch.sun_columns[j];
                                scaled += self.scaled_extinction[i * s + j] * column;
                                exact += self.extinction[i * s + j] * column;
                                // f_j beta_sca,j rho_j: what the peaks scatter here.
                                peak += (self.extinction[i * s + j]
                                    - self.scaled_extinction[i * s + j])
                                    * scratch.densities[j];
                            }
                            let direct = (-exact).exp();
                            let excess = weight * ((-scaled).exp() - direct);
                            for j in 0..s {
                                scratch.forward_integrals[j * w + i] +=
                                    excess * scratch.densities[j];
                            }
                            // The peak-only light: its weight and the
                            // peak optical depth X of its two legs.
                            let only = weight * direct * peak;
                            scratch.forward_integrals[s * w + i] += only;
                            scratch.forward_integrals[(s + 1) * w + i] += only * (exact - scaled);
                        }
                    }
                    ControlFlow::Continue(())
                },
            );
            scratch.view_columns.copy_from_slice(march.columns());
            scratch.march = march;
            scratch.view_panel_ends = view_ends;
        }
        let end = start + view * length;
        if end.length() <= self.ground_radius_m * (1.0 + 1e-12) {
            let sun_cosine = self.sun.dot(end.normalized());
            let (node, t) = self.sun_axis.locate(sun_cosine);
            let next = node + 1;
            for i in 0..w {
                let (mut tau_scaled, mut tau) = (0.0, 0.0);
                for j in 0..s {
                    tau_scaled += self.scaled_extinction[i * s + j] * scratch.view_columns[j];
                    tau += self.extinction[i * s + j] * scratch.view_columns[j];
                }
                let lerp = |table: &[f64]| {
                    interpolate_geometrically(table[node * w + i], table[next * w + i], t)
                };
                let (scaled, exact) = ((-tau_scaled).exp(), (-tau).exp());
                radiance[i] += scaled * lerp(&self.ground_diffuse)
                    + (scaled - exact) * lerp(&self.ground_direct);
            }
        }
    }

    /// The forward-peak integrals of one view node (the march's weight
    /// `weight`, m; its columns, densities and, where `lit`, its columns
    /// toward the sun in `scratch`) with the peaks' light reaching the
    /// node S = T*_sun - T_sun moved toward the tilted beam B of
    /// `scratch.beam` by `share` (`peak_beam.rs`): the first line's
    /// T* T*_sun - T T_sun becomes T* S~ + T_sun (T* - T), the peak-only
    /// light's weight T T_sun is scaled by (T_sun + S~) / T*_sun.
    fn add_tilted_forward_peak(
        &self,
        weight: f64,
        lit: bool,
        share: f64,
        scratch: &mut MultipleScatteringScratch,
    ) {
        let (w, s) = (self.wavelengths, self.species);
        // Optical depths, then (in place) transmittances: T* and T from the
        // eye, T*_sun and T_sun, per wavelength.
        let (view, sun) = scratch.tilted_depths.split_at_mut(2 * w);
        let (view_beam, view_direct) = view.split_at_mut(w);
        let (sun_beam, sun_direct) = sun.split_at_mut(w);
        for i in 0..w {
            let (mut depths, mut peak) = ([0.0; 4], 0.0);
            for j in 0..s {
                let (scaled, exact) = (
                    self.scaled_extinction[i * s + j],
                    self.extinction[i * s + j],
                );
                depths[0] += scaled * scratch.node_columns[j];
                depths[1] += exact * scratch.node_columns[j];
                depths[2] += scaled * scratch.sun_columns[j];
                depths[3] += exact * scratch.sun_columns[j];
                // f_j beta_sca,j rho_j: what the peaks scatter here.
                peak += (exact - scaled) * scratch.densities[j];
            }
            [view_beam[i], view_direct[i], sun_beam[i], sun_direct[i]] = depths;
            scratch.tilted_peak[i] = peak;
            // X, the peaks' optical depth of both legs.
            scratch.tilted_peak[w + i] = (depths[1] + depths[3]) - (depths[0] + depths[2]);
        }
        exp_neg_in_place(&mut scratch.tilted_depths);
        let (view, sun) = scratch.tilted_depths.split_at(2 * w);
        let (view_beam, view_direct) = view.split_at(w);
        let (sun_beam, sun_direct) = sun.split_at(w);
        for i in 0..w {
            let (sun_beam, sun_direct) = if lit {
                (sun_beam[i], sun_direct[i])
            } else {
                (0.0, 0.0)
            };
            let forward = sun_beam - sun_direct;
            let scattered = forward + share * (scratch.beam[i] - forward);
            let excess =
                weight * (view_beam[i] * scattered + sun_direct * (view_beam[i] - view_direct[i]));
            for j in 0..s {
                scratch.forward_integrals[j * w + i] += excess * scratch.densities[j];
            }
            if lit && sun_beam > 0.0 {
                let only = weight
                    * view_direct[i]
                    * sun_direct
                    * scratch.tilted_peak[i]
                    * ((sun_direct + scattered) / sun_beam);
                let x = scratch.tilted_peak[w + i];
                scratch.forward_integrals[s * w + i] += only;
                scratch.forward_integrals[(s + 1) * w + i] += only * x;
            }
        }
    }
}

/// The diffuse (multiply scattered) light field of a sky, solved at the
/// sun zenith angles its view rays meet.
#[derive(Debug, Clone)]
pub struct MultipleScatteringField {
    settings: MultipleScatteringSettings,
    /// The sky's optics (exact phase functions for the forward-peak term).
    atmosphere: AtmosphereOptics,
    grid: VerticalGrid,
    streams: Streams,
    optics: ViewRayOptics,
    /// [i * species + j].
    phases: Vec<TruncatedPhase>,
    harmonics: Vec<bool>,
    /// The solver's output as it wrote it: per wavelength i and sun node s
    /// a block of `solution_len + 2` values, L_m(z_k, mu_b) at [(m *
    /// levels + k) * streams + b] and then the ground's two values, blocks
    /// [i * sun nodes + s] (read with [`MultipleScatteringField::solution`];
    /// kept as solved, not transposed: tens of megabytes at twilight).
    solutions: Vec<f64>,
    solution_len: usize,
    /// The source's Legendre moments for the exact synthesis, made on
    /// first use ([`MultipleScatteringField::source_moments`]).
    moments: std::sync::OnceLock<Vec<f64>>,
    /// With Stokes vectors, the columns of the polarisation correction.
    polarisation: Option<PolarisationCorrection>,
}

impl MultipleScatteringField {
    /// [`MultipleScatteringField::compute_with_sun_column_nodes`] with the
    /// default image tables' sun-column table.
    #[cfg(test)]
    pub(crate) fn compute(
        sky: &SingleScatteringSky,
        settings: MultipleScatteringSettings,
        polarised: bool,
    ) -> Result<MultipleScatteringField> {
        MultipleScatteringField::compute_with_sun_column_nodes(
            sky,
            settings,
            FIRST_ORDER_SUN_COLUMN_NODES,
            polarised,
        )
    }

    /// Solves the field of `sky` for every sun zenith angle seen at a point
    /// of the atmosphere visible from its eye; an error for settings that
    /// `MultipleScatteringSettings::validate` rejects. The spherical first
    /// order reads the columns toward the sun from a table of
    /// `sun_column_nodes` (altitude, mu) nodes: a sky passes its image
    /// tables' size ([`crate::FastTableSize`], 128 x 256 by default), so
    /// that the two share one table. The explorer's preview (32 x 64) then
    /// builds no second table of 128 x 256 nodes for its first low sun
    /// (measured on one thread: its 128-pixel frame at sun 10 0.10 ->
    /// 0.075 s), and its first order on the coarse table moves its images
    /// by at most 0.1 % of their 99th-percentile error against the default
    /// resolution at suns 10 to -12 degrees (the `quality_accuracy`
    /// example of `crates/sora-web`). With `polarised`, the field also
    /// solves the columns of its polarisation correction.
    pub(crate) fn compute_with_sun_column_nodes(
        sky: &SingleScatteringSky,
        settings: MultipleScatteringSettings,
        sun_column_nodes: (usize, usize),
        polarised: bool,
    ) -> Result<MultipleScatteringField> {
        MultipleScatteringField::compute_for_visible_suns(
            sky,
            settings,
            sun_column_nodes,
            polarised,
            successive_orders::MAX_ITERATIONS,
        )
    }

    /// As [`MultipleScatteringField::compute_with_sun_column_nodes`], for
    /// views no lower than `lowest_view_elevation_rad` (>= 0) only: the sun
    /// zenith angles the field is solved for are those at the points of
    /// such views' rays, within acos(r cos e / R_top) - e of the eye's
    /// (the angle at the planet's centre between the eye and where a ray
    /// of elevation e leaves the atmosphere), instead of every point the
    /// eye sees (acos(R / R_top) + acos(R / r), 10 degrees on Earth). For an
    /// almucantar 15 degrees up that is 3 degrees, which spares the field
    /// the sunset's fine sun steps and spherical first order when the sun
    /// is 15 degrees high (a retrieval's forward model: 12 times faster
    /// there).
    pub(crate) fn compute_for_views_above(
        sky: &SingleScatteringSky,
        settings: MultipleScatteringSettings,
        sun_column_nodes: (usize, usize),
        polarised: bool,
        lowest_view_elevation_rad: f64,
    ) -> Result<MultipleScatteringField> {
        let (ground, top) = sky.radii_m();
        let r = sky.observer_radius_m().max(ground);
        let e = lowest_view_elevation_rad.clamp(0.0, 0.5 * PI);
        let reach = if r < top {
            (r * e.cos() / top).min(1.0).acos() - e
        } else {
            (ground / r).min(1.0).acos() + (ground / top).acos()
        };
        MultipleScatteringField::compute_within_reach(
            sky,
            settings,
            sun_column_nodes,
            polarised,
            successive_orders::MAX_ITERATIONS,
            reach,
        )
    }

    /// The field for every sun zenith angle at a point of the atmosphere
    /// the eye sees, the solver stopped after `sweeps` orders.
    fn compute_for_visible_suns(
        sky: &SingleScatteringSky,
        settings: MultipleScatteringSettings,
        sun_column_nodes: (usize, usize),
        polarised: bool,
        sweeps: usize,
    ) -> Result<MultipleScatteringField> {
        let (ground, top) = sky.radii_m();
        let r = sky.observer_radius_m();
        // A point of the atmosphere that the eye sees is at most this far
        // (as an angle at the planet's centre) from the eye's zenith.
        let reach = (ground / r.max(ground)).min(1.0).acos() + (ground / top).acos();
        MultipleScatteringField::compute_within_reach(
            sky,
            settings,
            sun_column_nodes,
            polarised,
            sweeps,
            reach,
        )
    }

    /// The field for the sun zenith angles within `reach` (rad) of the
    /// eye's, the solver stopped after `sweeps` orders.
    fn compute_within_reach(
        sky: &SingleScatteringSky,
        settings: MultipleScatteringSettings,
        sun_column_nodes: (usize, usize),
        polarised: bool,
        sweeps: usize,
        reach: f64,
    ) -> Result<MultipleScatteringField> {
        let sun_zenith = sky.sun_direction().z.clamp(-1.0, 1.0).acos();
        MultipleScatteringField::compute_for_sun_zenith_range(
            sky,
            settings,
            sun_column_nodes,
            (sun_zenith - reach).max(0.0),
            sun_zenith + reach,
            polarised,
            sweeps,
        )
    }

    /// As [`MultipleScatteringField::compute_with_sun_column_nodes`] (not
    /// polarised) with the solver stopped
    /// after `sweeps` orders of the field (the field's own first order, or
    /// the spherical one, is order 1): with one, the field is the first
    /// order and a view's multiply scattered radiance is the second order
    /// alone (the twilight survey compares it with the path tracer's).
    #[cfg(test)]
    pub(crate) fn compute_with_sweeps(
        sky: &SingleScatteringSky,
        settings: MultipleScatteringSettings,
        sun_column_nodes: (usize, usize),
        sweeps: usize,
    ) -> Result<MultipleScatteringField> {
        MultipleScatteringField::compute_for_visible_suns(
            sky,
            settings,
            sun_column_nodes,
            false,
            sweeps,
        )
    }

    fn compute_for_sun_zenith_range(
        sky: &SingleScatteringSky,
        settings: MultipleScatteringSettings,
        sun_column_nodes: (usize, usize),
        lowest_rad: f64,
        highest_rad: f64,
        polarised: bool,
        sweeps: usize,
    ) -> Result<MultipleScatteringField> {
        settings.validate()?;
        let optics = sky.optics();
        let (ground_radius_m, top_radius_m) = sky.radii_m();
        let wavelengths = optics.grid.len();
        let species = optics.species.len();
        let streams = Streams::new(settings.streams_per_hemisphere);
        let degrees = streams.count();
        // The sun sets for the top of a column at 90 degrees +
        // acos(R / R_top), and a straight path from a point of the column
        // reaches at most 2 acos(R / R_top) farther (to the top, grazing
        // the ground): beyond 90 degrees + 3 acos(R / R_top) nothing a
        // column's streams reach is sunlit (`spherical_first_order`), and
        // its field is zero. The axis ends a degree past that, so that a
        // sun angle beyond its end (read at its last node) reads darkness,
        // not the last lit column (measured: a zenith of 1e-6 cd/m^2 with
        // the sun 30 degrees below the horizon when it ended at 111 deg).
        let darkest = 0.5 * PI + 3.0 * (ground_radius_m / top_radius_m).acos() + 1f64.to_radians();
        let lowest = lowest_rad.clamp(0.0, darkest);
        let highest = highest_rad.clamp(lowest, darkest);
        let sun_axis = SunZenithAxis::new(
            lowest,
            highest,
            sky.sun_direction().z.clamp(-1.0, 1.0).acos(),
            settings.sun_zenith_step_deg.to_radians(),
            settings.sunset_sun_zenith_step_deg.to_radians(),
        );
        let count = sun_axis.count();
        // Delta-M truncated phase functions and scaled coefficients.
        let phases = compute_truncated_phases(optics, degrees);
        let mut extinction = vec![0.0; wavelengths * species];
        let mut scaled_extinction = vec![0.0; wavelengths * species];
        let mut scaled_scattering = vec![0.0; wavelengths * species];
        for i in 0..wavelengths {
            for (j, s) in optics.species.iter().enumerate() {
                let f = phases[i * species + j].forward_fraction;
                let (ext, sca) = (s.extinction_per_m[i], s.scattering_per_m[i]);
                extinction[i * species + j] = ext;
                scaled_extinction[i * species + j] = ext - f * sca;
                scaled_scattering[i * species + j] = (1.0 - f) * sca;
            }
        }
        let profiles: Vec<DensityProfile> =
            optics.species.iter().map(|s| s.profile.clone()).collect();
        let grid =
            VerticalGrid::for_optics(optics, top_radius_m - ground_radius_m, settings.layers);
        let levels = grid.levels();
        let radii: Vec<f64> = grid
            .altitudes_m()
            .iter()
            .map(|z| ground_radius_m + z)
            .collect();
        let paths = StreamPaths::compute(&radii, streams.cosines());
        // Geometric columns toward the sun from every level, per node; None
        // in the planet's shadow.
        let corners = ProfileCorners::new(&profiles, ground_radius_m, top_radius_m);
        let mut ends = Vec::with_capacity(corners.most_panel_ends(SUN_RAY_PANELS));
        let mut sun_columns: Vec<Option<Vec<f64>>> = Vec::with_capacity(count * levels);
        let mut add_columns_toward_sun = |theta: f64, sun_columns: &mut Vec<Option<Vec<f64>>>| {
            let direction = Vector3::new(theta.sin(), 0.0, theta.cos());
            for &z in grid.altitudes_m() {
                let r = ground_radius_m + z;
                if crate::geometry::ray_intersects_ground(r, theta.cos(), ground_radius_m) {
                    sun_columns.push(None);
                    continue;
                }
                let origin = Vector3::new(0.0, 0.0, r);
                let length =
                    crate::geometry::distance_to_top_of_atmosphere(origin, direction, top_radius_m);
                let mut columns = vec![0.0; species];
                corners.fill_panel_ends(origin, direction, length, SUN_RAY_PANELS, &mut ends);
                compute_columns_along_ray(
                    &profiles,
                    ground_radius_m,
                    origin,
                    direction,
                    &ends,
                    &mut columns,
                );
                sun_columns.push(Some(columns));
            }
        };
        for s in 0..count {
            add_columns_toward_sun(sun_axis.angle(s), &mut sun_columns);
        }
        // The polarisation correction's column has the eye's own sun.
        let eye_sun_zenith = sky.sun_direction().z.clamp(-1.0, 1.0).acos();
        let polarisation = polarised.then(|| {
            let mut eye_columns = Vec::with_capacity(levels);
            add_columns_toward_sun(eye_sun_zenith, &mut eye_columns);
            let sun_optical_depths: Vec<Option<(f64, f64)>> = (0..wavelengths)
                .flat_map(|i| {
                    let (scaled_extinction, extinction) = (&scaled_extinction, &extinction);
                    eye_columns.iter().map(move |columns| {
                        columns.as_ref().map(|columns| {
                            (0..species).fold((0.0, 0.0), |(scaled, exact), j| {
                                (
                                    scaled + scaled_extinction[i * species + j] * columns[j],
                                    exact + extinction[i * species + j] * columns[j],
                                )
                            })
                        })
                    })
                })
                .collect();
            PolarisationCorrection::compute(&CorrectionInputs {
                optics,
                streams: &streams,
                grid: &grid,
                paths: &paths,
                phases: &phases,
                scaled_extinction: &scaled_extinction,
                scaled_scattering: &scaled_scattering,
                sun_cosine: eye_sun_zenith.cos(),
                sun_optical_depths: &sun_optical_depths,
                eye_altitude_m: sky.observer_radius_m() - ground_radius_m,
            })
        });
        let solution_len = degrees * levels * degrees;
        // The first order in the spherical shell, with the planet's shadow,
        // at the sun nodes from FIRST_ORDER_SUN_ZENITH_DEG on (index
        // s - first_spherical); the column's own first order above.
        let first_spherical = sun_axis
            .angles_rad
            .partition_point(|a| *a < FIRST_ORDER_SUN_ZENITH_DEG.to_radians());
        let solar_irradiance: Vec<f64> = optics.solar_irradiance_w_m2_nm.values().to_vec();
        // The table only where some sun node needs the spherical first order
        // (a high sun's nodes all stop short of it).
        let first_order = if first_spherical < sun_axis.angles_rad.len() {
            let (altitude_nodes, mu_nodes) = sun_column_nodes;
            let table_columns = sky.sun_column_table(altitude_nodes, mu_nodes);
            compute_spherical_first_order(&FirstOrderInputs {
                profiles: &profiles,
                corners: &corners,
                sun_columns: &table_columns,
                level_altitudes_m: grid.altitudes_m(),
                streams: &streams,
                moments: MomentQuadrature::Fine,
                sun_zenith_rad: &sun_axis.angles_rad[first_spherical..],
                scaled_extinction: &scaled_extinction,
                scaled_scattering: &scaled_scattering,
                phases: &phases,
                solar_irradiance_w_m2_nm: &solar_irradiance,
            })
        } else {
            Vec::new()
        };
        // Per wavelength: every sun node's solution, then its two ground values.
        let chunk = count * (solution_len + 2);
        let mut solved = vec![0.0; wavelengths * chunk];
        crate::parallel::for_each_chunk_mut(&mut solved, chunk, |i, out| {
            // The spherical first order of node s >= first_spherical.
            let first_of = |s: usize| {
                &first_order[((s - first_spherical) * wavelengths + i) * solution_len..]
                    [..solution_len]
            };
            let scaled: Vec<ScaledSpecies> = (0..species)
                .map(|j| ScaledSpecies {
                    extinction_per_m: scaled_extinction[i * species + j],
                    scattering_per_m: scaled_scattering[i * species + j],
                    phase: &phases[i * species + j],
                })
                .collect();
            let solar = optics.solar_irradiance_w_m2_nm[i];
            let albedo = optics.ground_albedo[i];
            let system = ColumnSystem::new(&streams, &grid, Some(&paths), scaled, solar, albedo)
                .with_sweeps(sweeps);
            let mut work = Vec::new();
            let mut transmittance = vec![0.0; levels];
            // Per spherical node: the sunlit ground's radiance under the
            // scaled beam, and the sunlight delta-M moved into that beam
            // (W m^-2 nm^-1), for the ground values after the joint solve.
            let spherical_nodes = count - first_spherical.min(count);
            let mut ground_direct = vec![0.0; spherical_nodes];
            let mut moved_sunlight = vec![0.0; spherical_nodes];
            for s in 0..count {
                let sun_cosine = sun_axis.angle(s).cos();
                let mut exact_ground = 0.0;
                for k in 0..levels {
                    transmittance[k] = match &sun_columns[s * levels + k] {
                        None => 0.0,
                        Some(columns) => {
                            let (mut tau_scaled, mut tau) = (0.0, 0.0);
                            for j in 0..species {
                                tau_scaled += scaled_extinction[i * species + j] * columns[j];
                                tau += extinction[i * species + j] * columns[j];
                            }
                            if k == 0 {
                                exact_ground = (-tau).exp();
                            }
                            (-tau_scaled).exp()
                        }
                    };
                }
                let block = &mut out[s * (solution_len + 2)..(s + 1) * (solution_len + 2)];
                let (field, ground) = block.split_at_mut(solution_len);
                let lit = sun_cosine.max(0.0);
                // The ground's sunlight that delta-M moved into the beam
                // (reflected as if diffuse), and the exact direct beam.
                let moved = solar * lit * (transmittance[0] - exact_ground);
                ground[1] = albedo / PI * solar * lit * exact_ground;
                if s >= first_spherical {
                    // Solved below with the other spherical nodes.
                    moved_sunlight[s - first_spherical] = moved;
                    ground_direct[s - first_spherical] =
                        albedo / PI * solar * lit * transmittance[0];
                    continue;
                }
                let diffuse = system.solve(sun_cosine, &transmittance, field, &mut work);
                ground[0] = albedo / PI * (diffuse + moved);
            }
            // The near-horizontal light comes from columns where the sun
            // stands higher or lower (see `twilight_shift.rs`).
            // Only the sun nodes with the column's own first order: with the
            // spherical first order the light from lit columns is in the
            // field already, and the shift's finite difference across the
            // sun axis would carry light into columns that are dark
            // (measured: a zenith of 1e-6 cd/m^2 with the sun 30 degrees
            // below the horizon).
            let mut fields: Vec<&mut [f64]> = out
                .chunks_exact_mut(solution_len + 2)
                .map(|block| &mut block[..solution_len])
                .take(first_spherical)
                .collect();
            system.shift_toward_sources(&sun_axis.angles_rad[..fields.len()], &mut fields);
            // From FIRST_ORDER_SUN_ZENITH_DEG on, the nodes with the spherical first order,
            // all together: each order of the spherical streams shifted in
            // the logarithm before it is scattered again.
            if first_spherical < count {
                let first_orders: Vec<&[f64]> = (first_spherical..count).map(first_of).collect();
                let (mut fields, mut grounds): (Vec<&mut [f64]>, Vec<&mut [f64]>) = out
                    .chunks_exact_mut(solution_len + 2)
                    .skip(first_spherical)
                    .map(|block| block.split_at_mut(solution_len))
                    .unzip();
                let diffuse = system.solve_shifted_orders(
                    &sun_axis.angles_rad[first_spherical..],
                    &ground_direct,
                    &first_orders,
                    &mut fields,
                );
                for ((ground, diffuse), moved) in
                    grounds.iter_mut().zip(diffuse).zip(&moved_sunlight)
                {
                    ground[0] = albedo / PI * (diffuse + moved);
                }
            }
        });
        let mut ground_diffuse = vec![0.0; count * wavelengths];
        let mut ground_direct = vec![0.0; count * wavelengths];
        for i in 0..wavelengths {
            for s in 0..count {
                let block = &solved[i * chunk + s * (solution_len + 2)..][..solution_len + 2];
                ground_diffuse[s * wavelengths + i] = block[solution_len];
                ground_direct[s * wavelengths + i] = block[solution_len + 1];
            }
        }
        let forward_peak = ForwardPeak::new(
            optics,
            &phases,
            degrees,
            &profiles,
            top_radius_m - ground_radius_m,
        );
        let needed = PeakBeam::needed_elevations_deg(
            FRAC_PI_2 - eye_sun_zenith,
            (ground_radius_m, top_radius_m),
            sky.observer_radius_m(),
        );
        let peak_beam = match needed {
            Some(elevations_deg) if forward_peak.any() => {
                let (altitude_nodes, mu_nodes) = sun_column_nodes;
                PeakBeam::compute(
                    &PeakBeamInputs {
                        optics,
                        phases: &phases,
                        profiles: &profiles,
                        corners: &corners,
                        sun_columns: &sky.sun_column_table(altitude_nodes, mu_nodes),
                        altitudes_m: grid.altitudes_m(),
                        extinction: &extinction,
                        scaled_extinction: &scaled_extinction,
                    },
                    elevations_deg,
                )
            }
            _ => None,
        };
        let harmonics = (0..degrees)
            .map(|m| {
                phases
                    .iter()
                    .zip(&scaled_scattering)
                    .any(|(p, b)| *b > 0.0 && !p.harmonic_vanishes(m))
            })
            .collect();
        Ok(MultipleScatteringField {
            settings,
            atmosphere: optics.clone(),
            grid,
            streams,
            optics: ViewRayOptics {
                wavelengths,
                species,
                panels: settings.view_ray_panels,
                ground_radius_m,
                top_radius_m,
                observer: Vector3::new(0.0, 0.0, sky.observer_radius_m()),
                sun: sky.sun_direction(),
                profiles,
                corners,
                extinction,
                scaled_extinction,
                has_forward_peaks: forward_peak.any(),
                forward_peak,
                peak_beam,
                scaled_scattering,
                sun_axis,
                ground_diffuse,
                ground_direct,
            },
            phases,
            harmonics,
            solutions: solved,
            solution_len,
            moments: std::sync::OnceLock::new(),
            polarisation,
        })
    }

    /// The field L_m(z_k, mu_b) of sun node `s` at wavelength `i`, W m^-2
    /// sr^-1 nm^-1, [(m * levels + k) * streams + b].
    fn solution(&self, s: usize, i: usize) -> &[f64] {
        let block = self.solution_len + 2;
        let at = (i * self.optics.sun_axis.count() + s) * block;
        &self.solutions[at..at + self.solution_len]
    }

    /// The scattering source's moments per sun node s, wavelength i, level
    /// k, harmonic m and degree l >= m (the view direction factored out):
    ///
    /// ```text
    /// S[s, i, k, m, l] = c_l(k) sum_b 2 pi w_b Lambda_l^m(mu_b) L_m(z_k, mu_b; s)
    /// c_l(k) = sum_j (beta*_sca,j(z_k) / beta*_sca(z_k)) c_jl
    /// ```
    ///
    /// so that J / beta*_sca at (k, s) toward a view of zenith cosine mu_v
    /// and azimuth phi from the sun is sum_m cos(m phi) sum_l
    /// Lambda_l^m(mu_v) S[s, i, k, m, l]: the same sums as the harmonic
    /// kernels p*_jm(mu_v, mu_b) of [`MultipleScatteringTable`], reordered so
    /// that a view costs degrees^2 / 2 products per node and wavelength
    /// instead of species x degrees^3. Laid out
    /// [((s * wavelengths + i) * levels + k) * degrees^2 + m * degrees + l];
    /// zero where the level does not scatter. Made once, on one thread (it
    /// is called from inside parallel loops).
    fn source_moments(&self) -> &[f64] {
        self.moments.get_or_init(|| {
            let degrees = self.streams.count();
            let levels = self.grid.levels();
            let (w, species) = (self.optics.wavelengths, self.optics.species);
            let square = degrees * degrees;
            let suns = self.optics.sun_axis.count();
            let mut moments = vec![0.0; suns * w * levels * square];
            let mut mixed = vec![0.0; degrees];
            for s in 0..suns {
                for i in 0..w {
                    let solution = self.solution(s, i);
                    for k in 0..levels {
                        let densities = self.grid.densities_at_level(k);
                        let scattering = |j: usize| {
                            densities[j] * self.optics.scaled_scattering[i * species + j]
                        };
                        let total: f64 = (0..species).map(scattering).sum();
                        if total <= 0.0 {
                            continue;
                        }
                        mixed.fill(0.0);
                        for j in 0..species {
                            let fraction = scattering(j) / total;
                            let phase = &self.phases[i * species + j];
                            for (c, p) in mixed.iter_mut().zip(&phase.coefficients) {
                                *c += fraction * p;
                            }
                        }
                        let out = &mut moments[((s * w + i) * levels + k) * square..][..square];
                        for m in (0..degrees).filter(|m| self.harmonics[*m]) {
                            let radiance = &solution[(m * levels + k) * degrees..][..degrees];
                            for l in m..degrees {
                                let moment: f64 = (0..degrees)
                                    .map(|b| {
                                        2.0 * PI
                                            * self.streams.weights()[b]
                                            * self.streams.legendre(b)[m * degrees + l]
                                            * radiance[b]
                                    })
                                    .sum();
                                out[m * degrees + l] = mixed[l] * moment;
                            }
                        }
                    }
                }
            }
            moments
        })
    }

    /// For each level, the first and last sun node that a view ray from the
    /// eye can need there: a point at altitude h that the eye sees is at
    /// most acos(R / r_eye) + acos(R / (R + h)) from the eye (seen from the
    /// planet's centre), and so is its sun zenith angle from the eye's. A
    /// level takes the reach of the level above it (points between the two
    /// read both), and one node more on each side for the interpolation.
    fn reachable_sun_nodes(&self) -> Vec<(usize, usize)> {
        let optics = &self.optics;
        let ground = optics.ground_radius_m;
        let eye = optics.observer.length().max(ground);
        let centre = optics
            .sun
            .dot(optics.observer * (1.0 / eye))
            .clamp(-1.0, 1.0)
            .acos();
        let altitudes = self.grid.altitudes_m();
        let axis = &optics.sun_axis;
        (0..altitudes.len())
            .map(|k| {
                let above = altitudes[(k + 1).min(altitudes.len() - 1)];
                let reach = (ground / eye).min(1.0).acos() + (ground / (ground + above)).acos();
                let (low, _) = axis.locate((centre - reach).max(0.0).cos());
                let (high, t) = axis.locate((centre + reach).min(PI).cos());
                let high = if t > 0.0 { high + 1 } else { high };
                (low.saturating_sub(1), (high + 1).min(axis.count() - 1))
            })
            .collect()
    }

    /// The forward-peak term toward a view at cos(theta) = `cos_theta` from
    /// the sun, into `out`, from its integrals along the view ray
    /// ([`MultipleScatteringScratch::forward_integrals`], or the sky-view
    /// table's interpolation of them); `phase` is work space, one value per
    /// wavelength.
    pub(crate) fn compute_forward_peak_radiance(
        &self,
        cos_theta: f64,
        integrals: &[f64],
        phase: &mut [f64],
        out: &mut [f64],
    ) {
        if !self.optics.has_forward_peaks {
            out.fill(0.0);
            return;
        }
        self.optics
            .forward_peak
            .radiance(&self.atmosphere, cos_theta, integrals, phase, out);
    }

    /// Rows of the forward-peak integrals per wavelength.
    pub(crate) fn forward_integral_rows(&self) -> usize {
        self.optics.species + forward_peak::EXTRA_ROWS
    }

    /// The scattering-plane Q of the forward-peak term toward a view at
    /// cos(theta) = `cos_theta` from the sun, into `out` (see
    /// `ForwardPeak::polarised_radiance`), from the same integrals as
    /// [`MultipleScatteringField::compute_forward_peak_radiance`];
    /// `work` is work space of one value per wavelength.
    pub(crate) fn compute_forward_peak_polarised_radiance(
        &self,
        cos_theta: f64,
        integrals: &[f64],
        work: (&mut [f64], &mut [PhaseMatrix]),
        out: &mut [f64],
    ) {
        if !self.optics.has_forward_peaks {
            out.fill(0.0);
            return;
        }
        self.optics.forward_peak.polarised_radiance(
            &self.atmosphere,
            cos_theta,
            integrals,
            work,
            out,
        );
    }

    /// The polarisation correction's ratios (I, Q, U, V) / I_scalar of the
    /// light the scaled field scatters two or more times, toward the view
    /// of zenith cosine `view_cosine` at azimuth `view_azimuth_rad` from
    /// the sun's (clockwise) at the eye, into `ratios` ([component *
    /// wavelengths + i]; see `polarisation_correction.rs`). None for a
    /// scalar field.
    pub(crate) fn compute_polarisation_ratios(
        &self,
        (view_cosine, view_azimuth_rad): (f64, f64),
        ratios: &mut [f64],
    ) -> Option<()> {
        let correction = self.polarisation.as_ref()?;
        correction.compute_ratios(
            &self.atmosphere,
            &self.phases,
            (view_cosine, view_azimuth_rad),
            ratios,
        );
        Some(())
    }

    /// The polarisation correction's ratios tabulated over view directions
    /// on `nodes` (per half of the zenith-cosine axis, azimuths), for
    /// images (see `polarisation_correction.rs`). None for a scalar field.
    pub(crate) fn compute_polarisation_table(
        &self,
        nodes: (usize, usize),
    ) -> Option<PolarisationTable> {
        let correction = self.polarisation.as_ref()?;
        Some(correction.tabulate(&self.atmosphere, &self.phases, nodes))
    }

    /// Work space for [`MultipleScatteringField::compute_radiance`].
    pub(crate) fn scratch(&self) -> MultipleScatteringScratch {
        self.optics.scratch(self.streams.count())
    }

    /// Multiply scattered radiance (orders >= 2 and skylight reflected by
    /// the ground) seen along `view`, W m^-2 sr^-1 nm^-1, into `radiance`:
    /// the field's exact angular synthesis at every march node, with
    /// columns toward the sun from `sun_columns` for the forward-peak term.
    pub(crate) fn compute_radiance(
        &self,
        view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        self.optics
            .march(view, sun_columns, scratch, radiance, |node, _, scratch| {
                self.compute_log_source(node, scratch)
            });
        self.optics
            .add_forward_peak(&self.atmosphere, view, scratch, radiance);
    }

    /// ln R(x, view) at one march node into `scratch.log_source`: R synthesised
    /// exactly from the harmonics at the four surrounding (level, sun node)
    /// corners ([`MultipleScatteringField::source_moments`]), interpolated
    /// linearly in ln R (as the table does).
    fn compute_log_source(&self, node: NodeGeometry, scratch: &mut MultipleScatteringScratch) {
        let degrees = self.streams.count();
        let square = degrees * degrees;
        let levels = self.grid.levels();
        let w = self.optics.wavelengths;
        let moments = self.source_moments();
        let (k, tz) = self.grid.locate(node.altitude_m);
        let (sun_node, ts) = self.optics.sun_axis.locate(node.sun_cosine);
        normalized_associated_legendre(node.view_cosine, degrees, &mut scratch.view_legendre);
        // cos(m phi) Lambda_l^m(mu_v) by the Chebyshev recurrence for cos(m phi).
        let mut cosine = 0.0;
        let mut previous = 0.0;
        for m in 0..degrees {
            let next = match m {
                0 => 1.0,
                1 => node.cos_azimuth,
                _ => 2.0 * node.cos_azimuth * cosine - previous,
            };
            (previous, cosine) = (cosine, next);
            let weight = if self.harmonics[m] { cosine } else { 0.0 };
            for value in &mut scratch.view_legendre[m * degrees + m..(m + 1) * degrees] {
                *value *= weight;
            }
        }
        let view = &scratch.view_legendre[..square];
        for i in 0..w {
            let mut log_value = 0.0;
            for (kk, wk) in [(k, 1.0 - tz), (k + 1, tz)] {
                for (ss, ws) in [(sun_node, 1.0 - ts), (sun_node + 1, ts)] {
                    let source = &moments[((ss * w + i) * levels + kk) * square..][..square];
                    let mut value = 0.0;
                    for m in 0..degrees {
                        let range = m * degrees + m..(m + 1) * degrees;
                        value += view[range.clone()]
                            .iter()
                            .zip(&source[range])
                            .map(|(a, b)| a * b)
                            .sum::<f64>();
                    }
                    log_value += wk * ws * floored_log(value);
                }
            }
            scratch.log_source[i] = log_value;
        }
    }
}
