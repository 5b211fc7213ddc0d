//! The engine's reference tests: each part of the light transport against
//! closed forms, symmetries, the slow reference paths beside the fast ones,
//! and independent radiative-transfer results (`tests/data/`, each file
//! names its source). They live inside the crate because the kernels they
//! check one by one are private to it; the public front door is tested
//! from outside in `tests/`.

mod multiple_scattering_reference;
mod path_tracing_reference;
mod polarisation_reference;
pub(crate) mod reference_data;
mod render_accuracy;
mod single_scattering_closed_forms;
mod single_scattering_reference;
mod twilight_survey;
