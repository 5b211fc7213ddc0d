//! Regularised non-linear least squares: Levenberg-Marquardt with an a
//! priori (Rodgers 2000, eq. 5.36, with Marquardt's diagonal damping). Its
//! systems are at most 10 x 10 and symmetric positive definite
//! ([`crate::linear_algebra`]).
//!
//! The fit minimises
//!
//! ```text
//!     chi^2(t) = sum_i ((y_i - F_i(t)) / sigma_i)^2 + sum_k ((t_k - t_a,k) / sigma_a,k)^2
//! ```
//!
//! over the fit coordinates t (`state.rs`), with y the measurements (ln of
//! sky radiances, optical depths), F the forward model and a diagonal a
//! priori. Each iteration solves
//!
//! ```text
//!     (A + lambda diag(A)) dt = J^T W (y - F) - S_a^-1 (t - t_a),   A = J^T W J + S_a^-1
//! ```
//!
//! with the Jacobian J by forward differences, W = diag(1 / sigma_i^2);
//! lambda shrinks after a step that lowers chi^2 and grows until one does.
//! At the minimum, A^-1 is the posterior covariance of t (Rodgers eq.
//! 5.38), linearised. The fit stops when a step's squared length in that
//! metric, dt^T A dt, falls below 0.05 per parameter (Rodgers eq. 5.29),
//! or when no step lowers chi^2.

use crate::linear_algebra::{cholesky, cholesky_solve, inverse};

/// The convergence threshold of the step's squared length in the
/// posterior metric, per parameter.
const CONVERGENCE_METRIC: f64 = 0.05;

/// What a fit problem provides: measurements with their uncertainties,
/// the a priori, and the model.
#[derive(Clone, Copy)]
pub(crate) struct Problem<'a> {
    /// Measured values y.
    pub measured: &'a [f64],
    /// Their 1-sigma uncertainties.
    pub sigma: &'a [f64],
    /// A priori mean of t.
    pub prior_mean: &'a [f64],
    /// A priori standard deviation of t.
    pub prior_sigma: &'a [f64],
    /// Forward difference step in t.
    pub step: f64,
    /// The most iterations.
    pub max_iterations: usize,
    /// Whether to end with a finite-difference Jacobian and the posterior
    /// covariance (not for a scouting fit whose end may be discarded).
    pub finish: bool,
}

/// A fit's end point.
#[derive(Debug, Clone)]
pub(crate) struct Solution {
    /// The fit coordinates at the minimum.
    pub t: Vec<f64>,
    /// The model there.
    pub modelled: Vec<f64>,
    /// chi^2 of the measurements alone, and of the a priori term.
    pub chi_square_measurements: f64,
    pub chi_square_prior: f64,
    /// Posterior covariance of t (row-major; empty unless the problem
    /// asked to finish).
    pub covariance: Vec<f64>,
    /// The Jacobian at t (row-major, measurements x parameters), whether
    /// it is a finite-difference one (else Broyden-updated), and the
    /// damping reached.
    pub jacobian: Vec<f64>,
    pub fresh: bool,
    pub lambda: f64,
    /// Iterations taken, and whether the step size criterion was met.
    pub iterations: usize,
    pub converged: bool,
}

impl Problem<'_> {
    fn chi_square(&self, modelled: &[f64], t: &[f64]) -> (f64, f64) {
        let data = self
            .measured
            .iter()
            .zip(modelled)
            .zip(self.sigma)
            .map(|((y, f), s)| ((y - f) / s).powi(2))
            .sum();
        let prior = t
            .iter()
            .zip(self.prior_mean)
            .zip(self.prior_sigma)
            .map(|((t, a), s)| ((t - a) / s).powi(2))
            .sum();
        (data, prior)
    }

    /// The Jacobian at `t` (where the model is `modelled`) by forward
    /// differences, its columns evaluated by `evaluate_many` (in parallel).
    fn jacobian<E>(&self, t: &[f64], modelled: &[f64], evaluate_many: &E) -> Option<Vec<f64>>
    where
        E: Fn(&[Vec<f64>]) -> Vec<Option<Vec<f64>>>,
    {
        let n = t.len();
        let m = modelled.len();
        let points: Vec<Vec<f64>> = (0..n)
            .map(|k| {
                let mut p = t.to_vec();
                p[k] += self.step;
                p
            })
            .collect();
        let columns = evaluate_many(&points);
        let mut jacobian = vec![0.0; m * n];
        for (k, column) in columns.into_iter().enumerate() {
            let column = column?;
            for i in 0..m {
                jacobian[i * n + k] = (column[i] - modelled[i]) / self.step;
            }
        }
        Some(jacobian)
    }

    /// A = J^T W J + S_a^-1 and g = J^T W (y - F) - S_a^-1 (t - t_a).
    fn normal_equations(
        &self,
        jacobian: &[f64],
        modelled: &[f64],
        t: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let n = t.len();
        let mut a = vec![0.0; n * n];
        let mut g = vec![0.0; n];
        for (i, ((y, f), s)) in self
            .measured
            .iter()
            .zip(modelled)
            .zip(self.sigma)
            .enumerate()
        {
            let w = 1.0 / (s * s);
            let row = &jacobian[i * n..][..n];
            for j in 0..n {
                g[j] += row[j] * w * (y - f);
                for k in 0..n {
                    a[j * n + k] += row[j] * w * row[k];
                }
            }
        }
        for k in 0..n {
            let w = 1.0 / (self.prior_sigma[k] * self.prior_sigma[k]);
            a[k * n + k] += w;
            g[k] -= w * (t[k] - self.prior_mean[k]);
        }
        (a, g)
    }

    /// Levenberg-Marquardt from `start` (fit coordinates, or a
    /// [`Solution`] to go on from). `evaluate_many` computes the model at
    /// several points (None where the model fails there: treated as an
    /// infinitely bad point).
    ///
    /// The Jacobian is made by finite differences at the start; after each
    /// accepted step it is updated by Broyden's rank-one formula (Broyden
    /// 1965; Madsen, Nielsen & Tingleff 2004, eq. 3.19), which costs no
    /// model evaluation, and made anew by finite differences only where
    /// it matters: when no step lowers chi^2 with an updated one, and at
    /// the end, where it decides convergence and gives the covariance.
    pub(crate) fn solve<E>(&self, start: Start, evaluate_many: &E) -> Option<Solution>
    where
        E: Fn(&[Vec<f64>]) -> Vec<Option<Vec<f64>>>,
    {
        let start_fresh = match &start {
            Start::At(_) => None,
            Start::From(solution) => Some(solution.fresh),
        };
        let (mut t, mut modelled, mut jacobian, mut lambda) = match start {
            Start::At(t) => {
                let modelled = evaluate_many(std::slice::from_ref(&t)).pop()??;
                let jacobian = self.jacobian(&t, &modelled, evaluate_many)?;
                (t, modelled, jacobian, 1e-2)
            }
            Start::From(solution) => (
                solution.t,
                solution.modelled,
                solution.jacobian,
                solution.lambda,
            ),
        };
        // Whether `jacobian` is a finite-difference one at t.
        let mut fresh = match &start_fresh {
            Some(f) => *f,
            None => true,
        };
        let n = t.len();
        let (mut data, mut prior) = self.chi_square(&modelled, &t);
        let mut converged = false;
        let mut iterations = 0;
        while iterations < self.max_iterations {
            iterations += 1;
            let (a, g) = self.normal_equations(&jacobian, &modelled, &t);
            let mut accepted = None;
            for _ in 0..12 {
                let mut damped = a.clone();
                for k in 0..n {
                    damped[k * n + k] *= 1.0 + lambda;
                }
                let Some(l) = cholesky(&damped, n) else {
                    lambda *= 10.0;
                    continue;
                };
                let mut step = cholesky_solve(&l, n, &g);
                // No step longer than 3 units of t at once: the logit
                // coordinates saturate beyond, and the model is far from
                // linear over such a step anyway.
                let longest = step.iter().fold(0.0f64, |m, s| m.max(s.abs()));
                if longest > 3.0 {
                    step.iter_mut().for_each(|s| *s *= 3.0 / longest);
                }
                let trial: Vec<f64> = t.iter().zip(&step).map(|(t, s)| t + s).collect();
                if let Some(trial_model) =
                    evaluate_many(std::slice::from_ref(&trial)).pop().flatten()
                {
                    let (d, p) = self.chi_square(&trial_model, &trial);
                    if d + p < data + prior {
                        // The step measured by the posterior's metric: how
                        // many (squared) standard deviations it moved.
                        let metric: f64 = (0..n)
                            .map(|j| step[j] * (0..n).map(|k| a[j * n + k] * step[k]).sum::<f64>())
                            .sum();
                        accepted = Some((trial, trial_model, d, p, step, metric));
                        lambda = (lambda / 5.0).max(1e-7);
                        break;
                    }
                }
                lambda *= 5.0;
            }
            let Some((trial, trial_model, d, p, step, metric)) = accepted else {
                if fresh {
                    // No step lowers chi^2 however short, with a true
                    // Jacobian: a minimum, to the model's precision.
                    converged = true;
                    break;
                }
                // The updated Jacobian has gone stale: make it anew.
                jacobian = self.jacobian(&t, &modelled, evaluate_many)?;
                fresh = true;
                lambda = lambda.min(1e-2);
                continue;
            };
            let step_from_fresh = fresh;
            broyden_update(&mut jacobian, &step, &modelled, &trial_model);
            fresh = false;
            t = trial;
            modelled = trial_model;
            data = d;
            prior = p;
            // Converged when the step is small against the posterior
            // uncertainty (Rodgers 2000, eq. 5.29: d^2 << n): further
            // steps would change the answer by a fraction of its error.
            // Only a step from a true Jacobian decides; after a small
            // updated step, the next comes from a true one.
            if metric < CONVERGENCE_METRIC * n as f64 {
                jacobian = self.jacobian(&t, &modelled, evaluate_many)?;
                fresh = true;
                if step_from_fresh {
                    converged = true;
                    break;
                }
            }
        }
        let mut covariance = Vec::new();
        if self.finish {
            if !fresh {
                jacobian = self.jacobian(&t, &modelled, evaluate_many)?;
                fresh = true;
            }
            let (a, _) = self.normal_equations(&jacobian, &modelled, &t);
            covariance = inverse(&a, n)?;
        }
        Some(Solution {
            t,
            modelled,
            chi_square_measurements: data,
            chi_square_prior: prior,
            jacobian,
            fresh,
            lambda,
            covariance,
            iterations,
            converged,
        })
    }
}

/// Broyden's rank-one update of `jacobian` (row-major, measurements x
/// parameters) after the model went from `before` to `after` over `step`:
/// J += (dF - J dt) dt^T / (dt^T dt), so that J dt = dF exactly.
fn broyden_update(jacobian: &mut [f64], step: &[f64], before: &[f64], after: &[f64]) {
    let n = step.len();
    let length_squared: f64 = step.iter().map(|s| s * s).sum();
    if length_squared == 0.0 {
        return;
    }
    for (i, (b, a)) in before.iter().zip(after).enumerate() {
        let row = &mut jacobian[i * n..][..n];
        let predicted: f64 = row.iter().zip(step).map(|(j, s)| j * s).sum();
        let correction = (a - b - predicted) / length_squared;
        for (j, s) in row.iter_mut().zip(step) {
            *j += correction * s;
        }
    }
}

/// Where a fit starts.
pub(crate) enum Start {
    /// At these fit coordinates.
    At(Vec<f64>),
    /// Where an earlier fit stopped (its model, Jacobian and damping).
    From(Solution),
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-linear model with a known answer: y = a exp(-b x) sampled
    /// without noise is recovered, and the covariance equals the inverse
    /// of J^T W J + S_a^-1 of the exact Jacobian.
    #[test]
    fn levenberg_marquardt_recovers_an_exponential() {
        let x: Vec<f64> = (0..20).map(|i| i as f64 * 0.25).collect();
        let truth = [1.3f64, 0.7];
        let y: Vec<f64> = x.iter().map(|x| truth[0] * (-truth[1] * x).exp()).collect();
        let sigma = vec![0.01; x.len()];
        let problem = Problem {
            measured: &y,
            sigma: &sigma,
            prior_mean: &[0.0, 0.0],
            prior_sigma: &[1e3, 1e3],
            step: 1e-7,
            max_iterations: 50,
            finish: true,
        };
        let model = |points: &[Vec<f64>]| -> Vec<Option<Vec<f64>>> {
            points
                .iter()
                .map(|p| Some(x.iter().map(|x| p[0] * (-p[1] * x).exp()).collect()))
                .collect()
        };
        let solution = problem.solve(Start::At(vec![0.2, 2.0]), &model).unwrap();
        assert!(solution.converged);
        assert!(
            (solution.t[0] - truth[0]).abs() < 1e-6 && (solution.t[1] - truth[1]).abs() < 1e-6,
            "{:?}",
            solution.t
        );
        assert!(solution.chi_square_measurements < 1e-6);
        // Exact J^T W J at the truth.
        let mut a = [1e-6, 0.0, 0.0, 1e-6];
        for x in &x {
            let j = [(-truth[1] * x).exp(), -truth[0] * x * (-truth[1] * x).exp()];
            for r in 0..2 {
                for c in 0..2 {
                    a[r * 2 + c] += j[r] * j[c] / 1e-4;
                }
            }
        }
        let exact = inverse(&a, 2).unwrap();
        for (c, e) in solution.covariance.iter().zip(exact) {
            assert!((c - e).abs() < 1e-4 * e.abs().max(1e-9), "{c} {e}");
        }
    }
}
