//! A compliant foundation in the implicit step (METHOD.md §10 with §4-5):
//! the normal and friction forces of its nodes solved together with the
//! step's velocity, on the Schur complement's nodal unknowns.
//!
//! In the velocity form r_K = r_pred + (β/γ)Δt ṙ_K, so node J's approach
//! δ_J = max(0, −(g₀ + ν·r_pred) − (β/γ)Δt u_N,J) is a function of its
//! normal velocity u_N = ν·ṙ_J alone. The Schur path's P gains a row ν_J
//! per compliant node (`schur.rs`), and with x = (u_T, u_N) the step's
//! nodal system is
//!
//! ```text
//! R(x) = x + S f(x) − p = 0,
//! ```
//!
//! f_N,J = −w_J c_n δ_J^{m_n} (the foundation pushes along +ν; f enters as
//! −Pᵀf) and f_T,J the friction of the node's class with the bound
//! g_J = c_T δ_J^{m_T} of the iterate's approach: w g (u_T − V)/ε stuck,
//! w g sign slipping. The classes are those of the stick/slip iteration of
//! §5 with Remark 4.2 ([`stickslip_contact::iterate`], unchanged): for
//! given classes this module solves R(x) = 0 by Newton's method with an
//! Armijo backtracking line search on ½|R|².
//!
//! Why it converges: f_N is monotone in u_N (df_N/du_N = w c_n m_n
//! δ^{m_n−1}(β/γ)Δt ≥ 0), a stuck node's f_T monotone in u_T, so the
//! derivative D = Df is block-diagonal with a non-negative diagonal, and
//! without friction's coupling (frictionless, or pressure-law nodes) it is
//! the Hessian of the convex foundation energy: J = I + S D then has the
//! eigenvalues of I + D^{½}SD^{½} ≥ 1 (S symmetric positive semi-definite),
//! the Newton direction exists and is a descent direction of ½|R|² (its
//! slope there is −|R|²), and backtracking gives a monotone decrease to the
//! root, quadratic once the contact set settles (piecewise linear for
//! m_n = 1: exact in one step then). The bound's dependence on δ adds the
//! unsymmetric entry ∂f_T/∂u_N, bounded by the friction coefficient times
//! ∂f_N/∂u_N for a stuck node (|u_T − V| ≤ ε), a small perturbation for
//! c_T < c_n. Where Newton on the whole system fails nonetheless (J
//! singular, or the search stalled), the solve falls back to the authors'
//! successive approximation on the bounds: each pass a Newton solve of the
//! monotone system with the bounds of the last pass held fixed, until they
//! settle; if that fails too, the step stops with
//! [`TimeError::NormalSolve`] rather than return a wrong answer. A
//! plain successive approximation on the normal force (f from the last
//! iterate, then x = p − S f) is a contraction only while the spring's
//! stiffness times S stays below one, and oscillates or diverges beyond:
//! the tests show both.
//!
//! The normal force takes one of two forms ([`NormalForm`]): the law's at
//! the step's end, or Newmark ¼, ½'s energy-consistent one (`algorithmic.rs`),
//! f_N,J = −(w_J(σ(δ_J) + D_J) − e_J) with D the trapezoid's defect
//! against the step's starting approach and e the carried excess. Both
//! are monotone in u_N (D's divided difference of the convex stored energy
//! grows with either end), so the argument above holds for either; the
//! friction bound follows the physical approach δ_J in both.

use stickslip_contact::{ContactSurface, SlipState, StepSystem};
use stickslip_linalg::SolverError;

use super::schur::SchurOperator;
use crate::settings::TimeError;

/// Newton iterations allowed per solve for given classes.
const MAX_NEWTON: usize = 50;
/// Passes of the fallback's successive approximation on the bounds.
const MAX_PASSES: usize = 200;
/// Halvings of the step allowed per line search.
const MAX_HALVINGS: usize = 40;
/// The residual, relative to the system's scale, taken as converged.
const TOLERANCE: f64 = 1e-12;

/// How the compliant nodes' normal force enters the step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NormalForm {
    /// The law's force at the step's end, w σ(δ_K): what statics needs (K r
    /// + f(r) = R exactly) and every Newmark but ¼, ½.
    EndPoint,
    /// Newmark ¼, ½'s energy-consistent force w(σ(δ_K) + D) − e, from the
    /// signed approaches at the step's start and the excesses e carried
    /// ([`CompliantSolve::energy_consistent`]).
    EnergyConsistent,
}

/// Why a nodal solve failed.
#[derive(Debug)]
pub(crate) enum NormalFailure {
    /// Newton did not converge (cap or stalled search).
    Newton {
        iterations: usize,
        residual: f64,
        scale: f64,
    },
    /// The Newton matrix was singular (an exact zero pivot).
    Singular,
}

impl NormalFailure {
    /// The step's error.
    pub(crate) fn into_error(self, step: u64, t: f64) -> TimeError {
        match self {
            NormalFailure::Newton {
                iterations,
                residual,
                scale,
            } => TimeError::NormalSolve {
                step,
                t,
                iterations,
                residual,
                scale,
            },
            NormalFailure::Singular => TimeError::Solve {
                step,
                t,
                source: SolverError::Analysis(
                    "the normal-compliance Newton matrix is singular".into(),
                ),
            },
        }
    }
}

/// The compliant nodes' part of a step: the predictor's gaps, the nodal
/// unknowns and Newton's workspace, kept for the run.
pub(crate) struct CompliantSolve {
    /// (β/γ)Δt of this step: r_K = r_pred + c3 ṙ_K.
    c3: f64,
    /// g₀ + ν·r_pred per compliant node.
    gap: Vec<f64>,
    /// The compliant index of each contact node (`usize::MAX`: none).
    of_node: Vec<usize>,
    /// x = (u_T, u_N) of the last solve: the next one starts there.
    x: Vec<f64>,
    /// The forces at x and their derivatives per node:
    /// (∂f_T/∂u_T, ∂f_T/∂u_N, ∂f_N/∂u_N).
    f: Vec<f64>,
    slope: Vec<[f64; 3]>,
    residual: Vec<f64>,
    trial: Vec<f64>,
    trial_f: Vec<f64>,
    delta: Vec<f64>,
    jacobian: Vec<f64>,
    pivots: Vec<usize>,
    /// The fallback's bounds per compliant node, held fixed while `freeze`.
    frozen: Vec<f64>,
    freeze: bool,
    /// Where a solve started (the fallback starts there again).
    start: Vec<f64>,
    /// Newton iterations over the run.
    pub(crate) newton: u64,
    /// The normal force's form for this step.
    form: NormalForm,
    /// Energy-consistent: each compliant node's signed approach at the
    /// step's start, and its excess e carried from the last step.
    before: Vec<f64>,
    excess: Vec<f64>,
}

impl CompliantSolve {
    /// The workspace for `contact`'s compliant nodes.
    pub(crate) fn new(contact: &ContactSurface) -> CompliantSolve {
        let n_c = contact.len();
        let rows = n_c + contact.compliance.len();
        let mut of_node = vec![usize::MAX; n_c];
        for (k, c) in contact.compliance.iter().enumerate() {
            of_node[c.index] = k;
        }
        CompliantSolve {
            c3: 0.0,
            gap: vec![0.0; contact.compliance.len()],
            of_node,
            x: vec![0.0; rows],
            f: vec![0.0; rows],
            slope: vec![[0.0; 3]; n_c],
            residual: vec![0.0; rows],
            trial: vec![0.0; rows],
            trial_f: vec![0.0; rows],
            delta: vec![0.0; rows],
            jacobian: vec![0.0; rows * rows],
            pivots: vec![0; rows],
            frozen: vec![0.0; contact.compliance.len()],
            freeze: false,
            start: vec![0.0; rows],
            newton: 0,
            form: NormalForm::EndPoint,
            before: vec![0.0; contact.compliance.len()],
            excess: vec![0.0; contact.compliance.len()],
        }
    }

    /// Starts a step: the predictor `r_pred` and c3 = (β/γ)Δt give each
    /// node's approach as a function of its normal velocity; the unknowns
    /// start from the last step's velocity `v`.
    pub(crate) fn predict(&mut self, contact: &ContactSurface, r_pred: &[f64], v: &[f64], c3: f64) {
        self.c3 = c3;
        let n_c = contact.len();
        for (j, node) in contact.nodes.iter().enumerate() {
            self.x[j] = node.tangential(v);
        }
        for (k, c) in contact.compliance.iter().enumerate() {
            let node = &contact.nodes[c.index];
            let (mut gap, mut u_n) = (c.gap, 0.0);
            for comp in 0..2 {
                if let Some(d) = node.dofs[comp] {
                    gap += c.normal[comp] * r_pred[d];
                    u_n += c.normal[comp] * v[d];
                }
            }
            self.gap[k] = gap;
            self.x[n_c + k] = u_n;
        }
    }

    /// Makes this step's normal force `form`; energy-consistent, from the
    /// step's starting displacement `r` and the excesses `excess` per
    /// compliant node.
    pub(crate) fn set_form(
        &mut self,
        form: NormalForm,
        contact: &ContactSurface,
        (r, excess): (&[f64], &[f64]),
    ) {
        self.form = form;
        if form == NormalForm::EnergyConsistent {
            for (k, c) in contact.compliance.iter().enumerate() {
                self.before[k] = c.signed_approach(&contact.nodes[c.index], r);
            }
            self.excess.copy_from_slice(excess);
        }
    }

    /// The excess e_K = w D − e_{K−1} per compliant node at the converged
    /// x, into `out` (energy-consistent form).
    pub(crate) fn excess_after(&self, contact: &ContactSurface, out: &mut [f64]) {
        let n_c = contact.len();
        for (k, c) in contact.compliance.iter().enumerate() {
            let a = self.signed_approach(k, &self.x, n_c);
            let (defect, _) = c.law.energy_consistent(self.before[k], a);
            out[k] = contact.nodes[c.index].weight * defect - self.excess[k];
        }
    }

    /// f(x) into `f` and, when `slope` is given, its derivative per node;
    /// `reduced` is the surface on the nodal unknowns (its bounds those of
    /// the pressure-law nodes).
    fn forces(
        &self,
        reduced: &ContactSurface,
        classes: &[SlipState],
        x: &[f64],
        f: &mut [f64],
        mut slope: Option<&mut [[f64; 3]]>,
    ) {
        let n_c = reduced.len();
        for (j, (node, class)) in reduced.nodes.iter().zip(classes).enumerate() {
            let k = self.of_node[j];
            // The bound and its slope in u_N: dg/du_N = −c3 dg/dδ inside.
            let (g, dg, f_n, df_n) = match reduced.compliance.get(k) {
                Some(c) => {
                    let signed = self.signed_approach(k, x, n_c);
                    let delta = signed.max(0.0);
                    let inside = if delta > 0.0 { 1.0 } else { 0.0 };
                    let (g, dg) = if self.freeze {
                        (self.frozen[k], 0.0)
                    } else {
                        (
                            c.law.bound(delta),
                            -inside * self.c3 * c.law.bound_slope(delta),
                        )
                    };
                    let (f_n, df_n) = match self.form {
                        NormalForm::EndPoint => (
                            -node.weight * c.law.traction(delta),
                            inside * node.weight * self.c3 * c.law.stiffness(delta),
                        ),
                        NormalForm::EnergyConsistent => {
                            let (defect, slope) = c.law.energy_consistent(self.before[k], signed);
                            let w = node.weight;
                            (
                                -(w * (c.law.traction(delta) + defect) - self.excess[k]),
                                w * self.c3 * slope,
                            )
                        }
                    };
                    (g, dg, f_n, df_n)
                }
                None => (node.bound, 0.0, 0.0, 0.0),
            };
            let law = reduced.law_of(j);
            let w = node.weight;
            let (f_t, df_tt, df_tn) = if class.is_stuck() {
                let slip = reduced.slip(j, x[j]);
                let d = law.stuck_damping(w * g);
                (d * slip, d, law.stuck_damping(w * dg) * slip)
            } else {
                (w * g * class.sign(), 0.0, w * dg * class.sign())
            };
            f[j] = f_t;
            if k != usize::MAX {
                f[n_c + k] = f_n;
            }
            if let Some(s) = slope.as_deref_mut() {
                s[j] = [df_tt, df_tn, df_n];
            }
        }
    }

    /// Compliant node k's approach at x.
    fn approach(&self, k: usize, x: &[f64], n_c: usize) -> f64 {
        self.signed_approach(k, x, n_c).max(0.0)
    }

    /// Compliant node k's approach at x, negative off the foundation.
    fn signed_approach(&self, k: usize, x: &[f64], n_c: usize) -> f64 {
        -(self.gap[k] + self.c3 * x[n_c + k])
    }

    /// The compliant nodes' bounds at x into `frozen`; returns the largest
    /// change and the largest bound.
    fn freeze_bounds(&mut self, reduced: &ContactSurface) -> (f64, f64) {
        let n_c = reduced.len();
        let (mut change, mut largest) = (0.0_f64, 0.0_f64);
        for (k, c) in reduced.compliance.iter().enumerate() {
            let g = c.law.bound(self.approach(k, &self.x, n_c));
            change = change.max((g - self.frozen[k]).abs());
            largest = largest.max(g);
            self.frozen[k] = g;
        }
        (change, largest)
    }

    /// R = x + S f − p into `residual`; returns (|R|², max |R|, the scale
    /// max |x| + max |p| + max |S f| the residual is measured against).
    fn residual(s: &[f64], p: &[f64], x: &[f64], f: &[f64], residual: &mut [f64]) -> [f64; 3] {
        let n = p.len();
        for ((r, xi), pi) in residual.iter_mut().zip(x).zip(p) {
            *r = xi - pi;
        }
        let (mut norm2, mut max, mut sf_max) = (0.0_f64, 0.0_f64, 0.0_f64);
        // By columns of S (symmetric), skipping f = 0.
        for (col, &fj) in s.chunks_exact(n.max(1)).zip(f) {
            if fj != 0.0 {
                for (r, sij) in residual.iter_mut().zip(col) {
                    *r += sij * fj;
                }
            }
        }
        for ((r, xi), pi) in residual.iter().zip(x).zip(p) {
            norm2 += r * r;
            max = max.max(r.abs());
            sf_max = sf_max.max((r - xi + pi).abs());
        }
        let x_max = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let p_max = p.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        [norm2, max, x_max + p_max + sf_max]
    }

    /// Solves R(x) = 0 for `classes`, leaving the converged x in `self.x`,
    /// its forces in `f_out`, u_T in `velocity`: Newton on the whole
    /// system, or where it fails (the bound's coupling can leave it without
    /// a descent to the root) the authors' successive approximation on the
    /// bounds, each pass a Newton solve of the monotone system with the
    /// bounds of the last pass held fixed, until the bounds settle.
    fn solve(
        &mut self,
        reduced: &ContactSurface,
        classes: &[SlipState],
        (s, p): (&[f64], &[f64]),
        f_out: &mut [f64],
        velocity: &mut [f64],
    ) -> Result<(), NormalFailure> {
        self.start.copy_from_slice(&self.x);
        let mut result = self.newton(reduced, classes, (s, p));
        if result.is_err() && !reduced.compliance.is_empty() {
            self.x.copy_from_slice(&self.start);
            self.freeze_bounds(reduced);
            self.freeze = true;
            let first = std::mem::replace(&mut result, Ok(()));
            let mut settled = false;
            for _ in 0..MAX_PASSES {
                if let Err(e) = self.newton(reduced, classes, (s, p)) {
                    result = Err(e);
                    break;
                }
                let (change, largest) = self.freeze_bounds(reduced);
                if change <= TOLERANCE * largest {
                    settled = true;
                    break;
                }
            }
            self.freeze = false;
            // The bounds settled: the whole system's residual decides.
            result = match result {
                Ok(()) if settled => self.newton(reduced, classes, (s, p)),
                _ => first,
            };
        }
        let n_c = reduced.len();
        velocity[..n_c].copy_from_slice(&self.x[..n_c]);
        f_out.copy_from_slice(&self.f);
        result
    }

    /// Newton with the line search on R(x) = 0 from `self.x`, leaving x
    /// and f(x) there.
    fn newton(
        &mut self,
        reduced: &ContactSurface,
        classes: &[SlipState],
        (s, p): (&[f64], &[f64]),
    ) -> Result<(), NormalFailure> {
        let n = p.len();
        let n_c = reduced.len();
        let mut x = std::mem::take(&mut self.x);
        let mut f = std::mem::take(&mut self.f);
        let mut slope = std::mem::take(&mut self.slope);
        self.forces(reduced, classes, &x, &mut f, Some(&mut slope));
        let [mut norm2, mut max, mut scale] = Self::residual(s, p, &x, &f, &mut self.residual);
        let mut result = Err(NormalFailure::Newton {
            iterations: MAX_NEWTON,
            residual: max,
            scale,
        });
        for iteration in 0..=MAX_NEWTON {
            if max <= TOLERANCE * scale {
                result = Ok(());
                break;
            }
            if iteration == MAX_NEWTON {
                result = Err(NormalFailure::Newton {
                    iterations: iteration,
                    residual: max,
                    scale,
                });
                break;
            }
            self.newton += 1;
            // J = I + S D, D per node: (T_j, T_j) ∂f_T/∂u_T, (T_j, N_k)
            // ∂f_T/∂u_N, (N_k, N_k) ∂f_N/∂u_N; column-major.
            let jac = &mut self.jacobian;
            jac.iter_mut().for_each(|a| *a = 0.0);
            for (j, [tt, tn, nn]) in slope.iter().enumerate() {
                let k = self.of_node[j];
                for i in 0..n {
                    jac[j * n + i] += s[j * n + i] * tt;
                }
                if k != usize::MAX {
                    let col = n_c + k;
                    for i in 0..n {
                        jac[col * n + i] += s[j * n + i] * tn + s[col * n + i] * nn;
                    }
                }
            }
            for i in 0..n {
                jac[i * n + i] += 1.0;
            }
            for (d, r) in self.delta.iter_mut().zip(&self.residual) {
                *d = -r;
            }
            if !lu_solve(jac, n, &mut self.pivots, &mut self.delta) {
                result = Err(NormalFailure::Singular);
                break;
            }
            // Armijo on ½|R|²: the Newton direction's slope is −|R|².
            let mut alpha = 1.0;
            let mut accepted = false;
            for _ in 0..=MAX_HALVINGS {
                for ((t, xi), d) in self.trial.iter_mut().zip(&x).zip(&self.delta) {
                    *t = xi + alpha * d;
                }
                let mut trial_f = std::mem::take(&mut self.trial_f);
                self.forces(reduced, classes, &self.trial, &mut trial_f, None);
                let [t_norm2, t_max, t_scale] =
                    Self::residual(s, p, &self.trial, &trial_f, &mut self.residual);
                self.trial_f = trial_f;
                if t_norm2 <= (1.0 - 2e-4 * alpha) * norm2 || t_max <= TOLERANCE * t_scale {
                    (norm2, max, scale) = (t_norm2, t_max, t_scale);
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            if !accepted {
                // Back to x's residual for the report.
                let [_, m, sc] = Self::residual(s, p, &x, &f, &mut self.residual);
                result = Err(NormalFailure::Newton {
                    iterations: iteration + 1,
                    residual: m,
                    scale: sc,
                });
                break;
            }
            x.copy_from_slice(&self.trial);
            self.forces(reduced, classes, &x, &mut f, Some(&mut slope));
        }
        self.x = x;
        self.f = f;
        self.slope = slope;
        result
    }
}

/// Solves A y = b in place (A column-major n × n, overwritten by its LU
/// factors with partial pivoting); false on an exact zero pivot.
fn lu_solve(a: &mut [f64], n: usize, pivots: &mut [usize], b: &mut [f64]) -> bool {
    for k in 0..n {
        let (mut p, mut big) = (k, a[k * n + k].abs());
        for i in k + 1..n {
            if a[k * n + i].abs() > big {
                (p, big) = (i, a[k * n + i].abs());
            }
        }
        if big == 0.0 {
            return false;
        }
        pivots[k] = p;
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let inv = 1.0 / a[k * n + k];
        for i in k + 1..n {
            a[k * n + i] *= inv;
        }
        for j in k + 1..n {
            let akj = a[j * n + k];
            if akj != 0.0 {
                for i in k + 1..n {
                    a[j * n + i] -= a[k * n + i] * akj;
                }
            }
        }
    }
    for k in 0..n {
        b.swap(k, pivots[k]);
    }
    for j in 0..n {
        let bj = b[j];
        if bj != 0.0 {
            for i in j + 1..n {
                b[i] -= a[j * n + i] * bj;
            }
        }
    }
    for j in (0..n).rev() {
        b[j] /= a[j * n + j];
        let bj = b[j];
        for i in 0..j {
            b[i] -= a[j * n + i] * bj;
        }
    }
    true
}

/// The iteration's system with a compliant foundation: for given classes,
/// Newton on R(x) = 0 over the Schur complement's rows.
pub(crate) struct CompliantStep<'a> {
    pub(crate) op: &'a mut SchurOperator,
    pub(crate) solve: &'a mut CompliantSolve,
}

impl StepSystem for CompliantStep<'_> {
    type Error = NormalFailure;

    fn solve(
        &mut self,
        surface: &ContactSurface,
        classes: &[SlipState],
        velocity: &mut [f64],
    ) -> Result<(), NormalFailure> {
        let op = &mut *self.op;
        let mut f = std::mem::take(&mut op.f);
        let result = self
            .solve
            .solve(surface, classes, (op.schur(), &op.p), &mut f, velocity);
        op.f = f;
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stickslip_contact::{Compliance, CompliantNode, ContactNode};

    /// One node on the unknowns (u_T, u_N) = (x₀, x₁), weight `w`, held by
    /// a foundation of law `law` below it; friction of ε = 1e-3.
    fn node(w: f64, law: Compliance) -> ContactSurface {
        let n = ContactNode {
            node: 0,
            dofs: [Some(0), None],
            weight: w,
            tangent: [1.0, 0.0],
            s: 0.0,
            bound: 0.0,
        };
        let mut s = ContactSurface::from_nodes("c", vec![n], 1e-3).unwrap();
        s.compliance = vec![CompliantNode {
            index: 0,
            normal: [0.0, 1.0],
            gap: 0.0,
            law,
        }];
        s
    }

    /// A solve whose node's gap at the predictor is `gap` and c3 = `c3`,
    /// starting from x = 0.
    fn solver(s: &ContactSurface, gap: f64, c3: f64) -> CompliantSolve {
        let mut solve = CompliantSolve::new(s);
        solve.gap[0] = gap;
        solve.c3 = c3;
        solve
    }

    const FRICTIONLESS: [SlipState; 1] = [SlipState::Stuck];

    /// A stiff linear wall (w c_n c3 S_nn = 50): the node, moving in at
    /// p_N = −1 from the gap 0.001, settles at the root of u + S w c_n (g +
    /// c3 u) = p, u = (p − S w c_n g)/(1 + S w c_n c3), written here.
    /// Newton reaches it to round-off in a few iterations; the plain
    /// successive approximation (f from the last iterate, then u = p − S f)
    /// maps an error e to −50 e inside the wall and jumps out of it to
    /// u = p: it never settles, and its residual grows.
    #[test]
    fn newton_settles_where_the_plain_iteration_does_not() {
        let law = Compliance {
            cn: 1e4,
            mn: 1.0,
            ct: 0.0,
            mt: 1.0,
        };
        let (w, c3, gap) = (0.5, 0.01, 1e-3);
        let s_nn = 1.0;
        // S: the tangential row decoupled (S_tt = 1).
        let s_mat = [1.0, 0.0, 0.0, s_nn];
        let p = [0.0, -1.0];
        let surface = node(w, law);
        let k = s_nn * w * law.cn * c3;
        assert_eq!(k, 50.0);
        let exact = (p[1] - s_nn * w * law.cn * gap) / (1.0 + k);
        assert!(gap + c3 * exact < 0.0, "the root is in contact");

        let mut solve = solver(&surface, gap, c3);
        let (mut f, mut v) = (vec![0.0; 2], vec![0.0; 1]);
        solve
            .solve(&surface, &FRICTIONLESS, (&s_mat, &p), &mut f, &mut v)
            .unwrap();
        let u = solve.x[1];
        assert!((u - exact).abs() <= 1e-13 * exact.abs(), "{u} vs {exact}");
        assert!(solve.newton <= 5, "{} Newton iterations", solve.newton);
        // Its force is the law's at the root's approach.
        let delta = -(gap + c3 * exact);
        assert!((f[1] + w * law.cn * delta).abs() <= 1e-12 * w * law.cn * delta);

        // The plain iteration from the same start, written out.
        let mut u = 0.0_f64;
        let mut errors = Vec::new();
        for _ in 0..40 {
            let delta = (-(gap + c3 * u)).max(0.0);
            let f_n = -w * law.cn * delta;
            u = p[1] - s_nn * f_n;
            errors.push((u - exact).abs());
        }
        assert!(
            errors.iter().rev().take(10).all(|&e| e > 0.1 * exact.abs()),
            "plain iteration came near the root: {errors:?}"
        );
    }

    /// m_n = 2: the root of u + S f(u) = p is δ of S w c_n δ² + δ/c3 +
    /// (g/c3 + p) = 0 (u = −(g + δ)/c3), the quadratic's positive root
    /// written here; Newton with the line search reaches it from far.
    #[test]
    fn newton_solves_a_stiffening_wall() {
        let law = Compliance {
            cn: 1e6,
            mn: 2.0,
            ct: 0.0,
            mt: 2.0,
        };
        let (w, c3, gap) = (0.5, 0.01, 1e-3);
        let s_mat = [1.0, 0.0, 0.0, 2.0];
        let p = [0.0, -3.0];
        let surface = node(w, law);
        let a = 2.0 * w * law.cn;
        let (b, c) = (1.0 / c3, gap / c3 + p[1]);
        let delta = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
        let exact = -(gap + delta) / c3;
        let mut solve = solver(&surface, gap, c3);
        let (mut f, mut v) = (vec![0.0; 2], vec![0.0; 1]);
        solve
            .solve(&surface, &FRICTIONLESS, (&s_mat, &p), &mut f, &mut v)
            .unwrap();
        assert!(
            (solve.x[1] - exact).abs() <= 1e-12 * exact.abs(),
            "{} vs {exact}",
            solve.x[1]
        );
    }

    /// Frictionless (the monotone case the module's argument covers) the
    /// solve converges on every one of many systems drawn at random (a
    /// fixed linear congruential sequence): 4 nodes on 8 rows, S = B Bᵀ +
    /// I/10 symmetric positive definite, walls from soft to stiff (c_n from
    /// 10 to 1e6), m_n of 1 and 1.5, random gaps and classes, p driving
    /// nodes in and out: each returns a root, its residual checked by the
    /// equations written out here.
    #[test]
    fn newton_converges_on_random_systems() {
        let mut seed = 12345_u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (n_c, eps) = (4, 1e-3);
        let n = 2 * n_c;
        for case in 0..2000 {
            let mn = if case % 2 == 0 { 1.0 } else { 1.5 };
            let cn = 10f64.powf(1.0 + 5.0 * next());
            let law = Compliance {
                cn,
                mn,
                ct: 0.0,
                mt: mn,
            };
            let nodes = (0..n_c)
                .map(|j| ContactNode {
                    node: j,
                    dofs: [Some(j), None],
                    weight: 0.5,
                    tangent: [1.0, 0.0],
                    s: j as f64,
                    bound: 0.0,
                })
                .collect();
            let mut surface = ContactSurface::from_nodes("c", nodes, eps).unwrap();
            surface.compliance = (0..n_c)
                .map(|index| CompliantNode {
                    index,
                    normal: [0.0, 1.0],
                    gap: 0.0,
                    law,
                })
                .collect();
            let b: Vec<f64> = (0..n * n).map(|_| next() - 0.5).collect();
            let mut s_mat = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    let dot: f64 = (0..n).map(|k| b[i * n + k] * b[j * n + k]).sum();
                    s_mat[j * n + i] = dot + if i == j { 0.1 } else { 0.0 };
                }
            }
            let p: Vec<f64> = (0..n).map(|_| 2.0 * next() - 1.0).collect();
            let classes: Vec<SlipState> = (0..n_c)
                .map(|_| match (3.0 * next()) as usize {
                    0 => SlipState::Stuck,
                    1 => SlipState::SlipPositive,
                    _ => SlipState::SlipNegative,
                })
                .collect();
            let c3 = 0.01;
            let mut solve = CompliantSolve::new(&surface);
            solve.c3 = c3;
            for g in &mut solve.gap {
                *g = 0.01 * (next() - 0.5);
            }
            let gap = solve.gap.clone();
            let (mut f, mut v) = (vec![0.0; n], vec![0.0; n_c]);
            solve
                .solve(&surface, &classes, (&s_mat, &p), &mut f, &mut v)
                .unwrap_or_else(|e| panic!("case {case}: {e:?}"));
            let x = &solve.x;
            let mut force = vec![0.0; n];
            for j in 0..n_c {
                let delta = (-(gap[j] + c3 * x[n_c + j])).max(0.0);
                force[n_c + j] = -0.5 * cn * delta.powf(mn);
            }
            for i in 0..n {
                let sf: f64 = (0..n).map(|j| s_mat[j * n + i] * force[j]).sum();
                let big = (0..n).fold(0.0_f64, |m, j| m.max((s_mat[j * n + i] * force[j]).abs()));
                let r = x[i] + sf - p[i];
                assert!(
                    r.abs() <= 1e-9 * (x[i].abs() + p[i].abs() + big),
                    "case {case} row {i}: residual {r:e}"
                );
            }
        }
    }

    /// The energy-consistent form: one node whose approach at the step's
    /// start is a0 and whose carried excess is e solves u + S f(u) = p with
    /// f_N = −(2w(Φ(a₊) − Φ(a0₊))/(a − a0) − w σ(a0₊) − e), a = −(g + c3
    /// u), Φ = c_n d^{m+1}/(m+1) and σ = c_n d^m written here, for touches,
    /// releases and steps in contact, m_n = 1 and 1.5.
    #[test]
    fn newton_solves_the_energy_consistent_force() {
        for (mn, a0, e, p_n) in [
            (1.0, -1e-3, 0.0, -1.0),
            (1.0, 2e-3, 3.0, 1.0),
            (1.0, 2e-3, -1.0, -0.5),
            (1.5, -5e-4, 0.0, -2.0),
            (1.5, 3e-3, 2.0, 1.5),
            (1.5, 1e-3, 0.5, -1.0),
        ] {
            let law = Compliance {
                cn: 1e4,
                mn,
                ct: 0.0,
                mt: mn,
            };
            let (w, c3, gap) = (0.5, 0.01, 1e-3);
            let s_mat = [1.0, 0.0, 0.0, 0.5];
            let p = [0.0, p_n];
            let surface = node(w, law);
            let mut solve = solver(&surface, gap, c3);
            solve.form = NormalForm::EnergyConsistent;
            solve.before[0] = a0;
            solve.excess[0] = e;
            let (mut f, mut v) = (vec![0.0; 2], vec![0.0; 1]);
            solve
                .solve(&surface, &FRICTIONLESS, (&s_mat, &p), &mut f, &mut v)
                .unwrap();
            let u = solve.x[1];
            let a = -(gap + c3 * u);
            let phi = |a: f64| law.cn * a.max(0.0).powf(mn + 1.0) / (mn + 1.0);
            let f_n =
                -(2.0 * w * (phi(a) - phi(a0)) / (a - a0) - w * law.cn * a0.max(0.0).powf(mn) - e);
            let r = u + s_mat[3] * f_n - p[1];
            let size = u.abs() + p[1].abs() + (s_mat[3] * f_n).abs();
            assert!(
                r.abs() <= 1e-11 * size,
                "m = {mn}, a0 = {a0}: residual {r:e}"
            );
            assert!(
                (f[1] - f_n).abs() <= 1e-9 * f_n.abs().max(1e-12),
                "{} vs {f_n}",
                f[1]
            );
        }
    }

    /// With friction the bound follows the iterate's approach: a stuck
    /// node on a coupled S solves both rows of u + S f(u) = p, f_T = w
    /// c_T δ (u_T/ε) and f_N = −w c_n δ, checked by the equations written
    /// here at the returned x; slipping, f_T = w c_T δ.
    #[test]
    fn friction_follows_the_iterates_approach() {
        let law = Compliance {
            cn: 1e3,
            mn: 1.0,
            ct: 300.0,
            mt: 1.0,
        };
        let (w, c3, gap) = (0.5, 0.01, 0.0);
        let s_mat = [1.0, 0.2, 0.2, 1.5];
        let surface = node(w, law);
        for (class, p) in [
            (SlipState::Stuck, [1e-4, -1.0]),
            (SlipState::SlipPositive, [2.0, -1.0]),
        ] {
            let mut solve = solver(&surface, gap, c3);
            let (mut f, mut v) = (vec![0.0; 2], vec![0.0; 1]);
            solve
                .solve(&surface, &[class], (&s_mat, &p), &mut f, &mut v)
                .unwrap();
            let x = &solve.x;
            let delta = (-(gap + c3 * x[1])).max(0.0);
            assert!(delta > 0.0);
            let f_t = match class {
                SlipState::Stuck => w * law.ct * delta * x[0] / 1e-3,
                _ => w * law.ct * delta,
            };
            let f_n = -w * law.cn * delta;
            for i in 0..2 {
                let r = x[i] + s_mat[i] * f_t + s_mat[2 + i] * f_n - p[i];
                let size = x[i].abs() + p[i].abs() + (s_mat[i] * f_t).abs();
                assert!(r.abs() <= 1e-12 * size, "{class:?} row {i}: {r}");
            }
            assert_eq!(v[0], x[0]);
        }
    }
}
