//! Quadrature along a ray: composite 4-point Gauss-Legendre on panels, and
//! the running integral at the panel's own nodes.
//!
//! The fast single-scattering path needs, at each quadrature node s_k, both
//! the integrand and the column integral_0^{s_k} rho ds (for the
//! transmittance back to the eye). Evaluating rho a second time for the
//! running integral would double the cost, so we integrate the cubic that
//! interpolates rho at the four Gauss nodes: C(a -> s_k) = (b - a)/2 *
//! sum_m `W[k][m]` rho(s_m), with `W[k][m]` = integral_{-1}^{x_k} l_m(t) dt
//! (l_m the Lagrange basis on the nodes). This is exact for cubics, the
//! same order as the Gauss rule's own error for smooth integrands
//! (spectral integration, as in Chebyshev/Gauss collocation methods).

/// Nodes of the 4-point Gauss-Legendre rule on [-1, 1]: the values of
/// [`sora_mie::quadrature::gauss_legendre`](crate::mie::quadrature::gauss_legendre)`(4)`,
/// kept as constants for the per-ray hot path (tested equal).
pub(crate) const GAUSS_NODES: [f64; 4] = [
    -0.861_136_311_594_052_6,
    -0.339_981_043_584_856_3,
    0.339_981_043_584_856_3,
    0.861_136_311_594_052_6,
];

/// Weights of the 4-point Gauss-Legendre rule on [-1, 1] (they sum to 2).
pub(crate) const GAUSS_WEIGHTS: [f64; 4] = [
    0.347_854_845_137_453_86,
    0.652_145_154_862_546_1,
    0.652_145_154_862_546_1,
    0.347_854_845_137_453_86,
];

/// Lagrange basis polynomial `m` on the Gauss nodes, at `t`.
fn lagrange_basis(m: usize, t: f64) -> f64 {
    (0..4)
        .filter(|&j| j != m)
        .map(|j| (t - GAUSS_NODES[j]) / (GAUSS_NODES[m] - GAUSS_NODES[j]))
        .product()
}

/// `W[k][m]` = integral from -1 to x_k of l_m(t) dt (see the module docs),
/// computed by the 4-point rule on [-1, x_k], exact for the cubic l_m.
pub(crate) fn running_integral_matrix() -> [[f64; 4]; 4] {
    let mut w = [[0.0; 4]; 4];
    for (k, row) in w.iter_mut().enumerate() {
        let half = 0.5 * (GAUSS_NODES[k] + 1.0);
        for (m, entry) in row.iter_mut().enumerate() {
            *entry = (0..4)
                .map(|q| {
                    let t = -1.0 + half * (GAUSS_NODES[q] + 1.0);
                    half * GAUSS_WEIGHTS[q] * lagrange_basis(m, t)
                })
                .sum();
        }
    }
    w
}

/// Panel edges on [0, length] crowded toward 0: edge_k = length (k/n)^2.
/// Where a ray starts at the eye, both the density (near the ground) and the
/// transmittance back to the eye are largest near its start; quadratic
/// spacing puts panels of width ~ length/n^2 there and still covers the far
/// end, where the integrand is attenuated.
#[cfg(test)]
pub(crate) fn panel_edge_crowded_at_start(length: f64, k: usize, n: usize) -> f64 {
    let u = k as f64 / n as f64;
    length * u * u
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_rule_integrates_degree_7_exactly() {
        let integral: f64 = GAUSS_NODES
            .iter()
            .zip(GAUSS_WEIGHTS)
            .map(|(x, w)| w * x.powi(6))
            .sum();
        assert!((integral - 2.0 / 7.0).abs() < 1e-15);
        assert!((GAUSS_WEIGHTS.iter().sum::<f64>() - 2.0).abs() < 1e-15);
    }

    #[test]
    fn constants_are_the_generated_rule() {
        let (nodes, weights) = crate::mie::quadrature::gauss_legendre(4);
        for k in 0..4 {
            assert!((nodes[k] - GAUSS_NODES[k]).abs() <= 2e-16, "node {k}");
            assert!((weights[k] - GAUSS_WEIGHTS[k]).abs() <= 4e-16, "weight {k}");
        }
    }

    #[test]
    fn running_integral_is_exact_for_cubics() {
        let w = running_integral_matrix();
        let f = |t: f64| 1.0 - 2.0 * t + 3.0 * t * t + 4.0 * t * t * t;
        let antiderivative = |t: f64| t - t * t + t * t * t + t.powi(4);
        for k in 0..4 {
            let running: f64 = (0..4).map(|m| w[k][m] * f(GAUSS_NODES[m])).sum();
            let exact = antiderivative(GAUSS_NODES[k]) - antiderivative(-1.0);
            assert!((running - exact).abs() < 1e-14, "{k}: {running} vs {exact}");
        }
    }

    #[test]
    fn crowded_edges_cover_the_segment() {
        assert_eq!(panel_edge_crowded_at_start(100.0, 0, 10), 0.0);
        assert_eq!(panel_edge_crowded_at_start(100.0, 10, 10), 100.0);
        assert!((panel_edge_crowded_at_start(100.0, 1, 10) - 1.0).abs() < 1e-12);
    }
}
