//! A tiny raster plotter for the `paper_figures` example: line plots with
//! axes, tick labels and a legend, drawn with a built-in 5x7 bitmap font
//! (capital letters, digits and some punctuation; lower case is drawn in
//! capitals). The project has no plotting dependency, and a figure of a
//! few curves needs no more than this.
//!
//! Drawing happens on a canvas [`SUPERSAMPLING`] times finer than the image
//! and is box-filtered down at the end, which anti-aliases lines and text.
//! Coordinates are in output pixels, x to the right and y down.

/// Internal pixels per output pixel along each axis.
const SUPERSAMPLING: usize = 3;

/// An RGB canvas.
pub struct Canvas {
    width: usize,
    height: usize,
    /// Supersampled pixels, row-major.
    pixels: Vec<[u8; 3]>,
}

impl Canvas {
    /// A `width` x `height` canvas (output pixels) filled with `background`.
    pub fn new(width: usize, height: usize, background: [u8; 3]) -> Canvas {
        Canvas {
            width,
            height,
            pixels: vec![background; width * height * SUPERSAMPLING * SUPERSAMPLING],
        }
    }

    /// Fills the internal pixels whose centres satisfy `inside` within the
    /// box `x0..x1, y0..y1` (output pixels).
    fn fill_where(
        &mut self,
        (x0, y0, x1, y1): (f64, f64, f64, f64),
        colour: [u8; 3],
        inside: impl Fn(f64, f64) -> bool,
    ) {
        let s = SUPERSAMPLING as f64;
        let (w, h) = (self.width * SUPERSAMPLING, self.height * SUPERSAMPLING);
        let clamp = |v: f64, n: usize| (v * s).floor().clamp(0.0, n as f64) as usize;
        let (i0, i1) = (clamp(x0, w), clamp(x1 + 1.0 / s, w));
        let (j0, j1) = (clamp(y0, h), clamp(y1 + 1.0 / s, h));
        for j in j0..j1 {
            let y = (j as f64 + 0.5) / s;
            for i in i0..i1 {
                let x = (i as f64 + 0.5) / s;
                if inside(x, y) {
                    self.pixels[j * w + i] = colour;
                }
            }
        }
    }

    /// A filled axis-aligned rectangle.
    pub fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, colour: [u8; 3]) {
        self.fill_where((x0, y0, x1, y1), colour, |x, y| {
            x >= x0 && x < x1 && y >= y0 && y < y1
        });
    }

    /// A straight line `thickness` wide with round ends.
    pub fn line(&mut self, from: (f64, f64), to: (f64, f64), thickness: f64, colour: [u8; 3]) {
        let r = 0.5 * thickness;
        let (dx, dy) = (to.0 - from.0, to.1 - from.1);
        let length_sq = dx * dx + dy * dy;
        let bounds = (
            from.0.min(to.0) - r,
            from.1.min(to.1) - r,
            from.0.max(to.0) + r,
            from.1.max(to.1) + r,
        );
        self.fill_where(bounds, colour, |x, y| {
            let t = if length_sq > 0.0 {
                (((x - from.0) * dx + (y - from.1) * dy) / length_sq).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (px, py) = (from.0 + t * dx - x, from.1 + t * dy - y);
            px * px + py * py <= r * r
        });
    }

    /// A polyline; `dash` = Some((on, off)) in pixels makes it dashed.
    pub fn polyline(
        &mut self,
        points: &[(f64, f64)],
        thickness: f64,
        colour: [u8; 3],
        dash: Option<(f64, f64)>,
    ) {
        let Some((on, off)) = dash else {
            for pair in points.windows(2) {
                self.line(pair[0], pair[1], thickness, colour);
            }
            return;
        };
        // Walk the polyline, drawing the "on" parts of the dash pattern.
        let period = on + off;
        let mut travelled = 0.0;
        for pair in points.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let length = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
            if length == 0.0 {
                continue;
            }
            let at = |s: f64| {
                let t = s / length;
                (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
            };
            let mut s = 0.0;
            while s < length {
                let phase = (travelled + s) % period;
                let (drawing, left) = if phase < on {
                    (true, on - phase)
                } else {
                    (false, period - phase)
                };
                let end = (s + left).min(length);
                if drawing {
                    self.line(at(s), at(end), thickness, colour);
                }
                s = end;
            }
            travelled += length;
        }
    }

    /// A filled square marker of side `size` centred on `centre`.
    pub fn marker(&mut self, centre: (f64, f64), size: f64, colour: [u8; 3]) {
        let h = 0.5 * size;
        self.fill_rect(
            centre.0 - h,
            centre.1 - h,
            centre.0 + h,
            centre.1 + h,
            colour,
        );
    }

    /// Text with its top-left corner at (x, y); each font pixel is `scale`
    /// output pixels.
    pub fn text(&mut self, x: f64, y: f64, scale: f64, colour: [u8; 3], text: &str) {
        for (k, c) in text.chars().enumerate() {
            let glyph = glyph(c);
            let left = x + (k * GLYPH_ADVANCE) as f64 * scale;
            for (row, bits) in glyph.iter().enumerate() {
                for column in 0..GLYPH_WIDTH {
                    if bits & (1 << (GLYPH_WIDTH - 1 - column)) != 0 {
                        let (px, py) = (left + column as f64 * scale, y + row as f64 * scale);
                        self.fill_rect(px, py, px + scale, py + scale, colour);
                    }
                }
            }
        }
    }

    /// Text rotated a quarter turn counter-clockwise (reading upward), its
    /// baseline-start corner at (x, y): the first character is at the
    /// bottom, the glyphs' tops face left.
    pub fn text_upward(&mut self, x: f64, y: f64, scale: f64, colour: [u8; 3], text: &str) {
        for (k, c) in text.chars().enumerate() {
            let glyph = glyph(c);
            for (row, bits) in glyph.iter().enumerate() {
                for column in 0..GLYPH_WIDTH {
                    if bits & (1 << (GLYPH_WIDTH - 1 - column)) != 0 {
                        let px = x + row as f64 * scale;
                        let py = y - ((k * GLYPH_ADVANCE + column) as f64 + 1.0) * scale;
                        self.fill_rect(px, py, px + scale, py + scale, colour);
                    }
                }
            }
        }
    }

    /// The image: interleaved 8-bit R, G, B, box-filtered from the
    /// supersampled canvas.
    pub fn into_rgb8(self) -> (usize, usize, Vec<u8>) {
        let w = self.width * SUPERSAMPLING;
        let n = (SUPERSAMPLING * SUPERSAMPLING) as u32;
        let mut data = Vec::with_capacity(self.width * self.height * 3);
        for y in 0..self.height {
            for x in 0..self.width {
                let mut sum = [0u32; 3];
                for j in 0..SUPERSAMPLING {
                    for i in 0..SUPERSAMPLING {
                        let p = self.pixels[(y * SUPERSAMPLING + j) * w + x * SUPERSAMPLING + i];
                        for c in 0..3 {
                            sum[c] += p[c] as u32;
                        }
                    }
                }
                data.extend(sum.map(|s| ((s + n / 2) / n) as u8));
            }
        }
        (self.width, self.height, data)
    }
}

/// Width of a text in output pixels.
pub fn text_width(text: &str, scale: f64) -> f64 {
    let n = text.chars().count();
    if n == 0 {
        0.0
    } else {
        (n * GLYPH_ADVANCE - 1) as f64 * scale
    }
}

/// One curve of a line plot.
pub struct Series {
    pub label: String,
    pub colour: [u8; 3],
    pub dashed: bool,
    pub points: Vec<(f64, f64)>,
}

/// A line plot: axes with ticks and labels, curves with markers, a legend
/// in the top-right corner, and notes under the legend.
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    /// Tick values and the decimals of their labels.
    pub x_ticks: (Vec<f64>, usize),
    pub y_ticks: (Vec<f64>, usize),
    pub series: Vec<Series>,
    pub notes: Vec<String>,
}

const WHITE: [u8; 3] = [255, 255, 255];
const BLACK: [u8; 3] = [0, 0, 0];
const GRID: [u8; 3] = [225, 225, 225];
const GREY: [u8; 3] = [90, 90, 90];

impl LinePlot {
    /// Draws the plot on a `width` x `height` canvas.
    pub fn render(&self, width: usize, height: usize) -> Canvas {
        let mut canvas = Canvas::new(width, height, WHITE);
        let (left, right, top, bottom) = (90.0, width as f64 - 25.0, 50.0, height as f64 - 70.0);
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range;
        let to_px = |(x, y): (f64, f64)| {
            (
                left + (x - x0) / (x1 - x0) * (right - left),
                bottom - (y - y0) / (y1 - y0) * (bottom - top),
            )
        };
        let label_scale = 2.0;
        let tick_scale = 2.0;
        // Title.
        let title_x = 0.5 * (left + right) - 0.5 * text_width(&self.title, label_scale);
        canvas.text(title_x, 15.0, label_scale, BLACK, &self.title);
        // Grid lines and ticks.
        for &x in &self.x_ticks.0 {
            let (px, _) = to_px((x, y0));
            canvas.line((px, top), (px, bottom), 1.0, GRID);
            canvas.line((px, bottom), (px, bottom + 6.0), 1.5, BLACK);
            let label = format!("{x:.*}", self.x_ticks.1);
            let tw = text_width(&label, tick_scale);
            canvas.text(px - 0.5 * tw, bottom + 12.0, tick_scale, BLACK, &label);
        }
        for &y in &self.y_ticks.0 {
            let (_, py) = to_px((x0, y));
            canvas.line((left, py), (right, py), 1.0, GRID);
            canvas.line((left - 6.0, py), (left, py), 1.5, BLACK);
            let label = format!("{y:.*}", self.y_ticks.1);
            let tw = text_width(&label, tick_scale);
            canvas.text(left - 12.0 - tw, py - 7.0, tick_scale, BLACK, &label);
        }
        // Axis labels.
        let xw = text_width(&self.x_label, label_scale);
        canvas.text(
            0.5 * (left + right - xw),
            bottom + 40.0,
            label_scale,
            BLACK,
            &self.x_label,
        );
        let yw = text_width(&self.y_label, label_scale);
        canvas.text_upward(
            14.0,
            0.5 * (top + bottom + yw),
            label_scale,
            BLACK,
            &self.y_label,
        );
        // Curves.
        for series in &self.series {
            let points: Vec<(f64, f64)> = series.points.iter().map(|&p| to_px(p)).collect();
            let dash = series.dashed.then_some((10.0, 6.0));
            canvas.polyline(&points, 2.5, series.colour, dash);
            for &p in &points {
                canvas.marker(p, 6.0, series.colour);
            }
        }
        // Frame.
        for (a, b) in [
            ((left, top), (right, top)),
            ((right, top), (right, bottom)),
            ((right, bottom), (left, bottom)),
            ((left, bottom), (left, top)),
        ] {
            canvas.line(a, b, 1.5, BLACK);
        }
        // Legend, top right, on a white box.
        let legend_scale = 2.0;
        let line_height = 22.0;
        let sample = 36.0;
        let widest = self
            .series
            .iter()
            .map(|s| text_width(&s.label, legend_scale))
            .chain(
                self.notes
                    .iter()
                    .map(|n| text_width(n, legend_scale) - sample - 8.0),
            )
            .fold(0.0, f64::max);
        let box_width = sample + 8.0 + widest + 20.0;
        let rows = (self.series.len() + self.notes.len()) as f64;
        let (bx, by) = (right - box_width - 10.0, top + 10.0);
        canvas.fill_rect(
            bx,
            by,
            bx + box_width,
            by + rows * line_height + 10.0,
            WHITE,
        );
        for (a, b) in [
            ((bx, by), (bx + box_width, by)),
            (
                (bx + box_width, by),
                (bx + box_width, by + rows * line_height + 10.0),
            ),
            (
                (bx + box_width, by + rows * line_height + 10.0),
                (bx, by + rows * line_height + 10.0),
            ),
            ((bx, by + rows * line_height + 10.0), (bx, by)),
        ] {
            canvas.line(a, b, 1.0, GREY);
        }
        for (k, series) in self.series.iter().enumerate() {
            let y = by + 10.0 + k as f64 * line_height;
            let mid = y + 6.0;
            let dash = series.dashed.then_some((10.0, 6.0));
            canvas.polyline(
                &[(bx + 10.0, mid), (bx + 10.0 + sample, mid)],
                2.5,
                series.colour,
                dash,
            );
            canvas.marker((bx + 10.0 + 0.5 * sample, mid), 6.0, series.colour);
            canvas.text(bx + 18.0 + sample, y, legend_scale, BLACK, &series.label);
        }
        for (k, note) in self.notes.iter().enumerate() {
            let y = by + 10.0 + (self.series.len() + k) as f64 * line_height;
            canvas.text(bx + 10.0, y, legend_scale, GREY, note);
        }
        canvas
    }
}

/// Glyph cell: 5 columns (bit 4 is the leftmost) by 7 rows, plus one
/// column of spacing.
const GLYPH_WIDTH: usize = 5;
const GLYPH_ADVANCE: usize = 6;

/// The 5x7 glyph of `c` (lower case drawn as upper case; unknown
/// characters as '?').
fn glyph(c: char) -> [u8; 7] {
    match c.to_ascii_uppercase() {
        ' ' => [0, 0, 0, 0, 0, 0, 0],
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        '-' => [0, 0, 0, 0x1F, 0, 0, 0],
        '.' => [0, 0, 0, 0, 0, 0x0C, 0x0C],
        ',' => [0, 0, 0, 0, 0x0C, 0x04, 0x08],
        ':' => [0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '/' => [0, 0x01, 0x02, 0x04, 0x08, 0x10, 0],
        '=' => [0, 0, 0x1F, 0, 0x1F, 0, 0],
        '+' => [0, 0x04, 0x04, 0x1F, 0x04, 0x04, 0],
        '_' => [0, 0, 0, 0, 0, 0, 0x1F],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '^' => [0x04, 0x0A, 0x11, 0, 0, 0, 0],
        '\'' => [0x0C, 0x04, 0x08, 0, 0, 0, 0],
        _ => [0x0E, 0x11, 0x01, 0x02, 0x04, 0, 0x04],
    }
}
