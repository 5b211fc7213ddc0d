//! Irradiance: the light that falls on a plane, from the same radiance
//! field as views and images.
//!
//! For a plane facing the unit normal n (horizontal: the zenith) and the
//! sun in the unit direction s:
//!
//! ```text
//! E_dir,n(lambda) = E_sun(lambda) T(eye -> sun, lambda)        direct normal
//! E_dir(lambda)   = E_dir,n max(0, n.s)                        direct on the plane
//! E_dif(lambda)   = integral over n.w > 0 of L(w, lambda) (n.w) dw
//! E_glo(lambda)   = E_dir + E_dif                              global
//! ```
//!
//! in W m^-2 nm^-1. T is the Beer-Lambert transmittance of the path to the
//! top of the atmosphere toward the sun's centre (0 when the planet is in
//! the way); the disc is treated as a point, as the sky's single scattering
//! is. L is the sky's radiance without the disc ([`super::Sky`]), so the
//! direct beam is counted once; for a tilted plane the half of its
//! hemisphere below the horizon sees the ground (sunlit and skylit, as the
//! sky's radiance there holds).
//!
//! # The hemisphere integral
//! In the plane's frame, w = mu n + sqrt(1 - mu^2) (cos phi u + sin phi v)
//! with u toward the sun's azimuth about n, E_dif = integral_0^2pi
//! integral_0^1 L mu dmu dphi: Gauss-Legendre in mu on [0, 1]
//! ([`MU_NODES`] nodes), and the periodic trapezoid rule (exponentially
//! convergent for a smooth periodic integrand) in phi ([`AZIMUTH_NODES`]
//! nodes, the first toward the sun). The fast method reads L from the
//! image tables (about a microsecond a direction; within 1e-3 of the exact
//! views); the reference method marches every direction (slow: bounded by
//! [`MAX_REFERENCE_IRRADIANCE_STEPS`], checked before any work); path
//! tracing estimates E_dif directly, cosine-weighted, with its standard
//! error ([`crate::transport::PathTracer::compute_irradiance`]).
//!
//! Broadband values ([`Irradiance::broadband_w_m2`]) sum over the grid with
//! its quadrature weights; illuminance ([`Irradiance::illuminance_lx`]) is
//! 683 lm/W times the CIE 1931 y-bar-weighted integral.

use super::{Method, Sky, SkyRadiance};
use crate::colour::{Observer, SpectrumToXyz};
use crate::error::{Error, Result};
use crate::geometry::{Vector3, ViewDirection};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};
use crate::transport::PathTracer;

/// Gauss-Legendre nodes in mu over the plane's hemisphere.
pub const MU_NODES: usize = 48;
/// Azimuth nodes around the plane's normal.
pub const AZIMUTH_NODES: usize = 96;

/// Most march steps of one plane's diffuse irradiance by the reference
/// method: the `MU_NODES` x `AZIMUTH_NODES` = 4,608 directions times
/// view steps times sun steps. 1e8 takes about 7 s a wavelength on the
/// project's 2-core machine (release build; 4,608 marches of the default
/// 1000 x 250 steps, 1.15e9, took 84 s at one wavelength), so the default
/// steps are refused: the fast method (the same integral over views
/// within 1e-3 of the reference march's) or path tracing (an independent
/// flux estimate with its standard error) answer in about a second.
pub const MAX_REFERENCE_IRRADIANCE_STEPS: f64 = 1e8;

/// Refuses, before any work, a reference-method irradiance whose march
/// exceeds [`MAX_REFERENCE_IRRADIANCE_STEPS`] (other methods pass).
pub fn check_irradiance_work(method: Method) -> Result<()> {
    if let Method::Reference {
        view_steps,
        sun_steps,
    } = method
    {
        let directions = MU_NODES * AZIMUTH_NODES;
        let steps = directions as f64 * view_steps as f64 * sun_steps as f64;
        if steps > MAX_REFERENCE_IRRADIANCE_STEPS {
            return Err(Error::out_of_range(
                format!(
                    "reference irradiance march ({directions} directions x {view_steps} view steps x {sun_steps} sun steps)"
                ),
                steps,
                "steps",
                format!(
                    "<= {MAX_REFERENCE_IRRADIANCE_STEPS:e} (about 7 s a wavelength): use the fast method (within 1e-3 of the reference views) or path tracing, or fewer reference steps"
                ),
            ));
        }
    }
    Ok(())
}

/// A plane's orientation: tilted `tilt_deg` from horizontal (0: facing the
/// zenith, 90: vertical) toward `azimuth_deg` (clockwise from north: the
/// direction its normal leans to).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    tilt_deg: f64,
    azimuth_deg: f64,
}

impl Plane {
    /// A horizontal plane facing up.
    pub const HORIZONTAL: Plane = Plane {
        tilt_deg: 0.0,
        azimuth_deg: 0.0,
    };

    /// A plane tilted `tilt_deg` (0..=180) toward `azimuth_deg`.
    pub fn new(tilt_deg: f64, azimuth_deg: f64) -> Result<Plane> {
        if !(0.0..=180.0).contains(&tilt_deg) {
            return Err(Error::out_of_range(
                "plane tilt",
                tilt_deg,
                "deg",
                "0..=180",
            ));
        }
        if !azimuth_deg.is_finite() {
            return Err(Error::out_of_range(
                "plane azimuth",
                azimuth_deg,
                "deg",
                "a finite angle",
            ));
        }
        Ok(Plane {
            tilt_deg,
            azimuth_deg,
        })
    }

    /// The unit normal, east-north-up.
    pub fn normal(self) -> Vector3 {
        crate::geometry::direction_from_elevation_azimuth(90.0 - self.tilt_deg, self.azimuth_deg)
    }
}

/// The irradiance on one plane, W m^-2 nm^-1 on the sky's grid (see the
/// module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Irradiance {
    /// E_sun T toward the sun, on a plane facing it.
    pub direct_normal_w_m2_nm: SampledSpectrum,
    /// T, the direct beam's transmittance from the top of the atmosphere.
    pub direct_beam_transmittance: SampledSpectrum,
    /// The direct beam on the plane.
    pub direct_w_m2_nm: SampledSpectrum,
    /// The sky (and, tilted, the ground) on the plane.
    pub diffuse_w_m2_nm: SampledSpectrum,
    /// The standard error of the diffuse part (path tracing only).
    pub diffuse_standard_error_w_m2_nm: Option<SampledSpectrum>,
    /// Direct plus diffuse.
    pub global_w_m2_nm: SampledSpectrum,
}

impl Irradiance {
    /// sum_j w_j times each part, field by field and sample by sample (the
    /// k-distribution's sum over its terms, `atmosphere::gas_bands`, w_j a
    /// weight per sample; the parts on one grid). A standard error adds as
    /// sum_j w_j se_j, the bound for errors that may be correlated (the
    /// terms are traced with one seed).
    pub fn weighted_sum(parts: &[(SampledSpectrum, Irradiance)]) -> Irradiance {
        let sum = |field: fn(&Irradiance) -> &SampledSpectrum| {
            SampledSpectrum::weighted_sum(parts.iter().map(|(w, p)| (w, field(p))))
        };
        Irradiance {
            direct_normal_w_m2_nm: sum(|p| &p.direct_normal_w_m2_nm),
            direct_beam_transmittance: sum(|p| &p.direct_beam_transmittance),
            direct_w_m2_nm: sum(|p| &p.direct_w_m2_nm),
            diffuse_w_m2_nm: sum(|p| &p.diffuse_w_m2_nm),
            diffuse_standard_error_w_m2_nm: parts
                .iter()
                .map(|(w, p)| p.diffuse_standard_error_w_m2_nm.as_ref().map(|e| (w, e)))
                .collect::<Option<Vec<_>>>()
                .map(SampledSpectrum::weighted_sum),
            global_w_m2_nm: sum(|p| &p.global_w_m2_nm),
        }
    }

    /// The spectral values integrated over `grid` (the sky's), W m^-2.
    pub fn broadband_w_m2(spectrum: &SampledSpectrum, grid: &WavelengthGrid) -> f64 {
        (0..grid.len())
            .map(|i| spectrum[i] * grid.quadrature_weight_nm(i))
            .sum()
    }

    /// Illuminance of a spectral irradiance on `grid`, lux (CIE 1931
    /// 2-degree observer, 683 lm/W).
    pub fn illuminance_lx(spectrum: &SampledSpectrum, grid: &WavelengthGrid) -> Result<f64> {
        Ok(SpectrumToXyz::new(grid, Observer::Cie1931TwoDegree)
            .to_xyz(spectrum)?
            .luminance_cd_m2())
    }
}

impl Sky {
    /// The irradiance on `plane` (see the module docs).
    pub fn irradiance(&self, plane: Plane) -> Result<Irradiance> {
        check_irradiance_work(self.method)?;
        if !self.k_terms.is_empty() {
            return self.sum_term_irradiance(|term| term.irradiance(plane));
        }
        let normal = plane.normal();
        let sun = self.sun_direction();
        let transmittance = self.direct_beam_transmittance();
        let direct_normal = self.direct_normal_irradiance();
        let mut direct = direct_normal.clone();
        direct *= normal.dot(sun).max(0.0);
        let (diffuse, standard_error) = self.compute_diffuse_irradiance(normal)?;
        let mut global = direct.clone();
        global.add_scaled(&diffuse, 1.0);
        Ok(Irradiance {
            direct_normal_w_m2_nm: direct_normal,
            direct_beam_transmittance: transmittance,
            direct_w_m2_nm: direct,
            diffuse_w_m2_nm: diffuse,
            diffuse_standard_error_w_m2_nm: standard_error,
            global_w_m2_nm: global,
        })
    }

    /// E_dif on the plane facing `normal`, and its standard error when
    /// path tracing.
    fn compute_diffuse_irradiance(
        &self,
        normal: Vector3,
    ) -> Result<(SampledSpectrum, Option<SampledSpectrum>)> {
        if let Method::PathTracing { samples, seed } = self.method {
            let traced = PathTracer::new(&self.scene).compute_irradiance(normal, samples, seed)?;
            return Ok((traced.total.mean, Some(traced.total.standard_error)));
        }
        let views = hemisphere_views(normal, self.sun_direction())?;
        let directions: Vec<ViewDirection> = views.iter().map(|(v, _)| *v).collect();
        let radiances: Vec<SkyRadiance> = match self.method {
            Method::Fast => self.radiances_from_image_tables(&directions, &|_, _| {})?,
            _ => self.radiances(&directions)?,
        };
        let mut diffuse = SampledSpectrum::zeros(self.wavelengths().len());
        for ((_, weight), radiance) in views.iter().zip(&radiances) {
            diffuse.add_scaled(&radiance.radiance_w_m2_sr_nm, *weight);
        }
        Ok((diffuse, None))
    }
}

/// The quadrature directions over the hemisphere about `normal` and their
/// weights (sr, each times mu), the first azimuth toward `sun`'s.
fn hemisphere_views(normal: Vector3, sun: Vector3) -> Result<Vec<(ViewDirection, f64)>> {
    // u: the sun's direction projected on the plane (any perpendicular
    // when the sun is along the normal).
    let along = sun - normal * sun.dot(normal);
    let u = if along.length() > 1e-9 {
        along.normalized()
    } else {
        let helper = if normal.z.abs() < 0.9 {
            Vector3::new(0.0, 0.0, 1.0)
        } else {
            Vector3::new(0.0, 1.0, 0.0)
        };
        (helper - normal * helper.dot(normal)).normalized()
    };
    let v = normal.cross(u);
    let (nodes, weights) = sora_mie::quadrature::gauss_legendre(MU_NODES);
    let azimuth_weight = 2.0 * std::f64::consts::PI / AZIMUTH_NODES as f64;
    let mut views = Vec::with_capacity(MU_NODES * AZIMUTH_NODES);
    for (t, w) in nodes.iter().zip(&weights) {
        // [-1, 1] -> mu in [0, 1].
        let mu = 0.5 * (t + 1.0);
        let sine = (1.0 - mu * mu).max(0.0).sqrt();
        for k in 0..AZIMUTH_NODES {
            let phi = azimuth_weight * k as f64;
            let w_dir = normal * mu + (u * phi.cos() + v * phi.sin()) * sine;
            let (elevation, azimuth) = crate::geometry::elevation_azimuth_from_direction(w_dir);
            views.push((
                ViewDirection::new(elevation.clamp(-90.0, 90.0), azimuth)?,
                0.5 * w * mu * azimuth_weight,
            ));
        }
    }
    Ok(views)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The limit at its edge and one past it; the default steps (the
    /// command line's `--method reference`) are refused in one line.
    #[test]
    fn reference_irradiance_work_is_bounded_before_any_work() {
        let march = |view_steps, sun_steps| Method::Reference {
            view_steps,
            sun_steps,
        };
        // 4608 x 217 x 100 = 9.999e7; 4608 x 218 x 100 = 1.0045e8.
        assert!(check_irradiance_work(march(217, 100)).is_ok());
        let message = check_irradiance_work(march(218, 100))
            .unwrap_err()
            .to_string();
        assert!(
            message.starts_with(
                "reference irradiance march (4608 directions x 218 view steps x 100 sun steps) = 1.004544e8 steps is out of range: allowed <= 1e8"
            ),
            "{message}"
        );
        let message = check_irradiance_work(Method::REFERENCE_DEFAULT)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("1000 view steps x 250 sun steps) = 1.152e9 steps")
                && message.contains("use the fast method")
                && !message.contains('\n'),
            "{message}"
        );
        assert!(check_irradiance_work(Method::Fast).is_ok());
        assert!(
            check_irradiance_work(Method::PathTracing {
                samples: 100,
                seed: 1
            })
            .is_ok()
        );
    }
}
