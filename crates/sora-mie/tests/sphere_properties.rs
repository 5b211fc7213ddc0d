//! Properties every solution must have, over the whole supported domain
//! (proptest): x log-uniform over 1e-6 ..= 2e4 (weighted toward x < 1e3,
//! where most of the structure is, with fixed cases at 2e4), Re(m) over
//! 0.75 ..= 10 with the hard values 0.75 and 1.0001 drawn often, Im(m) = 0 or
//! log-uniform over 1e-8 ..= 10. And: invalid or arbitrary inputs never
//! panic; they give an error or a finite answer.

use proptest::prelude::*;
use sora_mie::Complex64;
use sora_mie::sphere::{
    Efficiencies, MAX_INTERIOR_SIZE_PARAMETER, MAX_SIZE_PARAMETER, MieError, MieSolution,
    REFRACTIVE_INDEX_MODULUS_RANGE, SphereWorkspace, compute_efficiencies,
    compute_efficiencies_perfect_conductor, compute_efficiencies_with,
};

fn size_parameter() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => (-6.0f64..3.0).prop_map(|e| 10f64.powf(e)),
        1 => (3.0f64..4.302).prop_map(|e| 10f64.powf(e)),
    ]
}

fn refractive_index() -> impl Strategy<Value = Complex64> {
    let real = prop_oneof![
        1 => Just(1.0001),
        1 => Just(0.75),
        4 => (0.75f64.log10()..1.0).prop_map(|e| 10f64.powf(e)),
    ];
    let imaginary = prop_oneof![
        1 => Just(0.0),
        2 => (-8.0f64..1.0).prop_map(|e| 10f64.powf(e)),
    ];
    (real, imaginary).prop_map(|(re, im)| Complex64::new(re, im))
}

/// The checks of one (m, x); returns a description of the first failure.
fn check_sphere(m: Complex64, x: f64) -> Result<(), String> {
    let q = compute_efficiencies(m, x).map_err(|e| e.to_string())?;
    let Efficiencies {
        qext,
        qsca,
        qabs,
        qback,
        g,
    } = q;
    let context = format!("m = {m}, x = {x}: {q:?}");
    for value in [qext, qsca, qabs, qback, g] {
        if !value.is_finite() {
            return Err(format!("non-finite value, {context}"));
        }
    }
    if !(qext >= 0.0 && qsca >= 0.0 && qabs >= 0.0 && qback >= 0.0) {
        return Err(format!("negative efficiency, {context}"));
    }
    if g.abs() > 1.0 {
        return Err(format!("|g| > 1, {context}"));
    }
    if qsca > qext * (1.0 + 1e-12) {
        return Err(format!("Q_sca > Q_ext, {context}"));
    }
    if (qext - (qsca + qabs)).abs() > 1e-12 * qext {
        return Err(format!("Q_ext != Q_sca + Q_abs, {context}"));
    }
    if (m.im == 0.0) != (qabs == 0.0) {
        return Err(format!(
            "Q_abs must vanish exactly when Im(m) = 0, {context}"
        ));
    }
    // Same numbers through the workspace and the full solution.
    let mut workspace = SphereWorkspace::new();
    if compute_efficiencies_with(&mut workspace, m, x).unwrap() != q {
        return Err(format!("workspace path differs, {context}"));
    }
    let solution = MieSolution::compute(m, x).unwrap();
    if solution.efficiencies() != q {
        return Err(format!("MieSolution differs, {context}"));
    }
    // Optical theorem, independent of how Q_ext was summed:
    // Q_ext = (4/x^2) Re S(0), S(0) = sum (2n+1)/2 (a_n + b_n). The
    // tolerance is the rounding of that sum, ~1e-16 n sum |terms|.
    let (s1, s2) = solution.amplitudes(1.0);
    let (a, b) = solution.coefficients();
    let magnitude: f64 = a
        .iter()
        .zip(b)
        .enumerate()
        .map(|(i, (a, b))| (2 * i + 3) as f64 / 2.0 * (a + b).norm())
        .sum();
    let rounding = 1e-16 * (a.len() as f64 + 10.0) * 4.0 / (x * x) * magnitude;
    if (4.0 / (x * x) * s1.re - qext).abs() > 1e-13 * qext + 10.0 * rounding {
        return Err(format!(
            "optical theorem: 4 Re S(0)/x^2 = {}, {context}",
            4.0 / (x * x) * s1.re
        ));
    }
    if (s1 - s2).norm() > 1e-12 * s1.norm() {
        return Err(format!("S1(0) != S2(0), {context}"));
    }
    // Mueller-matrix bound S11 >= |S12| and a non-negative phase function at
    // a few angles.
    let mu = [1.0, 0.7, 0.1, -0.4, -1.0];
    let (mut s11, mut s12, mut phase) = ([0.0; 5], [0.0; 5], [0.0; 5]);
    solution.s11_s12_table(&mu, &mut s11, &mut s12);
    solution.phase_function_table(&mu, &mut phase);
    for k in 0..5 {
        if !(s11[k].is_finite()
            && phase[k].is_finite()
            && phase[k] >= 0.0
            && s12[k].abs() <= s11[k] * (1.0 + 1e-12))
        {
            return Err(format!(
                "angular functions at mu = {}: S11 {} S12 {} p {}, {context}",
                mu[k], s11[k], s12[k], phase[k]
            ));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn efficiencies_are_physical_over_the_domain(m in refractive_index(), x in size_parameter()) {
        if let Err(message) = check_sphere(m, x) {
            prop_assert!(false, "{}", message);
        }
    }

    /// Perfect conductors: lossless, physical, and with the conductor's
    /// limits at both ends of the size range.
    #[test]
    fn perfect_conductors_are_physical(x in size_parameter()) {
        let q = compute_efficiencies_perfect_conductor(x).unwrap();
        for value in [q.qext, q.qsca, q.qback, q.g] {
            prop_assert!(value.is_finite(), "x = {}: {:?}", x, q);
        }
        prop_assert!(q.qsca > 0.0 && q.qback >= 0.0 && q.g.abs() <= 1.0, "x = {}: {:?}", x, q);
        prop_assert!(q.qabs == 0.0 && q.qext == q.qsca);
    }

    /// Any finite or non-finite input: an error exactly when it is outside
    /// the documented domain, otherwise finite non-negative efficiencies.
    /// Never a panic.
    #[test]
    fn arbitrary_inputs_never_panic(
        m_re in prop_oneof![Just(0.0), Just(-1.0), Just(f64::NAN), Just(f64::INFINITY), (-7.0f64..7.0).prop_map(|e| 10f64.powf(e))],
        m_im in prop_oneof![Just(0.0), Just(-1e-3), Just(f64::NAN), (-12.0f64..7.0).prop_map(|e| 10f64.powf(e))],
        x in prop_oneof![Just(0.0), Just(-1.0), Just(f64::NAN), Just(f64::INFINITY), Just(f64::MIN_POSITIVE), (-300.0f64..7.0).prop_map(|e| 10f64.powf(e))],
    ) {
        let m = Complex64::new(m_re, m_im);
        let modulus = m.norm();
        let m_valid = m_re > 0.0 && m_im >= 0.0 && m.re.is_finite() && m.im.is_finite() && REFRACTIVE_INDEX_MODULUS_RANGE.contains(&modulus);
        let x_valid = x > 0.0 && x <= MAX_SIZE_PARAMETER && modulus * x <= MAX_INTERIOR_SIZE_PARAMETER;
        // Keep the valid runs cheap: huge |m| x costs time, not correctness.
        prop_assume!(!(m_valid && x_valid) || modulus * x <= 1e5);
        match compute_efficiencies(m, x) {
            Err(MieError::InvalidRefractiveIndex(_)) => prop_assert!(!m_valid),
            Err(MieError::InvalidSizeParameter(_)) => prop_assert!(m_valid && !x_valid),
            Ok(q) => {
                prop_assert!(m_valid && x_valid);
                for value in [q.qext, q.qsca, q.qabs, q.qback, q.g] {
                    prop_assert!(value.is_finite(), "m = {}, x = {}: {:?}", m, x, q);
                }
                prop_assert!(q.qext >= 0.0 && q.qsca >= 0.0 && q.qabs >= 0.0 && q.qback >= 0.0 && q.g.abs() <= 1.0, "m = {}, x = {}: {:?}", m, x, q);
            }
        }
    }
}

/// The top of the supported range, for indices spanning the domain.
#[test]
fn largest_supported_spheres_are_physical() {
    for m in [
        Complex64::new(10.0, 10.0),
        Complex64::new(0.75, 0.0),
        Complex64::new(1.0001, 0.0),
        Complex64::new(1.33, 1e-8),
        Complex64::new(1.5, 0.01),
        Complex64::new(2.5, 1.5),
        Complex64::new(10.0, 0.0),
    ] {
        check_sphere(m, 2e4).unwrap();
    }
}

/// The smallest supported spheres, and far below.
#[test]
fn smallest_spheres_are_physical() {
    for m in [
        Complex64::new(1.0001, 0.0),
        Complex64::new(0.75, 0.0),
        Complex64::new(10.0, 10.0),
        Complex64::new(1.33, 1e-8),
    ] {
        for x in [1e-6, 1e-12, 1e-100, 1e-300] {
            check_sphere(m, x).unwrap();
        }
    }
}
