//! Light transport: how sunlight reaches the eye through the atmosphere.
//!
//! **The engine underneath [`crate::Sky`], private to the crate**: `Sky`
//! composes these parts and is their one interface; each part is checked
//! on its own by the reference tests in `reference_tests/` (closed forms,
//! the slow reference paths beside the fast ones, independent
//! radiative-transfer results), which live here because the kernels are
//! private.
//!
//! - `optical_column`: geometric columns of each species along rays,
//!   and the table of columns toward the sun (transmittance, Beer-Lambert);
//! - `single_scattering`: sunlight scattered once toward the eye (the
//!   paper's eq. 4-5), a reference path (the paper's uniform double march)
//!   and a fast path, tested against each other and against independent
//!   radiative-transfer results;
//! - `multiple_scattering`: light scattered more than once (and skylight
//!   reflected by the ground), by a discrete-ordinate field per image, added
//!   to single scattering;
//! - `sky_view_table`: the fast path tabulated over view directions, for
//!   images;
//! - `stokes`: Stokes vectors along a path (the meridian-plane convention,
//!   rotations, the Mueller matrix a polarised path carries);
//! - `path_tracing`: the Monte Carlo reference for all orders, and
//!   `sunlit_directions`, its directions from the planet's shadow toward
//!   the sunlit air in twilight;
//! - `quadrature`: the Gauss-Legendre rules they share.

pub(crate) mod multiple_scattering;
pub(crate) mod optical_column;
pub(crate) mod path_tracing;
pub(crate) mod quadrature;
pub(crate) mod random;
#[cfg(test)]
mod reference_tests;
pub(crate) mod single_scattering;
pub(crate) mod sky_view_table;
pub(crate) mod stokes;
pub(crate) mod sunlit_directions;
pub(crate) mod vector_exp;

pub use path_tracing::PathTracer;
pub use single_scattering::{
    Observation, SingleScatteringScene, SingleScatteringScratch, SunColumns,
};
pub(crate) use sky_view_table::SkyViewCell;
pub use sky_view_table::SkyViewTable;
