//! The critical step of central difference, Δt_crit = 2/ω_max (METHOD.md §4),
//! with ω_max² the largest eigenvalue of M_L⁻¹K.

use nalgebra_sparse::CsrMatrix;
use rayon::prelude::*;

use stickslip_linalg::chunks::{each_chunk_of, each_chunk_summed, parallel, partials, CHUNK};
use stickslip_linalg::csr::{dot, spmv};

/// Relative residual of the top Ritz pair at which Lanczos stops: the
/// estimate is θ + r with r ≤ `RESIDUAL`·θ, so Δt_crit = 2/√(θ + r) lies
/// at most r/(2θ) = 5e-4 below 2/√θ (the stability map asks 1%).
pub const RESIDUAL: f64 = 1e-3;

/// Largest eigenvalue of M⁻¹K for a diagonal (lumped) mass, by Lanczos on
/// the symmetric A = M^{-1/2} K M^{-1/2}.
///
/// The top Ritz value θ of a Krylov space is a Rayleigh quotient of A, so
/// θ ≤ λ_max; its Ritz vector's residual has the norm r = β_k |s_k| (β_k
/// the last Lanczos coefficient, s_k the last component of T_k's top
/// eigenvector), so some eigenvalue of A lies within r of θ. The estimate
/// is θ + r, once r ≤ [`RESIDUAL`]·θ or after `max_steps` (one at least,
/// n at most). It is above λ_max where that eigenvalue is λ_max, which is
/// what the top Ritz value converges to first (no reorthogonalization is
/// needed for the extreme eigenvalue) unless the start vector all but
/// lacks λ_max's mode: the standard assumption, not a proof, and the
/// stability map measures the margin of [`critical_step`] (`cargo xtask
/// stability`; where Gershgorin's cap applies, the cap's). A stop on
/// θ's own stagnation gave a θ below λ_max.
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
/// A step is the product and two passes over the vectors, threaded by
/// fixed chunks with their sums added in chunk order
/// (`stickslip_linalg::chunks`: the same bits on any number of threads).
/// The Lanczos vectors are kept unnormalized, w_j = β_j q_{j+1}, so that
/// the next product's x = M^{-1/2} w_j is formed in the pass that forms
/// w_j: with y = K x, α_j = yᵀx/β_{j−1}² and
/// w_j = (M^{-1/2} y − α_j w_{j−1})/β_{j−1} − (β_{j−1}/β_{j−2}) w_{j−2},
/// β_j² = w_jᵀw_j.
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
    let mut w: Vec<f64> = (0..n)
        .map(|i| 1.0 + ((i as f64) * 0.618_033_988_75).fract())
        .collect();
    let norm = dot(&w, &w).sqrt();
    w.iter_mut().for_each(|v| *v /= norm);
    let mut x: Vec<f64> = w.iter().zip(&scale).map(|(w, s)| w * s).collect();
    let mut w_prev = vec![0.0; n];
    let mut y = vec![0.0; n];
    let mut partials = partials::<1>(n);
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    // β_{j−1} and β_{j−2}; the start vector is q_1 = w_0 (β_0 = 1).
    let (mut beta, mut beta_prev) = (1.0_f64, 1.0_f64);
    let mut floor = f64::NEG_INFINITY;
    let steps = max_steps.clamp(1, n);
    for step in 0..steps {
        product(&x, &mut y);
        let [xy] = each_chunk_summed(&mut y, &mut partials, |c, y, p| {
            p[0] = dot(y, &x[c * CHUNK..c * CHUNK + y.len()]);
        });
        let alpha = xy / (beta * beta);
        // w_{j−2} becomes w_j in place, x its M^{-1/2} w_j.
        let (c, back) = (1.0 / beta, if step == 0 { 0.0 } else { beta / beta_prev });
        let (yv, wv) = (&y, &w);
        let [beta_squared] =
            each_chunk_of([&mut w_prev, &mut x], &mut partials, |k, [wn, x], p| {
                let r = k * CHUNK..k * CHUNK + wn.len();
                let (y, w, s) = (&yv[r.clone()], &wv[r.clone()], &scale[r]);
                let mut sum = 0.0;
                for i in 0..wn.len() {
                    wn[i] = (y[i] * s[i] - alpha * w[i]) * c - back * wn[i];
                    x[i] = wn[i] * s[i];
                    sum += wn[i] * wn[i];
                }
                p[0] = sum;
            });
        std::mem::swap(&mut w, &mut w_prev);
        (beta_prev, beta) = (beta, beta_squared.sqrt());
        alphas.push(alpha);
        // θ from above to within a small part of the stop's tolerance:
        // both it and s_k², which grows with the point it is taken at,
        // err on the safe side.
        let top = tridiagonal_top(&alphas, &betas, floor, 1e-3 * RESIDUAL);
        let r = beta * last_component_squared(&alphas, &betas, top).sqrt();
        if r <= RESIDUAL * top || beta == 0.0 || step + 1 == steps {
            return top + r;
        }
        floor = top * (1.0 - 1e-3 * RESIDUAL);
        betas.push(beta);
    }
    unreachable!("the loop returns at its last step")
}

/// An upper end, within `rel` of it, of the largest eigenvalue of the
/// symmetric tridiagonal matrix with diagonal `a` and off-diagonal `b`, by
/// bisection on the Sturm count between Gershgorin's bound and `floor` (a
/// value below it: the previous top Ritz value, by interlacing).
fn tridiagonal_top(a: &[f64], b: &[f64], floor: f64, rel: f64) -> f64 {
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
    if floor > lo && floor < hi && count_below(floor) < n {
        lo = floor;
    }
    while hi - lo > rel * hi.abs() {
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

/// s_k², the squared last component of the unit eigenvector of the
/// symmetric tridiagonal (a, b) for its largest eigenvalue θ, taken at x
/// at or just above θ: s_k² = χ_{k−1}(θ)/χ_k'(θ) = −1/d_k'(θ), d_i the
/// pivots of T − xI (d_i = a_i − x − b_{i−1}²/d_{i−1}). Above θ,
/// −1/d_k'(x) grows with x (d_k' = −1 − b²Σ_j w_j/(x − μ_j)², μ_j the
/// eigenvalues of T_{k−1}, all below x), so an x above θ overestimates.
///
/// A zero pivot, or one whose square leaves f64's range, gives 1, the
/// largest s_k² can be (the safe side: r = β_k): the recurrence there
/// would give 0 or NaN, a false stop.
fn last_component_squared(a: &[f64], b: &[f64], x: f64) -> f64 {
    let (mut d, mut slope) = (a[0] - x, -1.0_f64);
    for i in 1..a.len() {
        let b2 = b[i - 1] * b[i - 1];
        slope = -1.0 + b2 * slope / (d * d);
        d = a[i] - x - b2 / d;
    }
    let s2 = -1.0 / slope;
    if s2.is_finite() && s2 > 0.0 {
        s2.min(1.0)
    } else {
        1.0
    }
}

/// An upper bound on ω_max², the largest eigenvalue of M⁻¹K for a
/// diagonal (lumped) mass: Gershgorin's, the largest row sum of
/// |M^{-1/2} K M^{-1/2}|, max_i Σ_j |K_ij| / √(m_i m_j). Safe but loose,
/// for deciding what no Δt below 2/√bound can be refused for; it also
/// caps [`critical_step`]'s estimate, θ + r, which on a clustered top
/// spectrum can pass it (θ ≤ λ_max ≤ the bound: the cap stays above θ).
pub fn gershgorin_bound(stiffness: &CsrMatrix<f64>, lumped_mass: &[f64]) -> f64 {
    let scale: Vec<f64> = lumped_mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    let (offsets, cols, values) = (
        stiffness.row_offsets(),
        stiffness.col_indices(),
        stiffness.values(),
    );
    let row_sum = |i: usize| {
        let row = offsets[i]..offsets[i + 1];
        let sum: f64 = cols[row.clone()]
            .iter()
            .zip(&values[row])
            .map(|(&j, v)| v.abs() * scale[j])
            .sum();
        sum * scale[i]
    };
    // A maximum, the same whoever finds it: on the pool where the passes
    // use it (a small model starts no threads).
    let n = stiffness.nrows();
    if parallel(n) {
        (0..n)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(row_sum)
            .reduce(|| 0.0, f64::max)
    } else {
        (0..n).map(row_sum).fold(0.0, f64::max)
    }
}

/// Δt_crit = 2/ω_max for central difference with the lumped mass, from
/// [`largest_eigenvalue`]'s estimate capped by [`gershgorin_bound`].
pub fn critical_step(stiffness: &CsrMatrix<f64>, lumped_mass: &[f64]) -> f64 {
    critical_step_with(
        |x, y| spmv(stiffness, x, y),
        lumped_mass,
        Some(gershgorin_bound(stiffness, lumped_mass)),
    )
}

/// [`critical_step`] with y = K x formed by `product`, its estimate of
/// ω_max² capped by `bound` where one is known (a safe upper bound of that
/// product's M⁻¹K: [`gershgorin_bound`]), so that no Δt below 2/√bound
/// is ever above the critical step.
pub fn critical_step_with(
    product: impl FnMut(&[f64], &mut [f64]),
    lumped_mass: &[f64],
    bound: Option<f64>,
) -> f64 {
    let estimate = largest_eigenvalue_with(product, lumped_mass, 300);
    let lambda = bound.map_or(estimate, |b| estimate.min(b));
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

    /// The top eigenvalue 4 sin²(nπ/(2(n+1))) of the fixed-fixed chain of
    /// n unit masses and unit springs (eigenvalues 4 sin²(kπ/(2(n+1))),
    /// k = 1..n), over the masses m.
    fn fixed_chain_top(n: usize, m: f64) -> f64 {
        4.0 * (n as f64 * std::f64::consts::PI / (2.0 * (n as f64 + 1.0)))
            .sin()
            .powi(2)
            / m
    }

    #[test]
    fn spring_chain_eigenvalue_is_bounded_from_above() {
        // The upper spectrum is clustered (relative gap 2.5e-4), where the
        // Ritz value converges slowly from below; the estimate θ + r is
        // above λ_max (θ has found it) and within RESIDUAL of θ ≤ λ_max.
        let n = 400;
        let k = chain(n, true);
        let m = vec![1.0; n];
        let exact = fixed_chain_top(n, 1.0);
        let lambda = largest_eigenvalue(&k, &m, 300);
        assert!(lambda >= exact, "estimate {lambda} below λ_max {exact}");
        assert!(
            lambda <= exact * (1.0 + RESIDUAL),
            "λ = {lambda}, closed form {exact}"
        );
        // Here θ + r passes Gershgorin's bound, 4: the critical step is
        // the bound's, which no stable Δt is above.
        let bound = gershgorin_bound(&k, &m);
        assert!(lambda > bound, "{lambda} ≤ {bound}: the cap is not tested");
        assert_eq!(critical_step(&k, &m), 2.0 / bound.sqrt());
        assert!(critical_step(&k, &m) <= 2.0 / exact.sqrt());
        // Masses of 4 halve ω: Δt_crit doubles (the scaling by 1/2 is
        // exact in floating point, so every Lanczos step scales alike).
        let m4 = vec![4.0; n];
        let ratio = critical_step(&k, &m4) / critical_step(&k, &m);
        assert!((ratio - 2.0).abs() < 1e-12, "ratio {ratio}");
    }

    #[test]
    fn a_zero_pivot_gives_the_largest_last_component() {
        // T = [[2, 1], [1, 2]] at x = 2: the first pivot is 0, where the
        // recurrence's s² would be 0 (a false stop) or NaN.
        assert_eq!(last_component_squared(&[2.0, 2.0], &[1.0], 2.0), 1.0);
        // A pivot whose square underflows, likewise.
        let s2 = last_component_squared(&[1e-170, 2.0, 2.0], &[1.0, 1.0], 0.0);
        assert_eq!(s2, 1.0);
    }

    #[test]
    fn the_ritz_vectors_last_component_matches_the_closed_form() {
        // T = tridiag(−1, 2, −1) of order k: top eigenvalue
        // 2 + 2cos(π/(k+1)), unit eigenvector components
        // √(2/(k+1)) sin(ijπ/(k+1)) with j = k, the last one i = k.
        for k in [1, 2, 7, 40] {
            let (a, b) = (vec![2.0; k], vec![-1.0; k.saturating_sub(1)]);
            let h = std::f64::consts::PI / (k as f64 + 1.0);
            let theta = 2.0 + 2.0 * h.cos();
            let top = tridiagonal_top(&a, &b, f64::NEG_INFINITY, 1e-15);
            assert!(
                (top - theta).abs() <= 1e-14 * theta,
                "k = {k}: {top} vs {theta}"
            );
            let exact = 2.0 / (k as f64 + 1.0) * (k as f64 * k as f64 * h).sin().powi(2);
            let got = last_component_squared(&a, &b, top);
            assert!(
                (got - exact).abs() <= 1e-10 * exact,
                "k = {k}: s² = {got}, closed form {exact}"
            );
            // Taken above θ it can only grow (the estimate's safe side).
            assert!(last_component_squared(&a, &b, theta * (1.0 + 1e-6)) >= got);
        }
    }

    #[test]
    fn gershgorin_bounds_the_chain_from_above() {
        // Fixed-fixed chain: every row of K is (−1, 2, −1), masses m, so
        // each row sum of |M^{-1/2} K M^{-1/2}| is 4/m, the bound; above
        // λ_max = 4 sin²(nπ/(2(n+1)))/m, by 1.5e-5 of it at n = 400.
        let n = 400;
        let k = chain(n, true);
        for m in [1.0, 4.0] {
            let exact = fixed_chain_top(n, m);
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
        assert!(lambda >= exact, "estimate {lambda} below λ_max {exact}");
        assert!(
            lambda <= exact * (1.0 + RESIDUAL),
            "λ = {lambda}, closed form {exact}"
        );
    }
}
