//! Remark 4.1's static preload of a floating part: K r₀ = R(0⁻) when the
//! supports leave rigid motions Z free (K Z = 0). The problem has a
//! solution only if the loads do no work along them (Zᵀ R = 0: no net
//! force along a free translation, no moment about a free rotation's
//! centre), and then one up to a rigid motion: the one with no mean rigid
//! motion, Zᵀ M r₀ = 0, is taken.
//!
//! The solve pins one DOF per free motion (chosen by complete pivoting on
//! Z, so that Z restricted to the pins is well conditioned), which leaves
//! K definite on the rest; with balanced loads the pins carry no reaction
//! (their reactions ρ satisfy Z_Pᵀ ρ = Zᵀ(K x − R) = 0 and Z_P is
//! invertible), so x solves K x = R, and r₀ = x − Z (ZᵀMZ)⁻¹ ZᵀM x.

use nalgebra_sparse::CsrMatrix;
use stickslip_fem::{RigidMode, SetupTimes};
use stickslip_linalg::FillOrder;

use crate::initial::Mass;
use crate::settings::{TimeError, UnbalancedMotion};

/// Loads whose work along a free motion is below this fraction of the sum
/// of its terms' magnitudes are in equilibrium (round-off of the load
/// vectors' quadrature).
pub(crate) const BALANCE_TOLERANCE: f64 = 1e-9;

/// r₀ in place of the loads `r` (see the module's comment).
///
/// # Errors
/// [`TimeError::Unbalanced`] naming each free motion the loads do work
/// along, [`TimeError::Static`] when K is singular beyond the free
/// motions (a mechanism).
pub(crate) fn solve(
    k: &CsrMatrix<f64>,
    mass: Mass,
    fill_order: &FillOrder,
    modes: &[RigidMode],
    r: &mut [f64],
    times: &mut SetupTimes,
) -> Result<(), TimeError> {
    balanced(modes, r)?;
    let pins = pins(modes);
    let mut pinned = k.clone();
    pin(&mut pinned, &pins);
    for &i in &pins {
        r[i] = 0.0;
    }
    crate::initial::cholesky_solve(&pinned, fill_order, r, times)?;
    remove_rigid_motion(mass, modes, r);
    Ok(())
}

/// Decouples the DOFs `pins` (ascending) from the others in `k`: their
/// rows and columns keep only the diagonal.
pub(crate) fn pin(k: &mut CsrMatrix<f64>, pins: &[usize]) {
    let (offsets, cols, values) = k.csr_data_mut();
    let is_pin = |i: usize| pins.binary_search(&i).is_ok();
    for i in 0..offsets.len() - 1 {
        for p in offsets[i]..offsets[i + 1] {
            if (is_pin(i) || is_pin(cols[p])) && cols[p] != i {
                values[p] = 0.0;
            }
        }
    }
}

/// The work of loads `r` along the motion `z`, and Σ|z_i r_i| (its size
/// had every term one sign).
pub(crate) fn work_along(z: &[f64], r: &[f64]) -> (f64, f64) {
    z.iter()
        .zip(r)
        .fold((0.0, 0.0), |(w, s), (z, f)| (w + z * f, s + (z * f).abs()))
}

/// True where `work` is more than round-off of terms of `size`.
pub(crate) fn does_work(work: f64, size: f64) -> bool {
    work.abs() > BALANCE_TOLERANCE * size
}

/// Loads `r` that do no work along any of `modes`.
///
/// # Errors
/// [`TimeError::Unbalanced`] naming each motion they do work along.
pub(crate) fn balanced(modes: &[RigidMode], r: &[f64]) -> Result<(), TimeError> {
    let unbalanced: Vec<UnbalancedMotion> = modes
        .iter()
        .filter_map(|m| {
            let (work, size) = work_along(&m.vector, r);
            does_work(work, size).then(|| UnbalancedMotion {
                label: m.label.clone(),
                motion: m.motion,
                work,
            })
        })
        .collect();
    if !unbalanced.is_empty() {
        return Err(TimeError::Unbalanced(unbalanced));
    }
    Ok(())
}

/// One DOF per mode by complete pivoting on the modes' columns: the
/// largest entry of what is left of them, then that entry eliminated from
/// the others. Ascending.
pub(crate) fn pins(modes: &[RigidMode]) -> Vec<usize> {
    let mut left: Vec<Vec<f64>> = modes.iter().map(|m| m.vector.clone()).collect();
    let mut done = vec![false; left.len()];
    let mut pins = Vec::with_capacity(left.len());
    for _ in 0..left.len() {
        let mut best = (0.0, 0, 0);
        for (j, z) in left.iter().enumerate().filter(|(j, _)| !done[*j]) {
            for (i, &x) in z.iter().enumerate() {
                if x.abs() > best.0 {
                    best = (x.abs(), j, i);
                }
            }
        }
        let (_, j, i) = best;
        done[j] = true;
        pins.push(i);
        let pivot = left[j].clone();
        for (z, _) in left.iter_mut().zip(&done).filter(|(_, d)| !**d) {
            let f = z[i] / pivot[i];
            for (x, p) in z.iter_mut().zip(&pivot) {
                *x -= f * p;
            }
        }
    }
    pins.sort_unstable();
    pins
}

/// r ← r − Z (ZᵀMZ)⁻¹ ZᵀM r: no mean rigid motion left in r.
pub(crate) fn remove_rigid_motion(mass: Mass, modes: &[RigidMode], r: &mut [f64]) {
    let n = modes.len();
    let mz: Vec<Vec<f64>> = modes
        .iter()
        .map(|m| {
            let mut out = vec![0.0; r.len()];
            mass.apply(&m.vector, &mut out);
            out
        })
        .collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    // (ZᵀMZ) c = ZᵀM r, ZᵀMZ symmetric positive definite (the modes are
    // independent): no zero pivot. NaNs where one were met, as the
    // elimination's division by it gave.
    let a: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| dot(&mz[i], &modes[j].vector)).collect())
        .collect();
    let b = (0..n).map(|i| dot(&mz[i], r)).collect();
    let c = solve_small(a, b).unwrap_or_else(|| vec![f64::NAN; n]);
    for (m, cj) in modes.iter().zip(&c) {
        for (x, z) in r.iter_mut().zip(&m.vector) {
            *x -= cj * z;
        }
    }
}

/// x of the small square system A x = b by Gaussian elimination with
/// partial pivoting; `None` where A is singular (a zero pivot) or a result
/// is not finite.
pub(crate) fn solve_small(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let p = (col..n).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        a.swap(col, p);
        b.swap(col, p);
        if a[col][col] == 0.0 {
            return None;
        }
        for row in col + 1..n {
            let f = a[row][col] / a[col][col];
            for c in col..n {
                a[row][c] -= f * a[col][c];
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|j| a[row][j] * x[j]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|x| x.is_finite()).then_some(x)
}
