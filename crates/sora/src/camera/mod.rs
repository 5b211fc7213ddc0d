//! Cameras: which direction of the sky each pixel of an image sees.
//!
//! Pixels are addressed (column, row) from the top-left corner, and a pixel
//! sees the direction through its centre, (column + 0.5, row + 0.5).
//! Directions are unit vectors in the observer's east-north-up frame (see
//! `crate::geometry::direction`).
//!
//! - [`Camera::Fisheye`]: the whole sky in a disc, equidistant (angular)
//!   projection: the distance from the image centre is proportional to the
//!   zenith angle; the zenith is at the centre and the horizon on the
//!   inscribed circle. Orientation as a sky chart seen from below: **north
//!   at the top, east on the left, south at the bottom, west on the right**.
//!   Pixels outside the circle see nothing (black, zero radiance).
//! - [`Camera::Equirectangular`]: the 360 x 180 degree panorama renderers
//!   load as an environment map. The column gives the azimuth: the left edge
//!   is south (180), then west (270) at a quarter, **north (0) at the
//!   centre**, east (90) at three quarters, south again at the right edge;
//!   the row gives the elevation, +90 (zenith) at the top to -90 (nadir) at
//!   the bottom, linearly. A 2:1 aspect ratio gives square pixels.
//! - [`Camera::Perspective`]: a pinhole camera looking at (elevation,
//!   azimuth), horizontal field of view in degrees, the image's up as close
//!   to the zenith as the view direction allows (north when looking
//!   straight up or down).

use crate::error::{Error, Result};
use crate::geometry::{Vector3, ViewDirection, direction_from_elevation_azimuth};

/// A projection from image pixels to sky directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Camera {
    /// The whole sky in a disc: the zenith at the centre, the horizon at
    /// the rim, north up, east to the left (as seen from below).
    Fisheye,
    /// A 360 x 180 degree panorama (an environment map).
    Equirectangular,
    /// A pinhole camera with a view direction and a field of view.
    Perspective(PerspectiveCamera),
}

impl Camera {
    /// The cameras' names, in the order of the enum.
    pub const NAMES: [&'static str; 3] = ["fisheye", "equirectangular", "perspective"];

    /// `"fisheye"`, `"equirectangular"` or `"perspective"`.
    pub fn name(&self) -> &'static str {
        match self {
            Camera::Fisheye => Self::NAMES[0],
            Camera::Equirectangular => Self::NAMES[1],
            Camera::Perspective(_) => Self::NAMES[2],
        }
    }
}

impl Camera {
    /// The image width a front end draws when none is given, pixels: 512,
    /// and 1024 for the equirectangular panorama (its height is half its
    /// width, [`Camera::default_height_px`]). `sora render` and Python's
    /// `Sky.render` share it.
    pub fn default_width_px(&self) -> u32 {
        match self {
            Camera::Equirectangular => 1024,
            Camera::Fisheye | Camera::Perspective(_) => 512,
        }
    }

    /// The image height for `width` when none is given, pixels: half the
    /// width (rounded up) for the equirectangular panorama, 360 x 180
    /// degrees with square pixels; the width otherwise.
    pub fn default_height_px(&self, width: u32) -> u32 {
        match self {
            Camera::Equirectangular => width.div_ceil(2),
            Camera::Fisheye | Camera::Perspective(_) => width,
        }
    }
}

impl std::fmt::Display for Camera {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Camera {
    type Err = Error;

    /// A camera by name; `"equirect"` (the older spelling) reads as
    /// `"equirectangular"`, and `"perspective"` is the default view
    /// ([`PerspectiveCamera::DEFAULT_ELEVATION_DEG`] and the rest).
    fn from_str(name: &str) -> Result<Camera> {
        match name {
            "fisheye" => Ok(Camera::Fisheye),
            "equirectangular" | "equirect" => Ok(Camera::Equirectangular),
            "perspective" => Ok(Camera::Perspective(PerspectiveCamera::new(
                PerspectiveCamera::DEFAULT_ELEVATION_DEG,
                PerspectiveCamera::DEFAULT_AZIMUTH_DEG,
                PerspectiveCamera::DEFAULT_FOV_DEG,
            )?)),
            other => Err(Error::unknown_name("camera", other, &Camera::NAMES)),
        }
    }
}

/// A pinhole camera (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerspectiveCamera {
    forward: Vector3,
    right: Vector3,
    up: Vector3,
    /// tan(horizontal field of view / 2).
    tan_half_fov: f64,
}

impl PerspectiveCamera {
    /// The default view of every front end (`sora render --camera
    /// perspective`, Python's `Sky.render(camera="perspective")`): 10
    /// degrees above the horizon, degrees.
    pub const DEFAULT_ELEVATION_DEG: f64 = 10.0;
    /// The default view's azimuth: south (180 degrees clockwise from north).
    pub const DEFAULT_AZIMUTH_DEG: f64 = 180.0;
    /// The default horizontal field of view, degrees.
    pub const DEFAULT_FOV_DEG: f64 = 90.0;

    /// Looking toward `elevation_deg` above the horizon at `azimuth_deg`
    /// (clockwise from north), with `horizontal_fov_deg` across the image's width.
    pub fn new(
        elevation_deg: f64,
        azimuth_deg: f64,
        horizontal_fov_deg: f64,
    ) -> Result<PerspectiveCamera> {
        let forward = ViewDirection::new(elevation_deg, azimuth_deg)?.to_vector();
        if !(horizontal_fov_deg > 0.0 && horizontal_fov_deg < 180.0) {
            return Err(Error::out_of_range(
                "field of view",
                horizontal_fov_deg,
                "deg",
                "0 < fov < 180",
            ));
        }
        let zenith = Vector3::new(0.0, 0.0, 1.0);
        // Near the zenith or nadir the horizontal reference is the view
        // azimuth itself, so the image's up points along it.
        let right = if forward.cross(zenith).length() > 1e-9 {
            forward.cross(zenith).normalized()
        } else {
            direction_from_elevation_azimuth(0.0, azimuth_deg + 90.0)
        };
        let up = right.cross(forward);
        Ok(PerspectiveCamera {
            forward,
            right,
            up,
            tan_half_fov: (0.5 * horizontal_fov_deg).to_radians().tan(),
        })
    }
}

impl Camera {
    /// The sky direction seen through the centre of pixel (`column`, `row`)
    /// of a `width` x `height` image (row 0 at the top), or None where the
    /// camera sees nothing (outside the fisheye's circle): which direction
    /// a click on a rendered image means.
    pub fn view_at_pixel(
        &self,
        column: u32,
        row: u32,
        width: u32,
        height: u32,
    ) -> Option<ViewDirection> {
        let direction = self.direction_for_pixel(column, row, width, height)?;
        let (elevation_deg, azimuth_deg) =
            crate::geometry::elevation_azimuth_from_direction(direction);
        ViewDirection::new(elevation_deg, azimuth_deg).ok()
    }

    /// The unit direction seen through the centre of pixel (column, row) of a
    /// `width` x `height` image, or None where the camera sees nothing
    /// (outside the fisheye's circle).
    pub(crate) fn direction_for_pixel(
        &self,
        column: u32,
        row: u32,
        width: u32,
        height: u32,
    ) -> Option<Vector3> {
        let u = (column as f64 + 0.5) / width as f64;
        let v = (row as f64 + 0.5) / height as f64;
        match self {
            Camera::Fisheye => {
                // Centred square coordinates in [-1, 1], y up, radius 1 = horizon.
                let scale = width.min(height) as f64;
                let sx = (2.0 * (column as f64 + 0.5) - width as f64) / scale;
                let sy = (height as f64 - 2.0 * (row as f64 + 0.5)) / scale;
                let radius = (sx * sx + sy * sy).sqrt();
                if radius > 1.0 {
                    return None;
                }
                let zenith_angle = radius * std::f64::consts::FRAC_PI_2;
                let (sin_z, cos_z) = zenith_angle.sin_cos();
                // East on the left: x_east = -sx.
                let horizontal = if radius > 0.0 { sin_z / radius } else { 0.0 };
                Some(Vector3::new(-sx * horizontal, sy * horizontal, cos_z))
            }
            Camera::Equirectangular => {
                let azimuth_deg = (u * 360.0 + 180.0).rem_euclid(360.0);
                let elevation_deg = 90.0 - v * 180.0;
                Some(direction_from_elevation_azimuth(elevation_deg, azimuth_deg))
            }
            Camera::Perspective(camera) => {
                let aspect = height as f64 / width as f64;
                let sx = (2.0 * u - 1.0) * camera.tan_half_fov;
                let sy = (1.0 - 2.0 * v) * camera.tan_half_fov * aspect;
                Some((camera.forward + camera.right * sx + camera.up * sy).normalized())
            }
        }
    }
}

impl Camera {
    /// Where `direction` (unit, east-north-up) lands on a `width` x
    /// `height` image: continuous pixel coordinates (x, y), pixel (column,
    /// row) covering [column, column + 1) x [row, row + 1); None where the
    /// camera does not see it. The inverse of [`Camera::direction_for_pixel`].
    pub(crate) fn image_point_for_direction(
        &self,
        direction: Vector3,
        width: u32,
        height: u32,
    ) -> Option<(f64, f64)> {
        let (w, h) = (width as f64, height as f64);
        let (u, v) = match self {
            Camera::Fisheye => {
                let zenith_angle = direction.z.clamp(-1.0, 1.0).acos();
                let radius = zenith_angle / std::f64::consts::FRAC_PI_2;
                if radius > 1.0 {
                    return None;
                }
                let horizontal = direction.x.hypot(direction.y);
                let (sx, sy) = if horizontal > 0.0 {
                    (
                        -direction.x / horizontal * radius,
                        direction.y / horizontal * radius,
                    )
                } else {
                    (0.0, 0.0)
                };
                let scale = w.min(h);
                return Some((0.5 * (sx * scale + w), 0.5 * (h - sy * scale)));
            }
            Camera::Equirectangular => {
                let (elevation, azimuth) =
                    crate::geometry::elevation_azimuth_from_direction(direction);
                (
                    ((azimuth - 180.0).rem_euclid(360.0)) / 360.0,
                    (90.0 - elevation) / 180.0,
                )
            }
            Camera::Perspective(camera) => {
                let depth = direction.dot(camera.forward);
                if depth <= 0.0 {
                    return None;
                }
                let aspect = h / w;
                let sx = direction.dot(camera.right) / depth / camera.tan_half_fov;
                let sy = direction.dot(camera.up) / depth / (camera.tan_half_fov * aspect);
                (0.5 * (sx + 1.0), 0.5 * (1.0 - sy))
            }
        };
        ((0.0..1.0).contains(&u) && (0.0..=1.0).contains(&v))
            .then_some((u * w, (v * h).min(h - 1e-9)))
    }

    /// Solid angle of pixel (column, row), sr: exact for the panorama
    /// (a band of azimuth times a band of elevation), and the projection's
    /// Jacobian at the pixel's centre times its area for the fisheye
    /// (dOmega = sin(theta) (pi/2) / r dA, r the distance from the centre
    /// in units of the horizon's) and the pinhole (dOmega = dA / (1 + x^2 +
    /// y^2)^(3/2) on the image plane at distance 1); zero outside the
    /// fisheye's circle.
    pub(crate) fn pixel_solid_angle_sr(
        &self,
        column: u32,
        row: u32,
        width: u32,
        height: u32,
    ) -> f64 {
        let (w, h) = (width as f64, height as f64);
        let (x, y) = (column as f64 + 0.5, row as f64 + 0.5);
        match self {
            Camera::Fisheye => {
                let scale = w.min(h);
                let (sx, sy) = ((2.0 * x - w) / scale, (h - 2.0 * y) / scale);
                let radius = sx.hypot(sy);
                if radius > 1.0 {
                    return 0.0;
                }
                let theta = radius * std::f64::consts::FRAC_PI_2;
                let sine_over_radius = if radius > 0.0 {
                    theta.sin() / radius
                } else {
                    std::f64::consts::FRAC_PI_2
                };
                std::f64::consts::FRAC_PI_2 * sine_over_radius * (2.0 / scale).powi(2)
            }
            Camera::Equirectangular => {
                let top = (90.0 - 180.0 * row as f64 / h).to_radians();
                let bottom = (90.0 - 180.0 * (row + 1) as f64 / h).to_radians();
                2.0 * std::f64::consts::PI / w * (top.sin() - bottom.sin())
            }
            Camera::Perspective(camera) => {
                let aspect = h / w;
                let sx = (2.0 * x / w - 1.0) * camera.tan_half_fov;
                let sy = (1.0 - 2.0 * y / h) * camera.tan_half_fov * aspect;
                let area =
                    (2.0 * camera.tan_half_fov / w) * (2.0 * camera.tan_half_fov * aspect / h);
                area / (1.0 + sx * sx + sy * sy).powf(1.5)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::elevation_azimuth_from_direction;

    fn el_az(camera: &Camera, column: u32, row: u32, width: u32, height: u32) -> (f64, f64) {
        elevation_azimuth_from_direction(
            camera
                .direction_for_pixel(column, row, width, height)
                .unwrap(),
        )
    }

    #[test]
    fn fisheye_orientation_north_up_east_left() {
        let c = Camera::Fisheye;
        let (el, _) = el_az(&c, 50, 50, 101, 101);
        assert!((el - 90.0).abs() < 1e-9, "centre is the zenith: {el}");
        let (el, az) = el_az(&c, 50, 0, 101, 101);
        assert!(
            el < 2.0 && az.min(360.0 - az) < 1e-9,
            "top is north: {el} {az}"
        );
        let (el, az) = el_az(&c, 0, 50, 101, 101);
        assert!(
            el < 2.0 && (az - 90.0).abs() < 1e-9,
            "left is east: {el} {az}"
        );
        let (_, az) = el_az(&c, 100, 50, 101, 101);
        assert!((az - 270.0).abs() < 1e-9, "right is west: {az}");
        assert!(
            c.direction_for_pixel(0, 0, 101, 101).is_none(),
            "corners see nothing"
        );
        // Equidistant: half-way to the edge is 45 deg elevation.
        let (el, _) = el_az(&c, 75, 50, 101, 101);
        assert!((el - (90.0 - 90.0 * 50.0 / 101.0)).abs() < 1e-9, "{el}");
    }

    #[test]
    fn equirectangular_layout() {
        let c = Camera::Equirectangular;
        let (w, h) = (3600, 1800);
        let (el, az) = el_az(&c, 1800, 0, w, h);
        assert!(
            (el - 89.95).abs() < 1e-9 && (az - 0.05).abs() < 1e-9,
            "{el} {az}"
        );
        let (_, az) = el_az(&c, 2700, 900, w, h);
        assert!((az - 90.05).abs() < 1e-9, "three quarters is east: {az}");
        let (_, az) = el_az(&c, 0, 900, w, h);
        assert!((az - 180.05).abs() < 1e-9, "left edge is south: {az}");
        let (el, _) = el_az(&c, 0, 1799, w, h);
        assert!((el + 89.95).abs() < 1e-9, "bottom is the nadir: {el}");
    }

    #[test]
    fn perspective_centre_and_edges() {
        let c = Camera::Perspective(PerspectiveCamera::new(17.0, 347.0, 90.0).unwrap());
        // Even size: the centre falls between pixels; use an odd size.
        let (el, az) = el_az(&c, 100, 50, 201, 101);
        assert!(
            (el - 17.0).abs() < 1e-9 && (az - 347.0).abs() < 1e-9,
            "{el} {az}"
        );
        // The last column's centre, at the horizon level, is atan(200/201) to the right.
        let level = Camera::Perspective(PerspectiveCamera::new(0.0, 0.0, 90.0).unwrap());
        let d = level.direction_for_pixel(200, 50, 201, 101).unwrap();
        let (el, az) = elevation_azimuth_from_direction(d);
        let expected_az = (200.0f64 / 201.0).atan().to_degrees();
        assert!(
            el.abs() < 1e-9 && (az - expected_az).abs() < 1e-9,
            "{el} {az} vs {expected_az}"
        );
        // Looking straight up still works.
        let up = Camera::Perspective(PerspectiveCamera::new(90.0, 0.0, 60.0).unwrap());
        assert!(up.direction_for_pixel(0, 0, 10, 10).unwrap().z > 0.8);
        assert!(PerspectiveCamera::new(0.0, 0.0, 180.0).is_err());
        assert!(PerspectiveCamera::new(95.0, 0.0, 60.0).is_err());
    }

    /// Every pixel's centre direction lands back in that pixel, and the
    /// pixels' solid angles add up to what each camera sees: 4 pi for the
    /// panorama, 2 pi for the fisheye's hemisphere (to its resolution), and
    /// the pinhole's rectangle (4 asin(a b / sqrt((1 + a^2)(1 + b^2))) for
    /// half-sides a, b on the plane at distance 1).
    #[test]
    fn inverse_projection_and_solid_angles() {
        let perspective = PerspectiveCamera::new(20.0, 300.0, 70.0).unwrap();
        for (camera, width, height) in [
            (Camera::Fisheye, 64, 64),
            (Camera::Fisheye, 90, 60),
            (Camera::Equirectangular, 96, 48),
            (Camera::Perspective(perspective), 80, 50),
        ] {
            let mut total = 0.0;
            for row in 0..height {
                for column in 0..width {
                    total += camera.pixel_solid_angle_sr(column, row, width, height);
                    let Some(direction) = camera.direction_for_pixel(column, row, width, height)
                    else {
                        continue;
                    };
                    let (x, y) = camera
                        .image_point_for_direction(direction, width, height)
                        .unwrap();
                    assert_eq!(
                        (x.floor() as u32, y.floor() as u32),
                        (column, row),
                        "{camera:?}: ({x}, {y})"
                    );
                }
            }
            let expected = match camera {
                Camera::Equirectangular => 4.0 * std::f64::consts::PI,
                Camera::Fisheye => 2.0 * std::f64::consts::PI,
                Camera::Perspective(p) => {
                    let (a, b) = (
                        p.tan_half_fov,
                        p.tan_half_fov * height as f64 / width as f64,
                    );
                    4.0 * (a * b / ((1.0 + a * a) * (1.0 + b * b)).sqrt()).asin()
                }
            };
            // The fisheye's circle is resolved by its pixels: ~1 / side.
            let bound = if camera == Camera::Fisheye {
                0.03
            } else {
                1e-3
            };
            assert!(
                (total / expected - 1.0).abs() < bound,
                "{camera:?} {width}x{height}: {total} vs {expected}"
            );
        }
        assert!(
            Camera::Perspective(perspective)
                .image_point_for_direction(-perspective.forward, 80, 50)
                .is_none()
        );
    }
}
