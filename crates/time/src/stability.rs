//! The critical step of central difference, Δt_crit = 2/ω_max (METHOD.md §4),
//! with ω_max² the largest eigenvalue of M_L⁻¹K.

use nalgebra_sparse::CsrMatrix;

use stickslip_linalg::chunks::{each_chunk_of, each_chunk_summed, partials, CHUNK};
use stickslip_linalg::csr::{dot, spmv};

/// Largest eigenvalue of M⁻¹K for a diagonal (lumped) mass, by Lanczos on
/// the symmetric M^{-1/2} K M^{-1/2}.
///
/// The top Ritz value of a Krylov space converges from below to λ_max much
/// faster than power iteration converges when the upper spectrum is
/// clustered (as on a fine mesh); no reorthogonalization is needed for the
/// extreme eigenvalue. Stops when it changes by less than 1e-12 relative
/// over 5 steps, or after `max_steps`.
pub fn largest_eigenvalue(
    stiffness: &CsrMatrix<f64>,
    lumped_mass: &[f64],
    max_steps: usize,
) -> f64 {
    largest_eigenvalue_with(|x, y| spmv(stiffness, x, y), lumped_mass, max_steps)
}

/// [`largest_eigenvalue`] with y = K x formed by `product` (the explicit
/// step's own K·x).
///
/// A step is the product and three passes over the vectors, threaded by
/// fixed chunks with their sums added in chunk order
/// (`stickslip_linalg::chunks`: the same bits on any number of threads): with x = M^{-1/2} q and y = K x, α = yᵀx; w = M^{-1/2} y −
/// α q − β q_prev and β² = wᵀw; then q_prev, q ← q, w/β and the next x.
/// (α = yᵀx is qᵀM^{-1/2} K M^{-1/2} q, one pass before w exists.)
pub fn largest_eigenvalue_with(
    mut product: impl FnMut(&[f64], &mut [f64]),
    lumped_mass: &[f64],
    max_steps: usize,
) -> f64 {
    let n = lumped_mass.len();
    if n == 0 {
        return 0.0;
    }
    let scale: Vec<f64> = lumped_mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    // A deterministic start vector with all modes present.
    let mut q: Vec<f64> = (0..n)
        .map(|i| 1.0 + ((i as f64) * 0.618_033_988_75).fract())
        .collect();
    let norm = dot(&q, &q).sqrt();
    q.iter_mut().for_each(|v| *v /= norm);
    let mut x: Vec<f64> = q.iter().zip(&scale).map(|(q, s)| q * s).collect();
    let mut q_prev = vec![0.0; n];
    let mut y = vec![0.0; n];
    let mut partials = partials::<1>(n);
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    let mut beta_prev = 0.0;
    let mut last = 0.0;
    for step in 0..max_steps.min(n) {
        product(&x, &mut y);
        let [alpha] = each_chunk_summed(&mut y, &mut partials, |c, y, p| {
            p[0] = dot(y, &x[c * CHUNK..c * CHUNK + y.len()]);
        });
        // y becomes w in place.
        let [beta_squared] = each_chunk_summed(&mut y, &mut partials, |c, w, p| {
            let r = c * CHUNK..c * CHUNK + w.len();
            let (q, qp, s) = (&q[r.clone()], &q_prev[r.clone()], &scale[r]);
            let mut sum = 0.0;
            for i in 0..w.len() {
                w[i] = w[i] * s[i] - (alpha * q[i] + beta_prev * qp[i]);
                sum += w[i] * w[i];
            }
            p[0] = sum;
        });
        let beta = beta_squared.sqrt();
        alphas.push(alpha);
        if step % 5 == 4 || beta <= 1e-14 * alpha.abs() || step + 1 == max_steps.min(n) {
            let top = tridiagonal_max_eigenvalue(&alphas, &betas);
            if beta <= 1e-14 * alpha.abs() || (top - last).abs() <= 1e-12 * top.abs() {
                return top;
            }
            last = top;
        }
        betas.push(beta);
        // q_prev ← q, q ← w/β, x ← M^{-1/2} q.
        std::mem::swap(&mut q_prev, &mut q);
        let (w, s) = (&y, &scale);
        each_chunk_of([&mut q, &mut x], &mut partials, |c, [q, x], _| {
            let r = c * CHUNK..c * CHUNK + q.len();
            let (w, s) = (&w[r.clone()], &s[r]);
            for i in 0..q.len() {
                q[i] = w[i] / beta;
                x[i] = q[i] * s[i];
            }
        });
        beta_prev = beta;
    }
    tridiagonal_max_eigenvalue(&alphas, &betas[..alphas.len().saturating_sub(1)])
}

/// Largest eigenvalue of the symmetric tridiagonal matrix with diagonal `a`
/// and off-diagonal `b`, by bisection on the Sturm count.
fn tridiagonal_max_eigenvalue(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len();
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for i in 0..n {
        let r = if i > 0 { b[i - 1].abs() } else { 0.0 } + if i < n - 1 { b[i].abs() } else { 0.0 };
        lo = lo.min(a[i] - r);
        hi = hi.max(a[i] + r);
    }
    // Number of eigenvalues below x.
    let count_below = |x: f64| {
        let mut count = 0;
        let mut d = 1.0;
        for i in 0..n {
            let off = if i > 0 { b[i - 1] * b[i - 1] } else { 0.0 };
            d = a[i] - x - if i > 0 { off / d } else { 0.0 };
            if d == 0.0 {
                d = -1e-300;
            }
            if d < 0.0 {
                count += 1;
            }
        }
        count
    };
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if count_below(mid) >= n {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// An upper bound on ω_max², the largest eigenvalue of M⁻¹K for a
/// diagonal (lumped) mass: Gershgorin's, the largest row sum of
/// |M^{-1/2} K M^{-1/2}|, max_i Σ_j |K_ij| / √(m_i m_j). Safe but loose
/// (above [`largest_eigenvalue`]'s estimate), for deciding what no Δt
/// below 2/√bound can be refused for.
pub fn gershgorin_bound(stiffness: &CsrMatrix<f64>, lumped_mass: &[f64]) -> f64 {
    let scale: Vec<f64> = lumped_mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    stiffness
        .row_iter()
        .zip(&scale)
        .map(|(row, si)| {
            let sum: f64 = row
                .col_indices()
                .iter()
                .zip(row.values())
                .map(|(&j, v)| v.abs() * scale[j])
                .sum();
            sum * si
        })
        .fold(0.0, f64::max)
}

/// Δt_crit = 2/ω_max for central difference with the lumped mass.
pub fn critical_step(stiffness: &CsrMatrix<f64>, lumped_mass: &[f64]) -> f64 {
    critical_step_with(|x, y| spmv(stiffness, x, y), lumped_mass)
}

/// [`critical_step`] with y = K x formed by `product`.
pub fn critical_step_with(product: impl FnMut(&[f64], &mut [f64]), lumped_mass: &[f64]) -> f64 {
    let lambda = largest_eigenvalue_with(product, lumped_mass, 300);
    if lambda > 0.0 {
        2.0 / lambda.sqrt()
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    /// K of a chain of n unit springs between n nodes, its ends held by a
    /// spring each (`fixed`) or free.
    fn chain(n: usize, fixed: bool) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n, n);
        for i in 0..n {
            let ends = if fixed {
                2
            } else {
                usize::from(i > 0) + usize::from(i + 1 < n)
            };
            coo.push(i, i, ends as f64);
            if i > 0 {
                coo.push(i, i - 1, -1.0);
                coo.push(i - 1, i, -1.0);
            }
        }
        CsrMatrix::from(&coo)
    }

    #[test]
    fn spring_chain_eigenvalue_matches_closed_form() {
        // Fixed-fixed chain of n unit masses and unit springs: eigenvalues
        // 4 sin²(kπ/(2(n+1))), k = 1..n; the largest has k = n.
        let n = 400;
        let k = chain(n, true);
        let m = vec![1.0; n];
        let exact = 4.0
            * (n as f64 * std::f64::consts::PI / (2.0 * (n as f64 + 1.0)))
                .sin()
                .powi(2);
        let lambda = largest_eigenvalue(&k, &m, 300);
        // The top Ritz value approaches λ_max from below; on this chain the
        // upper spectrum is clustered (relative gap 2.5e-4), and 300 steps
        // leave about 1.4e-6. Δt_crit = 2/√λ then errs by < 1e-5, far below
        // the 2% the stability map asks for.
        assert!(lambda <= exact * (1.0 + 1e-12), "Ritz value above λ_max");
        assert!(
            (lambda - exact).abs() < 1e-5 * exact,
            "λ = {lambda}, closed form {exact}"
        );
        // Masses of 4 halve ω: Δt_crit doubles.
        let m4 = vec![4.0; n];
        let ratio = critical_step(&k, &m4) / critical_step(&k, &m);
        assert!((ratio - 2.0).abs() < 1e-6, "ratio {ratio}");
    }

    #[test]
    fn gershgorin_bounds_the_chain_from_above() {
        // Fixed-fixed chain: every row of K is (−1, 2, −1), masses m, so
        // each row sum of |M^{-1/2} K M^{-1/2}| is 4/m, the bound; above
        // λ_max = 4 sin²(nπ/(2(n+1)))/m, by 1.5e-5 of it at n = 400.
        let n = 400;
        let k = chain(n, true);
        for m in [1.0, 4.0] {
            let exact = 4.0
                * (n as f64 * std::f64::consts::PI / (2.0 * (n as f64 + 1.0)))
                    .sin()
                    .powi(2)
                / m;
            let bound = gershgorin_bound(&k, &vec![m; n]);
            assert_eq!(bound, 4.0 / m);
            assert!(
                bound > exact && bound - exact < 2e-5 * exact,
                "{bound} {exact}"
            );
        }
    }

    #[test]
    fn a_free_chain_has_zero_modes_and_the_same_top() {
        // Free-free chain of n unit masses and unit springs (a floating
        // part: K has the rigid translation in its null space):
        // eigenvalues 4 sin²(kπ/(2n)), k = 0..n−1; the zero mode is in the
        // start vector and must not disturb the top one (k = n − 1).
        let n = 400;
        let k = chain(n, false);
        let m = vec![1.0; n];
        let exact = 4.0
            * ((n as f64 - 1.0) * std::f64::consts::PI / (2.0 * n as f64))
                .sin()
                .powi(2);
        let lambda = largest_eigenvalue(&k, &m, 300);
        assert!(lambda <= exact * (1.0 + 1e-12), "Ritz value above λ_max");
        assert!(
            (lambda - exact).abs() < 1e-5 * exact,
            "λ = {lambda}, closed form {exact}"
        );
    }
}
