//! Text in the 8 x 8 bitmap font of `font8x8` (printable ASCII; other
//! characters show as the font's blank). A character is 8 x 8 font pixels,
//! its right column and bottom row mostly empty (the spacing), so the text
//! of `n` characters at scale `s` is `8 n s` pixels wide and `8 s` high.

/// Width and height of one character cell, font pixels.
pub const GLYPH_PIXELS: usize = 8;

/// The font pixels of `text`: (column, row) from its top-left corner, the
/// `k`-th character in columns `8 k .. 8 k + 8`.
pub fn font_pixels(text: &str) -> impl Iterator<Item = (usize, usize)> + '_ {
    text.chars().enumerate().flat_map(|(k, character)| {
        let glyph = font8x8::legacy::BASIC_LEGACY
            .get(character as usize)
            .copied()
            .unwrap_or(font8x8::legacy::NOTHING_TO_DISPLAY);
        glyph.into_iter().enumerate().flat_map(move |(row, bits)| {
            (0..GLYPH_PIXELS)
                .filter(move |column| bits & (1 << column) != 0)
                .map(move |column| (k * GLYPH_PIXELS + column, row))
        })
    })
}

/// Width of `text` at `scale` (image pixels per font pixel), pixels.
pub fn text_width(text: &str, scale: f64) -> f64 {
    (text.chars().count() * GLYPH_PIXELS) as f64 * scale
}

/// Draws `text` in `colour` with its top-left corner at `(left, top)`
/// straight into the interleaved RGB samples `data` of a `width` x `rows`
/// image, each font pixel `scale` x `scale` image pixels (hard-edged, no
/// anti-aliasing); clipped to the image.
pub fn draw_text(
    data: &mut [u8],
    (width, rows): (usize, usize),
    (left, top): (usize, usize),
    scale: usize,
    text: &str,
    colour: [u8; 3],
) {
    for (x, y) in font_pixels(text) {
        for (dy, dx) in (0..scale).flat_map(|dy| (0..scale).map(move |dx| (dy, dx))) {
            let column = left + x * scale + dx;
            let row = top + y * scale + dy;
            if column < width && row < rows {
                let start = (row * width + column) * 3;
                data[start..start + 3].copy_from_slice(&colour);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_where_the_font_puts_them() {
        // "I" of font8x8: its top row is 0x1E, columns 1-4 (bit 0 is the
        // leftmost column); a space has no pixels.
        let i: Vec<(usize, usize)> = font_pixels("I").collect();
        assert!(i.contains(&(1, 0)) && i.contains(&(4, 0)) && !i.contains(&(0, 0)));
        assert!(i.iter().all(|&(x, y)| x < 8 && y < 8));
        assert_eq!(font_pixels(" ").count(), 0);
        // The second character is 8 columns to the right.
        let shifted: Vec<(usize, usize)> = font_pixels(" I").filter(|&(x, _)| x >= 8).collect();
        assert_eq!(
            shifted,
            i.iter().map(|&(x, y)| (x + 8, y)).collect::<Vec<_>>()
        );
        // Lower case differs from upper case.
        assert!(font_pixels("a").ne(font_pixels("A")));
        assert_eq!(text_width("abc", 2.0), 48.0);
    }

    #[test]
    fn text_is_drawn_in_its_colour_and_clipped() {
        let (width, rows) = (20, 10);
        let mut data = vec![0u8; width * rows * 3];
        // "A" at the right edge: only part of it fits, and nothing panics.
        draw_text(&mut data, (width, rows), (14, 1), 1, "AA", [1, 2, 3]);
        let coloured = data.chunks_exact(3).filter(|p| *p == [1, 2, 3]).count();
        assert!(coloured > 0);
        assert!(
            data.chunks_exact(3)
                .all(|p| p == [0, 0, 0] || p == [1, 2, 3])
        );
        // At scale 2 every font pixel is 4 image pixels.
        let mut big = vec![0u8; 40 * 20 * 3];
        draw_text(&mut big, (40, 20), (0, 0), 2, "A", [9, 9, 9]);
        let lit = big.chunks_exact(3).filter(|p| *p == [9, 9, 9]).count();
        assert_eq!(lit, 4 * font_pixels("A").count());
    }
}
