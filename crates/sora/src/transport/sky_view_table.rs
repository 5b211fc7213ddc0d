//! The sky-view table: the fast path's in-scattering integrals tabulated
//! over view directions, so that an image costs one table read per pixel
//! instead of one ray march (Hillaire 2020's sky-view LUT, here spectral
//! and without the phase function).
//!
//! What is tabulated, per view direction and wavelength: the integrals
//! I_j(lambda) of [`super::single_scattering`] (one per species that
//! scatters at some wavelength, m: an absorber's integral is multiplied by
//! its scattering coefficient, 0, wherever it is used, so a read gives it
//! as zeros) and the sunlit ground's radiance. Neither contains the phase function: with a
//! point sun the scattering angle is fixed along each view ray, so the
//! phase functions, which carry all the sharp structure (the aerosol's
//! forward peak, the Mie glory), are applied exactly per pixel by
//! `SingleScatteringScene::radiance_from_integrals`. What remains varies
//! smoothly with direction, except across the horizon.
//!
//! Axes: the view's zenith angle and its azimuth relative to the sun's,
//! 0..180 degrees (the sky is symmetric about the solar meridian). The
//! zenith axis has two halves that meet at the ground's horizon as seen by
//! the eye (90 degrees on the ground, lower from above): nodes crowd
//! toward it from both sides (u = 1 - (1 - v)^2 in each half), and no cell
//! straddles it, so the jump from sky to ground is never interpolated.
//! Bilinear interpolation in (v, azimuth).
//!
//! Optionally the table also holds the multiply scattered radiance of
//! [`super::multiple_scattering`] per node (W m^-2 sr^-1 nm^-1, a third
//! block of values after the ground's: the air's, then the ground's
//! skylight, each a term of its own). It has no single phase function
//! to factor out, but it is smooth in direction (a scattering integral of
//! a diffuse field): it is marched at every other node of each axis
//! (and the last node of each half) and filled in between them by cubics
//! (`fill_unmarched`), which quarters its cost (images; the engine tables'
//! layers march it at every row of their coarser zenith axis, or blend it
//! from the tables of the sun nodes either side,
//! [`SkyViewTable::blend_multiple_from`]). The same march gives the forward-peak
//! integrals of delta-M (light that the multiple-scattering solver counts
//! as unscattered and that single scattering with the real transmittances
//! misses), a fourth block: like single scattering's integrals they take
//! the phase functions per pixel (`MultipleScatteringField::compute_forward_peak_radiance`,
//! with the peak-only rows of `forward_peak.rs`).

use super::multiple_scattering::{MultipleScatteringScratch, MultipleScatteringTable};
use super::optical_column::SunColumnTable;
use super::single_scattering::{
    SingleScatteringScene, SingleScatteringScratch, SunColumns, Together,
};
use crate::geometry::Vector3;

/// Which zenith rows of each half a sky-view table marches, counted from
/// the zenith (or the nadir): every row ([`MarchedRows::EVERY`]), or every
/// other row over the first `by_two` pairs of rows, every third over the
/// next `by_three` triples and every one after (the engine tables' zenith
/// axis on a finer grid, `engine_tables::axes`, whose views lie on those
/// rows alone). The rows between are left zero: a table read must fall on
/// the marched rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct MarchedRows {
    pub(crate) by_two: usize,
    pub(crate) by_three: usize,
}

impl MarchedRows {
    /// Every row marched.
    pub(crate) const EVERY: MarchedRows = MarchedRows {
        by_two: 0,
        by_three: 0,
    };

    /// Whether row `index` of a half, counted from the zenith (or the
    /// nadir), is marched.
    pub(crate) fn marches(&self, index: usize) -> bool {
        let (two, three) = (2 * self.by_two, 2 * self.by_two + 3 * self.by_three);
        if index <= two {
            index % 2 == 0
        } else if index <= three {
            (index - two) % 3 == 0
        } else {
            true
        }
    }
}

/// How far (rad) the zenith nodes next to the horizon sit inside their
/// half, so that a ray along them is unambiguously sky or ground. A hair
/// of 1e-9 rad was not enough: the ground test compares |p x d| with R,
/// and R (1 - 5e-19) rounds either way, so at some azimuths the ground
/// half's first node took the horizon's sky radiance (an eye on the
/// ground saw the ground just below the horizon 1.8 times too bright in
/// the table). At 1e-6 rad, |p x d| = R (1 - 5e-13).
pub(crate) const HORIZON_MARGIN_RAD: f64 = 1e-6;

/// In-scattering integrals over view directions (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SkyViewTable {
    /// Nodes per half of the zenith axis (sky half, ground half).
    half_zenith_nodes: usize,
    azimuth_nodes: usize,
    /// Zenith angle of the horizon seen by the eye, rad.
    horizon_zenith_rad: f64,
    /// Values per node: the integrals (m) of the species that scatter
    /// ([`SkyViewTable::kept`]), kept * wavelengths, then wavelengths sunlit
    /// ground radiances, then (with multiple scattering) wavelengths
    /// multiply scattered radiances of the air, wavelengths radiances of
    /// the ground's skylight (W m^-2 sr^-1 nm^-1) and the forward-peak
    /// integrals of the kept species and the peak-only rows ((kept + 2) *
    /// wavelengths, see `MultipleScatteringScratch::forward_integrals`).
    values_per_node: usize,
    /// The species that scatter at some wavelength, in order: an absorber's
    /// integrals and forward-peak rows take its scattering coefficient, 0,
    /// wherever they are used (`radiance_from_integrals` and the forward
    /// peak's radiances add E beta_sca p I_j), so the table holds none of
    /// them and a read gives zeros in their rows (whose terms those sums
    /// skip: the same values, bit for bit). Of the sky's `species`.
    kept: Vec<usize>,
    species: usize,
    wavelengths: usize,
    has_multiple_scattering: bool,
    /// Values per node of the multiply scattered light's blocks (the
    /// air's, the ground's skylight, the forward-peak integrals), the
    /// last of each node; 0 without multiple scattering.
    multiple_values: usize,
    /// [(half * half_zenith_nodes + i) * azimuth_nodes + k] * values_per_node.
    values: Vec<f32>,
    /// Unit vector of the sun's azimuth in the horizontal plane.
    sun_horizontal: (f64, f64),
}

impl SkyViewTable {
    /// The table of each of `skies` (a scene, its sun-column table, its
    /// multiply scattered light or none), filled with `half_zenith_nodes`
    /// nodes above and below the horizon and `azimuth_nodes` over 0..180
    /// degrees, with sun columns from the sun-column table, and with
    /// multiple scattering the multiply scattered radiance at every node
    /// too, only at the rows `rows` marches (the others left zero), marched
    /// at every `multiple_stride.0`-th node of the zenith
    /// axis's halves and `multiple_stride.1`-th of the azimuth axis (and
    /// the last of each) and filled in between (`fill_unmarched`; see the
    /// module docs); with `march_multiple` false its blocks are laid out
    /// but left zero, for [`SkyViewTable::blend_multiple_from`] to fill.
    /// Rows run in parallel with the `parallel` feature; the result does
    /// not depend on the thread count.
    ///
    /// The skies' tables are filled row by row together: the integrals of
    /// a sky whose view rays are the first sky's
    /// (`SingleScatteringScene::has_view_geometry_of`) and whose
    /// sun-column table is the first's (the same table) are computed in
    /// the first sky's march, each node's optical depths and
    /// transmittances of every such sky one loop (`Together`), bit for bit
    /// the table it builds alone (the k-distribution's term skies, which
    /// differ in what absorbs only). So is the multiply scattered light of
    /// such a sky whose source table's view rays are the first's
    /// (`MultipleScatteringTable::marches_with`): the first sky's
    /// multiple-scattering march takes it node by node with its own
    /// (`MultipleScatteringTable::compute_radiance_parts_together`: the
    /// nodes, their densities, geometry and columns toward the sun found
    /// once, each sky's source read from its own table), bit for bit what
    /// its own march (`compute_radiance_parts`, the slow path) gives.
    pub(crate) fn compute_sharing_geometry(
        skies: &[(
            &SingleScatteringScene,
            &SunColumnTable,
            Option<&MultipleScatteringTable>,
        )],
        (half_zenith_nodes, azimuth_nodes): (usize, usize),
        (multiple_stride, rows): ((usize, usize), MarchedRows),
        march_multiple: bool,
    ) -> Vec<SkyViewTable> {
        assert!(half_zenith_nodes >= 2 && azimuth_nodes >= 2);
        assert!(multiple_stride.0 >= 1 && multiple_stride.1 >= 1);
        let mut tables: Vec<SkyViewTable> = skies
            .iter()
            .map(|(sky, _, multiple_scattering)| {
                SkyViewTable::laid_out(
                    sky,
                    *multiple_scattering,
                    (half_zenith_nodes, azimuth_nodes),
                )
            })
            .collect();
        // Per sky: whether it reads the first sky's columns toward the sun.
        let shares: Vec<bool> = skies
            .iter()
            .enumerate()
            .map(|(t, (sky, sun_columns, _))| {
                let (first, first_columns, _) = skies[0];
                t > 0
                    && sky.has_view_geometry_of(first)
                    && std::ptr::eq(*sun_columns, first_columns)
            })
            .collect();
        let together = shares.iter().any(|s| *s);
        // One node's integrals and sunlit ground from a scene's scratch.
        let store = |scratch: &SingleScatteringScratch, table: &SkyViewTable, node: &mut [f32]| {
            let w = table.wavelengths;
            let (integrals, rest) = node.split_at_mut(table.kept.len() * w);
            let ground = &mut rest[..w];
            table.store_kept_rows(scratch.inscattering_integrals(), integrals);
            for (o, v) in ground.iter_mut().zip(scratch.ground_radiance()) {
                *o = *v as f32;
            }
        };
        // Per sky: whether its multiply scattered light is marched in the
        // first sky's march (`compute_radiance_parts_together`): it shares
        // the first's view rays and sun-column table, and both have a
        // source table whose view rays are the same.
        let multiple_together: Vec<bool> = skies
            .iter()
            .enumerate()
            .map(|(t, (_, _, multiple_scattering))| {
                let first = skies[0].2;
                shares[t]
                    && matches!((first, multiple_scattering), (Some(a), Some(b)) if a.marches_with(b))
            })
            .collect();
        // One node's multiply scattered light (the air's, the ground's
        // skylight, the forward-peak integrals of the scratch's last ray).
        let store_multiple = |table: &SkyViewTable,
                              node: &mut [f32],
                              (air, skylit): (&[f64], &[f64]),
                              ms_scratch: &MultipleScatteringScratch| {
            let wavelengths = table.wavelengths;
            let rest = &mut node[(table.kept.len() + 1) * wavelengths..];
            let (multiple, rest) = rest.split_at_mut(wavelengths);
            let (ground_skylight, forward) = rest.split_at_mut(wavelengths);
            for (o, v) in multiple.iter_mut().zip(air.iter()) {
                *o = *v as f32;
            }
            for (o, v) in ground_skylight.iter_mut().zip(skylit.iter()) {
                *o = *v as f32;
            }
            // The kept species' rows, then the peak-only rows.
            let all = ms_scratch.forward_integrals();
            let (rows, peak_only) = forward.split_at_mut(table.kept.len() * wavelengths);
            table.store_kept_rows(all, rows);
            let extra = &all[table.species * wavelengths..];
            for (o, v) in peak_only.iter_mut().zip(extra) {
                *o = *v as f32;
            }
        };
        let fill_row = |row: usize, outs: &mut [&mut [f32]]| {
            if !rows.marches(row.min(2 * half_zenith_nodes - 1 - row)) {
                return;
            }
            // The row's rays are one zenith angle from one eye: their
            // densities and columns are marched once for every azimuth
            // (where the planet's shadow does not cut them apart).
            let index_in_half = row % half_zenith_nodes;
            let zenith = tables[0].zenith_of_node(row);
            let view_of = |k: usize| {
                let relative_azimuth = std::f64::consts::PI * k as f64 / (azimuth_nodes - 1) as f64;
                tables[0].direction(zenith, relative_azimuth)
            };
            let mut scratches: Vec<SingleScatteringScratch> = skies
                .iter()
                .map(|(sky, ..)| {
                    let mut scratch = sky.scratch();
                    scratch.reuse_view_nodes();
                    scratch
                })
                .collect();
            if together {
                // The first sky marches each ray once for those that
                // share its geometry, their integrals computed with its
                // own at each node.
                let (first, rest) = scratches.split_first_mut().expect("a sky");
                let mut with: Vec<usize> = Vec::new();
                let mut others = Vec::new();
                for (t, scratch) in rest.iter_mut().enumerate() {
                    if shares[t + 1] {
                        with.push(t + 1);
                        others.push((skies[t + 1].0, scratch));
                    }
                }
                let mut others = Together::new(others);
                let (sky, sun_columns, _) = skies[0];
                for k in 0..azimuth_nodes {
                    sky.compute_inscattering_integrals_together(
                        view_of(k),
                        SunColumns::Table(sun_columns),
                        first,
                        &mut others,
                    );
                    let stride = tables[0].values_per_node;
                    store(first, &tables[0], &mut outs[0][k * stride..][..stride]);
                    for (t, scratch) in with.iter().zip(others.scratches()) {
                        let stride = tables[*t].values_per_node;
                        store(scratch, &tables[*t], &mut outs[*t][k * stride..][..stride]);
                    }
                }
            }
            // Per sky: the multiple scattering's scratch and the air's and
            // the ground's skylight of a ray.
            let mut ms_work: Vec<_> = skies
                .iter()
                .zip(&tables)
                .map(|((_, _, multiple_scattering), table)| {
                    multiple_scattering.map(|ms| {
                        let mut ms_scratch = ms.scratch();
                        ms_scratch.reuse_view_nodes();
                        let wavelengths = table.wavelengths;
                        (ms_scratch, vec![0.0; wavelengths], vec![0.0; wavelengths])
                    })
                })
                .collect();
            // Sky by sky (each sky's source table stays in cache through
            // the row): the integrals of those not marched together, and
            // the multiply scattered light (the first sky's march takes
            // that of those marched with it).
            for (t, (((sky, sun_columns, multiple_scattering), table), scratch)) in skies
                .iter()
                .zip(&tables)
                .zip(scratches.iter_mut())
                .enumerate()
            {
                let marched_together = together && (t == 0 || shares[t]);
                if multiple_together[t] {
                    // Marched in the first sky's march.
                    debug_assert!(marched_together);
                    continue;
                }
                let (own_work, rest_work) = ms_work[t..].split_first_mut().expect("a sky");
                for k in 0..azimuth_nodes {
                    let view = view_of(k);
                    let columns = SunColumns::Table(sun_columns);
                    let stride = table.values_per_node;
                    let node = &mut outs[t][k * stride..(k + 1) * stride];
                    if !marched_together {
                        sky.compute_inscattering_integrals(view, columns, scratch);
                        store(scratch, table, node);
                    }
                    let marched_here = march_multiple
                        && marched(index_in_half, half_zenith_nodes, multiple_stride.0)
                        && marched(k, azimuth_nodes, multiple_stride.1);
                    let (Some(ms), Some((ms_scratch, air, skylit)), true) =
                        (multiple_scattering, own_work.as_mut(), marched_here)
                    else {
                        continue;
                    };
                    if t == 0 && multiple_together.iter().any(|m| *m) {
                        // The others' light with this sky's, node by node.
                        let mut others = Vec::new();
                        let mut sources = Vec::new();
                        let mut with = Vec::new();
                        for (u, work) in rest_work.iter_mut().enumerate() {
                            if let (true, Some((other_scratch, other_air, other_skylit))) =
                                (multiple_together[u + 1], work.as_mut())
                            {
                                let other = skies[u + 1].2.expect("a source table");
                                let (alongside, source) =
                                    ms.alongside(other, other_scratch, (other_air, other_skylit));
                                others.push(alongside);
                                sources.push(source);
                                with.push(u + 1);
                            }
                        }
                        ms.compute_radiance_parts_together(
                            (view, f64::INFINITY),
                            columns,
                            ms_scratch,
                            (air, skylit),
                            (&mut others, &sources),
                        );
                        drop(others);
                        store_multiple(table, node, (air, skylit), ms_scratch);
                        for u in with {
                            let (other_scratch, other_air, other_skylit) =
                                rest_work[u - 1].as_ref().expect("marched");
                            let other = &tables[u];
                            let stride = other.values_per_node;
                            let node = &mut outs[u][k * stride..(k + 1) * stride];
                            store_multiple(other, node, (other_air, other_skylit), other_scratch);
                        }
                    } else {
                        ms.compute_radiance_parts(
                            (view, f64::INFINITY),
                            columns,
                            ms_scratch,
                            (air, skylit),
                        );
                        store_multiple(table, node, (air, skylit), ms_scratch);
                    }
                }
            }
            for (table, out) in tables.iter().zip(outs.iter_mut()) {
                if table.has_multiple_scattering && march_multiple {
                    // Fill the azimuths between marched ones.
                    let stride = table.values_per_node;
                    fill_unmarched(
                        out,
                        azimuth_nodes,
                        stride,
                        (stride - table.multiple_values, table.multiple_values),
                        multiple_stride.1,
                        table.wavelengths,
                    );
                }
            }
        };
        let mut values: Vec<Vec<f32>> = tables
            .iter()
            .map(|table| {
                // Zeroed by the threads (megabytes per table: zeroed on
                // one thread, it left the others idle).
                crate::parallel::filled(
                    2 * half_zenith_nodes * azimuth_nodes * table.values_per_node,
                    0.0f32,
                )
            })
            .collect();
        {
            // Row by row, every sky's row together.
            let mut rows: Vec<Vec<&mut [f32]>> =
                (0..2 * half_zenith_nodes).map(|_| Vec::new()).collect();
            for (table, values) in tables.iter().zip(values.iter_mut()) {
                let row_length = azimuth_nodes * table.values_per_node;
                for (row, chunk) in rows.iter_mut().zip(values.chunks_mut(row_length)) {
                    row.push(chunk);
                }
            }
            crate::parallel::for_each_chunk_mut(&mut rows, 1, |row, outs| {
                fill_row(row, &mut outs[0])
            });
        }
        for (table, mut values) in tables.iter_mut().zip(values) {
            let stride = table.values_per_node;
            let marched_values = table.multiple_values;
            let row_length = azimuth_nodes * stride;
            if table.has_multiple_scattering && march_multiple {
                // Fill the rows between marched ones, within each half.
                for half in [0, 1] {
                    let rows = &mut values[half * half_zenith_nodes * row_length..]
                        [..half_zenith_nodes * row_length];
                    for k in 0..azimuth_nodes {
                        let offset = k * stride + stride - marched_values;
                        fill_unmarched(
                            rows,
                            half_zenith_nodes,
                            row_length,
                            (offset, marched_values),
                            multiple_stride.0,
                            table.wavelengths,
                        );
                    }
                }
            }
            table.values = values;
        }
        tables
    }

    /// An empty table of `sky` (its values not yet filled) with
    /// `half_zenith_nodes` nodes above and below the horizon and
    /// `azimuth_nodes` over 0..180 degrees, with the blocks of
    /// `multiple_scattering`'s light when it has some.
    fn laid_out(
        sky: &SingleScatteringScene,
        multiple_scattering: Option<&MultipleScatteringTable>,
        (half_zenith_nodes, azimuth_nodes): (usize, usize),
    ) -> SkyViewTable {
        let optics = sky.optics();
        let wavelengths = optics.grid.len();
        let has_multiple_scattering = multiple_scattering.is_some();
        let species = optics.species.len();
        let kept: Vec<usize> = (0..species)
            .filter(|j| {
                optics.species[*j]
                    .scattering_per_m
                    .values()
                    .iter()
                    .any(|v| *v != 0.0)
            })
            .collect();
        // Integrals, ground; with multiple scattering its radiance and its
        // forward-peak integrals (the kept species' rows and the peak-only
        // rows).
        let forward_rows = multiple_scattering.map_or(0, |ms| {
            ms.field().forward_integral_rows() - species + kept.len()
        });
        let blocks = if has_multiple_scattering {
            kept.len() + 3 + forward_rows
        } else {
            kept.len() + 1
        };
        let (ground_radius, _) = sky.radii_m();
        let observer_radius = sky.observer_radius_m();
        let horizon_zenith_rad =
            std::f64::consts::PI - (ground_radius / observer_radius).min(1.0).asin();
        let sun = sky.sun_direction();
        let horizontal = (sun.x.hypot(sun.y) > 1e-12)
            .then(|| (sun.x / sun.x.hypot(sun.y), sun.y / sun.x.hypot(sun.y)));
        SkyViewTable {
            half_zenith_nodes,
            azimuth_nodes,
            horizon_zenith_rad,
            values_per_node: blocks * wavelengths,
            kept,
            species,
            wavelengths,
            has_multiple_scattering,
            // Marched at every other node: multiple scattering's radiance
            // and forward-peak integrals.
            multiple_values: if has_multiple_scattering {
                (forward_rows + 2) * wavelengths
            } else {
                0
            },
            values: Vec::new(),
            sun_horizontal: horizontal.unwrap_or((0.0, 1.0)),
        }
    }

    /// Fills the multiply scattered light's blocks of every node (left
    /// zero by `march_multiple` false) from two tables of the same layout
    /// with the sun at other elevations, `t` of the way from `below` to
    /// `above`: geometrically (linear in the logarithm, as the engine
    /// tables' sun axis is read) where both are positive, linearly
    /// otherwise. Node for node, at the same zenith angle and azimuth from
    /// the sun (engine tables: `engine_tables::layer_sky_view`).
    ///
    /// With `outer` (the tables one step beyond `below` and `above`, the
    /// four evenly spaced in the sun's parameter, and `t` one half), the
    /// logarithm is the cubic through the four, (9 (b + c) - (a + d)) / 16,
    /// where that lies between b and c and all four are positive (as
    /// `fill_unmarched` fills between azimuths), otherwise as above.
    pub(crate) fn blend_multiple_from(
        &mut self,
        (below, above): (&SkyViewTable, &SkyViewTable),
        outer: Option<(&SkyViewTable, &SkyViewTable)>,
        t: f64,
    ) {
        let others: Vec<&SkyViewTable> = match outer {
            Some((lowest, highest)) => vec![below, above, lowest, highest],
            None => vec![below, above],
        };
        for other in &others {
            assert_eq!(
                (
                    other.half_zenith_nodes,
                    other.azimuth_nodes,
                    other.values_per_node,
                    other.multiple_values
                ),
                (
                    self.half_zenith_nodes,
                    self.azimuth_nodes,
                    self.values_per_node,
                    self.multiple_values
                )
            );
        }
        debug_assert!(outer.is_none() || t == 0.5);
        let (n, m) = (self.values_per_node, self.multiple_values);
        if m == 0 {
            return;
        }
        let t32 = t as f32;
        // Row by row in parallel (each node's blend is its own: the same
        // values whatever the threads).
        let azimuth_nodes = self.azimuth_nodes;
        crate::parallel::for_each_chunk_mut(&mut self.values, azimuth_nodes * n, |row, values| {
            for (k, node) in values.chunks_exact_mut(n).enumerate() {
                let index = row * azimuth_nodes + k;
                let at = |table: &SkyViewTable, j: usize| table.values[index * n + n - m + j];
                for (j, o) in node[n - m..].iter_mut().enumerate() {
                    let (a, b) = (at(below, j), at(above, j));
                    *o = if a > 0.0 && b > 0.0 {
                        let (ln_a, ln_b) = (f64::from(a).ln(), f64::from(b).ln());
                        let linear = (1.0 - t) * ln_a + t * ln_b;
                        let cubic = outer
                            .map(|(lowest, highest)| (at(lowest, j), at(highest, j)))
                            .filter(|(l, h)| *l > 0.0 && *h > 0.0)
                            .map(|(l, h)| {
                                (9.0 * (ln_a + ln_b) - f64::from(l).ln() - f64::from(h).ln()) / 16.0
                            })
                            .filter(|c| ln_a.min(ln_b) <= *c && *c <= ln_a.max(ln_b));
                        cubic.unwrap_or(linear).exp() as f32
                    } else {
                        (1.0 - t32) * a + t32 * b
                    };
                }
            }
        });
    }

    /// Zenith angle (rad) of zenith-axis node `row` (0 = the zenith,
    /// half - 1 = just above the horizon, half = just below, 2 half - 1 =
    /// the nadir), [`HORIZON_MARGIN_RAD`] inside its half next to the horizon.
    fn zenith_of_node(&self, row: usize) -> f64 {
        let half = self.half_zenith_nodes;
        if row < half {
            let v = row as f64 / (half - 1) as f64;
            let u = 1.0 - (1.0 - v) * (1.0 - v);
            u * (self.horizon_zenith_rad - HORIZON_MARGIN_RAD)
        } else {
            let v = (2 * half - 1 - row) as f64 / (half - 1) as f64;
            let u = 1.0 - (1.0 - v) * (1.0 - v);
            std::f64::consts::PI
                - u * (std::f64::consts::PI - self.horizon_zenith_rad - HORIZON_MARGIN_RAD)
        }
    }

    /// Fractional node coordinate of a zenith angle, and which half: the
    /// exact inverse of [`SkyViewTable::zenith_of_node`], margin included,
    /// so that a read at a node's zenith angle takes that row alone (a
    /// table that marches some rows only, `MarchedRows`, leaves the others
    /// zero; with the margin left out, a read at the engine tables' row
    /// next to the fine cells took 2.4e-4 of the unmarched row beside it).
    fn zenith_coordinate(&self, zenith: f64) -> f64 {
        let half = self.half_zenith_nodes;
        if zenith < self.horizon_zenith_rad {
            let u = (zenith / (self.horizon_zenith_rad - HORIZON_MARGIN_RAD)).clamp(0.0, 1.0);
            let v = 1.0 - (1.0 - u).sqrt();
            v * (half - 1) as f64
        } else {
            let u = ((std::f64::consts::PI - zenith)
                / (std::f64::consts::PI - self.horizon_zenith_rad - HORIZON_MARGIN_RAD))
                .clamp(0.0, 1.0);
            let v = 1.0 - (1.0 - u).sqrt();
            (2 * half - 1) as f64 - v * (half - 1) as f64
        }
    }

    /// The view direction with this zenith angle and azimuth relative to
    /// the sun (east-north-up).
    fn direction(&self, zenith: f64, relative_azimuth: f64) -> Vector3 {
        let (sin_z, cos_z) = zenith.sin_cos();
        let (sin_a, cos_a) = relative_azimuth.sin_cos();
        let (sx, sy) = self.sun_horizontal;
        // Rotate (sin a, cos a) from the sun's azimuth: the sun's azimuth
        // direction is (sx, sy) in (east, north).
        let east = sx * cos_a + sy * sin_a;
        let north = sy * cos_a - sx * sin_a;
        Vector3::new(sin_z * east, sin_z * north, cos_z)
    }

    /// Where `view` falls among the table's nodes ([`SkyViewCell`]).
    pub(crate) fn cell(&self, view: Vector3) -> SkyViewCell {
        let zenith = view.z.clamp(-1.0, 1.0).acos();
        let (sx, sy) = self.sun_horizontal;
        let along = view.x * sx + view.y * sy;
        let across = view.x * sy - view.y * sx;
        let relative_azimuth = across.abs().atan2(along);
        let x = self.zenith_coordinate(zenith);
        let half = self.half_zenith_nodes;
        // Stay inside the half the direction belongs to.
        let (lowest, highest) = if x < (half - 1) as f64 + 0.5 {
            (0, half - 2)
        } else {
            (half, 2 * half - 2)
        };
        let i = (x.floor() as usize).clamp(lowest, highest);
        let fx = (x - i as f64).clamp(0.0, 1.0);
        let y = relative_azimuth / std::f64::consts::PI * (self.azimuth_nodes - 1) as f64;
        let k = (y.floor() as usize).min(self.azimuth_nodes - 2);
        let fy = y - k as f64;
        SkyViewCell {
            row: i,
            column: k,
            weights: [
                ((1.0 - fx) * (1.0 - fy)) as f32,
                ((1.0 - fx) * fy) as f32,
                (fx * (1.0 - fy)) as f32,
                (fx * fy) as f32,
            ],
        }
    }

    /// Whether a view falls in the same [`SkyViewCell`] of `other` as of
    /// this table: the same axes, horizon and sun's azimuth (the
    /// k-distribution's term skies' tables).
    pub(crate) fn has_cells_of(&self, other: &SkyViewTable) -> bool {
        (self.half_zenith_nodes, self.azimuth_nodes)
            == (other.half_zenith_nodes, other.azimuth_nodes)
            && self.horizon_zenith_rad.to_bits() == other.horizon_zenith_rad.to_bits()
            && self.sun_horizontal.0.to_bits() == other.sun_horizontal.0.to_bits()
            && self.sun_horizontal.1.to_bits() == other.sun_horizontal.1.to_bits()
    }

    /// The view's integrals and sunlit ground's radiance into `integrals`
    /// and `ground`, and the air's multiply
    /// scattered radiance into `multiple`, the ground's skylight into
    /// `ground_skylight` and the forward-peak integrals ((species + 2) *
    /// wavelengths, see [`crate::transport::multiple_scattering::MultipleScatteringScratch::forward_integrals`])
    /// into `forward` (zeros when the table has none).
    pub(crate) fn lookup_with_multiple_scattering(
        &self,
        cell: SkyViewCell,
        (integrals, ground): (&mut [f64], &mut [f64]),
        (multiple, ground_skylight, forward): (&mut [f64], &mut [f64], &mut [f64]),
    ) {
        if self.has_multiple_scattering {
            self.interpolate(
                cell,
                integrals,
                ground,
                Some((multiple, ground_skylight, forward)),
            );
        } else {
            self.interpolate(cell, integrals, ground, None);
            multiple.fill(0.0);
            ground_skylight.fill(0.0);
            forward.fill(0.0);
        }
    }

    fn interpolate(
        &self,
        SkyViewCell {
            row: i,
            column: k,
            weights: w,
        }: SkyViewCell,
        integrals: &mut [f64],
        ground: &mut [f64],
        multiple: Option<(&mut [f64], &mut [f64], &mut [f64])>,
    ) {
        let n = self.values_per_node;
        let node = |row: usize, column: usize| {
            &self.values[(row * self.azimuth_nodes + column) * n..][..n]
        };
        let (a, b, c, d) = (
            node(i, k),
            node(i, k + 1),
            node(i + 1, k),
            node(i + 1, k + 1),
        );
        // The values from `from` on into `out`, one loop over the four
        // nodes' slices (the same operations value by value).
        let interpolate = |out: &mut [f64], from: usize| {
            let n = out.len();
            let (a, b, c, d) = (
                &a[from..from + n],
                &b[from..from + n],
                &c[from..from + n],
                &d[from..from + n],
            );
            for (m, o) in out.iter_mut().enumerate() {
                *o = (a[m] * w[0] + b[m] * w[1] + c[m] * w[2] + d[m] * w[3]) as f64;
            }
            from + n
        };
        let wavelengths = self.wavelengths;
        // The species' rows from the kept ones' at `from` (zeros for the
        // others); returns where the table's values go on.
        let rows = |out: &mut [f64], mut from: usize| {
            out[..self.species * wavelengths].fill(0.0);
            for j in &self.kept {
                from = interpolate(&mut out[j * wavelengths..][..wavelengths], from);
            }
            from
        };
        let split = rows(integrals, 0);
        let next = interpolate(ground, split);
        if let Some((multiple, ground_skylight, forward)) = multiple {
            let next = interpolate(multiple, next);
            let next = interpolate(ground_skylight, next);
            let peak_only = rows(forward, next);
            interpolate(&mut forward[self.species * wavelengths..], peak_only);
        }
    }

    /// The kept species' rows of `all` (species-major, [j * wavelengths +
    /// i], every species of the sky) into `out`, kept-major.
    fn store_kept_rows(&self, all: &[f64], out: &mut [f32]) {
        let w = self.wavelengths;
        for (row, j) in out.chunks_exact_mut(w).zip(&self.kept) {
            for (o, v) in row.iter_mut().zip(&all[j * w..][..w]) {
                *o = *v as f32;
            }
        }
    }
}

/// Where a view falls among a sky-view table's nodes
/// ([`SkyViewTable::cell`]): the first zenith row and azimuth column of its
/// cell and the bilinear weights of the cell's four nodes (row, column),
/// (row, column + 1), (row + 1, column), (row + 1, column + 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SkyViewCell {
    row: usize,
    column: usize,
    weights: [f32; 4],
}

/// Whether node `index` of an axis of `count` nodes gets its multiply
/// scattered radiance marched (the others are interpolated): every
/// `stride`-th node and the last.
fn marched(index: usize, count: usize, stride: usize) -> bool {
    index % stride == 0 || index + 1 == count
}

/// Along one axis of `count` nodes, `step` values apart in `values`: fills
/// the `width` values at `offset` of every node that is not [`marched`]
/// at `stride`. At stride 2 (images) by the cubic through the four marched
/// nodes around it, (9 (b + c) - (a + d)) / 16 for nodes a, b, (this one),
/// c, d two apart, where that lies between b and c; otherwise (next to an
/// end of the axis, at a peak or where the values change by orders of
/// magnitude, as in deep twilight, where the cubic could even turn
/// negative) the mean of b and c. The cubic's error falls as the fourth
/// power of the step, the mean's as the square: the mean put a view 2.5
/// degrees up near the sun's azimuth 3.6e-4 lower than the cubic
/// (earth-clear, 440 nm, `docs/polarisation.md`). At other strides,
/// linearly between the marched nodes on either side.
///
/// The last `2 ratio_width` of the `width` values are the forward peak's
/// Q rows and then its Q X-bar rows (`forward_peak::EXTRA_ROWS`): a node's
/// X-bar is filled as the other values are, from the marched nodes' X-bar
/// (Q X-bar / Q, where Q > 0), and its Q X-bar is its Q times that. Each
/// filled on its own, they could give a node an X-bar far outside its
/// neighbours' (the peak-only light takes e^X-bar, `forward_peak.rs`):
/// where Q falls by an order of magnitude per node the cubic of Q cancels
/// to a small part of its neighbours' while that of Q X-bar does not
/// (earth-hazy, the eye at 100 km, the sun at -9.1 degrees, a view 0.32
/// degrees below the horizon 20 degrees from the sun, 420 nm: the image
/// read X-bar 30.7 where the view's own march gives 2.9, and e^30.7 times
/// the peak-only light's kernel, negative there, made the radiance -0.044
/// W m^-2 sr^-1 nm^-1 where the view's own is 1.065e-3).
fn fill_unmarched(
    values: &mut [f32],
    count: usize,
    step: usize,
    (offset, width): (usize, usize),
    stride: usize,
    ratio_width: usize,
) {
    debug_assert!(2 * ratio_width <= width);
    let ratios_from = width - ratio_width;
    for i in (1..count.saturating_sub(1)).filter(|i| !marched(*i, count, stride)) {
        let before = i - i % stride;
        let after = (before + stride).min(count - 1);
        // At stride 2 marched nodes are the even ones and the last, so an
        // unmarched node (odd) has marched nodes at i +- 1 and i +- 3
        // within the axis.
        let outer = after - before == 2 && i >= 3 && i + 3 < count;
        // The rule above from the value `at` each marched node (None: no
        // value there, an X-bar where Q is 0).
        let fill = |at: &dyn Fn(usize) -> Option<f32>| -> f32 {
            let (b, c) = match (at(before), at(after)) {
                (Some(b), Some(c)) => (b, c),
                (Some(v), None) | (None, Some(v)) => return v,
                (None, None) => return 0.0,
            };
            if after - before == 2 {
                let mean = 0.5 * (b + c);
                outer
                    .then(|| Some((9.0 * (b + c) - (at(i - 3)? + at(i + 3)?)) / 16.0))
                    .flatten()
                    .filter(|cubic| b.min(c) <= *cubic && *cubic <= b.max(c))
                    .unwrap_or(mean)
            } else {
                let t = (i - before) as f32 / (after - before) as f32;
                (1.0 - t) * b + t * c
            }
        };
        for m in 0..width {
            let value = |node: usize, m: usize| values[node * step + offset + m];
            values[i * step + offset + m] = if m < ratios_from {
                fill(&|node| Some(value(node, m)))
            } else {
                // Q (filled already) times X-bar.
                let q = m - ratio_width;
                let x_bar = fill(&|node| {
                    let weight = value(node, q);
                    (weight > 0.0).then(|| value(node, m) / weight)
                });
                value(i, q) * x_bar
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The forward peak's Q and Q X-bar along an axis of 9 nodes, every
    /// other one marched: Q falls by an order of magnitude or two per
    /// node, X-bar rises slowly (what the exact march gives earth-hazy's
    /// eye at 100 km, the sun at -9.1 degrees, 0.32 degrees below the
    /// horizon, 420 nm, every 3.8 degrees of azimuth from the sun's). A
    /// filled node's X-bar lies between its marched neighbours' (filled
    /// on their own, Q by the cubic and Q X-bar by the cubic, node 5 had
    /// 35.5 between 2.4 and 3.0), and its Q is what the rule above gives
    /// any other value.
    #[test]
    fn a_filled_node_s_peak_depth_lies_between_its_neighbours() {
        let q = [3.076e-11, 1.684e-11, 1.893e-12, 1.105e-14, 1.0e-18];
        let x_bar = [1.648, 1.836, 2.415, 2.980, 3.7];
        // Per node: one other value (Q again), Q, Q X-bar.
        let mut values = vec![0.0f32; 9 * 3];
        for (n, (q, x)) in q.iter().zip(x_bar).enumerate() {
            values[2 * n * 3..][..3].copy_from_slice(&[*q, *q, q * x]);
        }
        fill_unmarched(&mut values, 9, 3, (0, 3), 2, 1);
        for i in [1, 3, 5, 7] {
            let node = &values[i * 3..][..3];
            assert_eq!(node[0], node[1], "node {i}: Q filled as the other values");
            let (before, after) = (x_bar[i / 2], x_bar[i / 2 + 1]);
            let x = node[2] / node[1];
            assert!(
                before <= x && x <= after,
                "node {i}: X-bar {x} outside {before}..{after}"
            );
        }
    }
}
