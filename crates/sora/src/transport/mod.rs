//! Light transport: how sunlight reaches the eye through the atmosphere.
//!
//! **The engine underneath [`crate::Sky`], not a stable interface**: its
//! types and functions are public for the reference tests and benchmarks
//! that check each part on its own (and for those extending the physics),
//! and change when the engine does. Use [`crate::Sky`], which composes
//! them; scratch buffers, quadrature constants and table internals are
//! private to the crate.
//!
//! - [`optical_column`]: geometric columns of each species along rays,
//!   and the table of columns toward the sun (transmittance, Beer-Lambert);
//! - [`single_scattering`]: sunlight scattered once toward the eye (the
//!   paper's eq. 4-5), a reference path (the paper's uniform double march)
//!   and a fast path, tested against each other and against independent
//!   radiative-transfer results;
//! - [`multiple_scattering`]: light scattered more than once (and skylight
//!   reflected by the ground), by a discrete-ordinate field per image, added
//!   to single scattering;
//! - [`sky_view_table`]: the fast path tabulated over view directions, for
//!   images;
//! - [`quadrature`]: the Gauss-Legendre rules they share.

pub mod multiple_scattering;
pub mod optical_column;
pub mod path_tracing;
pub mod quadrature;
pub mod random;
pub mod single_scattering;
pub mod sky_view_table;

pub use path_tracing::{PathTracedSpectrum, PathTracer, SpectralEstimate};
pub use single_scattering::{
    Observation, SingleScatteringScratch, SingleScatteringSky, SunColumns,
};
pub use sky_view_table::SkyViewTable;
