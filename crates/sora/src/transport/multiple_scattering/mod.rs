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
//!    azimuth from the sun; its 19 azimuths crowded 10-30 degrees from the
//!    sun, where a dust's source bends most), read quadrilinearly, only
//!    where view rays can reach; the sky-view table ([`super::sky_view_table`]) stores the
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
//! | polarisation ratio (`polarisation_correction.rs`) | (I, Q, U, V) / I of the orders >= 2 | `Polarisation::Vector`: one column at the eye's sun, with its own first order and no shift | - |
//! | polarisation column's lowest sun | the column's sun stops this far (deg) above its last lit sun, -acos(R_ground / R_top) | sun below it | `POLARISATION_COLUMN_MARGIN_DEG` = 0.5 |
//! | polarisation fade | the column's polarisation blended toward unpolarised light | sun this far (deg) below the column's last lit sun | `POLARISATION_FADE_START_DEG` = 2 |
//! | polarisation fade | the polarised share exp(-d / this), d degrees past the fade's start | (as above) | `POLARISATION_FADE_SCALE_DEG` = 6 |
//!
//! # Accuracy (measured; the tests named hold it)
//! - DISORT (plane-parallel, every row of the clear-sky reference): worst
//!   0.074 % (black ground) and 0.061 % (albedo 0.3) with the exact
//!   synthesis, 0.10 % and 0.14 % through an image's tables
//!   (`black_ground_matches_disort_at_every_row`,
//!   `bright_ground_matches_disort_at_every_row`).
//! - The path tracer on the spherical planet, `clear-sky-reference`, 14
//!   views from the zenith to 1 degree up: suns 90 to 10 degrees within
//!   0.9 %, 5 degrees within 1.6 %; an eye 10 km up or a ground of albedo
//!   0.3 within 1.1 % (`spherical_sky_matches_the_path_tracer_within_two_percent`,
//!   `spherical_sky_matches_the_path_tracer_exhaustively`). Mie phase
//!   functions away from the sun: `earth-hazy` within 1.7 %, `mars-dust`
//!   within 2 % (`mie_aerosols_match_the_path_tracer_away_from_the_sun`).
//! - Near a low sun (`tests/twilight.rs`:
//!   `near_a_low_sun_with_aerosols_matches_the_path_tracer`,
//!   `the_sun_on_the_horizon_through_dust_matches_the_path_tracer`):
//!   `mars-dust` within 0.8 % 2 to 10 degrees from a sun 10 and 5 degrees
//!   high, `earth-hazy` within 0.7 % 2 to 5 degrees from a sun 5 degrees
//!   high; all 120 values 1 and 2 degrees up within 5 degrees of a sun at
//!   5 to -2 degrees within 3 % + 3 standard errors. Weakest: `mars-dust` 1
//!   degree up with the sun on the horizon or 2 degrees down, -0.6 to
//!   -3.6 % (1 600 000 paths; the peak scatterings on the view's side,
//!   exactly forward here, would add +1.7 to +3.2 %).
//! - Civil twilight, suns -2 to -6 (`civil_twilight_matches_the_path_tracer`,
//!   `sun_six_below_matches_the_path_tracer_at_three_wavelengths`,
//!   `twilight_matches_the_path_tracer_over_the_whole_grid`): all 189 values
//!   of the earth presets and `us-standard-1976-rayleigh` at the survey's
//!   views, and all 693 earth values of the issue's grid, within 3 % + 3
//!   standard errors; `mars-dust` 61 of 63 (its antisolar horizon leans
//!   bright, up to +15.7 % +-4.5 1 degree up). What remains is the third
//!   and higher orders, a few per cent dark at 440 nm toward the sun and at the zenith
//!   (the steeper streams' sources are their own column's, item 4); 16
//!   streams per hemisphere move the zenith at -6 by +0.3 to +0.5 %
//!   (`nautical_twilight_is_converged_in_the_streams`).
//! - Deep twilight, -8 to -12 (1 000 000 paths a view): earth-clear +0.2
//!   to +5.4 %, earth-hazy +1.2 to +7.9 %, us-standard +0.2 to +3.0 %, all
//!   within 5 % + 3 standard errors; earth-clear leans dark in the blue.
//!
//! Each number with its paths and standard errors, what each piece
//! changed when it was added, and why the field is not Hillaire's (2020)
//! table with isotropic orders >= 2, are in `docs/twilight_survey.md`.
//!
//! # Cost (measured, `benches/multiple_scattering.rs`, 2 shared cores)
//! One solve per wavelength and sun node (9 nodes for a sun 30 degrees
//! high, 18 for 5 degrees; at 21 wavelengths the field 0.12 s and its
//! source table 0.08 s at sun 30). The spherical first order adds 20-30 ms
//! per node it applies to, its fine moments about as much again after
//! sunset, the twilight shift about 0.1 s; none applies to a sun higher
//! than about 16 degrees. An earth-clear 512 x 512 fisheye (scalar) takes
//! about 1.7 s at sun 5 and 2.1 s at sun -6 (peak memory 123 MiB);
//! `cargo bench --bench multiple_scattering -- twilight` 1.91 s.
//!
//! # What it approximates
//! - Diffuse light between nearby points travels as in a column of uniform
//!   horizontal layers with one sun zenith angle, except for the
//!   near-horizontal streams' paths and their first-order shift, and for
//!   the spherical first order (Regimes): exact in the
//!   plane-parallel limit, good for a sun above 5 degrees, within a few
//!   per cent in civil twilight. The steeper streams' orders >= 2 still
//!   take their sources from their own column's sun angle (shifting them
//!   too moved no mars-dust twilight view by more than 1.4 %). The
//!   near-horizontal streams' shift reads each path's light at one mean
//!   angle: after sunset it brightens the light gathered in the shadow
//!   near the point, in a thin red haze by about 2 % of the segment's
//!   light (`twilight_shift.rs`; `twilight_shift_pieces` of the settings
//!   reads each path in pieces, most of it away at 1.1-1.2 times the CPU).
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
//!   depth across a layer, and the tables' interpolations. The 2n = 16
//!   Legendre terms of a strongly forward-peaked phase function leave a
//!   wave in azimuth in the multiply scattered light: mars-dust along an
//!   almucantar (suns 30 to 2), period 22.5-27 degrees, 0.14-0.31 % rms
//!   and 1.1 % at most against 24 streams; the path tracer has at most a
//!   third of it (0.27 +- 0.13 of its amplitude, sun 10, 450 nm); 16
//!   streams make it 5-10 times smaller; the Earth presets 0.01 % or
//!   less (`docs/engine-tables.md`, "Mars-dust's wave in azimuth").
//!
//! # Units
//! Radiances W m^-2 sr^-1 nm^-1, irradiances W m^-2 nm^-1, coefficients
//! m^-1 at relative density 1 (as [`crate::atmosphere::AtmosphereOptics`]),
//! altitudes m, angles rad inside (degrees in settings).

mod column_optics;
mod forward_peak;
mod peak_beam;
mod phase_fourier;
mod phase_matrix_fourier;
mod polarisation_correction;
mod regimes;
mod settings;
mod source_table;
mod spherical_first_order;
mod spherical_paths;
mod successive_orders;
mod twilight_shift;
mod vector_successive_orders;
mod vertical_grid;

pub use settings::MultipleScatteringSettings;
pub use source_table::MultipleScatteringTable;
pub(crate) use source_table::{
    ExportedBeam, ExportedSource, TABLE_AZIMUTHS_DEG, azimuth_cell, interpolate_log_source,
};

mod field;
mod view_march;

pub(crate) use self::field::{FieldRequest, MultipleScatteringField, SunFreeParts};
pub(crate) use self::polarisation_correction::{
    PolarisationRows, PolarisationTable, ViewHarmonicsCache,
};
#[cfg(test)]
pub(crate) use self::twilight_shift::SHIFT_PIECE_SPREAD_DEG;
pub use self::view_march::MultipleScatteringScratch;
use self::view_march::{LOG_FLOOR, NodeGeometry, SourceCells, floored_log};
