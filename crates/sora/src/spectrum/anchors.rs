//! A grid's wavelengths as blends of a subset of them, the anchors: for
//! quantities smooth in wavelength (the polarisation correction's columns,
//! the Mie phase-matrix ratios) computed at the anchors only and
//! interpolated in wavelength between them, by the cubic through the four
//! nearest anchors (Lagrange; through three or two where the grid has
//! fewer).
//!
//! **Every `stride`-th** ([`WavelengthAnchors::new`]): the anchors are
//! every `stride`-th wavelength from the first, and the last; the stride is
//! cut so that two neighbouring anchors are at most [`MAX_ANCHOR_SPAN_NM`]
//! apart (a coarse grid keeps every wavelength). Stride 1 makes every
//! wavelength an anchor: the exact path. The Mie ratios take these (they
//! depend on the particles only, smooth in wavelength).
//!
//! **Following the absorption** ([`WavelengthAnchors::following_optics`],
//! the polarisation correction's columns, each sky's own optics, so each
//! k-term sky's): the same anchors, and then every wavelength where the
//! cubic blend of the anchors misses the column's own optics becomes an
//! anchor too, until none does. The optics checked, per wavelength: the
//! column's vertical absorbing optical depth (extinction less scattering,
//! all species; dimensionless) within [`ABSORBING_TOLERANCE`] (absolute),
//! its vertical scattering optical depth within [`SCATTERING_TOLERANCE`]
//! of itself (relative), and the ground's albedo within
//! [`ALBEDO_TOLERANCE`] (absolute). A column's light goes as exp(-tau m)
//! along paths of air mass m, so an absolute miss d in the absorbing
//! optical depth is a relative miss of about m d in the light, however
//! deep the absorption: where a gas absorbs strongly or its absorption
//! changes steeply between neighbours (ozone's Hartley and Huggins bands,
//! the O2 and water bands, a strong k-term's sky) the cubic misses by far
//! more and every such wavelength is solved, rather than guessed; in
//! smooth stretches (Rayleigh's lambda^-4, the Chappuis band's misses of
//! at most 2e-3 at 20-nm steps, aerosols) the stride's spacing stays.
//! Scattering alone (Rayleigh, aerosols) is smooth: its relative check
//! only guards against a species whose scattering is not.

use super::WavelengthGrid;
use crate::atmosphere::AtmosphereOptics;

/// The widest span between two neighbouring anchors, nm.
pub(crate) const MAX_ANCHOR_SPAN_NM: f64 = 60.0;

/// The largest miss of the anchors' blend of the column's vertical
/// absorbing optical depth at a wavelength that is not an anchor
/// ([`WavelengthAnchors::following_optics`]), dimensionless.
pub(crate) const ABSORBING_TOLERANCE: f64 = 3e-3;

/// The largest miss of the anchors' blend of the column's vertical
/// scattering optical depth at a wavelength that is not an anchor, relative
/// to the optical depth there.
pub(crate) const SCATTERING_TOLERANCE: f64 = 1e-2;

/// The largest miss of the anchors' blend of the ground's albedo at a
/// wavelength that is not an anchor.
pub(crate) const ALBEDO_TOLERANCE: f64 = 2e-3;

/// Which wavelengths of a grid are anchors, and each wavelength's blend.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct WavelengthAnchors {
    /// The anchors' wavelength indices, increasing.
    anchors: Vec<usize>,
    /// Per wavelength: the positions among `anchors` of the anchors it is
    /// blended from, and their weights (summing to 1).
    blends: Vec<Vec<(usize, f64)>>,
}

/// The anchors whose cubic interpolates a wavelength.
const CUBIC_NODES: usize = 4;

/// Every `stride`-th wavelength index of `grid` from the first, and the
/// last (the stride at least 1, cut to [`MAX_ANCHOR_SPAN_NM`]).
fn every_stride(grid: &WavelengthGrid, stride: usize) -> Vec<usize> {
    let len = grid.len();
    let widest = (MAX_ANCHOR_SPAN_NM / grid.step_nm() + 1e-9).floor() as usize;
    let stride = stride.min(widest).max(1);
    let mut anchors: Vec<usize> = (0..len).step_by(stride).collect();
    if anchors.last() != Some(&(len - 1)) {
        anchors.push(len - 1);
    }
    anchors
}

impl WavelengthAnchors {
    /// The anchors of `grid` every `stride` wavelengths (at least 1; cut to
    /// [`MAX_ANCHOR_SPAN_NM`]).
    pub(crate) fn new(grid: &WavelengthGrid, stride: usize) -> WavelengthAnchors {
        WavelengthAnchors::at(grid.len(), every_stride(grid, stride))
    }

    /// The anchors of `optics`' grid every `stride` wavelengths, and every
    /// wavelength where the anchors' blend misses the column's absorbing
    /// optical depth by more than [`ABSORBING_TOLERANCE`], its scattering
    /// optical depth by more than [`SCATTERING_TOLERANCE`] of itself or the
    /// ground's albedo by more than [`ALBEDO_TOLERANCE`] (see the module
    /// docs).
    pub(crate) fn following_optics(optics: &AtmosphereOptics, stride: usize) -> WavelengthAnchors {
        let len = optics.grid.len();
        let mut absorbing = vec![0.0; len];
        let mut scattering = vec![0.0; len];
        for species in &optics.species {
            for i in 0..len {
                let (ext, sca) = (species.extinction_per_m[i], species.scattering_per_m[i]);
                absorbing[i] += (ext - sca).max(0.0) * species.vertical_column_m;
                scattering[i] += sca * species.vertical_column_m;
            }
        }
        // (values, absolute tolerance, relative tolerance)
        let checks = [
            (&absorbing[..], ABSORBING_TOLERANCE, 0.0),
            (&scattering[..], 0.0, SCATTERING_TOLERANCE),
            (optics.ground_albedo.values(), ALBEDO_TOLERANCE, 0.0),
        ];
        let mut anchors = WavelengthAnchors::new(&optics.grid, stride);
        loop {
            let missed: Vec<usize> = (0..len)
                .filter(|&i| {
                    let blend = anchors.blend(i);
                    blend.len() > 1
                        && checks.iter().any(|(values, absolute, relative)| {
                            let blended: f64 = blend
                                .iter()
                                .map(|&(n, w)| w * values[anchors.anchors[n]])
                                .sum();
                            (blended - values[i]).abs() > absolute + relative * values[i]
                        })
                })
                .collect();
            if missed.is_empty() {
                return anchors;
            }
            let mut indices = anchors.anchors;
            indices.extend(missed);
            indices.sort_unstable();
            anchors = WavelengthAnchors::at(len, indices);
        }
    }

    /// The blends of a grid of `len` wavelengths from `anchors` (increasing,
    /// the first and the last wavelength among them).
    fn at(len: usize, anchors: Vec<usize>) -> WavelengthAnchors {
        let blends = (0..len)
            .map(|i| {
                let above = anchors.partition_point(|&a| a < i);
                if anchors[above] == i {
                    return vec![(above, 1.0)];
                }
                // The four nearest anchors, two each side where there are.
                let count = anchors.len().min(CUBIC_NODES);
                let first = (above - 1).saturating_sub(1).min(anchors.len() - count);
                let nodes = first..first + count;
                let x = |n: usize| anchors[n] as f64;
                nodes
                    .clone()
                    .map(|n| {
                        let weight = nodes
                            .clone()
                            .filter(|&k| k != n)
                            .map(|k| (i as f64 - x(k)) / (x(n) - x(k)))
                            .product();
                        (n, weight)
                    })
                    .collect()
            })
            .collect();
        WavelengthAnchors { anchors, blends }
    }

    /// The anchors' wavelength indices, increasing.
    pub(crate) fn anchors(&self) -> &[usize] {
        &self.anchors
    }

    /// Whether every wavelength is an anchor.
    #[cfg(test)]
    pub(crate) fn is_every_wavelength(&self) -> bool {
        self.anchors.len() == self.blends.len()
    }

    /// Wavelength `i` as a blend: the positions among [`Self::anchors`] of
    /// the anchors it is interpolated from and their weights (an anchor:
    /// itself, weight 1).
    pub(crate) fn blend(&self, i: usize) -> &[(usize, f64)] {
        &self.blends[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchors_cover_the_grid_and_interpolate_cubics_exactly() {
        let paper = WavelengthGrid::paper();
        let anchors = WavelengthAnchors::new(&paper, 2);
        assert_eq!(anchors.anchors().len(), 11);
        assert_eq!(anchors.blend(4), &[(2, 1.0)]);
        // A cubic in wavelength is blended exactly, at the ends too.
        let cubic = |i: f64| 2.0 - 0.3 * i + 0.05 * i * i - 0.002 * i * i * i;
        for (grid, stride) in [
            (paper, 2),
            (paper, 3),
            (WavelengthGrid::new(400.0, 430.0, 10.0).unwrap(), 3),
            (WavelengthGrid::new(400.0, 440.0, 10.0).unwrap(), 3),
        ] {
            let anchors = WavelengthAnchors::new(&grid, stride);
            assert_eq!(anchors.anchors()[0], 0);
            assert_eq!(*anchors.anchors().last().unwrap(), grid.len() - 1);
            for i in 0..grid.len() {
                let blend = anchors.blend(i);
                let sum: f64 = blend.iter().map(|(_, w)| w).sum();
                assert!((sum - 1.0).abs() < 1e-12);
                if anchors.anchors().len() >= 4 {
                    let value: f64 = blend
                        .iter()
                        .map(|(n, w)| w * cubic(anchors.anchors()[*n] as f64))
                        .sum();
                    assert!((value - cubic(i as f64)).abs() < 1e-12, "{i} {stride}");
                }
            }
        }
        assert_eq!(
            WavelengthAnchors::new(&WavelengthGrid::new(400.0, 440.0, 10.0).unwrap(), 3).anchors(),
            &[0, 3, 4]
        );
        // One and two wavelengths, a coarse grid and stride 1: every one.
        for (grid, stride) in [
            (WavelengthGrid::new(550.0, 550.0, 10.0).unwrap(), 2),
            (WavelengthGrid::new(440.0, 660.0, 220.0).unwrap(), 2),
            (WavelengthGrid::new(400.0, 700.0, 100.0).unwrap(), 2),
            (WavelengthGrid::new(380.0, 780.0, 40.0).unwrap(), 3),
            (paper, 1),
        ] {
            let anchors = WavelengthAnchors::new(&grid, stride);
            assert!(anchors.is_every_wavelength());
            assert_eq!(anchors.anchors(), (0..grid.len()).collect::<Vec<_>>());
        }
    }
}
