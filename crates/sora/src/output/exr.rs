//! OpenEXR output: a [`LinearImage`] written as a single-part, scan-line
//! OpenEXR file with three linear channels, with the `exr` crate. With the
//! `parallel` feature (the default) its blocks are compressed on a pool of
//! threads and written in increasing line order, so the file's bytes are
//! those of the sequential writer (the browser build, without the
//! feature).
//!
//! - Channels: `R, G, B` for [`ChannelKind::Rgb`], `X, Y, Z` for
//!   [`ChannelKind::Xyz`] (OpenEXR stores channels sorted by name, so an RGB
//!   file lists them as `B, G, R`; readers look them up by name). More
//!   images of the same size can go into the same file as layers
//!   ([`write_exr_with_layers`]): channels named `<layer>.R` and so on, the
//!   OpenEXR convention for layers of one part (a polarised sky's Stokes
//!   images S0..S3, say).
//! - Samples: 32-bit float ([`ExrSampleType::F32`], the default, exact) or
//!   16-bit half float ([`ExrSampleType::F16`], rounded to nearest; a value
//!   whose magnitude rounds beyond the half-float maximum 65504 is rejected
//!   rather than written as infinity, or with [`ExrSampleType::F16Clamped`]
//!   clamped to +-65504; values below 2^-14 lose relative precision as
//!   half-float subnormals).
//! - Units: the `whiteLuminance` attribute (the luminance, cd/m^2, of
//!   RGB = (1, 1, 1)) and text attributes `sora:*` (the unit, the sun) from
//!   [`ExrOptions`], so a reader can tell what the numbers are.
//! - Compression: lossless ZIP over blocks of 16 scan lines
//!   ([`ExrCompression::Zip`], the default) or none. Both are built into
//!   `exr` without optional features.
//! - The `chromaticities` header attribute: for RGB, the sRGB / Rec. 709
//!   primaries and D65 white, (0.64, 0.33), (0.30, 0.60), (0.15, 0.06),
//!   white (0.3127, 0.3290); for XYZ, the primaries of CIE XYZ itself, red
//!   (1, 0), green (0, 1), blue (0, 0), white (1/3, 1/3) (equal-energy
//!   illuminant E), the convention OpenEXR uses to mark XYZ data. Generic
//!   viewers map `R, G, B` channels to the screen; `X, Y, Z` channels are
//!   for tools that read them by name (many show `Y` as luminance).
//! - A sky image's channels from its CIE XYZ: [`SkyImageUnits::image`],
//!   the one conversion (XYZ or linear sRGB, radiance or luminance units)
//!   behind `sora render -o sky.exr` and the explorer's EXR download.
//! - The `software` attribute is `sora <version>`.
//! - The header's attributes are sorted by name (as the OpenEXR library
//!   writes them), so the same image makes the same file byte for byte.
//!
//! The file is written atomically, as [`OutputFiles`] describes.

use std::io::Write;
use std::path::Path;

use ::exr::math::Vec2;
use ::exr::meta::attribute::{AttributeValue, Chromaticities, Compression, LineOrder, Text};
use ::exr::meta::header::LayerAttributes;
use ::exr::prelude::{AnyChannel, AnyChannels, Blocks, Encoding, FlatSamples, Image, Layer};
use ::exr::prelude::{SmallVec, WritableImage, f16};

use super::atomic_file::OutputFiles;
use super::image_buffer::{ChannelKind, LinearImage};
use crate::colour::{RgbColourSpace, Xyz};
use crate::{Error, Result};

/// The sample type of the channels in an OpenEXR file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ExrSampleType {
    /// 32-bit IEEE float: every value of a [`LinearImage`] is stored exactly.
    #[default]
    F32,
    /// 16-bit half float: half the size, 11 significant bits (relative
    /// rounding error at most 2^-11 for magnitudes in 2^-14..=65504); a
    /// value beyond 65504 is an error.
    F16,
    /// As [`ExrSampleType::F16`], magnitudes beyond 65504 clamped to it
    /// (the sun's core in luminance units, typically).
    F16Clamped,
}

/// How the pixel data of an OpenEXR file is compressed; both are lossless.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ExrCompression {
    /// Deflate (zlib) over blocks of 16 scan lines: smaller, slower.
    #[default]
    Zip,
    /// Raw samples: largest, fastest, readable by anything.
    Uncompressed,
}

/// Options for [`write_exr`]; the default is 32-bit float, ZIP compressed,
/// no unit attributes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExrOptions {
    /// Sample type of all three channels.
    pub sample_type: ExrSampleType,
    /// Compression of the pixel data.
    pub compression: ExrCompression,
    /// The `whiteLuminance` attribute: cd/m^2 of RGB = (1, 1, 1).
    pub white_luminance_cd_m2: Option<f32>,
    /// Text attributes, written as `sora:<name>` (e.g. `units`).
    pub text_attributes: Vec<(String, String)>,
}

/// What the channels of a sky image hold, as [`ExrOptions::sky_image`]
/// labels them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum SkyImageUnits {
    /// CIE XYZ (or linear RGB from it) of the spectral radiance integrated
    /// over nm, without the 683 lm/W: W m^-2 sr^-1 weighted by the
    /// colour-matching functions. `whiteLuminance` is 683.
    #[default]
    Radiance,
    /// As [`SkyImageUnits::Radiance`] times 683 lm/W, so that Y is the
    /// luminance in cd/m^2. `whiteLuminance` is 1.
    Luminance,
}

impl SkyImageUnits {
    /// The `sora:units` attribute's text.
    pub fn description(self) -> &'static str {
        match self {
            Self::Radiance => {
                "radiance_w_m2_sr (XYZ of spectral radiance integrated over nm, no 683 lm/W)"
            }
            Self::Luminance => "luminance_cd_m2 (Y in cd/m^2)",
        }
    }

    /// The `whiteLuminance` attribute: cd/m^2 of a channel value of 1.
    pub fn white_luminance_cd_m2(self) -> f32 {
        match self {
            Self::Radiance => crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W as f32,
            Self::Luminance => 1.0,
        }
    }
}

impl SkyImageUnits {
    /// A colour's three channels of `kind` in these units: CIE XYZ as
    /// rendered (radiance units), times 683 lm/W for
    /// [`SkyImageUnits::Luminance`], then kept as XYZ
    /// ([`ChannelKind::Xyz`]) or taken to linear sRGB
    /// ([`ChannelKind::Rgb`], [`RgbColourSpace::Srgb`]'s matrix).
    pub fn channels(self, kind: ChannelKind, xyz: Xyz) -> [f64; 3] {
        let c = match self {
            Self::Radiance => xyz,
            Self::Luminance => xyz.scaled(crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W),
        };
        match kind {
            ChannelKind::Xyz => [c.x, c.y, c.z],
            ChannelKind::Rgb => RgbColourSpace::Srgb.linear_rgb_from_xyz(c).to_array(),
        }
    }

    /// A sky image of `kind`'s channels in these units from its pixels'
    /// CIE XYZ (radiance units, row-major, top row first), as `sora render
    /// -o sky.exr` and the explorer's download write it: each pixel
    /// through [`SkyImageUnits::channels`], stored as `f32`. Fails as
    /// [`LinearImage::new`] does.
    pub fn image(
        self,
        kind: ChannelKind,
        width: usize,
        height: usize,
        xyz: impl IntoIterator<Item = Xyz>,
    ) -> Result<LinearImage> {
        let pixels = xyz
            .into_iter()
            .map(|c| self.channels(kind, c).map(|v| v as f32))
            .collect();
        LinearImage::new(width, height, kind, pixels)
    }
}

impl ExrOptions {
    /// The header of a rendered sky image, as `sora render -o sky.exr` and
    /// the explorer's download write it: `whiteLuminance` and `sora:units`
    /// from `units`, then `sora:sun_elevation_deg` and
    /// `sora:sun_azimuth_deg` (the sun's apparent position, degrees);
    /// 32-bit floats, ZIP compressed. Callers add their own attributes to
    /// [`ExrOptions::text_attributes`] and choose
    /// [`ExrOptions::sample_type`].
    pub fn sky_image(units: SkyImageUnits, sun_elevation_deg: f64, sun_azimuth_deg: f64) -> Self {
        Self {
            white_luminance_cd_m2: Some(units.white_luminance_cd_m2()),
            text_attributes: vec![
                ("units".into(), units.description().into()),
                ("sun_elevation_deg".into(), sun_elevation_deg.to_string()),
                ("sun_azimuth_deg".into(), sun_azimuth_deg.to_string()),
            ],
            ..Self::default()
        }
    }
}

/// The largest finite half-float value.
const HALF_FLOAT_MAX: f32 = 65504.0;

/// Writes `image` to `path` as an OpenEXR file with three linear channels
/// named after its [`ChannelKind`], of the sample type and compression in
/// `options`, atomically: on any failure, no partial file is left and an
/// existing file at `path` is unchanged.
///
/// Fails (before creating any file) if `options` asks for half floats and a
/// value would overflow them; the error names the pixel and channel. I/O
/// and encoder errors name `path`.
pub fn write_exr(path: impl AsRef<Path>, image: &LinearImage, options: ExrOptions) -> Result<()> {
    write_exr_with_layers(path, image, &[], options)
}

/// [`write_exr`] with `layers` beside the image, each as channels
/// `<name>.R, <name>.G, <name>.B` (or `.X, .Y, .Z`) of the same part; an
/// error, before any file is made, if a layer's size or channel kind is
/// not the image's.
pub fn write_exr_with_layers(
    path: impl AsRef<Path>,
    image: &LinearImage,
    layers: &[(&str, &LinearImage)],
    options: ExrOptions,
) -> Result<()> {
    let mut files = OutputFiles::new();
    files.exr_with_layers(path, image, layers, options)?;
    files.commit()
}

impl OutputFiles {
    /// Stages the file [`write_exr_with_layers`] writes (see
    /// [`OutputFiles`]).
    pub fn exr_with_layers(
        &mut self,
        path: impl AsRef<Path>,
        image: &LinearImage,
        layers: &[(&str, &LinearImage)],
        options: ExrOptions,
    ) -> Result<()> {
        let path = path.as_ref();
        // Encoded in memory first: a half-float overflow or an encoder error
        // leaves no file behind, and the file is written in one piece.
        let bytes =
            encode_exr_with_layers(image, layers, options).map_err(|error| match error {
                Error::Io { message, .. } => Error::Io {
                    path: path.display().to_string(),
                    message,
                },
                other => other,
            })?;
        self.stage(path, |file| {
            file.write_all(&bytes).map_err(|error| Error::Io {
                path: path.display().to_string(),
                message: format!("cannot write OpenEXR: {error}"),
            })
        })
    }
}

/// The OpenEXR file [`write_exr`] writes, as bytes in memory (for a
/// browser download or a network reply, where there is no file system).
///
/// Fails as [`write_exr`] does before it creates a file; an encoder error
/// is an [`Error::Io`] with the path `"(memory)"`.
pub fn encode_exr(image: &LinearImage, options: ExrOptions) -> Result<Vec<u8>> {
    encode_exr_with_layers(image, &[], options)
}

/// The bytes of [`write_exr_with_layers`]'s file (see [`encode_exr`]).
pub fn encode_exr_with_layers(
    image: &LinearImage,
    layers: &[(&str, &LinearImage)],
    options: ExrOptions,
) -> Result<Vec<u8>> {
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (prefix, layer) in std::iter::once(("", image)).chain(layers.iter().copied()) {
        if (layer.width(), layer.height(), layer.channel_kind())
            != (image.width(), image.height(), image.channel_kind())
        {
            return Err(Error::Unsupported(format!(
                "OpenEXR layer {prefix}: {} x {} {:?} pixels, but the image is {} x {} {:?}",
                layer.width(),
                layer.height(),
                layer.channel_kind(),
                image.width(),
                image.height(),
                image.channel_kind()
            )));
        }
        for (channel, name) in layer.channel_kind().channel_names().into_iter().enumerate() {
            let name = if prefix.is_empty() {
                name.to_string()
            } else {
                format!("{prefix}.{name}")
            };
            let samples = channel_samples(layer, channel, &name, options.sample_type)?;
            channels.push(AnyChannel::new(name.as_str(), samples));
        }
    }

    let layer_attributes = LayerAttributes {
        software_name: Some(Text::from(concat!("sora ", env!("CARGO_PKG_VERSION")))),
        white_luminance: options.white_luminance_cd_m2,
        ..LayerAttributes::default()
    };
    let layer = Layer::new(
        Vec2(image.width(), image.height()),
        layer_attributes,
        encoding(options.compression),
        AnyChannels::sort(channels),
    );
    let mut exr_image = Image::from_layer(layer);
    exr_image.attributes.chromaticities = Some(chromaticities(image.channel_kind()));
    for (name, value) in &options.text_attributes {
        exr_image.layer_data.attributes.other.insert(
            Text::from(format!("sora:{name}").as_str()),
            AttributeValue::Text(Text::from(value.as_str())),
        );
    }

    let mut bytes = Vec::new();
    exr_image
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|error| Error::Io {
            path: "(memory)".to_string(),
            message: format!("cannot encode OpenEXR: {error}"),
        })?;
    sort_header_attributes(&mut bytes);
    Ok(bytes)
}

/// Puts the attributes of a single-part file's header in the order of
/// their names, in place. The `exr` crate keeps the other attributes
/// (ours, `sora:*`) in a hash map with a random order per run, so the same
/// image made two files that differed in their headers; the OpenEXR
/// library itself writes attributes sorted by name. The header's length
/// does not change, so the offset table after it stays right. A header
/// that does not parse as expected is left alone.
///
/// The layout (OpenEXR file layout, "Header"): after the magic number and
/// the version field (4 bytes each), attributes of name (NUL-terminated),
/// type name (NUL-terminated), value size (i32, little-endian) and value,
/// ended by an empty name (one NUL byte).
fn sort_header_attributes(bytes: &mut [u8]) {
    const MULTIPART: u32 = 0x1000;
    let Some(version) = bytes.get(4..8) else {
        return;
    };
    if u32::from_le_bytes([version[0], version[1], version[2], version[3]]) & MULTIPART != 0 {
        return;
    }
    let nul = |from: usize| bytes[from..].iter().position(|b| *b == 0).map(|p| from + p);
    // (start, end of the name, end) of each attribute.
    let mut records: Vec<(usize, usize, usize)> = Vec::new();
    let mut at = 8;
    loop {
        let Some(name_end) = nul(at) else {
            return;
        };
        if name_end == at {
            break;
        }
        let Some(type_end) = nul(name_end + 1) else {
            return;
        };
        let Some(size) = bytes.get(type_end + 1..type_end + 5) else {
            return;
        };
        let size = i32::from_le_bytes([size[0], size[1], size[2], size[3]]);
        let Ok(size) = usize::try_from(size) else {
            return;
        };
        let end = type_end + 5 + size;
        if end > bytes.len() {
            return;
        }
        records.push((at, name_end, end));
        at = end;
    }
    records.sort_by(|a, b| bytes[a.0..a.1].cmp(&bytes[b.0..b.1]));
    let reordered: Vec<u8> = records
        .iter()
        .flat_map(|(start, _, end)| bytes[*start..*end].iter().copied())
        .collect();
    bytes[8..at].copy_from_slice(&reordered);
}

/// One channel of `image` (named `name` in the file) as a flat, row-major
/// sample vector of `sample_type`, rejecting values that half floats
/// cannot hold.
fn channel_samples(
    image: &LinearImage,
    channel: usize,
    name: &str,
    sample_type: ExrSampleType,
) -> Result<FlatSamples> {
    let values = image.pixels().iter().map(|pixel| pixel[channel]);
    match sample_type {
        ExrSampleType::F32 => Ok(FlatSamples::F32(values.collect())),
        ExrSampleType::F16Clamped => Ok(FlatSamples::F16(
            values
                .map(|value| f16::from_f32(value.clamp(-HALF_FLOAT_MAX, HALF_FLOAT_MAX)))
                .collect(),
        )),
        ExrSampleType::F16 => {
            let mut halves = Vec::with_capacity(image.pixels().len());
            for (index, value) in values.enumerate() {
                let half = f16::from_f32(value);
                // Values just above the maximum round down to it; only those
                // that round to infinity are lost.
                if half.is_infinite() {
                    let (x, y) = (index % image.width(), index / image.width());
                    return Err(Error::out_of_range(
                        format!("half-float OpenEXR pixel ({x}, {y}) channel {name}"),
                        f64::from(value),
                        "1",
                        format!(
                            "magnitudes up to {HALF_FLOAT_MAX} (write 32-bit float samples instead)"
                        ),
                    ));
                }
                halves.push(half);
            }
            Ok(FlatSamples::F16(halves))
        }
    }
}

/// The block layout and compression for `compression`: scan lines, top to
/// bottom, so that files stream in the order of the image rows.
fn encoding(compression: ExrCompression) -> Encoding {
    Encoding {
        compression: match compression {
            ExrCompression::Zip => Compression::ZIP16,
            ExrCompression::Uncompressed => Compression::Uncompressed,
        },
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    }
}

/// The primaries and white point that the three channels are relative to.
fn chromaticities(channel_kind: ChannelKind) -> Chromaticities {
    match channel_kind {
        ChannelKind::Rgb => Chromaticities {
            red: Vec2(0.64, 0.33),
            green: Vec2(0.30, 0.60),
            blue: Vec2(0.15, 0.06),
            white: Vec2(0.3127, 0.3290),
        },
        ChannelKind::Xyz => Chromaticities {
            red: Vec2(1.0, 0.0),
            green: Vec2(0.0, 1.0),
            blue: Vec2(0.0, 0.0),
            white: Vec2(1.0 / 3.0, 1.0 / 3.0),
        },
    }
}

/// One channel of the first layer of an OpenEXR file (for a depth buffer,
/// say): its `width` x `height` samples as f64, row-major, top row first;
/// the channel named `name`, or the file's only channel. A file that cannot
/// be read or lacks the channel is an [`Error::Io`] naming it.
pub fn read_exr_channel(path: &Path, name: &str) -> Result<(usize, usize, Vec<f64>)> {
    let io = |message: String| Error::Io {
        path: path.display().to_string(),
        message,
    };
    let image = ::exr::prelude::read_first_flat_layer_from_file(path)
        .map_err(|error| io(format!("not a readable OpenEXR file ({error})")))?;
    let size = image.layer_data.size;
    let channels = &image.layer_data.channel_data.list;
    let channel = channels
        .iter()
        .find(|c| c.name.to_string() == name)
        .or(if channels.len() == 1 {
            channels.first()
        } else {
            None
        })
        .ok_or_else(|| io(format!("no channel {name} (and not a single channel)")))?;
    let values = channel.sample_data.values_as_f32().map(f64::from).collect();
    Ok((size.0, size.1, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_image_channels_are_xyz_or_srgb_in_radiance_or_luminance() {
        let xyz = Xyz::new(0.2, 0.25, 0.3);
        let k = crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W;
        let radiance = SkyImageUnits::Radiance;
        let luminance = SkyImageUnits::Luminance;
        assert_eq!(radiance.channels(ChannelKind::Xyz, xyz), [0.2, 0.25, 0.3]);
        assert_eq!(
            luminance.channels(ChannelKind::Xyz, xyz),
            [0.2 * k, 0.25 * k, 0.3 * k]
        );
        // Back through the inverse matrix: the same XYZ.
        let rgb = radiance.channels(ChannelKind::Rgb, xyz);
        let back = RgbColourSpace::Srgb
            .xyz_from_linear_rgb(crate::colour::LinearRgb::new(rgb[0], rgb[1], rgb[2]));
        for (got, want) in [back.x, back.y, back.z].into_iter().zip([0.2, 0.25, 0.3]) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
        // A value of 1 is whiteLuminance cd/m^2 in either unit.
        for units in [radiance, luminance] {
            let y = units.channels(ChannelKind::Xyz, xyz)[1];
            let cd_m2 = y * f64::from(units.white_luminance_cd_m2());
            assert!((cd_m2 / (0.25 * k) - 1.0).abs() < 1e-12, "{units:?}");
        }
        let image = luminance
            .image(ChannelKind::Rgb, 2, 1, [xyz, Xyz::BLACK])
            .unwrap();
        let want = luminance.channels(ChannelKind::Rgb, xyz).map(|v| v as f32);
        assert_eq!(image.pixels(), &[want, [0.0; 3]]);
        assert!(luminance.image(ChannelKind::Rgb, 3, 1, [xyz]).is_err());
    }

    /// An encoded file read back with the `exr` crate: every channel and
    /// attribute of its one layer.
    fn decode(bytes: &[u8]) -> Image<Layer<AnyChannels<FlatSamples>>> {
        use ::exr::prelude::{ReadChannels, ReadLayers};
        ::exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(bytes))
            .unwrap()
    }

    /// The same image and attributes make the same bytes every time (the
    /// `exr` crate's attribute map has a random order per instance), and
    /// the file still reads back with every attribute and pixel.
    #[test]
    fn the_same_image_encodes_to_the_same_bytes() {
        let image = LinearImage::new(
            2,
            2,
            ChannelKind::Rgb,
            vec![[0.25, 0.5, 1.0], [2.0, 4.0, 8.0], [0.0; 3], [1e-3; 3]],
        )
        .unwrap();
        let options = || ExrOptions {
            white_luminance_cd_m2: Some(683.0),
            text_attributes: (0..8)
                .map(|n| (format!("name_{n}"), format!("value {n}")))
                .collect(),
            ..ExrOptions::default()
        };
        let first = encode_exr(&image, options()).unwrap();
        for _ in 0..8 {
            assert_eq!(encode_exr(&image, options()).unwrap(), first);
        }
        let decoded = decode(&first);
        let attributes = &decoded.layer_data.attributes.other;
        for n in 0..8 {
            assert_eq!(
                attributes.get(&Text::from(format!("sora:name_{n}").as_str())),
                Some(&AttributeValue::Text(Text::from(
                    format!("value {n}").as_str()
                )))
            );
        }
        let red = decoded
            .layer_data
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *"R")
            .unwrap();
        let values: Vec<f32> = red.sample_data.values_as_f32().collect();
        assert_eq!(values, [0.25, 2.0, 0.0, 1e-3]);
    }

    /// A sky image's header reads back with its units, whiteLuminance and
    /// sun, for both units, and the two units' whiteLuminance values agree
    /// with the 683 lm/W that separates them.
    #[test]
    fn a_sky_image_header_names_its_units_and_sun() {
        let image = LinearImage::new(1, 1, ChannelKind::Xyz, vec![[1.0, 2.0, 3.0]]).unwrap();
        for (units, white, unit_text) in [
            (SkyImageUnits::Radiance, 683.0, "radiance_w_m2_sr"),
            (SkyImageUnits::Luminance, 1.0, "luminance_cd_m2"),
        ] {
            let mut options = ExrOptions::sky_image(units, 12.5, -0.25);
            options
                .text_attributes
                .push(("sun_disc".into(), "false".into()));
            assert_eq!(options.sample_type, ExrSampleType::F32);
            let bytes = encode_exr(&image, options).unwrap();
            let decoded = decode(&bytes);
            let layer = &decoded.layer_data.attributes;
            assert_eq!(layer.white_luminance, Some(white));
            let text = |name: &str| match layer.other.get(&Text::from(name)) {
                Some(AttributeValue::Text(text)) => text.to_string(),
                other => panic!("{name}: {other:?}"),
            };
            assert!(text("sora:units").starts_with(unit_text));
            assert_eq!(text("sora:sun_elevation_deg"), "12.5");
            assert_eq!(text("sora:sun_azimuth_deg"), "-0.25");
            assert_eq!(text("sora:sun_disc"), "false");
        }
        assert_eq!(
            SkyImageUnits::Radiance.white_luminance_cd_m2()
                / SkyImageUnits::Luminance.white_luminance_cd_m2(),
            crate::colour::MAXIMUM_LUMINOUS_EFFICACY_LM_PER_W as f32
        );
    }

    #[test]
    fn half_float_overflow_is_rejected_naming_pixel_and_channel() {
        let image =
            LinearImage::new(2, 1, ChannelKind::Rgb, vec![[1.0; 3], [1.0, 1.0, 70000.0]]).unwrap();
        let error = channel_samples(&image, 2, "B", ExrSampleType::F16).unwrap_err();
        let message = error.to_string();
        assert!(message.contains("pixel (1, 0) channel B"), "{message}");
        assert!(message.contains("70000"), "{message}");
        // The same value is fine as a 32-bit float and other channels are
        // fine as halves.
        assert!(channel_samples(&image, 2, "B", ExrSampleType::F32).is_ok());
        assert!(channel_samples(&image, 0, "R", ExrSampleType::F16).is_ok());
    }

    #[test]
    fn clamped_half_floats_keep_the_maximum_and_the_sign() {
        let image = LinearImage::new(
            2,
            1,
            ChannelKind::Rgb,
            vec![[1.0, -1e9, 3.5], [1e9, 0.0, 65504.0]],
        )
        .unwrap();
        for (channel, expected) in [(0, [1.0, HALF_FLOAT_MAX]), (1, [-HALF_FLOAT_MAX, 0.0])] {
            let Ok(FlatSamples::F16(halves)) =
                channel_samples(&image, channel, "R", ExrSampleType::F16Clamped)
            else {
                panic!("expected half-float samples");
            };
            assert_eq!(
                halves.iter().map(|h| h.to_f32()).collect::<Vec<_>>(),
                expected
            );
        }
    }

    #[test]
    fn half_float_maximum_and_values_rounding_to_it_are_kept() {
        let image = LinearImage::new(
            3,
            1,
            ChannelKind::Xyz,
            vec![[HALF_FLOAT_MAX; 3], [65519.0; 3], [-65519.0; 3]],
        )
        .unwrap();
        let Ok(FlatSamples::F16(halves)) = channel_samples(&image, 1, "Y", ExrSampleType::F16)
        else {
            panic!("expected half-float samples");
        };
        assert_eq!(
            halves.iter().map(|h| h.to_f32()).collect::<Vec<_>>(),
            [HALF_FLOAT_MAX, HALF_FLOAT_MAX, -HALF_FLOAT_MAX]
        );
    }
}
