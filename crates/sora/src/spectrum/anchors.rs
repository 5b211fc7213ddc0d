//! A grid's wavelengths as blends of a subset of them, the anchors: for
//! quantities smooth in wavelength (the polarisation correction's columns,
//! the Mie phase-matrix ratios) computed at the anchors only and
//! interpolated in wavelength between them, by the cubic through the four
//! nearest anchors (Lagrange; through three or two where the grid has
//! fewer).
//!
//! The anchors are every `stride`-th wavelength from the first, and the
//! last; the stride is cut so that two neighbouring anchors are at most
//! [`MAX_ANCHOR_SPAN_NM`] apart (a coarse grid keeps every wavelength).
//! Stride 1 makes every wavelength an anchor: the exact path.

use super::WavelengthGrid;

/// The widest span between two neighbouring anchors, nm.
pub(crate) const MAX_ANCHOR_SPAN_NM: f64 = 60.0;

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

impl WavelengthAnchors {
    /// The anchors of `grid` every `stride` wavelengths (at least 1; cut to
    /// [`MAX_ANCHOR_SPAN_NM`]).
    pub(crate) fn new(grid: &WavelengthGrid, stride: usize) -> WavelengthAnchors {
        let len = grid.len();
        let widest = (MAX_ANCHOR_SPAN_NM / grid.step_nm() + 1e-9).floor() as usize;
        let stride = stride.min(widest).max(1);
        let mut anchors: Vec<usize> = (0..len).step_by(stride).collect();
        if anchors.last() != Some(&(len - 1)) {
            anchors.push(len - 1);
        }
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
