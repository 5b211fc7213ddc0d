//! The aerosol a retrieval fits, its bounds, and the unconstrained
//! coordinates the fit moves in.
//!
//! The state is AERONET's bimodal description (Dubovik et al. 2006 use the
//! same two log-normal modes for their retrieved products):
//! - the aerosol optical depth tau at a reference wavelength;
//! - a volume size distribution of two log-normal modes,
//!
//!   ```text
//!       dV/d ln r = sum_{mode} c_mode / (sqrt(2 pi) s_mode)
//!                   exp(-(ln r - ln r_mode)^2 / (2 s_mode^2))
//!   ```
//!
//!   with r_mode the volume median radius (um) and s_mode the standard
//!   deviation of ln r (so sigma_g = exp(s)); c_fine = f, c_coarse = 1 - f
//!   with f the fine mode's fraction of the volume;
//! - a complex refractive index n + ik for both modes: here the one at
//!   the reference wavelength. The retrieval fits one per measured
//!   wavelength, smooth in wavelength, as AERONET does (or, with
//!   `IndexSpectrum::One`, one for every wavelength: `mod.rs`); each
//!   wavelength's has these bounds and this a priori.
//!
//! Each parameter lives in a bounded interval (below); the fit moves in
//! `t = logit((g(x) - g(lo)) / (g(hi) - g(lo)))`, g = ln for the positive
//! parameters that span decades and g = identity otherwise, so that every
//! step stays inside the bounds. The a priori is the middle of each
//! interval in t with a standard deviation of [`PRIOR_SIGMA`] in t: weak
//! (about the interval's middle 90 % at 1 sigma), enough to keep
//! parameters the measurements do not constrain (the refractive index at
//! a small optical depth) where they are plausible and their posterior
//! uncertainty honest.

use crate::error::{Error, Result};

/// One log-normal mode of the volume size distribution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogNormalMode {
    /// Volume median radius, um.
    pub volume_median_radius_um: f64,
    /// Standard deviation of ln r (ln of the geometric standard deviation).
    pub width: f64,
}

impl LogNormalMode {
    /// The mode's effective radius (area-weighted mean radius, Hansen &
    /// Travis 1974), um: r_eff = r_v exp(-s^2 / 2) for a volume log-normal.
    pub fn effective_radius_um(&self) -> f64 {
        self.volume_median_radius_um * (-0.5 * self.width * self.width).exp()
    }

    /// dV/d ln r of one unit of volume at `radius_um`.
    pub fn volume_per_ln_radius(&self, radius_um: f64) -> f64 {
        let z = (radius_um / self.volume_median_radius_um).ln() / self.width;
        (-0.5 * z * z).exp() / ((2.0 * std::f64::consts::PI).sqrt() * self.width)
    }
}

/// The aerosol of a retrieval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AerosolState {
    /// Aerosol extinction optical depth at the reference wavelength.
    pub optical_depth: f64,
    /// The fine mode.
    pub fine: LogNormalMode,
    /// The coarse mode.
    pub coarse: LogNormalMode,
    /// The fine mode's fraction of the particle volume.
    pub fine_volume_fraction: f64,
    /// Real part of the refractive index.
    pub refractive_index_real: f64,
    /// Imaginary part of the refractive index (absorption).
    pub refractive_index_imaginary: f64,
}

/// The fitted parameters, in the order of the state vector.
pub const PARAMETER_NAMES: [&str; 8] = [
    "aerosol_optical_depth",
    "fine_volume_median_radius_um",
    "fine_width",
    "coarse_volume_median_radius_um",
    "coarse_width",
    "fine_volume_fraction",
    "refractive_index_real",
    "refractive_index_imaginary",
];

/// How many parameters the aerosol has.
pub const PARAMETERS: usize = PARAMETER_NAMES.len();

/// A parameter's bounds (exclusive) and whether it is fitted in ln.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// Fitted in ln (parameters that span decades).
    pub logarithmic: bool,
}

/// The bounds of each parameter, in [`PARAMETER_NAMES`]' order: optical
/// depth 0.001-5; fine mode 0.07-0.6 um wide 0.25-0.8 (sigma_g 1.28-2.2);
/// coarse mode 0.7-8 um wide 0.35-1.0; fine volume fraction 0.01-0.99;
/// n 1.33-1.65 (water to dust and soot mixtures); k 0.0003-0.1. AERONET's
/// version 3 limits are n 1.33-1.6 and k 0.0005-0.5 (Sinyuk et al. 2020).
pub const BOUNDS: [Bounds; PARAMETERS] = [
    Bounds {
        lower: 0.001,
        upper: 5.0,
        logarithmic: true,
    },
    Bounds {
        lower: 0.07,
        upper: 0.6,
        logarithmic: true,
    },
    Bounds {
        lower: 0.25,
        upper: 0.8,
        logarithmic: false,
    },
    Bounds {
        lower: 0.7,
        upper: 8.0,
        logarithmic: true,
    },
    Bounds {
        lower: 0.35,
        upper: 1.0,
        logarithmic: false,
    },
    Bounds {
        lower: 0.01,
        upper: 0.99,
        logarithmic: false,
    },
    Bounds {
        lower: 1.33,
        upper: 1.65,
        logarithmic: false,
    },
    Bounds {
        lower: 0.0003,
        upper: 0.1,
        logarithmic: true,
    },
];

/// The a priori's standard deviation in the fit's coordinates (logit
/// units; the middle 68 % of the a priori spans 0.18-0.82 of the
/// interval in g).
pub const PRIOR_SIGMA: f64 = 1.5;

impl Bounds {
    fn g(&self, x: f64) -> f64 {
        if self.logarithmic { x.ln() } else { x }
    }

    /// The fit's coordinate of `x` (inside the bounds).
    pub fn to_fit(&self, x: f64) -> f64 {
        let u = (self.g(x) - self.g(self.lower)) / (self.g(self.upper) - self.g(self.lower));
        (u / (1.0 - u)).ln()
    }

    /// The value of fit coordinate `t`.
    pub fn from_fit(&self, t: f64) -> f64 {
        let u = 1.0 / (1.0 + (-t).exp());
        let g = self.g(self.lower) + u * (self.g(self.upper) - self.g(self.lower));
        // Rounding in exp must not step outside the bounds.
        let x = if self.logarithmic { g.exp() } else { g };
        x.clamp(self.lower, self.upper)
    }

    /// dx/dt at fit coordinate `t` (to carry uncertainties from t to x).
    pub fn derivative(&self, t: f64) -> f64 {
        let u = 1.0 / (1.0 + (-t).exp());
        let dg = u * (1.0 - u) * (self.g(self.upper) - self.g(self.lower));
        if self.logarithmic {
            dg * self.from_fit(t)
        } else {
            dg
        }
    }
}

impl AerosolState {
    /// The parameters in [`PARAMETER_NAMES`]' order.
    pub fn to_array(self) -> [f64; PARAMETERS] {
        [
            self.optical_depth,
            self.fine.volume_median_radius_um,
            self.fine.width,
            self.coarse.volume_median_radius_um,
            self.coarse.width,
            self.fine_volume_fraction,
            self.refractive_index_real,
            self.refractive_index_imaginary,
        ]
    }

    /// From parameters in [`PARAMETER_NAMES`]' order (unchecked).
    pub fn from_array(p: [f64; PARAMETERS]) -> AerosolState {
        AerosolState {
            optical_depth: p[0],
            fine: LogNormalMode {
                volume_median_radius_um: p[1],
                width: p[2],
            },
            coarse: LogNormalMode {
                volume_median_radius_um: p[3],
                width: p[4],
            },
            fine_volume_fraction: p[5],
            refractive_index_real: p[6],
            refractive_index_imaginary: p[7],
        }
    }

    /// An error naming the first parameter outside its bounds.
    pub fn check_bounds(&self) -> Result<()> {
        for ((name, value), bounds) in PARAMETER_NAMES.iter().zip(self.to_array()).zip(BOUNDS) {
            if !(value > bounds.lower && value < bounds.upper) {
                return Err(Error::out_of_range(
                    *name,
                    value,
                    if name.ends_with("_um") { "um" } else { "1" },
                    format!("{}..{} (exclusive)", bounds.lower, bounds.upper),
                ));
            }
        }
        Ok(())
    }

    /// The fit's coordinates of this state.
    pub(crate) fn to_fit(self) -> [f64; PARAMETERS] {
        let p = self.to_array();
        std::array::from_fn(|i| BOUNDS[i].to_fit(p[i]))
    }

    /// The state at fit coordinates `t`.
    pub(crate) fn from_fit(t: &[f64]) -> AerosolState {
        AerosolState::from_array(std::array::from_fn(|i| BOUNDS[i].from_fit(t[i])))
    }

    /// The a priori: the middle of every interval (in the fit's
    /// coordinates, t = 0).
    pub fn a_priori() -> AerosolState {
        AerosolState::from_fit(&[0.0; PARAMETERS])
    }

    /// dV/d ln r of the whole distribution (unit total volume, before the
    /// truncation to the kernels' radius range) at `radius_um`.
    pub fn volume_per_ln_radius(&self, radius_um: f64) -> f64 {
        self.fine_volume_fraction * self.fine.volume_per_ln_radius(radius_um)
            + (1.0 - self.fine_volume_fraction) * self.coarse.volume_per_ln_radius(radius_um)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_coordinates_round_trip_and_stay_inside_the_bounds() {
        let state = AerosolState {
            optical_depth: 0.37,
            fine: LogNormalMode {
                volume_median_radius_um: 0.16,
                width: 0.42,
            },
            coarse: LogNormalMode {
                volume_median_radius_um: 2.8,
                width: 0.66,
            },
            fine_volume_fraction: 0.3,
            refractive_index_real: 1.47,
            refractive_index_imaginary: 0.008,
        };
        state.check_bounds().unwrap();
        let back = AerosolState::from_fit(&state.to_fit());
        for (a, b) in state.to_array().iter().zip(back.to_array()) {
            assert!((a - b).abs() < 1e-12 * a.abs(), "{a} {b}");
        }
        // Far steps in t still give states inside the bounds.
        for t in [-40.0, 40.0] {
            let s = AerosolState::from_fit(&[t; PARAMETERS]);
            for (x, b) in s.to_array().iter().zip(BOUNDS) {
                assert!(*x >= b.lower && *x <= b.upper);
            }
        }
        // The derivative against a central difference.
        for (i, b) in BOUNDS.iter().enumerate() {
            let t = state.to_fit()[i];
            let numeric = (b.from_fit(t + 1e-6) - b.from_fit(t - 1e-6)) / 2e-6;
            assert!((b.derivative(t) - numeric).abs() < 1e-6 * numeric.abs());
        }
    }

    #[test]
    fn a_volume_mode_has_unit_volume_and_its_effective_radius() {
        let mode = LogNormalMode {
            volume_median_radius_um: 0.2,
            width: 0.5,
        };
        let h = 1e-3;
        let (mut volume, mut area, mut radius_area) = (0.0, 0.0, 0.0);
        for i in -8000..8000 {
            let r = 0.2 * (i as f64 * h).exp();
            let v = mode.volume_per_ln_radius(r) * h;
            volume += v;
            // Number ~ v / r^3, area ~ v / r, area-weighted radius ~ v.
            area += v / r;
            radius_area += v;
        }
        assert!((volume - 1.0).abs() < 1e-10);
        assert!((radius_area / area - mode.effective_radius_um()).abs() < 1e-10);
    }
}
