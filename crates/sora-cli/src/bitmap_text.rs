//! Text in 8-bit RGB pictures: the 8 x 8 bitmap font of `font8x8` (ASCII),
//! each font pixel drawn as `scale` x `scale` image pixels. Shared by the
//! polarisation maps' legends and the retrieval's fit plot.

/// Width of one character at scale 1, pixels.
pub const GLYPH_PIXELS: usize = 8;

/// Draws `text` (ASCII; other characters show as the font's blank) in
/// `colour` with its top-left corner at `(left, top)` into the interleaved
/// RGB samples `data` of a `width` x `rows` image, each font pixel `scale`
/// x `scale` image pixels; clipped to the image.
pub fn draw_text(
    data: &mut [u8],
    (width, rows): (usize, usize),
    (left, top): (usize, usize),
    scale: usize,
    text: &str,
    colour: [u8; 3],
) {
    for (n, character) in text.chars().enumerate() {
        let glyph = font8x8::legacy::BASIC_LEGACY
            .get(character as usize)
            .copied()
            .unwrap_or(font8x8::legacy::NOTHING_TO_DISPLAY);
        for (y, bits) in glyph.iter().enumerate() {
            for x in 0..GLYPH_PIXELS {
                if bits & (1 << x) == 0 {
                    continue;
                }
                for (dy, dx) in (0..scale).flat_map(|dy| (0..scale).map(move |dx| (dy, dx))) {
                    let column = left + (n * GLYPH_PIXELS + x) * scale + dx;
                    let row = top + y * scale + dy;
                    if column < width && row < rows {
                        let start = (row * width + column) * 3;
                        data[start..start + 3].copy_from_slice(&colour);
                    }
                }
            }
        }
    }
}

/// Width of `text` drawn at `scale`, pixels.
pub fn text_width(text: &str, scale: usize) -> usize {
    text.chars().count() * GLYPH_PIXELS * scale
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(text_width("abc", 2), 48);
    }
}
