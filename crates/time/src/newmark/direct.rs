//! The implicit Newmark step solved directly: the operator (β/γ)ΔtK +
//! M/(γΔt) + C and its factorization, kept until Δt or the stuck set
//! changes (METHOD.md §4-5). The reference the Schur path is checked
//! against.

use nalgebra_sparse::CsrMatrix;
use stickslip_contact::{ContactSurface, SlipState, StepSystem};
use stickslip_linalg::{FillOrder, SolverError, SparseCholesky};

use stickslip_linalg::csr::index as csr_index;

use super::Operator;
use crate::initial::SharedAnalysis;

/// The implicit operator and its factorization for the current (Δt, stuck
/// set); `factorizations` counts numeric factorizations over the run.
pub(crate) struct DirectOperator {
    /// A₀ = c_K K + c_M M for the current Δt (values only change).
    a0: CsrMatrix<f64>,
    /// A₀ + C for the current stuck set: what is factorized.
    work: CsrMatrix<f64>,
    cholesky: SparseCholesky,
    /// Positions of (xx, xy, yx, yy) of each contact node in the CSR values.
    entries: Vec<[Option<usize>; 4]>,
    key_dt: f64,
    key_stuck: Vec<bool>,
    /// The bounds' revision C was formed with (a bound that changes in
    /// time changes C).
    key_revision: u64,
    valid: bool,
    pub factorizations: u64,
}

impl DirectOperator {
    /// The analysis of K's pattern its factor uses.
    pub(crate) fn analysis(&self) -> &stickslip_linalg::Analysis {
        self.cholesky.analysis()
    }

    /// Analyses the pattern of K (which M shares) once for the run, or
    /// takes its `analysis`, made already.
    pub fn new(
        stiffness: &CsrMatrix<f64>,
        order: &FillOrder,
        analysis: SharedAnalysis,
        contact: Option<&ContactSurface>,
    ) -> Result<DirectOperator, SolverError> {
        let cholesky = SparseCholesky::on(stickslip_linalg::Analysis::shared_or_of(
            analysis, stiffness, order,
        )?)?;
        let entries = contact
            .map(|s| {
                s.nodes
                    .iter()
                    .map(|n| {
                        let mut e = [None; 4];
                        for a in 0..2 {
                            for b in 0..2 {
                                if let (Some(i), Some(j)) = (n.dofs[a], n.dofs[b]) {
                                    e[2 * a + b] = csr_index(stiffness, i, j);
                                }
                            }
                        }
                        e
                    })
                    .collect()
            })
            .unwrap_or_default();
        Ok(DirectOperator {
            a0: stiffness.clone(),
            work: stiffness.clone(),
            cholesky,
            entries,
            key_dt: f64::NAN,
            key_stuck: contact.map(|s| vec![false; s.len()]).unwrap_or_default(),
            key_revision: 0,
            valid: false,
            factorizations: 0,
        })
    }

    /// Sets A₀ = c_k K + c_m M for a new Δt (M has K's pattern).
    pub fn set_dt(&mut self, operator: Operator) {
        if operator.dt == self.key_dt {
            return;
        }
        for (a, v) in self.a0.values_mut().iter_mut().zip(operator.values()) {
            *a = v;
        }
        self.key_dt = operator.dt;
        self.valid = false;
    }

    /// Makes the factorization match the stuck set of `classes`,
    /// refactorizing only if it changed.
    fn ensure_factorized(
        &mut self,
        surface: Option<&ContactSurface>,
        classes: &[SlipState],
    ) -> Result<(), SolverError> {
        let revision = surface.map_or(0, |s| s.revision);
        let same = self.valid
            && self.key_revision == revision
            && self
                .key_stuck
                .iter()
                .zip(classes)
                .all(|(&k, c)| k == c.is_stuck());
        if same {
            return Ok(());
        }
        self.work.values_mut().copy_from_slice(self.a0.values());
        if let Some(surface) = surface {
            let (values, entries) = (self.work.values_mut(), &self.entries);
            surface.add_damping(classes, |j, a, b, value| {
                if let Some(p) = entries[j][2 * a + b] {
                    values[p] += value;
                }
            });
            for (k, c) in self.key_stuck.iter_mut().zip(classes) {
                *k = c.is_stuck();
            }
        }
        self.key_revision = revision;
        self.valid = false;
        self.cholesky.factorize(&self.work)?;
        self.factorizations += 1;
        self.valid = true;
        Ok(())
    }

    /// Solves (A₀ + C) x = rhs for a contact-free scene.
    pub fn solve_plain(&mut self, rhs: &[f64], x: &mut [f64]) -> Result<(), SolverError> {
        self.ensure_factorized(None, &[])?;
        x.copy_from_slice(rhs);
        self.cholesky.solve_in_place(x);
        Ok(())
    }
}

/// One step's linear system for the stick/slip iteration: b is the
/// right-hand side without friction (R̂_K of METHOD.md §4).
pub(crate) struct ImplicitStep<'a> {
    pub operator: &'a mut DirectOperator,
    pub b: &'a [f64],
}

impl StepSystem for ImplicitStep<'_> {
    type Error = SolverError;

    fn solve(
        &mut self,
        surface: &ContactSurface,
        classes: &[SlipState],
        velocity: &mut [f64],
    ) -> Result<(), SolverError> {
        self.operator.ensure_factorized(Some(surface), classes)?;
        velocity.copy_from_slice(self.b);
        surface.subtract_slip_forces(classes, velocity);
        self.operator.cholesky.solve_in_place(velocity);
        Ok(())
    }
}
