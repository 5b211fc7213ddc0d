//! Next-event estimation toward the sun at a scattering vertex (step 3) and
//! at the ground (step 5), scalar and polarised.

use std::f64::consts::PI;

use super::estimate::{PARTS, Part, STOKES_PARTS};
use super::tracer::{PathScratch, PathTracer};
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::geometry::{
    Vector3, distance_to_top_boundary, perpendicular_basis, ray_intersects_ground,
};
use crate::transport::optical_column::compute_columns_along_ray;
use crate::transport::single_scattering::SUN_RAY_PANELS;
use crate::transport::stokes;

impl<'a> PathTracer<'a> {
    /// Relative densities of every species at `position`, and the
    /// scattering coefficient there per wavelength.
    pub(super) fn set_densities(&self, position: Vector3, scratch: &mut PathScratch) {
        let n = self.wavelengths;
        let altitude_m = position.length() - self.ground_radius_m;
        scratch.scattering_coefficient.fill(0.0);
        for (j, profile) in self.profiles.iter().enumerate() {
            let density = profile.relative_density(altitude_m);
            scratch.densities[j] = density;
            if density > 0.0 && self.scatters[j] {
                for (s, beta) in scratch
                    .scattering_coefficient
                    .iter_mut()
                    .zip(&self.scattering_per_m[j * n..(j + 1) * n])
                {
                    *s += density * beta;
                }
            }
        }
    }

    /// sum_j sigma_s,j p_j(cos_theta) per wavelength into
    /// `scratch.phase_term`, m^-1 sr^-1 (the densities must be set).
    fn set_phase_term(&self, cos_theta: f64, scratch: &mut PathScratch) {
        let n = self.wavelengths;
        scratch.phase_term.fill(0.0);
        for (j, species) in self.optics.species.iter().enumerate() {
            let density = scratch.densities[j];
            if !(density > 0.0 && self.scatters[j]) {
                continue;
            }
            species
                .phase_function
                .eval_into(cos_theta, &mut scratch.phase_values);
            for ((term, beta), p) in scratch
                .phase_term
                .iter_mut()
                .zip(&self.scattering_per_m[j * n..(j + 1) * n])
                .zip(&scratch.phase_values)
            {
                *term += density * beta * p;
            }
        }
    }

    /// Columns from `position` to the top toward the sun into the scratch
    /// (Gauss-Legendre on [`SUN_RAY_PANELS`] panels, as the
    /// single-scattering code's exact sun columns, cut at kink altitudes);
    /// false in the planet's shadow.
    fn set_sun_columns(&self, position: Vector3, scratch: &mut PathScratch) -> bool {
        let r = position.length();
        let mu = position.dot(self.sun_direction) / r;
        if ray_intersects_ground(r, mu, self.ground_radius_m) {
            return false;
        }
        let length = distance_to_top_boundary(
            r.clamp(self.ground_radius_m, self.top_radius_m),
            mu,
            self.top_radius_m,
        );
        scratch.sun_columns_m.fill(0.0);
        if length <= 0.0 {
            return true;
        }
        self.corners.fill_panel_ends(
            position,
            self.sun_direction,
            length,
            SUN_RAY_PANELS,
            &mut scratch.sun_panel_ends_m,
        );
        compute_columns_along_ray(
            &self.profiles,
            self.ground_radius_m,
            position,
            self.sun_direction,
            &scratch.sun_panel_ends_m,
            &mut scratch.sun_columns_m,
        );
        true
    }

    /// NEE at a scattering vertex: beta sum_j sigma_s,j p_j(w.s) E T_sun;
    /// false (and nothing added) in the planet's shadow.
    pub(super) fn add_scattered_sunlight(
        &self,
        position: Vector3,
        direction: Vector3,
        part: Part,
        scratch: &mut PathScratch,
    ) -> bool {
        if !self.set_sun_columns(position, scratch) {
            return false;
        }
        let cos_theta = direction.dot(self.sun_direction);
        self.set_phase_term(cos_theta, scratch);
        let n = self.wavelengths;
        let row = part as usize * n;
        for i in 0..n {
            let tau = self.optical_depth(i, &scratch.sun_columns_m);
            scratch.next_event[i] = scratch.throughput[i]
                * scratch.phase_term[i]
                * self.optics.solar_irradiance_w_m2_nm[i]
                * (-tau).exp();
            scratch.contributions[row + i] += scratch.next_event[i];
        }
        if self.polarised {
            self.add_stokes_of_sunlight(direction, cos_theta, scratch);
        }
        true
    }

    /// The Stokes vector of a sky next-event (its scalar estimate in
    /// `scratch.next_event`): sunlight (unpolarised) scattered toward the
    /// eye through `T L(eta_s) (1, b1/a1, 0, 0)` (`stokes.rs`).
    fn add_stokes_of_sunlight(
        &self,
        direction: Vector3,
        cos_theta: f64,
        scratch: &mut PathScratch,
    ) {
        let k_out = -direction;
        let normal = stokes::scattering_plane(-self.sun_direction, k_out, scratch.frame_l);
        let rotation = stokes::rotation_cos_sin_2eta(k_out, normal.cross(k_out), scratch.frame_l);
        self.set_phase_matrix_term(cos_theta, scratch);
        let n = self.wavelengths;
        let (c, s) = rotation;
        for i in 0..n {
            let m = &scratch.phase_matrices[i];
            let b = if m.a1 > 0.0 { m.b1 / m.a1 } else { 0.0 };
            let v = [1.0, c * b, -s * b];
            for (k, row) in scratch.transfer[i].iter().enumerate() {
                let value = row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
                scratch.contributions[(PARTS + k) * n + i] += scratch.next_event[i] * value;
            }
        }
    }

    /// sum_j sigma_s,j F_j(cos_theta) per wavelength into
    /// `scratch.phase_matrices` (the densities must be set).
    fn set_phase_matrix_term(&self, cos_theta: f64, scratch: &mut PathScratch) {
        let n = self.wavelengths;
        scratch.phase_matrices.fill(PhaseMatrix::default());
        for (j, species) in self.optics.species.iter().enumerate() {
            let density = scratch.densities[j];
            if !(density > 0.0 && self.scatters[j]) {
                continue;
            }
            species
                .phase_function
                .phase_matrix_into(cos_theta, &mut scratch.species_phase_matrices);
            for i in 0..n {
                let coefficient = density * self.scattering_per_m[j * n + i];
                scratch.phase_matrices[i]
                    .add_scaled(coefficient, &scratch.species_phase_matrices[i]);
            }
        }
    }

    /// A polarised path scatters from `direction` into `next` (the scalar
    /// throughput is weighted already): T <- T L(eta) F / a1, and the frame
    /// becomes the incoming side of the scattering plane.
    pub(super) fn scatter_stokes(
        &self,
        direction: Vector3,
        next: Vector3,
        cos_theta: f64,
        scratch: &mut PathScratch,
    ) {
        let (k_in, k_out) = (-next, -direction);
        let normal = stokes::scattering_plane(k_in, k_out, scratch.frame_l);
        let rotation = stokes::rotation_cos_sin_2eta(k_out, normal.cross(k_out), scratch.frame_l);
        self.set_phase_matrix_term(cos_theta, scratch);
        for (t, m) in scratch.transfer.iter_mut().zip(&scratch.phase_matrices) {
            stokes::multiply_rotated(t, rotation, &m.normalised_matrix());
        }
        scratch.frame_l = normal.cross(k_in);
    }

    /// NEE at a ground vertex: beta a/pi E (n.s) T_sun.
    pub(super) fn add_sunlit_ground(
        &self,
        position: Vector3,
        normal: Vector3,
        part: Part,
        scratch: &mut PathScratch,
    ) {
        let mu_sun = normal.dot(self.sun_direction);
        if mu_sun <= 0.0 || !self.set_sun_columns(position, scratch) {
            return;
        }
        let n = self.wavelengths;
        let row = part as usize * n;
        for i in 0..n {
            let tau = self.optical_depth(i, &scratch.sun_columns_m);
            let value = scratch.throughput[i] * self.optics.ground_albedo[i] / PI
                * self.optics.solar_irradiance_w_m2_nm[i]
                * mu_sun
                * (-tau).exp();
            scratch.contributions[row + i] += value;
            // The ground reflects unpolarised light: T's first column.
            if self.polarised {
                for k in 0..STOKES_PARTS {
                    scratch.contributions[(PARTS + k) * n + i] += value * scratch.transfer[i][k][0];
                }
            }
        }
    }
}

/// A polarised path leaves a Lambertian ground along `direction`: the
/// ground reflects unpolarised light whatever reaches it, so only T's first
/// column (the response to unpolarised light) remains, and any frame
/// perpendicular to the new direction will do.
pub(super) fn reflect_depolarised(direction: Vector3, scratch: &mut PathScratch) {
    for t in &mut scratch.transfer {
        for row in t.iter_mut() {
            row[1] = 0.0;
            row[2] = 0.0;
            row[3] = 0.0;
        }
    }
    scratch.frame_l = perpendicular_basis(direction).0;
}
