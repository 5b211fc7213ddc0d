//! Geometry of a spherical planet and its atmosphere, in f64 metres.
//!
//! Two frames: the observer's local east-north-up frame for directions as
//! users give them (`direction`), and the planet-centred frame for
//! positions, whose z axis passes through the observer, so that a local
//! direction is used unchanged (`planet_sphere`).

pub(crate) mod direction;
pub(crate) mod planet_sphere;

pub(crate) use direction::{
    Vector3, direction_about, direction_from_elevation_azimuth, elevation_azimuth_from_direction,
    perpendicular_basis,
};
pub use direction::{ViewDirection, angle_between_deg, azimuth_in_one_turn_deg};
pub(crate) use planet_sphere::{
    distance_to_ground_boundary, distance_to_top_boundary, distance_to_top_of_atmosphere,
    ray_intersects_ground, ray_sphere_roots, segment_in_atmosphere,
};
