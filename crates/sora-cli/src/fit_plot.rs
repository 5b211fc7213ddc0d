//! The picture of `sora retrieve --plot`: a retrieval's measured sky
//! radiances against its fitted ones, as an 8-bit RGB PNG, drawn by
//! `sora-plot` (the line plot of the docs' figures).
//!
//! Radiance on a log scale (the fit is in ln L) against the scattering
//! angle, one colour per wavelength; measured values as discs with their
//! 1-sigma error bars, the forward model at the retrieved state as lines.
//! A line joins the fitted values of one branch of the scan (one side of
//! an almucantar; the sun's side of a principal plane below or above the
//! sun, or its far side), in order of scattering angle, so that the two
//! sides of a principal plane are not zig-zagged into one line; a branch
//! of one point gets a short dash. The scan's label is the title; the
//! legend gives the wavelengths and chi^2 / N.

use sora::inversion::{FittedRadiance, Retrieval};
use sora::output::DisplayImage;
use sora_plot::{Axis, LinePlot, Marker, Series, log_ticks};

/// Image size, pixels.
pub const WIDTH: usize = 960;
/// See above.
pub const HEIGHT: usize = 640;

/// One colour per wavelength, shortest first: blue, green, orange, red,
/// then the rest of Tableau 10 (whose order is blue, orange, red, teal,
/// green, ...).
fn wavelength_colour(index: usize) -> [u8; 3] {
    const ORDER: [usize; 10] = [0, 4, 1, 2, 3, 5, 6, 7, 8, 9];
    let colour = colorous::TABLEAU10[ORDER[index % ORDER.len()]];
    [colour.r, colour.g, colour.b]
}

/// Which branch of a scan a measurement is on (see the module docs).
fn branch(r: &FittedRadiance) -> (i8, i64, i64) {
    let m = &r.measured;
    let relative = (m.view_azimuth_deg - m.sun_azimuth_deg + 540.0).rem_euclid(360.0) - 180.0;
    let tenths = |deg: f64| (deg * 10.0).round() as i64;
    let above_sun = m.view_elevation_deg > m.sun_elevation_deg;
    if relative.abs() < 0.5 {
        // The sun's vertical, on the sun's side: below or above the sun.
        (0, i64::from(above_sun), 0)
    } else if relative.abs() > 179.5 && (m.view_elevation_deg - m.sun_elevation_deg).abs() > 0.05 {
        // The sun's vertical, on the far side (a principal plane).
        (2, 0, 0)
    } else {
        // One side of an almucantar, or any set at one view elevation.
        (
            if relative > 0.0 { 1 } else { -1 },
            tenths(m.view_elevation_deg),
            tenths(m.sun_elevation_deg),
        )
    }
}

/// The plot of `retrieval`'s sky radiances (see the module docs).
pub fn fit_plot(retrieval: &Retrieval) -> anyhow::Result<DisplayImage<u8>> {
    let radiances = &retrieval.radiances;
    let mut wavelengths: Vec<f64> = radiances.iter().map(|r| r.measured.wavelength_nm).collect();
    wavelengths.sort_by(f64::total_cmp);
    wavelengths.dedup();

    // Ranges: scattering angle from 0 to a round step past the largest;
    // ln radiance over every point, error bar (its positive part) and fit.
    let largest_angle = radiances
        .iter()
        .map(|r| r.measured.scattering_angle_deg())
        .fold(0.0, f64::max);
    let angle_step = if largest_angle <= 60.0 {
        10.0
    } else if largest_angle <= 120.0 {
        20.0
    } else {
        30.0
    };
    let angle_max = ((largest_angle + 1.0) / angle_step).ceil() * angle_step;
    let mut low = f64::INFINITY;
    let mut high = f64::NEG_INFINITY;
    for r in radiances {
        let m = &r.measured;
        let lower = m.radiance_w_m2_sr_nm - m.uncertainty_w_m2_sr_nm;
        for value in [
            m.radiance_w_m2_sr_nm + m.uncertainty_w_m2_sr_nm,
            if lower > 0.0 {
                lower
            } else {
                m.radiance_w_m2_sr_nm
            },
            r.fitted_w_m2_sr_nm,
        ] {
            if value > 0.0 && value.is_finite() {
                low = low.min(value.ln());
                high = high.max(value.ln());
            }
        }
    }
    if !(low.is_finite() && high.is_finite()) {
        anyhow::bail!("--plot: no positive radiance to plot");
    }
    let pad = 0.06 * (high - low).max(0.2);
    let (low, high) = (low - pad, high + pad);

    let mut series = Vec::new();
    for (index, wavelength) in wavelengths.iter().enumerate() {
        let mut points: Vec<&FittedRadiance> = radiances
            .iter()
            .filter(|r| r.measured.wavelength_nm == *wavelength)
            .collect();
        points.sort_by(|a, b| {
            branch(a).cmp(&branch(b)).then(
                a.measured
                    .scattering_angle_deg()
                    .total_cmp(&b.measured.scattering_angle_deg()),
            )
        });
        // Fitted: a line per branch; measured: discs with 1-sigma error
        // bars (to the bottom of the plot where the lower end is not
        // positive).
        let lines = points
            .chunk_by(|a, b| branch(a) == branch(b))
            .map(|group| {
                group
                    .iter()
                    .map(|r| (r.measured.scattering_angle_deg(), r.fitted_w_m2_sr_nm.ln()))
                    .collect()
            })
            .collect();
        let error_bars = points
            .iter()
            .map(|r| {
                let m = &r.measured;
                let lower = m.radiance_w_m2_sr_nm - m.uncertainty_w_m2_sr_nm;
                (
                    m.scattering_angle_deg(),
                    if lower > 0.0 { lower.ln() } else { low },
                    (m.radiance_w_m2_sr_nm + m.uncertainty_w_m2_sr_nm).ln(),
                )
            })
            .collect();
        let markers = points
            .iter()
            .map(|r| {
                (
                    r.measured.scattering_angle_deg(),
                    r.measured.radiance_w_m2_sr_nm.ln(),
                )
            })
            .collect();
        series.push(Series {
            label: format!("{wavelength} nm"),
            colour: wavelength_colour(index),
            dashed: false,
            marker: Marker::Disc,
            lines,
            markers,
            error_bars,
        });
    }
    let figure = LinePlot {
        title: retrieval.label.clone(),
        x: Axis::linear(
            "scattering angle, deg",
            (0.0, angle_max),
            (0..=(angle_max / angle_step).round() as usize).map(|k| k as f64 * angle_step),
            0,
        ),
        y: Axis {
            label: if retrieval.radiance_scale.is_some() {
                "relative radiance (log scale)"
            } else {
                "radiance, W m^-2 sr^-1 nm^-1 (log scale)"
            }
            .into(),
            range: (low, high),
            ticks: log_ticks(low, high),
        },
        series,
        notes: vec![
            "o measured, +-1 sigma".into(),
            "- fitted".into(),
            format!(
                "chi^2/N {:.2}",
                retrieval.chi_square / retrieval.measurement_count.max(1) as f64
            ),
        ],
        text_scale: 1.5,
    };
    let (width, height, data) = figure.render(WIDTH, HEIGHT).into_rgb8();
    Ok(DisplayImage::new(width, height, data)?)
}
