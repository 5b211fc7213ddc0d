//! Round trips through the output stage: files written by `sora::output`
//! are read back with independent decoders (`exr`'s reader, `image`'s PNG
//! decoder) and compared value by value; failed writes must leave nothing.

use std::path::Path;

use exr::prelude::{FlatSamples, f16};
use sora::Error;
use sora::output::{
    ChannelKind, DisplayImage8, DisplayImage16, ExrCompression, ExrOptions, ExrSampleType,
    LinearImage, OutputFormat, write_exr, write_png,
};

/// Names of all entries in `directory`, sorted.
fn directory_entries(directory: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(directory)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A 7 x 5 image whose values span f32's range: zero, negative zero,
/// subnormals, the smallest normal, values near 1 that need every mantissa
/// bit, huge values and negatives, different in every pixel and channel.
fn extreme_value_image(channel_kind: ChannelKind) -> LinearImage {
    let specials = [
        0.0,
        -0.0,
        f32::from_bits(1), // smallest subnormal
        f32::MIN_POSITIVE,
        1.0e-30,
        1.0,
        1.0 + f32::EPSILON,
        std::f32::consts::PI,
        -2.5e-7,
        6.02e23,
        f32::MAX,
        -f32::MAX,
        123_456.79,
    ];
    LinearImage::from_fn(7, 5, channel_kind, |x, y| {
        let index = (y * 7 + x) * 3;
        [0, 1, 2].map(|channel| {
            let i = index + channel;
            specials[i % specials.len()]
                * if (i / specials.len()) % 2 == 0 {
                    1.0
                } else {
                    0.5
                }
        })
    })
    .unwrap()
}

/// A 6 x 4 image of values that half floats hold as normal numbers: a wide
/// spread of magnitudes (2^-14 ..= 65504), signs and non-round mantissas.
fn half_range_image(channel_kind: ChannelKind) -> LinearImage {
    LinearImage::from_fn(6, 4, channel_kind, |x, y| {
        [0, 1, 2].map(|channel| {
            let i = (y * 6 + x) * 3 + channel;
            let exponent = (i % 31) as i32 - 14; // -14 ..= 16 but capped below
            let mantissa = 1.0 + (i as f32 * 0.618_034).fract() * 0.999;
            let sign = if i % 5 == 0 { -1.0 } else { 1.0 };
            (sign * mantissa * 2.0_f32.powi(exponent)).clamp(-65504.0, 65504.0)
        })
    })
    .unwrap()
}

/// One channel of the first layer of the OpenEXR file at `path`, looked up
/// by name, with its samples, and the file's chromaticities.
struct ReadBackExr {
    channel_names: Vec<String>,
    samples_by_name: Vec<(String, FlatSamples)>,
    size: (usize, usize),
    chromaticities: exr::meta::attribute::Chromaticities,
    compression: exr::meta::attribute::Compression,
}

fn read_back_exr(path: &Path) -> ReadBackExr {
    let image = exr::prelude::read_first_flat_layer_from_file(path).unwrap();
    let layer = image.layer_data;
    let channels = layer.channel_data.list;
    ReadBackExr {
        channel_names: channels.iter().map(|c| c.name.to_string()).collect(),
        samples_by_name: channels
            .into_iter()
            .map(|c| (c.name.to_string(), c.sample_data))
            .collect(),
        size: (layer.size.width(), layer.size.height()),
        chromaticities: image.attributes.chromaticities.unwrap(),
        compression: layer.encoding.compression,
    }
}

impl ReadBackExr {
    fn samples(&self, name: &str) -> &FlatSamples {
        &self
            .samples_by_name
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no channel {name}"))
            .1
    }
}

#[test]
fn f32_exr_reads_back_bit_for_bit_for_rgb_and_xyz() {
    let directory = tempfile::tempdir().unwrap();
    for channel_kind in [ChannelKind::Rgb, ChannelKind::Xyz] {
        for compression in [ExrCompression::Zip, ExrCompression::Uncompressed] {
            let image = extreme_value_image(channel_kind);
            let path = directory
                .path()
                .join(format!("{channel_kind:?}-{compression:?}.exr"));
            let options = ExrOptions {
                sample_type: ExrSampleType::F32,
                compression,
                ..ExrOptions::default()
            };
            write_exr(&path, &image, options).unwrap();

            let read = read_back_exr(&path);
            assert_eq!(read.size, (7, 5));
            let mut expected_names = channel_kind.channel_names().map(String::from).to_vec();
            expected_names.sort();
            assert_eq!(read.channel_names, expected_names);
            let expected_compression = match compression {
                ExrCompression::Zip => exr::meta::attribute::Compression::ZIP16,
                ExrCompression::Uncompressed => exr::meta::attribute::Compression::Uncompressed,
            };
            assert_eq!(read.compression, expected_compression);
            for (channel, name) in channel_kind.channel_names().into_iter().enumerate() {
                let FlatSamples::F32(samples) = read.samples(name) else {
                    panic!("channel {name} is not f32");
                };
                let expected: Vec<u32> = image
                    .pixels()
                    .iter()
                    .map(|p| p[channel].to_bits())
                    .collect();
                let actual: Vec<u32> = samples.iter().map(|v| v.to_bits()).collect();
                assert_eq!(
                    actual, expected,
                    "{channel_kind:?} {compression:?} channel {name}"
                );
            }
        }
    }
}

#[test]
fn f16_exr_reads_back_within_half_float_rounding_for_rgb_and_xyz() {
    let directory = tempfile::tempdir().unwrap();
    for channel_kind in [ChannelKind::Rgb, ChannelKind::Xyz] {
        let image = half_range_image(channel_kind);
        let path = directory.path().join(format!("{channel_kind:?}-half.exr"));
        let options = ExrOptions {
            sample_type: ExrSampleType::F16,
            ..ExrOptions::default()
        };
        write_exr(&path, &image, options).unwrap();

        let read = read_back_exr(&path);
        assert_eq!(read.size, (6, 4));
        for (channel, name) in channel_kind.channel_names().into_iter().enumerate() {
            let FlatSamples::F16(samples) = read.samples(name) else {
                panic!("channel {name} is not f16");
            };
            assert_eq!(samples.len(), 24);
            for (pixel, half) in image.pixels().iter().zip(samples) {
                let expected = pixel[channel];
                let actual = half.to_f32();
                assert!(
                    (actual - expected).abs() <= expected.abs() * 2.0_f32.powi(-11),
                    "{channel_kind:?} {name}: wrote {expected}, read {actual}"
                );
                // Rounded to nearest: exactly what a direct conversion gives.
                assert_eq!(*half, f16::from_f32(expected));
            }
        }
    }
}

#[test]
fn exr_chromaticities_name_the_primaries_of_the_channels() {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join("rgb.exr");
    write_exr(
        &path,
        &extreme_value_image(ChannelKind::Rgb),
        ExrOptions::default(),
    )
    .unwrap();
    let rgb = read_back_exr(&path).chromaticities;
    assert_eq!((rgb.red.x(), rgb.red.y()), (0.64, 0.33));
    assert_eq!((rgb.green.x(), rgb.green.y()), (0.30, 0.60));
    assert_eq!((rgb.blue.x(), rgb.blue.y()), (0.15, 0.06));
    assert_eq!((rgb.white.x(), rgb.white.y()), (0.3127, 0.3290));

    let path = directory.path().join("xyz.exr");
    write_exr(
        &path,
        &extreme_value_image(ChannelKind::Xyz),
        ExrOptions::default(),
    )
    .unwrap();
    let xyz = read_back_exr(&path).chromaticities;
    assert_eq!((xyz.red.x(), xyz.red.y()), (1.0, 0.0));
    assert_eq!((xyz.green.x(), xyz.green.y()), (0.0, 1.0));
    assert_eq!((xyz.blue.x(), xyz.blue.y()), (0.0, 0.0));
    assert_eq!((xyz.white.x(), xyz.white.y()), (1.0 / 3.0, 1.0 / 3.0));
}

#[test]
fn half_float_overflow_fails_before_touching_the_target() {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join("sun.exr");
    std::fs::write(&path, b"previous").unwrap();
    let image = LinearImage::new(1, 1, ChannelKind::Xyz, vec![[1.0, 1.0e6, 1.0]]).unwrap();
    let options = ExrOptions {
        sample_type: ExrSampleType::F16,
        ..ExrOptions::default()
    };
    let error = write_exr(&path, &image, options).unwrap_err();
    assert!(
        error.to_string().contains("pixel (0, 0) channel Y"),
        "{error}"
    );
    assert_eq!(std::fs::read(&path).unwrap(), b"previous");
    assert_eq!(directory_entries(directory.path()), ["sun.exr"]);
}

#[test]
fn png_8_bit_ramp_decodes_to_the_same_bytes() {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join("ramp.png");
    // 256 x 3 image: row 0 ramps red, row 1 green, row 2 all channels, with
    // the other channels holding distinct patterns so swaps would show.
    let (width, height) = (256, 3);
    let mut data = Vec::with_capacity(width * height * 3);
    for y in 0..height {
        for x in 0..width {
            let ramp = x as u8;
            let pixel = match y {
                0 => [ramp, 0, 255 - ramp],
                1 => [17, ramp, 200],
                _ => [ramp, ramp, ramp],
            };
            data.extend_from_slice(&pixel);
        }
    }
    let image = DisplayImage8::new(width, height, data.clone()).unwrap();
    write_png(&path, &image).unwrap();

    let decoded = image::open(&path).unwrap();
    assert_eq!(decoded.color(), image::ColorType::Rgb8);
    assert_eq!((decoded.width(), decoded.height()), (256, 3));
    assert_eq!(decoded.into_rgb8().into_raw(), data);
    assert_eq!(directory_entries(directory.path()), ["ramp.png"]);
}

#[test]
fn png_16_bit_ramp_decodes_to_the_same_samples() {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join("ramp16.png");
    // Samples whose two bytes differ, so a byte-order mistake would show.
    let (width, height) = (300, 2);
    let data: Vec<u16> = (0..width * height * 3)
        .map(|i| (i as u32 * 65535 / (width * height * 3 - 1) as u32) as u16 ^ 0x0100)
        .collect();
    let image = DisplayImage16::new(width, height, data.clone()).unwrap();
    write_png(&path, &image).unwrap();

    let decoded = image::open(&path).unwrap();
    assert_eq!(decoded.color(), image::ColorType::Rgb16);
    assert_eq!((decoded.width(), decoded.height()), (300, 2));
    assert_eq!(decoded.into_rgb16().into_raw(), data);
}

#[test]
fn an_existing_file_is_replaced_on_success() {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join("sky.png");
    std::fs::write(&path, b"not a png").unwrap();
    let image = DisplayImage8::new(1, 1, vec![1, 2, 3]).unwrap();
    write_png(&path, &image).unwrap();
    assert_eq!(
        image::open(&path).unwrap().into_rgb8().into_raw(),
        [1, 2, 3]
    );
    assert_eq!(directory_entries(directory.path()), ["sky.png"]);
}

/// Asserts that `error` is an I/O error naming `path`.
fn assert_io_error_names(error: Error, path: &Path) {
    match error {
        Error::Io { path: named, .. } => assert_eq!(named, path.display().to_string()),
        other => panic!(
            "expected an I/O error naming {}, got {other}",
            path.display()
        ),
    }
}

/// Asserts that `error` is the one-line refusal of the output path `path`
/// (`sora::output::output_target`), saying `why`.
fn assert_refused(error: Error, path: &Path, why: &str) {
    match error {
        Error::Unsupported(message) => {
            assert!(
                message.starts_with(&format!("output {}", path.display())) && message.contains(why),
                "{message}"
            );
            assert!(!message.contains('\n'), "{message}");
        }
        other => panic!("expected the refusal of {}, got {other}", path.display()),
    }
}

#[test]
fn writing_into_a_missing_directory_fails_naming_the_path_and_leaves_nothing() {
    let directory = tempfile::tempdir().unwrap();
    let missing = directory.path().join("no-such-directory");
    let png_path = missing.join("sky.png");
    let error = write_png(&png_path, &DisplayImage8::new(1, 1, vec![0; 3]).unwrap()).unwrap_err();
    assert!(
        error.to_string().contains("no-such-directory/sky.png"),
        "{error}"
    );
    assert_refused(error, &png_path, "does not exist");

    let exr_path = missing.join("sky.exr");
    let error = write_exr(
        &exr_path,
        &extreme_value_image(ChannelKind::Rgb),
        ExrOptions::default(),
    )
    .unwrap_err();
    assert_refused(error, &exr_path, "does not exist");
    assert!(!missing.exists());
    assert!(directory_entries(directory.path()).is_empty());
}

#[test]
fn writing_onto_a_directory_fails_and_leaves_no_temporary_file() {
    let directory = tempfile::tempdir().unwrap();
    // The target is an existing directory: refused before a temporary file
    // is made.
    let png_target = directory.path().join("occupied.png");
    std::fs::create_dir(&png_target).unwrap();
    std::fs::write(png_target.join("keep.txt"), b"keep").unwrap();
    let error =
        write_png(&png_target, &DisplayImage16::new(2, 1, vec![9; 6]).unwrap()).unwrap_err();
    assert_refused(error, &png_target, "is a directory");

    let exr_target = directory.path().join("occupied.exr");
    std::fs::create_dir(&exr_target).unwrap();
    let error = write_exr(
        &exr_target,
        &half_range_image(ChannelKind::Xyz),
        ExrOptions::default(),
    )
    .unwrap_err();
    assert_refused(error, &exr_target, "is a directory");

    assert_eq!(
        directory_entries(directory.path()),
        ["occupied.exr", "occupied.png"]
    );
    assert_eq!(directory_entries(&png_target), ["keep.txt"]);
    assert!(directory_entries(&exr_target).is_empty());
}

#[test]
fn the_format_follows_the_extension() {
    assert_eq!(
        OutputFormat::from_path("a/b/Sky.PNG").unwrap(),
        OutputFormat::Png
    );
    assert_eq!(
        OutputFormat::from_path("sky.Exr").unwrap(),
        OutputFormat::Exr
    );
    let error = OutputFormat::from_path("sky.jpg").unwrap_err();
    assert_io_error_names(error.clone(), Path::new("sky.jpg"));
    assert!(error.to_string().contains(".png, .exr"), "{error}");
}

#[test]
fn invalid_images_never_reach_a_file() {
    let error =
        LinearImage::new(2, 1, ChannelKind::Rgb, vec![[0.0; 3], [0.0, 0.0, f32::NAN]]).unwrap_err();
    assert!(
        error.to_string().contains("pixel (1, 0) channel B"),
        "{error}"
    );
    assert!(LinearImage::new(0, 0, ChannelKind::Xyz, Vec::new()).is_err());
    assert!(DisplayImage8::new(0, 1, Vec::new()).is_err());
    assert!(DisplayImage16::new(1, 0, Vec::new()).is_err());
}

/// The unit attributes come back: `whiteLuminance` and the `sora:*` texts.
#[test]
fn exr_unit_attributes_round_trip() {
    let directory = tempfile::tempdir().unwrap();
    let path = directory.path().join("units.exr");
    let image = LinearImage::new(1, 1, ChannelKind::Rgb, vec![[1.0, 2.0, 3.0]]).unwrap();
    let options = ExrOptions {
        white_luminance_cd_m2: Some(683.0),
        text_attributes: vec![
            ("units".into(), "radiance".into()),
            ("sun_elevation_deg".into(), "30".into()),
        ],
        ..ExrOptions::default()
    };
    write_exr(&path, &image, options).unwrap();
    let read = exr::prelude::read_first_flat_layer_from_file(&path).unwrap();
    assert_eq!(read.layer_data.attributes.white_luminance, Some(683.0));
    let text = |name: &str| match read
        .layer_data
        .attributes
        .other
        .get(&exr::meta::attribute::Text::from(name))
    {
        Some(exr::meta::attribute::AttributeValue::Text(text)) => text.to_string(),
        other => panic!("{name}: {other:?}"),
    };
    assert_eq!(text("sora:units"), "radiance");
    assert_eq!(text("sora:sun_elevation_deg"), "30");
}
