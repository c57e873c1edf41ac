//! Gauss-Legendre rules on [-1, 1] (1 to 5 points) and their tensor products
//! on the reference square [-1, 1]².

/// A 1-D Gauss-Legendre rule with `n` points on [-1, 1], exact for
/// polynomials of degree 2n - 1. Points ascend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussLegendre {
    n: usize,
    points: [f64; 5],
    weights: [f64; 5],
}

impl GaussLegendre {
    /// The `n`-point rule, `1 <= n <= 5` (closed forms, e.g. Abramowitz &
    /// Stegun 25.4.29).
    ///
    /// # Panics
    /// If `n` is 0 or greater than 5 (a programming error, not user input).
    pub fn new(n: usize) -> Self {
        let (p, w): (Vec<f64>, Vec<f64>) = match n {
            1 => (vec![0.0], vec![2.0]),
            2 => {
                let a = 1.0 / 3f64.sqrt();
                (vec![-a, a], vec![1.0, 1.0])
            }
            3 => {
                let a = (3.0f64 / 5.0).sqrt();
                (vec![-a, 0.0, a], vec![5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])
            }
            4 => {
                let r = 2.0 / 7.0 * (6.0f64 / 5.0).sqrt();
                let inner = (3.0 / 7.0 - r).sqrt();
                let outer = (3.0 / 7.0 + r).sqrt();
                let s30 = 30f64.sqrt();
                let wi = (18.0 + s30) / 36.0;
                let wo = (18.0 - s30) / 36.0;
                (vec![-outer, -inner, inner, outer], vec![wo, wi, wi, wo])
            }
            5 => {
                let r = 2.0 * (10.0f64 / 7.0).sqrt();
                let inner = (5.0 - r).sqrt() / 3.0;
                let outer = (5.0 + r).sqrt() / 3.0;
                let s70 = 70f64.sqrt();
                let wi = (322.0 + 13.0 * s70) / 900.0;
                let wo = (322.0 - 13.0 * s70) / 900.0;
                (
                    vec![-outer, -inner, 0.0, inner, outer],
                    vec![wo, wi, 128.0 / 225.0, wi, wo],
                )
            }
            _ => panic!("Gauss-Legendre rules exist here for 1 to 5 points, not {n}"),
        };
        let mut points = [0.0; 5];
        let mut weights = [0.0; 5];
        points[..n].copy_from_slice(&p);
        weights[..n].copy_from_slice(&w);
        GaussLegendre { n, points, weights }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false (a rule has at least one point).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The points, ascending.
    pub fn points(&self) -> &[f64] {
        &self.points[..self.n]
    }

    /// The weights (they sum to 2).
    pub fn weights(&self) -> &[f64] {
        &self.weights[..self.n]
    }
}

/// Tensor-product Gauss rule on the reference square: `n × n` points,
/// ξ varying fastest.
pub fn square_rule(n: usize) -> Vec<([f64; 2], f64)> {
    let g = GaussLegendre::new(n);
    let mut out = Vec::with_capacity(n * n);
    for (&eta, &weta) in g.points().iter().zip(g.weights()) {
        for (&xi, &wxi) in g.points().iter().zip(g.weights()) {
            out.push(([xi, eta], wxi * weta));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Expected values: ∫_{-1}^{1} x^k dx = 2/(k+1) for even k, 0 for odd k;
    /// an n-point Gauss rule is exact up to degree 2n - 1 (and not beyond).
    #[test]
    fn gauss_rules_integrate_monomials_exactly_up_to_degree_2n_minus_1() {
        for n in 1..=5 {
            let g = GaussLegendre::new(n);
            for k in 0..=(2 * n) {
                let exact = if k % 2 == 0 {
                    2.0 / (k as f64 + 1.0)
                } else {
                    0.0
                };
                let q: f64 = g
                    .points()
                    .iter()
                    .zip(g.weights())
                    .map(|(x, w)| w * x.powi(k as i32))
                    .sum();
                if k < 2 * n {
                    assert!((q - exact).abs() < 1e-14, "n={n} k={k}: {q} vs {exact}");
                } else {
                    assert!(
                        (q - exact).abs() > 1e-6,
                        "n={n} should not integrate degree {k} exactly"
                    );
                }
            }
        }
    }

    #[test]
    fn square_rule_area_is_four() {
        for n in 1..=5 {
            let s: f64 = square_rule(n).iter().map(|p| p.1).sum();
            assert!((s - 4.0).abs() < 1e-14);
        }
    }
}
