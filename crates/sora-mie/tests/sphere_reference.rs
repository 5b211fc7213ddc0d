//! The sphere solver against reference values computed in 100-digit
//! arithmetic (scattnlay 2.4, audited with mpmath; see
//! `shared/reference/mie/README.md`), copied into `tests/data/` with their
//! provenance on the first line, and against limits that theory fixes.

use sora_mie::Complex64;
use sora_mie::sphere::{
    MieSolution, SphereWorkspace, compute_efficiencies, compute_efficiencies_perfect_conductor,
    compute_efficiencies_with,
};

/// Rows of a reference CSV: header names and string fields, '#' lines skipped.
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    fn load(text: &str) -> Table {
        let mut lines = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
        let header = split_csv(lines.next().expect("header"));
        let rows = lines.map(split_csv).collect();
        Table { header, rows }
    }
    fn column(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    }
}

/// Split one CSV line, honouring double quotes (the published cases quote
/// labels containing commas).
fn split_csv(line: &str) -> Vec<String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    fields.push(field);
    fields
}

fn number(field: &str) -> f64 {
    field
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("not a number: {field:?}"))
}

fn relative_error(value: f64, reference: f64) -> f64 {
    if reference == 0.0 {
        value.abs()
    } else {
        (value - reference).abs() / reference.abs()
    }
}

const EFFICIENCIES: &str = include_str!("data/efficiencies.csv");
const PHASE: &str = include_str!("data/phase.csv");
const PUBLISHED: &str = include_str!("data/published_test_cases.csv");

#[test]
fn data_files_state_their_provenance() {
    for text in [EFFICIENCIES, PHASE, PUBLISHED] {
        assert!(
            text.starts_with("# source: "),
            "first line must give the source"
        );
    }
}

/// Every row of efficiencies.csv (6 indices x 15 size parameters 1e-4..1e4):
/// Q_ext, Q_sca, Q_abs and g within 1e-9 relative, Q_back within 1e-8, Q_abs
/// exactly 0 for a real index.
#[test]
fn efficiencies_match_the_100_digit_reference_at_every_row() {
    let table = Table::load(EFFICIENCIES);
    let col = |name| table.column(name);
    let (c_mre, c_mim, c_x) = (col("m_re"), col("m_im"), col("x"));
    let names = ["qext", "qsca", "qabs", "qback", "g"];
    let columns: Vec<usize> = names.iter().map(|n| col(n)).collect();
    let tolerances = [1e-9, 1e-9, 1e-9, 1e-8, 1e-9];
    let mut worst: [(f64, String); 5] = Default::default();
    let mut workspace = SphereWorkspace::new();
    assert_eq!(table.rows.len(), 90);
    for row in &table.rows {
        let m = Complex64::new(number(&row[c_mre]), number(&row[c_mim]));
        let x = number(&row[c_x]);
        let q = compute_efficiencies(m, x).unwrap();
        // The workspace entry point is the same computation.
        assert_eq!(compute_efficiencies_with(&mut workspace, m, x).unwrap(), q);
        let values = [q.qext, q.qsca, q.qabs, q.qback, q.g];
        for k in 0..5 {
            let reference = number(&row[columns[k]]);
            if names[k] == "qabs" && m.im == 0.0 {
                assert_eq!(reference, 0.0);
                assert!(
                    values[k] == 0.0 && values[k].is_sign_positive(),
                    "qabs of a real index must be +0"
                );
                continue;
            }
            let error = relative_error(values[k], reference);
            if error > worst[k].0 {
                worst[k] = (error, format!("m = {m}, x = {x}"));
            }
            assert!(
                error <= tolerances[k],
                "{} at m = {m}, x = {x}: {} vs reference {reference} (relative error {error:e})",
                names[k],
                values[k]
            );
        }
    }
    for k in 0..5 {
        eprintln!(
            "efficiencies.csv worst {}: {:.2e} at {}",
            names[k], worst[k].0, worst[k].1
        );
    }
}

/// phase.csv: S1, S2, S11, S12, the normalised phase function and the degree
/// of linear polarisation at every degree for three spheres, within 1e-7.
///
/// S1, S2 are compared as complex numbers (|S - S_ref| / |S_ref|), so their
/// real and imaginary parts crossing zero do not matter. S12 and -S12/S11
/// cross zero at some angles; being (|S2|^2 - |S1|^2)/2, their rounding and
/// truncation errors scale with S11, not with S12, so their error is measured
/// relative to S11 (an absolute 1e-7 on the degree of polarisation, which is
/// what a polarimeter reading needs).
#[test]
fn phase_matrix_matches_the_100_digit_reference_at_every_angle() {
    let table = Table::load(PHASE);
    let col = |name| table.column(name);
    let mut worst = [0.0f64; 6];
    let mut current: Option<(f64, f64, f64, MieSolution)> = None;
    for row in &table.rows {
        let (m_re, m_im, x) = (
            number(&row[col("m_re")]),
            number(&row[col("m_im")]),
            number(&row[col("x")]),
        );
        if current
            .as_ref()
            .is_none_or(|c| (c.0, c.1, c.2) != (m_re, m_im, x))
        {
            let solution = MieSolution::compute(Complex64::new(m_re, m_im), x).unwrap();
            let q = solution.efficiencies();
            assert!(relative_error(q.qsca, number(&row[col("Qsca")])) < 1e-9);
            assert!(relative_error(q.qext, number(&row[col("Qext")])) < 1e-9);
            current = Some((m_re, m_im, x, solution));
        }
        let solution = &current.as_ref().unwrap().3;
        let theta = number(&row[col("theta_deg")]);
        let mu = theta.to_radians().cos();
        let (s1, s2) = solution.amplitudes(mu);
        let s1_ref = Complex64::new(number(&row[col("S1_re")]), number(&row[col("S1_im")]));
        let s2_ref = Complex64::new(number(&row[col("S2_re")]), number(&row[col("S2_im")]));
        let (s11, s12) = solution.s11_s12(mu);
        let s11_ref = number(&row[col("S11")]);
        let s12_ref = number(&row[col("S12")]);
        let p_ref = number(&row[col("p_4pi_norm1")]);
        let dolp_ref = number(&row[col("dolp")]);
        let errors = [
            (s1 - s1_ref).norm() / s1_ref.norm(),
            (s2 - s2_ref).norm() / s2_ref.norm(),
            relative_error(s11, s11_ref),
            (s12 - s12_ref).abs() / s11_ref,
            relative_error(solution.phase_function_per_sr(mu), p_ref),
            (-s12 / s11 - dolp_ref).abs(),
        ];
        for (k, &e) in errors.iter().enumerate() {
            worst[k] = worst[k].max(e);
            assert!(
                e <= 1e-7,
                "quantity {k} at m = {m_re}+{m_im}i, x = {x}, theta = {theta}: error {e:e}"
            );
        }
    }
    eprintln!("phase.csv worst (S1, S2, S11, S12/S11, p, dolp): {worst:?}");
}

/// The table entry points give the same numbers as the single-angle ones.
#[test]
fn phase_tables_agree_with_single_angles() {
    let solution = MieSolution::compute(Complex64::new(1.55, 0.001), 100.0).unwrap();
    let mu: Vec<f64> = (0..=180).map(|d| (d as f64).to_radians().cos()).collect();
    let (mut s11, mut s12, mut p) = (
        vec![0.0; mu.len()],
        vec![0.0; mu.len()],
        vec![0.0; mu.len()],
    );
    solution.s11_s12_table(&mu, &mut s11, &mut s12);
    solution.phase_function_table(&mu, &mut p);
    for (i, &m) in mu.iter().enumerate() {
        let (v11, v12) = solution.s11_s12(m);
        assert!((s11[i] - v11).abs() <= 1e-14 * v11);
        assert!((s12[i] - v12).abs() <= 1e-14 * v11);
        assert!((p[i] - solution.phase_function_per_sr(m)).abs() <= 1e-14 * p[i]);
    }
}

/// The published values of miepython's test suite (Wiscombe's MIEV0 cases,
/// the B&H BHMIE example, scattnlay), each row beside its 100-digit value
/// (`ref_value`). Every plain-sphere row whose reference lies within the
/// published tolerance must agree with `ref_value`: 1e-9 relative for
/// Q_ext, Q_sca and g, 1e-8 for Q_back. Amplitude components and the
/// normalised phase-matrix ratios (S11/S11(0), -S12/S11, S33/S11, S34/S11)
/// are held to 1e-9 of their natural scale: |S| for a component of S1 or S2
/// (a component can cross zero), 1 for a ratio to S11.
///
/// The S1, S2 components in this file come from MIEV0 printouts, and
/// MIEV0 (like miepython) uses the time dependence exp(+i w t) with
/// m = n - i k: its amplitudes are the complex conjugates of Bohren &
/// Huffman's (the file's m_re_bh, m_im_bh columns convert m, not S). They are
/// compared with conj(S1), conj(S2); everything else (efficiencies, S11, S12,
/// S33 = Re(S2 S1*), S34 = Im(S2 S1*), from the B&H printout) is the same in
/// both conventions or already in B&H's.
///
/// The perfectly conducting spheres (m_as_written = "PEC") are checked
/// against [`compute_efficiencies_perfect_conductor`] with the same
/// tolerances.
#[test]
fn published_test_cases_match_their_100_digit_values() {
    let table = Table::load(PUBLISHED);
    let col = |name| table.column(name);
    let (c_m, c_mre, c_mim, c_x) = (
        col("m_as_written"),
        col("m_re_bh"),
        col("m_im_bh"),
        col("x"),
    );
    let (c_quantity, c_ref, c_within) = (
        col("quantity"),
        col("ref_value"),
        col("ref_within_test_tolerance"),
    );
    let mut checked = 0;
    let mut conductors = 0;
    let mut worst = 0.0f64;
    for row in &table.rows {
        if row[c_within].trim() != "1" {
            continue;
        }
        if row[c_m].trim() == "PEC" {
            let x = number(&row[c_x]);
            let reference = number(&row[c_ref]);
            let q = compute_efficiencies_perfect_conductor(x).unwrap();
            let quantity = row[c_quantity].trim();
            let value = match quantity {
                "qext" => q.qext,
                "qsca" => q.qsca,
                "g" => q.g,
                _ => panic!("unknown conductor quantity {quantity:?}"),
            };
            let error = relative_error(value, reference);
            worst = worst.max(error / 1e-9);
            assert!(
                error <= 1e-9,
                "conductor {quantity} at x = {x}: {value} vs {reference} ({error:e})"
            );
            conductors += 1;
            continue;
        }
        let m = Complex64::new(number(&row[c_mre]), number(&row[c_mim]));
        let x = number(&row[c_x]);
        let quantity = row[c_quantity].trim();
        let reference = number(&row[c_ref]);
        let solution = MieSolution::compute(m, x).unwrap();
        let q = solution.efficiencies();
        assert_eq!(q, compute_efficiencies(m, x).unwrap());
        // "S1_re(180deg)" -> ("S1_re", 180)
        let angle = |q: &str| -> f64 {
            let inside = &q[q.rfind('(').unwrap() + 1..q.rfind("deg)").unwrap()];
            number(inside)
        };
        let (value, scale, tolerance) = match quantity {
            "qext" => (q.qext, reference, 1e-9),
            "qsca" => (q.qsca, reference, 1e-9),
            "g" => (q.g, reference, 1e-9),
            "qback" | "qback=|2*S1(180)/x|^2" | "qback=4*|S1(180)|^2/x^2" => {
                let (s1, _) = solution.amplitudes(-1.0);
                // Both forms of the published value are the same number
                // (pi_n(-1) = -tau_n(-1) = (-1)^(n+1) n(n+1)/2), summed in a
                // different order: they differ by rounding of a cancelling
                // sum, ~1e-14 per term.
                let from_amplitude = 4.0 * s1.norm_sqr() / (x * x);
                let agreement = relative_error(from_amplitude, q.qback);
                let rounding = 1e-14 * solution.n_terms() as f64;
                assert!(
                    agreement < rounding,
                    "m = {m}, x = {x}: 4|S1(180)|^2/x^2 vs Q_back: {agreement:e}"
                );
                (q.qback, reference, 1e-8)
            }
            _ if quantity.starts_with("S1_") || quantity.starts_with("S2_") => {
                let mu = angle(quantity).to_radians().cos();
                let (s1, s2) = solution.amplitudes(mu);
                assert!(
                    row[col("case_label")].contains("MIEV0"),
                    "amplitude convention of {quantity}"
                );
                let s = if quantity.starts_with("S1_") {
                    s1.conj()
                } else {
                    s2.conj()
                };
                let part = if quantity[3..].starts_with("re") {
                    s.re
                } else {
                    s.im
                };
                (part, s.norm(), 1e-9)
            }
            _ => {
                let mu = angle(quantity).to_radians().cos();
                let (s1, s2) = solution.amplitudes(mu);
                let (s11, s12) = solution.s11_s12(mu);
                let value = if quantity.starts_with("S11/S11(0)") {
                    s11 / solution.s11_s12(1.0).0
                } else if quantity.starts_with("POL=-S12/S11") {
                    -s12 / s11
                } else if quantity.starts_with("S33/S11") {
                    (s2 * s1.conj()).re / s11
                } else if quantity.starts_with("S34/S11") {
                    (s2 * s1.conj()).im / s11
                } else {
                    panic!("unknown published quantity {quantity:?}");
                };
                (value, 1.0, 1e-9)
            }
        };
        let error = (value - reference).abs() / scale.abs();
        worst = worst.max(error / tolerance);
        assert!(
            error <= tolerance,
            "{quantity} at m = {m}, x = {x}: {value} vs {reference} (error {error:e} of scale {scale:e})"
        );
        checked += 1;
    }
    assert_eq!(checked, 193, "plain-sphere rows checked");
    assert_eq!(conductors, 10, "perfect-conductor rows checked");
    eprintln!(
        "published cases: {checked} spheres and {conductors} perfect conductors checked, worst error {worst:.2e} of its tolerance"
    );
}

/// Rayleigh limit: Q_sca -> (8/3) x^4 |(m^2-1)/(m^2+2)|^2 and
/// Q_abs -> 4 x Im((m^2-1)/(m^2+2)) as x -> 0, with relative corrections of
/// order x^2: halving x divides the deviation by 4.
#[test]
fn rayleigh_limit_is_approached_at_the_right_rate() {
    for m in [
        Complex64::new(1.33, 0.0),
        Complex64::new(1.5, 0.01),
        Complex64::new(1.75, 0.44),
        Complex64::new(0.75, 0.0),
    ] {
        let k = (m * m - 1.0) / (m * m + 2.0);
        let deviation = |x: f64| {
            let q = compute_efficiencies(m, x).unwrap();
            let sca = q.qsca / (8.0 / 3.0 * x.powi(4) * k.norm_sqr()) - 1.0;
            let abs = if m.im > 0.0 {
                q.qabs / (4.0 * x * k.im) - 1.0
            } else {
                0.0
            };
            (sca, abs)
        };
        // The next correction is O(x^4) with a coefficient up to ~13 times
        // the x^2 one (m = 1.75 + 0.44i), hence x <= 0.01 for a 1 % rate.
        for x in [0.01, 0.005, 0.0025] {
            let (big_sca, big_abs) = deviation(x);
            let (small_sca, small_abs) = deviation(x / 2.0);
            let rate_sca = big_sca / small_sca;
            assert!(
                (rate_sca - 4.0).abs() < 0.04,
                "m = {m}, x = {x}: Q_sca deviation ratio {rate_sca}"
            );
            if m.im > 0.0 {
                let rate_abs = big_abs / small_abs;
                assert!(
                    (rate_abs - 4.0).abs() < 0.04,
                    "m = {m}, x = {x}: Q_abs deviation ratio {rate_abs}"
                );
            }
        }
        // Deep in the limit the deviation is ~x^2: below 1e-11 at x = 1e-6
        // (what is left is rounding).
        let (sca, abs) = deviation(1e-6);
        assert!(
            sca.abs() < 1e-11 && abs.abs() < 1e-11,
            "m = {m}: {sca:e} {abs:e}"
        );
        let q = compute_efficiencies(m, 1e-6).unwrap();
        // g ~ x^2 and Q_back -> (3/2) Q_sca (dipole) in the limit.
        assert!(q.g.abs() < 1e-11);
        assert!((q.qback / q.qsca - 1.5).abs() < 1e-9);
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut rule = Vec::with_capacity(n);
    for i in 0..n {
        let mut mu = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, mu);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * mu * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            derivative = n as f64 * (mu * p1 - p0) / (mu * mu - 1.0);
            let step = p1 / derivative;
            mu -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        rule.push((mu, 2.0 / ((1.0 - mu * mu) * derivative * derivative)));
    }
    rule
}

/// The phase function integrates to 1 over 4 pi sr, and its mu-weighted
/// integral is g. S11(mu) is a polynomial of degree 2 N in mu (N series
/// terms), so Gauss-Legendre with N + 2 nodes integrates it exactly: any
/// difference is rounding, and the tolerance is 1e-12.
#[test]
fn phase_function_is_normalised_and_its_mean_cosine_is_g() {
    for &(m, x) in &[
        (Complex64::new(1.33, 0.0), 10.0),
        (Complex64::new(1.5, 0.01), 30.0),
        (Complex64::new(1.75, 0.44), 100.0),
        (Complex64::new(0.75, 0.0), 50.0),
        (Complex64::new(1.5, 0.0), 0.3),
    ] {
        let solution = MieSolution::compute(m, x).unwrap();
        let rule = gauss_legendre(solution.n_terms() + 2);
        let mu: Vec<f64> = rule.iter().map(|&(mu, _)| mu).collect();
        let mut phase = vec![0.0; mu.len()];
        solution.phase_function_table(&mu, &mut phase);
        let (mut norm, mut mean_cosine) = (0.0, 0.0);
        for (&(mu, weight), &p) in rule.iter().zip(&phase) {
            norm += 2.0 * std::f64::consts::PI * weight * p;
            mean_cosine += 2.0 * std::f64::consts::PI * weight * p * mu;
        }
        let g = solution.efficiencies().g;
        assert!(
            (norm - 1.0).abs() < 1e-12,
            "m = {m}, x = {x}: integral {norm}"
        );
        assert!(
            (mean_cosine - g).abs() < 1e-12,
            "m = {m}, x = {x}: <mu> = {mean_cosine} vs g = {g}"
        );
    }
}

/// Normal-incidence Fresnel reflectance |(m-1)/(m+1)|^2 and its average over
/// a sphere's projected area, 2 int_0^1 R(mu) mu dmu (unpolarised).
fn fresnel_reflectances(m: Complex64) -> (f64, f64) {
    let normal = ((m - 1.0) / (m + 1.0)).norm_sqr();
    let steps = 20_000;
    let mut average = 0.0;
    for i in 0..steps {
        let mu = (i as f64 + 0.5) / steps as f64;
        let cos_t = (1.0 - (1.0 - mu * mu) / (m * m)).sqrt();
        let rs = (mu - m * cos_t) / (mu + m * cos_t);
        let rp = (m * mu - cos_t) / (m * mu + cos_t);
        average += (rs.norm_sqr() + rp.norm_sqr()) / 2.0 * 2.0 * mu / steps as f64;
    }
    (normal, average)
}

/// Hand-picked hard cases against limits that theory fixes independently of
/// the series.
#[test]
fn hard_cases_reach_their_physical_limits() {
    // Metal-like, huge: |mx| = 2.8e5, Im(mx) = 2e5. Nothing enters and comes
    // back, so geometric optics is exact up to edge terms O(x^(-2/3)):
    // Q_ext = 2 + O(x^(-2/3)) (extinction paradox plus the edge term),
    // Q_abs = 1 - (area-averaged Fresnel reflectance), and Q_back = the
    // normal-incidence reflectance (B&H 4.82 convention).
    let m = Complex64::new(10.0, 10.0);
    let x = 2e4;
    let q = compute_efficiencies(m, x).unwrap();
    let (normal, average) = fresnel_reflectances(m);
    // The edge coefficient depends on m (2.0 for 1.5 + 1i, 0.13 for a perfect
    // conductor in the reference data): only its sign and size are fixed.
    let edge = (q.qext - 2.0) / x.powf(-2.0 / 3.0);
    assert!(
        edge > 0.0 && edge < 4.0,
        "Q_ext = {} (edge coefficient {edge})",
        q.qext
    );
    assert!(
        (q.qabs - (1.0 - average)).abs() < 5e-3,
        "Q_abs = {} vs {}",
        q.qabs,
        1.0 - average
    );
    assert!(
        (q.qback - normal).abs() < 1e-4 * normal,
        "Q_back = {} vs {normal}",
        q.qback
    );
    assert!(q.g > 0.0 && q.g < 1.0);

    // A bubble (Re m < 1) at x = 1e4: lossless, Q_ext -> 2.
    let q = compute_efficiencies(Complex64::new(0.75, 0.0), 1e4).unwrap();
    assert_eq!(q.qabs, 0.0);
    assert_eq!(q.qext, q.qsca);
    assert!((q.qext - 2.0).abs() < 0.02, "bubble Q_ext = {}", q.qext);

    // Nearly index-matched, large: anomalous diffraction (van de Hulst 1957,
    // sec. 11.22) with phase shift rho = 2 x (m - 1) = 2:
    // Q_ext = 2 - (4/rho) sin rho + (4/rho^2)(1 - cos rho).
    let (m, x) = (Complex64::new(1.0001, 0.0), 1e4);
    let rho = 2.0 * x * (m.re - 1.0);
    let anomalous = 2.0 - 4.0 / rho * rho.sin() + 4.0 / (rho * rho) * (1.0 - rho.cos());
    let q = compute_efficiencies(m, x).unwrap();
    assert!(
        (q.qext / anomalous - 1.0).abs() < 2e-3,
        "Q_ext = {} vs ADT {anomalous}",
        q.qext
    );
    assert!(q.g > 0.99 && q.g < 1.0, "g = {}", q.g);

    // Nearly index-matched, tiny: Rayleigh to ~x^2 = 1e-12.
    let (m, x) = (Complex64::new(1.0001, 0.0), 1e-6);
    let k = (m * m - 1.0) / (m * m + 2.0);
    let q = compute_efficiencies(m, x).unwrap();
    assert!((q.qsca / (8.0 / 3.0 * x.powi(4) * k.norm_sqr()) - 1.0).abs() < 1e-10);

    // Water with a trace of absorption at x = 1e4: Q_ext -> 2, and the weak
    // absorption of a large sphere, (8/3) x Im(m) n^2 [1 - (n^2-1)^(3/2)/n^3]
    // (single pass with refraction, no internal reflections), to ~1 %.
    let (m, x) = (Complex64::new(1.33, 1e-8), 1e4);
    let q = compute_efficiencies(m, x).unwrap();
    let n = m.re;
    let single_pass = 8.0 / 3.0 * x * m.im * n * n * (1.0 - (n * n - 1.0).powf(1.5) / (n * n * n));
    assert!(
        (q.qabs / single_pass - 1.0).abs() < 0.01,
        "Q_abs = {} vs {single_pass}",
        q.qabs
    );
    assert!((q.qext - 2.0).abs() < 0.01);
}
