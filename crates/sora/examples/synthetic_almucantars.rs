//! Generates the closed-loop validation set of the aerosol retrieval
//! (`sora::inversion`): synthetic almucantars computed by the **path
//! tracer** (a different numerical method from the retrieval's forward
//! model, the fast discrete-ordinate method, so the test is not circular)
//! from known aerosols, plus measurement noise.
//!
//! ```sh
//! cargo run --release -p sora --example synthetic_almucantars -- \
//!     crates/sora/tests/data/retrieval [CASES] [PATHS]
//! ```
//!
//! writes `synthetic_almucantars.csv` (the measurements) and
//! `synthetic_truth.csv` (the true states and their optics) there.
//! Defaults: 50 cases, 20 000 paths per direction and wavelength.
//!
//! Each case (drawn by a fixed-seed generator, seed 2026, fixed before any
//! retrieval was run):
//! - optical depth at 440 nm log-uniform in 0.05-1.5;
//! - half the cases fine-dominated (fine volume fraction 0.45-0.85, as
//!   urban and smoke aerosols), half coarse-dominated (0.05-0.25, as dust);
//! - fine mode: volume median radius 0.12-0.2 um, width (sigma of ln r)
//!   0.38-0.55; coarse mode: 1.8-3.5 um, 0.55-0.75;
//! - refractive index n 1.36-1.58, k log-uniform 0.001-0.05, the same at
//!   every wavelength and in both modes;
//! - sun zenith angle 50-75 degrees, sun in the south.
//!
//! The truth's atmosphere is `earth-clear` (air, 300 DU of ozone, ground
//! albedo 0.1) with its aerosol replaced by two Mie species, one per mode
//! (number log-normals cut to 0.005-40 um, which holds all but 0.1 % of
//! their volume, through `sora-mie`'s adaptive
//! ensembles, not the retrieval's kernels), in an exponential profile of
//! scale height 1.2 km. The almucantar: 26 azimuths from the sun, 3.5 to
//! 160 degrees (AERONET's, one side), at 440, 675, 870 and 1020 nm, scalar
//! light. Noise: each radiance times (1 + 0.03 z), z standard normal; its
//! stated uncertainty is 3 % of the noisy value combined with the path
//! tracer's own standard error. The aerosol optical depths the retrieval
//! is given are the truth's plus normal noise of 0.01 (a sun
//! photometer's), stated as uncertainty 0.01.

use std::fmt::Write as _;

use sora::mie::Complex64;
use sora::mie::distribution::{RadiusQuadratureSettings, SizeDistribution};
use sora::mie::ensemble::compute_ensemble_cross_sections;
use sora::{Atmosphere, Method, Sky, ViewDirection, WavelengthGrid};

const WAVELENGTHS_NM: [f64; 4] = [440.0, 675.0, 870.0, 1020.0];
const AZIMUTHS_DEG: [f64; 26] = [
    3.5, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0,
    50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 120.0, 140.0, 160.0,
];
const SUN_AZIMUTH_DEG: f64 = 180.0;

/// SplitMix64 (Steele et al. 2014): a few lines, fixed-seed, portable.
struct Random(u64);

impl Random {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.uniform(lo.ln(), hi.ln()).exp()
    }
    /// Box-Muller.
    fn normal(&mut self) -> f64 {
        let u = self.uniform(f64::MIN_POSITIVE, 1.0);
        let v = self.uniform(0.0, 1.0);
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

struct Case {
    optical_depth_440: f64,
    fine: (f64, f64),
    coarse: (f64, f64),
    fine_volume_fraction: f64,
    n: f64,
    k: f64,
    sun_zenith_deg: f64,
}

/// Extinction per unit particle volume of a volume log-normal mode at
/// 440 nm, m^-1 (to split the optical depth between the modes).
fn extinction_per_volume(
    mode: (f64, f64),
    m: Complex64,
) -> Result<f64, Box<dyn std::error::Error>> {
    let (volume_median_um, s) = mode;
    let number_median_m = volume_median_um * 1e-6 * (-3.0 * s * s).exp();
    let mean_volume_m3 =
        4.0 / 3.0 * std::f64::consts::PI * number_median_m.powi(3) * (4.5 * s * s).exp();
    let distribution = SizeDistribution::log_normal(number_median_m, s.exp())?;
    let c = compute_ensemble_cross_sections(
        440.0,
        m,
        &distribution,
        &RadiusQuadratureSettings::cross_sections(),
    )?;
    Ok(c.extinction_cross_section_m2 / mean_volume_m3)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arguments: Vec<String> = std::env::args().skip(1).collect();
    let directory = std::path::PathBuf::from(
        arguments
            .first()
            .ok_or("usage: synthetic_almucantars DIRECTORY [CASES] [PATHS]")?,
    );
    let cases: usize = arguments.get(1).map_or(Ok(50), |s| s.parse())?;
    let paths: u64 = arguments.get(2).map_or(Ok(20_000), |s| s.parse())?;

    let base = include_str!("../../../atmospheres/earth-clear.toml");
    let base = &base[..base
        .find("[[species]]\nname = \"continental aerosol\"")
        .ok_or("earth-clear.toml: no continental aerosol block")?];

    let mut random = Random(2026);
    let mut measurements = String::from(
        "case,wavelength_nm,sun_elevation_deg,sun_azimuth_deg,view_elevation_deg,view_azimuth_deg,radiance_w_m2_sr_nm,uncertainty_w_m2_sr_nm,path_tracer_w_m2_sr_nm,path_tracer_standard_error_w_m2_sr_nm\n",
    );
    let mut truth = String::from(
        "case,sun_zenith_deg,aerosol_optical_depth_440,fine_volume_median_radius_um,fine_width,coarse_volume_median_radius_um,coarse_width,fine_volume_fraction,refractive_index_real,refractive_index_imaginary,fine_effective_radius_um,coarse_effective_radius_um,optical_depth_440,optical_depth_675,optical_depth_870,optical_depth_1020,single_scattering_albedo_440,single_scattering_albedo_675,single_scattering_albedo_870,single_scattering_albedo_1020,measured_optical_depth_440,measured_optical_depth_675,measured_optical_depth_870,measured_optical_depth_1020\n",
    );
    for index in 0..cases {
        let fine_dominated = index % 2 == 0;
        let case = Case {
            optical_depth_440: random.log_uniform(0.05, 1.5),
            fine: (random.uniform(0.12, 0.2), random.uniform(0.38, 0.55)),
            coarse: (random.uniform(1.8, 3.5), random.uniform(0.55, 0.75)),
            fine_volume_fraction: if fine_dominated {
                random.uniform(0.45, 0.85)
            } else {
                random.uniform(0.05, 0.25)
            },
            n: random.uniform(1.36, 1.58),
            k: random.log_uniform(0.001, 0.05),
            sun_zenith_deg: random.uniform(50.0, 75.0),
        };
        let m = Complex64::new(case.n, case.k);
        let fine_extinction = case.fine_volume_fraction * extinction_per_volume(case.fine, m)?;
        let coarse_extinction =
            (1.0 - case.fine_volume_fraction) * extinction_per_volume(case.coarse, m)?;
        let fine_depth =
            case.optical_depth_440 * fine_extinction / (fine_extinction + coarse_extinction);
        let mut toml = base.to_string();
        for (name, (r, s), depth) in [
            ("fine mode", case.fine, fine_depth),
            (
                "coarse mode",
                case.coarse,
                case.optical_depth_440 - fine_depth,
            ),
        ] {
            let number_median_um = r * (-3.0 * s * s).exp();
            writeln!(
                toml,
                "[[species]]\nname = \"{name}\"\noptical_depth = {depth:e}\nreference_wavelength_nm = 440\nprofile.exponential.scale_height_m = 1200\nscattering.mie.refractive_index = {{ n = {}, k = {} }}\nscattering.mie.size_distribution.lognormal = {{ median_radius_um = {number_median_um:e}, geometric_std_dev = {}, min_radius_um = 0.005, max_radius_um = 40 }}\nscattering.mie.phase = \"mie\"\n",
                case.n,
                case.k,
                s.exp()
            )?;
        }
        let atmosphere = Atmosphere::from_toml_str(&toml)?;
        let sun_elevation_deg = 90.0 - case.sun_zenith_deg;
        let views: Vec<ViewDirection> = AZIMUTHS_DEG
            .iter()
            .map(|a| ViewDirection::new(sun_elevation_deg, SUN_AZIMUTH_DEG + a))
            .collect::<Result<_, _>>()?;
        let mut depths = Vec::new();
        let mut albedos = Vec::new();
        for (w, &wavelength_nm) in WAVELENGTHS_NM.iter().enumerate() {
            let sky = Sky::builder(&atmosphere)
                .sun_deg(sun_elevation_deg, SUN_AZIMUTH_DEG)
                .wavelengths(WavelengthGrid::new(wavelength_nm, wavelength_nm, 1.0)?)
                .method(Method::PathTracing {
                    samples: paths,
                    seed: 1000 * index as u64 + w as u64,
                })
                .polarisation(sora::Polarisation::Scalar)
                .build()?;
            let (mut extinction, mut scattering) = (0.0, 0.0);
            for species in sky.optics().species.iter().filter(|s| s.kind == "mie") {
                extinction += species.optical_depth_extinction()[0];
                scattering += species.optical_depth_scattering()[0];
            }
            depths.push(extinction);
            albedos.push(scattering / extinction);
            for (view, radiance) in views.iter().zip(sky.radiances(&views)?) {
                let l = radiance.radiance_w_m2_sr_nm[0];
                let se = radiance
                    .standard_error_w_m2_sr_nm
                    .as_ref()
                    .ok_or("the path tracer reports standard errors")?[0];
                let noisy = l * (1.0 + 0.03 * random.normal());
                let uncertainty = (0.03f64.hypot(se / l)) * noisy;
                writeln!(
                    measurements,
                    "{index},{wavelength_nm},{sun_elevation_deg:.4},{SUN_AZIMUTH_DEG},{:.4},{:.4},{noisy:.6e},{uncertainty:.4e},{l:.6e},{se:.4e}",
                    view.elevation_deg(),
                    view.azimuth_deg()
                )?;
            }
        }
        let measured: Vec<f64> = depths.iter().map(|d| d + 0.01 * random.normal()).collect();
        let effective = |(r, s): (f64, f64)| r * (-0.5 * s * s).exp();
        writeln!(
            truth,
            "{index},{:.4},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.6},{:.5},{:.5},{},{},{}",
            case.sun_zenith_deg,
            case.optical_depth_440,
            case.fine.0,
            case.fine.1,
            case.coarse.0,
            case.coarse.1,
            case.fine_volume_fraction,
            case.n,
            case.k,
            effective(case.fine),
            effective(case.coarse),
            depths
                .iter()
                .map(|d| format!("{d:.6}"))
                .collect::<Vec<_>>()
                .join(","),
            albedos
                .iter()
                .map(|a| format!("{a:.6}"))
                .collect::<Vec<_>>()
                .join(","),
            measured
                .iter()
                .map(|d| format!("{d:.6}"))
                .collect::<Vec<_>>()
                .join(","),
        )?;
        eprintln!(
            "case {index}: tau(440) {:.3}, fine fraction {:.2}, k {:.4}, sun zenith {:.1}",
            case.optical_depth_440, case.fine_volume_fraction, case.k, case.sun_zenith_deg
        );
    }
    std::fs::create_dir_all(&directory)?;
    std::fs::write(directory.join("synthetic_almucantars.csv"), measurements)?;
    std::fs::write(directory.join("synthetic_truth.csv"), truth)?;
    Ok(())
}
