//! The picture of `sora retrieve --plot`: a retrieval's measured sky
//! radiances against its fitted ones, as an 8-bit RGB PNG.
//!
//! Radiance on a log scale (the fit is in ln L) against the scattering
//! angle, one colour per wavelength; measured values as points with their
//! 1-sigma error bars, the forward model at the retrieved state as lines.
//! A line joins the fitted values of one branch of the scan (one side of
//! an almucantar; the sun's side of a principal plane below or above the
//! sun, or its far side), in order of scattering angle, so that the two
//! sides of a principal plane are not zig-zagged into one line; a branch
//! of one point gets a short dash. White background, dark text (the 8 x 8
//! bitmap font, `bitmap_text`), tick labels on both axes and a legend.

use sora::inversion::{FittedRadiance, Retrieval};
use sora::output::DisplayImage;

use crate::bitmap_text::{GLYPH_PIXELS, draw_text, text_width};

/// Image size, pixels.
pub const WIDTH: usize = 960;
/// See above.
pub const HEIGHT: usize = 640;
/// Text scale (16-pixel characters).
const TEXT: usize = 2;
/// The plot area's margins: left, right, top, bottom, pixels.
const MARGINS: (usize, usize, usize, usize) = (128, 24, 72, 88);

const BACKGROUND: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [32, 32, 32];
const GRID: [u8; 3] = [225, 225, 225];

/// One colour per wavelength, shortest first: blue, green, orange, red,
/// then the rest of Tableau 10 (whose order is blue, orange, red, teal,
/// green, ...).
fn wavelength_colour(index: usize) -> [u8; 3] {
    const ORDER: [usize; 10] = [0, 4, 1, 2, 3, 5, 6, 7, 8, 9];
    let colour = colorous::TABLEAU10[ORDER[index % ORDER.len()]];
    [colour.r, colour.g, colour.b]
}

/// An RGB canvas with the few primitives the plot needs.
struct Canvas {
    data: Vec<u8>,
    width: usize,
    height: usize,
    /// The rectangle drawing of data is clipped to: x0, y0, x1, y1
    /// (inclusive).
    clip: (i64, i64, i64, i64),
}

impl Canvas {
    fn new(width: usize, height: usize) -> Canvas {
        let mut data = vec![0u8; width * height * 3];
        for pixel in data.chunks_exact_mut(3) {
            pixel.copy_from_slice(&BACKGROUND);
        }
        Canvas {
            data,
            width,
            height,
            clip: (0, 0, width as i64 - 1, height as i64 - 1),
        }
    }

    fn set(&mut self, x: i64, y: i64, colour: [u8; 3]) {
        let (x0, y0, x1, y1) = self.clip;
        if x >= x0 && x <= x1 && y >= y0 && y <= y1 {
            let start = (y as usize * self.width + x as usize) * 3;
            self.data[start..start + 3].copy_from_slice(&colour);
        }
    }

    /// A line of `thickness` pixels between two points.
    fn line(&mut self, (xa, ya): (f64, f64), (xb, yb): (f64, f64), thickness: i64, c: [u8; 3]) {
        let steps = (xb - xa).abs().max((yb - ya).abs()).ceil().max(1.0) as i64;
        let (low, high) = (-(thickness - 1) / 2, thickness / 2);
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            let (x, y) = (
                (xa + t * (xb - xa)).round() as i64,
                (ya + t * (yb - ya)).round() as i64,
            );
            for dy in low..=high {
                for dx in low..=high {
                    self.set(x + dx, y + dy, c);
                }
            }
        }
    }

    /// A filled disc.
    fn disc(&mut self, (x, y): (f64, f64), radius: f64, c: [u8; 3]) {
        let r = radius.ceil() as i64;
        let (cx, cy) = (x.round() as i64, y.round() as i64);
        for dy in -r..=r {
            for dx in -r..=r {
                if ((dx * dx + dy * dy) as f64) <= radius * radius {
                    self.set(cx + dx, cy + dy, c);
                }
            }
        }
    }

    fn rectangle(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64), c: [u8; 3]) {
        for y in y0..=y1 {
            for x in x0..=x1 {
                self.set(x, y, c);
            }
        }
    }

    fn text(&mut self, (left, top): (usize, usize), text: &str, c: [u8; 3]) {
        draw_text(
            &mut self.data,
            (self.width, self.height),
            (left, top),
            TEXT,
            text,
            c,
        );
    }
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

/// Ticks of a log axis over ln values `low..=high`: (ln value, label).
fn log_ticks(low: f64, high: f64) -> Vec<(f64, String)> {
    let decades = (low / std::f64::consts::LN_10).floor() as i32 - 1
        ..=(high / std::f64::consts::LN_10).ceil() as i32 + 1;
    for mantissas in [&[1.0][..], &[1.0, 2.0, 5.0], &[1.0, 2.0, 3.0, 5.0, 7.0]] {
        let mut ticks = Vec::new();
        for exponent in decades.clone() {
            for &m in mantissas {
                let value = m * 10f64.powi(exponent);
                if (low..=high).contains(&value.ln()) {
                    let label = if (-4..=5).contains(&exponent) {
                        format!("{:.*}", (-exponent).max(0) as usize, value)
                    } else {
                        format!("{m}e{exponent}")
                    };
                    ticks.push((value.ln(), label));
                }
            }
        }
        if ticks.len() > 10 {
            // Every other decade.
            return ticks.into_iter().step_by(2).collect();
        }
        if ticks.len() >= 3 {
            return ticks;
        }
    }
    // Less than a factor of about 1.5: linear ticks at a round step.
    let (a, b) = (low.exp(), high.exp());
    let step = round_step((b - a) / 4.0);
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let mut ticks = Vec::new();
    let mut value = (a / step).ceil() * step;
    while value <= b {
        ticks.push((value.ln(), format!("{value:.decimals$}")));
        value += step;
    }
    ticks
}

/// 1, 2 or 5 times a power of ten, at least `step`.
fn round_step(step: f64) -> f64 {
    let power = 10f64.powf(step.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|s| *s >= step)
        .unwrap_or(10.0 * power)
}

/// The plot of `retrieval`'s sky radiances (see the module docs).
pub fn fit_plot(retrieval: &Retrieval) -> anyhow::Result<DisplayImage<u8>> {
    let (left, right, top, bottom) = MARGINS;
    let (x0, x1) = (left as f64, (WIDTH - right) as f64);
    let (y0, y1) = (top as f64, (HEIGHT - bottom) as f64);
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
    let px = |angle: f64| x0 + (x1 - x0) * angle / angle_max;
    let py = |ln: f64| y1 - (y1 - y0) * (ln - low) / (high - low);

    let mut canvas = Canvas::new(WIDTH, HEIGHT);
    let glyph = GLYPH_PIXELS * TEXT;
    // Grid and tick labels.
    let mut angle = 0.0;
    while angle <= angle_max + 1e-9 {
        canvas.line((px(angle), y0), (px(angle), y1), 1, GRID);
        let label = format!("{angle:.0}");
        let x = px(angle) as usize;
        canvas.text(
            (
                x.saturating_sub(text_width(&label, TEXT) / 2),
                y1 as usize + 8,
            ),
            &label,
            INK,
        );
        canvas.line((px(angle), y1), (px(angle), y1 + 5.0), 2, INK);
        angle += angle_step;
    }
    for (ln, label) in log_ticks(low, high) {
        canvas.line((x0, py(ln)), (x1, py(ln)), 1, GRID);
        canvas.line((x0 - 5.0, py(ln)), (x0, py(ln)), 2, INK);
        let width = text_width(&label, TEXT);
        canvas.text(
            (
                (x0 as usize).saturating_sub(width + 10),
                (py(ln) as usize).saturating_sub(glyph / 2),
            ),
            &label,
            INK,
        );
    }
    // Axes.
    canvas.line((x0, y0), (x0, y1), 2, INK);
    canvas.line((x0, y1), (x1, y1), 2, INK);
    canvas.line((x0, y0), (x1, y0), 1, INK);
    canvas.line((x1, y0), (x1, y1), 1, INK);
    // Titles: the scan above, the y axis's unit under it, the x axis below.
    let mut title = retrieval.label.clone();
    let room = (WIDTH - 16) / glyph;
    if title.chars().count() > room {
        title = title
            .chars()
            .take(room.saturating_sub(3))
            .collect::<String>()
            + "...";
    }
    canvas.text((8, 8), &title, INK);
    let unit = format!(
        "{} (log scale); chi^2/N {:.2}",
        if retrieval.radiance_scale.is_some() {
            "relative radiance"
        } else {
            "radiance, W m^-2 sr^-1 nm^-1"
        },
        retrieval.chi_square / retrieval.measurement_count.max(1) as f64
    );
    canvas.text((8, 8 + glyph + 12), &unit, INK);
    let x_label = "scattering angle, deg";
    canvas.text(
        (
            (x0 + x1) as usize / 2 - text_width(x_label, TEXT) / 2,
            HEIGHT - glyph - 12,
        ),
        x_label,
        INK,
    );

    // The data, clipped to the plot area.
    canvas.clip = (x0 as i64 + 1, y0 as i64 + 1, x1 as i64 - 1, y1 as i64 - 1);
    for (index, wavelength) in wavelengths.iter().enumerate() {
        let colour = wavelength_colour(index);
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
        // Fitted: a line per branch.
        for group in points.chunk_by(|a, b| branch(a) == branch(b)) {
            let xy: Vec<(f64, f64)> = group
                .iter()
                .map(|r| {
                    (
                        px(r.measured.scattering_angle_deg()),
                        py(r.fitted_w_m2_sr_nm.ln()),
                    )
                })
                .collect();
            if let [(x, y)] = xy[..] {
                canvas.line((x - 7.0, y), (x + 7.0, y), 2, colour);
            }
            for pair in xy.windows(2) {
                canvas.line(pair[0], pair[1], 2, colour);
            }
        }
        // Measured: points with 1-sigma error bars.
        for r in &points {
            let m = &r.measured;
            let x = px(m.scattering_angle_deg());
            let lower = m.radiance_w_m2_sr_nm - m.uncertainty_w_m2_sr_nm;
            let bar_low = if lower > 0.0 { py(lower.ln()) } else { y1 };
            let bar_high = py((m.radiance_w_m2_sr_nm + m.uncertainty_w_m2_sr_nm).ln());
            canvas.line((x, bar_low), (x, bar_high), 1, colour);
            canvas.line((x - 3.0, bar_low), (x + 3.0, bar_low), 1, colour);
            canvas.line((x - 3.0, bar_high), (x + 3.0, bar_high), 1, colour);
            canvas.disc((x, py(m.radiance_w_m2_sr_nm.ln())), 3.5, colour);
        }
    }

    // The legend, in the plot's top right corner.
    let rows: Vec<String> = wavelengths.iter().map(|w| format!("{w} nm")).collect();
    let notes = ["o measured, +-1 sigma", "- fitted"];
    let legend_width = rows
        .iter()
        .map(|r| text_width(r, TEXT) + 48)
        .chain(notes.iter().map(|n| text_width(n, TEXT)))
        .max()
        .unwrap_or(0)
        + 20;
    let row_height = glyph + 8;
    let legend_height = (rows.len() + notes.len()) * row_height + 12;
    let (lx1, ly0) = (x1 as i64 - 10, y0 as i64 + 10);
    let lx0 = lx1 - legend_width as i64;
    let ly1 = ly0 + legend_height as i64;
    canvas.rectangle((lx0, ly0), (lx1, ly1), BACKGROUND);
    for (a, b) in [
        ((lx0, ly0), (lx1, ly0)),
        ((lx0, ly1), (lx1, ly1)),
        ((lx0, ly0), (lx0, ly1)),
        ((lx1, ly0), (lx1, ly1)),
    ] {
        canvas.line((a.0 as f64, a.1 as f64), (b.0 as f64, b.1 as f64), 1, INK);
    }
    let labels: Vec<String> = rows
        .iter()
        .cloned()
        .chain(notes.iter().map(|n| n.to_string()))
        .collect();
    for (k, label) in labels.iter().enumerate() {
        let top = ly0 as usize + 8 + k * row_height;
        let middle = (top + glyph / 2) as f64;
        let mut text_left = lx0 as usize + 10;
        if k < rows.len() {
            let colour = wavelength_colour(k);
            let start = lx0 as f64 + 10.0;
            canvas.line((start, middle), (start + 32.0, middle), 2, colour);
            canvas.disc((start + 16.0, middle), 3.5, colour);
            text_left += 40;
        }
        canvas.text((text_left, top), label, INK);
    }
    Ok(DisplayImage::new(WIDTH, HEIGHT, canvas.data)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_round_and_inside() {
        let (low, high) = (0.001f64.ln(), 2.0f64.ln());
        let ticks = log_ticks(low, high);
        let labels: Vec<&str> = ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0.001", "0.01", "0.1", "1"]);
        // A narrow range: 1-2-5 or linear ticks, at least 3.
        let narrow = log_ticks(0.8f64.ln(), 1.25f64.ln());
        assert!(narrow.len() >= 3, "{narrow:?}");
        assert!(
            narrow
                .iter()
                .all(|(v, _)| (0.8f64.ln()..=1.25f64.ln()).contains(v))
        );
        assert_eq!(round_step(0.13), 0.2);
    }
}
