//! # sora-mie: Mie theory for homogeneous spheres and particle ensembles
//!
//! The aerosol optics engine of sora (Nakai & Sakai §2-3, eq. 2-3, with the
//! misprint of eq. 2 corrected: C_sca = lambda^2 / (2 pi) * sum (2n+1)(|a_n|^2 + |b_n|^2),
//! see `../shared/paper/NOTES.md`).
//!
//! Conventions (Bohren & Huffman 1983): refractive index `m = n + i k` relative
//! to the surrounding medium, `k >= 0` means absorption (time dependence
//! exp(-i w t)); size parameter `x = 2 pi r / lambda` with lambda in the medium.
//!
//! The crate is split along the physics:
//! - [`sphere`]: one homogeneous sphere: series coefficients a_n, b_n,
//!   efficiencies, asymmetry parameter, amplitude functions S1, S2 and the
//!   phase function.
//! - [`distribution`]: particle size distributions (log-normal, modified gamma,
//!   truncation) and the quadrature over radius.
//! - [`ensemble`]: per-particle averaged optics of a size distribution
//!   (cross-sections, single-scattering albedo, g, phase function table).
//! - [`refractive_index`]: constant or wavelength-tabulated m(lambda).
//! - [`paper_phase`]: the paper's Henyey-Greenstein mode (eq. 3, g linear in radius).
//! - [`quadrature`]: the Gauss-Legendre rule (the radius rules', and sora's
//!   discrete-ordinate streams').
//! - `simd` (private): the hot kernels compiled for AVX-512F with FMA, for
//!   AVX and portably from one source, the build chosen at run time.
//!
//! No global state, no I/O, no allocation in the per-term loops.

pub use num_complex::Complex64;

pub mod distribution;
pub mod ensemble;
pub mod paper_phase;
pub mod quadrature;
pub mod refractive_index;
mod simd;
pub mod sphere;
