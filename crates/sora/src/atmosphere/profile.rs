//! Density profiles: how the amount of a species varies with altitude.
//!
//! The paper's eq. 1 writes a species' scattering coefficient as
//! beta(lambda, h) = rho(h) * sigma(lambda): number density times
//! cross-section. The paper gives only surface densities; sora separates the
//! two factors as
//!
//! ```text
//!     beta(lambda, h) = relative_density(h) * beta_reference(lambda)
//! ```
//!
//! where `relative_density` is dimensionless and equals 1 at the profile's
//! reference altitude (the ground for exponential profiles and tables, the
//! peak of a tent), and `beta_reference` is the coefficient there (m^-1).
//! The optics of a species (its cross-sections, see the sibling modules) and
//! its profile are thus independent, and a column optical depth is
//! `tau(lambda) = beta_reference(lambda) * column_m`, with
//!
//! ```text
//!     column_m = integral_0^top relative_density(h) dh        [m]
//! ```
//!
//! the *equivalent thickness* of the species: the height of a layer of the
//! reference density holding the same number of particles. Every profile
//! here has an exact closed-form column (no quadrature).
//!
//! Profiles:
//! - [`DensityProfile::Exponential`]: exp(-h / H), the isothermal barometric
//!   law; H is the scale height (air ~8 km on Earth, aerosol ~1.2 km, Mars
//!   CO2 ~11 km). Column H (1 - exp(-top / H)).
//! - [`DensityProfile::PiecewiseLinear`]: straight lines between rows
//!   (altitude, relative density), zero outside the rows: layers, and the
//!   tent of an ozone layer (zero at peak -/+ half-width, 1 at the peak).
//! - [`DensityProfile::LogLinear`]: a table interpolated linearly in the
//!   logarithm of the density, so exponential within each layer, as the
//!   U.S. Standard Atmosphere is tabulated. Outside the rows the nearest
//!   layer's exponential continues (a ray marcher that steps a few metres
//!   past the top or below the ground gets a smooth value, not a jump).
//!
//! Altitudes are in metres above sea level, f64: the ground, unless the
//! planet raises it (`Planet::with_ground_altitude_m`; the sky then reads
//! each profile as `DensityProfile::above_ground` shifts it).

use crate::error::{Error, Result};

/// Relative density (dimensionless, 1 at the reference altitude) as a
/// function of altitude above sea level (m; above the ground unless a
/// raised ground shifts it).
#[derive(Debug, Clone, PartialEq)]
pub enum DensityProfile {
    /// exp(-altitude / scale_height_m).
    Exponential {
        /// The altitude over which the density falls by e, m.
        scale_height_m: f64,
    },
    /// Linear between rows, zero outside them.
    PiecewiseLinear(ProfileTable),
    /// Linear in ln(density) between rows (exponential layers), each
    /// end layer's exponential continued outside the rows.
    LogLinear(ProfileTable),
}

/// Rows (altitude_m, relative_density), altitudes strictly increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileTable {
    altitudes_m: Vec<f64>,
    relative_densities: Vec<f64>,
}

impl ProfileTable {
    /// A table from its columns: at least two rows, altitudes finite and
    /// strictly increasing, densities finite and >= 0 (> 0 when
    /// `positive_densities`, as logarithmic interpolation needs). `name`
    /// is the key in error messages (`species[0].profile.table`).
    pub(crate) fn new(
        altitudes_m: Vec<f64>,
        relative_densities: Vec<f64>,
        positive_densities: bool,
        name: &str,
    ) -> Result<ProfileTable> {
        if altitudes_m.len() != relative_densities.len() || altitudes_m.len() < 2 {
            return Err(Error::parse(
                "atmosphere file",
                0,
                format!(
                    "{name}: altitude_m and relative_density need the same number of rows, at least 2 (got {} and {})",
                    altitudes_m.len(),
                    relative_densities.len()
                ),
            ));
        }
        for (i, &h) in altitudes_m.iter().enumerate() {
            if !(h.is_finite() && h.abs() <= 1e9) {
                return Err(Error::out_of_range(
                    format!("{name}.altitude_m[{i}]"),
                    h,
                    "m",
                    "finite, within -1e9..=1e9",
                ));
            }
            if i > 0 && h <= altitudes_m[i - 1] {
                return Err(Error::out_of_range(
                    format!("{name}.altitude_m[{i}]"),
                    h,
                    "m",
                    format!("altitudes must increase: > {}", altitudes_m[i - 1]),
                ));
            }
        }
        for (i, &rho) in relative_densities.iter().enumerate() {
            let ok = rho.is_finite()
                && if positive_densities {
                    rho > 0.0
                } else {
                    rho >= 0.0
                };
            if !ok {
                let allowed = if positive_densities {
                    "> 0 and finite (logarithmic interpolation)"
                } else {
                    ">= 0 and finite"
                };
                return Err(Error::out_of_range(
                    format!("{name}.relative_density[{i}]"),
                    rho,
                    "1",
                    allowed,
                ));
            }
        }
        Ok(ProfileTable {
            altitudes_m,
            relative_densities,
        })
    }

    /// The rows' altitudes, m.
    pub(crate) fn altitudes_m(&self) -> &[f64] {
        &self.altitudes_m
    }

    /// Index i of the layer [h_i, h_{i+1}] to use at `altitude_m`, clamped
    /// to the first and last layer.
    fn layer(&self, altitude_m: f64) -> usize {
        let upper = self.altitudes_m.partition_point(|&h| h <= altitude_m);
        upper.clamp(1, self.altitudes_m.len() - 1) - 1
    }

    fn layer_ends(&self, i: usize) -> (f64, f64, f64, f64) {
        (
            self.altitudes_m[i],
            self.altitudes_m[i + 1],
            self.relative_densities[i],
            self.relative_densities[i + 1],
        )
    }
}

impl DensityProfile {
    /// This profile (altitudes above sea level) seen from a ground
    /// `ground_altitude_m` above sea level: the same densities as a profile
    /// of heights above that ground, and the factor its relative density
    /// carries there. An exponential keeps its shape and carries
    /// exp(-g / H); a table's rows move down by g (rows below the ground
    /// stay, at negative heights, so interpolation is unchanged).
    pub(crate) fn above_ground(&self, ground_altitude_m: f64) -> (DensityProfile, f64) {
        let shifted = |table: &ProfileTable| ProfileTable {
            altitudes_m: table
                .altitudes_m
                .iter()
                .map(|h| h - ground_altitude_m)
                .collect(),
            relative_densities: table.relative_densities.clone(),
        };
        match self {
            DensityProfile::Exponential { scale_height_m } => {
                (self.clone(), (-ground_altitude_m / scale_height_m).exp())
            }
            DensityProfile::PiecewiseLinear(table) => {
                (DensityProfile::PiecewiseLinear(shifted(table)), 1.0)
            }
            DensityProfile::LogLinear(table) => (DensityProfile::LogLinear(shifted(table)), 1.0),
        }
    }

    /// The profile of the square of this one's relative density (what a
    /// pair absorption such as O2-O2's follows): exact for an exponential
    /// (half the scale height) and a log-linear table (its rows squared:
    /// ln rho^2 is linear wherever ln rho is); a piecewise-linear table has
    /// its rows squared and stays linear between them, which is at least
    /// the square between rows (rho^2 is convex), by (r1 - r0)^2 / 4 at
    /// most at a layer's middle.
    pub(crate) fn squared(&self) -> DensityProfile {
        let squared = |table: &ProfileTable| ProfileTable {
            altitudes_m: table.altitudes_m.clone(),
            relative_densities: table.relative_densities.iter().map(|r| r * r).collect(),
        };
        match self {
            DensityProfile::Exponential { scale_height_m } => DensityProfile::Exponential {
                scale_height_m: 0.5 * scale_height_m,
            },
            DensityProfile::PiecewiseLinear(table) => {
                DensityProfile::PiecewiseLinear(squared(table))
            }
            DensityProfile::LogLinear(table) => DensityProfile::LogLinear(squared(table)),
        }
    }

    /// An exponential profile; `scale_height_m` must be finite and > 0.
    /// `name` is the key in errors.
    pub(crate) fn exponential(scale_height_m: f64, name: &str) -> Result<DensityProfile> {
        if !(scale_height_m.is_finite() && scale_height_m > 0.0 && scale_height_m <= 1e9) {
            return Err(Error::out_of_range(
                name,
                scale_height_m,
                "m",
                "> 0 and <= 1e9",
            ));
        }
        Ok(DensityProfile::Exponential { scale_height_m })
    }

    /// A tent: relative density 1 at `peak_altitude_m`, falling linearly to
    /// 0 at `peak_altitude_m -/+ half_width_m`, zero beyond (the usual
    /// shape of an ozone layer, e.g. peak 25 km, half-width 15 km, as in
    /// Bruneton 2017).
    pub(crate) fn tent(
        peak_altitude_m: f64,
        half_width_m: f64,
        name: &str,
    ) -> Result<DensityProfile> {
        if !(peak_altitude_m.is_finite() && peak_altitude_m.abs() <= 1e9) {
            return Err(Error::out_of_range(
                format!("{name}.peak_altitude_m"),
                peak_altitude_m,
                "m",
                "finite, within -1e9..=1e9",
            ));
        }
        if !(half_width_m.is_finite() && half_width_m > 0.0 && half_width_m <= 1e9) {
            return Err(Error::out_of_range(
                format!("{name}.half_width_m"),
                half_width_m,
                "m",
                "> 0 and <= 1e9",
            ));
        }
        let table = ProfileTable::new(
            vec![
                peak_altitude_m - half_width_m,
                peak_altitude_m,
                peak_altitude_m + half_width_m,
            ],
            vec![0.0, 1.0, 0.0],
            false,
            name,
        )?;
        Ok(DensityProfile::PiecewiseLinear(table))
    }

    /// Relative density at `altitude_m` (m above the ground): the factor
    /// that multiplies a species' coefficients at relative density 1
    /// ([`super::SpeciesOptics`]).
    pub fn relative_density(&self, altitude_m: f64) -> f64 {
        match self {
            DensityProfile::Exponential { scale_height_m } => (-altitude_m / scale_height_m).exp(),
            DensityProfile::PiecewiseLinear(table) => {
                let (first, last) = (table.altitudes_m[0], *table.altitudes_m.last().unwrap());
                if !(first..=last).contains(&altitude_m) {
                    return 0.0;
                }
                let (h0, h1, r0, r1) = table.layer_ends(table.layer(altitude_m));
                r0 + (altitude_m - h0) / (h1 - h0) * (r1 - r0)
            }
            DensityProfile::LogLinear(table) => {
                let (h0, h1, r0, r1) = table.layer_ends(table.layer(altitude_m));
                let t = (altitude_m - h0) / (h1 - h0);
                r0 * (r1 / r0).powf(t)
            }
        }
    }

    /// Exact integral of the relative density over altitude from
    /// `lower_altitude_m` to `upper_altitude_m` (m): the equivalent
    /// thickness of that slab. Negative when the bounds are reversed.
    pub(crate) fn column_between_m(&self, lower_altitude_m: f64, upper_altitude_m: f64) -> f64 {
        if upper_altitude_m < lower_altitude_m {
            return -self.column_between_m(upper_altitude_m, lower_altitude_m);
        }
        let (a, b) = (lower_altitude_m, upper_altitude_m);
        match self {
            DensityProfile::Exponential { scale_height_m: h } => {
                // H (e^{-a/H} - e^{-b/H}) = H e^{-a/H} (1 - e^{-(b-a)/H}),
                // the second form keeps its accuracy for thin slabs.
                h * (-a / h).exp() * -(-(b - a) / h).exp_m1()
            }
            DensityProfile::PiecewiseLinear(table) => {
                let (first, last) = (table.altitudes_m[0], *table.altitudes_m.last().unwrap());
                let (a, b) = (a.max(first), b.min(last));
                if b <= a {
                    return 0.0;
                }
                integrate_layers(table, a, b, |h0, h1, r0, r1, x0, x1| {
                    let at = |x: f64| r0 + (x - h0) / (h1 - h0) * (r1 - r0);
                    0.5 * (at(x0) + at(x1)) * (x1 - x0)
                })
            }
            DensityProfile::LogLinear(table) => {
                integrate_layers(table, a, b, |h0, h1, r0, r1, x0, x1| {
                    // Within a layer rho = r0 exp(-(x - h0) / s) with
                    // 1/s = ln(r0 / r1) / (h1 - h0); its integral from x0 to
                    // x1 is exact. A layer of constant density has 1/s = 0.
                    let inverse_scale = (r0 / r1).ln() / (h1 - h0);
                    let rho_x0 = r0 * (-(x0 - h0) * inverse_scale).exp();
                    let width = x1 - x0;
                    if (inverse_scale * width).abs() < 1e-12 {
                        rho_x0 * width
                    } else {
                        rho_x0 * -(-width * inverse_scale).exp_m1() / inverse_scale
                    }
                })
            }
        }
    }

    /// The vertical column from the ground to `top_altitude_m`, m
    /// (the equivalent thickness of the species in the atmosphere).
    pub(crate) fn vertical_column_m(&self, top_altitude_m: f64) -> f64 {
        self.column_between_m(0.0, top_altitude_m)
    }

    /// A short description for listings ("exponential, H = 8000 m").
    pub fn describe(&self) -> String {
        match self {
            DensityProfile::Exponential { scale_height_m } => {
                format!("exponential, scale height {scale_height_m} m")
            }
            DensityProfile::PiecewiseLinear(table) => format!(
                "piecewise linear, {} rows from {} m to {} m",
                table.altitudes_m.len(),
                table.altitudes_m[0],
                table.altitudes_m.last().unwrap()
            ),
            DensityProfile::LogLinear(table) => format!(
                "log-linear table, {} rows from {} m to {} m",
                table.altitudes_m.len(),
                table.altitudes_m[0],
                table.altitudes_m.last().unwrap()
            ),
        }
    }
}

/// Sums `layer_integral(h0, h1, r0, r1, x0, x1)` over the pieces of [a, b]
/// cut at the table's rows; the end layers extend to infinity (the
/// log-linear profile continues them; the piecewise-linear one clips
/// [a, b] to the rows before calling).
fn integrate_layers(
    table: &ProfileTable,
    a: f64,
    b: f64,
    layer_integral: impl Fn(f64, f64, f64, f64, f64, f64) -> f64,
) -> f64 {
    let last_layer = table.altitudes_m.len() - 2;
    let mut total = 0.0;
    let mut x0 = a;
    let mut i = table.layer(a);
    loop {
        let (h0, h1, r0, r1) = table.layer_ends(i);
        let x1 = if i == last_layer { b } else { b.min(h1) };
        if x1 > x0 {
            total += layer_integral(h0, h1, r0, r1, x0, x1);
        }
        if x1 >= b || i == last_layer {
            break;
        }
        x0 = x1;
        i += 1;
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Composite Simpson quadrature with `n` (even) intervals.
    fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        let mut sum = f(a) + f(b);
        for i in 1..n {
            let x = a + i as f64 * h;
            sum += if i % 2 == 1 { 4.0 } else { 2.0 } * f(x);
        }
        sum * h / 3.0
    }

    fn midpoint(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        (0..n).map(|i| f(a + (i as f64 + 0.5) * h)).sum::<f64>() * h
    }

    #[test]
    fn the_squared_profile_is_the_square_of_the_density() {
        // Exponential and log-linear: exactly rho^2 at every height, and the
        // column is that of rho^2 (Simpson over the whole profile).
        let tent = DensityProfile::tent(25e3, 15e3, "t").unwrap();
        for profile in [
            DensityProfile::Exponential {
                scale_height_m: 8435.0,
            },
            us_1976_like(),
            tent.clone(),
        ] {
            let squared = profile.squared();
            for h in [0.0, 500.0, 7000.0, 11000.0, 33000.0, 90000.0] {
                let want = profile.relative_density(h).powi(2);
                let got = squared.relative_density(h);
                if matches!(profile, DensityProfile::PiecewiseLinear(_)) {
                    // At or above the square between rows (convexity).
                    assert!(got >= want - 1e-15, "{h}: {got} vs {want}");
                } else {
                    assert!((got / want - 1.0).abs() < 1e-12, "{h}: {got} vs {want}");
                }
            }
            let column = squared.vertical_column_m(100e3);
            let direct = simpson(|h| profile.relative_density(h).powi(2), 0.0, 100e3, 20000);
            if let DensityProfile::PiecewiseLinear(_) = profile {
                // The tent's rows (0, 1, 0) squared are the same tent: its
                // column 15 km against the square's 10 km (2/3 of it).
                assert!((column - 15e3).abs() < 1e-6 && (direct - 10e3).abs() < 1.0);
            } else {
                assert!((column / direct - 1.0).abs() < 1e-6, "{column} vs {direct}");
            }
        }
    }

    fn us_1976_like() -> DensityProfile {
        DensityProfile::LogLinear(
            ProfileTable::new(
                vec![0.0, 1000.0, 11000.0, 20000.0, 50000.0, 100000.0],
                vec![1.0, 0.907738, 0.297887, 0.0725892, 0.000838475, 4.66635e-07],
                true,
                "t",
            )
            .unwrap(),
        )
    }

    #[test]
    fn exponential_column_is_closed_form_and_matches_quadrature() {
        let profile = DensityProfile::exponential(8000.0, "h").unwrap();
        let exact = 8000.0 * (1.0 - (-100e3f64 / 8000.0).exp());
        assert!((profile.vertical_column_m(100e3) - exact).abs() < 1e-9 * exact);
        let numeric = simpson(|h| profile.relative_density(h), 0.0, 100e3, 20000);
        assert!((profile.vertical_column_m(100e3) - numeric).abs() < 1e-9 * numeric);
        // A thin slab keeps its relative accuracy: rho(50 km) * ~1 mm
        // (2^-10 m, so that both bounds are exact in binary).
        let width = 2f64.powi(-10);
        let thin = profile.column_between_m(50e3, 50e3 + width);
        let x = width / 8000.0;
        let expected = (-50e3f64 / 8000.0).exp() * width * (1.0 - x / 2.0 + x * x / 6.0);
        assert!(
            (thin - expected).abs() < 1e-9 * expected,
            "{thin} {expected}"
        );
    }

    #[test]
    fn tent_column_is_its_half_width() {
        let tent = DensityProfile::tent(25e3, 15e3, "o3").unwrap();
        assert_eq!(tent.relative_density(25e3), 1.0);
        assert_eq!(tent.relative_density(10e3), 0.0);
        assert_eq!(tent.relative_density(5e3), 0.0);
        assert!((tent.relative_density(17.5e3) - 0.5).abs() < 1e-15);
        assert!((tent.vertical_column_m(100e3) - 15e3).abs() < 1e-9);
        // Cut by the top of the atmosphere at 30 km: 7.5 km below the peak
        // side plus the trapezoid 25-30 km (mean density (1 + 2/3)/2).
        let cut = tent.vertical_column_m(30e3);
        let numeric = simpson(|h| tent.relative_density(h), 0.0, 30e3, 30000);
        assert!((cut - (7.5e3 + 5e3 * (1.0 + 2.0 / 3.0) / 2.0)).abs() < 1e-9);
        assert!((cut - numeric).abs() < 1e-6, "{cut} {numeric}");
    }

    #[test]
    fn piecewise_linear_column_matches_quadrature() {
        let layers = DensityProfile::PiecewiseLinear(
            ProfileTable::new(
                vec![0.0, 2000.0, 2500.0, 9000.0],
                vec![1.0, 1.0, 0.2, 0.0],
                false,
                "l",
            )
            .unwrap(),
        );
        for (a, b) in [
            (0.0, 100e3),
            (1000.0, 2200.0),
            (-50.0, 3000.0),
            (8000.0, 12000.0),
        ] {
            let exact = layers.column_between_m(a, b);
            // The kinks are at rows; split the quadrature there.
            let mut cuts = vec![a, b];
            cuts.extend(
                [0.0, 2000.0, 2500.0, 9000.0]
                    .iter()
                    .filter(|h| **h > a && **h < b),
            );
            cuts.sort_by(f64::total_cmp);
            // The midpoint rule is exact on each linear piece and never
            // evaluates the jump to 0 at the ends of the rows.
            let numeric: f64 = cuts
                .windows(2)
                .map(|w| midpoint(|h| layers.relative_density(h), w[0], w[1], 200))
                .sum();
            assert!(
                (exact - numeric).abs() < 1e-9 * numeric.max(1.0),
                "{a}-{b}: {exact} {numeric}"
            );
        }
        assert!(layers.relative_density(9001.0) == 0.0);
        assert!(layers.relative_density(-1.0) == 0.0);
    }

    #[test]
    fn log_linear_is_exponential_within_layers_and_its_column_is_exact() {
        let table = us_1976_like();
        // Geometric mean at the middle of a layer.
        let mid = table.relative_density(500.0);
        assert!((mid - (1.0f64 * 0.907738).sqrt()).abs() < 1e-12);
        assert!((table.relative_density(11000.0) - 0.297887).abs() < 1e-15);
        for (a, b) in [
            (0.0, 100e3),
            (0.0, 120e3),
            (3000.0, 15000.0),
            (-100.0, 500.0),
        ] {
            let exact = table.column_between_m(a, b);
            let mut cuts = vec![a, b];
            cuts.extend(
                [0.0, 1000.0, 11000.0, 20000.0, 50000.0, 100000.0]
                    .iter()
                    .filter(|h| **h > a && **h < b),
            );
            cuts.sort_by(f64::total_cmp);
            let numeric: f64 = cuts
                .windows(2)
                .map(|w| simpson(|h| table.relative_density(h), w[0], w[1], 2000))
                .sum();
            assert!(
                (exact - numeric).abs() < 1e-9 * numeric,
                "{a}-{b}: {exact} {numeric}"
            );
        }
        // Beyond the last row the last layer's exponential continues smoothly.
        let above = table.relative_density(100e3 + 1.0);
        assert!(above < 4.66635e-07 && above > 4.6e-07, "{above}");
    }

    #[test]
    fn constant_log_linear_layer_integrates_exactly() {
        let flat = DensityProfile::LogLinear(
            ProfileTable::new(vec![0.0, 10.0], vec![0.5, 0.5], true, "f").unwrap(),
        );
        assert!((flat.vertical_column_m(4.0) - 2.0).abs() < 1e-15);
        assert!((flat.column_between_m(4.0, 0.0) + 2.0).abs() < 1e-15);
    }

    #[test]
    fn invalid_profiles_name_the_key() {
        let e =
            DensityProfile::exponential(-8000.0, "species[0].profile.exponential.scale_height_m")
                .unwrap_err()
                .to_string();
        assert!(
            e.contains("species[0].profile.exponential.scale_height_m = -8000 m"),
            "{e}"
        );
        let e = DensityProfile::tent(25e3, 0.0, "p.tent")
            .unwrap_err()
            .to_string();
        assert!(e.contains("p.tent.half_width_m = 0 m"), "{e}");
        let e = ProfileTable::new(vec![0.0, 10.0, 5.0], vec![1.0, 1.0, 1.0], false, "p.layers")
            .unwrap_err()
            .to_string();
        assert!(e.contains("p.layers.altitude_m[2] = 5 m"), "{e}");
        let e = ProfileTable::new(vec![0.0, 10.0], vec![1.0, 0.0], true, "p.table")
            .unwrap_err()
            .to_string();
        assert!(e.contains("p.table.relative_density[1] = 0"), "{e}");
        assert!(ProfileTable::new(vec![0.0], vec![1.0], false, "p").is_err());
        assert!(ProfileTable::new(vec![0.0, 1.0], vec![1.0], false, "p").is_err());
        assert!(ProfileTable::new(vec![0.0, f64::NAN], vec![1.0, 1.0], false, "p").is_err());
    }
}
