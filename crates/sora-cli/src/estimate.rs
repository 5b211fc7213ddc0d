//! What a run will cost, said (and bounded) before it starts.
//!
//! Memory: `sora render` holds a frame's CIE XYZ image (24 bytes a pixel)
//! and its encoded copy (PNG: the display pixels and the byte stream, 6
//! bytes a pixel at 8 bits, 12 at 16; OpenEXR: the float pixels and the
//! encoder's copy, 24 bytes a pixel at 32 bits). The total is bounded by
//! [`MAX_RENDER_BYTES`], 4 GiB, checked before any work: 143 million pixels
//! of 8-bit PNG (11 965 x 11 965), 89 million of OpenEXR (9 459 x 9 459).
//! The path tracer keeps its statistics per chunk of 1024 paths, about
//! 32 bytes per wavelength and chunk (`--samples` is itself limited to 1e9).
//!
//! Time: a run expected to take longer than [`ANNOUNCE_AFTER_S`] prints one
//! line with the estimate of its time and memory first, on stderr and only
//! when stderr is a terminal (a script's or a test's stderr stays as it
//! was). The rates are measured, release build, on the project's 2-core
//! machine (earth-clear, 21 wavelengths, multiple scattering; the cost of a
//! pixel or a path is about proportional to the number of wavelengths): an
//! estimate to a factor of a few, which is what deciding to wait needs.

use std::io::IsTerminal;

/// Most bytes `sora render` may hold for one frame's image buffers (4 GiB).
pub const MAX_RENDER_BYTES: u64 = 4 << 30;

/// Runs expected to last longer than this print their estimate, seconds.
pub const ANNOUNCE_AFTER_S: f64 = 10.0;

/// Fast method, pixels per second at 21 wavelengths, once the tables are
/// built (measured 0.47 Mpixel/s at 512 x 512).
const FAST_PIXELS_PER_S_AT_21: f64 = 4.7e5;

/// Reference method (the paper's march per pixel): measured 113 pixel/s.
const REFERENCE_PIXELS_PER_S_AT_21: f64 = 113.0;

/// Path tracer, paths per second at 21 wavelengths: measured 6.7e4.
const PATHS_PER_S_AT_21: f64 = 6.7e4;

/// Bytes of the CIE XYZ image, per pixel.
const XYZ_BYTES_PER_PIXEL: u64 = 24;

/// How a render is computed, for its time estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RenderSpeed {
    Fast,
    Reference,
}

/// The image buffers of one `width` x `height` frame whose encoded copy
/// takes `encoded_bytes_per_pixel`, bytes.
pub fn render_bytes(width: u32, height: u32, encoded_bytes_per_pixel: u64) -> u64 {
    u64::from(width) * u64::from(height) * (XYZ_BYTES_PER_PIXEL + encoded_bytes_per_pixel)
}

/// Refuses a frame whose buffers exceed [`MAX_RENDER_BYTES`], naming the
/// size, the limit and the largest square that fits.
pub fn check_render_memory(
    width: u32,
    height: u32,
    encoded_bytes_per_pixel: u64,
    format_name: &str,
) -> anyhow::Result<()> {
    let bytes = render_bytes(width, height, encoded_bytes_per_pixel);
    if bytes > MAX_RENDER_BYTES {
        let per_pixel = XYZ_BYTES_PER_PIXEL + encoded_bytes_per_pixel;
        let most_pixels = MAX_RENDER_BYTES / per_pixel;
        let side = (most_pixels as f64).sqrt().floor();
        anyhow::bail!(
            "--width {width} --height {height} needs {bytes} bytes of image buffers ({per_pixel} bytes a pixel for {format_name}), more than the limit of {MAX_RENDER_BYTES} bytes ({}): render at most {most_pixels} pixels (e.g. {side} x {side}), or tile the image",
            format_bytes(MAX_RENDER_BYTES)
        );
    }
    Ok(())
}

/// The estimate line of a render of `frames` frames, or None when it is
/// expected to take under [`ANNOUNCE_AFTER_S`].
pub fn render_estimate(
    width: u32,
    height: u32,
    frames: usize,
    wavelengths: usize,
    speed: RenderSpeed,
    encoded_bytes_per_pixel: u64,
) -> Option<String> {
    let pixels = f64::from(width) * f64::from(height) * frames as f64;
    let rate_at_21 = match speed {
        RenderSpeed::Fast => FAST_PIXELS_PER_S_AT_21,
        RenderSpeed::Reference => REFERENCE_PIXELS_PER_S_AT_21,
    };
    let seconds = pixels / (rate_at_21 * 21.0 / wavelengths.max(1) as f64);
    (seconds > ANNOUNCE_AFTER_S).then(|| {
        format!(
            "estimate: {frames} x {width}x{height} pixels at {wavelengths} wavelengths, {:?} method: about {} (to a factor of a few) and {} of image buffers",
            speed,
            format_seconds(seconds),
            format_bytes(render_bytes(width, height, encoded_bytes_per_pixel))
        )
    })
}

/// The estimate line of `samples` paths in each of `directions` at
/// `wavelengths` wavelengths, or None when under [`ANNOUNCE_AFTER_S`].
pub fn path_tracing_estimate(
    samples: u64,
    directions: usize,
    wavelengths: usize,
) -> Option<String> {
    let paths = samples as f64 * directions.max(1) as f64;
    let seconds = paths / (PATHS_PER_S_AT_21 * 21.0 / wavelengths.max(1) as f64);
    let bytes = samples.div_ceil(1024) * wavelengths as u64 * 32;
    (seconds > ANNOUNCE_AFTER_S).then(|| {
        format!(
            "estimate: {samples} paths x {} direction(s) at {wavelengths} wavelengths: about {} (to a factor of a few) and {} of statistics",
            directions.max(1),
            format_seconds(seconds),
            format_bytes(bytes)
        )
    })
}

/// Prints `line` on stderr when stderr is a terminal (see the module docs).
pub fn announce(line: Option<String>) {
    if let Some(line) = line
        && std::io::stderr().is_terminal()
    {
        eprintln!("{line}");
    }
}

fn format_seconds(seconds: f64) -> String {
    if seconds < 120.0 {
        format!("{seconds:.0} s")
    } else if seconds < 7200.0 {
        format!("{:.0} min", seconds / 60.0)
    } else if seconds < 172_800.0 {
        format!("{:.1} h", seconds / 3600.0)
    } else {
        format!("{:.1} days", seconds / 86_400.0)
    }
}

fn format_bytes(bytes: u64) -> String {
    let gib = bytes as f64 / f64::from(1u32 << 30);
    if gib >= 1.0 {
        format!("{gib:.1} GiB")
    } else {
        format!("{:.0} MiB", bytes as f64 / f64::from(1u32 << 20))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound at its edge and one past it (8-bit PNG: 30 bytes a pixel).
    #[test]
    fn render_memory_is_bounded_at_the_documented_edge() {
        let most = MAX_RENDER_BYTES / 30;
        let width = 16384u32;
        let height = (most / u64::from(width)) as u32;
        assert!(check_render_memory(width, height, 6, "8-bit PNG").is_ok());
        let message = check_render_memory(width, height + 1, 6, "8-bit PNG")
            .unwrap_err()
            .to_string();
        assert!(
            message.contains(&format!("--width 16384 --height {}", height + 1))
                && message.contains("30 bytes a pixel for 8-bit PNG")
                && message.contains("more than the limit of 4294967296 bytes (4.0 GiB)")
                && message.contains(&format!("at most {most} pixels (e.g. 11965 x 11965)")),
            "{message}"
        );
        // The documented sizes: 143 million pixels of PNG, 89 million of EXR.
        assert_eq!(most / 1_000_000, 143);
        assert_eq!(MAX_RENDER_BYTES / 48 / 1_000_000, 89);
    }

    #[test]
    fn only_long_runs_are_announced() {
        assert_eq!(render_estimate(512, 512, 1, 21, RenderSpeed::Fast, 6), None);
        let long = render_estimate(16384, 8192, 1, 21, RenderSpeed::Fast, 6).unwrap();
        assert!(
            long.contains("about 5 min") && long.contains("3.8 GiB"),
            "{long}"
        );
        let reference = render_estimate(256, 256, 1, 21, RenderSpeed::Reference, 6).unwrap();
        assert!(reference.contains("about 10 min"), "{reference}");
        assert_eq!(path_tracing_estimate(10_000, 1, 21), None);
        let traced = path_tracing_estimate(1_000_000_000, 1, 21).unwrap();
        assert!(
            traced.contains("about 4.1 h") && traced.contains("626 MiB"),
            "{traced}"
        );
    }
}
