//! A x = b to double precision's accuracy with a factor computed in
//! single precision: conjugate gradients preconditioned by that factor.
//!
//! A factorization that serves one solve (the explicit run's static
//! preload) costs most of that solve; in f32 it moves half the bytes and
//! its dense kernels fit twice the values in a vector register. Its
//! factor L̃L̃ᵀ = A + E, with ‖E‖ of order u₃₂‖A‖ times a growth factor,
//! is positive definite (faer refuses a pivot ≤ 0), so it preconditions
//! CG, whose iterates then gain about the factor's relative accuracy
//! (u₃₂ κ(A)) a step; the products with A and the sums are in f64, so
//! the solution reaches what a double factorization's solve reaches. The
//! stopping test is that solve's accuracy, measured as the normwise
//! backward error η = ‖b − Ax‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞) (Rigal and Gaches):
//! the smallest relative change of A and b that x solves exactly, which a
//! backward-stable Cholesky solve keeps to a small multiple of u₆₄.

use nalgebra_sparse::CsrMatrix;

use crate::csr::{dot, spmv};
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

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
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
        refine(a, x, tolerance, |z| self.solve_single_in_place(z))
    }
}

/// [`SparseCholesky::solve_refined`] with the preconditioner `approx`,
/// which replaces z by an approximation of A⁻¹z (a single factor's solve).
pub(crate) fn refine(
    a: &CsrMatrix<f64>,
    x: &mut [f64],
    tolerance: f64,
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
        if iterations == MAX_ITERATIONS || restarts == MAX_RESTARTS || !backward_error.is_finite() {
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
