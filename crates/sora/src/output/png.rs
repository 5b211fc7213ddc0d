//! PNG output: an RGB [`DisplayImage`] written as an 8-bit (default) or
//! 16-bit per channel truecolour PNG, no alpha, with the `image` crate's
//! encoder.
//!
//! The samples are stored exactly as given: the caller (the colour module)
//! has already applied the sRGB transfer curve. No `sRGB`, `gAMA` or `iCCP`
//! chunk is written (`image`'s encoder offers only ICC profiles); viewers
//! treat an untagged PNG as sRGB, which is what the samples are.

use std::io::{BufWriter, Write};
use std::path::Path;

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

use super::atomic_file::OutputFiles;
use super::image_buffer::DisplayImage;
use crate::{Error, Result};

/// A sample type that PNG stores: `u8` (8 bits per channel) or `u16`
/// (16 bits per channel). Sealed: PNG has no other RGB bit depths that the
/// output stage writes.
pub trait PngSample: Copy + private::Sealed {
    /// The encoder's colour type for interleaved RGB of this sample type.
    #[doc(hidden)]
    const RGB_COLOR_TYPE: ExtendedColorType;

    /// The samples as bytes in native byte order, as the encoder expects
    /// (it converts 16-bit samples to PNG's big-endian order itself).
    #[doc(hidden)]
    fn to_native_endian_bytes(samples: &[Self]) -> Vec<u8>;
}

impl PngSample for u8 {
    const RGB_COLOR_TYPE: ExtendedColorType = ExtendedColorType::Rgb8;

    fn to_native_endian_bytes(samples: &[u8]) -> Vec<u8> {
        samples.to_vec()
    }
}

impl PngSample for u16 {
    const RGB_COLOR_TYPE: ExtendedColorType = ExtendedColorType::Rgb16;

    fn to_native_endian_bytes(samples: &[u16]) -> Vec<u8> {
        samples
            .iter()
            .flat_map(|sample| sample.to_ne_bytes())
            .collect()
    }
}

mod private {
    /// Keeps [`super::PngSample`] implemented only here.
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
}

/// Writes `image` to `path` as an RGB PNG of 8 or 16 bits per channel (from
/// the image's sample type), atomically: on any failure, no partial file is
/// left and an existing file at `path` is unchanged. Errors name `path`.
/// Only a regular file, a link to one or a new file is written
/// ([`output_target`](super::output_target)).
pub fn write_png<T: PngSample>(path: impl AsRef<Path>, image: &DisplayImage<T>) -> Result<()> {
    let mut files = OutputFiles::new();
    files.png(path, image)?;
    files.commit()
}

impl OutputFiles {
    /// Stages `image` for `path` as [`write_png`] writes it (see
    /// [`OutputFiles`]).
    pub fn png<T: PngSample>(
        &mut self,
        path: impl AsRef<Path>,
        image: &DisplayImage<T>,
    ) -> Result<()> {
        let path = path.as_ref();
        // Dimensions are at most `MAX_IMAGE_DIMENSION` (2^31 - 1) by construction.
        let width = u32::try_from(image.width()).expect("image width fits in u32");
        let height = u32::try_from(image.height()).expect("image height fits in u32");
        let bytes = T::to_native_endian_bytes(image.data());
        let encoding_error = |error: &dyn std::fmt::Display| Error::Io {
            path: path.display().to_string(),
            message: format!("cannot write PNG: {error}"),
        };
        self.stage(path, |file| {
            let mut buffered = BufWriter::new(file);
            PngEncoder::new(&mut buffered)
                .write_image(&bytes, width, height, T::RGB_COLOR_TYPE)
                .map_err(|error| encoding_error(&error))?;
            // Flush explicitly: dropping a `BufWriter` would swallow the error.
            buffered.flush().map_err(|error| encoding_error(&error))
        })
    }
}
