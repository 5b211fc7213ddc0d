//! The columns of the built-in Mars dust table
//! (`refractive_index::MARS_DUST_WOLFF2009_CSV`) for sora-mie's own tests
//! and benches, which build it with `TabulatedRefractiveIndex::from_columns`.
//! Reading refractive-index CSV is sora's (its one numeric-table reader,
//! which checks user files); this reads only that one fixed file, with the
//! same numbers sora gets: each cell parsed as `f64`, micrometres times 1000.

/// Wavelength (nm), `n` and `k` of the `wavelength_um,n,k` table `text`.
pub fn wavelength_nm_n_k(text: &str) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut lines = text.lines().filter(|line| !line.starts_with('#'));
    assert_eq!(lines.next(), Some("wavelength_um,n,k"));
    let (mut wavelength_nm, mut n, mut k) = (Vec::new(), Vec::new(), Vec::new());
    for line in lines {
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let [um, real, imaginary] = cells[..] else {
            panic!("{line}: three cells expected");
        };
        wavelength_nm.push(um * 1000.0);
        n.push(real);
        k.push(imaginary);
    }
    (wavelength_nm, n, k)
}
