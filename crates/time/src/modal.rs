//! The implicit step of small systems in the modes of (K, M) (issue 7: the
//! paper mesh's Newmark step).
//!
//! With Φ the M-orthonormal eigenvectors of K φ = λ M φ (ΦᵀMΦ = I,
//! ΦᵀKΦ = Λ, all n of them: no truncation, so nothing is approximated),
//! the state is held as modal coordinates r = Φ q, ṙ = Φ q̇, r̈ = Φ q̈ and
//! Newmark's step (METHOD.md §4) becomes diagonal:
//!
//! * R̂ = ΦᵀR − Λ q_pred + (cv q̇ + ca q̈): no product with K or M;
//! * A₀ = (β/γ)Δt Λ + I/(γΔt): its "factorization" per Δt is n
//!   reciprocals, its solve n multiplications;
//! * the friction acts on the contact tangential DOFs through
//!   Φ_c = P Φ (n_c × n, dense): p = Φ_c q̇₀, S = Φ_c A₀⁻¹ Φ_cᵀ and
//!   Z = A₀⁻¹ Φ_cᵀ, and the stick/slip iteration is `schur.rs`'s on S;
//! * the energies are ½Σq̇² and ½Σλq², and rᵀR = qᵀ(ΦᵀR).
//!
//! A step then costs O(n·n_c) against the sparse path's two products over
//! K and M, one triangular solve pair and two quadratic forms. The price is
//! Φ (n² values, formed once in O(n³)), and the physical state is formed
//! (r = Φ q, n² operations) only when it is read, so the path is taken for
//! small systems only ([`MODAL_MAX_DOFS`]). The modes are refined by a
//! Jacobi sweep ([`refine`]). The bits are not the sparse path's: the
//! Schur-path tests hold it to the direct path to 1e-10.

use std::cell::{Cell, OnceCell};

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par, Side};
use nalgebra_sparse::CsrMatrix;
use stickslip_contact::ContactNode;

/// Systems up to this many free DOFs take the modal step by default.
///
/// Set by the cost of reading the state, not by the step or by agreement.
/// A step costs O(n·n_c) at any n, but every output (or checkpoint) forms
/// r, ṙ, r̈ = Φ(q, q̇, q̈), 3n² operations over Φ's n² values. Up to 300
/// DOFs Φ (≤ 720 KB) stays in the 1 MB L2. Measured (release, 2000 steps,
/// best of five, reading the state after every step or not; the factor's
/// Schur step beside):
///
/// * the paper's Q2 8×2 slab (148 DOFs): 1.24 µs a step, 4.70 µs when
///   reading it every step, against 3.9 µs by the factor;
/// * the Q1 32×8 slab (552 DOFs, Φ 2.4 MB): 5.5 µs, but 59.6 µs when
///   reading every step, against 30.8 µs.
///
/// So with output at every step the paper mesh's modal run is 0.8 µs a
/// step slower than the factor's, and from every second step faster. The
/// agreement with the direct path holds on both (1e-12 a step,
/// `tests/schur.rs`, which runs the modal path on both).
pub const MODAL_MAX_DOFS: usize = 300;

/// The M-orthonormal modes of (K, M).
#[derive(Clone, Debug)]
pub(crate) struct Modes {
    n: usize,
    /// Φ column-major: column i is mode i.
    phi: Vec<f64>,
    /// λ_i = ω_i², ascending.
    lambda: Vec<f64>,
}

impl Modes {
    /// The modes of K φ = λ M φ (M symmetric positive definite): with
    /// M = L Lᵀ, C = L⁻¹ K L⁻ᵀ = Q Λ Qᵀ and Φ = L⁻ᵀ Q.
    ///
    /// # Errors
    /// A message when M is not positive definite or the eigensolver fails.
    pub fn new(stiffness: &CsrMatrix<f64>, mass: &CsrMatrix<f64>) -> Result<Modes, String> {
        let n = stiffness.nrows();
        let dense = |a: &CsrMatrix<f64>| {
            let mut m = Mat::<f64>::zeros(n, n);
            for (i, j, v) in a.triplet_iter() {
                m[(i, j)] = *v;
            }
            m
        };
        let m = dense(mass);
        let llt = m
            .llt(Side::Lower)
            .map_err(|e| format!("the mass matrix is not positive definite ({e:?})"))?;
        let l = llt.L();
        // X = L⁻¹K, then C = L⁻¹Xᵀ = L⁻¹KL⁻ᵀ (K symmetric).
        let mut x = dense(stiffness);
        solve_lower_triangular_in_place(l, x.as_mut(), Par::Seq);
        let mut c = x.transpose().to_owned();
        solve_lower_triangular_in_place(l, c.as_mut(), Par::Seq);
        // Symmetric in exact arithmetic: make it so for the eigensolver.
        for j in 0..n {
            for i in j + 1..n {
                let s = 0.5 * (c[(i, j)] + c[(j, i)]);
                c[(i, j)] = s;
                c[(j, i)] = s;
            }
        }
        let evd = c
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| format!("the eigensolver did not converge ({e:?})"))?;
        let lambda: Vec<f64> = (0..n).map(|i| evd.S()[i]).collect();
        let mut phi = evd.U().to_owned();
        solve_upper_triangular_in_place(l.transpose(), phi.as_mut(), Par::Seq);
        let (phi, lambda) = refine(stiffness, phi, lambda);
        let phi = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .map(|(i, j)| phi[(i, j)])
            .collect();
        Ok(Modes { n, phi, lambda })
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// λ_i = ω_i².
    pub fn lambda(&self) -> &[f64] {
        &self.lambda
    }

    /// Values held (Φ and λ).
    pub fn len(&self) -> usize {
        self.phi.len() + self.lambda.len()
    }

    /// out = Φᵀ y (y = M x gives x's modal coordinates; y = R its modal
    /// load).
    pub fn project(&self, y: &[f64], out: &mut [f64]) {
        for (o, col) in out.iter_mut().zip(self.phi.chunks_exact(self.n)) {
            *o = dot4(col, y);
        }
    }

    /// out_k = Φ q_k for K vectors in one pass over Φ (a column read
    /// once for all of them), 8 wide where the CPU has AVX-512 (the same
    /// operations per entry, so the same bits).
    #[allow(unsafe_code)]
    pub fn expand<const K: usize>(&self, q: [&[f64]; K], out: [&mut [f64]; K]) {
        #[cfg(target_arch = "x86_64")]
        if crate::kernels::avx512() {
            // SAFETY: the CPU has AVX-512 (checked).
            return unsafe { expand_avx512(self.n, &self.phi, q, out) };
        }
        expand_body(self.n, &self.phi, q, out);
    }

    /// Φ_c = P Φ by rows (node j's row: Σ_d t_d Φ[dof_d, ·]), n_c × n.
    pub fn tangential_rows(&self, nodes: &[ContactNode]) -> Vec<f64> {
        let n = self.n;
        let mut rows = vec![0.0; nodes.len() * n];
        for (row, node) in rows.chunks_exact_mut(n).zip(nodes) {
            for (k, col) in row.iter_mut().zip(self.phi.chunks_exact(n)) {
                *k = node.tangential(col);
            }
        }
        rows
    }
}

/// Jacobi sweeps at most in [`refine`] (one sufficed on the slabs).
const MAX_SWEEPS: usize = 10;

/// Refines M-orthonormal modes Φ by Jacobi rotations on ΦᵀKΦ (nearly
/// diagonal: each sweep squares the off-diagonal part), until every
/// off-diagonal entry is below 1e-15 of the smaller of its two diagonal
/// ones; rotations keep ΦᵀMΦ = I.
///
/// The dense eigensolver's low modes are its weak part: on the Q1 32×8
/// slab (552 DOFs, λ_max/λ_min = 2.6e4) max |(ΦᵀKΦ − Λ)_ij| / min(λ_i, λ_j)
/// was 3.6e-9 (1.4e-12 on the paper's 148 DOFs), and a modal step from
/// the direct path's state differed from it by 1.3e-9 in ṙ, for ε = 1e-4,
/// 1e-2 and 1 alike. One sweep (24,671 rotations there, 0.1 s) brings that
/// to 2.0e-12 (9.2e-13 on the paper mesh); a second finds nothing to do.
fn refine(
    stiffness: &CsrMatrix<f64>,
    mut phi: Mat<f64>,
    mut lambda: Vec<f64>,
) -> (Mat<f64>, Vec<f64>) {
    let n = phi.nrows();
    let mut kphi = Mat::<f64>::zeros(n, n);
    for (i, row) in stiffness.row_iter().enumerate() {
        for (&k, v) in row.col_indices().iter().zip(row.values()) {
            for j in 0..n {
                kphi[(i, j)] += v * phi[(k, j)];
            }
        }
    }
    let mut a = phi.transpose() * &kphi;
    drop(kphi);
    for _ in 0..MAX_SWEEPS {
        let mut rotated = 0usize;
        for p in 0..n {
            for q in p + 1..n {
                let apq = 0.5 * (a[(p, q)] + a[(q, p)]);
                let (app, aqq) = (a[(p, p)], a[(q, q)]);
                if apq.abs() <= 1e-15 * app.abs().min(aqq.abs()) {
                    continue;
                }
                rotated += 1;
                let theta = (aqq - app) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[(k, p)], a[(k, q)]);
                    a[(k, p)] = c * akp - s * akq;
                    a[(k, q)] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[(p, k)], a[(q, k)]);
                    a[(p, k)] = c * apk - s * aqk;
                    a[(q, k)] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (xp, xq) = (phi[(k, p)], phi[(k, q)]);
                    phi[(k, p)] = c * xp - s * xq;
                    phi[(k, q)] = s * xp + c * xq;
                }
            }
        }
        if rotated == 0 {
            break;
        }
    }
    for (i, l) in lambda.iter_mut().enumerate() {
        *l = a[(i, i)];
    }
    (phi, lambda)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
fn expand_avx512<const K: usize>(n: usize, phi: &[f64], q: [&[f64]; K], out: [&mut [f64]; K]) {
    expand_body(n, phi, q, out);
}

#[inline(always)]
fn expand_body<const K: usize>(n: usize, phi: &[f64], q: [&[f64]; K], out: [&mut [f64]; K]) {
    // Rows in blocks held in registers over all columns (K·32 sums), so a
    // column's block is loaded once for the K vectors and nothing else is
    // stored until the block is done: by columns, each pass loaded and
    // stored the outputs (5.9 µs for three on the paper mesh).
    let q = q.map(|q| &q[..n]);
    let mut out = out.map(|o| &mut o[..n]);
    let mut r0 = 0;
    while r0 + 32 <= n {
        let sums = expand_rows::<K, 32>(n, phi, &q, r0);
        for (o, s) in out.iter_mut().zip(&sums) {
            o[r0..r0 + 32].copy_from_slice(s);
        }
        r0 += 32;
    }
    while r0 + 8 <= n {
        let sums = expand_rows::<K, 8>(n, phi, &q, r0);
        for (o, s) in out.iter_mut().zip(&sums) {
            o[r0..r0 + 8].copy_from_slice(s);
        }
        r0 += 8;
    }
    while r0 < n {
        let sums = expand_rows::<K, 1>(n, phi, &q, r0);
        for (o, s) in out.iter_mut().zip(&sums) {
            o[r0] = s[0];
        }
        r0 += 1;
    }
}

/// Rows r0..r0 + W of Φ q_k for each k: Σ_i q_k[i] Φ[r, i] in order of i.
#[inline(always)]
fn expand_rows<const K: usize, const W: usize>(
    n: usize,
    phi: &[f64],
    q: &[&[f64]; K],
    r0: usize,
) -> [[f64; W]; K] {
    let mut acc = [[0.0; W]; K];
    for (i, col) in phi.chunks_exact(n).enumerate() {
        let block: &[f64; W] = col[r0..r0 + W].try_into().expect("W rows");
        for (a, q) in acc.iter_mut().zip(q) {
            let qi = q[i];
            for j in 0..W {
                a[j] += qi * block[j];
            }
        }
    }
    acc
}

/// Σ a_i b_i in four interleaved partial sums.
pub(crate) fn dot4(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0; 4];
    let split = n & !3;
    for (x, y) in a[..split].chunks_exact(4).zip(b[..split].chunks_exact(4)) {
        for l in 0..4 {
            s[l] += x[l] * y[l];
        }
    }
    for k in split..n {
        s[k - split] += a[k] * b[k];
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// The modal state's companions in the integrator: the modes, the loads in
/// modal coordinates and the physical state, formed when read.
pub(crate) struct ModalState {
    pub modes: Modes,
    /// Φᵀ of the constant load and of each load's vector.
    pub constant_load: Vec<f64>,
    pub loads: Vec<Vec<f64>>,
    /// Tangential velocity of each contact node in the current state and
    /// in the step being taken (P ṙ = Φ_c q̇ at the end of the step).
    pub contact_v: Vec<f64>,
    pub contact_v_new: Vec<f64>,
    /// r, ṙ, r̈ formed together from q, q̇, q̈ at the first read of any
    /// since the step (one pass over Φ), in buffers kept across steps
    /// (`spare`): no allocation after the first read.
    physical: OnceCell<[Vec<f64>; 3]>,
    spare: Cell<[Vec<f64>; 3]>,
}

impl std::fmt::Debug for ModalState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModalState")
            .field("n", &self.modes.n())
            .field("contact_nodes", &self.contact_v.len())
            .finish_non_exhaustive()
    }
}

impl ModalState {
    pub fn new(modes: Modes, nodes: &[ContactNode]) -> ModalState {
        let n = modes.n();
        ModalState {
            constant_load: vec![0.0; n],
            loads: Vec::new(),
            contact_v: vec![0.0; nodes.len()],
            contact_v_new: vec![0.0; nodes.len()],
            physical: Default::default(),
            spare: Cell::new(std::array::from_fn(|_| vec![0.0; n])),
            modes,
        }
    }

    /// Forgets the physical state formed from the last state (the step
    /// changed it), keeping its buffers.
    pub fn invalidate(&mut self) {
        if let Some(v) = self.physical.take() {
            self.spare.set(v);
        }
    }

    /// The physical vector `which` (0: r, 1: ṙ, 2: r̈) of the modal
    /// coordinates `q` = [q, q̇, q̈] (the integrator's current ones).
    pub fn physical(&self, which: usize, q: [&[f64]; 3]) -> &[f64] {
        &self.physical.get_or_init(|| {
            let mut out = self.spare.take();
            for o in out.iter_mut() {
                o.resize(self.modes.n(), 0.0);
            }
            let [r, v, a] = &mut out;
            self.modes.expand(q, [r, v, a]);
            out
        })[which]
    }
}

/// The step's first pass in the modes: r_pred = r + c1 q̇ + c2 q̈ into
/// `r_new`, cv q̇ + ca q̈ into `tmp` and R̂ = l − λ r_pred + tmp into `b`
/// (METHOD.md §4 with K = Λ, M = I), 8 wide where the CPU has AVX-512 (the
/// same operations per entry, so the same bits).
#[allow(unsafe_code)]
pub(crate) fn predict(
    [c1, c2, cv, ca]: [f64; 4],
    [lambda, r, v, a, l]: [&[f64]; 5],
    [r_new, tmp, b]: [&mut [f64]; 3],
) {
    #[cfg(target_arch = "x86_64")]
    if crate::kernels::avx512() {
        // SAFETY: the CPU has AVX-512 (checked).
        return unsafe { predict_avx512([c1, c2, cv, ca], [lambda, r, v, a, l], [r_new, tmp, b]) };
    }
    predict_body([c1, c2, cv, ca], [lambda, r, v, a, l], [r_new, tmp, b]);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
fn predict_avx512(c: [f64; 4], x: [&[f64]; 5], out: [&mut [f64]; 3]) {
    predict_body(c, x, out);
}

#[inline(always)]
fn predict_body(
    [c1, c2, cv, ca]: [f64; 4],
    [lambda, r, v, a, l]: [&[f64]; 5],
    [r_new, tmp, b]: [&mut [f64]; 3],
) {
    let n = r.len();
    let (lambda, v, a, l) = (&lambda[..n], &v[..n], &a[..n], &l[..n]);
    let (r_new, tmp, b) = (&mut r_new[..n], &mut tmp[..n], &mut b[..n]);
    for k in 0..n {
        let rn = r[k] + c1 * v[k] + c2 * a[k];
        let t = cv * v[k] + ca * a[k];
        r_new[k] = rn;
        tmp[k] = t;
        b[k] = l[k] - lambda[k] * rn + t;
    }
}

/// The step's last pass in the modes: the corrector r_K = r_pred + c3 q̇_K
/// (in `r_new`), q̈_K = (q̇_K − q̇) cv − ka q̈ (into `a_new`), whether
/// r_K and q̇_K are finite, and the sums [Σ ½(l_K + l)(r_K − r), r_K·l_K,
/// q̇_K·q̇_K, r_K·Λ r_K] (the work of the step, rᵀR, twice the kinetic and
/// the strain energy), each in eight partial sums; 8 wide where the CPU
/// has AVX-512.
#[allow(unsafe_code)]
pub(crate) fn close(
    c: [f64; 3],
    x: [&[f64]; 7],
    r_new: &mut [f64],
    a_new: &mut [f64],
) -> (bool, [f64; 4]) {
    #[cfg(target_arch = "x86_64")]
    if crate::kernels::avx512() {
        // SAFETY: the CPU has AVX-512 (checked).
        return unsafe { close_avx512(c, x, r_new, a_new) };
    }
    close_body(c, x, r_new, a_new)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
fn close_avx512(
    c: [f64; 3],
    x: [&[f64]; 7],
    r_new: &mut [f64],
    a_new: &mut [f64],
) -> (bool, [f64; 4]) {
    close_body(c, x, r_new, a_new)
}

#[inline(always)]
fn close_body(
    [c3, cv, ka]: [f64; 3],
    [lambda, r, v, a, v_new, l, l_new]: [&[f64]; 7],
    r_new: &mut [f64],
    a_new: &mut [f64],
) -> (bool, [f64; 4]) {
    let n = r.len();
    let (lambda, v, a, v_new) = (&lambda[..n], &v[..n], &a[..n], &v_new[..n]);
    let (l, l_new, r_new, a_new) = (&l[..n], &l_new[..n], &mut r_new[..n], &mut a_new[..n]);
    let mut finite = true;
    let mut check = [0.0; 8];
    let mut sums = [[0.0; 8]; 4];
    let whole = n / 8 * 8;
    // Rows k0..k0 + 8 in lanes 0..8 (whole groups), then the rest in
    // lanes 0.., the same arithmetic per row.
    for (k0, width) in (0..whole)
        .step_by(8)
        .map(|k0| (k0, 8))
        .chain((whole < n).then_some((whole, n - whole)))
    {
        if width == 8 {
            let s8 = |x: &[f64]| -> [f64; 8] { x[k0..k0 + 8].try_into().expect("8") };
            let (lm, r, v, a, vn, l, ln) =
                (s8(lambda), s8(r), s8(v), s8(a), s8(v_new), s8(l), s8(l_new));
            let rn0 = s8(r_new);
            let mut rn = [0.0; 8];
            let mut an = [0.0; 8];
            for j in 0..8 {
                rn[j] = rn0[j] + c3 * vn[j];
                // x − x is 0 for a finite x, NaN otherwise (IEEE: not
                // folded to 0): a sum, where a flag per lane kept the loop
                // from running 8 wide (0·x instead: 1.22 → 1.41 µs a step).
                #[allow(clippy::eq_op)]
                let c = (rn[j] - rn[j]) + (vn[j] - vn[j]);
                check[j] += c;
                an[j] = (vn[j] - v[j]) * cv - ka * a[j];
                sums[0][j] += 0.5 * (ln[j] + l[j]) * (rn[j] - r[j]);
                sums[1][j] += rn[j] * ln[j];
                sums[2][j] += vn[j] * vn[j];
                sums[3][j] += lm[j] * rn[j] * rn[j];
            }
            r_new[k0..k0 + 8].copy_from_slice(&rn);
            a_new[k0..k0 + 8].copy_from_slice(&an);
        } else {
            for j in 0..width {
                let k = k0 + j;
                let rn = r_new[k] + c3 * v_new[k];
                r_new[k] = rn;
                finite &= rn.is_finite() & v_new[k].is_finite();
                a_new[k] = (v_new[k] - v[k]) * cv - ka * a[k];
                sums[0][j] += 0.5 * (l_new[k] + l[k]) * (rn - r[k]);
                sums[1][j] += rn * l_new[k];
                sums[2][j] += v_new[k] * v_new[k];
                sums[3][j] += lambda[k] * rn * rn;
            }
        }
    }
    finite &= check.iter().all(|&x| x == 0.0);
    let total = |s: [f64; 8]| ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
    (finite, sums.map(total))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    /// A spring chain with a consistent-like tridiagonal mass.
    fn chain(n: usize) -> (CsrMatrix<f64>, CsrMatrix<f64>) {
        let mut k = CooMatrix::new(n, n);
        let mut m = CooMatrix::new(n, n);
        for i in 0..n {
            k.push(i, i, 2.0 + i as f64 * 0.1);
            m.push(i, i, 4.0 + (i % 3) as f64);
            if i + 1 < n {
                k.push(i, i + 1, -1.0);
                k.push(i + 1, i, -1.0);
                m.push(i, i + 1, 1.0);
                m.push(i + 1, i, 1.0);
            }
        }
        (CsrMatrix::from(&k), CsrMatrix::from(&m))
    }

    /// ΦᵀMΦ = I and ΦᵀKΦ = Λ to round-off, and project ∘ (M·) ∘ expand is
    /// the identity.
    #[test]
    fn modes_diagonalize_k_and_m() {
        let n = 37;
        let (k, m) = chain(n);
        let modes = Modes::new(&k, &m).unwrap();
        let col = |j: usize| &modes.phi[j * n..(j + 1) * n];
        let apply = |a: &CsrMatrix<f64>, x: &[f64]| -> Vec<f64> {
            let mut y = vec![0.0; n];
            for (i, j, v) in a.triplet_iter() {
                y[i] += v * x[j];
            }
            y
        };
        for i in 0..n {
            let (ki, mi) = (apply(&k, col(i)), apply(&m, col(i)));
            for j in 0..n {
                let (kij, mij) = (dot4(col(j), &ki), dot4(col(j), &mi));
                let want_m = if i == j { 1.0 } else { 0.0 };
                let want_k = if i == j { modes.lambda[i] } else { 0.0 };
                assert!((mij - want_m).abs() < 1e-13, "M ({i},{j}) = {mij}");
                assert!(
                    (kij - want_k).abs() < 1e-13 * modes.lambda[n - 1],
                    "K ({i},{j}) = {kij}"
                );
            }
        }
        let q: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut x = vec![0.0; n];
        modes.expand([&q], [&mut x]);
        let mut back = vec![0.0; n];
        modes.project(&apply(&m, &x), &mut back);
        for i in 0..n {
            assert!((back[i] - q[i]).abs() < 1e-13, "mode {i}");
        }
    }

    /// The step's two passes: the dispatched kernel (AVX-512 where the CPU
    /// has it) has the scalar body's bits, and both are the plain formulas
    /// (within rounding for the sums), for lengths around the 8-row groups.
    #[test]
    fn passes_match_the_plain_formulas() {
        for n in [1, 7, 8, 9, 148, 150] {
            let x = |s: f64| -> Vec<f64> { (0..n).map(|i| (s * (i as f64 + 1.0)).sin()).collect() };
            let (lambda, r, v, a, l) = (
                x(0.3).iter().map(|y| 10.0 + y).collect::<Vec<_>>(),
                x(0.7),
                x(1.1),
                x(1.3),
                x(1.7),
            );
            let c = [0.1, 0.02, 3.0, 0.5];
            let mut fast = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
            let mut plain = fast.clone();
            {
                let [a0, a1, a2] = &mut fast;
                predict(c, [&lambda, &r, &v, &a, &l], [a0, a1, a2]);
                let [b0, b1, b2] = &mut plain;
                predict_body(c, [&lambda, &r, &v, &a, &l], [b0, b1, b2]);
            }
            assert_eq!(fast, plain, "n = {n}: predict's bits");
            for k in 0..n {
                let rn = r[k] + c[0] * v[k] + c[1] * a[k];
                let t = c[2] * v[k] + c[3] * a[k];
                assert_eq!(fast[0][k], rn);
                assert_eq!(fast[1][k], t);
                assert_eq!(fast[2][k], l[k] - lambda[k] * rn + t);
            }
            let (vn, ln) = (x(2.3), x(2.9));
            let c = [0.25, 4.0, 0.5];
            let inputs = [&lambda[..], &r, &v, &a, &vn, &l, &ln];
            let (mut rn_fast, mut an_fast) = (fast[0].clone(), vec![0.0; n]);
            let (mut rn_plain, mut an_plain) = (fast[0].clone(), vec![0.0; n]);
            let got = close(c, inputs, &mut rn_fast, &mut an_fast);
            let want = close_body(c, inputs, &mut rn_plain, &mut an_plain);
            assert_eq!(got, want, "n = {n}: close's bits");
            assert_eq!((rn_fast.clone(), an_fast.clone()), (rn_plain, an_plain));
            let mut sums = [0.0; 4];
            for k in 0..n {
                let rn = fast[0][k] + c[0] * vn[k];
                assert_eq!(rn_fast[k], rn);
                assert_eq!(an_fast[k], (vn[k] - v[k]) * c[1] - c[2] * a[k]);
                sums[0] += 0.5 * (ln[k] + l[k]) * (rn - r[k]);
                sums[1] += rn * ln[k];
                sums[2] += vn[k] * vn[k];
                sums[3] += lambda[k] * rn * rn;
            }
            assert!(got.0, "finite");
            for (g, w) in got.1.iter().zip(sums) {
                assert!(
                    (g - w).abs() <= 1e-12 * (1.0 + w.abs()),
                    "n = {n}: {g} against {w}"
                );
            }
            // A non-finite velocity is reported.
            let mut bad = vn.clone();
            bad[n - 1] = f64::NAN;
            let inputs = [&lambda[..], &r, &v, &a, &bad, &l, &ln];
            assert!(!close(c, inputs, &mut fast[0].clone(), &mut vec![0.0; n]).0);
        }
    }

    /// Φq for three vectors at once: the dispatched kernel has the scalar
    /// body's bits, each vector the bits of its own expansion, and the
    /// plain sum to rounding, for n around the 32- and 8-row blocks.
    #[test]
    fn expand_matches_the_plain_product() {
        for n in [1, 8, 9, 33, 47, 148] {
            let phi: Vec<f64> = (0..n * n)
                .map(|i| ((i * 37) % 101) as f64 / 7.0 - 6.0)
                .collect();
            let modes = Modes {
                n,
                phi: phi.clone(),
                lambda: vec![1.0; n],
            };
            let q: [Vec<f64>; 3] = std::array::from_fn(|k| {
                (0..n)
                    .map(|i| ((k + 1) as f64 * i as f64 * 0.3).cos())
                    .collect()
            });
            let [mut a, mut b, mut c] = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
            modes.expand([&q[0], &q[1], &q[2]], [&mut a, &mut b, &mut c]);
            let [mut a2, mut b2, mut c2] = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
            expand_body(n, &phi, [&q[0], &q[1], &q[2]], [&mut a2, &mut b2, &mut c2]);
            assert_eq!([&a, &b, &c], [&a2, &b2, &c2], "n = {n}: the body's bits");
            for (k, out) in [&a, &b, &c].into_iter().enumerate() {
                let mut one = vec![0.0; n];
                modes.expand([&q[k]], [&mut one]);
                assert_eq!(&one, out, "n = {n}: vector {k} alone");
                for r in 0..n {
                    let want: f64 = (0..n).map(|i| q[k][i] * phi[i * n + r]).sum();
                    assert!((out[r] - want).abs() < 1e-10, "n = {n}, row {r}");
                }
            }
        }
    }

    #[test]
    fn dot4_matches_the_plain_sum() {
        for n in 0..11 {
            let a: Vec<f64> = (0..n).map(|i| i as f64 + 0.5).collect();
            let b: Vec<f64> = (0..n).map(|i| 1.0 / (i as f64 + 1.0)).collect();
            let plain: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            assert!((dot4(&a, &b) - plain).abs() < 1e-12);
        }
    }
}
