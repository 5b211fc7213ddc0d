//! The axes of the engine tables and their mappings between physical
//! coordinates and fractional node indices. The reference shaders
//! (`web/shaders/sora_sky.glsl`, `sora_sky.wgsl`) and the manifest's
//! `lookup` text repeat these formulas; a change here is a change of the
//! table format (`FORMAT_VERSION`).
//!
//! - Sun elevation e (degrees, -12..90): node coordinate
//!   `s = (asinh(e / W) - t0) / (t1 - t0) * (S - 1)`, t0 = asinh(-12 / W),
//!   t1 = asinh(90 / W), W = [`SUN_WIDTH_DEG`]: with 48 nodes they are 0.4
//!   degrees apart at sunset, where the sky changes fastest, 0.9 at -6,
//!   1.6 at -12 and about 10 near the zenith.
//! - Eye altitude h (m above the ground, 0..H with H the atmosphere's
//!   thickness): `a = ln(1 + h / h0) / ln(1 + H / h0) * (A - 1)`,
//!   h0 = H / [`ALTITUDE_SCALE_DIVISOR`]: crowded toward the ground, with a
//!   finite slope there (a square root's infinite slope made the
//!   aerial-perspective difference of two nearby points jump).
//! - View zenith angle z (rad) for an eye at radius r, with the horizon at
//!   z_h = pi - asin(R / r) (R the ground's radius): two halves that meet
//!   at the horizon, each crowding its nodes toward it (sora's own
//!   sky-view table, `transport/sky_view_table.rs`), the nodes next to it
//!   kept a margin m = 1e-6 rad inside their half: above the horizon
//!   `y = (1 - sqrt(1 - z / (z_h - m))) * (Z - 1)`, below it
//!   `y = (2 Z - 1) - (1 - sqrt(1 - (pi - z) / (pi - z_h - m))) * (Z - 1)`,
//!   and no cell straddles the horizon.
//! - View azimuth relative to the sun's, phi in 0..pi (the sky is
//!   symmetric about the solar meridian): `x = sqrt(phi / pi) * (K - 1)`,
//!   crowded toward the sun's side, where the aerosol's forward peak is.
//! - Transmittance's view cosine mu for an eye at radius r, above the
//!   horizon's cosine mu_h = -sqrt(1 - (R / r)^2):
//!   `m = sqrt((mu - mu_h) / (1 - mu_h)) * (M - 1)`, crowded toward the
//!   horizon.

/// Lowest sun elevation the tables cover, degrees.
pub const SUN_ELEVATION_MIN_DEG: f64 = -12.0;
/// Highest sun elevation, degrees.
pub const SUN_ELEVATION_MAX_DEG: f64 = 90.0;
/// Width of the sun axis's asinh mapping, degrees.
pub const SUN_WIDTH_DEG: f64 = 3.0;

/// The sun axis's parameter t = asinh(e / W) at elevation `e_deg`.
fn sun_parameter(e_deg: f64) -> f64 {
    (e_deg / SUN_WIDTH_DEG).asinh()
}

/// Fractional node index of sun elevation `e_deg` on `nodes` nodes
/// (clamped to the axis).
pub fn sun_coordinate(e_deg: f64, nodes: usize) -> f64 {
    let (t0, t1) = (
        sun_parameter(SUN_ELEVATION_MIN_DEG),
        sun_parameter(SUN_ELEVATION_MAX_DEG),
    );
    ((sun_parameter(e_deg) - t0) / (t1 - t0)).clamp(0.0, 1.0) * (nodes - 1) as f64
}

/// Sun elevation (degrees) of node `index` of `nodes`.
pub fn sun_elevation_of_node(index: usize, nodes: usize) -> f64 {
    let (t0, t1) = (
        sun_parameter(SUN_ELEVATION_MIN_DEG),
        sun_parameter(SUN_ELEVATION_MAX_DEG),
    );
    let t = t0 + (t1 - t0) * index as f64 / (nodes - 1) as f64;
    (SUN_WIDTH_DEG * t.sinh()).clamp(SUN_ELEVATION_MIN_DEG, SUN_ELEVATION_MAX_DEG)
}

/// The altitude axis's scale h0 is the atmosphere's thickness over this.
pub const ALTITUDE_SCALE_DIVISOR: f64 = 50.0;

/// Fractional node index of altitude `h_m` on an axis of `nodes` nodes
/// over 0..`thickness_m`.
pub fn altitude_coordinate(h_m: f64, thickness_m: f64, nodes: usize) -> f64 {
    let h0 = thickness_m / ALTITUDE_SCALE_DIVISOR;
    let x = h_m.clamp(0.0, thickness_m) / h0;
    (x.ln_1p() / ALTITUDE_SCALE_DIVISOR.ln_1p()).clamp(0.0, 1.0) * (nodes - 1) as f64
}

/// Altitude (m) of node `index` of `nodes` over 0..`thickness_m`.
pub fn altitude_of_node(index: usize, nodes: usize, thickness_m: f64) -> f64 {
    let v = index as f64 / (nodes - 1) as f64;
    let h0 = thickness_m / ALTITUDE_SCALE_DIVISOR;
    (h0 * (v * ALTITUDE_SCALE_DIVISOR.ln_1p()).exp_m1()).min(thickness_m)
}

/// Zenith angle of the horizon (rad) for an eye at radius `r_m` above a
/// ground of radius `ground_m`.
pub fn horizon_zenith(r_m: f64, ground_m: f64) -> f64 {
    std::f64::consts::PI - (ground_m / r_m).min(1.0).asin()
}

// The nodes next to the horizon sit this hair (rad) inside their half,
// so that a ray along them is unambiguously sky or ground: the sky-view
// table's own margin, one constant, since the bake's layers read that
// table at these nodes' zenith angles.
use crate::transport::sky_view_table::HORIZON_MARGIN_RAD;

/// The zenith axis's grid: with `half` nodes per half, `fine` fine cells
/// next to the horizon and `wide` wide cells before them, the half's
/// nodes lie on a grid of `2 (half - 1) - fine + wide` cells evenly
/// spaced in v = 1 - sqrt(1 - u): from the zenith (or the nadir) every
/// other grid node for the `half - 1 - fine - wide` coarse cells, every
/// third for the `wide` cells, every one in the last `fine` cells. With
/// `fine` and `wide` 0 the nodes are evenly spaced in v. (`fine + wide`
/// at most `half - 1`, `EngineTableSettings::validate`.)
fn fine_grid_cells(half: usize, fine: usize, wide: usize) -> usize {
    let fine = fine.min(half - 1);
    2 * (half - 1) - fine + wide.min(half - 1 - fine)
}

/// The coarse and wide cells of a half (the fine ones are the rest).
pub fn coarse_and_wide(half: usize, fine: usize, wide: usize) -> (usize, usize) {
    let fine = fine.min(half - 1);
    let wide = wide.min(half - 1 - fine);
    (half - 1 - fine - wide, wide)
}

/// The fine-grid node of zenith node `k` of a half (0 the zenith or the
/// nadir, `half - 1` next to the horizon): 2 grid cells a coarse cell, 3 a
/// wide one, 1 a fine one.
fn fine_grid_node(k: usize, half: usize, fine: usize, wide: usize) -> usize {
    let (coarse, wide) = coarse_and_wide(half, fine, wide);
    2 * k.min(coarse) + 3 * k.saturating_sub(coarse).min(wide) + k.saturating_sub(coarse + wide)
}

/// The zenith node coordinate (0..half - 1) of fine-grid coordinate `j`:
/// `j / 2` over the coarse cells, a third of a node a grid cell over the
/// wide ones, then one node a grid cell.
fn node_of_fine_grid(j: f64, half: usize, fine: usize, wide: usize) -> f64 {
    let (coarse, wide) = coarse_and_wide(half, fine, wide);
    let (c, w) = (coarse as f64, wide as f64);
    if j <= 2.0 * c {
        0.5 * j
    } else if j <= 2.0 * c + 3.0 * w {
        c + (j - 2.0 * c) / 3.0
    } else {
        j - c - 2.0 * w
    }
}

/// The fine grid's nodes per half (its cells plus one; the axis's own
/// nodes where it has no fine or wide cells).
pub fn fine_grid_rows(half: usize, fine: usize, wide: usize) -> usize {
    if fine == 0 && wide == 0 {
        half
    } else {
        fine_grid_cells(half, fine, wide) + 1
    }
}

/// Zenith angle (rad) of zenith-axis node `row` of `2 half` rows (0 the
/// zenith, half - 1 just above the horizon, half just below, 2 half - 1
/// the nadir) for a horizon at `horizon` rad, with `fine` fine and `wide`
/// wide cells next to the horizon in each half (`fine_grid_cells`).
pub fn zenith_of_node(row: usize, half: usize, (fine, wide): (usize, usize), horizon: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let cells = fine_grid_cells(half, fine, wide) as f64;
    if row < half {
        let v = fine_grid_node(row, half, fine, wide) as f64 / cells;
        let u = 1.0 - (1.0 - v) * (1.0 - v);
        u * (horizon - HORIZON_MARGIN_RAD)
    } else {
        let v = fine_grid_node(2 * half - 1 - row, half, fine, wide) as f64 / cells;
        let u = 1.0 - (1.0 - v) * (1.0 - v);
        pi - u * (pi - horizon - HORIZON_MARGIN_RAD)
    }
}

/// Fractional row of zenith angle `zenith` (rad) for a horizon at
/// `horizon`, and the rows the interpolation may use: (y, lowest cell,
/// highest cell) so that no cell straddles the horizon. The exact inverse
/// of [`zenith_of_node`], margin included.
pub fn zenith_coordinate(
    zenith: f64,
    half: usize,
    (fine, wide): (usize, usize),
    horizon: f64,
) -> (f64, usize, usize) {
    let pi = std::f64::consts::PI;
    let cells = fine_grid_cells(half, fine, wide) as f64;
    let node = |u: f64| node_of_fine_grid((1.0 - (1.0 - u).sqrt()) * cells, half, fine, wide);
    if zenith < horizon {
        let u = (zenith / (horizon - HORIZON_MARGIN_RAD)).clamp(0.0, 1.0);
        (node(u), 0, half - 2)
    } else {
        let u = ((pi - zenith) / (pi - horizon - HORIZON_MARGIN_RAD)).clamp(0.0, 1.0);
        ((2 * half - 1) as f64 - node(u), half, 2 * half - 2)
    }
}

/// Relative azimuth (rad, 0..pi) of azimuth node `index` of `nodes`.
pub fn azimuth_of_node(index: usize, nodes: usize) -> f64 {
    let v = index as f64 / (nodes - 1) as f64;
    std::f64::consts::PI * v * v
}

/// Fractional node index of relative azimuth `phi` (rad, 0..pi).
pub fn azimuth_coordinate(phi: f64, nodes: usize) -> f64 {
    (phi / std::f64::consts::PI).clamp(0.0, 1.0).sqrt() * (nodes - 1) as f64
}

/// Cosine of the horizon's zenith angle for an eye at `r_m`.
pub fn horizon_cosine(r_m: f64, ground_m: f64) -> f64 {
    -(1.0 - (ground_m / r_m).min(1.0).powi(2)).max(0.0).sqrt()
}

/// View cosine of transmittance node `index` of `nodes` at radius `r_m`.
pub fn transmittance_mu_of_node(index: usize, nodes: usize, r_m: f64, ground_m: f64) -> f64 {
    let mu_h = horizon_cosine(r_m, ground_m);
    let v = index as f64 / (nodes - 1) as f64;
    mu_h + (1.0 - mu_h) * v * v
}

/// Fractional node index of view cosine `mu` at radius `r_m` (clamped to
/// the horizon and the zenith).
pub fn transmittance_mu_coordinate(mu: f64, nodes: usize, r_m: f64, ground_m: f64) -> f64 {
    let mu_h = horizon_cosine(r_m, ground_m);
    ((mu - mu_h) / (1.0 - mu_h)).clamp(0.0, 1.0).sqrt() * (nodes - 1) as f64
}

/// The aerial-perspective table's nearest distance node is the
/// atmosphere's thickness over this (100 m for a 100 km atmosphere).
pub const AERIAL_NEAREST_DIVISOR: f64 = 1000.0;

/// Length (m) of the ray from radius `r_m` along view cosine `mu` to where
/// it meets the ground (below the horizon) or leaves the top of the
/// atmosphere.
pub fn ray_length(r_m: f64, mu: f64, ground_m: f64, top_m: f64) -> f64 {
    let b = r_m * mu;
    let c = r_m * r_m;
    if mu < horizon_cosine(r_m, ground_m) {
        (-b - (b * b - c + ground_m * ground_m).max(0.0).sqrt()).max(0.0)
    } else {
        (-b + (b * b - c + top_m * top_m).max(0.0).sqrt()).max(0.0)
    }
}

/// The aerial-perspective table's distance axis for a ray of length
/// `length_m` in an atmosphere `thickness_m` thick: (nearest node, last
/// node), the last the ray's end (at least twice the nearest).
pub fn distance_range(thickness_m: f64, length_m: f64) -> (f64, f64) {
    let nearest = thickness_m / AERIAL_NEAREST_DIVISOR;
    (nearest, length_m.max(2.0 * nearest))
}

/// Fractional node index of distance `d_m` on `nodes` nodes spaced evenly
/// in ln d over `(nearest, last)` (clamped to the axis).
pub fn distance_coordinate(d_m: f64, nodes: usize, (nearest, last): (f64, f64)) -> f64 {
    ((d_m.max(nearest) / nearest).ln() / (last / nearest).ln()).clamp(0.0, 1.0) * (nodes - 1) as f64
}

/// Distance (m) of node `index` of `nodes` over `(nearest, last)` (the
/// last node exactly `last`).
pub fn distance_of_node(index: usize, nodes: usize, (nearest, last): (f64, f64)) -> f64 {
    if index + 1 == nodes {
        return last;
    }
    nearest * (last / nearest).powf(index as f64 / (nodes - 1) as f64)
}

/// The cell and the weight of the upper node for fractional index `x` on
/// an axis whose cells run lowest..=highest.
pub fn cell(x: f64, lowest: usize, highest: usize) -> (usize, f64) {
    let i = (x.floor().max(0.0) as usize).clamp(lowest, highest);
    (i, (x - i as f64).clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_mapping_inverts_its_nodes() {
        for n in [2, 7, 48] {
            for i in 0..n {
                let e = sun_elevation_of_node(i, n);
                assert!((sun_coordinate(e, n) - i as f64).abs() < 1e-9, "{i} {e}");
                let h = altitude_of_node(i, n, 100e3);
                assert!((altitude_coordinate(h, 100e3, n) - i as f64).abs() < 1e-9);
                let phi = azimuth_of_node(i, n);
                assert!((azimuth_coordinate(phi, n) - i as f64).abs() < 1e-9);
                let range =
                    distance_range(100e3, ray_length(6.371e6 + 10.0, 0.1, 6.371e6, 6.471e6));
                let d = distance_of_node(i, n, range);
                assert!((distance_coordinate(d, n, range) - i as f64).abs() < 1e-9);
                let r = 6.371e6 + 5e3;
                let mu = transmittance_mu_of_node(i, n, r, 6.371e6);
                assert!((transmittance_mu_coordinate(mu, n, r, 6.371e6) - i as f64).abs() < 1e-6);
            }
        }
        assert!((sun_elevation_of_node(0, 48) + 12.0).abs() < 1e-12);
        assert!((sun_elevation_of_node(47, 48) - 90.0).abs() < 1e-12);
        let horizon = horizon_zenith(6.371e6 + 1e3, 6.371e6);
        for cells in [(0, 0), (7, 0), (31, 0), (0, 9), (7, 9), (10, 21)] {
            for row in 0..64 {
                let z = zenith_of_node(row, 32, cells, horizon);
                let (y, lowest, highest) = zenith_coordinate(z, 32, cells, horizon);
                assert!((y - row as f64).abs() < 1e-3, "{cells:?} {row}: {y}");
                assert_eq!(lowest, if row < 32 { 0 } else { 32 });
                assert!(highest + 1 < 64);
            }
        }
    }

    #[test]
    fn the_fine_cells_are_the_rows_of_a_grid_twice_as_fine() {
        // 78 nodes per half with 27 fine cells: the nodes are rows of a
        // 128-row half (the images' sky-view table's), every other row
        // from the zenith to row 100 and every row in the last 27 cells.
        let horizon = horizon_zenith(3.3895e6 + 10.0, 3.3895e6);
        let grid = |j: usize| zenith_of_node(j, 128, (0, 0), horizon);
        for row in 0..78 {
            let j = if row <= 50 { 2 * row } else { row + 50 };
            let z = zenith_of_node(row, 78, (27, 0), horizon);
            assert!((z - grid(j)).abs() < 1e-12, "{row}: {z} {}", grid(j));
            let below = zenith_of_node(2 * 78 - 1 - row, 78, (27, 0), horizon);
            assert!((below - zenith_of_node(255 - j, 128, (0, 0), horizon)).abs() < 1e-12);
        }
        // 64 nodes per half with 21 fine and 22 wide cells: every other
        // row to row 40, every third to row 106, every row from there.
        let mut rows = Vec::new();
        for row in 0..64 {
            let j = match row {
                0..=20 => 2 * row,
                21..=42 => 40 + 3 * (row - 20),
                _ => 106 + (row - 42),
            };
            let z = zenith_of_node(row, 64, (21, 22), horizon);
            assert!((z - grid(j)).abs() < 1e-12, "{row}: {z} {}", grid(j));
            let below = zenith_of_node(127 - row, 64, (21, 22), horizon);
            assert!((below - zenith_of_node(255 - j, 128, (0, 0), horizon)).abs() < 1e-12);
            rows.push(j);
        }
        assert_eq!(*rows.last().unwrap(), 127);
        // The rows a layer's sky-view table marches are these.
        let marched = crate::transport::sky_view_table::MarchedRows {
            by_two: 20,
            by_three: 22,
        };
        let marched: Vec<usize> = (0..128).filter(|j| marched.marches(*j)).collect();
        assert_eq!(marched, rows);
        // With no fine cells, the mapping is the plain one.
        for row in 0..128 {
            let v = (row.min(127 - row)) as f64 / 63.0;
            let u = 1.0 - (1.0 - v) * (1.0 - v);
            let z = zenith_of_node(row, 64, (0, 0), horizon);
            let plain = if row < 64 {
                u * (horizon - HORIZON_MARGIN_RAD)
            } else {
                std::f64::consts::PI - u * (std::f64::consts::PI - horizon - HORIZON_MARGIN_RAD)
            };
            assert!((z - plain).abs() < 1e-12, "{row}");
        }
    }

    #[test]
    fn sun_nodes_are_finest_in_twilight() {
        let n = 48;
        let step = |e: f64| {
            let s = sun_coordinate(e, n);
            sun_elevation_of_node(s.floor() as usize + 1, n)
                - sun_elevation_of_node(s.floor() as usize, n)
        };
        assert!(
            step(-6.0) < 1.0 && step(0.5) < 0.45,
            "{} {}",
            step(-6.0),
            step(0.5)
        );
        assert!(step(80.0) > 5.0);
    }
}
