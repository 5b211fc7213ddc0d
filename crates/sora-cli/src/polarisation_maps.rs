//! The degree- and angle-of-polarisation maps of `sora render --dolp` and
//! `--aop`: 8-bit sRGB pictures of a polarised sky's broadband
//! polarisation, each with a legend (a colour bar, its scale and a title)
//! below the image.
//!
//! What is mapped, per pixel: the degree of linear polarisation
//! sqrt(Q^2 + U^2) / I and the angle of polarisation 0.5 atan2(U, Q) of
//! the luminance-weighted Stokes vector (the Y of the XYZ of I, Q and U,
//! i.e. what a polarisation camera with the eye's spectral response
//! measures), Q and U referred to each pixel's meridian plane, the angle
//! from the vertical toward the observer's left (`docs/polarisation.md`).
//!
//! Colour maps, both perceptual:
//! - degree 0..1: viridis (van der Walt & Smith 2015; `colorous`);
//! - angle -90..90 degrees, a cyclic quantity: a hue circle at constant
//!   lightness and chroma in Oklab (Ottosson 2020), L = 0.72, C = 0.11,
//!   hue = twice the angle, so that -90 and 90 degrees (the same
//!   polarisation) meet and no angle looks brighter than another. Written
//!   here because `colorous` has no perceptually uniform cyclic map.
//!
//! Pixels the camera does not see, and wholly unpolarised ones for the
//! angle, are black. The legend's text is the plots' 8 x 8 bitmap font
//! (`sora_plot::text`), at twice its size when the image is wide enough.

use sora::colour::{TransferCurve, Xyz};
use sora::output::DisplayImage;

use sora_plot::text::draw_text;

/// The legend's text colour.
const WHITE: [u8; 3] = [255, 255, 255];

/// Height of the legend strip below the image, pixels (at text scale 2).
const LEGEND_ROWS: usize = 64;

/// The luminance-weighted degree of linear polarisation of each pixel's
/// Stokes XYZ (None where the camera sees nothing).
pub fn degrees(stokes: &[[Xyz; 4]]) -> Vec<Option<f64>> {
    stokes
        .iter()
        .map(|[i, q, u, _]| (i.y > 0.0).then(|| (q.y.hypot(u.y) / i.y).min(1.0)))
        .collect()
}

/// The luminance-weighted angle of polarisation of each pixel, degrees in
/// (-90, 90] (None where the camera sees nothing or the light is wholly
/// unpolarised).
pub fn angles_deg(stokes: &[[Xyz; 4]]) -> Vec<Option<f64>> {
    stokes
        .iter()
        .map(|[i, q, u, _]| {
            (i.y > 0.0 && (q.y != 0.0 || u.y != 0.0)).then(|| {
                let angle = 0.5 * u.y.atan2(q.y).to_degrees();
                if angle <= -90.0 { angle + 180.0 } else { angle }
            })
        })
        .collect()
}

/// The degree map: viridis over 0..1, with its legend.
pub fn degree_map(
    degrees: &[Option<f64>],
    width: usize,
    height: usize,
) -> anyhow::Result<DisplayImage<u8>> {
    let (rows, data) = compose(
        degrees,
        (width, height),
        viridis,
        (0.0, 1.0),
        &["0", "0.25", "0.5", "0.75", "1"],
        "degree of linear polarisation",
    );
    Ok(DisplayImage::new(width, rows, data)?)
}

/// The angle map: the Oklab hue circle over -90..90 degrees, with its
/// legend.
pub fn angle_map(
    angles_deg: &[Option<f64>],
    width: usize,
    height: usize,
) -> anyhow::Result<DisplayImage<u8>> {
    let (rows, data) = compose(
        angles_deg,
        (width, height),
        cyclic,
        (-90.0, 90.0),
        &["-90", "-45", "0", "45", "90"],
        "angle of polarisation, deg from vertical",
    );
    Ok(DisplayImage::new(width, rows, data)?)
}

/// Viridis at t in 0..1, 8-bit sRGB.
fn viridis(t: f64) -> [u8; 3] {
    let colour = colorous::VIRIDIS.eval_continuous(t.clamp(0.0, 1.0));
    [colour.r, colour.g, colour.b]
}

/// The cyclic map at t in 0..1 (the angle's place in -90..90 degrees):
/// Oklab L = 0.72, C = 0.11, hue 2 pi t, to 8-bit sRGB (Ottosson's Oklab
/// to linear sRGB, clipped to the gamut).
fn cyclic(t: f64) -> [u8; 3] {
    let (b, a) = (std::f64::consts::TAU * t).sin_cos();
    let (lightness, a, b) = (0.72, 0.11 * a, 0.11 * b);
    let l = (lightness + 0.396_337_777_4 * a + 0.215_803_757_3 * b).powi(3);
    let m = (lightness - 0.105_561_345_8 * a - 0.063_854_172_8 * b).powi(3);
    let s = (lightness - 0.089_484_177_5 * a - 1.291_485_548_0 * b).powi(3);
    let linear = [
        4.076_741_662_1 * l - 3.307_711_591_3 * m + 0.230_969_929_2 * s,
        -1.268_438_004_6 * l + 2.609_757_401_1 * m - 0.341_319_396_5 * s,
        -0.004_196_086_3 * l - 0.703_418_614_7 * m + 1.707_614_701_0 * s,
    ];
    linear.map(|c| (255.0 * TransferCurve::Srgb.encode(c).clamp(0.0, 1.0)).round() as u8)
}

/// The image of `values` through `colour_map` over `range`, with a legend
/// strip below it: the colour bar, `labels` spread evenly under it, and
/// `title`. Returns its rows and its interleaved 8-bit RGB samples.
fn compose(
    values: &[Option<f64>],
    (width, height): (usize, usize),
    colour_map: fn(f64) -> [u8; 3],
    (low, high): (f64, f64),
    labels: &[&str],
    title: &str,
) -> (usize, Vec<u8>) {
    let scale = if width >= 320 { 2 } else { 1 };
    let legend_rows = LEGEND_ROWS * scale / 2;
    let rows = height + legend_rows;
    let mut data = vec![0u8; width * rows * 3];
    for (pixel, value) in data.chunks_exact_mut(3).zip(values) {
        if let Some(value) = value {
            pixel.copy_from_slice(&colour_map((value - low) / (high - low)));
        }
    }
    // The colour bar, with a margin for the end labels.
    let margin = (width / 10).min(48 * scale).max(1);
    let bar_width = width.saturating_sub(2 * margin).max(1);
    let bar_top = height + 4 * scale;
    let bar_rows = 8 * scale;
    for row in bar_top..(bar_top + bar_rows).min(rows) {
        for column in margin..(margin + bar_width).min(width) {
            let t = (column - margin) as f64 / (bar_width.max(2) - 1) as f64;
            let start = (row * width + column) * 3;
            data[start..start + 3].copy_from_slice(&colour_map(t));
        }
    }
    // Tick labels centred under their places on the bar, then the title.
    let label_top = bar_top + bar_rows + 2 * scale;
    for (k, label) in labels.iter().enumerate() {
        let centre = margin + k * (bar_width - 1) / (labels.len() - 1).max(1);
        let text_width = label.len() * 8 * scale;
        let left = centre.saturating_sub(text_width / 2);
        draw_text(
            &mut data,
            (width, rows),
            (left, label_top),
            scale,
            label,
            WHITE,
        );
    }
    // The title at the labels' size if it fits, else at the font's own.
    let title_top = label_top + 10 * scale;
    let title_scale = if title.len() * 8 * scale <= width {
        scale
    } else {
        1
    };
    let left = width.saturating_sub(title.len() * 8 * title_scale) / 2;
    draw_text(
        &mut data,
        (width, rows),
        (left, title_top),
        title_scale,
        title,
        WHITE,
    );
    (rows, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cyclic_map_closes_and_keeps_its_lightness() {
        // -90 and 90 degrees are the same polarisation: the same colour.
        assert_eq!(cyclic(0.0), cyclic(1.0));
        // Constant Oklab lightness: the sRGB luminance of every hue within
        // a narrow band (the gamut clip is the only departure).
        let luminance = |[r, g, b]: [u8; 3]| {
            let linear = |c: u8| {
                let c = f64::from(c) / 255.0;
                if c <= 0.04045 {
                    c / 12.92
                } else {
                    ((c + 0.055) / 1.055).powf(2.4)
                }
            };
            0.2126 * linear(r) + 0.7152 * linear(g) + 0.0722 * linear(b)
        };
        let values: Vec<f64> = (0..36)
            .map(|k| luminance(cyclic(k as f64 / 36.0)))
            .collect();
        let (low, high) = values
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
        assert!(high - low < 0.06, "luminance {low}..{high}");
        // And it is a colour wheel, not a grey.
        assert!(cyclic(0.0) != cyclic(0.5));
    }

    #[test]
    fn maps_have_their_legend_below_and_black_where_nothing_is_seen() {
        let (width, height) = (400, 300);
        let mut values = vec![Some(0.5); width * height];
        values[0] = None;
        let labels = ["0", "1"];
        let (rows, data) = compose(&values, (width, height), viridis, (0.0, 1.0), &labels, "t");
        assert_eq!(rows, height + LEGEND_ROWS);
        assert_eq!(&data[0..3], &[0, 0, 0]);
        assert_eq!(&data[3..6], &viridis(0.5));
        assert!(degree_map(&values, width, height).is_ok());
        // The legend has white text somewhere below the bar.
        let legend = &data[width * (height + 16) * 3..];
        assert!(legend.chunks_exact(3).any(|p| p == [255, 255, 255]));
    }

    #[test]
    fn degrees_and_angles_from_stokes_xyz() {
        let xyz = |y: f64| Xyz { x: 0.0, y, z: 0.0 };
        let pixels = [
            [xyz(1.0), xyz(0.0), xyz(0.5), xyz(0.0)],
            [xyz(1.0), xyz(-0.3), xyz(0.0), xyz(0.0)],
            [xyz(1.0), xyz(0.0), xyz(0.0), xyz(0.0)],
            [xyz(0.0), xyz(0.0), xyz(0.0), xyz(0.0)],
        ];
        let degree = degrees(&pixels);
        assert_eq!(degree, vec![Some(0.5), Some(0.3), Some(0.0), None]);
        let angle = angles_deg(&pixels);
        assert!((angle[0].unwrap() - 45.0).abs() < 1e-12);
        assert!((angle[1].unwrap() - 90.0).abs() < 1e-12);
        assert_eq!(angle[2], None);
        assert_eq!(angle[3], None);
    }
}
