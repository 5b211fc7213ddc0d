//! Stokes vectors along a path: reference frames, rotations and the
//! accumulated Mueller matrix of a path traced from the eye.
//!
//! # Convention (one for all of sora)
//! The Stokes vector (I, Q, U, V) of light travelling along the unit vector
//! k is referred to a unit vector e_l perpendicular to k, with
//! e_r = k x e_l (so e_l x e_r = k): Q = I_l - I_r, U the excess along
//! (e_l + e_r) / sqrt 2 over (e_l - e_r) / sqrt 2, and the angle of
//! polarisation chi is measured from e_l toward e_r, Q = I_p cos 2 chi,
//! U = I_p sin 2 chi (I_p the polarised intensity).
//!
//! **At the eye** the reference is the local meridian plane of the view
//! direction w (the plane through the zenith and w): e_l = dw/d(elevation),
//! the unit vector toward the zenith across the sky, so Q > 0 means the
//! electric field is mostly vertical (in the meridian plane) and Q < 0
//! mostly horizontal. Light reaches the eye travelling along k = -w, so
//! e_r = k x e_l = e_l x w: for an observer facing w with e_l up, e_r
//! points to the observer's left, and chi runs from "up" toward the left,
//! counter-clockwise as the observer sees the sky. Looking straight up or
//! down, the meridian plane is the one of the view's azimuth (e_l is the
//! limit of dw/d(elevation) there). Other codes' conventions differ in the
//! sign of Q or U; the Coulson-table test (`reference_tests/`) maps
//! theirs to this one.
//!
//! # Scattering and rotation
//! A phase matrix F (`atmosphere/phase_matrix.rs`) refers both Stokes
//! vectors to the scattering plane: with n = (k_in x k_out) / |k_in x k_out|,
//! e_r = n for both and e_l = n x k. Re-referring a Stokes vector from
//! e_l to e_l' = cos eta e_l + sin eta e_r (about the same k) multiplies
//! it by the rotation matrix
//!
//! ```text
//!          | 1    0       0     0 |
//! L(eta) = | 0  cos 2eta  sin 2eta  0 |
//!          | 0 -sin 2eta  cos 2eta  0 |
//!          | 0    0       0     1 |
//! ```
//!
//! (Hovenier, van der Mee & Domke 2004, eq. 1.35; chi' = chi - eta).
//!
//! # Along a path from the eye
//! The light reaching the eye after scatterings at vertices 1..m is
//! `S_eye = L(eta_1) F_1 L(eta_2) F_2 ... S_source`, each F_v in its own
//! scattering plane and each L(eta_v) turning the scattering plane of vertex
//! v into the frame in which the next vertex toward the eye expects the
//! light. A path traced from the eye therefore accumulates the product from
//! the left: it keeps, for the segment it travels, the frame e_l of the
//! light on that segment (the eye's meridian frame first, then the
//! incoming side of each scattering plane) and the matrix
//! `T = L(eta_1) F_1 / a1_1 ... ` (each F divided by its a1, the scalar
//! phase function, whose value and sampling stay with the scalar
//! throughput). Sunlight is unpolarised, so next-event estimation at a
//! vertex adds `T L(eta_s) (1, b1/a1, 0, 0)` times the scalar estimate; a
//! Lambertian ground reflects unpolarised light whatever it receives, so
//! it keeps only T's first column.

use crate::geometry::Vector3;

/// A 4 x 4 Mueller matrix, [row][column], acting on (I, Q, U, V).
pub(crate) type Mueller = [[f64; 4]; 4];

/// The identity matrix.
pub(crate) const IDENTITY: Mueller = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// The eye's reference vector e_l for the view at `elevation_deg` and
/// `azimuth_deg` (clockwise from north): dw/d(elevation) in the
/// east-north-up frame, the unit vector in the view's meridian plane,
/// perpendicular to it, toward the zenith (see the module docs).
pub(crate) fn meridian_reference(elevation_deg: f64, azimuth_deg: f64) -> Vector3 {
    let (sin_el, cos_el) = elevation_deg.to_radians().sin_cos();
    let (sin_az, cos_az) = azimuth_deg.to_radians().sin_cos();
    Vector3::new(-sin_el * sin_az, -sin_el * cos_az, cos_el)
}

/// (cos 2 eta, sin 2 eta) of the rotation that re-refers a Stokes vector
/// of light along `k` from the frame `from_l` to the frame `to_l` (both
/// unit, perpendicular to `k`).
pub(crate) fn rotation_cos_sin_2eta(k: Vector3, from_l: Vector3, to_l: Vector3) -> (f64, f64) {
    let from_r = k.cross(from_l);
    let (c, s) = (to_l.dot(from_l), to_l.dot(from_r));
    let norm = c * c + s * s;
    if norm <= 0.0 {
        return (1.0, 0.0);
    }
    ((c * c - s * s) / norm, 2.0 * c * s / norm)
}

/// The normal n of the scattering plane of light turning from `k_in` to
/// `k_out` (unit vectors), and the reference e_l of the scattered light
/// in it (n x k_out). When the two are (anti)parallel any plane through
/// them will do: the one whose e_l is `current_l` (no rotation).
pub(crate) fn scattering_plane(k_in: Vector3, k_out: Vector3, current_l: Vector3) -> Vector3 {
    let normal = k_in.cross(k_out);
    let length = normal.length();
    if length < 1e-12 {
        return k_out.cross(current_l).normalized();
    }
    normal * (1.0 / length)
}

/// `t * L(eta) * f` with (c, s) = (cos 2 eta, sin 2 eta), written into `t`.
pub(crate) fn multiply_rotated(t: &mut Mueller, (c, s): (f64, f64), f: &Mueller) {
    // L(eta) f: rows 1 and 2 of f mixed.
    let mut lf = *f;
    for col in 0..4 {
        lf[1][col] = c * f[1][col] + s * f[2][col];
        lf[2][col] = -s * f[1][col] + c * f[2][col];
    }
    let left = *t;
    for (row, out) in t.iter_mut().enumerate() {
        for (col, value) in out.iter_mut().enumerate() {
            *value = (0..4).map(|k| left[row][k] * lf[k][col]).sum();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::direction_from_elevation_azimuth;

    #[test]
    fn the_meridian_reference_is_perpendicular_and_points_up() {
        for (el, az) in [(0.0, 0.0), (30.0, 45.0), (-20.0, 200.0), (89.0, 310.0)] {
            let w = direction_from_elevation_azimuth(el, az);
            let l = meridian_reference(el, az);
            assert!(w.dot(l).abs() < 1e-15 && (l.length() - 1.0).abs() < 1e-15);
            // A small step up in elevation moves w along l.
            let up = direction_from_elevation_azimuth(el + 1e-6, az);
            let step = (up - w) * (1.0 / 1e-6f64.to_radians());
            assert!((step - l).length() < 1e-6, "el {el} az {az}");
        }
        // Straight up: the meridian plane of the azimuth.
        let l = meridian_reference(90.0, 90.0);
        assert!((l - Vector3::new(-1.0, 0.0, 0.0)).length() < 1e-15);
    }

    #[test]
    fn rotations_compose_and_turn_the_angle_of_polarisation() {
        let k = Vector3::new(0.0, 0.0, 1.0);
        let e_l = Vector3::new(1.0, 0.0, 0.0);
        // Light polarised along e_l: Q = 1. Referred to a frame turned by
        // 30 degrees, its angle is -30 degrees: Q = cos 60, U = -sin 60.
        let eta = 30f64.to_radians();
        let e_l2 = e_l * eta.cos() + k.cross(e_l) * eta.sin();
        let (c, s) = rotation_cos_sin_2eta(k, e_l, e_l2);
        let mut t = IDENTITY;
        multiply_rotated(&mut t, (c, s), &IDENTITY);
        let q = t[1][1];
        let u = t[2][1];
        assert!((q - 0.5).abs() < 1e-15 && (u + 0.75f64.sqrt()).abs() < 1e-15);
        // Turning back gives the identity.
        let back = rotation_cos_sin_2eta(k, e_l2, e_l);
        multiply_rotated(&mut t, back, &IDENTITY);
        for (r, row) in t.iter().enumerate() {
            for (col, v) in row.iter().enumerate() {
                let expected = if r == col { 1.0 } else { 0.0 };
                assert!((v - expected).abs() < 1e-15);
            }
        }
    }
}
