//! In-memory images, independent of colour science: [`LinearImage`] holds
//! linear float values for OpenEXR, [`DisplayImage`] holds display-encoded
//! integers (8 or 16 bits) for PNG.
//!
//! Both are row-major, top row first, three interleaved channels per pixel.
//! Constructors validate everything a file format could trip over, so that
//! the writers can only fail on I/O: each dimension is in
//! `1..=`[`MAX_IMAGE_DIMENSION`], the sample count matches the dimensions
//! without overflow, and linear values are finite (a NaN or an infinity never
//! reaches a file).

use crate::{Error, Result};

/// The largest width or height of an image, in pixels: 2^31 - 1, the limit
/// of both PNG (which forbids larger dimensions) and OpenEXR (whose pixel
/// coordinates are signed 32-bit integers).
pub const MAX_IMAGE_DIMENSION: usize = i32::MAX as usize;

/// What the three channels of a [`LinearImage`] mean. The output stage only
/// uses it to name the channels and tag the primaries in OpenEXR files; it
/// converts nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ChannelKind {
    /// Scene-referred linear RGB with sRGB / Rec. 709 primaries and a D65
    /// white point.
    Rgb,
    /// CIE 1931 XYZ tristimulus values.
    Xyz,
}

impl ChannelKind {
    /// The names of the three channels, in storage order: `R, G, B` or
    /// `X, Y, Z` (the OpenEXR channel names).
    pub fn channel_names(self) -> [&'static str; 3] {
        match self {
            ChannelKind::Rgb => ["R", "G", "B"],
            ChannelKind::Xyz => ["X", "Y", "Z"],
        }
    }
}

/// An image of linear (scene-referred) values, three `f32` channels per
/// pixel, row-major with the top row first. Every value is finite; values
/// may be negative (out-of-gamut RGB) or above 1 (radiance is not bounded).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearImage {
    width: usize,
    height: usize,
    channel_kind: ChannelKind,
    pixels: Vec<[f32; 3]>,
}

impl LinearImage {
    /// Wraps `pixels` (row-major, top row first) as a `width` x `height`
    /// image whose channels mean `channel_kind`.
    ///
    /// Fails if a dimension is 0 or above [`MAX_IMAGE_DIMENSION`], if
    /// `pixels.len() != width * height`, or if a value is not finite (the
    /// error names the pixel's `(x, y)` and the channel).
    pub fn new(
        width: usize,
        height: usize,
        channel_kind: ChannelKind,
        pixels: Vec<[f32; 3]>,
    ) -> Result<LinearImage> {
        let pixel_count = checked_pixel_count("linear image", width, height)?;
        if pixels.len() != pixel_count {
            return Err(Error::out_of_range(
                "linear image pixel count",
                pixels.len() as f64,
                "1",
                format!("{pixel_count} (width {width} x height {height})"),
            ));
        }
        let names = channel_kind.channel_names();
        for (index, pixel) in pixels.iter().enumerate() {
            for (channel, &value) in pixel.iter().enumerate() {
                if !value.is_finite() {
                    let (x, y) = (index % width, index / width);
                    return Err(Error::out_of_range(
                        format!("linear image pixel ({x}, {y}) channel {}", names[channel]),
                        f64::from(value),
                        "1",
                        "a finite value",
                    ));
                }
            }
        }
        Ok(LinearImage {
            width,
            height,
            channel_kind,
            pixels,
        })
    }

    /// Builds a `width` x `height` image by calling `pixel_at(x, y)` for
    /// every pixel, row by row from the top; fails as [`LinearImage::new`]
    /// does (without calling `pixel_at` if the dimensions are invalid).
    pub fn from_fn(
        width: usize,
        height: usize,
        channel_kind: ChannelKind,
        mut pixel_at: impl FnMut(usize, usize) -> [f32; 3],
    ) -> Result<LinearImage> {
        let pixel_count = checked_pixel_count("linear image", width, height)?;
        let mut pixels = Vec::with_capacity(pixel_count);
        for y in 0..height {
            for x in 0..width {
                pixels.push(pixel_at(x, y));
            }
        }
        LinearImage::new(width, height, channel_kind, pixels)
    }

    /// Width in pixels (at least 1).
    pub(crate) fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels (at least 1).
    pub(crate) fn height(&self) -> usize {
        self.height
    }

    /// What the three channels mean.
    pub(crate) fn channel_kind(&self) -> ChannelKind {
        self.channel_kind
    }

    /// All pixels, row-major, top row first.
    pub fn pixels(&self) -> &[[f32; 3]] {
        &self.pixels
    }

    /// The pixel at column `x`, row `y` (0 = top), or `None` outside the image.
    #[cfg(test)]
    pub(crate) fn pixel(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        (x < self.width && y < self.height).then(|| self.pixels[y * self.width + x])
    }

    /// Gives the pixel buffer back (row-major, top row first).
    #[cfg(test)]
    pub(crate) fn into_pixels(self) -> Vec<[f32; 3]> {
        self.pixels
    }
}

/// A display-encoded RGB image: three interleaved integer samples per pixel
/// (`R, G, B`), row-major with the top row first, already through a transfer
/// curve (the colour module applies sRGB's). `T` is the sample type: `u8`
/// ([`DisplayImage8`]) or `u16` ([`DisplayImage16`]), whose whole range is
/// the display range (0 = black, `T::MAX` = full scale).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DisplayImage<T> {
    width: usize,
    height: usize,
    data: Vec<T>,
}

/// An 8-bit display-encoded image (the default PNG output).
pub type DisplayImage8 = DisplayImage<u8>;

/// A 16-bit display-encoded image (16-bit PNG output).
pub type DisplayImage16 = DisplayImage<u16>;

impl<T: Copy> DisplayImage<T> {
    /// Wraps `data` (interleaved `R, G, B` samples, row-major, top row first)
    /// as a `width` x `height` image.
    ///
    /// Fails if a dimension is 0 or above [`MAX_IMAGE_DIMENSION`] or if
    /// `data.len() != width * height * 3`.
    pub fn new(width: usize, height: usize, data: Vec<T>) -> Result<DisplayImage<T>> {
        let pixel_count = checked_pixel_count("display image", width, height)?;
        let sample_count = pixel_count.checked_mul(3).ok_or_else(|| {
            too_large_error("display image", width, height, "samples overflow usize")
        })?;
        if data.len() != sample_count {
            return Err(Error::out_of_range(
                "display image sample count",
                data.len() as f64,
                "1",
                format!("{sample_count} (width {width} x height {height} x 3 channels)"),
            ));
        }
        Ok(DisplayImage {
            width,
            height,
            data,
        })
    }

    /// Width in pixels (at least 1).
    pub(crate) fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels (at least 1).
    pub(crate) fn height(&self) -> usize {
        self.height
    }

    /// All samples, interleaved `R, G, B`, row-major, top row first.
    pub(crate) fn data(&self) -> &[T] {
        &self.data
    }

    /// The `[R, G, B]` samples at column `x`, row `y` (0 = top), or `None`
    /// outside the image.
    #[cfg(test)]
    pub(crate) fn pixel(&self, x: usize, y: usize) -> Option<[T; 3]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let start = (y * self.width + x) * 3;
        Some([self.data[start], self.data[start + 1], self.data[start + 2]])
    }
}

/// Checks both dimensions of an image and returns `width * height`.
fn checked_pixel_count(what: &str, width: usize, height: usize) -> Result<usize> {
    for (name, value) in [("width", width), ("height", height)] {
        if value == 0 || value > MAX_IMAGE_DIMENSION {
            return Err(Error::out_of_range(
                format!("{what} {name}"),
                value as f64,
                "px",
                format!("1..={MAX_IMAGE_DIMENSION}"),
            ));
        }
    }
    width
        .checked_mul(height)
        .ok_or_else(|| too_large_error(what, width, height, "pixel count overflows usize"))
}

/// The error for dimensions that are each valid but whose product does not
/// fit in memory's address space.
fn too_large_error(what: &str, width: usize, height: usize, why: &str) -> Error {
    Error::out_of_range(
        format!("{what} width x height ({width} x {height})"),
        width as f64 * height as f64,
        "px",
        format!("a size addressable in memory ({why})"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_image_keeps_pixels_row_major_top_row_first() {
        let image = LinearImage::from_fn(3, 2, ChannelKind::Rgb, |x, y| [x as f32, y as f32, -1.0])
            .unwrap();
        assert_eq!((image.width(), image.height()), (3, 2));
        assert_eq!(image.pixels()[4], [1.0, 1.0, -1.0]);
        assert_eq!(image.pixel(2, 1), Some([2.0, 1.0, -1.0]));
        assert_eq!(image.pixel(3, 0), None);
        assert_eq!(image.pixel(0, 2), None);
    }

    #[test]
    fn linear_image_rejects_non_finite_values_naming_pixel_and_channel() {
        for (bad, shown) in [
            (f32::NAN, "NaN"),
            (f32::INFINITY, "inf"),
            (f32::NEG_INFINITY, "-inf"),
        ] {
            let mut pixels = vec![[0.5_f32; 3]; 6];
            pixels[5][1] = bad; // x = 2, y = 1 in a 3-wide image
            let error = LinearImage::new(3, 2, ChannelKind::Xyz, pixels).unwrap_err();
            let message = error.to_string();
            assert!(
                message.contains("pixel (2, 1) channel Y"),
                "message: {message}"
            );
            assert!(message.contains(shown), "message: {message}");
        }
    }

    #[test]
    fn linear_image_accepts_negative_and_huge_finite_values() {
        let pixels = vec![[-1.0e-30, f32::MAX, f32::MIN]];
        let image = LinearImage::new(1, 1, ChannelKind::Rgb, pixels.clone()).unwrap();
        assert_eq!(image.into_pixels(), pixels);
    }

    #[test]
    fn zero_sized_images_are_rejected() {
        let error = LinearImage::new(0, 4, ChannelKind::Rgb, Vec::new()).unwrap_err();
        assert!(error.to_string().contains("linear image width = 0 px"));
        let error = LinearImage::new(4, 0, ChannelKind::Rgb, Vec::new()).unwrap_err();
        assert!(error.to_string().contains("linear image height = 0 px"));
        let error = DisplayImage8::new(0, 0, Vec::new()).unwrap_err();
        assert!(error.to_string().contains("display image width = 0 px"));
        let error = DisplayImage16::new(2, 0, Vec::new()).unwrap_err();
        assert!(error.to_string().contains("display image height = 0 px"));
    }

    #[test]
    fn oversized_dimensions_are_rejected_before_allocating() {
        let mut calls = 0;
        let result = LinearImage::from_fn(MAX_IMAGE_DIMENSION + 1, 1, ChannelKind::Rgb, |_, _| {
            calls += 1;
            [0.0; 3]
        });
        assert!(result.is_err());
        assert_eq!(calls, 0);
        // Both dimensions allowed, but the product overflows on 32-bit
        // targets (and mismatches the data on 64-bit ones): either way the
        // check must fail with an error, not panic.
        let result = DisplayImage8::new(MAX_IMAGE_DIMENSION, MAX_IMAGE_DIMENSION, vec![0; 3]);
        assert!(result.is_err());
    }

    #[test]
    fn sample_count_must_match_dimensions() {
        let error = LinearImage::new(2, 2, ChannelKind::Rgb, vec![[0.0; 3]; 3]).unwrap_err();
        assert!(error.to_string().contains("allowed 4 (width 2 x height 2)"));
        let error = DisplayImage8::new(2, 1, vec![0; 5]).unwrap_err();
        assert!(
            error
                .to_string()
                .contains("6 (width 2 x height 1 x 3 channels)")
        );
        assert!(DisplayImage8::new(2, 1, vec![0; 6]).is_ok());
    }

    #[test]
    fn display_image_pixel_reads_interleaved_samples() {
        let data: Vec<u16> = (0..12).collect();
        let image = DisplayImage16::new(2, 2, data.clone()).unwrap();
        assert_eq!(image.pixel(1, 0), Some([3, 4, 5]));
        assert_eq!(image.pixel(0, 1), Some([6, 7, 8]));
        assert_eq!(image.pixel(2, 1), None);
        assert_eq!(image.data(), &data[..]);
    }
}
