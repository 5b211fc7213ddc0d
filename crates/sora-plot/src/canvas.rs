//! An RGB canvas drawn [`SUPERSAMPLING`] times finer than the image and
//! box-filtered down at the end ([`Canvas::into_rgb8`]), which anti-aliases
//! lines, discs and text. Coordinates are in image pixels (fractions
//! allowed), x to the right and y down; a shape covers the fine pixels
//! whose centres are inside it, within the clip rectangle.

use crate::text::font_pixels;

/// Fine pixels per image pixel along each axis.
pub const SUPERSAMPLING: usize = 3;

/// An RGB canvas (see the module docs).
pub struct Canvas {
    width: usize,
    height: usize,
    /// Fine pixels, row-major.
    pixels: Vec<[u8; 3]>,
    /// Drawing is clipped to x0..x1, y0..y1 (image pixels).
    clip: (f64, f64, f64, f64),
}

impl Canvas {
    /// A `width` x `height` canvas (image pixels) filled with `background`.
    pub fn new(width: usize, height: usize, background: [u8; 3]) -> Canvas {
        Canvas {
            width,
            height,
            pixels: vec![background; width * height * SUPERSAMPLING * SUPERSAMPLING],
            clip: (0.0, 0.0, width as f64, height as f64),
        }
    }

    /// Clips all drawing to the rectangle `x0..x1, y0..y1`, or to the whole
    /// canvas with `None`.
    pub fn set_clip(&mut self, clip: Option<(f64, f64, f64, f64)>) {
        self.clip = clip.unwrap_or((0.0, 0.0, self.width as f64, self.height as f64));
    }

    /// Fills the fine pixels whose centres satisfy `inside` within the box
    /// `x0..x1, y0..y1` (image pixels) and the clip rectangle.
    fn fill_where(
        &mut self,
        (x0, y0, x1, y1): (f64, f64, f64, f64),
        colour: [u8; 3],
        inside: impl Fn(f64, f64) -> bool,
    ) {
        let s = SUPERSAMPLING as f64;
        let (w, h) = (self.width * SUPERSAMPLING, self.height * SUPERSAMPLING);
        let (cx0, cy0, cx1, cy1) = self.clip;
        let index = |v: f64, n: usize| (v * s).floor().clamp(0.0, n as f64) as usize;
        let (i0, i1) = (index(x0.max(cx0), w), index(x1.min(cx1) + 1.0 / s, w));
        let (j0, j1) = (index(y0.max(cy0), h), index(y1.min(cy1) + 1.0 / s, h));
        for j in j0..j1 {
            let y = (j as f64 + 0.5) / s;
            if y < cy0 || y >= cy1 {
                continue;
            }
            for i in i0..i1 {
                let x = (i as f64 + 0.5) / s;
                if x >= cx0 && x < cx1 && inside(x, y) {
                    self.pixels[j * w + i] = colour;
                }
            }
        }
    }

    /// A filled axis-aligned rectangle `x0..x1, y0..y1`.
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

    /// The outline of the axis-aligned rectangle with corners `(x0, y0)`
    /// and `(x1, y1)`: its four sides as lines `thickness` wide.
    pub fn outline(
        &mut self,
        (x0, y0): (f64, f64),
        (x1, y1): (f64, f64),
        thickness: f64,
        colour: [u8; 3],
    ) {
        for (a, b) in [
            ((x0, y0), (x1, y0)),
            ((x1, y0), (x1, y1)),
            ((x1, y1), (x0, y1)),
            ((x0, y1), (x0, y0)),
        ] {
            self.line(a, b, thickness, colour);
        }
    }

    /// A polyline; `dash` = Some((on, off)) in pixels makes it dashed, the
    /// pattern running on across the corners.
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

    /// A filled disc.
    pub fn disc(&mut self, (cx, cy): (f64, f64), radius: f64, colour: [u8; 3]) {
        let bounds = (cx - radius, cy - radius, cx + radius, cy + radius);
        self.fill_where(bounds, colour, |x, y| {
            (x - cx).powi(2) + (y - cy).powi(2) <= radius * radius
        });
    }

    /// A filled square of side `size` centred on `centre`.
    pub fn square(&mut self, centre: (f64, f64), size: f64, colour: [u8; 3]) {
        let h = 0.5 * size;
        self.fill_rect(
            centre.0 - h,
            centre.1 - h,
            centre.0 + h,
            centre.1 + h,
            colour,
        );
    }

    /// Text (the [`crate::text`] font) with its top-left corner at (x, y),
    /// each font pixel `scale` image pixels.
    pub fn text(&mut self, x: f64, y: f64, scale: f64, colour: [u8; 3], text: &str) {
        for (column, row) in font_pixels(text) {
            let (px, py) = (x + column as f64 * scale, y + row as f64 * scale);
            self.fill_rect(px, py, px + scale, py + scale, colour);
        }
    }

    /// Text rotated a quarter turn counter-clockwise (reading upward), the
    /// bottom-left corner of its first character cell, as the text is read,
    /// at (x, y): the glyphs' tops face left, the text runs up from y.
    pub fn text_upward(&mut self, x: f64, y: f64, scale: f64, colour: [u8; 3], text: &str) {
        for (column, row) in font_pixels(text) {
            let px = x + row as f64 * scale;
            let py = y - (column as f64 + 1.0) * scale;
            self.fill_rect(px, py, px + scale, py + scale, colour);
        }
    }

    /// The image: `(width, height, samples)`, the samples interleaved 8-bit
    /// R, G, B, each pixel the mean of its fine pixels.
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
                            sum[c] += u32::from(p[c]);
                        }
                    }
                }
                data.extend(sum.map(|s| ((s + n / 2) / n) as u8));
            }
        }
        (self.width, self.height, data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: [u8; 3] = [255, 255, 255];
    const RED: [u8; 3] = [255, 0, 0];

    fn pixel(data: &[u8], width: usize, (x, y): (usize, usize)) -> [u8; 3] {
        let start = (y * width + x) * 3;
        [data[start], data[start + 1], data[start + 2]]
    }

    #[test]
    fn a_line_is_where_it_is_drawn_and_anti_aliased_at_its_edges() {
        let mut canvas = Canvas::new(20, 10, WHITE);
        // A horizontal line 2 pixels thick centred on y = 5: rows 4 and 5.
        canvas.line((2.0, 5.0), (17.0, 5.0), 2.0, RED);
        let (width, height, data) = canvas.into_rgb8();
        assert_eq!((width, height, data.len()), (20, 10, 600));
        for x in 3..17 {
            assert_eq!(pixel(&data, width, (x, 4)), RED, "x {x}");
            assert_eq!(pixel(&data, width, (x, 5)), RED, "x {x}");
            assert_eq!(pixel(&data, width, (x, 3)), WHITE, "x {x}");
            assert_eq!(pixel(&data, width, (x, 6)), WHITE, "x {x}");
        }
        // Off the line's ends, white; at a round end, a blend.
        assert_eq!(pixel(&data, width, (0, 4)), WHITE);
        assert_eq!(pixel(&data, width, (19, 5)), WHITE);
        let end = pixel(&data, width, (1, 4));
        assert!(end[0] == 255 && end[1] > 0 && end[1] < 255, "{end:?}");
    }

    #[test]
    fn drawing_is_clipped_and_a_half_covered_pixel_is_half_blended() {
        let mut canvas = Canvas::new(10, 10, WHITE);
        canvas.set_clip(Some((2.0, 2.0, 8.0, 8.0)));
        canvas.fill_rect(0.0, 0.0, 10.0, 10.0, [0, 0, 0]);
        canvas.set_clip(None);
        // A disc's centre pixel is covered; its bounding box's corner not.
        canvas.disc((5.0, 5.0), 1.5, RED);
        let (width, _, data) = canvas.into_rgb8();
        assert_eq!(pixel(&data, width, (1, 1)), WHITE);
        assert_eq!(pixel(&data, width, (2, 2)), [0, 0, 0]);
        assert_eq!(pixel(&data, width, (8, 8)), WHITE);
        assert_eq!(pixel(&data, width, (4, 4)), RED);
        let mut half = Canvas::new(4, 1, WHITE);
        // x 0..1.5 covers the fine columns centred at 1/6 ... 7/6 (the one
        // centred at 1.5 is outside): pixel 1 is one-third black.
        half.fill_rect(0.0, 0.0, 1.5, 1.0, [0, 0, 0]);
        let (_, _, data) = half.into_rgb8();
        assert_eq!(&data[0..3], &[0, 0, 0]);
        assert_eq!(&data[3..6], &[170, 170, 170]);
        assert_eq!(&data[6..9], &WHITE);
    }

    #[test]
    fn text_is_drawn_and_upward_text_runs_up() {
        let mut canvas = Canvas::new(40, 40, WHITE);
        canvas.text(2.0, 2.0, 1.0, RED, "E");
        canvas.text_upward(20.0, 38.0, 2.0, RED, "E");
        let (width, _, data) = canvas.into_rgb8();
        let red_in = |x0: usize, y0: usize, x1: usize, y1: usize| {
            (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&p| pixel(&data, width, p) == RED)
                .count()
        };
        // Integer positions and scale: hard-edged, as many pixels as the
        // glyph has, inside its cell.
        let glyph = font_pixels("E").count();
        assert_eq!(red_in(2, 2, 10, 10), glyph);
        // Upward at scale 2: 4 pixels per font pixel, inside x 20..36,
        // y 22..38 (the cell turned on its side).
        assert_eq!(red_in(20, 22, 36, 38), 4 * glyph);
        assert_eq!(red_in(0, 0, 40, 40), 5 * glyph);
    }
}
