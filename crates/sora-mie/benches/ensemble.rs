//! Ensemble optics of one aerosol species at the paper's 21 wavelengths
//! (380-780 nm by 20 nm): cross-sections, albedo, g and the 406-angle Mie
//! phase table per wavelength, the work a renderer does per species. The
//! requirement is well under 100 ms per species.
//!
//! Cases: Mars dust (log-normal r_m 0.78 um, sigma_g 1.67, i.e. r_eff 1.5 um,
//! v_eff 0.3; m = 1.5 + 0.005i), the paper's Table 1 aerosol (log-normal
//! r_m 0.5 um, sigma_g 2.0, truncated to 0.1-2.5 um; m = 1.5 + 0.01i), and
//! Mars dust with the Wolff et al. (2009) tabulated index, where every
//! wavelength has its own index and so its own Mie solutions: with the
//! default phase tables interpolated between reference indices, with the
//! exact per-index tables, and with the paper's HG phase (cross-sections
//! only, which are always computed per index).
//!
//! `water_cloud_800nm`: one wavelength, a water cloud (modified gamma
//! r_eff 10 um, v_eff 0.1; m = 1.329 + 1.25e-7i, x_eff = 79) with the
//! default rule (the ripple density) and with the ripple density off (the
//! rule before it), side by side.

use criterion::{Criterion, criterion_group, criterion_main};
use sora_mie::Complex64;
use sora_mie::distribution::{RadiusQuadratureSettings, RadiusWindow, SizeDistribution};
use sora_mie::ensemble::{
    EnsembleSettings, PAPER_WAVELENGTHS_NM, SpectralPhaseMethod, compute_ensemble_optics_spectrum,
};
use sora_mie::paper_phase::AerosolPhaseMode;
use sora_mie::refractive_index::{
    MARS_DUST_WOLFF2009_CSV, RefractiveIndexModel, TabulatedRefractiveIndex,
};
use std::hint::black_box;

fn bench_species(c: &mut Criterion) {
    let mars_dust = SizeDistribution::log_normal(0.78e-6, 1.67).unwrap();
    let mars_index = RefractiveIndexModel::constant(Complex64::new(1.5, 0.005)).unwrap();
    let table1 = SizeDistribution::log_normal(0.5e-6, 2.0)
        .unwrap()
        .truncated_to(RadiusWindow::from_micrometres(0.1, 2.5).unwrap())
        .unwrap();
    let table1_index = RefractiveIndexModel::constant(Complex64::new(1.5, 0.01)).unwrap();
    let wolff = RefractiveIndexModel::Tabulated(mars_dust_wolff2009());
    let mie = EnsembleSettings::default();
    let paper_hg = EnsembleSettings {
        phase_mode: AerosolPhaseMode::PaperHenyeyGreenstein,
        ..EnsembleSettings::default()
    };

    let exact_phase = EnsembleSettings {
        spectral_phase_method: SpectralPhaseMethod::Exact,
        ..EnsembleSettings::default()
    };

    let mut group = c.benchmark_group("ensemble_21_wavelengths");
    group.sample_size(20);
    let cases = [
        ("mars_dust_mie_phase", &mars_dust, &mars_index, &mie),
        ("mars_dust_paper_hg", &mars_dust, &mars_index, &paper_hg),
        ("table1_0.1-2.5um_mie_phase", &table1, &table1_index, &mie),
        (
            "mars_dust_wolff2009_table_mie_phase",
            &mars_dust,
            &wolff,
            &mie,
        ),
        (
            "mars_dust_wolff2009_table_exact_mie_phase",
            &mars_dust,
            &wolff,
            &exact_phase,
        ),
        (
            "mars_dust_wolff2009_table_paper_hg",
            &mars_dust,
            &wolff,
            &paper_hg,
        ),
    ];
    for (name, distribution, index, settings) in cases {
        group.bench_function(name, |b| {
            b.iter(|| {
                compute_ensemble_optics_spectrum(
                    black_box(&PAPER_WAVELENGTHS_NM),
                    black_box(index),
                    black_box(distribution),
                    black_box(settings),
                )
                .unwrap()
            })
        });
    }
    group.finish();

    let cloud = SizeDistribution::modified_gamma(10e-6, 0.1).unwrap();
    let water = RefractiveIndexModel::constant(Complex64::new(1.329, 1.25e-7)).unwrap();
    let without_ripple = EnsembleSettings {
        phase_function_quadrature: RadiusQuadratureSettings {
            ripple_nodes_per_unit_size_parameter: 0.0,
            ..RadiusQuadratureSettings::phase_function()
        },
        ..EnsembleSettings::default()
    };
    let mut group = c.benchmark_group("water_cloud_800nm");
    group.sample_size(10);
    for (name, settings) in [
        ("ripple_density", &mie),
        ("without_ripple_density", &without_ripple),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                compute_ensemble_optics_spectrum(
                    black_box(&[800.0]),
                    black_box(&water),
                    black_box(&cloud),
                    black_box(settings),
                )
                .unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_species);
criterion_main!(benches);

#[path = "../tests/support/mars_dust.rs"]
mod mars_dust;

/// The built-in Wolff et al. (2009) Mars dust table.
fn mars_dust_wolff2009() -> TabulatedRefractiveIndex {
    let (wavelength_nm, n, k) = mars_dust::wavelength_nm_n_k(MARS_DUST_WOLFF2009_CSV);
    TabulatedRefractiveIndex::from_columns(wavelength_nm, n, k).unwrap()
}
