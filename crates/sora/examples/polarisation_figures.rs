//! The polarisation figures of `docs/polarisation.md`: the neutral points
//! the fast method puts on the sun's vertical, marked on the degree-of-
//! polarisation maps that `sora render --dolp` wrote, and the change of
//! the intensity from scalar to polarised light over the whole sky.
//!
//! ```sh
//! for case in "us-standard-1976-rayleigh 30" "us-standard-1976-rayleigh 2" \
//!             "earth-clear 30" "earth-clear 2"; do
//!   set -- $case
//!   sora render --preset $1 --sun-elevation $2 --width 384 --no-sun-disc \
//!       -o /tmp/$1_$2.png --dolp docs/polarisation_degree_$1_sun$2.png
//! done
//! cargo run --release -p sora --example polarisation_figures -- docs
//! ```
//!
//! For each case it prints the neutral points (where the luminance-weighted
//! Q changes sign along the sun's vertical: Babinet's above the sun,
//! Brewster's below it, Arago's above the antisolar point), marks them with
//! white rings on the map (the sun with a black one), and writes
//! `polarisation_intensity_change_<preset>_sun<elevation>.png`: the
//! luminance's I_vector / I_scalar - 1, blue at -5 % through white to red
//! at 5 %, a colour bar below, and prints its range.

use sora::colour::{Observer, SpectrumToXyz};
use sora::output::{DisplayImage, write_png};
use sora::{Atmosphere, Camera, ImageSettings, Polarisation, Sky, ViewDirection};

/// The fisheye's side, pixels (as the `sora render` commands above).
const SIDE: u32 = 384;

/// The equidistant fisheye's pixel of (elevation, azimuth): zenith at the
/// centre, north up, east left, the horizon at the rim.
fn fisheye_pixel(elevation_deg: f64, azimuth_deg: f64) -> (f64, f64) {
    let radius = (90.0 - elevation_deg) / 90.0 * f64::from(SIDE) / 2.0;
    let (sin, cos) = azimuth_deg.to_radians().sin_cos();
    let centre = f64::from(SIDE) / 2.0;
    (centre - radius * sin, centre - radius * cos)
}

/// Draws a ring of `colour` around pixel `(x, y)`.
fn ring(data: &mut [u8], width: usize, (x, y): (f64, f64), colour: [u8; 3]) {
    for step in 0..360 {
        let angle = f64::from(step).to_radians();
        for radius in [5.0, 6.0] {
            let (px, py) = (x + radius * angle.cos(), y + radius * angle.sin());
            if px >= 0.0 && py >= 0.0 && (px as usize) < width && (py as usize) < SIDE as usize {
                let start = (py as usize * width + px as usize) * 3;
                data[start..start + 3].copy_from_slice(&colour);
            }
        }
    }
}

/// The luminance-weighted Stokes Q of the view (elevation, azimuth).
fn luminance_q(sky: &Sky, to_xyz: &SpectrumToXyz, views: &[(f64, f64)]) -> Vec<f64> {
    let views: Vec<ViewDirection> = views
        .iter()
        .map(|&(e, a)| ViewDirection::new(e, a).expect("view"))
        .collect();
    sky.radiances(&views)
        .expect("radiances")
        .iter()
        .map(|r| {
            let stokes = r.stokes.as_ref().expect("a polarised sky");
            to_xyz.to_xyz_signed(&stokes.q_w_m2_sr_nm).expect("xyz").y
        })
        .collect()
}

/// Where Q changes sign along `path(t)` for t from 0.5 to 45 degrees
/// (every 0.25 degree, then the crossing interpolated linearly): the
/// first crossing's t.
fn neutral_point(
    sky: &Sky,
    to_xyz: &SpectrumToXyz,
    path: impl Fn(f64) -> Option<(f64, f64)>,
) -> Option<f64> {
    let ts: Vec<f64> = (2..=180).map(|k| f64::from(k) * 0.25).collect();
    let points: Vec<(f64, (f64, f64))> = ts.iter().filter_map(|&t| Some((t, path(t)?))).collect();
    let q = luminance_q(sky, to_xyz, &points.iter().map(|p| p.1).collect::<Vec<_>>());
    points.windows(2).zip(q.windows(2)).find_map(|(p, q)| {
        (q[0].signum() != q[1].signum()).then(|| p[0].0 + (p[1].0 - p[0].0) * q[0] / (q[0] - q[1]))
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let directory = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or("docs".into()));
    for (preset, sun) in [
        ("us-standard-1976-rayleigh", 30.0),
        ("us-standard-1976-rayleigh", 2.0),
        ("earth-clear", 30.0),
        ("earth-clear", 2.0),
    ] {
        let atmosphere = Atmosphere::preset(preset)?;
        let builder = Sky::builder(&atmosphere).sun_deg(sun, 180.0);
        let vector = builder.polarisation(Polarisation::Vector).build()?;
        let scalar = Sky::builder(&atmosphere)
            .sun_deg(sun, 180.0)
            .polarisation(sora::Polarisation::Scalar)
            .build()?;
        let to_xyz = SpectrumToXyz::new(vector.wavelengths(), Observer::Cie1931TwoDegree);
        // The sun's vertical: the sun in the south (azimuth 180).
        let above_sun = |t: f64| {
            let elevation = sun + t;
            if elevation < 90.0 {
                Some((elevation, 180.0))
            } else {
                Some((180.0 - elevation, 0.0))
            }
        };
        let below_sun = |t: f64| (sun - t > 0.5).then_some((sun - t, 180.0));
        let above_antisun = |t: f64| (t - sun > 0.5).then_some((t - sun, 0.0));
        let babinet = neutral_point(&vector, &to_xyz, above_sun);
        let brewster = neutral_point(&vector, &to_xyz, below_sun);
        let arago = neutral_point(&vector, &to_xyz, above_antisun);
        let show = |p: Option<f64>| {
            p.map_or("none above the horizon".to_string(), |t| {
                format!("{t:.1} deg")
            })
        };
        println!(
            "{preset} sun {sun}: Babinet {} above the sun, Brewster {} below it, Arago {} above the antisolar point",
            show(babinet),
            show(brewster),
            show(arago)
        );
        // The rings on the degree map `sora render --dolp` wrote.
        let map_path = directory.join(format!("polarisation_degree_{preset}_sun{sun}.png"));
        if let Ok(map) = image::open(&map_path) {
            let mut map = map.to_rgb8();
            let width = map.width() as usize;
            let data: &mut [u8] = &mut map;
            for (point, path) in [
                (babinet, &above_sun as &dyn Fn(f64) -> Option<(f64, f64)>),
                (brewster, &below_sun),
                (arago, &above_antisun),
            ] {
                if let Some((e, a)) = point.and_then(path) {
                    ring(data, width, fisheye_pixel(e, a), [255, 255, 255]);
                }
            }
            ring(data, width, fisheye_pixel(sun, 180.0), [0, 0, 0]);
            map.save(&map_path)?;
            println!("  marked {}", map_path.display());
        }
        // The intensity change from scalar to polarised light.
        let image = ImageSettings {
            draw_sun_disc: false,
            ..ImageSettings::new(Camera::Fisheye, SIDE, SIDE)
        };
        let with = vector.render_xyz(&image, &to_xyz, &|_| {})?;
        let without = scalar.render_xyz(&image, &to_xyz, &|_| {})?;
        let bar_rows = 24;
        let side = SIDE as usize;
        let mut data = vec![0u8; side * (side + bar_rows) * 3];
        let colour = |change: f64| -> [u8; 3] {
            // Blue (-5 %) through white to red (+5 %).
            let t = (change / 0.05).clamp(-1.0, 1.0);
            let fade = |c: f64| (255.0 * c).round() as u8;
            if t < 0.0 {
                [fade(1.0 + t), fade(1.0 + 0.6 * t), 255]
            } else {
                [255, fade(1.0 - 0.6 * t), fade(1.0 - t)]
            }
        };
        let (mut low, mut high) = (f64::MAX, f64::MIN);
        for (k, (v, s)) in with.iter().zip(&without).enumerate() {
            if s.y > 0.0 {
                let change = v.y / s.y - 1.0;
                (low, high) = (low.min(change), high.max(change));
                data[k * 3..k * 3 + 3].copy_from_slice(&colour(change));
            }
        }
        for row in side + 8..side + bar_rows - 4 {
            for column in side / 10..side - side / 10 {
                let t = (column - side / 10) as f64 / (side - side / 5) as f64;
                let start = (row * side + column) * 3;
                data[start..start + 3].copy_from_slice(&colour(0.1 * t - 0.05));
            }
        }
        let change_path = directory.join(format!(
            "polarisation_intensity_change_{preset}_sun{sun}.png"
        ));
        write_png(
            &change_path,
            &DisplayImage::new(side, side + bar_rows, data)?,
        )?;
        println!(
            "  intensity change vector / scalar - 1: {:+.2} % to {:+.2} %, wrote {}",
            100.0 * low,
            100.0 * high,
            change_path.display()
        );
    }
    Ok(())
}
