//! The raster plots of sora: the `sora retrieve --plot` fit plot, the line
//! figures of `docs/` (the `paper_figures` example) and the legends of the
//! polarisation maps, all drawn by this crate with one canvas and one font.
//!
//! - [`Canvas`]: an RGB canvas drawn at [`SUPERSAMPLING`] times the image's
//!   resolution and box-filtered down at the end, which anti-aliases lines,
//!   discs and text; coordinates in image pixels, x to the right, y down.
//! - [`text`]: the 8 x 8 bitmap font of `font8x8` (printable ASCII),
//!   drawn on a canvas at any scale or straight into an RGB buffer.
//! - [`LinePlot`]: axes with grid, ticks and labels, curves with markers
//!   and error bars, and a legend with notes; [`log_ticks`] and
//!   [`round_step`] for round tick values.
//!
//! Hand-written because the plots need little (lines, markers, a frame,
//! short labels) and no small crate does it: `plotters` was considered,
//! but its text needs a TrueType font (a system font through `font-kit`,
//! or one supplied through `ab_glyph`), whose rendering differs between
//! machines or must be bundled, and it brings many crates into the build,
//! against this crate's one dependency (`font8x8`, itself without any).
//! Its output is 8-bit RGB samples; writing them (PNG) is the caller's.

pub mod canvas;
pub mod line_plot;
pub mod text;

pub use canvas::{Canvas, SUPERSAMPLING};
pub use line_plot::{Axis, LinePlot, Marker, Series, log_ticks, round_step};
