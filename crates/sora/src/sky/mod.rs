//! The front door: one [`Sky`], built once from an atmosphere, the sun and
//! the eye, a wavelength grid and the choice of physics and method, that
//! answers every question the library can ask of a sky.
//!
//! - [`Sky::radiance`] and [`Sky::radiances`]: the spectral radiance
//!   (W m^-2 sr^-1 nm^-1) of one view or of many views in one call, with
//!   standard errors when path tracing;
//! - [`Sky::render_xyz`] and [`Sky::render_spectral`]: an image for a
//!   camera, as CIE XYZ or as radiance per wavelength, with the sun's disc
//!   energy-true at any resolution (`sky/sun_disc.rs`);
//! - [`Sky::irradiance`]: direct, diffuse and global irradiance on a plane
//!   (`sky/irradiance.rs`);
//! - [`Sky::aerial_perspective`]: the light of the air between the eye and
//!   a point of a scene and the segment's transmittance, the same terms
//!   along a segment (`sky/aerial_perspective.rs`);
//! - with [`Polarisation::Vector`], the Stokes vector of each view
//!   ([`SkyRadiance::stokes`]) and of each pixel
//!   ([`Sky::render_stokes_xyz`]); `docs/polarisation.md` says which
//!   methods follow it.
//!
//! This is the one place where single scattering and the multiply
//! scattered light are added: what [`Scattering`] asks for is composed
//! here and nowhere else. The expensive parts are built once, on first
//! use, and kept: the multiple-scattering field (used by every view, so an
//! almucantar of 72 directions costs about as much as one), and for images
//! the sun-column, source and sky-view tables.
//!
//! # Methods ([`Method`])
//! - [`Method::Fast`]: single scattering by Gauss-Legendre columns
//!   (`crate::transport::single_scattering`) with exact columns toward the
//!   sun for views, a sun-column table and a sky-view table for images
//!   (within 0.1 % of the exact path); the higher orders from the
//!   discrete-ordinate field, synthesised exactly along each view, or read
//!   from its source table for images
//!   (`crate::transport::multiple_scattering`).
//! - [`Method::Reference`]: the paper's uniform double march for single
//!   scattering per view and per pixel (slow: the oracle the fast method
//!   is tested against), plus the field's exact synthesis for views, and
//!   the march of its source table for images (as the fast image's
//!   sky-view table does; a fast 24 x 24 fisheye at sun 36 degrees differs
//!   by up to 4.1e-3 in XYZ from one whose higher orders are synthesised
//!   exactly per pixel, against 1.7e-3 from this reference).
//! - [`Method::PathTracing`]: the Monte Carlo path tracer (all orders,
//!   unbiased, with standard errors; views only).
//!
//! The sun's disc is part of images only (`ImageSettings::draw_sun_disc`);
//! a view's radiance is the sky's, and the direct beam is in
//! [`Sky::irradiance`] and [`Sky::direct_normal_irradiance`].
//!
//! Views and pixels run in parallel with the `parallel` feature; each is
//! computed by the same code whatever the thread count or the number of
//! views asked for together, so `radiances(&[v])[0] == radiance(v)` to the
//! last bit, with one exception: from [`TABLE_VIEW_COUNT`] views on,
//! [`Sky::radiances`] of the fast method reads its views from tables, as
//! an image's pixels are, with a source table at half the image's steps
//! (measured over 256 views of earth-clear: within 0.095 % of the exact
//! path in I, the worst near the horizon close to the sun's azimuth, and
//! 1.3e-3 in the degree of polarisation; 1 % in twilight;
//! [`Sky::radiances_exact`] keeps the exact path).
//!
//! # Files
//! `options.rs` (the builder and the settings and limits it checks),
//! `setup.rs` (the [`Sky`], its construction and the parts built on first
//! use), `composition.rs` (a view's terms and their sum, views),
//! `rendering.rs` (images); the other quantities in `irradiance.rs`,
//! `aerial_perspective.rs`, the banded gases' sum over k-terms in
//! `k_terms.rs`, the sun's disc in `sun_disc.rs`, the names of the choices
//! in `names.rs`.

mod aerial_perspective;
mod composition;
mod irradiance;
pub(crate) mod k_terms;
mod names;
mod options;
mod rendering;
mod setup;
mod shared_field;
mod sun_disc;

pub use crate::transport::multiple_scattering::MultipleScatteringSettings;
pub use aerial_perspective::AerialPerspective;
pub use composition::{SkyRadiance, Stokes, TABLE_VIEW_COUNT};
pub use irradiance::{Irradiance, MAX_REFERENCE_IRRADIANCE_STEPS, Plane, check_irradiance_work};
pub use options::{
    FastTableSize, ImageSettings, MAX_IMAGE_BUFFER_BYTES, MAX_IMAGE_SIDE,
    MAX_REFERENCE_MARCH_STEPS, MAX_REFERENCE_STEPS, MAX_VIEW_VALUES, MAX_VIEWS, Method,
    Polarisation, Scattering, SkyBuilder, check_image_size, check_view_count, image_side,
};
pub use setup::Sky;

/// Most paths per view of the path tracer ([`Method::PathTracing`]).
pub use crate::transport::path_tracing::MAX_SAMPLES;

pub(crate) use shared_field::{SharedField, SkyViewGrid};
pub(crate) use sun_disc::LIMB_DARKENING as SUN_LIMB_DARKENING;
