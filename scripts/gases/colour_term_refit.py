#!/usr/bin/env python3
"""How many k-distribution terms a colour image needs at each band sample.

A sky for colour images (`SkyBuilder::for_colour_images`, crates/sora/src/sky/
k_terms.rs) folds a band sample's 5 terms into the single effective solve where
the fold's bound s_i D_i, summed over the folded samples, stays within
COLOUR_BOUND (1e-3): D_i = sup_m |sum_j w_j exp(-m tau_j) - T_fit(m)| over air
masses m in 1e-2..1e3 (tau_j the vertical banded optical depth of term j), s_i
the sample's largest share of the colour-matching sums. This script asks the
same of a refit: the 5-term transmittance replaced by n terms (n = 1..4) with
their own weights and coefficients, fitted minimax (iteratively reweighted
least squares for the weights, coordinate descent on the log coefficients)
over the same air masses, and prints D_i and s_i D_i per sample of the default
grid (380:780:20 nm) with 2.92 cm of water and one air column of mixed gases.

It models the sampling as sora does (the band table linearly interpolated; at
each sample the banded gas that absorbs most at air mass 2 keeps the terms, the
other takes its effective coefficient, `GasBand::coefficient_of`); its
effective-solve bounds reproduce the module doc's (s D 0.11, 0.13, 3.4e-3 at
580, 600, 680 nm).

Reads only crates/sora/src/data/{gas_bands_k_terms,gas_bands_spectrl2,
cie1931_2deg_cmf_1nm}.csv. Run: python3 scripts/gases/colour_term_refit.py
(needs numpy; about a minute).
"""

import itertools
import pathlib

import numpy as np

DATA = pathlib.Path(__file__).resolve().parents[2] / "crates/sora/src/data"
WATER_CM = 2.92
MIXED_COLUMNS = 1.0
EFFECTIVE_AIR_MASS = 2.0
GRID = np.arange(380, 781, 20)
AIR_MASSES = 1e-2 * 1e5 ** (np.arange(501) / 500)


def table(name):
    lines = [l for l in (DATA / name).read_text().splitlines() if not l.startswith("#")]
    return np.array([[float(v) for v in l.split(",")] for l in lines[1:]])


def water_t(x):
    return np.exp(-0.2385 * x / (1 + 20.07 * x) ** 0.45)


def mixed_t(y):
    return np.exp(-1.41 * y / (1 + 118.3 * y) ** 0.45)


def transmittance(tau, weights):
    return np.exp(-np.outer(AIR_MASSES, tau)) @ weights


def minimax(tau, target):
    """The weights that make sum_k v_k exp(-m tau_k) nearest `target` (sup)."""
    a = np.exp(-np.outer(AIR_MASSES, tau))
    scale = np.ones(len(AIR_MASSES))
    for _ in range(12):
        v = np.linalg.lstsq(a * scale[:, None], target * scale, rcond=None)[0]
        error = np.abs(a @ v - target)
        scale *= error / error.max() + 1e-2
        scale /= scale.max()
    return np.abs(a @ v - target).max(), v


def refit(start, target):
    log_tau = np.log(start)
    best = minimax(start, target)[0]
    step = 0.5
    while step > 0.01:
        improved = False
        for k in range(len(log_tau)):
            for s in (-step, step):
                trial = log_tau.copy()
                trial[k] += s
                d = minimax(np.exp(trial), target)[0]
                if d < best:
                    best, log_tau, improved = d, trial, True
        if not improved:
            step /= 2
    return best, np.exp(log_tau), minimax(np.exp(log_tau), target)[1]


def main():
    k = table("gas_bands_k_terms.csv")
    w, c_water, c_mixed = k[:, 0], k[:, 1], k[:, 2]
    band = table("gas_bands_spectrl2.csv")
    cmf = table("cie1931_2deg_cmf_1nm.csv")
    cbar = np.array([cmf[cmf[:, 0] == nm][0, 1:4] for nm in GRID])
    cbar[0] *= 0.5
    cbar[-1] *= 0.5
    share = (cbar / cbar.sum(0)).max(1)
    rng = np.random.default_rng(1)
    print("nm  gas    s_i    s_i D_i: effective  n=1  n=2  n=3  n=4")
    for i, nm in enumerate(GRID):
        a_w = np.interp(nm, band[:, 0], band[:, 1])
        a_u = np.interp(nm, band[:, 0], band[:, 2])
        if a_w == 0 and a_u == 0:
            continue
        water = 1 - water_t(EFFECTIVE_AIR_MASS * a_w * WATER_CM)
        mixed = 1 - mixed_t(EFFECTIVE_AIR_MASS * a_u * MIXED_COLUMNS)
        if mixed > water:
            gas, tau = "mixed", c_mixed * a_u * MIXED_COLUMNS
            other = -np.log(water_t(EFFECTIVE_AIR_MASS * a_w * WATER_CM)) / EFFECTIVE_AIR_MASS
        else:
            gas, tau = "water", c_water * a_w * WATER_CM
            other = -np.log(mixed_t(EFFECTIVE_AIR_MASS * a_u * MIXED_COLUMNS)) / EFFECTIVE_AIR_MASS
        tau = tau + other
        target = transmittance(tau, w)
        at_two = np.argmin(np.abs(AIR_MASSES - EFFECTIVE_AIR_MASS))
        effective = -np.log(target[at_two]) / AIR_MASSES[at_two]
        row = [np.abs(np.exp(-AIR_MASSES * effective) - target).max()]
        for n in (1, 2, 3, 4):
            starts = [tau[list(c)] for c in itertools.combinations(range(len(w)), n)]
            starts += [
                np.sort(np.exp(rng.uniform(np.log(tau[0] / 3), np.log(tau[-1] * 3), n)))
                for _ in range(6)
            ]
            row.append(min(refit(s, target)[0] for s in starts))
        print(f"{nm} {gas} {share[i]:.3f} " + " ".join(f"{share[i] * d:.2e}" for d in row), flush=True)


if __name__ == "__main__":
    main()
