//! Rays against the spheres that bound an atmosphere: the ground (radius
//! `R_ground`) and the top of the atmosphere (radius `R_top`), both centred
//! on the planet's centre.
//!
//! A ray is a start point p (metres, planet-centred) and a unit direction d.
//! Distances solve |p + t d|^2 = R^2, i.e. t^2 + 2 b t + c = 0 with
//! b = p.d, c = |p|^2 - R^2. For the far root we use the numerically
//! stable form: q = -b - sign(b) sqrt(b^2 - c), roots q and c/q, which
//! keeps full precision when the planet is huge (R ~ 1e10 m, the
//! plane-parallel limit) and the ray grazes it.
//!
//! Everything is f64: at R = 6.4e6 m an f32 has a resolution of 0.5 m, and
//! at 1e10 m of 1 km, too coarse for an 8 km scale height.

use super::Vector3;

/// The two roots (near, far) of |p + t d| = radius, or None if the ray's
/// line misses the sphere. `d` must be a unit vector.
pub(crate) fn ray_sphere_roots(p: Vector3, d: Vector3, radius_m: f64) -> Option<(f64, f64)> {
    let b = p.dot(d);
    let c = p.dot(p) - radius_m * radius_m;
    // discriminant b^2 - c, written to avoid cancellation of |p|^2 and b^2
    // for huge radii: b^2 - |p|^2 = -|p x d|^2 (d is unit).
    let perpendicular_squared = p.cross(d).dot(p.cross(d));
    let discriminant =
        (radius_m - perpendicular_squared.sqrt()) * (radius_m + perpendicular_squared.sqrt());
    if discriminant < 0.0 {
        return None;
    }
    let root = discriminant.sqrt();
    let q = if b > 0.0 { -b - root } else { -b + root };
    if q == 0.0 {
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (q, c / q);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// Distance (m) along the ray from p (inside or on the top sphere) to where
/// it leaves the atmosphere through the top boundary.
pub(crate) fn distance_to_top_of_atmosphere(p: Vector3, d: Vector3, top_radius_m: f64) -> f64 {
    match ray_sphere_roots(p, d, top_radius_m) {
        Some((_, far)) => far.max(0.0),
        None => 0.0,
    }
}

/// Distance (m) along the ray from p to the ground, or None if the ray does
/// not hit the ground (it points above the ground's horizon).
#[cfg(test)]
pub(crate) fn distance_to_ground(p: Vector3, d: Vector3, ground_radius_m: f64) -> Option<f64> {
    let (near, far) = ray_sphere_roots(p, d, ground_radius_m)?;
    if near >= 0.0 {
        Some(near)
    } else if far >= 0.0 && p.length() < ground_radius_m {
        // Start below the ground: the only exit is the far root (used by
        // callers that clamp positions to the ground, within rounding).
        Some(far)
    } else {
        None
    }
}

/// The segment [t_enter, t_exit] (m) of the ray inside the atmosphere shell
/// between the ground and the top, from a start point anywhere (inside the
/// atmosphere, or outside it looking at the limb). The segment ends at the
/// ground when the ray hits it. None when the ray misses the atmosphere.
pub(crate) fn segment_in_atmosphere(
    p: Vector3,
    d: Vector3,
    ground_radius_m: f64,
    top_radius_m: f64,
) -> Option<(f64, f64)> {
    let (top_near, top_far) = ray_sphere_roots(p, d, top_radius_m)?;
    if top_far <= 0.0 {
        return None;
    }
    let enter = top_near.max(0.0);
    let exit = match ray_sphere_roots(p, d, ground_radius_m) {
        Some((ground_near, _)) if ground_near >= enter => ground_near.min(top_far),
        _ => top_far,
    };
    Some((enter, exit))
}

/// Distance (m) from a point at radius `r_m` (at or below the top) along
/// a direction of zenith cosine `mu` to the top boundary of radius
/// `top_radius_m`: the positive root of d^2 + 2 r mu d - (top^2 - r^2) = 0
/// (Bruneton 2017, DistanceToTopAtmosphereBoundary), written without the
/// cancellation of -r mu + sqrt(disc) for upward rays.
pub(crate) fn distance_to_top_boundary(r_m: f64, mu: f64, top_radius_m: f64) -> f64 {
    let c = (top_radius_m - r_m) * (top_radius_m + r_m);
    let discriminant = (r_m * mu * r_m * mu + c).max(0.0).sqrt();
    if mu >= 0.0 {
        let q = r_m * mu + discriminant;
        if q > 0.0 { c.max(0.0) / q } else { 0.0 }
    } else {
        -r_m * mu + discriminant
    }
}

/// True when a ray from radius `r_m` (at or above the ground) with zenith
/// cosine `mu` hits the ground of radius `ground_radius_m`: it points down
/// and below the ground's horizon (Bruneton 2017, RayIntersectsGround).
pub(crate) fn ray_intersects_ground(r_m: f64, mu: f64, ground_radius_m: f64) -> bool {
    mu < 0.0 && r_m * r_m * (1.0 - mu * mu) <= ground_radius_m * ground_radius_m
}

/// Distance (m) from radius `r_m` along zenith cosine `mu` to the ground,
/// or None when the ray misses it. The near root -r mu - sqrt(disc) cancels
/// for grazing rays; it equals (r^2 - R^2) / (-r mu + sqrt(disc)).
pub(crate) fn distance_to_ground_boundary(r_m: f64, mu: f64, ground_radius_m: f64) -> Option<f64> {
    if !ray_intersects_ground(r_m, mu, ground_radius_m) {
        return None;
    }
    let c = (r_m - ground_radius_m) * (r_m + ground_radius_m);
    let discriminant = (r_m * mu * r_m * mu - c).max(0.0).sqrt();
    let q = -r_m * mu + discriminant;
    Some(if q > 0.0 { (c / q).max(0.0) } else { 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: f64 = 6_360e3;
    const TOP: f64 = 6_460e3;

    #[test]
    fn vertical_rays() {
        let p = Vector3::new(0.0, 0.0, R);
        let up = Vector3::new(0.0, 0.0, 1.0);
        assert!((distance_to_top_of_atmosphere(p, up, TOP) - 100e3).abs() < 1e-6);
        assert_eq!(distance_to_ground(p, up, R), None);
        let high = Vector3::new(0.0, 0.0, R + 10e3);
        assert!((distance_to_ground(high, -up, R).unwrap() - 10e3).abs() < 1e-6);
    }

    #[test]
    fn horizontal_ray_from_the_ground_grazes_and_escapes() {
        let p = Vector3::new(0.0, 0.0, R);
        let d = Vector3::new(1.0, 0.0, 0.0);
        let expected = (TOP * TOP - R * R).sqrt();
        assert!((distance_to_top_of_atmosphere(p, d, TOP) - expected).abs() < 1e-6);
        // From 1 km up, a ray 5 deg below the horizon hits the ground where
        // |p + t d| = R: t = (R+h) sin(dip) - sqrt(R^2 - (R+h)^2 cos^2(dip)).
        let h = 1e3;
        let dip = 5f64.to_radians();
        let high = Vector3::new(0.0, 0.0, R + h);
        let down = Vector3::new(dip.cos(), 0.0, -dip.sin());
        let hit = distance_to_ground(high, down, R).unwrap();
        let expected =
            (R + h) * dip.sin() - (R * R - (R + h) * (R + h) * dip.cos() * dip.cos()).sqrt();
        assert!((hit / expected - 1.0).abs() < 1e-9, "{hit} vs {expected}");
        // An observer on the ground looking below the horizon hits it at once.
        assert_eq!(distance_to_ground(p, down, R), Some(0.0));
    }

    #[test]
    fn plane_parallel_limit_with_a_huge_radius() {
        // R = 6.36e9 m: a ray at 10 deg elevation reaches the top at
        // t = -R sin(el) + sqrt(R^2 sin^2(el) + 2 R h + h^2), within 5e-4 of
        // the flat-atmosphere h / sin(el).
        let big = 6.36e9;
        let h = 100e3;
        let el = 10f64.to_radians();
        let p = Vector3::new(0.0, 0.0, big);
        let d = Vector3::new(el.cos(), 0.0, el.sin());
        let t = distance_to_top_of_atmosphere(p, d, big + h);
        let exact =
            -big * el.sin() + (big * big * el.sin() * el.sin() + 2.0 * big * h + h * h).sqrt();
        assert!((t / exact - 1.0).abs() < 1e-9, "{t} vs {exact}");
        assert!((t * el.sin() / h - 1.0).abs() < 5e-4);
    }

    #[test]
    fn segments_from_space_and_inside() {
        // Observer in space looking at the limb tangent 50 km above the ground.
        let p = Vector3::new(-1e7, 0.0, R + 50e3);
        let d = Vector3::new(1.0, 0.0, 0.0);
        let (enter, exit) = segment_in_atmosphere(p, d, R, TOP).unwrap();
        let half_chord = (TOP * TOP - (R + 50e3) * (R + 50e3)).sqrt();
        assert!(
            (enter - (1e7 - half_chord)).abs() < 1e-3 && (exit - (1e7 + half_chord)).abs() < 1e-3
        );
        // Looking away from the planet in space: misses.
        assert!(segment_in_atmosphere(p, -d, R, TOP).is_none());
        // From the ground looking down: empty segment at the ground.
        let ground = Vector3::new(0.0, 0.0, R);
        let (enter, exit) =
            segment_in_atmosphere(ground, Vector3::new(0.0, 0.0, -1.0), R, TOP).unwrap();
        assert!(enter == 0.0 && exit.abs() < 1e-6, "{enter} {exit}");
    }
}
