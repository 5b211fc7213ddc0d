//! Line plots: a frame with grid lines, ticks and their labels, a title, an
//! x-axis label below and a y-axis label reading upward on the left; the
//! series drawn inside the frame (clipped to it) as lines, markers and
//! error bars; a legend in the top-right corner (a sample of each labelled
//! series beside its label, then the notes, in grey). A log axis is drawn
//! by plotting the logarithms, with [`log_ticks`] for its labels.

use crate::canvas::Canvas;
use crate::text::{GLYPH_PIXELS, text_width};

const WHITE: [u8; 3] = [255, 255, 255];
const BLACK: [u8; 3] = [0, 0, 0];
const GRID: [u8; 3] = [225, 225, 225];
const GREY: [u8; 3] = [90, 90, 90];

/// The dash pattern of dashed lines: on, off, pixels.
const DASH: (f64, f64) = (10.0, 6.0);
/// Thickness of series lines, pixels.
const LINE: f64 = 2.5;

/// One axis: its label, the range it shows, and its ticks (value, label).
pub struct Axis {
    pub label: String,
    pub range: (f64, f64),
    pub ticks: Vec<(f64, String)>,
}

impl Axis {
    /// An axis with ticks at `values`, labelled with `decimals` decimals.
    pub fn linear(
        label: impl Into<String>,
        range: (f64, f64),
        values: impl IntoIterator<Item = f64>,
        decimals: usize,
    ) -> Axis {
        Axis {
            label: label.into(),
            range,
            ticks: values
                .into_iter()
                .map(|v| (v, format!("{v:.decimals$}")))
                .collect(),
        }
    }
}

/// The shape of a series' markers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled square, 6 pixels wide.
    Square,
    /// A filled disc, 7 pixels across.
    Disc,
}

/// One series of a plot, in one colour: polylines, markers and error bars,
/// in data coordinates.
pub struct Series {
    /// Its legend entry; empty: none.
    pub label: String,
    pub colour: [u8; 3],
    /// Its lines dashed rather than solid.
    pub dashed: bool,
    pub marker: Marker,
    /// Polylines; one of a single point is drawn as a short horizontal dash.
    pub lines: Vec<Vec<(f64, f64)>>,
    pub markers: Vec<(f64, f64)>,
    /// Vertical error bars: (x, low y, high y).
    pub error_bars: Vec<(f64, f64, f64)>,
}

impl Series {
    /// A curve through `points`, with a square marker on each.
    pub fn curve(
        label: impl Into<String>,
        colour: [u8; 3],
        dashed: bool,
        points: Vec<(f64, f64)>,
    ) -> Series {
        Series {
            label: label.into(),
            colour,
            dashed,
            marker: Marker::Square,
            lines: vec![points.clone()],
            markers: points,
            error_bars: Vec::new(),
        }
    }
}

/// A line plot (see the module docs).
pub struct LinePlot {
    /// Centred above the frame; cut short with "..." if wider than the image.
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    /// Lines of text under the legend's entries.
    pub notes: Vec<String>,
    /// Image pixels per font pixel of all text (12-pixel characters at 1.5).
    pub text_scale: f64,
}

impl LinePlot {
    /// The frame's left, top, right and bottom edges on a `width` x
    /// `height` image, pixels: room on the left for the upward y label and
    /// the widest y tick label, on top for the title, below for the x tick
    /// labels and the x label.
    pub fn frame(&self, width: usize, height: usize) -> (f64, f64, f64, f64) {
        let glyph = GLYPH_PIXELS as f64 * self.text_scale;
        let widest = self
            .y
            .ticks
            .iter()
            .map(|(_, label)| text_width(label, self.text_scale))
            .fold(0.0, f64::max);
        (
            12.0 + glyph + 14.0 + widest + 12.0,
            14.0 + glyph + 24.0,
            width as f64 - 25.0,
            height as f64 - (12.0 + glyph + 14.0 + glyph + 14.0),
        )
    }

    /// The image position of the data point `(x, y)` on a `width` x
    /// `height` image.
    pub fn to_pixels(&self, width: usize, height: usize, (x, y): (f64, f64)) -> (f64, f64) {
        let (left, top, right, bottom) = self.frame(width, height);
        let ((x0, x1), (y0, y1)) = (self.x.range, self.y.range);
        (
            left + (x - x0) / (x1 - x0) * (right - left),
            bottom - (y - y0) / (y1 - y0) * (bottom - top),
        )
    }

    /// Draws the plot on a `width` x `height` canvas.
    pub fn render(&self, width: usize, height: usize) -> Canvas {
        let mut canvas = Canvas::new(width, height, WHITE);
        let scale = self.text_scale;
        let glyph = GLYPH_PIXELS as f64 * scale;
        let (left, top, right, bottom) = self.frame(width, height);
        let to_px = |p: (f64, f64)| self.to_pixels(width, height, p);
        let ((x0, _), (y0, _)) = (self.x.range, self.y.range);

        // The title, cut to the image's width.
        let room = ((width as f64 - 16.0) / (GLYPH_PIXELS as f64 * scale)).max(3.0) as usize;
        let title = if self.title.chars().count() > room {
            self.title.chars().take(room - 3).collect::<String>() + "..."
        } else {
            self.title.clone()
        };
        let title_x = (0.5 * (left + right - text_width(&title, scale)))
            .min(width as f64 - 8.0 - text_width(&title, scale))
            .max(8.0);
        canvas.text(title_x, 14.0, scale, BLACK, &title);

        // Grid lines, ticks and their labels.
        for (x, label) in &self.x.ticks {
            let (px, _) = to_px((*x, y0));
            canvas.line((px, top), (px, bottom), 1.0, GRID);
            canvas.line((px, bottom), (px, bottom + 6.0), 1.5, BLACK);
            let tw = text_width(label, scale);
            canvas.text(px - 0.5 * tw, bottom + 12.0, scale, BLACK, label);
        }
        for (y, label) in &self.y.ticks {
            let (_, py) = to_px((x0, *y));
            canvas.line((left, py), (right, py), 1.0, GRID);
            canvas.line((left - 6.0, py), (left, py), 1.5, BLACK);
            let tw = text_width(label, scale);
            canvas.text(left - 12.0 - tw, py - 0.5 * glyph, scale, BLACK, label);
        }
        // Axis labels.
        let xw = text_width(&self.x.label, scale);
        canvas.text(
            0.5 * (left + right - xw),
            bottom + 12.0 + glyph + 14.0,
            scale,
            BLACK,
            &self.x.label,
        );
        let yw = text_width(&self.y.label, scale);
        canvas.text_upward(
            12.0,
            (0.5 * (top + bottom + yw)).min(height as f64),
            scale,
            BLACK,
            &self.y.label,
        );

        // The series, clipped to the frame.
        canvas.set_clip(Some((left, top, right, bottom)));
        for series in &self.series {
            let dash = series.dashed.then_some(DASH);
            for line in &series.lines {
                let points: Vec<(f64, f64)> = line.iter().map(|&p| to_px(p)).collect();
                if let [(x, y)] = points[..] {
                    canvas.line((x - 7.0, y), (x + 7.0, y), LINE, series.colour);
                } else {
                    canvas.polyline(&points, LINE, series.colour, dash);
                }
            }
            for &(x, low, high) in &series.error_bars {
                let ((x, low), (_, high)) = (to_px((x, low)), to_px((x, high)));
                canvas.line((x, low), (x, high), 1.0, series.colour);
                for y in [low, high] {
                    canvas.line((x - 3.0, y), (x + 3.0, y), 1.0, series.colour);
                }
            }
            for &p in &series.markers {
                marker(&mut canvas, series.marker, to_px(p), series.colour);
            }
        }
        canvas.set_clip(None);

        canvas.outline((left, top), (right, bottom), 1.5, BLACK);
        self.legend(&mut canvas, (top, right));
        canvas
    }

    /// The legend in the frame's top-right corner, on a white box.
    fn legend(&self, canvas: &mut Canvas, (top, right): (f64, f64)) {
        let scale = self.text_scale;
        let glyph = GLYPH_PIXELS as f64 * scale;
        let entries: Vec<&Series> = self.series.iter().filter(|s| !s.label.is_empty()).collect();
        if entries.is_empty() && self.notes.is_empty() {
            return;
        }
        let line_height = glyph + 10.0;
        let sample = 36.0;
        // Entries' text starts after their sample, notes' at the box's edge.
        let widest = entries
            .iter()
            .map(|s| sample + 8.0 + text_width(&s.label, scale))
            .chain(self.notes.iter().map(|n| text_width(n, scale)))
            .fold(0.0, f64::max);
        let box_width = widest + 20.0;
        let rows = (entries.len() + self.notes.len()) as f64;
        let (bx, by) = (right - box_width - 10.0, top + 10.0);
        let (bx1, by1) = (bx + box_width, by + rows * line_height + 10.0);
        canvas.fill_rect(bx, by, bx1, by1, WHITE);
        canvas.outline((bx, by), (bx1, by1), 1.0, GREY);
        for (k, series) in entries.iter().enumerate() {
            let y = by + 10.0 + k as f64 * line_height;
            let middle = y + 0.5 * glyph - 0.5;
            if !series.lines.is_empty() {
                let dash = series.dashed.then_some(DASH);
                let ends = [(bx + 10.0, middle), (bx + 10.0 + sample, middle)];
                canvas.polyline(&ends, LINE, series.colour, dash);
            }
            if !series.markers.is_empty() {
                let centre = (bx + 10.0 + 0.5 * sample, middle);
                marker(canvas, series.marker, centre, series.colour);
            }
            canvas.text(bx + 18.0 + sample, y, scale, BLACK, &series.label);
        }
        for (k, note) in self.notes.iter().enumerate() {
            let y = by + 10.0 + (entries.len() + k) as f64 * line_height;
            canvas.text(bx + 10.0, y, scale, GREY, note);
        }
    }
}

/// Draws one marker centred on `centre`.
fn marker(canvas: &mut Canvas, shape: Marker, centre: (f64, f64), colour: [u8; 3]) {
    match shape {
        Marker::Square => canvas.square(centre, 6.0, colour),
        Marker::Disc => canvas.disc(centre, 3.5, colour),
    }
}

/// Ticks of a log axis that shows ln values `low..=high`: (ln value,
/// label), at powers of ten, or at 1-2-5 or 1-2-3-5-7 times them where a
/// decade gives fewer than three, every other decade where it gives more
/// than ten, and at a linear round step where even 1-2-3-5-7 gives fewer
/// than three (a range under a factor of about 1.5). Labels are plain
/// decimals from 1e-4 to 1e5, `me` + exponent outside.
pub fn log_ticks(low: f64, high: f64) -> Vec<(f64, String)> {
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

/// 1, 2 or 5 times a power of ten, at least `step`: the round tick step
/// nearest above it.
pub fn round_step(step: f64) -> f64 {
    let power = 10f64.powf(step.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|s| *s >= step)
        .unwrap_or(10.0 * power)
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
        assert!((ticks[0].0 - 0.001f64.ln()).abs() < 1e-12);
        // A decade and a bit: 1-2-5.
        let labels: Vec<String> = log_ticks(0.015f64.ln(), 0.3f64.ln())
            .into_iter()
            .map(|(_, l)| l)
            .collect();
        assert_eq!(labels, ["0.02", "0.05", "0.1", "0.2"]);
        // Many decades: every other one, with exponents outside 1e-4..1e5.
        let labels: Vec<String> = log_ticks(1e-9f64.ln(), 1e9f64.ln())
            .into_iter()
            .map(|(_, l)| l)
            .collect();
        assert_eq!(
            labels,
            [
                "1e-9", "1e-7", "1e-5", "0.001", "0.1", "10", "1000", "100000", "1e7", "1e9"
            ]
        );
        // A narrow range: linear ticks at a round step, at least 3.
        let narrow = log_ticks(0.8f64.ln(), 1.25f64.ln());
        assert!(narrow.len() >= 3, "{narrow:?}");
        assert!(
            narrow
                .iter()
                .all(|(v, _)| (0.8f64.ln()..=1.25f64.ln()).contains(v))
        );
        assert_eq!(round_step(0.13), 0.2);
        assert_eq!(round_step(3.0), 5.0);
        assert_eq!(round_step(0.07), 0.1);
    }

    fn plot(series: Vec<Series>) -> LinePlot {
        LinePlot {
            title: "a title".into(),
            x: Axis::linear("x", (0.0, 10.0), (0..=5).map(|k| 2.0 * k as f64), 0),
            y: Axis::linear("y", (0.0, 1.0), [0.0, 0.5, 1.0], 1),
            series,
            notes: vec!["a note".into()],
            text_scale: 1.5,
        }
    }

    #[test]
    fn series_are_drawn_where_their_data_are_and_clipped_to_the_frame() {
        const RED: [u8; 3] = [200, 0, 0];
        let (width, height) = (400, 300);
        let points = vec![(1.0, 0.1), (5.0, 0.3), (9.0, 0.2), (12.0, 0.5)];
        let figure = plot(vec![Series::curve("", RED, false, points)]);
        let (_, _, data) = figure.render(width, height).into_rgb8();
        let pixel = |(x, y): (f64, f64)| {
            let start = (y as usize * width + x as usize) * 3;
            [data[start], data[start + 1], data[start + 2]]
        };
        // The markers' centres and the line's middle are the series' colour.
        for p in [(1.0, 0.1), (5.0, 0.3), (9.0, 0.2), (3.0, 0.2), (7.0, 0.25)] {
            assert_eq!(pixel(figure.to_pixels(width, height, p)), RED, "{p:?}");
        }
        // Nothing red outside the frame (the last point is beyond it).
        let (left, top, right, bottom) = figure.frame(width, height);
        for (n, p) in data.chunks_exact(3).enumerate() {
            let (x, y) = ((n % width) as f64, (n / width) as f64);
            if x < left - 1.0 || x > right + 1.0 || y < top - 1.0 || y > bottom + 1.0 {
                assert!(p[1] == p[0] || p[0] < 150, "red at {x}, {y}");
            }
        }
        // The frame's edges meet the axes' ends.
        assert_eq!(figure.to_pixels(width, height, (0.0, 0.0)), (left, bottom));
        assert_eq!(figure.to_pixels(width, height, (10.0, 1.0)), (right, top));
    }

    #[test]
    fn titles_labels_and_the_legend_have_text() {
        let (width, height) = (400, 300);
        let dark_in = |data: &[u8], (x0, y0, x1, y1): (usize, usize, usize, usize)| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (y * width + x) * 3))
                .filter(|&i| data[i] < 128)
                .count()
        };
        let empty = LinePlot {
            title: String::new(),
            x: Axis::linear("", (0.0, 1.0), [], 0),
            y: Axis::linear("", (0.0, 1.0), [], 0),
            series: Vec::new(),
            notes: Vec::new(),
            text_scale: 1.5,
        };
        let regions = |figure: &LinePlot| {
            let (left, top, right, bottom) = figure.frame(width, height);
            let (left, top, right, bottom) =
                (left as usize, top as usize, right as usize, bottom as usize);
            // Above the frame (the title), below it (tick labels and the x
            // label), left of it (the y label and tick labels), inside it
            // (the legend).
            [
                (0, 0, width, top - 2),
                (0, bottom + 2, width, height),
                (0, 0, left - 2, height),
                (right / 2, top + 2, right - 2, bottom / 2),
            ]
        };
        let (_, _, blank) = empty.render(width, height).into_rgb8();
        for region in regions(&empty) {
            assert_eq!(dark_in(&blank, region), 0, "{region:?}");
        }
        let figure = plot(vec![Series::curve("curve", [0, 0, 200], true, vec![])]);
        let (_, _, data) = figure.render(width, height).into_rgb8();
        for region in regions(&figure) {
            assert!(dark_in(&data, region) > 20, "{region:?}");
        }
    }
}
