//! The sphere solver against reference values computed in 100-digit
//! arithmetic (scattnlay 2.4, audited with mpmath; see
//! `shared/reference/mie/README.md`), copied into `tests/data/` with their
//! provenance on the first line, and against limits that theory fixes.

use sora_mie::Complex64;
use sora_mie::sphere::{
    MieSolution, SphereWorkspace, compute_efficiencies, compute_efficiencies_with,
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
