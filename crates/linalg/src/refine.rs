//! A x = b to double precision's accuracy by conjugate gradients with a
//! preconditioner cheaper than a double factorization: a factor computed
//! in single precision, or for a matrix close to its diagonal (a
//! consistent mass) that diagonal.
//!
//! A factorization that serves one solve (the explicit run's static
//! preload) costs most of that solve; in f32 it moves half the bytes and
//! its dense kernels fit twice the values in a vector register. Its
//! factor L̃L̃ᵀ = A + E, with ‖E‖ of order u₃₂‖A‖ times a growth factor,
//! is positive definite (faer refuses a pivot ≤ 0), so it preconditions
//! CG, whose iterates then gain about the factor's relative accuracy
//! (u₃₂ κ(A)) a step; the products with A and the sums are in f64, so
//! the solution reaches what a double factorization's solve reaches. A
//! consistent mass needs no factor at all: the assembled quotient
//! xᵀMx / xᵀDx is a weighted mean of the elements' x_eᵀM_e x_e / x_eᵀD_e x_e
//! (Wathen, 1987), so κ(D⁻¹M) ≤ max_e λ_max(D_e⁻¹M_e) / min_e
//! λ_min(D_e⁻¹M_e): 6.25 for Q2 and 9 for Q1 parallelograms, a few units
//! more on distorted cells, whatever the mesh's size, so CG on the
//! diagonal gains a fixed fraction of a digit a step. The
//! stopping test is that solve's accuracy, measured as the normwise
//! backward error η = ‖b − Ax‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞) (Rigal and Gaches):
//! the smallest relative change of A and b that x solves exactly, which a
//! backward-stable Cholesky solve keeps to a small multiple of u₆₄.

use nalgebra_sparse::CsrMatrix;

use crate::csr::{diagonal, dot, spmv};
use crate::SparseCholesky;

/// The backward error refined solves stop at: 2u (u = 2⁻⁵³, f64's unit
/// roundoff), below what the double factorization's solve reaches on the
/// bench's meshes and about twice the floor under which the rounding of a
/// computed residual keeps η (docs/performance.md, "The preload in single
/// precision").
pub const BACKWARD_ERROR: f64 = f64::EPSILON;

/// Iterations after which a refined solve gives up (its caller then
/// factorizes in double): each gains about three digits where the factor
/// serves, so a handful reach [`BACKWARD_ERROR`].
pub const MAX_ITERATIONS: usize = 20;

/// True residuals above the tolerance after the recurrence's fell below
/// it, after which a refined solve gives up: the tolerance is under the
/// floor of the computed residual's rounding for this system.
const MAX_RESTARTS: usize = 2;

/// How a refined solve went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refined {
    /// CG's iterations (each a product with A and a solve with the single
    /// factor, after the first solve).
    pub iterations: usize,
    /// The backward error of the solution returned, by its true residual.
    pub backward_error: f64,
}

/// max_i Σ_j |a_ij|.
fn norm_inf(a: &CsrMatrix<f64>) -> f64 {
    let (offsets, values) = (a.row_offsets(), a.values());
    offsets
        .windows(2)
        .map(|w| values[w[0]..w[1]].iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// max_i |x_i|, NaN where any x_i is (`f64::max` would drop it, and a b
/// with NaNs would pass for zero).
fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m: f64, v| {
        if m.is_nan() || v.is_nan() {
            f64::NAN
        } else {
            m.max(v.abs())
        }
    })
}

impl SparseCholesky {
    /// Solves A x = b in place (`x` holds b on entry) by CG preconditioned
    /// with the single factor ([`SparseCholesky::factorize_single`]),
    /// from x₀ = (L̃L̃ᵀ)⁻¹b, until the backward error of x is at most
    /// `tolerance`. The recurrence's residual stops the iteration and the
    /// true one confirms it (where they differ, CG restarts from the true
    /// one). Products and sums in fixed order: the same bits on any
    /// number of threads.
    ///
    /// # Errors
    /// `x` given back unchanged (holding b) with how far it got, when
    /// [`MAX_ITERATIONS`] did not reach `tolerance`, or the true residual
    /// stayed above it where the recurrence's fell below (twice).
    ///
    /// # Panics
    /// Before a successful [`SparseCholesky::factorize_single`], or for a
    /// matrix or vector of another size (programming errors).
    pub fn solve_refined(
        &self,
        a: &CsrMatrix<f64>,
        x: &mut [f64],
        tolerance: f64,
    ) -> Result<Refined, Refined> {
        refine(a, x, tolerance, MAX_ITERATIONS, |z| {
            self.solve_single_in_place(z)
        })
    }
}

/// Solves A x = b in place (`x` holds b on entry) by CG preconditioned
/// with A's diagonal, from x₀ = D⁻¹b, to the backward error `tolerance`,
/// as [`SparseCholesky::solve_refined`] (the same stopping test, bits on
/// any number of threads and errors) but with at most `max_iterations`:
/// for a matrix close to its diagonal (module documentation).
///
/// # Errors
/// As [`SparseCholesky::solve_refined`]; also where a diagonal entry is
/// not positive (x given back holding b).
pub fn solve_by_diagonal(
    a: &CsrMatrix<f64>,
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Result<Refined, Refined> {
    let diagonal = diagonal(a);
    if diagonal.iter().any(|&d| d.is_nan() || d <= 0.0) {
        return Err(Refined {
            iterations: 0,
            backward_error: f64::INFINITY,
        });
    }
    refine(a, x, tolerance, max_iterations, |z| {
        for (z, d) in z.iter_mut().zip(&diagonal) {
            *z /= d;
        }
    })
}

/// [`SparseCholesky::solve_refined`] with the preconditioner `approx`,
/// which replaces z by an approximation of A⁻¹z (a single factor's solve).
pub(crate) fn refine(
    a: &CsrMatrix<f64>,
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
    mut approx: impl FnMut(&mut [f64]),
) -> Result<Refined, Refined> {
    let n = x.len();
    let b = x.to_vec();
    let (norm_a, norm_b) = (norm_inf(a), max_abs(&b));
    let eta = |r: &[f64], x: &[f64]| max_abs(r) / (norm_a * max_abs(x) + norm_b);
    if norm_b == 0.0 {
        x.fill(0.0);
        return Ok(Refined {
            iterations: 0,
            backward_error: 0.0,
        });
    }
    approx(x);
    let mut q = vec![0.0; n];
    let residual = |x: &[f64], q: &mut [f64], r: &mut [f64]| {
        spmv(a, x, q);
        for ((r, b), q) in r.iter_mut().zip(&b).zip(q.iter()) {
            *r = b - q;
        }
    };
    let mut r = vec![0.0; n];
    residual(x, &mut q, &mut r);
    let (mut z, mut p) = (vec![0.0; n], vec![0.0; n]);
    let (mut rz, mut fresh, mut true_residual) = (0.0, true, true);
    let (mut iterations, mut restarts) = (0, 0);
    loop {
        let mut backward_error = eta(&r, x);
        if backward_error <= tolerance && !true_residual {
            // The recurrence drifts from the true residual by the
            // rounding of its updates: confirm, or restart from it.
            residual(x, &mut q, &mut r);
            backward_error = eta(&r, x);
            fresh = true;
            restarts += usize::from(backward_error > tolerance);
        }
        let refined = Refined {
            iterations,
            backward_error,
        };
        if backward_error <= tolerance {
            return Ok(refined);
        }
        if iterations == max_iterations || restarts == MAX_RESTARTS || !backward_error.is_finite() {
            x.copy_from_slice(&b);
            return Err(refined);
        }
        z.copy_from_slice(&r);
        approx(&mut z);
        let rz_next = dot(&r, &z);
        if fresh {
            p.copy_from_slice(&z);
        } else {
            let beta = rz_next / rz;
            for (p, z) in p.iter_mut().zip(&z) {
                *p = z + beta * *p;
            }
        }
        rz = rz_next;
        spmv(a, &p, &mut q);
        let alpha = rz / dot(&p, &q);
        for ((x, r), (p, q)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&q)) {
            *x += alpha * p;
            *r -= alpha * q;
        }
        (true_residual, fresh) = (false, false);
        iterations += 1;
    }
}

/// The backward error ‖b − Ax‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞) of `x` as a solution
/// of A x = b, with which [`SparseCholesky::solve_refined`] stops.
pub fn backward_error(a: &CsrMatrix<f64>, x: &[f64], b: &[f64]) -> f64 {
    let mut r = vec![0.0; b.len()];
    spmv(a, x, &mut r);
    for (r, b) in r.iter_mut().zip(b) {
        *r = b - *r;
    }
    max_abs(&r) / (norm_inf(a) * max_abs(x) + max_abs(b))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::FillOrder;
    use nalgebra_sparse::CooMatrix;

    /// The 5-point Laplacian of an n×n grid (Dirichlet) plus `shift` I.
    pub(crate) fn grid(n: usize, shift: f64) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n * n, n * n);
        for i in 0..n {
            for j in 0..n {
                let p = i * n + j;
                coo.push(p, p, 4.0 + shift);
                if i + 1 < n {
                    coo.push(p, p + n, -1.0);
                    coo.push(p + n, p, -1.0);
                }
                if j + 1 < n {
                    coo.push(p, p + 1, -1.0);
                    coo.push(p + 1, p, -1.0);
                }
            }
        }
        CsrMatrix::from(&coo)
    }

    /// The grid's lowest mode, v_ij = sin(π(i+1)/(n+1)) sin(π(j+1)/(n+1)),
    /// and its eigenvalue shift + 8 sin²(π/(2(n+1))): A x = v is solved by
    /// v/λ.
    pub(crate) fn lowest_mode(n: usize, shift: f64) -> (Vec<f64>, f64) {
        let h = std::f64::consts::PI / (n + 1) as f64;
        let s = |i: usize| (h * (i + 1) as f64).sin();
        let v = (0..n * n).map(|p| s(p / n) * s(p % n)).collect();
        (v, shift + 8.0 * (0.5 * h).sin().powi(2))
    }

    fn refined(a: &CsrMatrix<f64>, b: &[f64]) -> (Vec<f64>, Result<Refined, Refined>) {
        let mut chol = SparseCholesky::analyze(a, &FillOrder::amd()).unwrap();
        chol.factorize_single(a).unwrap();
        let mut x = b.to_vec();
        let outcome = chol.solve_refined(a, &mut x, BACKWARD_ERROR);
        (x, outcome)
    }

    #[test]
    fn a_single_factor_refined_reaches_the_closed_form_to_double_accuracy() {
        // κ(A) = (shift + 8 cos²(π/(2(n+1))))/λ ≈ 1.8e4 (λ ≈ 4.4e-4): the
        // single factor alone is good to about κ u₃₂ ≈ 1e-3, a solve of
        // backward error 2u to about 2 κ · 2u ≈ 2e-11 (relative).
        let (n, shift) = (300, 1e-6);
        let a = grid(n, shift);
        let (v, lambda) = lowest_mode(n, shift);
        let (x, outcome) = refined(&a, &v);
        let outcome = outcome.expect("the refinement converges");
        assert!(outcome.backward_error <= BACKWARD_ERROR, "{outcome:?}");
        assert!(outcome.iterations <= 5, "{outcome:?}");
        let worst = x
            .iter()
            .zip(&v)
            .map(|(x, v)| (x - v / lambda).abs())
            .fold(0.0, f64::max);
        let scale = 1.0 / lambda; // max |v/λ| ≤ 1/λ
        assert!(worst <= 2e-11 * scale, "{worst:e} of {scale:e}");
        assert_eq!(outcome.backward_error, backward_error(&a, &x, &v));
    }

    #[test]
    fn a_refined_solve_has_the_same_bits_on_one_thread_and_on_four() {
        let a = grid(300, 1e-6);
        let (v, _) = lowest_mode(300, 1e-6);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| refined(&a, &v))
        };
        let ((one, r1), (four, r4)) = (on(1), on(4));
        assert_eq!(r1, r4);
        assert!(one
            .iter()
            .zip(&four)
            .all(|(x, y)| x.to_bits() == y.to_bits()));
    }

    #[test]
    fn a_tolerance_under_the_rounding_floor_gives_b_back() {
        let a = grid(20, 1.0);
        let (v, _) = lowest_mode(20, 1.0);
        let mut chol = SparseCholesky::analyze(&a, &FillOrder::amd()).unwrap();
        chol.factorize_single(&a).unwrap();
        let mut x = v.clone();
        // η of a computed residual cannot reach 1e-30 (u ≈ 1.1e-16).
        let outcome = chol.solve_refined(&a, &mut x, 1e-30).unwrap_err();
        assert!(outcome.iterations <= MAX_ITERATIONS);
        assert_eq!(x, v);
    }

    /// The consistent mass of n linear elements of length 1 on a line,
    /// both ends free: diagonal 2/6 at the ends, 4/6 inside, 1/6 beside.
    fn line_mass(n: usize) -> CsrMatrix<f64> {
        let mut coo = CooMatrix::new(n + 1, n + 1);
        for e in 0..n {
            for (i, j, v) in [(0, 0, 2.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 2.0)] {
                coo.push(e + i, e + j, v / 6.0);
            }
        }
        CsrMatrix::from(&coo)
    }

    #[test]
    fn a_consistent_mass_is_solved_on_its_diagonal_to_double_accuracy() {
        // Each element's D⁻¹M has eigenvalues 1/2 and 3/2, so κ(D⁻¹M) ≤ 3
        // and CG gains (√3 − 1)/(√3 + 1) ≈ 0.27 a step: about 28 steps to
        // 2u from 1, whatever n. ‖M⁻¹‖∞ ≤ 6 (rows diagonally dominant by
        // 1/6, Varah), so x is off the exact one by at most 6 times its
        // true residual against M x_exact: the stopping test's 2u · (‖M‖∞
        // ‖x‖∞ + ‖b‖∞) ≤ 2u · 6 = 12u, the computed residual's own
        // rounding (γ₃ · ‖M‖∞ ‖x‖∞ ≈ 9u) and b's (the same 9u): 6 · 30u =
        // 90ε at most; measured 4ε and 8ε.
        for n in [10, 10_000] {
            let m = line_mass(n);
            let exact: Vec<f64> = (0..=n).map(|i| (0.37 * i as f64).sin() + 2.0).collect();
            let mut b = vec![0.0; n + 1];
            spmv(&m, &exact, &mut b);
            let mut x = b.clone();
            let outcome = solve_by_diagonal(&m, &mut x, BACKWARD_ERROR, 40).expect("CG converges");
            assert!(outcome.backward_error <= BACKWARD_ERROR, "{outcome:?}");
            assert!(outcome.iterations <= 30, "{outcome:?}");
            let worst = x
                .iter()
                .zip(&exact)
                .map(|(x, e)| (x - e).abs())
                .fold(0.0, f64::max);
            assert!(worst <= 90.0 * f64::EPSILON, "{worst:e}");
        }
    }

    #[test]
    fn a_matrix_far_from_its_diagonal_gives_b_back() {
        // The grid's κ(D⁻¹A) ≈ 4e2: ten steps of CG on the diagonal do not
        // reach 2u from a b of many modes (its lowest mode alone, an
        // eigenvector of D⁻¹A here, would take one).
        let a = grid(30, 1e-6);
        let v: Vec<f64> = (0..900).map(|p| (0.37 * p as f64).sin() + 2.0).collect();
        let mut x = v.clone();
        let outcome = solve_by_diagonal(&a, &mut x, BACKWARD_ERROR, 10).unwrap_err();
        assert_eq!(outcome.iterations, 10);
        assert_eq!(x, v);
        // Nor a b with a NaN (it once passed for zero).
        let m = line_mass(10);
        let mut b = vec![0.0; 11];
        b[3] = f64::NAN;
        let mut x = b.clone();
        assert!(solve_by_diagonal(&m, &mut x, BACKWARD_ERROR, 10).is_err());
        assert!(x[3].is_nan() && x.iter().enumerate().all(|(i, v)| i == 3 || *v == 0.0));
        // Nor a diagonal entry that is not positive.
        let mut coo = CooMatrix::new(2, 2);
        coo.push(0, 0, 1.0);
        coo.push(1, 1, -1.0);
        let mut x = vec![1.0, 1.0];
        assert!(solve_by_diagonal(&CsrMatrix::from(&coo), &mut x, BACKWARD_ERROR, 10).is_err());
        assert_eq!(x, [1.0, 1.0]);
    }

    #[test]
    fn a_matrix_singular_in_single_precision_fails_there_and_factorizes_in_double() {
        // [[1, 1 − 2⁻³⁰], [1 − 2⁻³⁰, 1]]: determinant ≈ 2⁻²⁹ > 0, but
        // 1 − 2⁻³⁰ rounds to 1 in f32 (24-bit significand): singular.
        let off = 1.0 - 2.0_f64.powi(-30);
        let mut coo = CooMatrix::new(2, 2);
        for (i, j, v) in [(0, 0, 1.0), (0, 1, off), (1, 0, off), (1, 1, 1.0)] {
            coo.push(i, j, v);
        }
        let a = CsrMatrix::from(&coo);
        let mut chol = SparseCholesky::analyze(&a, &FillOrder::amd()).unwrap();
        assert!(matches!(
            chol.factorize_single(&a),
            Err(crate::SolverError::NotPositiveDefinite { .. })
        ));
        chol.factorize(&a).unwrap();
        // A (1, 1) = (1 + off)(1, 1): x = (1, 1)/(1 + off).
        let mut x = vec![1.0, 1.0];
        chol.solve_in_place(&mut x);
        for x in x {
            assert!((x - 1.0 / (1.0 + off)).abs() <= 1e-6, "{x}");
        }
    }
}
