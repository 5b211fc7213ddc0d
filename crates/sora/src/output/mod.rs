//! Images (and text: [`write_text`]) on disk: the only module of the
//! library that touches files.
//!
//! Two in-memory image types, independent of colour science (the colour
//! module fills them), both row-major with the top row first and three
//! interleaved channels per pixel:
//! - [`LinearImage`]: linear `f32` values, scene-referred RGB (sRGB / Rec. 709
//!   primaries) or CIE XYZ, as its [`ChannelKind`] says; every value finite;
//! - [`DisplayImage`]: display-encoded `R, G, B` integers after a transfer
//!   curve, 8-bit ([`DisplayImage8`]) or 16-bit ([`DisplayImage16`]).
//!
//! Two file formats, chosen by the caller or from the file extension with
//! [`OutputFormat::from_path`] (`.png`, `.exr`, any letter case):
//! - PNG ([`write_png`]): a [`DisplayImage`] as truecolour RGB without alpha,
//!   8 or 16 bits per channel, samples stored as given (sRGB-encoded by the
//!   caller; no colour chunk is written, which viewers read as sRGB);
//! - OpenEXR ([`write_exr`]): a [`LinearImage`] as channels `R, G, B` or
//!   `X, Y, Z` of 32-bit (exact) or 16-bit half floats, ZIP-compressed or
//!   uncompressed, with a `chromaticities` attribute for the primaries
//!   (Rec. 709 / D65 for RGB; CIE XYZ's own, white (1/3, 1/3), for XYZ).
//!
//! What may be written: a regular file, a link to one (the file is
//! written, the link kept) or a new file in an existing directory, never a
//! device, a FIFO or a directory ([`output_target`], the one check every
//! output of the command-line tool and every writer here goes through;
//! [`output_targets`] also refuses two outputs on one file).
//!
//! Atomicity: every file is written in full to a temporary file in the
//! target's directory, synced, then renamed onto the target. A failed write
//! leaves no partial file and no temporary file, and an existing file at
//! the target is replaced only when the new one is complete. The outputs of
//! one run are written together or not at all ([`OutputFiles`]: staged,
//! then renamed in turn; on a failure the files the run created are
//! removed). Errors are [`Error::Io`](crate::Error::Io)
//! naming the target path (image validation errors are
//! [`Error::OutOfRange`](crate::Error::OutOfRange) naming the pixel and
//! channel).

mod atomic_file;
mod exr;
mod format;
mod image_buffer;
mod path;
mod png;
mod text;

pub use atomic_file::OutputFiles;
pub use path::{MAX_SYMBOLIC_LINK_HOPS, output_target, output_targets};

pub use exr::{
    ExrCompression, ExrOptions, ExrSampleType, SkyImageUnits, encode_exr, encode_exr_with_layers,
    read_exr_channel, write_exr, write_exr_with_layers,
};
pub use format::OutputFormat;
pub use image_buffer::{
    ChannelKind, DisplayImage, DisplayImage8, DisplayImage16, LinearImage, MAX_IMAGE_DIMENSION,
};
pub use png::{PngSample, write_png};
pub use text::write_text;
