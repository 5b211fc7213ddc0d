//! The k-distribution's sum over its terms, inside the sky.
//!
//! An atmosphere with banded gases (`atmosphere::gas_bands`: water vapour
//! and the mixed gases of an atmosphere file's `[gases]`) is, band by band,
//! a weighted sum of [`crate::atmosphere::gas_bands::TERMS`] monochromatic
//! atmospheres: atmosphere j has every banded gas at k-term j, and any
//! quantity linear in the light (radiance, its Stokes vector, irradiance,
//! a transmittance, an image's XYZ or spectral values, the light and
//! transmittance of an aerial-perspective segment) is
//!
//! ```text
//!     Q = sum_j w_j Q_j
//! ```
//!
//! with w_j the terms' weights (they sum to 1 at each wavelength; the
//! shared weights of `gas_bands::k_terms` but in the O2 A band, whose
//! samples have their own, `gas_bands::k_distribution_terms`), taken sample
//! by sample: a colour (XYZ) of the terms is summed through colour-matching
//! functions scaled by each term's weights. A [`Sky`] built from such
//! an atmosphere keeps one sky per term ([`Sky::k_terms`]) and answers
//! every question with that sum, so views, images, irradiance and aerial
//! perspective are the k-distribution's whatever calls them (the command
//! line, Python, the explorer). The sky itself is then the single
//! effective solve (each banded gas at the coefficient that matches the
//! band model at air mass 2, `gas_bands::EFFECTIVE_AIR_MASS`): its optics
//! ([`Sky::optics`]) are that solve's, and no radiance is taken from it
//! (it is never solved). Without banded gases the sky has no terms and
//! every answer is the one solve's, bit for bit as before.
//!
//! **Which terms are solved where.** The terms' atmospheres differ only at
//! the samples where a banded gas absorbs, so only the span of them
//! ([`term_span`]: from the first such sample to the last) takes every
//! term. Term 0's sky covers the whole grid, weighted outside the span by
//! the sum of all the terms' weights (there every term is the same
//! atmosphere, so one solve is their sum); terms 1-4 are solved on the
//! span's sub-grid alone (a sky's grid is one uniform run of samples: its
//! optics are band averages over the grid's step). Every sample of the
//! span keeps its five terms: their coefficients span a factor of about
//! 1e4, so one solve at the weights' mean coefficient misses sum_j w_j
//! exp(-tau_j) by 2e-2 to more than 1 in the visible bands (colour skies
//! excepted, below). Inside a band, exact views leave out the higher
//! orders of scattering of the terms that absorb too strongly for them to
//! matter: every path from the top of the atmosphere to the eye crosses
//! the gas above the eye, so term j's higher orders are at most
//! exp(-dtau_j) times term 0's, dtau_j the difference of their vertical
//! optical depths above the eye ([`higher_orders_needed`]); where the sum
//! of (w_j / w_0) exp(-dtau_j) over the terms left out is within
//! [`HIGHER_ORDERS_BOUND`] (1e-3 of the radiance), those terms take single
//! scattering (and the sunlit ground) alone, the span cut into runs with
//! and without higher orders, one sky each ([`TermSkies::view_runs`]).
//! Images, views read from tables, irradiance and aerial perspective keep
//! every term whole. Each term's sky carries only the species that absorb
//! or scatter on its grid ([`carried_species`]: the mixed gases are left
//! out at 900-1000 nm), bit for bit the same answers.
//!
//! **What the terms share.** The terms' skies march the same view rays
//! toward the same sun through the same profiles, so what depends on the
//! geometry alone is found once and read by every term, bit for bit what
//! each term finds alone (a test beside each):
//! - an exact view's columns toward the sun (`ExactSunColumns`) and the
//!   polarisation correction's phase-matrix harmonics
//!   (`ViewHarmonicsCache`, keyed by the scattering species' phase
//!   functions, which the gases do not change);
//! - one store of sun-column tables, which hold the species' profile
//!   columns without a coefficient
//!   (`SingleScatteringScene::sharing_sun_column_tables_of`);
//! - the sky-view tables of images and of views read from tables, built
//!   together row by row (`Sky::prepare_term_tables`,
//!   `SkyViewTable::compute_sharing_geometry`): term 0's march computes
//!   every term's single-scattering integrals node by node
//!   (`single_scattering::Together`) and every term's multiply scattered
//!   light (`MultipleScatteringTable::compute_radiance_parts_together`,
//!   `ViewRayOptics::march_alongside`: the nodes, their columns toward the
//!   sun and the source tables' sun and azimuth cells found once, each
//!   term's source read from its own table; each term's own march,
//!   `compute_radiance_parts`, is the slow path, and the test of the
//!   tables built together asserts the shared path is taken). The tables
//!   hold only the species that scatter (the banded gases, ozone and NO2
//!   add no rows);
//! - an image's pixel geometry (`PixelGeometry`: the direction, its cell
//!   in the sky-view table, its scattering plane's rotation, its azimuth
//!   from the sun): a colour image of the terms is one pixel pass
//!   (`Sky::render_pixels_of`) adding each term's colour into the pixel in
//!   term order, bit for bit the sum of the terms' own images.
//!
//! **Colour skies merge terms.** A sky for colour images alone
//! ([`SkyBuilder::for_colour_images`], what `sora render` builds) merges
//! the terms ([`colour_plan`]): at each sample the terms, sorted by the
//! vertical optical depth tau_j of the one banded gas that differs between
//! them, are cut into runs, each carried by one sky with the run's weights
//! summed (W_G) at one depth tau_G. A path with m vertical columns of that
//! gas has depth m tau_j in term j (the correlated-k scaling), and every
//! path from the top of the atmosphere to the eye crosses each shell above
//! it, so m >= m_min (the gas' column above the eye over the ground's; 1
//! on the ground) whatever the sun and the orders of scattering; a run
//! then moves each path's light by at most D_G = sup_{m >= m_min} |sum_{j
//! in G} w_j exp(-m tau_j) - W_G exp(-m tau_G)| of its gas-free light
//! (tau_G chosen to make it least), and a colour's X, Y or Z, relative, by
//! at most sum_i s_i D_i (D_i the sum over the sample's runs, s_i its
//! largest share of the colour-matching sums, for a pixel whose gas-free
//! radiance there is at most its mean). Each sample takes as few runs as
//! keep that sum within [`COLOUR_BOUND`] (1e-3) with the fewest skies: sky
//! g carries each sample's g-th run (the weakest first), term 0's slot on
//! the whole grid, the others on the samples from the first to the last
//! with more runs (weight 0 between). The sup covers m -> infinity, where
//! the weakest term is the only light left, so one run (the whole fold)
//! errs D about 0.14 wherever a band absorbs and weak terms merge only
//! where their colour share is small. With the measured summer file (2.92
//! cm of water, O2-O2) on the default grid: four skies, terms {0}, {1},
//! {2}, {3, 4} at 580 and 600 nm (s D 3.1e-4 each), {0}, {1}, {2-4} at 680
//! nm (1.3e-4), {0}, {1-4} at 700 nm (1.2e-4), one run at 720-780 nm
//! (1.1e-4 together), 9.7e-4 in all; the extra skies cover 580-700,
//! 580-680 and 580-600 nm. The strong bands keep the terms whose light
//! differs (760 nm: any merge errs D > 6e-3; a test). Against every
//! term's image (the slow path, the default sky): 16 x 16 fisheyes of the
//! summer file, 5 cm and earth-clear with 2.9 cm of water, suns 30 and 5,
//! X, Y, Z within 5.7e-4 (a test). The plan costs some 20 ms (the sup
//! sampled 100 times a decade of m, widened by the most the difference
//! can bend between samples). Exact views, spectra, irradiance and aerial
//! perspective of a default sky keep every term; a colour sky's spectral
//! images are refused (docs/atmosphere-file.md).
//!
//! **Cost.** On the summer file (`scripts/bench/gases.sh`, release) the
//! 256 x 256 colour fisheye over 380-780 nm takes 2.14 times the CPU of the
//! gas-free image (0.90 against 0.42 CPU-s, idle, median of 5), and 36 exact views at 900-1000 nm (every sample in the 940-nm
//! water band) about 2.6 times the gas-free views. The extra CPU is spread
//! over the stages (the sky-view tables' single scattering 23 %, the
//! sun-column table 18 %, the tables' multiply scattered march 16 %, the
//! pixels 13 %, the polarisation tables 10 %, the fields 10 %, the source
//! tables 7 %), per species and per sky. The sun-column table takes the
//! absorbing gases on exponential profiles by the vector exponential, a
//! ray's nodes at once (`SunColumnTable::compute_with_fast_exponentials`:
//! a gas column within 1e-11 of `f64::exp`'s, nothing against
//! [`COLOUR_BOUND`]). How each saving was measured and what was tried and
//! set aside (the air-mass-2 fold, refits with
//! fewer terms, coarser term tables) is in docs/atmosphere-file.md
//! ("`[gases]`").
//!
//! Standard errors (path tracing) add as sum_j w_j se_j, the bound for
//! errors that may be correlated (the terms are traced with one seed).

#[cfg(doc)]
use super::SkyBuilder;
use super::{AerialPerspective, Irradiance, Sky, SkyRadiance};
use crate::atmosphere::gas_bands::{
    MergedSample, TERMS, band_of, band_of_mut, banded_depths_above, has_untermed_gas_bands,
    k_distribution_terms, term_span,
};
use crate::atmosphere::{Atmosphere, DensityProfile, Species, SpeciesModel};
use crate::colour::{Observer, SpectrumToXyz, Xyz};
use crate::error::Result;
use crate::spectrum::{SampledSpectrum, WavelengthGrid};

/// The most a sample's radiance may change, relative, where terms leave
/// out their higher orders of scattering (the bound of
/// [`higher_orders_needed`], summed over the terms left out).
pub(super) const HIGHER_ORDERS_BOUND: f64 = 1e-3;

/// The skies of a k-distribution's terms ([`term_skies`]).
pub(super) struct TermSkies {
    /// (w_j on its grid, the sky of term j), every term with its higher
    /// orders: what images, tables, irradiance and aerial perspective sum.
    pub(super) all: Vec<(SampledSpectrum, Sky)>,
    /// Per entry of `all`: whether exact views take it as it is.
    pub(super) for_views: Vec<bool>,
    /// The runs of samples with and without higher orders that exact views
    /// take for the other entries.
    pub(super) view_runs: Vec<(SampledSpectrum, Sky)>,
}

/// The skies of `atmosphere`'s k-distribution terms, each built by
/// `build(atmosphere of the term, grid, higher orders)` (with the higher
/// orders of scattering, or single scattering and the sunlit ground
/// alone), with their weights per sample of that grid; none without banded
/// gases, or when they are already at a term (a term's own atmosphere is
/// one solve).
///
/// Only the samples of `gas_bands::term_span` (from the first to the last
/// at which the terms' atmospheres differ) need every term: term 0's sky
/// covers the whole of `grid`, weighted there by the sum of all the terms'
/// weights outside the span (every term is the same atmosphere at those
/// samples), and the other terms' skies cover the span alone (`grid`'s
/// sub-grid). With `eye_altitude_m` (m above the ground; `None`: every
/// term keeps its higher orders everywhere), a term that may leave out its
/// higher orders at some samples ([`higher_orders_needed`]) also has its
/// span cut into runs of samples solved with and without them, one sky
/// each, for exact views ([`TermSkies::view_runs`]): a view costs little
/// beyond its samples' fields, whereas each sky's image tables cost as much
/// as some 70 samples' fields (a 256 x 256 fisheye), so images keep every
/// term whole. With `whole_grid` every term is on `grid` with its higher
/// orders (the oracle the tests compare with).
pub(super) fn term_skies(
    atmosphere: &Atmosphere,
    grid: &WavelengthGrid,
    whole_grid: bool,
    eye_altitude_m: Option<f64>,
    colour: Option<(Observer, f64)>,
    build: impl Fn(&Atmosphere, &WavelengthGrid, bool) -> Result<Sky>,
) -> Result<TermSkies> {
    let mut skies = TermSkies {
        all: Vec::new(),
        for_views: Vec::new(),
        view_runs: Vec::new(),
    };
    if !has_untermed_gas_bands(atmosphere) {
        return Ok(skies);
    }
    // Each term's sky carries only the species that absorb or scatter on
    // its grid ([`carried_species`]).
    let build = |at_term: &Atmosphere, grid: &WavelengthGrid, higher_orders: bool| {
        build(&carried_species(at_term, grid)?, grid, higher_orders)
    };
    let terms = k_distribution_terms(atmosphere, grid)?;
    if whole_grid {
        for (weights, at_term) in &terms {
            skies
                .all
                .push((weights.clone(), build(at_term, grid, true)?));
            skies.for_views.push(true);
        }
        return Ok(skies);
    }
    let span = term_span(atmosphere, grid)?;
    if let (Some((observer, eye_altitude_m)), Some(_)) = (colour, span) {
        // A colour sky: the terms merged into as few skies as keep a
        // colour within COLOUR_BOUND (`colour_plan`).
        let plan = colour_plan(&terms, grid, observer, eye_altitude_m)?;
        for (weights, sky) in colour_skies(&terms, grid, &plan)? {
            let on = build(&sky, &weights.1, true)?;
            skies.all.push((weights.0, on));
            skies.for_views.push(true);
        }
        return Ok(skies);
    }
    let inside = |i: usize| span.is_some_and(|(first, last)| (first..=last).contains(&i));
    let mut weights = terms[0].0.clone();
    for (i, w) in weights.values_mut().iter_mut().enumerate() {
        if !inside(i) {
            *w += terms[1..].iter().map(|(other, _)| other[i]).sum::<f64>();
        }
    }
    skies.all.push((weights, build(&terms[0].1, grid, true)?));
    skies.for_views.push(true);
    let Some((first, last)) = span else {
        return Ok(skies);
    };
    let sub = grid.sub_grid(first, last - first + 1);
    let needed = match eye_altitude_m {
        Some(altitude_m) => higher_orders_needed(&terms, (first, &sub), altitude_m)?,
        None => vec![[true; TERMS]; sub.len()],
    };
    let on = |weights: &SampledSpectrum, start: usize, end: usize| {
        SampledSpectrum::from_values(weights.values()[first + start..first + end].to_vec())
    };
    for (j, (weights, at_term)) in terms.iter().enumerate().skip(1) {
        skies
            .all
            .push((on(weights, 0, sub.len()), build(at_term, &sub, true)?));
        let whole = needed.iter().all(|n| n[j]);
        skies.for_views.push(whole);
        let mut start = 0;
        while !whole && start < sub.len() {
            let higher = needed[start][j];
            let end = (start..sub.len())
                .find(|i| needed[*i][j] != higher)
                .unwrap_or(sub.len());
            let run = grid.sub_grid(first + start, end - start);
            skies
                .view_runs
                .push((on(weights, start, end), build(at_term, &run, higher)?));
            start = end;
        }
    }
    Ok(skies)
}

/// The most a colour image's X, Y or Z may change, relative, where a sky
/// for colour images merges the k-distribution's terms ([`colour_plan`]),
/// for a pixel whose gas-free radiance at the merged samples is at most its
/// colour-matching-weighted mean radiance.
pub const COLOUR_BOUND: f64 = 1e-3;

/// A group of terms one sky of a colour sky carries at a sample: its
/// members' weights summed, one coefficient.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct TermGroup {
    /// The terms merged (in the order of their optical depths).
    pub(super) members: Vec<usize>,
    /// The sum of the members' weights.
    pub(super) weight: f64,
    /// The member whose coefficient the group scales, and the factor on
    /// it (1 for a lone term).
    pub(super) term: usize,
    pub(super) factor: f64,
}

/// What a colour sky carries at each sample: the groups of terms, one sky
/// each (the weakest group first), and the sample's bound s_i D_i.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ColourPlan {
    /// [sample] the groups.
    pub(super) groups: Vec<Vec<TermGroup>>,
    /// [sample] s_i D_i: the most the merge there moves a colour, relative.
    pub(super) bounds: Vec<f64>,
}

/// The groups of terms a sky for colour images (seen by `observer`, from
/// an eye `eye_altitude_m` above the ground) carries at each sample of
/// `grid`: as few skies as keep the sum over the samples of s_i D_i within
/// [`COLOUR_BOUND`].
///
/// At each sample the terms differ in one banded gas (where several
/// absorb, the weaker take their effective coefficient in every term,
/// `gas_bands`), with vertical optical depths tau_j from the ground. A
/// path whose amount of that gas is m vertical columns has optical depth
/// m tau_j in term j (the correlated-k scaling; the other gases' depths are
/// the same in every term), and every path light takes from the top of the
/// atmosphere to the eye crosses each shell above it, so m >= m_min, the
/// gas' column above the eye over its column above the ground (1 on the
/// ground), whatever the sun and however many times the light scatters.
/// A group G of terms carried by one sky at depth tau_G with weight
/// W_G = sum_{j in G} w_j changes each path's light, relative to its
/// light without the gas, by at most
///
/// ```text
///     D_G = sup_{m >= m_min} |sum_{j in G} w_j exp(-m tau_j) - W_G exp(-m tau_G)|
/// ```
///
/// (tau_G chosen to make D_G least; for a spread of depths small against
/// 1/m the error is second order in it, w-weighted variance m^2 var(tau)
/// / 2, so weak terms merge freely and strong ones where they are all but
/// dark), and a sample's groups together by at most D_i = sum_G D_G of
/// L_free, the radiance without the gas. The colour's change, relative,
/// is then at most sum_i s_i D_i, s_i the sample's largest share of the
/// colour-matching sums (`colour_plan` of the fold before it; a pixel
/// twice as red as its mean at the merged samples may err twice the
/// bound). Groups are runs of the terms sorted by depth; each sample
/// takes the fewest groups G_i such that the bound holds with as few
/// skies (max_i G_i) as possible: first the fewest skies K for which the
/// samples' least D_i(K) sum within the bound, then samples give up groups
/// (the cheapest in bound first) while the sum stays within it.
pub(super) fn colour_plan(
    terms: &[(SampledSpectrum, Atmosphere)],
    grid: &WavelengthGrid,
    observer: Observer,
    eye_altitude_m: f64,
) -> Result<ColourPlan> {
    let n = grid.len();
    let ground = terms
        .iter()
        .map(|(_, at_term)| banded_depths_above(at_term, grid, 0.0))
        .collect::<Result<Vec<_>>>()?;
    let above = banded_depths_above(&terms[0].1, grid, eye_altitude_m)?;
    let ground_0 = &ground[0];
    let cmfs = SpectrumToXyz::new(grid, observer);
    let cmfs = cmfs.weighted_cmfs();
    let totals: [f64; 3] = std::array::from_fn(|c| cmfs.iter().map(|v| v[c]).sum());
    // [sample][groups - 1]: (D_i, the groups).
    let mut options: Vec<Vec<(f64, Vec<TermGroup>)>> = Vec::with_capacity(n);
    let mut shares = Vec::with_capacity(n);
    for i in 0..n {
        let share = (0..3).map(|c| cmfs[i][c] / totals[c]).fold(0.0, f64::max);
        shares.push(share);
        let gases = ground_0.len();
        let varying: Vec<usize> = (0..gases)
            .filter(|g| ground.iter().any(|t| t[*g][i] != ground_0[*g][i]))
            .collect();
        let weights: Vec<f64> = terms.iter().map(|(w, _)| w[i]).collect();
        let depths: Vec<f64> = ground
            .iter()
            .map(|t| varying.iter().map(|g| t[*g][i]).sum())
            .collect();
        // m_min: the least ratio of column above the eye to column from
        // the ground over the varying gases (each one's profile alone).
        let m_min = varying
            .iter()
            .filter(|g| ground_0[**g][i] > 0.0)
            .map(|g| above[*g][i] / ground_0[*g][i])
            .fold(f64::INFINITY, f64::min);
        let m_min = if m_min.is_finite() { m_min } else { 1.0 };
        options.push(sample_options(
            &weights,
            &depths,
            !varying.is_empty(),
            m_min,
        ));
    }
    let bound_of = |i: usize, g: usize| shares[i] * options[i][g - 1].0;
    let most = terms.len();
    let skies = (1..=most)
        .find(|g| (0..n).map(|i| bound_of(i, *g)).sum::<f64>() <= COLOUR_BOUND)
        .unwrap_or(most);
    let mut count = vec![skies; n];
    let mut total: f64 = (0..n).map(|i| bound_of(i, skies)).sum();
    loop {
        let cheapest = (0..n)
            .filter(|i| count[*i] > 1)
            .map(|i| (bound_of(i, count[i] - 1) - bound_of(i, count[i]), i))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match cheapest {
            Some((added, i)) if total + added <= COLOUR_BOUND => {
                total += added;
                count[i] -= 1;
            }
            _ => break,
        }
    }
    Ok(ColourPlan {
        bounds: (0..n).map(|i| bound_of(i, count[i])).collect(),
        groups: options
            .into_iter()
            .zip(&count)
            .map(|(mut best, g)| std::mem::take(&mut best[g - 1].1))
            .collect(),
    })
}

/// A sample's best partition of its terms (`weights` w_j, `depths` tau_j
/// of the gas that varies, none if not `varying`; paths from `m_min`
/// vertical columns) into each number of groups, runs of the terms sorted
/// by depth: [groups - 1] (D_i, the groups) of [`colour_plan`].
#[allow(clippy::needless_range_loop)]
pub(super) fn sample_options(
    weights: &[f64],
    depths: &[f64],
    varying: bool,
    m_min: f64,
) -> Vec<(f64, Vec<TermGroup>)> {
    let mut order: Vec<usize> = (0..weights.len()).collect();
    order.sort_by(|a, b| depths[*a].total_cmp(&depths[*b]));
    let air = varying.then(|| AirMasses::new(weights, depths, m_min));
    // Every run [a, b] of `order` as one group.
    let k = order.len();
    let mut runs = vec![vec![None; k]; k];
    for a in 0..k {
        for b in a..k {
            let members: Vec<usize> = order[a..=b].to_vec();
            let (depth, bound) = match &air {
                None => (depths[members[0]], 0.0),
                Some(air) => merged_depth(&members, weights, depths, air),
            };
            let strongest = *members.last().unwrap();
            let factor = if members.len() == 1 || depths[strongest] <= 0.0 {
                1.0
            } else {
                depth / depths[strongest]
            };
            runs[a][b] = Some((
                bound,
                TermGroup {
                    weight: members.iter().map(|j| weights[*j]).sum(),
                    members,
                    term: strongest,
                    factor,
                },
            ));
        }
    }
    // The best partition into each number of runs.
    let mut best: Vec<(f64, Vec<TermGroup>)> = vec![(f64::INFINITY, Vec::new()); k];
    for cuts in 0u32..(1 << (k - 1)) {
        let mut groups = Vec::new();
        let mut bound = 0.0;
        let mut a = 0;
        for b in 0..k {
            if b == k - 1 || cuts & (1 << b) != 0 {
                let (d, group) = runs[a][b].clone().unwrap();
                bound += d;
                groups.push(group);
                a = b + 1;
            }
        }
        let slot = &mut best[groups.len() - 1];
        if bound < slot.0 {
            *slot = (bound, groups);
        }
    }
    best
}

/// The skies of a colour sky's `plan`: ((the weights on its grid, its
/// grid), its atmosphere) per slot, slot g carrying each sample's g-th
/// group (the weakest first): slot 0 on the whole of `grid`, the others
/// on the sub-grid from the first to the last sample with more than g
/// groups (weight 0 at the samples between with fewer).
#[allow(clippy::type_complexity)]
pub(super) fn colour_skies(
    terms: &[(SampledSpectrum, Atmosphere)],
    grid: &WavelengthGrid,
    plan: &ColourPlan,
) -> Result<Vec<((SampledSpectrum, WavelengthGrid), Atmosphere)>> {
    let slots = plan.groups.iter().map(Vec::len).max().unwrap_or(1);
    // The banded gases that vary between the terms at each sample.
    let at_term = |j: usize| -> Result<Vec<Vec<f64>>> {
        let optics = terms[j].1.compute_optics(grid)?;
        Ok(optics
            .species
            .iter()
            .map(|s| s.extinction_per_m.values().to_vec())
            .collect())
    };
    let by_term = (0..terms.len()).map(at_term).collect::<Result<Vec<_>>>()?;
    let banded: Vec<bool> = terms[0]
        .1
        .species
        .iter()
        .map(|s| band_of(s).is_some())
        .collect();
    let mut out = Vec::with_capacity(slots);
    for slot in 0..slots {
        let (first, last) = if slot == 0 {
            (0, grid.len() - 1)
        } else {
            let has = |i: &usize| plan.groups[*i].len() > slot;
            let first = (0..grid.len()).find(has).unwrap_or(0);
            (first, (0..grid.len()).rfind(has).unwrap_or(0))
        };
        let sub = grid.sub_grid(first, last - first + 1);
        let mut atmosphere = terms[0].1.clone();
        let mut weights = Vec::with_capacity(sub.len());
        let mut merged: Vec<Vec<MergedSample>> = vec![Vec::new(); banded.len()];
        for i in first..=last {
            let groups = &plan.groups[i];
            let (weight, group) = match groups.get(slot) {
                Some(group) => (group.weight, group),
                None => (0.0, groups.last().expect("a group")),
            };
            weights.push(weight);
            for (s, list) in merged.iter_mut().enumerate() {
                if !banded[s] {
                    continue;
                }
                let varies = by_term.iter().any(|t| t[s][i] != by_term[0][s][i]);
                list.push(MergedSample {
                    wavelength_nm: grid.wavelength_nm(i),
                    term: group.term,
                    factor: if varies { group.factor } else { 1.0 },
                });
            }
        }
        for (species, list) in atmosphere.species.iter_mut().zip(merged) {
            if let Some(band) = band_of_mut(species) {
                band.merged = list;
            }
        }
        out.push(((SampledSpectrum::from_values(weights), sub), atmosphere));
    }
    Ok(out)
}

/// The air masses at which [`merged_depth`] samples D_G at a sample, and
/// each term's w_j exp(-m tau_j) there.
struct AirMasses {
    /// m_min = m_0 < m_1 < ... up to where every positive depth is dark
    /// (m tau >= 40), log-spaced, [`MERGE_STEPS_PER_DECADE`] a decade.
    m: Vec<f64>,
    /// [term][step] w_j exp(-m tau_j).
    light: Vec<Vec<f64>>,
    /// The step in ln m.
    step: f64,
    /// Whether m_min lies below the first air mass (see [`AirMasses::new`]).
    below: bool,
}

impl AirMasses {
    fn new(weights: &[f64], depths: &[f64], m_min: f64) -> AirMasses {
        let positive = depths
            .iter()
            .copied()
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min);
        // An eye high above the gas (m_min near 0): the air masses start
        // where the deepest term's depth is 1e-6, below which every
        // difference is within 2e-6 W (|df/dm| <= 2 W tau_max), added to
        // the bound ([`merged_depth`]).
        let deepest = depths.iter().copied().fold(0.0, f64::max);
        let floor = if deepest > 0.0 { 1e-6 / deepest } else { 1.0 };
        let below = m_min < floor;
        let m_min = m_min.max(floor);
        let m_max = if positive.is_finite() {
            (40.0 / positive).max(m_min)
        } else {
            m_min
        };
        let steps = ((m_max / m_min).log10() * MERGE_STEPS_PER_DECADE as f64)
            .ceil()
            .max(1.0) as usize;
        let m: Vec<f64> = (0..=steps)
            .map(|s| m_min * (m_max / m_min).powf(s as f64 / steps as f64))
            .collect();
        let light = weights
            .iter()
            .zip(depths)
            .map(|(w, d)| m.iter().map(|m| w * (-m * d).exp()).collect())
            .collect();
        AirMasses {
            below,
            step: (m_max / m_min).ln() / steps as f64,
            m,
            light,
        }
    }
}

/// The depth tau_G that makes D_G of [`colour_plan`] least for the group
/// `members` (`weights` w_j, `depths` tau_j of the varying gas, on the
/// air masses `air`), and that D_G: (tau_G, D_G).
///
/// D_G is the sup of |f(m)| = |sum_{j in G} w_j exp(-m tau_j) - W_G exp(-m
/// tau_G)| over m >= m_min: sampled at `air`'s air masses, every m between
/// two of them within h^2 / 8 sup |f''| of the line between theirs (h
/// their step in ln m; d^2/d(ln m)^2 of w exp(-m tau) is w x (x - 1) e^-x,
/// x = m tau, at most 0.31 w in size, so |f''| <= 0.62 W_G), and beyond
/// the last (every positive depth dark) within the weight of the members
/// of zero depth plus W_G e^-40.
fn merged_depth(members: &[usize], weights: &[f64], depths: &[f64], air: &AirMasses) -> (f64, f64) {
    if members.len() == 1 {
        return (depths[members[0]], 0.0);
    }
    let total_weight: f64 = members.iter().map(|j| weights[*j]).sum();
    let positive = members
        .iter()
        .map(|j| depths[*j])
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let deepest = members.iter().map(|j| depths[*j]).fold(0.0, f64::max);
    if !positive.is_finite() || total_weight <= 0.0 {
        return (0.0, 0.0);
    }
    // Beyond m = 40 / (the least positive depth) every member and the
    // merged term (tau_G at least that depth) are dark.
    let steps = air.m.iter().take_while(|m| **m * positive <= 40.0).count();
    let summed: Vec<f64> = (0..(steps + 1).min(air.m.len()))
        .map(|s| members.iter().map(|j| air.light[*j][s]).sum())
        .collect();
    let unabsorbed: f64 = members
        .iter()
        .filter(|j| depths[**j] <= 0.0)
        .map(|j| weights[*j])
        .sum();
    let error = |tau: f64| -> f64 {
        let mut worst = unabsorbed + total_weight * (-40.0f64).exp();
        for (m, summed) in air.m.iter().zip(&summed) {
            worst = worst.max((summed - total_weight * (-m * tau).exp()).abs());
        }
        worst
    };
    // A scan of ln tau over the members' positive depths, then golden
    // sections about the best point.
    let (lo, hi) = (positive.ln(), deepest.ln());
    const SCAN: usize = 12;
    let at = |s: usize| lo + (hi - lo) * s as f64 / SCAN as f64;
    let best = (0..=SCAN)
        .map(|s| (error(at(s).exp()), s))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap()
        .1;
    let (mut a, mut b) = (at(best.saturating_sub(1)), at((best + 1).min(SCAN)));
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - ratio * (b - a), a + ratio * (b - a));
    let (mut fc, mut fd) = (error(c.exp()), error(d.exp()));
    for _ in 0..20 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - ratio * (b - a);
            fc = error(c.exp());
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + ratio * (b - a);
            fd = error(d.exp());
        }
    }
    let (tau, bound) = if fc < fd {
        (c.exp(), fc)
    } else {
        (d.exp(), fd)
    };
    let below = if air.below { 2e-6 * total_weight } else { 0.0 };
    (
        tau,
        bound + 0.62 * total_weight * air.step * air.step / 8.0 + below,
    )
}

/// Air masses a decade for the sup of [`merged_depth`].
const MERGE_STEPS_PER_DECADE: usize = 100;

/// `atmosphere` without its absorbing gases whose coefficients are zero
/// at every sample of `grid` (the mixed gases and NO2 at 900-1000 nm, say):
/// a species with zero extinction and scattering adds exactly 0 to every
/// optical depth and scattering sum, so the sky is the same without it,
/// and each part built per species (the columns toward the sun, the
/// source's per-species terms) costs less. Only absorbing gases are
/// looked at (their coefficients are cheap to sample; aerosols' are not,
/// and air always scatters), and not those on a piecewise-linear profile
/// (its corners cut every ray's quadrature panels). The same atmosphere
/// when none is zero.
pub(super) fn carried_species(
    atmosphere: &Atmosphere,
    grid: &WavelengthGrid,
) -> Result<Atmosphere> {
    // A piecewise-linear profile's corners cut the rays' quadrature
    // panels (`ProfileCorners`) whatever the species' coefficient: such a
    // species stays, so that the sky is the same bit for bit.
    let is_gas = |s: &&Species| {
        matches!(s.model, SpeciesModel::AbsorbingGas(_))
            && !matches!(s.profile, DensityProfile::PiecewiseLinear(_))
    };
    let with = |species: Vec<Species>| Atmosphere {
        species,
        name: atmosphere.name.clone(),
        description: atmosphere.description.clone(),
        planet: atmosphere.planet.clone(),
        sun: atmosphere.sun.clone(),
    };
    let gases = with(atmosphere.species.iter().filter(is_gas).cloned().collect());
    let optics = gases.compute_optics(grid)?;
    let mut zero = optics.species.iter().map(|s| {
        s.extinction_per_m
            .values()
            .iter()
            .chain(s.scattering_per_m.values())
            .all(|v| *v == 0.0)
    });
    Ok(with(
        atmosphere
            .species
            .iter()
            .filter(|s| !is_gas(s) || !zero.next().unwrap_or(false))
            .cloned()
            .collect(),
    ))
}

/// Which terms need their higher orders of scattering (all orders but the
/// first, and the skylight the ground reflects) at each sample of `sub`
/// (the span, from sample `first` of the terms' grid), for an eye
/// `altitude_m` above the ground: [sample][term].
///
/// Every path light takes from the top of the atmosphere to the eye
/// crosses each shell above the eye, so its optical depth in a banded gas
/// is at least the gas' vertical optical depth above the eye, tau_v. Term
/// j's atmosphere is term 0's with more absorption by the banded gases
/// (where every gas absorbs at least as much in j as in 0), the same
/// profiles, so each path's light in term j is term 0's times
/// exp(-(its optical depth in j less that in 0)), at most exp(-dtau_j)
/// with dtau_j = tau_v,j - tau_v,0 summed over the gases: order by order,
/// term j's higher orders M_j are at most exp(-dtau_j) M_0, in every
/// direction and at every point the eye sees. Leaving them out of the sum
/// L = sum_k w_k L_k >= w_0 L_0 >= w_0 M_0 changes it by less than
///
/// ```text
///     sum_j w_j M_j / L <= sum_j (w_j / w_0) exp(-dtau_j)
/// ```
///
/// of itself; the strongest terms leave theirs out while that sum stays
/// within [`HIGHER_ORDERS_BOUND`]. Term 0 keeps them everywhere.
pub(super) fn higher_orders_needed(
    terms: &[(SampledSpectrum, Atmosphere)],
    (first, sub): (usize, &WavelengthGrid),
    altitude_m: f64,
) -> Result<Vec<[bool; TERMS]>> {
    // [term][gas][sample]
    let depths = terms
        .iter()
        .map(|(_, at_term)| banded_depths_above(at_term, sub, altitude_m))
        .collect::<Result<Vec<_>>>()?;
    Ok((0..sub.len())
        .map(|i| {
            let mut needed = [true; TERMS];
            let w0 = terms[0].0[first + i];
            let mut bound = 0.0;
            for j in (1..terms.len().min(TERMS)).rev() {
                let gases = depths[j].iter().zip(&depths[0]);
                if w0 <= 0.0 || gases.clone().any(|(dj, d0)| dj[i] < d0[i]) {
                    break;
                }
                let extra: f64 = gases.map(|(dj, d0)| dj[i] - d0[i]).sum();
                let term_bound = terms[j].0[first + i] / w0 * (-extra).exp();
                if bound + term_bound > HIGHER_ORDERS_BOUND {
                    break;
                }
                bound += term_bound;
                needed[j] = false;
            }
            needed
        })
        .collect())
}

/// A term's values on its sub-grid, from sample `offset` of a grid of `n`,
/// as a spectrum on that grid (zero elsewhere).
fn widen(spectrum: &SampledSpectrum, offset: usize, n: usize) -> SampledSpectrum {
    if offset == 0 && spectrum.len() == n {
        return spectrum.clone();
    }
    let mut values = vec![0.0; n];
    values[offset..offset + spectrum.len()].copy_from_slice(spectrum.values());
    SampledSpectrum::from_values(values)
}

/// [`widen`] of every spectrum of a view's radiance.
fn widen_radiance(radiance: &SkyRadiance, offset: usize, n: usize) -> SkyRadiance {
    let w = |s: &SampledSpectrum| widen(s, offset, n);
    SkyRadiance {
        radiance_w_m2_sr_nm: w(&radiance.radiance_w_m2_sr_nm),
        standard_error_w_m2_sr_nm: radiance.standard_error_w_m2_sr_nm.as_ref().map(w),
        stokes: radiance.stokes.as_ref().map(|stokes| super::Stokes {
            q_w_m2_sr_nm: w(&stokes.q_w_m2_sr_nm),
            u_w_m2_sr_nm: w(&stokes.u_w_m2_sr_nm),
            v_w_m2_sr_nm: w(&stokes.v_w_m2_sr_nm),
            standard_errors_w_m2_sr_nm: stokes
                .standard_errors_w_m2_sr_nm
                .as_ref()
                .map(|errors| errors.each_ref().map(w)),
        }),
    }
}

/// The one weight of every sample, when the weights are all equal (the
/// shared weights: the sum then scales whole colours, as it did before
/// the A band had weights of its own).
pub(super) fn uniform_weight(weights: &SampledSpectrum) -> Option<f64> {
    let first = *weights.values().first()?;
    weights
        .values()
        .iter()
        .all(|w| *w == first)
        .then_some(first)
}

/// A term's colour conversion, for a term on `grid`, the sub-grid from
/// sample `offset` of `to_xyz`'s: `to_xyz` on that sub-grid (with the
/// weight to scale its colours by) when the term's weights are uniform,
/// else with its colour-matching functions scaled sample by sample by the
/// weights (weight 1); `None` when the sub-grid has no sample in the
/// colour-matching functions' range (the term adds no colour).
pub(super) fn term_colour_conversion<'a>(
    to_xyz: &'a SpectrumToXyz,
    (offset, grid): (usize, &WavelengthGrid),
    weights: &SampledSpectrum,
) -> Option<(f64, std::borrow::Cow<'a, SpectrumToXyz>)> {
    let on_grid = if grid == to_xyz.grid() {
        std::borrow::Cow::Borrowed(to_xyz)
    } else {
        std::borrow::Cow::Owned(to_xyz.restricted(offset, grid))
    };
    if on_grid.colour_sample_count() == 0 {
        return None;
    }
    Some(match uniform_weight(weights) {
        Some(weight) => (weight, on_grid),
        None => (
            1.0,
            std::borrow::Cow::Owned(on_grid.scaled(weights.values())),
        ),
    })
}

/// sum_j w_j x_j of colours.
pub(super) fn add_scaled_xyz(sum: &mut Xyz, weight: f64, xyz: &Xyz) {
    sum.x += weight * xyz.x;
    sum.y += weight * xyz.y;
    sum.z += weight * xyz.z;
}

/// sum_j w_j image_j, pixel by pixel, of equal-sized images; `add(sum, w,
/// value)` adds w value to sum.
pub(super) fn weighted_images<T: Clone>(
    images: Vec<(f64, Vec<T>)>,
    add: impl Fn(&mut T, f64, &T),
    zero: T,
) -> Vec<T> {
    let pixels = images.first().map_or(0, |(_, image)| image.len());
    let mut sum = vec![zero; pixels];
    for (weight, image) in &images {
        for (s, v) in sum.iter_mut().zip(image) {
            add(s, *weight, v);
        }
    }
    sum
}

impl Sky {
    /// The k-distribution's terms of a sky with banded gases: (w_j per
    /// sample, the sky with every banded gas at term j), whose weighted sum
    /// every radiance, image, irradiance and aerial perspective of this sky
    /// is (see `sky/k_terms.rs`); empty without banded gases.
    pub fn k_terms(&self) -> &[(SampledSpectrum, Sky)] {
        &self.k_terms
    }

    /// Where term sky `term` starts on this sky's grid (0, or the first
    /// sample of its sub-grid; see [`term_skies`]).
    pub(super) fn term_offset(&self, term: &Sky) -> usize {
        let grid = self.wavelengths();
        ((term.wavelengths().start_nm() - grid.start_nm()) / grid.step_nm()).round() as usize
    }

    /// The terms' weights on this sky's grid (zero outside a term's
    /// sub-grid) and their skies.
    fn widened_terms(&self) -> impl Iterator<Item = (usize, SampledSpectrum, &Sky)> {
        let n = self.wavelengths().len();
        self.k_terms.iter().map(move |(weights, sky)| {
            let offset = self.term_offset(sky);
            (offset, widen(weights, offset, n), sky)
        })
    }

    /// sum_j w_j f(sky_j) of per-view radiances, `compute(k, skies,
    /// sky_k)` of each of the skies summed; with `exact_views`, the terms'
    /// skies that exact views take (runs without negligible higher orders,
    /// see [`term_skies`]), else every term's whole sky.
    pub(super) fn sum_term_radiances(
        &self,
        exact_views: bool,
        compute: impl Fn(usize, usize, &Sky) -> Result<Vec<SkyRadiance>>,
    ) -> Result<Vec<SkyRadiance>> {
        let n = self.wavelengths().len();
        let skies: Vec<&(SampledSpectrum, Sky)> = if exact_views {
            self.k_terms
                .iter()
                .zip(&self.k_terms_for_views)
                .filter_map(|(term, whole)| whole.then_some(term))
                .chain(&self.view_terms)
                .collect()
        } else {
            self.k_terms.iter().collect()
        };
        let by_term = skies
            .iter()
            .enumerate()
            .map(|(k, (weights, sky))| {
                let offset = self.term_offset(sky);
                let results = compute(k, skies.len(), sky)?;
                Ok((offset, widen(weights, offset, n), results))
            })
            .collect::<Result<Vec<_>>>()?;
        let views = by_term.first().map_or(0, |(_, _, r)| r.len());
        Ok((0..views)
            .map(|v| {
                let parts: Vec<(SampledSpectrum, SkyRadiance)> = by_term
                    .iter()
                    .map(|(offset, w, results)| {
                        (w.clone(), widen_radiance(&results[v], *offset, n))
                    })
                    .collect();
                SkyRadiance::weighted_sum(&parts)
            })
            .collect())
    }

    /// sum_j w_j f(sky_j) of spectra.
    pub(super) fn sum_term_spectra(&self, f: impl Fn(&Sky) -> SampledSpectrum) -> SampledSpectrum {
        let n = self.wavelengths().len();
        let parts: Vec<(SampledSpectrum, SampledSpectrum)> = self
            .widened_terms()
            .map(|(offset, w, sky)| (w, widen(&f(sky), offset, n)))
            .collect();
        SampledSpectrum::weighted_sum(parts.iter().map(|(w, s)| (w, s)))
    }

    /// sum_j w_j of the terms' irradiance on a plane.
    pub(super) fn sum_term_irradiance(
        &self,
        f: impl Fn(&Sky) -> Result<Irradiance>,
    ) -> Result<Irradiance> {
        let n = self.wavelengths().len();
        let parts = self
            .widened_terms()
            .map(|(offset, w, sky)| {
                let e = f(sky)?;
                let widened = |s: &SampledSpectrum| widen(s, offset, n);
                Ok((
                    w,
                    Irradiance {
                        direct_normal_w_m2_nm: widened(&e.direct_normal_w_m2_nm),
                        direct_beam_transmittance: widened(&e.direct_beam_transmittance),
                        direct_w_m2_nm: widened(&e.direct_w_m2_nm),
                        diffuse_w_m2_nm: widened(&e.diffuse_w_m2_nm),
                        diffuse_standard_error_w_m2_nm: e
                            .diffuse_standard_error_w_m2_nm
                            .as_ref()
                            .map(widened),
                        global_w_m2_nm: widened(&e.global_w_m2_nm),
                    },
                ))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Irradiance::weighted_sum(&parts))
    }

    /// sum_j w_j of the terms' aerial perspectives, segment by segment
    /// (each part linear in the light; the distance is every term's).
    pub(super) fn sum_term_aerial_perspectives(
        &self,
        f: impl Fn(&Sky) -> Result<Vec<AerialPerspective>>,
    ) -> Result<Vec<AerialPerspective>> {
        let n = self.wavelengths().len();
        let by_term = self
            .widened_terms()
            .map(|(offset, w, sky)| Ok((offset, w, f(sky)?)))
            .collect::<Result<Vec<_>>>()?;
        let segments = by_term.first().map_or(0, |(_, _, r)| r.len());
        Ok((0..segments)
            .map(|s| {
                let sum = |field: fn(&AerialPerspective) -> &SampledSpectrum| {
                    let parts: Vec<(&SampledSpectrum, SampledSpectrum)> = by_term
                        .iter()
                        .map(|(offset, w, r)| (w, widen(field(&r[s]), *offset, n)))
                        .collect();
                    SampledSpectrum::weighted_sum(parts.iter().map(|(w, v)| (*w, v)))
                };
                let radiances: Vec<(SampledSpectrum, SkyRadiance)> = by_term
                    .iter()
                    .map(|(offset, w, r)| (w.clone(), widen_radiance(&r[s].radiance, *offset, n)))
                    .collect();
                AerialPerspective {
                    distance_m: by_term[0].2[s].distance_m,
                    radiance: SkyRadiance::weighted_sum(&radiances),
                    transmittance: sum(|a| &a.transmittance),
                    sun_transmittance_at_point: sum(|a| &a.sun_transmittance_at_point),
                    sky_irradiance_at_point: sum(|a| &a.sky_irradiance_at_point),
                }
            })
            .collect())
    }

    /// Sky `k`'s progress (`done` of `total`) as a share of the work of all
    /// `terms` skies summed, for a `progress` callback: (k total + done) of
    /// (terms x total).
    pub(super) fn term_progress(
        &self,
        (k, terms): (usize, usize),
        done: u64,
        total: u64,
    ) -> (u64, u64) {
        (k as u64 * total + done, terms as u64 * total)
    }
}

impl Sky {
    /// sum_j w_j of the terms' images, each rendered by `render((offset_j,
    /// w_j), sky_j, progress)` (offset_j: where sky_j's grid starts on this
    /// sky's, w_j on sky_j's grid), which returns (the weight to scale its
    /// values by, the image on this sky's grid): the weight where w_j is
    /// uniform, else 1 with the image already weighted sample by sample;
    /// `None` for a term that adds nothing (no colour on its sub-grid);
    /// `progress(rows)` sees the terms' rows as one pass.
    pub(super) fn sum_term_images<T: Clone>(
        &self,
        progress: &(dyn Fn(usize) + Sync),
        zero: T,
        add: impl Fn(&mut T, f64, &T),
        render: impl Fn(
            (usize, &SampledSpectrum),
            &Sky,
            &(dyn Fn(usize) + Sync),
        ) -> Result<Option<(f64, Vec<T>)>>,
    ) -> Result<Vec<T>> {
        let terms = self.k_terms.len();
        let mut images = Vec::with_capacity(terms);
        let mut rows_before = 0;
        for (weights, sky) in &self.k_terms {
            let before = rows_before;
            let most = std::sync::atomic::AtomicUsize::new(0);
            let image = render((self.term_offset(sky), weights), sky, &|rows| {
                most.fetch_max(rows, std::sync::atomic::Ordering::Relaxed);
                progress((before + rows) / terms);
            })?;
            rows_before += most.into_inner();
            images.extend(image);
        }
        Ok(weighted_images(images, add, zero))
    }

    /// The term skies that add colour, each with its colour conversion
    /// through [`term_colour_conversion`] (the weight to scale its colours
    /// by, and the conversion on its grid): what a colour image of the
    /// terms sums, pixel by pixel (`Sky::render_pixels_of`).
    pub(super) fn term_colour_conversions<'a>(
        &'a self,
        to_xyz: &'a SpectrumToXyz,
    ) -> (
        Vec<&'a Sky>,
        Vec<(f64, std::borrow::Cow<'a, SpectrumToXyz>)>,
    ) {
        self.k_terms
            .iter()
            .filter_map(|(weights, term)| {
                let grid = (self.term_offset(term), term.wavelengths());
                term_colour_conversion(to_xyz, grid, weights).map(|c| (term, c))
            })
            .unzip()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::atmosphere::gas_bands::{BandedGases, banded_gas_species};
    use crate::camera::Camera;
    use crate::geometry::ViewDirection;
    use crate::sky::{ImageSettings, Method, Plane, Polarisation};
    use crate::spectrum::WavelengthGrid;
    use crate::transport::multiple_scattering::MultipleScatteringTable;

    /// earth-clear with 2.9 cm of water (2 km scale height) and the mixed
    /// gases (also the polarisation correction's tests' atmosphere).
    pub(crate) fn earth_clear_with_gases() -> Atmosphere {
        let mut atmosphere = Atmosphere::preset("earth-clear").unwrap();
        atmosphere
            .species
            .extend(banded_gas_species(&BandedGases::new(
                Some((2.9, 2000.0)),
                true,
            )));
        atmosphere
    }

    fn relative(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    #[test]
    fn every_answer_of_a_sky_with_gases_is_the_weighted_sum_of_its_terms() {
        // Each term's sky built on its own from the term's atmosphere; the
        // sky of the whole atmosphere must give their weighted sum for
        // views, irradiance, the direct beam, spectral images and aerial
        // perspective (740, 760 and 780 nm: the O2 A band in the middle).
        let atmosphere = earth_clear_with_gases();
        let grid = WavelengthGrid::new(740.0, 780.0, 20.0).unwrap();
        let build = |a: &Atmosphere| {
            Sky::builder(a)
                .sun_deg(10.0, 180.0)
                .wavelengths(grid)
                .polarisation(Polarisation::Scalar)
                .build()
                .unwrap()
        };
        // Every term with its higher orders on the whole grid (the span is
        // the whole grid here; the strong terms leaving theirs out is
        // measured against this sky in the tests below).
        let sky = Sky::builder(&atmosphere)
            .sun_deg(10.0, 180.0)
            .wavelengths(grid)
            .polarisation(Polarisation::Scalar)
            .build_with_terms(true)
            .unwrap();
        assert_eq!(sky.k_terms().len(), crate::atmosphere::gas_bands::TERMS);
        let terms: Vec<(SampledSpectrum, Sky)> = k_distribution_terms(&atmosphere, &grid)
            .unwrap()
            .iter()
            .map(|(w, a)| (w.clone(), build(a)))
            .collect();
        // 760 nm (the A band, the mixed gases absorbing most) has weights of
        // its own; 740 and 780 nm the shared ones.
        let shared = crate::atmosphere::gas_bands::k_terms()[0].weight;
        assert_eq!(terms[0].0[0], shared);
        assert_ne!(terms[0].0[1], shared);
        assert!(terms.iter().all(|(_, t)| t.k_terms().is_empty()));
        let sum = |f: &dyn Fn(&Sky) -> Vec<f64>| -> Vec<f64> {
            let mut total = vec![0.0; 0];
            for (w, t) in &terms {
                let v = f(t);
                total.resize(v.len(), 0.0);
                // Each quantity is a run of spectra on the grid.
                for (i, (s, x)) in total.iter_mut().zip(v).enumerate() {
                    *s += w[i % w.len()] * x;
                }
            }
            total
        };
        let check = |what: &str, got: Vec<f64>, want: Vec<f64>| {
            assert_eq!(got.len(), want.len(), "{what}");
            for (g, w) in got.iter().zip(&want) {
                assert!(relative(*g, *w) < 1e-12, "{what}: {g} vs {w}");
            }
        };
        let zenith = ViewDirection::new(90.0, 0.0).unwrap();
        let low = ViewDirection::new(5.0, 90.0).unwrap();
        let views = |s: &Sky| -> Vec<f64> {
            s.radiances(&[zenith, low])
                .unwrap()
                .iter()
                .flat_map(|r| r.radiance_w_m2_sr_nm.values().to_vec())
                .collect()
        };
        check("views", views(&sky), sum(&views));
        let global = |s: &Sky| -> Vec<f64> {
            s.irradiance(Plane::HORIZONTAL)
                .unwrap()
                .global_w_m2_nm
                .values()
                .to_vec()
        };
        check("global irradiance", global(&sky), sum(&global));
        let direct = |s: &Sky| s.direct_beam_transmittance().values().to_vec();
        check("direct beam", direct(&sky), sum(&direct));
        let aerial = |s: &Sky| -> Vec<f64> {
            let ap = s.aerial_perspective(low, 20e3).unwrap();
            [
                ap.radiance.radiance_w_m2_sr_nm.values(),
                ap.transmittance.values(),
                ap.sun_transmittance_at_point.values(),
            ]
            .concat()
        };
        check("aerial perspective", aerial(&sky), sum(&aerial));
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, 9, 9)
        };
        let spectral = |s: &Sky| s.render_spectral(&image, &|_| {}).unwrap();
        let rendered = spectral(&sky);
        check("spectral image", rendered.clone(), sum(&spectral));
        // The colour image is the colour of the summed spectra (the terms'
        // colours taken through colour-matching functions scaled by their
        // weights where the weights differ between samples).
        let to_xyz =
            crate::colour::SpectrumToXyz::new(&grid, crate::colour::Observer::Cie1931TwoDegree);
        let colours = sky.render_xyz(&image, &to_xyz, &|_| {}).unwrap();
        let from_spectra: Vec<f64> = rendered
            .chunks(grid.len())
            .flat_map(|pixel| {
                let xyz = to_xyz.to_xyz_unchecked(pixel);
                [xyz.x, xyz.y, xyz.z]
            })
            .collect();
        let got: Vec<f64> = colours.iter().flat_map(|c| [c.x, c.y, c.z]).collect();
        check("colour image", got, from_spectra);
        // The image's zenith pixel and the zenith view now agree in the A
        // band (both the k-sum; they differ by the image tables' error).
        let centre = 4 * 9 + 4;
        let pixel = &rendered[centre * 3..centre * 3 + 3];
        let view = sky.radiance(zenith).unwrap().radiance_w_m2_sr_nm;
        for i in 0..3 {
            assert!(
                relative(pixel[i], view[i]) < 5e-3,
                "{} nm: pixel {} vs view {}",
                grid.wavelength_nm(i),
                pixel[i],
                view[i]
            );
        }
        // One effective solve (what images were before the sky summed its
        // terms) is far off in the A band with the sun low (its coefficient
        // is matched to the banded transmittance at air mass 2; here the
        // sun's is 5.6).
        let effective = Sky::from_scene(
            sky.scene().clone(),
            sky.scattering(),
            Method::Fast,
            sky.table_size(),
        )
        .unwrap();
        let one = effective.render_spectral(&image, &|_| {}).unwrap();
        let error = one[centre * 3 + 1] / view[1] - 1.0;
        println!(
            "zenith 760 nm: image/view - 1 = {:.2e} with the k-sum, {error:.3} with one effective solve",
            pixel[1] / view[1] - 1.0
        );
        assert!(error.abs() > 0.05, "{error}");
        // Without banded gases there are no terms.
        let clear = Atmosphere::preset("earth-clear").unwrap();
        assert!(build(&clear).k_terms().is_empty());
    }
    /// The largest relative difference between `got` and `want`, value by
    /// value (of the larger of |want| and 1e-6 of want's largest).
    fn worst(got: &[f64], want: &[f64]) -> f64 {
        assert_eq!(got.len(), want.len());
        let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs())) * 1e-6;
        got.iter()
            .zip(want)
            .map(|(g, w)| (g - w).abs() / w.abs().max(scale))
            .fold(0.0, f64::max)
    }

    #[test]
    fn terms_on_the_absorbing_span_alone_match_every_term_on_the_whole_grid() {
        // 540-780 nm every 20: water and the O2 bands absorb from 580 nm
        // (water's band at 593 nm, read linearly from the row below), so
        // terms 1-4 are solved on 580-780 nm only and term 0 carries 540
        // and 560 nm with the weights' sum. The oracle: every term on the
        // whole grid.
        let atmosphere = earth_clear_with_gases();
        let grid = WavelengthGrid::new(540.0, 780.0, 20.0).unwrap();
        assert_eq!(term_span(&atmosphere, &grid).unwrap(), Some((2, 12)));
        let zenith = ViewDirection::new(90.0, 0.0).unwrap();
        let low = ViewDirection::new(5.0, 90.0).unwrap();
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, 9, 9)
        };
        let to_xyz =
            crate::colour::SpectrumToXyz::new(&grid, crate::colour::Observer::Cie1931TwoDegree);
        // Scalar (vector measured the same: 4.6e-4 views, 6.1e-4 spectral
        // image, 5.2e-9 direct beam).
        for polarisation in [Polarisation::Scalar] {
            let build = |whole: bool| {
                Sky::builder(&atmosphere)
                    .sun_deg(10.0, 180.0)
                    .wavelengths(grid)
                    .polarisation(polarisation)
                    .build_with_terms(whole)
                    .unwrap()
            };
            let (fast, oracle) = (build(false), build(true));
            assert_eq!(oracle.k_terms().len(), 5);
            assert_eq!(fast.k_terms()[0].1.wavelengths(), &grid);
            assert_eq!(fast.k_terms()[1].1.wavelengths().len(), 11);
            let views = |s: &Sky| -> Vec<f64> {
                s.radiances(&[zenith, low])
                    .unwrap()
                    .iter()
                    .flat_map(|r| {
                        let mut v = r.radiance_w_m2_sr_nm.values().to_vec();
                        if let Some(stokes) = &r.stokes {
                            v.extend(stokes.q_w_m2_sr_nm.values());
                        }
                        v
                    })
                    .collect()
            };
            let global = |s: &Sky| -> Vec<f64> {
                s.irradiance(Plane::HORIZONTAL)
                    .unwrap()
                    .global_w_m2_nm
                    .values()
                    .to_vec()
            };
            let direct = |s: &Sky| s.direct_beam_transmittance().values().to_vec();
            let aerial = |s: &Sky| -> Vec<f64> {
                let ap = s.aerial_perspective(low, 20e3).unwrap();
                [
                    ap.radiance.radiance_w_m2_sr_nm.values(),
                    ap.transmittance.values(),
                    ap.sky_irradiance_at_point.values(),
                ]
                .concat()
            };
            let spectral = |s: &Sky| s.render_spectral(&image, &|_| {}).unwrap();
            let colour = |s: &Sky| -> Vec<f64> {
                s.render_xyz(&image, &to_xyz, &|_| {})
                    .unwrap()
                    .iter()
                    .flat_map(|c| [c.x, c.y, c.z])
                    .collect()
            };
            type Answer<'a> = &'a dyn Fn(&Sky) -> Vec<f64>;
            let checks: [(&str, Answer); 6] = [
                ("views", &views),
                ("global irradiance", &global),
                ("direct beam", &direct),
                ("aerial perspective", &aerial),
                ("spectral image", &spectral),
                ("colour image", &colour),
            ];
            for (what, f) in checks {
                let (got, want) = (f(&fast), f(&oracle));
                let error = worst(&got, &want);
                println!("{polarisation:?} {what}: largest relative difference {error:.2e}");
                // The direct beam is each term's own column (exact to
                // rounding); the rest differ by what the fast method takes
                // from its grid as a whole (the field's layers and the
                // polarisation anchors of a shorter grid): measured 4.7e-4
                // at most, held to the 1e-3 the polarisation anchors are
                // held to (`tests/polarisation_wavelength_stride.rs`).
                assert!(error < 1e-3, "{polarisation:?} {what}: {error:e}");
            }
        }
    }

    #[test]
    fn the_stokes_image_of_a_sky_with_gases_sums_its_terms_as_the_colour_image_does() {
        // A polarised sky with gases (740-780 nm, the A band's own weights
        // at 760 nm): S0 of its Stokes image is its colour image (both the
        // terms' colours summed), and Q's colour is not nothing (the
        // terms' Q images reach the sum).
        let atmosphere = earth_clear_with_gases();
        let grid = WavelengthGrid::new(740.0, 780.0, 20.0).unwrap();
        let sky = Sky::builder(&atmosphere)
            .sun_deg(30.0, 180.0)
            .wavelengths(grid)
            .polarisation(Polarisation::Vector)
            .build()
            .unwrap();
        assert!(!sky.k_terms().is_empty());
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, 9, 9)
        };
        let to_xyz =
            crate::colour::SpectrumToXyz::new(&grid, crate::colour::Observer::Cie1931TwoDegree);
        let colour = sky.render_xyz(&image, &to_xyz, &|_| {}).unwrap();
        let stokes = sky.render_stokes_xyz(&image, &to_xyz, &|_| {}).unwrap();
        assert_eq!(colour.len(), stokes.len());
        let mut q = 0.0f64;
        for (c, s) in colour.iter().zip(&stokes) {
            for (a, b) in [(c.x, s[0].x), (c.y, s[0].y), (c.z, s[0].z)] {
                assert!(relative(b, a) < 1e-12, "S0 {b} vs XYZ {a}");
            }
            q = q.max(s[1].y.abs() / s[0].y.max(1e-300));
        }
        // Rayleigh air 60 degrees from a sun 30 up is strongly polarised.
        assert!(q > 0.1, "largest |Q|/I in Y: {q}");
    }

    #[test]
    fn terms_leave_out_their_higher_orders_only_where_the_bound_allows() {
        // 900-1000 nm every 50 (the 940 nm water band at 950 nm, its wings
        // at 900 and 1000), 2.9 cm of water: where the strong terms' water
        // above the eye is thick, their higher orders are left out, and
        // every answer stays within the bound of the sky whose terms all
        // keep theirs on the whole grid (the oracle).
        let atmosphere = earth_clear_with_gases();
        let grid = WavelengthGrid::new(900.0, 1000.0, 50.0).unwrap();
        let terms = k_distribution_terms(&atmosphere, &grid).unwrap();
        let needed =
            |altitude_m: f64| higher_orders_needed(&terms, (0, &grid), altitude_m).unwrap();
        // On the ground: at 950 nm terms 2-4 leave theirs out, at 900 nm
        // terms 3 and 4, at 1000 nm (a_w ~ 0.09 per cm) term 4 alone; term
        // 0 and term 1 (a vertical optical depth of at most 2.6 more than
        // term 0's) keep theirs.
        assert_eq!(
            needed(0.0),
            vec![
                [true, true, true, false, false],
                [true, true, false, false, false],
                [true, true, true, true, false],
            ]
        );
        // From 20 km, above all but 5e-5 of the water, every term keeps them.
        assert!(needed(20e3).iter().flatten().all(|n| *n));
        let zenith = ViewDirection::new(90.0, 0.0).unwrap();
        let views: Vec<ViewDirection> = [0.0, 30.0, 90.0, 180.0]
            .iter()
            .map(|a| ViewDirection::new(30.0, 180.0 + a).unwrap())
            .chain([zenith, ViewDirection::new(5.0, 90.0).unwrap()])
            .collect();
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, 9, 9)
        };
        let build = |whole: bool| {
            Sky::builder(&atmosphere)
                .sun_deg(30.0, 180.0)
                .wavelengths(grid)
                .polarisation(Polarisation::Scalar)
                .build_with_terms(whole)
                .unwrap()
        };
        let (fast, oracle) = (build(false), build(true));
        // Images, irradiance and aerial perspective take every term whole
        // (here on the whole grid, as the oracle's); exact views the runs.
        assert_eq!(fast.k_terms_for_views, [true, true, false, false, false]);
        assert!(
            fast.k_terms()
                .iter()
                .all(|(_, t)| t.scattering() != crate::sky::Scattering::Single)
        );
        let single: Vec<f64> = fast
            .view_terms
            .iter()
            .filter(|(_, t)| t.scattering() == crate::sky::Scattering::Single)
            .map(|(_, t)| t.wavelengths().start_nm())
            .collect();
        // Term 2 at 950, term 3 at 900-950, term 4 everywhere (runs of 900,
        // 950 and 1000 nm; 900-950 and 1000 nm; 900-1000 nm).
        assert_eq!(fast.view_terms.len(), 6);
        assert_eq!(single, vec![950.0, 900.0, 900.0]);
        let radiances = |s: &Sky| -> Vec<f64> {
            s.radiances(&views)
                .unwrap()
                .iter()
                .flat_map(|r| r.radiance_w_m2_sr_nm.values().to_vec())
                .collect()
        };
        let global = |s: &Sky| -> Vec<f64> {
            let e = s.irradiance(Plane::HORIZONTAL).unwrap();
            [e.global_w_m2_nm.values(), e.diffuse_w_m2_nm.values()].concat()
        };
        let aerial = |s: &Sky| -> Vec<f64> {
            let ap = s.aerial_perspective(views[5], 20e3).unwrap();
            [
                ap.radiance.radiance_w_m2_sr_nm.values(),
                ap.transmittance.values(),
                ap.sky_irradiance_at_point.values(),
            ]
            .concat()
        };
        let spectral = |s: &Sky| s.render_spectral(&image, &|_| {}).unwrap();
        type Answer<'a> = &'a dyn Fn(&Sky) -> Vec<f64>;
        let checks: [(&str, Answer); 4] = [
            ("views", &radiances),
            ("irradiance", &global),
            ("aerial perspective", &aerial),
            ("spectral image", &spectral),
        ];
        for (what, f) in checks {
            let (got, want) = (f(&fast), f(&oracle));
            let error = worst(&got, &want);
            println!("{what}: largest relative difference {error:.2e}");
            // The bound on what is left out, and the sub-grids' own
            // difference (held to 1e-3 in the test above): measured 6.7e-5
            // in views (earth-clear's aerosol scatters more than the
            // benchmark's air alone), 0 in the rest (every term whole).
            assert!(error < HIGHER_ORDERS_BOUND, "{what}: {error:e}");
        }
        // The path tracer keeps every term's higher orders (it has no
        // single scattering alone).
        let traced = Sky::builder(&atmosphere)
            .wavelengths(grid)
            .method(Method::PathTracing {
                samples: 16,
                seed: 1,
            })
            .build()
            .unwrap();
        assert!(
            traced
                .k_terms()
                .iter()
                .all(|(_, t)| t.scattering() != crate::sky::Scattering::Single)
        );
    }

    #[test]
    fn a_term_sky_without_the_species_that_are_zero_on_its_grid_is_the_same() {
        // earth-clear with water, the mixed gases and O2-O2 at 900-1000 nm
        // every 50 (the 940 nm water band): the mixed gases (O2 and CO2
        // bands) have no coefficient there. Each term's sky built
        // from the atmosphere that carries only the rest gives bit for bit
        // the answers of the term's whole atmosphere: polarised views,
        // irradiance, aerial perspective and a spectral image.
        let mut atmosphere = earth_clear_with_gases();
        atmosphere
            .species
            .push(crate::atmosphere::o2_o2::o2_o2_species(&atmosphere.species).unwrap());
        let grid = WavelengthGrid::new(900.0, 1000.0, 50.0).unwrap();
        let views: Vec<ViewDirection> = [0.0, 30.0, 90.0, 180.0]
            .iter()
            .map(|a| ViewDirection::new(30.0, 180.0 + a).unwrap())
            .chain([ViewDirection::new(90.0, 0.0).unwrap()])
            .collect();
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, 9, 9)
        };
        let answers = |a: &Atmosphere| -> Vec<f64> {
            let sky = Sky::builder(a)
                .sun_deg(30.0, 180.0)
                .wavelengths(grid)
                .polarisation(Polarisation::Vector)
                .build()
                .unwrap();
            let mut out = Vec::new();
            for r in sky.radiances(&views).unwrap() {
                out.extend(r.radiance_w_m2_sr_nm.values());
                let stokes = r.stokes.unwrap();
                out.extend(stokes.q_w_m2_sr_nm.values());
                out.extend(stokes.u_w_m2_sr_nm.values());
            }
            let e = sky.irradiance(Plane::HORIZONTAL).unwrap();
            out.extend(e.global_w_m2_nm.values());
            out.extend(e.diffuse_w_m2_nm.values());
            let ap = sky.aerial_perspective(views[4], 20e3).unwrap();
            out.extend(ap.radiance.radiance_w_m2_sr_nm.values());
            out.extend(ap.transmittance.values());
            out.extend(sky.render_spectral(&image, &|_| {}).unwrap());
            out
        };
        let names = |a: &Atmosphere| -> Vec<String> {
            a.species.iter().map(|s| s.name.clone()).collect::<Vec<_>>()
        };
        for (_, at_term) in k_distribution_terms(&atmosphere, &grid).unwrap() {
            let carried = carried_species(&at_term, &grid).unwrap();
            let dropped: Vec<String> = names(&at_term)
                .into_iter()
                .filter(|n| !names(&carried).contains(n))
                .collect();
            assert_eq!(dropped, ["mixed gases (O2, CO2)"]);
            let (got, want) = (answers(&carried), answers(&at_term));
            assert!(want.iter().all(|v| v.is_finite()) && want.iter().any(|v| *v > 0.0));
            assert_eq!(got, want);
        }
        // On the visible grid every gas absorbs somewhere: none is dropped.
        let visible = WavelengthGrid::new(380.0, 780.0, 20.0).unwrap();
        assert_eq!(carried_species(&atmosphere, &visible).unwrap(), atmosphere);
    }

    #[test]
    fn the_terms_skies_share_one_store_of_sun_column_tables() {
        // The sun-column table holds the species' profile columns alone (no
        // coefficient), the same for every term: the terms' skies (and the
        // views' runs, and the terms of the sky moved to another sun) read
        // the one table the first of them built, where they carry the
        // sky's species (580-780 nm: every gas absorbs somewhere). The
        // answers are those of terms built on their own (the first test,
        // within 1e-12).
        let atmosphere = earth_clear_with_gases();
        let grid = WavelengthGrid::new(580.0, 780.0, 40.0).unwrap();
        let sky = Sky::builder(&atmosphere)
            .sun_deg(30.0, 180.0)
            .wavelengths(grid)
            .polarisation(Polarisation::Scalar)
            .build()
            .unwrap();
        let (a, m) = sky.table_size().sun_column_nodes;
        let table = |s: &Sky| s.scene().sun_column_table(a, m);
        let first = table(&sky.k_terms()[0].1);
        let moved = sky.with_sun_deg(10.0, 180.0).unwrap();
        assert_eq!(sky.k_terms().len(), TERMS);
        assert!(!sky.view_terms.is_empty());
        for (_, term) in sky.k_terms().iter().chain(moved.k_terms()) {
            assert!(std::sync::Arc::ptr_eq(&first, &table(term)));
        }
        // The views' runs too, but those that leave out a gas (580-660 nm:
        // the mixed gases have no coefficient there), which build their own.
        let species = sky.optics().species.len();
        for (_, run) in &sky.view_terms {
            let carries_all = run.optics().species.len() == species;
            assert_eq!(std::sync::Arc::ptr_eq(&first, &table(run)), carries_all);
        }
        // A sky of another atmosphere keeps its own.
        let clear = Sky::builder(&Atmosphere::preset("earth-clear").unwrap())
            .wavelengths(grid)
            .build()
            .unwrap();
        assert!(!std::sync::Arc::ptr_eq(&first, &table(&clear)));
    }

    #[test]
    fn the_terms_image_tables_built_together_are_each_terms_own() {
        // The terms' skies march the same view rays through the same
        // sun-column table: built together (`Sky::prepare_images`), the
        // second and later terms' integrals are computed in the first's
        // march (`Together`), and their multiply scattered light in the
        // first's multiple-scattering march
        // (`MultipleScatteringTable::compute_radiance_parts_together`);
        // each term's sky-view table must be bit for bit
        // the one it builds alone (`Sky::compute_tables`), polarised and
        // scalar.
        let atmosphere = earth_clear_with_gases();
        // 500-540 nm without a band: term 0 on the whole grid, the others
        // on the span's sub-grid.
        let grid = WavelengthGrid::new(500.0, 780.0, 40.0).unwrap();
        for polarisation in [Polarisation::Scalar, Polarisation::Vector] {
            let sky = Sky::builder(&atmosphere)
                .sun_deg(20.0, 180.0)
                .wavelengths(grid)
                .polarisation(polarisation)
                .build()
                .unwrap();
            sky.prepare_images().unwrap();
            let first = &sky.k_terms()[0].1;
            assert_eq!(sky.k_terms().len(), TERMS);
            assert!(sky.k_terms()[1].1.wavelengths().len() < grid.len());
            for (_, term) in sky.k_terms() {
                // Every term takes the sharing path, its multiply
                // scattered light marched in the first term's march too.
                assert!(term.scene().has_view_geometry_of(first.scene()));
                let sources = (first.source_table(), term.source_table());
                assert!(matches!(sources, (Some(a), Some(b)) if a.marches_with(b)));
                let together = term.image_tables.get().expect("built together");
                let alone = term.compute_tables(term.source_table(), true);
                assert!(together.sky_view == alone.sky_view, "{polarisation:?}");
            }
            // The tables of many views (their own source tables, at half
            // the steps) too.
            sky.prepare_term_tables(true).unwrap();
            for (_, term) in sky.k_terms() {
                let together = term.view_tables.get().expect("built together");
                let half_steps = term.field.get().map(|field| {
                    MultipleScatteringTable::compute_at_half_steps(std::sync::Arc::clone(field))
                });
                let alone = term.compute_tables(half_steps.as_ref(), true);
                assert!(together.sky_view == alone.sky_view, "{polarisation:?}");
            }
        }
    }

    #[test]
    fn the_terms_colour_images_in_one_pass_are_each_terms_images_summed() {
        // A colour image of a sky with gases renders its terms in one pixel
        // pass (`Sky::render_pixels_of`); it must be bit for bit the sum,
        // in term order, of each term's own image (`weighted_images`, what
        // the images were before), colour and Stokes, the sun's disc in
        // view (5 degrees up, fisheye) and the terms on their sub-grids.
        let atmosphere = earth_clear_with_gases();
        let grid = WavelengthGrid::new(500.0, 780.0, 40.0).unwrap();
        let observer = crate::colour::Observer::Cie1931TwoDegree;
        let sky = Sky::builder(&atmosphere)
            .sun_deg(5.0, 180.0)
            .wavelengths(grid)
            .polarisation(Polarisation::Vector)
            .for_colour_images(observer)
            .build()
            .unwrap();
        let image = ImageSettings::new(Camera::Fisheye, 16, 16);
        assert!(image.draw_sun_disc);
        let to_xyz = SpectrumToXyz::new(&grid, observer);
        let (skies, conversions) = sky.term_colour_conversions(&to_xyz);
        // The colour sky's merged groups: four skies here (`colour_plan`).
        assert!(skies.len() > 2, "{}", skies.len());
        assert!(skies[1].wavelengths().len() < grid.len());
        let bits = |x: &Xyz| [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()];
        let together = sky.render_xyz(&image, &to_xyz, &|_| {}).unwrap();
        let own: Vec<(f64, Vec<Xyz>)> = skies
            .iter()
            .zip(&conversions)
            .map(|(term, (w, c))| (*w, term.render_xyz(&image, c, &|_| {}).unwrap()))
            .collect();
        let summed = weighted_images(own, add_scaled_xyz, Xyz::BLACK);
        assert!(together.iter().any(|x| x.y > 0.0));
        assert!(
            together
                .iter()
                .zip(&summed)
                .all(|(a, b)| bits(a) == bits(b))
        );
        let together = sky.render_stokes_xyz(&image, &to_xyz, &|_| {}).unwrap();
        let own: Vec<(f64, Vec<[Xyz; 4]>)> = skies
            .iter()
            .zip(&conversions)
            .map(|(term, (w, c))| (*w, term.render_stokes_xyz(&image, c, &|_| {}).unwrap()))
            .collect();
        let add = |sum: &mut [Xyz; 4], w: f64, x: &[Xyz; 4]| {
            for (s, x) in sum.iter_mut().zip(x) {
                add_scaled_xyz(s, w, x);
            }
        };
        let summed = weighted_images(own, add, [Xyz::BLACK; 4]);
        for (a, b) in together.iter().zip(&summed) {
            assert!(a.iter().zip(b).all(|(a, b)| bits(a) == bits(b)));
        }
    }

    /// The image's luminance Y and chromaticity x, y of `got` against
    /// `want`, pixel by pixel: (max, p99) of |dY| / Y and of the larger of
    /// |dx|, |dy|, and the largest relative change of X, Y or Z.
    fn colour_errors(got: &[Xyz], want: &[Xyz]) -> ((f64, f64), (f64, f64), f64) {
        let (mut luminance, mut chroma, mut worst) = (Vec::new(), Vec::new(), 0.0f64);
        for (g, w) in got.iter().zip(want) {
            if w.y <= 0.0 {
                continue;
            }
            luminance.push(relative(g.y, w.y));
            let xy = |c: &Xyz| {
                let sum = c.x + c.y + c.z;
                (c.x / sum, c.y / sum)
            };
            let ((gx, gy), (wx, wy)) = (xy(g), xy(w));
            chroma.push((gx - wx).abs().max((gy - wy).abs()));
            for (a, b) in [(g.x, w.x), (g.y, w.y), (g.z, w.z)] {
                worst = worst.max(relative(a, b));
            }
        }
        let stats = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            let p99 = v[((v.len() as f64 * 0.99) as usize).min(v.len() - 1)];
            (*v.last().unwrap(), p99)
        };
        (stats(luminance), stats(chroma), worst)
    }

    /// The sky `builder` makes for colour images (its terms merged,
    /// `colour_plan`) or with every term (the slow path).
    fn colour_or_every_term(
        builder: crate::sky::SkyBuilder<'_>,
        colour: bool,
        observer: crate::colour::Observer,
    ) -> Sky {
        if colour {
            builder.for_colour_images(observer)
        } else {
            builder
        }
        .build()
        .unwrap()
    }

    fn summer_file() -> Atmosphere {
        Atmosphere::from_toml_str(include_str!(
            "../../../sora-cli/tests/data/measured/earth-clear-summer-no-aerosol.toml"
        ))
        .unwrap()
    }

    #[test]
    fn a_colour_sky_merges_its_terms_only_where_colour_stays_within_the_bound() {
        // The default grid (380-780 nm every 20; the terms differ at
        // 580-780 nm). A sky for colour images carries each sample's terms
        // in as few merged groups as keep sum_i s_i D_i within
        // COLOUR_BOUND (`colour_plan`); its image must stay within the
        // bound of the image of every term (the default sky, the slow
        // path): each pixel's X, Y and Z, on the measured summer file
        // (2.92 cm of water, O2-O2), a wetter column (5 cm) and earth-clear
        // with 2.9 cm, suns 30 and 5 degrees (air masses near 10 toward
        // the sun), the horizon's red band in view. One sky at the
        // effective coefficient (every term folded) errs far more, so the
        // test sees the choice.
        let grid = WavelengthGrid::new(380.0, 780.0, 20.0).unwrap();
        let observer = crate::colour::Observer::Cie1931TwoDegree;
        let mut wetter = Atmosphere::preset("earth-clear").unwrap();
        wetter.species.extend(banded_gas_species(&BandedGases::new(
            Some((5.0, 2000.0)),
            true,
        )));
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, 16, 16)
        };
        let to_xyz = SpectrumToXyz::new(&grid, observer);
        for (name, atmosphere) in [
            ("summer file", summer_file()),
            ("5 cm", wetter),
            ("earth-clear 2.9 cm", earth_clear_with_gases()),
        ] {
            let terms = k_distribution_terms(&atmosphere, &grid).unwrap();
            let plan = colour_plan(&terms, &grid, observer, 0.0).unwrap();
            let total: f64 = plan.bounds.iter().sum();
            assert!(total <= COLOUR_BOUND, "{name}: {total:e}");
            for sun in [30.0, 5.0] {
                let build = |colour: bool| {
                    let builder = Sky::builder(&atmosphere)
                        .sun_deg(sun, 180.0)
                        .wavelengths(grid)
                        .polarisation(Polarisation::Scalar);
                    colour_or_every_term(builder, colour, observer)
                };
                let (exact, colour, mut folded) = (build(false), build(true), build(false));
                assert!(colour.k_terms().len() < exact.k_terms().len(), "{name}");
                folded.k_terms.clear();
                let render = |s: &Sky| s.render_xyz(&image, &to_xyz, &|_| {}).unwrap();
                let want = render(&exact);
                let (luminance, chroma, kept) = colour_errors(&render(&colour), &want);
                let (_, _, all_folded) = colour_errors(&render(&folded), &want);
                println!(
                    "{name}, sun {sun}: {} skies; luminance max {:.2e} p99 {:.2e}, xy max {:.2e} p99 {:.2e}, XYZ {kept:.2e}; every term folded {all_folded:.2e}",
                    colour.k_terms().len(),
                    luminance.0,
                    luminance.1,
                    chroma.0,
                    chroma.1
                );
                assert!(kept < COLOUR_BOUND, "{name}, sun {sun}: {kept:e}");
                assert!(all_folded > 10.0 * COLOUR_BOUND, "{name}: {all_folded:e}");
                // Spectral images are refused (merged samples are not the
                // k-distribution's).
                assert!(colour.render_spectral(&image, &|_| {}).is_err());
            }
        }
    }

    #[test]
    #[ignore = "a measurement: the benchmark's image (scripts/bench/gases.sh), some 30 s"]
    fn the_benchmark_fisheye_of_a_colour_sky_against_every_terms() {
        // gases.sh's render case (the measured summer file, a 256 x 256
        // fisheye over 380-780 nm every 20, the default polarisation) and
        // a sun of 5 degrees: the merged colour sky's luminance and xy
        // against every term's (the default sky).
        let grid = WavelengthGrid::new(380.0, 780.0, 20.0).unwrap();
        let observer = crate::colour::Observer::Cie1931TwoDegree;
        let atmosphere = summer_file();
        let image = ImageSettings::new(Camera::Fisheye, 256, 256);
        let to_xyz = SpectrumToXyz::new(&grid, observer);
        for sun in [30.0, 5.0] {
            let build = |colour: bool| {
                let builder = Sky::builder(&atmosphere)
                    .sun_deg(sun, 180.0)
                    .wavelengths(grid);
                colour_or_every_term(builder, colour, observer)
            };
            let render = |s: &Sky| s.render_xyz(&image, &to_xyz, &|_| {}).unwrap();
            let (luminance, chroma, worst) =
                colour_errors(&render(&build(true)), &render(&build(false)));
            println!(
                "sun {sun}: luminance max {:.2e} p99 {:.2e}, xy max {:.2e} p99 {:.2e}, XYZ {worst:.2e}",
                luminance.0, luminance.1, chroma.0, chroma.1
            );
            assert!(worst < COLOUR_BOUND, "{worst:e}");
        }
    }

    #[test]
    fn strong_bands_keep_the_terms_whose_light_differs() {
        // The merge rule at the O2 A band (760 nm) and the 940 nm water
        // band, the measured summer file (2.92 cm) seen from the ground
        // (m >= 1): at 760 nm every partition into fewer than five groups
        // errs more than COLOUR_BOUND even at the whole of a colour's
        // weight (s = 1), so the terms stay; at 940 nm one group errs
        // about 0.08 (the terms are never folded), and only the terms dark
        // along every path from the top (terms 2-4: vertical depths 30 to
        // 3600) merge, within 1e-5. On the default grid 760 nm merges only
        // because its colour share is some 1e-4.
        let grid = WavelengthGrid::new(740.0, 960.0, 20.0).unwrap();
        let atmosphere = summer_file();
        let terms = k_distribution_terms(&atmosphere, &grid).unwrap();
        let depths = terms
            .iter()
            .map(|(_, t)| banded_depths_above(t, &grid, 0.0).unwrap())
            .collect::<Vec<_>>();
        let options = |nm: f64| {
            let i = ((nm - 740.0) / 20.0).round() as usize;
            let w: Vec<f64> = terms.iter().map(|(w, _)| w[i]).collect();
            let d: Vec<f64> = depths
                .iter()
                .map(|t| t.iter().map(|g| g[i]).sum())
                .collect();
            (sample_options(&w, &d, true, 1.0), d)
        };
        let (a_band, _) = options(760.0);
        for (groups, (bound, _)) in a_band.iter().enumerate().take(TERMS - 1) {
            assert!(*bound > COLOUR_BOUND, "{} groups: {bound:e}", groups + 1);
        }
        assert_eq!(a_band[TERMS - 1].0, 0.0);
        let (water, d) = options(940.0);
        assert!(water[0].0 > 50.0 * COLOUR_BOUND, "{:e}", water[0].0);
        assert!(d[2] > 25.0);
        let three = &water[2];
        assert!(three.0 < 1e-5, "{:e}", three.0);
        let members: Vec<Vec<usize>> = three.1.iter().map(|g| g.members.clone()).collect();
        assert_eq!(members, vec![vec![0], vec![1], vec![2, 3, 4]]);
        // Merging the transmitting terms 0 and 1 instead errs far more.
        assert!(water[1].0 > 50.0 * three.0, "{:e}", water[1].0);
        // An eye above the gas (m_min 0): paths with little of it, so the
        // dark terms too are told apart, and the plan still ends.
        let colour = WavelengthGrid::new(380.0, 780.0, 20.0).unwrap();
        let terms = k_distribution_terms(&atmosphere, &colour).unwrap();
        let observer = crate::colour::Observer::Cie1931TwoDegree;
        let ground = colour_plan(&terms, &colour, observer, 0.0).unwrap();
        let aloft = colour_plan(&terms, &colour, observer, 100e3).unwrap();
        let skies = |plan: &ColourPlan| plan.groups.iter().map(Vec::len).max().unwrap();
        assert!(aloft.bounds.iter().sum::<f64>() <= COLOUR_BOUND);
        assert!(skies(&aloft) >= skies(&ground), "{}", skies(&aloft));
    }

    #[test]
    fn the_effective_sky_of_a_sky_with_gases_is_never_solved() {
        // Its optics are the sky's (Sky::optics); every radiance is the
        // terms' sum, so its own field stays unbuilt.
        let atmosphere = earth_clear_with_gases();
        let sky = Sky::builder(&atmosphere)
            .sun_deg(30.0, 180.0)
            .wavelengths(WavelengthGrid::new(900.0, 1000.0, 50.0).unwrap())
            .polarisation(Polarisation::Scalar)
            .build()
            .unwrap();
        sky.radiances(&[ViewDirection::new(30.0, 0.0).unwrap()])
            .unwrap();
        sky.irradiance(Plane::HORIZONTAL).unwrap();
        assert!(sky.field.get().is_none());
        assert!(sky.k_terms().iter().all(|(_, t)| t.field.get().is_some()));
    }
}
