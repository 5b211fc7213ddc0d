//! A scene at sunset with aerial perspective, written as a PNG: ridges 3
//! to 90 km away under earth-clear's sky, looking toward the sun 1 degree
//! up (the README's picture, `docs/readme_aerial_scene.png`).
//!
//! ```sh
//! cargo run --release -p sora --example aerial_scene -- scene.png
//! ```
//!
//! The eye is 200 m up, looking 3 degrees up at azimuth 240 (a 50-degree
//! perspective, 240 x 96 pixels; the sun at 270, just outside it). The
//! depth buffer is synthetic: five ridge lines at 3, 8, 20, 45 and 90 km,
//! each crest at an elevation angle that wanders with azimuth (the nearer
//! ridges lower); a pixel's depth is the distance along its view to the
//! nearest ridge whose crest is above it, infinity for the sky. Per pixel,
//! with L_air and T from [`sora::Sky::render_aerial_perspective_xyz`] (T
//! per CIE XYZ channel):
//!
//! ```text
//! sky pixel:   L_air (the segment to infinity: the sky's radiance)
//! ridge pixel: L_point T + L_air
//! L_point(lambda) = (rho / pi) (E_sun T_sun(point) max(0, cos i) + E_sky(point) (1 + cos s) / 2)
//! ```
//!
//! a grey Lambertian ridge face (rho = 0.15) tilted s = 40 degrees from
//! vertical toward the eye (the sun behind the ridges: cos i < 0, so it
//! is lit by the sky alone), E_sky the sky's diffuse irradiance (as an
//! isotropic sky on the tilted face) at the ridge's crest in the middle of
//! the view ([`sora::Sky::aerial_perspective_to_point`]). Automatic
//! exposure, sRGB.

use sora::camera::PerspectiveCamera;
use sora::colour::{DisplayMapping, Observer, SpectrumToXyz, Xyz};
use sora::output::{DisplayImage, write_png};
use sora::spectrum::SampledSpectrum;
use sora::{Atmosphere, Camera, ImageSettings, Sky};

/// The image's size, pixels.
const WIDTH: u32 = 240;
const HEIGHT: u32 = 96;
/// The eye's altitude, m, and the camera's view (elevation, azimuth,
/// horizontal field of view), degrees.
const EYE_ALTITUDE_M: f64 = 200.0;
const CAMERA: (f64, f64, f64) = (3.0, 240.0, 50.0);
/// The sun's elevation and azimuth, degrees.
const SUN: (f64, f64) = (1.0, 270.0);
/// The ridges: distance (m), the crest's mean elevation angle and how far
/// it wanders (degrees).
const RIDGES: [(f64, f64, f64); 5] = [
    (3e3, -1.2, 0.8),
    (8e3, 0.3, 0.7),
    (20e3, 1.3, 0.6),
    (45e3, 2.1, 0.5),
    (90e3, 2.7, 0.4),
];
/// The ridge faces' albedo and tilt from vertical toward the eye, degrees.
const ALBEDO: f64 = 0.15;
const FACE_TILT_DEG: f64 = 40.0;

/// The crest's elevation angle (degrees) of ridge `k` at `azimuth_deg`.
fn crest_deg(k: usize, azimuth_deg: f64) -> f64 {
    let (_, mean, wander) = RIDGES[k];
    let a = azimuth_deg.to_radians();
    let phase = 1.7 * k as f64;
    mean + wander
        * (0.6 * (7.0 * a + phase).sin()
            + 0.3 * (17.0 * a + 2.0 * phase).sin()
            + 0.1 * (41.0 * a + 3.0 * phase).sin())
}

/// East-north-up unit vector of (elevation, azimuth) in degrees.
fn direction(elevation_deg: f64, azimuth_deg: f64) -> [f64; 3] {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    [e.cos() * a.sin(), e.cos() * a.cos(), e.sin()]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "scene.png".into());
    let atmosphere = Atmosphere::preset("earth-clear")?;
    let sky = Sky::builder(&atmosphere)
        .sun_deg(SUN.0, SUN.1)
        .observer_altitude_m(EYE_ALTITUDE_M)
        .polarisation(sora::Polarisation::Scalar)
        .build()?;
    let camera = Camera::Perspective(PerspectiveCamera::new(CAMERA.0, CAMERA.1, CAMERA.2)?);
    let image = ImageSettings::new(camera, WIDTH, HEIGHT);
    let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::Cie1931TwoDegree);

    // The depth buffer and which ridge each pixel sees.
    let pixels = (WIDTH * HEIGHT) as usize;
    let (mut depth, mut ridge) = (vec![f64::INFINITY; pixels], vec![None; pixels]);
    for k in 0..pixels {
        let (column, row) = (k as u32 % WIDTH, k as u32 / WIDTH);
        let Some(view) = camera.view_at_pixel(column, row, WIDTH, HEIGHT) else {
            continue;
        };
        let (elevation, azimuth) = (view.elevation_deg(), view.azimuth_deg());
        if let Some(r) = (0..RIDGES.len()).find(|r| elevation < crest_deg(*r, azimuth)) {
            depth[k] = RIDGES[r].0 / elevation.to_radians().cos();
            ridge[k] = Some(r);
        }
    }

    // Each ridge's own light, from the sun and the sky at its crest ahead.
    let sun = direction(SUN.0, SUN.1);
    let tilt = FACE_TILT_DEG.to_radians();
    let toward_eye = direction(0.0, CAMERA.1 + 180.0);
    let face = [
        toward_eye[0] * tilt.sin(),
        toward_eye[1] * tilt.sin(),
        tilt.cos(),
    ];
    let cos_incidence = (face[0] * sun[0] + face[1] * sun[1] + face[2] * sun[2]).max(0.0);
    let sky_view = (1.0 + tilt.cos()) / 2.0;
    let solar = &sky.optics().solar_irradiance_w_m2_nm;
    let ahead = direction(0.0, CAMERA.1);
    let mut ridge_light = Vec::new();
    for (k, (distance, _, _)) in RIDGES.iter().enumerate() {
        let up = distance * crest_deg(k, CAMERA.1).to_radians().tan();
        let point =
            sky.aerial_perspective_to_point([distance * ahead[0], distance * ahead[1], up])?;
        let light: Vec<f64> = (0..sky.wavelengths().len())
            .map(|i| {
                ALBEDO / std::f64::consts::PI
                    * (solar[i] * point.sun_transmittance_at_point[i] * cos_incidence
                        + point.sky_irradiance_at_point[i] * sky_view)
            })
            .collect();
        ridge_light.push(to_xyz.to_xyz(&SampledSpectrum::from_values(light))?);
    }

    // The air's light and transmittance per pixel, and the composite.
    let (air, through) = sky.render_aerial_perspective_xyz(&image, &depth, &to_xyz)?;
    let white = to_xyz.to_xyz(&SampledSpectrum::from_values(vec![
        1.0;
        sky.wavelengths().len()
    ]))?;
    let xyz: Vec<Xyz> = (0..pixels)
        .map(|k| match ridge[k] {
            None => air[k],
            Some(r) => {
                let (l, t) = (ridge_light[r], through[k]);
                Xyz {
                    x: l.x * t.x / white.x + air[k].x,
                    y: l.y * t.y / white.y + air[k].y,
                    z: l.z * t.z / white.z + air[k].z,
                }
            }
        })
        .collect();
    let rgb = DisplayMapping::default().to_u8(&xyz)?.concat();
    write_png(
        &path,
        &DisplayImage::new(WIDTH as usize, HEIGHT as usize, rgb)?,
    )?;
    println!("wrote {path}");
    Ok(())
}
