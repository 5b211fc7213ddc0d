//! # The Gauss-Legendre rule
//!
//! The n-point Gauss-Legendre rule integrates polynomials of degree up to
//! 2n - 1 exactly on [-1, 1] with positive weights (Abramowitz & Stegun
//! 25.4.29; Press et al., Numerical Recipes 3rd ed., §4.6):
//!
//! ```text
//!     integral_{-1}^{1} f(t) dt  ~=  sum_i w_i f(t_i),   P_n(t_i) = 0,
//!     w_i = 2 / ((1 - t_i^2) P_n'(t_i)^2)                (sum_i w_i = 2)
//! ```
//!
//! Nodes and weights are dimensionless; on an interval [a, b] the nodes map
//! to `a + (b - a) (t_i + 1) / 2` and the weights scale by `(b - a) / 2`.
//! One generator serves the whole project: the radius rules of
//! [`crate::distribution`] (composite, panels in `ln r`) and sora's
//! discrete-ordinate streams (one rule on each hemisphere of mu in [0, 1]).
//! The nodes are the roots of `P_n` by Newton's method from Tricomi's
//! initial guess, `P_n` by its three-term recurrence, converged to machine
//! precision; the rule is exactly symmetric (each pair +-t_i computed once).

use std::f64::consts::PI;

/// Gauss-Legendre nodes and weights on [-1, 1] of order `order` (>= 1),
/// nodes increasing; Newton iteration on the Legendre polynomial from the
/// Tricomi initial guess, converged to machine precision.
pub fn gauss_legendre(order: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; order];
    let mut weights = vec![0.0; order];
    let n = order as f64;
    for i in 0..order.div_ceil(2) {
        let mut z = (PI * (i as f64 + 0.75) / (n + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            // Legendre P_n(z) by the three-term recurrence, and P_n'(z).
            let (mut p_previous, mut p) = (0.0, 1.0);
            for j in 0..order {
                let j = j as f64;
                let p_next = ((2.0 * j + 1.0) * z * p - j * p_previous) / (j + 1.0);
                p_previous = p;
                p = p_next;
            }
            derivative = n * (z * p - p_previous) / (z * z - 1.0);
            let step = p / derivative;
            z -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        nodes[i] = -z;
        nodes[order - 1 - i] = z;
        let weight = 2.0 / ((1.0 - z * z) * derivative * derivative);
        weights[i] = weight;
        weights[order - 1 - i] = weight;
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for order in [1, 2, 5, 8, 12, 20] {
            let (nodes, weights) = gauss_legendre(order);
            assert!(nodes.windows(2).all(|w| w[0] < w[1]));
            for degree in 0..2 * order {
                let integral: f64 = nodes
                    .iter()
                    .zip(&weights)
                    .map(|(x, w)| w * x.powi(degree as i32))
                    .sum();
                let exact = if degree % 2 == 1 {
                    0.0
                } else {
                    2.0 / (degree as f64 + 1.0)
                };
                assert!(
                    (integral - exact).abs() < 1e-14,
                    "order {order} degree {degree}: {integral}"
                );
            }
        }
    }
}
