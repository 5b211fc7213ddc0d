//! The O2 A band's k-terms from line data (750-780 nm).
//!
//! `data/o2_a_band_k_terms.csv` (written by
//! `scripts/gases/make_lbl_reference.py` from HITRAN 2016 O2 lines through
//! the U.S. Standard Atmosphere 1976) holds, for each 0.5 nm bin of
//! 750-780 nm, the coefficients k_bj (per sea-level air column) of the
//! shared weights w_j ([`super::gas_bands::k_terms`]) fitted to the bin's
//! line-by-line column transmittance T(M) = sum_j w_j exp(-k_bj M), M = 1-20
//! air columns. A grid sample stands for its band, [lambda - step/2,
//! lambda + step/2] (as the sun's band means do): the bins it overlaps give
//! the pieces (w_j times the bin's share of the band, k_bj), the part of the
//! band outside 750-780 nm a piece of k = 0 (O2 does not absorb there), and
//! the pieces are ranked by k into the shared weights' g-intervals (the
//! correlated-k re-sort within a band; [`ranked_terms`]: term j's
//! coefficient keeps its interval's transmittance at [`RANKING_AIR_MASS`]).
//! From there the five coefficients are refitted ([`band_terms`]) to the
//! pieces' T(M) over M = 1-20 (Levenberg-Marquardt in log k, error in units
//! of max(1 - T, 1e-3)), since one air mass per interval does not keep a
//! wide band's curve of growth: over air masses 1-20, against the pieces'
//! own T(M), the ranking alone errs by 7.5-8.1 % of 1 - T for the 10 nm
//! bands 755-765, 760-770 and 765-775 nm, the refit by 5.1, 2.3 and 1.3 %
//! (shared weights cannot do much better: the script's least-squares fit
//! of a 10 nm band with them errs 1.5-4.8 %), and for 750-770 nm (a 20 nm
//! grid's sample at 760 nm) 30 % and 19 % (tested). A 1 nm grid's samples
//! are within 0.8 % of the line-by-line band means of 1 - T
//! (`tests/gas_line_by_line.rs`).

use super::gas_bands::{TERMS, k_terms};
use crate::linear_algebra::{cholesky, cholesky_solve};
use crate::spectrum::WavelengthGrid;
use crate::table::NumericTable;

const K_TERMS_CSV: &str = include_str!("../data/o2_a_band_k_terms.csv");

/// The wavelengths the line-derived k-terms cover, nm: a sample inside takes
/// its O2 from them, not from the band model.
pub const A_BAND_RANGE_NM: (f64, f64) = (750.0, 780.0);

/// The air mass at which the ranking keeps each g-interval's transmittance.
pub const RANKING_AIR_MASS: f64 = 2.0;

/// The air masses of the refit: 12 log-spaced over 1-20.
fn refit_air_masses() -> [f64; 12] {
    std::array::from_fn(|i| 20f64.powf(i as f64 / 11.0))
}

/// One bin: its wavelengths, nm, and k_bj per air column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ABandBin {
    /// Lower edge, nm.
    pub lo_nm: f64,
    /// Upper edge, nm.
    pub hi_nm: f64,
    /// k_bj per sea-level air column, one per shared weight.
    pub k: [f64; TERMS],
}

/// The embedded bins (parsed once).
pub fn a_band_bins() -> &'static [ABandBin] {
    static PARSED: std::sync::LazyLock<Vec<ABandBin>> = std::sync::LazyLock::new(|| {
        let table = NumericTable::parse(K_TERMS_CSV, "embedded O2 A band k-terms")
            .expect("the embedded O2 A band k-terms are valid");
        let bins: Vec<ABandBin> = table
            .rows
            .iter()
            .map(|row| ABandBin {
                lo_nm: row[0],
                hi_nm: row[1],
                k: std::array::from_fn(|j| row[2 + j]),
            })
            .collect();
        assert_eq!(bins.first().map(|b| b.lo_nm), Some(A_BAND_RANGE_NM.0));
        assert_eq!(bins.last().map(|b| b.hi_nm), Some(A_BAND_RANGE_NM.1));
        assert!(bins.windows(2).all(|p| p[0].hi_nm == p[1].lo_nm));
        bins
    });
    &PARSED
}

/// The band [lo_nm, hi_nm]'s pieces: (weight, k per air column), weights
/// summing to 1 (the part outside the bins a piece of k = 0).
pub fn pieces(lo_nm: f64, hi_nm: f64) -> Vec<(f64, f64)> {
    let width = hi_nm - lo_nm;
    assert!(width > 0.0, "an empty band {lo_nm}-{hi_nm} nm");
    let weights: Vec<f64> = k_terms().iter().map(|t| t.weight).collect();
    let mut out = Vec::new();
    let mut covered = 0.0;
    for bin in a_band_bins() {
        let overlap = hi_nm.min(bin.hi_nm) - lo_nm.max(bin.lo_nm);
        if overlap > 0.0 {
            covered += overlap;
            for (w, k) in weights.iter().zip(bin.k) {
                out.push((w * overlap / width, k));
            }
        }
    }
    if covered < width {
        out.push(((width - covered) / width, 0.0));
    }
    out
}

/// The pieces' transmittance for `air_mass` air columns.
pub fn pieces_transmittance(pieces: &[(f64, f64)], air_mass: f64) -> f64 {
    pieces.iter().map(|(w, k)| w * (-k * air_mass).exp()).sum()
}

/// The shared weights' transmittance with coefficients `k`.
pub fn terms_transmittance(k: &[f64; TERMS], air_mass: f64) -> f64 {
    k_terms()
        .iter()
        .zip(k)
        .map(|(t, k)| t.weight * (-k * air_mass).exp())
        .sum()
}

/// The correlated-k re-sort: `pieces` ranked by k, term j's g-interval (of
/// width w_j) taking the pieces (or parts of them) that fall in it, its
/// coefficient the one that keeps their transmittance at
/// [`RANKING_AIR_MASS`].
pub fn ranked_terms(pieces: &[(f64, f64)]) -> [f64; TERMS] {
    let mut sorted = pieces.to_vec();
    sorted.sort_by(|a, b| a.1.total_cmp(&b.1));
    let m = RANKING_AIR_MASS;
    let mut out = [0.0; TERMS];
    let (mut g_lo, mut piece, mut used) = (0.0, 0, 0.0);
    for (j, term) in k_terms().iter().enumerate() {
        let g_hi = if j + 1 == TERMS {
            f64::INFINITY
        } else {
            g_lo + term.weight
        };
        // sum of weight exp(-(k - k_min) m) over the interval, k_min its
        // smallest k (no underflow for strong lines).
        let (mut width, mut sum, mut k_min) = (0.0, 0.0, f64::NAN);
        let mut g = g_lo;
        while piece < sorted.len() && g < g_hi {
            let (w, k) = sorted[piece];
            let take = (w - used).min(g_hi - g);
            if k_min.is_nan() {
                k_min = k;
            }
            width += take;
            sum += take * (-(k - k_min) * m).exp();
            g += take;
            used += take;
            if used >= w * (1.0 - 1e-12) {
                piece += 1;
                used = 0.0;
            }
        }
        out[j] = if width > 0.0 {
            k_min - (sum / width).ln() / m
        } else {
            // Rounding left this interval empty: the strongest piece.
            sorted.last().map_or(0.0, |p| p.1)
        };
        g_lo = g_hi;
    }
    out
}

/// The k-terms of the band [lo_nm, hi_nm]: [`ranked_terms`] refitted to the
/// pieces' T(M), M = 1-20 (see the module docs).
pub fn band_terms(lo_nm: f64, hi_nm: f64) -> [f64; TERMS] {
    let pieces = pieces(lo_nm, hi_nm);
    let start = ranked_terms(&pieces);
    refit(&pieces, start)
}

/// Levenberg-Marquardt in p_j = ln k_j of r_i = (T_k(M_i) - T_pieces(M_i)) /
/// max(1 - T_pieces(M_i), 1e-3), with the analytic Jacobian. Not the
/// retrieval's (`inversion::fit`): that one carries an a priori, takes its
/// Jacobian by finite differences and stops where a step is small against
/// the measurements' noise; this one is a plain least squares run until no
/// step lowers the cost.
fn refit(pieces: &[(f64, f64)], start: [f64; TERMS]) -> [f64; TERMS] {
    // k beyond these absorbs nothing / everything at M = 1-20.
    const FLOOR: f64 = 1e-12;
    const CEILING: f64 = 1e6;
    let air_masses = refit_air_masses();
    let target: Vec<f64> = air_masses
        .iter()
        .map(|m| pieces_transmittance(pieces, *m))
        .collect();
    if target.iter().all(|t| 1.0 - t < 1e-9) {
        return start;
    }
    let scale: Vec<f64> = target.iter().map(|t| (1.0 - t).max(1e-3)).collect();
    let weights: Vec<f64> = k_terms().iter().map(|t| t.weight).collect();
    let residuals = |p: &[f64; TERMS]| -> Vec<f64> {
        let k = p.map(f64::exp);
        air_masses
            .iter()
            .zip(&target)
            .zip(&scale)
            .map(|((m, t), s)| (terms_transmittance(&k, *m) - t) / s)
            .collect()
    };
    let cost = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    let mut p = start.map(|k| k.clamp(FLOOR, CEILING).ln());
    let mut r = residuals(&p);
    let mut current = cost(&r);
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let k = p.map(f64::exp);
        // J_ij = -w_j k_j M_i exp(-k_j M_i) / s_i
        let jac: Vec<[f64; TERMS]> = air_masses
            .iter()
            .zip(&scale)
            .map(|(m, s)| std::array::from_fn(|j| -weights[j] * k[j] * m * (-k[j] * m).exp() / s))
            .collect();
        let mut jtj = [[0.0; TERMS]; TERMS];
        let mut jtr = [0.0; TERMS];
        for (row, ri) in jac.iter().zip(&r) {
            for a in 0..TERMS {
                jtr[a] += row[a] * ri;
                for b in 0..TERMS {
                    jtj[a][b] += row[a] * row[b];
                }
            }
        }
        let mut improved = false;
        while lambda < 1e12 {
            let mut system = jtj;
            for (a, row) in system.iter_mut().enumerate() {
                row[a] += lambda * jtj[a][a].max(1e-30);
            }
            let Some(step) = solve(system, jtr.map(|x| -x)) else {
                lambda *= 10.0;
                continue;
            };
            let trial: [f64; TERMS] = std::array::from_fn(|j| {
                (p[j] + step[j].clamp(-2.0, 2.0)).clamp(FLOOR.ln(), CEILING.ln())
            });
            let r_trial = residuals(&trial);
            let c = cost(&r_trial);
            if c < current {
                let gain = current - c;
                (p, r, current) = (trial, r_trial, c);
                lambda = (lambda / 3.0).max(1e-12);
                improved = gain > 1e-14 * current.max(1e-30);
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    let mut k = p.map(f64::exp);
    k.sort_by(f64::total_cmp);
    k
}

/// Solves the damped normal equations `a x = b` (symmetric positive
/// definite; [`crate::linear_algebra`], as the retrieval's steps are);
/// `None` if `a` is not positive definite.
fn solve(a: [[f64; TERMS]; TERMS], b: [f64; TERMS]) -> Option<[f64; TERMS]> {
    let l = cholesky(a.as_flattened(), TERMS)?;
    let x = cholesky_solve(&l, TERMS, &b);
    Some(std::array::from_fn(|j| x[j]))
}

/// Each sample of `grid`: its band's k-terms per air column when the sample
/// lies in [`A_BAND_RANGE_NM`], else `None` (the band model's O2 holds).
pub fn terms_on(grid: &WavelengthGrid) -> Vec<Option<[f64; TERMS]>> {
    let half = 0.5 * grid.step_nm();
    grid.wavelengths_nm()
        .map(|w| {
            (A_BAND_RANGE_NM.0..=A_BAND_RANGE_NM.1)
                .contains(&w)
                .then(|| band_terms(w - half, w + half))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn worst_error(k: &[f64; TERMS], pieces: &[(f64, f64)]) -> f64 {
        refit_air_masses()
            .iter()
            .chain(&[1.15467, 3.85948])
            .map(|m| {
                let want = pieces_transmittance(pieces, *m);
                (terms_transmittance(k, *m) - want).abs() / (1.0 - want).max(1e-3)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn one_bin_is_its_own_terms() {
        // A band that is one bin: each g-interval holds one piece, so the
        // ranking and the refit return the bin's k exactly.
        let bin = a_band_bins()[25];
        let terms = band_terms(bin.lo_nm, bin.hi_nm);
        for (got, want) in terms.iter().zip(bin.k) {
            assert!((got / want - 1.0).abs() < 1e-9, "{got} {want}");
        }
    }

    #[test]
    fn the_refit_keeps_wide_bands_closer_than_the_ranking() {
        // The fast path (five terms) against the slow one (every piece's
        // exponential), for 10 and 20 nm bands, air masses 1-20; measured:
        // the refit errs 5.1, 2.3 and 1.3 % of 1 - T (755-765, 760-770,
        // 765-775 nm; the ranking 7.5-8.1 %), and 19 % for 750-770 nm (the
        // ranking 30 %): five shared weights hold a 20 nm band poorly.
        for (lo, hi) in [
            (755.0, 765.0),
            (760.0, 770.0),
            (765.0, 775.0),
            (750.0, 770.0),
        ] {
            let pieces = pieces(lo, hi);
            let ranked = worst_error(&ranked_terms(&pieces), &pieces);
            let refitted = worst_error(&band_terms(lo, hi), &pieces);
            assert!(refitted < ranked, "{lo}-{hi}: {refitted} {ranked}");
            println!("{lo}-{hi} nm: refit {refitted:.4}, ranking {ranked:.4}");
            if hi - lo <= 10.0 {
                assert!(refitted < 0.055, "{lo}-{hi}: {refitted}");
            }
        }
    }

    #[test]
    fn outside_the_lines_nothing_absorbs() {
        let pieces = pieces(740.0, 750.0);
        assert_eq!(pieces, vec![(1.0, 0.0)]);
        let grid = WavelengthGrid::new(700.0, 800.0, 10.0).unwrap();
        let terms = terms_on(&grid);
        let inside: Vec<f64> = grid
            .wavelengths_nm()
            .zip(&terms)
            .filter_map(|(w, t)| t.map(|_| w))
            .collect();
        assert_eq!(inside, vec![750.0, 760.0, 770.0, 780.0]);
        // The band 755-765 nm absorbs most at 760 nm.
        let t760 = terms_transmittance(&terms[6].unwrap(), 1.0);
        let t770 = terms_transmittance(&terms[7].unwrap(), 1.0);
        assert!(t760 < 0.75 && t770 > 0.85, "{t760} {t770}");
    }
}
