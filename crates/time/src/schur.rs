//! The implicit Newmark step by a Schur complement on the contact DOFs
//! (issue 7, deliverable 1; METHOD.md §4-5).
//!
//! The step's operator is A₀ + C with A₀ = (β/γ)ΔtK + M/(γΔt) and C the
//! damping of the stuck nodes, which lives on the contact tangential DOFs
//! only: C = Pᵀ D P, P the n_c × n restriction whose row J is τ_J on node
//! J's free DOFs, D = diag(w_J g_J/ε) over stuck nodes. So A₀ is factorized
//! once per distinct Δt (one symbolic analysis for the run), and with
//! Z = A₀⁻¹Pᵀ and S = P Z (dense n_c × n_c) a step is
//!
//! * v₀ = A₀⁻¹ b (one solve), p = P v₀;
//! * the nodal tangential velocities u solve u + S f(u) = p, where
//!   f_J = w_J g_J φ_ε(u_J): the stick/slip iteration of §5 with Remark 4.2
//!   runs on these n_c unknowns (a [`ContactSurface`] of unit nodes, so it
//!   is literally [`iterate`]); for given classes, f = F on slipping nodes
//!   and f_s = D_s u_s on stuck ones, with u_s from the SPD system
//!   (I + W S_ss W) y = W (p_s − S_sl F_l), W = D_s^{1/2}, f_s = W y;
//! * v = v₀ − Z f (Woodbury: (A₀ + PᵀDP)v = b − PᵀF gives the same v).
//!
//! The solves are this crate's own loops over faer's supernodal factor
//! (`supernodal.rs`: 2.7× faster than faer's one-column solve at 250k DOFs,
//! the tree split between two threads), and on small factors the inverted
//! blocks of `small_solve.rs` (the paper mesh: 3.6× faster than those
//! loops). Without a stored Z the step's two
//! solves share their work: v₀ is only needed at the contact DOFs before
//! the iteration, and A₀⁻¹(b − Pᵀf) differs from A₀⁻¹b only on the paths
//! from the contact DOFs to the root, so a step is one forward solve, a
//! back solve on those paths, the iteration, a forward solve on those paths
//! and one back solve: 2·|L| + 2·|reach| values read instead of 4·|L|.
//! Better still, the two restricted solves are products with W = L⁻¹Pᵀ,
//! whose columns live on those paths only (p = Wᵀy, the correction W f):
//! W is built with S, and serves the step when its 12 bytes a value are
//! fewer than the reach's 8 (Q1 slab of 251k DOFs: 2.5M values of W
//! against 6.8M of L in the reach). Z costs n·n_c values per step and as
//! much memory; it is stored only when n·n_c is below both 2·|reach| and
//! |L| (small meshes).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltError, LltParams};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky};
use faer::{Conj, MatMut, Par, Side, Spec};
use nalgebra_sparse::CsrMatrix;
use stickslip_contact::{ContactNode, ContactSurface, SlipState, StepSystem};
use stickslip_fem::{analyze_symbolic, csc_view, ContactOperator, FillOrder, SolverError};

use stickslip_fem::Supernodal;

use crate::small_solve::{minus_columns, BlockInverse};

/// Right-hand sides solved together when building Z and S: one pass over
/// the factor serves the whole block.
/// (16: the pool's two blocks in flight hold what one block of 32 did.)
const BLOCK: usize = 16;

/// How many Δt keep their factor (the normal and the reduced step).
const CACHE: usize = 2;

/// How the implicit step solves its linear systems.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ImplicitSolver {
    /// A₀ factorized once per Δt, friction on the contact DOFs through the
    /// Schur complement; the correction −Z f or a second solve, whichever
    /// costs less memory traffic (n·n_c against the factor's size).
    #[default]
    Schur,
    /// As [`ImplicitSolver::Schur`], always storing Z.
    SchurStoredZ,
    /// As [`ImplicitSolver::Schur`], never storing Z: the step's second
    /// solve shares its passes with the first, restricted to the contact
    /// DOFs' paths (`supernodal.rs`).
    SchurSecondSolve,
    /// As [`ImplicitSolver::Schur`], never storing Z, the step through
    /// W = L⁻¹Pᵀ on its paths (p = Wᵀy, correction W f).
    SchurPaths,
    /// A₀ + C refactorized whenever Δt or the stuck set changes, the
    /// iteration on the full system (the reference).
    Direct,
    /// The state in the modes of (K, M), A₀ diagonal, friction through
    /// the Schur complement on Φ_c = PΦ (`modal.rs`); the default for
    /// systems of up to [`MODAL_MAX_DOFS`](crate::MODAL_MAX_DOFS) free DOFs.
    Modal,
}

/// S is symmetric in exact arithmetic; make it so in floating point so that
/// the dense Cholesky sees one matrix.
fn symmetrize(s: &mut [f64], n_c: usize) {
    for j in 0..n_c {
        for i in 0..j {
            let m = 0.5 * (s[j * n_c + i] + s[i * n_c + j]);
            s[j * n_c + i] = m;
            s[i * n_c + j] = m;
        }
    }
}

/// One Δt's factor of A₀ and its Schur data.
struct Entry {
    dt_bits: u64,
    /// Values of L (the pattern is the shared symbolic factor's).
    l_values: Vec<f64>,
    /// S = P A₀⁻¹ Pᵀ, column-major n_c × n_c.
    s: Vec<f64>,
    /// Z = A₀⁻¹ Pᵀ, column-major n × n_c; empty when not stored.
    z: Vec<f64>,
    /// W = L⁻¹Pᵀ on its paths (`Supernodal::schur_complement`), when the
    /// step goes through it rather than through solves on the reach.
    paths: Option<ContactOperator>,
    /// The solve by inverted supernode blocks, for small factors
    /// (`small_solve.rs`).
    small: Option<BlockInverse>,
    /// The modal step's A₀⁻¹ = 1/((β/γ)Δt λ + 1/(γΔt)) (`modal.rs`).
    dinv: Vec<f64>,
    /// Distinguishes entries for the dense factor's cache.
    id: u64,
    last_used: u64,
}

/// The dense Cholesky factor of I + W S_ss W for one (entry, stuck set).
struct DenseFactor {
    entry_id: u64,
    stuck: Vec<bool>,
    valid: bool,
    /// Stuck node indices.
    index: Vec<usize>,
    /// W = √(w g/ε) of the stuck nodes.
    w: Vec<f64>,
    /// The factor, column-major n_s × n_s in the first n_s² values.
    l: Vec<f64>,
    /// 1 / the factor's diagonal (the solves multiply: a division's
    /// latency per column was most of their chains).
    inv_diag: Vec<f64>,
    /// Lᵀ column-major (L by rows), for the back solve by columns.
    lt: Vec<f64>,
    /// The nodes with f ≠ 0 at this solve (slipping).
    slip: Vec<usize>,
    scratch: MemBuffer,
}

/// The modal step's P = Φ_c and Λ.
struct ModalOperator {
    /// Φ_c by rows (n_c × n: a contact node's row).
    rows: Vec<f64>,
    /// Φ_c by modes (n × n_c: a mode's n_c values), for p = Φ_c q̇ as a
    /// sum of n_c-long columns (a dot product per node waited on its
    /// adder: 0.6 µs of the paper mesh's step).
    by_mode: Vec<f64>,
    lambda: Vec<f64>,
}

/// A₀'s factors per Δt and the Schur complement on the contact DOFs.
pub(crate) struct SchurOperator {
    n: usize,
    symbolic: SymbolicCholesky<usize>,
    /// The solves on the factor's layout.
    sn: Supernodal,
    /// Permuted index of every DOF (for the contact DOFs' values).
    perm: Vec<usize>,
    /// Pᵀf as (permuted index, value), for the split step's correction.
    correction: Vec<(usize, f64)>,
    entries: Vec<Entry>,
    current: usize,
    clock: u64,
    next_id: u64,
    store_z: Option<bool>,
    /// Some(true/false) forces the step through W or through solves on
    /// the reach; None picks by bytes.
    use_paths: Option<bool>,
    /// The contact nodes as seen by P.
    nodes: Vec<ContactNode>,
    /// The same nodes as unit nodes on the n_c nodal unknowns, for the
    /// iteration.
    pub reduced: Option<ContactSurface>,
    dense: DenseFactor,
    /// p = P v₀.
    p: Vec<f64>,
    /// f of the last solve of the iteration.
    f: Vec<f64>,
    pub factorizations: u64,
    /// The step in the modes of (K, M) (`modal.rs`); the vectors it is
    /// given and returns are modal coordinates.
    modal: Option<ModalOperator>,
}

impl SchurOperator {
    /// Analyses K's pattern (which M shares) once for the run.
    pub fn new(
        stiffness: &CsrMatrix<f64>,
        order: &FillOrder,
        contact: Option<&ContactSurface>,
        solver: ImplicitSolver,
    ) -> Result<SchurOperator, SolverError> {
        let n = stiffness.nrows();
        if n != stiffness.ncols() {
            return Err(SolverError::NotSquare {
                rows: n,
                cols: stiffness.ncols(),
            });
        }
        let symbolic = analyze_symbolic(stiffness, order)?;
        let mut sn = Supernodal::new(&symbolic).ok_or_else(|| {
            SolverError::Analysis("faer returned a factor layout this solver does not know".into())
        })?;
        let perm = sn.permuted_indices();
        let nodes = contact.map(|c| c.nodes.clone()).unwrap_or_default();
        let contact_dofs: Vec<usize> = nodes
            .iter()
            .flat_map(|node| node.dofs.iter().flatten().copied())
            .collect();
        sn.set_reach(&contact_dofs);
        let n_c = nodes.len();
        let reduced = contact
            .filter(|_| n_c > 0)
            .map(ContactSurface::on_tangential_unknowns);
        let store_z = match solver {
            ImplicitSolver::SchurStoredZ => Some(true),
            ImplicitSolver::SchurSecondSolve | ImplicitSolver::SchurPaths => Some(false),
            _ => None,
        };
        let dense = DenseFactor {
            entry_id: u64::MAX,
            stuck: vec![false; n_c],
            valid: false,
            index: Vec::with_capacity(n_c),
            w: Vec::with_capacity(n_c),
            l: vec![0.0; n_c * n_c],
            inv_diag: Vec::with_capacity(n_c),
            lt: vec![0.0; n_c * n_c],
            slip: Vec::with_capacity(n_c),
            scratch: MemBuffer::new(
                faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
                    n_c,
                    Par::Seq,
                    Default::default(),
                ),
            ),
        };
        Ok(SchurOperator {
            n,
            symbolic,
            sn,
            perm,
            correction: Vec::with_capacity(contact_dofs.len()),
            entries: Vec::with_capacity(CACHE),
            current: usize::MAX,
            clock: 0,
            next_id: 0,
            store_z,
            use_paths: match solver {
                ImplicitSolver::SchurSecondSolve => Some(false),
                ImplicitSolver::SchurPaths => Some(true),
                _ => None,
            },
            nodes,
            reduced,
            dense,
            p: vec![0.0; n_c],
            f: vec![0.0; n_c],
            factorizations: 0,
            modal: None,
        })
    }

    /// Makes this the modal step's operator (`modal.rs`): A₀ = c_k Λ + c_m I
    /// and P = Φ_c (`rows`, n_c × n by rows); the factor's entries go.
    pub fn set_modal(&mut self, rows: Vec<f64>, lambda: Vec<f64>) {
        self.entries.clear();
        self.current = usize::MAX;
        let (n, n_c) = (self.n, self.nodes.len());
        let mut by_mode = vec![0.0; n * n_c];
        for (j, row) in rows.chunks_exact(n).enumerate() {
            for (k, x) in row.iter().enumerate() {
                by_mode[k * n_c + j] = *x;
            }
        }
        self.modal = Some(ModalOperator {
            rows,
            by_mode,
            lambda,
        });
    }

    /// The modal entry for this Δt: A₀⁻¹'s diagonal, Z = A₀⁻¹Φ_cᵀ and
    /// S = Φ_c Z, into `slot`.
    fn build_modal(&mut self, slot: usize, c_k: f64, c_m: f64) {
        let ModalOperator { rows, lambda, .. } = self.modal.as_ref().expect("modal");
        let (n, n_c) = (self.n, self.nodes.len());
        let entry = &mut self.entries[slot];
        entry.dinv.clear();
        entry
            .dinv
            .extend(lambda.iter().map(|l| 1.0 / (c_k * l + c_m)));
        entry.z.clear();
        entry.z.resize(n * n_c, 0.0);
        for (z, row) in entry.z.chunks_exact_mut(n).zip(rows.chunks_exact(n)) {
            for ((zi, r), d) in z.iter_mut().zip(row).zip(&entry.dinv) {
                *zi = d * r;
            }
        }
        entry.s.clear();
        entry.s.resize(n_c * n_c, 0.0);
        for (j, z) in entry.z.chunks_exact(n).enumerate() {
            for (i, row) in rows.chunks_exact(n).enumerate() {
                entry.s[j * n_c + i] = crate::modal::dot4(row, z);
            }
        }
        symmetrize(&mut entry.s, n_c);
    }

    /// Values held per Δt for the solves (for memory figures): L's, and
    /// the inverted blocks' where the factor is small.
    pub fn factor_len(&self) -> usize {
        if let Some(m) = &self.modal {
            let entry = self.entries.get(self.current);
            return m.rows.len()
                + m.by_mode.len()
                + m.lambda.len()
                + entry.map_or(0, |e| e.dinv.len() + e.z.len() + e.s.len());
        }
        let small = self
            .entries
            .get(self.current)
            .and_then(|e| e.small.as_ref())
            .map_or(0, BlockInverse::len);
        self.symbolic.len_val() + small
    }

    /// (values of W the current Δt's step uses, 0 if it goes otherwise;
    /// values of L on the contact DOFs' paths to the root).
    pub fn paths_len(&self) -> (usize, usize) {
        let w = self
            .entries
            .get(self.current)
            .and_then(|e| e.paths.as_ref())
            .map_or(0, |op| op.w_len());
        (w, self.sn.reach_len())
    }

    /// Makes the factor of A₀ = c_k K + c_m M for this Δt current: from the
    /// cache, or factorized (with S and Z) once.
    pub fn set_dt(
        &mut self,
        dt: f64,
        c_k: f64,
        stiffness: &CsrMatrix<f64>,
        c_m: f64,
        mass: &CsrMatrix<f64>,
    ) -> Result<(), SolverError> {
        self.clock += 1;
        let bits = dt.to_bits();
        if let Some(k) = self.entries.iter().position(|e| e.dt_bits == bits) {
            self.current = k;
            self.entries[k].last_used = self.clock;
            return Ok(());
        }
        if self.modal.is_some() {
            let slot = self.free_slot(bits);
            self.build_modal(slot, c_k, c_m);
            self.make_current(slot, bits);
            return Ok(());
        }
        // A₀'s values (K and M share one pattern) and the factorization's
        // workspace live only while it runs: the step holds K, M and the
        // factors, not a third matrix.
        let a0: Vec<f64> = stiffness
            .values()
            .iter()
            .zip(mass.values())
            .map(|(k, m)| c_k * k + c_m * m)
            .collect();
        let mut factor_scratch = MemBuffer::new(
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        let slot = self.free_slot(bits);
        let entry = &mut self.entries[slot];
        entry.dt_bits = u64::MAX; // invalid until factorized
        let result = self.symbolic.factorize_numeric_llt(
            &mut entry.l_values,
            csc_view(stiffness, &a0),
            Side::Lower,
            Default::default(),
            Par::Seq,
            MemStack::new(&mut factor_scratch),
            Spec::<LltParams, f64>::default(),
        );
        match result {
            Ok(_) => {}
            Err(LltError::NonPositivePivot { index }) => {
                return Err(SolverError::NotPositiveDefinite {
                    pivot: index,
                    n: self.n,
                })
            }
        }
        drop(factor_scratch);
        drop(a0);
        self.make_current(slot, bits);
        let entry = &mut self.entries[slot];
        entry.small =
            BlockInverse::worth_it(&self.sn).then(|| BlockInverse::new(&self.sn, &entry.l_values));
        self.build_schur(slot);
        // The factorization's workspace and S's scratch are freed.
        crate::memory::release_free_memory();
        Ok(())
    }

    /// Entry `slot`, formed for Δt `bits`, becomes the current one: a new
    /// id (for the dense factor's cache) and one more factorization.
    fn make_current(&mut self, slot: usize, bits: u64) {
        let entry = &mut self.entries[slot];
        entry.dt_bits = bits;
        entry.id = self.next_id;
        entry.last_used = self.clock;
        self.next_id += 1;
        self.factorizations += 1;
        self.current = slot;
    }

    /// A new entry, or the least recently used one's storage once the
    /// cache is full; no entry is current after it.
    fn free_slot(&mut self, bits: u64) -> usize {
        self.current = usize::MAX;
        if self.entries.len() < CACHE {
            self.entries.push(Entry {
                dt_bits: bits,
                l_values: if self.modal.is_some() {
                    Vec::new()
                } else {
                    vec![0.0; self.symbolic.len_val()]
                },
                s: Vec::new(),
                z: Vec::new(),
                paths: None,
                small: None,
                dinv: Vec::new(),
                id: 0,
                last_used: 0,
            });
            self.entries.len() - 1
        } else {
            let (k, _) = self
                .entries
                .iter()
                .enumerate()
                .min_by_key(|(_, e)| e.last_used)
                .expect("cache is full");
            k
        }
    }

    /// Z = A₀⁻¹Pᵀ and S = P Z for entry `slot`, BLOCK columns per solve.
    fn build_schur(&mut self, slot: usize) {
        let n = self.n;
        let n_c = self.nodes.len();
        let z_len = n.saturating_mul(n_c);
        let store = self
            .store_z
            .unwrap_or(z_len <= self.symbolic.len_val() && z_len < 2 * self.sn.reach_len());
        let entry = &mut self.entries[slot];
        entry.s.clear();
        entry.s.resize(n_c * n_c, 0.0);
        entry.z.clear();
        entry.paths = None;
        if n_c == 0 {
            return;
        }
        if store {
            entry.z.resize(n * n_c, 0.0);
        } else {
            // S alone: solves restricted to the contact DOFs' paths, eight
            // columns per pass (`Supernodal::schur_complement`).
            let rows: Vec<Vec<(usize, f64)>> = self
                .nodes
                .iter()
                .map(|node| {
                    node.dofs
                        .iter()
                        .zip(node.tangent)
                        .filter_map(|(d, t)| d.map(|i| (self.perm[i], t)))
                        .collect()
                })
                .collect();
            let mut op = self.sn.schur_complement(&entry.l_values, &rows);
            entry.s = std::mem::take(&mut op.s);
            symmetrize(&mut entry.s, n_c);
            // W (12 bytes a value) against the reach's part of L (8):
            // whichever streams fewer bytes serves the step.
            let paths = self
                .use_paths
                .unwrap_or(12 * op.w_len() < 8 * self.sn.reach_len());
            entry.paths = paths.then_some(op);
            return;
        }
        let llt = LltRef::<'_, usize, f64>::new(&self.symbolic, &entry.l_values);
        let width = BLOCK.min(n_c);
        let nodes = &self.nodes;
        let symbolic = &self.symbolic;
        // The blocks in two halves, one per thread of the pool, each with
        // one buffer made here (so that the allocator returns them when
        // they are dropped here); a column's arithmetic is the same on any
        // thread.
        let starts: Vec<usize> = (0..n_c).step_by(width).collect();
        let (first, second) = starts.split_at(starts.len().div_ceil(2));
        let buffer = || {
            (
                vec![0.0; n * width],
                MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(width, Par::Seq)),
            )
        };
        let work = |starts: &[usize], (x, scratch): &mut (Vec<f64>, MemBuffer)| {
            let mut out = Vec::with_capacity(starts.len());
            for &start in starts {
                let cols = width.min(n_c - start);
                let x = &mut x[..n * cols];
                x.fill(0.0);
                for c in 0..cols {
                    let node = &nodes[start + c];
                    for (d, t) in node.dofs.iter().zip(node.tangent) {
                        if let Some(i) = d {
                            x[c * n + i] = t;
                        }
                    }
                }
                llt.solve_in_place_with_conj(
                    Conj::No,
                    MatMut::from_column_major_slice_mut(x, n, cols),
                    Par::Seq,
                    MemStack::new(scratch),
                );
                out.push((start, x.to_vec()));
            }
            out
        };
        let (mut buf0, mut buf1) = (buffer(), buffer());
        let (mut blocks, rest) = rayon::join(|| work(first, &mut buf0), || work(second, &mut buf1));
        drop((buf0, buf1));
        blocks.extend(rest);
        for (start, data) in blocks {
            let cols = width.min(n_c - start);
            for c in 0..cols {
                let j = start + c;
                let col = &data[c * n..(c + 1) * n];
                for (i, node) in nodes.iter().enumerate() {
                    entry.s[j * n_c + i] = node.tangential(col);
                }
                entry.z[j * n..(j + 1) * n].copy_from_slice(col);
            }
        }
        symmetrize(&mut entry.s, n_c);
    }

    fn solve(&mut self, x: &mut [f64]) {
        let entry = &mut self.entries[self.current];
        if self.modal.is_some() {
            for (xi, d) in x.iter_mut().zip(&entry.dinv) {
                *xi *= d;
            }
            return;
        }
        match &mut entry.small {
            Some(small) => small.solve(x),
            None => self.sn.solve(&entry.l_values, x),
        }
    }

    /// v = A₀⁻¹ b without friction.
    pub fn solve_plain(&mut self, b: &[f64], v: &mut [f64]) {
        v.copy_from_slice(b);
        self.solve(v);
    }

    /// v₀ = A₀⁻¹ b into `v` and p = P v₀: the start of a step with friction.
    pub fn begin(&mut self, b: &[f64], v: &mut [f64]) {
        if self.modal.is_some() {
            // q̇₀ = A₀⁻¹b (diagonal), p = Φ_c q̇₀.
            v.copy_from_slice(b);
            self.solve(v);
            let m = self.modal.as_ref().expect("modal");
            modal_columns(&m.by_mode, v, &mut self.p);
            return;
        }
        let entry = &self.entries[self.current];
        if let Some(op) = &entry.paths {
            // p = Wᵀ(L⁻¹b); `finish` corrects and back-solves.
            self.sn
                .begin_step_paths(&entry.l_values, op, b, &mut self.p);
            return;
        }
        if entry.z.is_empty() {
            // The split step: v₀ at the contact DOFs only; `finish` solves.
            self.sn.begin_step(&self.entries[self.current].l_values, b);
            for (p, node) in self.p.iter_mut().zip(&self.nodes) {
                let mut sum = 0.0;
                for (d, t) in node.dofs.iter().zip(node.tangent) {
                    if let Some(i) = d {
                        sum += t * self.sn.reach_value(self.perm[*i]);
                    }
                }
                *p = sum;
            }
            return;
        }
        v.copy_from_slice(b);
        self.solve(v);
        for (p, node) in self.p.iter_mut().zip(&self.nodes) {
            *p = node.tangential(v);
        }
    }

    /// The nodal system of this step for the iteration.
    pub fn nodal_system(&mut self) -> NodalStep<'_> {
        NodalStep { op: self }
    }

    /// v = v₀ − Z f (or A₀⁻¹(b − Pᵀf) by the split step) with the f of
    /// the converged iteration; with a stored Z, `v` holds v₀ on entry.
    pub fn finish(&mut self, v: &mut [f64]) {
        let n = self.n;
        let entry = &self.entries[self.current];
        if self.modal.is_some() {
            minus_columns(&mut v[..n], &entry.z, &self.f);
            return;
        }
        if let Some(op) = &entry.paths {
            self.sn.finish_step_paths(&entry.l_values, op, &self.f, v);
            return;
        }
        if entry.z.is_empty() {
            self.correction.clear();
            for (node, f) in self.nodes.iter().zip(&self.f) {
                for (d, t) in node.dofs.iter().zip(node.tangent) {
                    if let Some(i) = d {
                        self.correction.push((self.perm[*i], f * t));
                    }
                }
            }
            self.sn.finish_step(&entry.l_values, &self.correction, v);
        } else {
            // A node with f = 0 costs nothing.
            minus_columns(&mut v[..n], &entry.z, &self.f);
        }
    }

    /// f for `classes` into self.f and u = p − S f into `u`, on `reduced`
    /// (the nodes as unit nodes on the n_c unknowns).
    fn nodal_solve(
        &mut self,
        reduced: &ContactSurface,
        classes: &[SlipState],
        u: &mut [f64],
    ) -> Result<(), SolverError> {
        let n_c = self.nodes.len();
        let entry = &self.entries[self.current];
        let s = &entry.s;
        // Slip forces F_J = w g sign (0 on stuck nodes, set below).
        for ((f, node), c) in self.f.iter_mut().zip(&reduced.nodes).zip(classes) {
            *f = node.slip_force(*c);
        }
        let d = &mut self.dense;
        let same = d.valid
            && d.entry_id == entry.id
            && d.stuck.iter().zip(classes).all(|(&k, c)| k == c.is_stuck());
        if !same {
            d.valid = false;
            d.index.clear();
            d.w.clear();
            for (j, (node, c)) in reduced.nodes.iter().zip(classes).enumerate() {
                d.stuck[j] = c.is_stuck();
                if c.is_stuck() {
                    d.index.push(j);
                    d.w.push(node.stuck_damping(&reduced.law).sqrt());
                }
            }
            let m = d.index.len();
            let l = &mut d.l[..m * m];
            for (b, &jb) in d.index.iter().enumerate() {
                for (a, &ja) in d.index.iter().enumerate() {
                    l[b * m + a] = d.w[a] * s[jb * n_c + ja] * d.w[b];
                }
                l[b * m + b] += 1.0;
            }
            if m > 0 {
                let result = faer::linalg::cholesky::llt::factor::cholesky_in_place(
                    MatMut::from_column_major_slice_mut(l, m, m),
                    Default::default(),
                    Par::Seq,
                    MemStack::new(&mut d.scratch),
                    Spec::<LltParams, f64>::default(),
                );
                if let Err(LltError::NonPositivePivot { index }) = result {
                    return Err(SolverError::NotPositiveDefinite { pivot: index, n: m });
                }
            }
            d.inv_diag.clear();
            d.inv_diag.extend((0..m).map(|j| 1.0 / d.l[j * m + j]));
            for j in 0..m {
                for i in j..m {
                    d.lt[i * m + j] = d.l[j * m + i];
                }
            }
            d.entry_id = entry.id;
            d.valid = true;
        }
        let m = d.index.len();
        if m > 0 {
            // y = (I + W S_ss W)⁻¹ W (p_s − S_s· F); f_s = W y.
            let y = &mut u[..m];
            d.slip.clear();
            d.slip.extend((0..n_c).filter(|&j| self.f[j] != 0.0));
            for (a, &ja) in d.index.iter().enumerate() {
                let mut r = self.p[ja];
                for &j in &d.slip {
                    r -= s[j * n_c + ja] * self.f[j];
                }
                y[a] = d.w[a] * r;
            }
            // L Lᵀ y = rhs by plain loops: at n_s ≤ n_c (16 on the paper
            // mesh) faer's dispatch cost more than the 2·n_s² operations.
            // Both by columns: a column's updates are independent, so a
            // step waits on one multiplication, where the back solve by
            // rows summed each row in a chain (the paper mesh's nodal
            // solve: 9.7% → 6.7% of its Newmark step, perf, about 0.15 µs).
            let (l, lt) = (&d.l[..m * m], &d.lt[..m * m]);
            for j in 0..m {
                let col = &l[j * m..(j + 1) * m];
                let yj = y[j] * d.inv_diag[j];
                y[j] = yj;
                for (yi, lij) in y[j + 1..].iter_mut().zip(&col[j + 1..]) {
                    *yi -= lij * yj;
                }
            }
            for j in (0..m).rev() {
                // Column j of Lᵀ above the diagonal: row j of L.
                let col = &lt[j * m..j * m + j];
                let yj = y[j] * d.inv_diag[j];
                y[j] = yj;
                for (yi, lji) in y[..j].iter_mut().zip(col) {
                    *yi -= lji * yj;
                }
            }
            for (a, &ja) in d.index.iter().enumerate() {
                self.f[ja] = d.w[a] * y[a];
            }
        }
        // u = p − S f by columns of S (symmetric): the n_c sums side by
        // side, a node with f = 0 skipped.
        u.copy_from_slice(&self.p);
        for (col, &fj) in s.chunks_exact(n_c).zip(&self.f) {
            if fj != 0.0 {
                for (ui, sij) in u.iter_mut().zip(col) {
                    *ui -= sij * fj;
                }
            }
        }
        Ok(())
    }
}

/// p = Σ_k v_k c_k over the n_c-long columns c_k of `by_mode`, four
/// modes to one addition into p (the chain on p is a quarter as long);
/// the same loops compiled for AVX-512 where the CPU has it (the same
/// operations per entry, so the same bits).
#[allow(unsafe_code)]
fn modal_columns(by_mode: &[f64], v: &[f64], p: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if crate::kernels::avx512() {
        // SAFETY: the CPU has AVX-512 (checked).
        return unsafe { modal_columns_avx512(by_mode, v, p) };
    }
    modal_columns_body(by_mode, v, p);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(unsafe_code)]
fn modal_columns_avx512(by_mode: &[f64], v: &[f64], p: &mut [f64]) {
    modal_columns_body(by_mode, v, p);
}

#[inline(always)]
fn modal_columns_body(by_mode: &[f64], v: &[f64], p: &mut [f64]) {
    let n_c = p.len();
    // Sixteen nodes at a time, summed over all modes in a local array (two
    // registers 8 wide): into p itself, each group of modes waited on
    // storing the last.
    for j0 in (0..n_c).step_by(16) {
        if n_c - j0 >= 16 {
            p[j0..j0 + 16].copy_from_slice(&modal_block::<16>(by_mode, v, n_c, j0));
        } else {
            for (j, x) in p[j0..].iter_mut().enumerate() {
                *x = modal_block::<1>(by_mode, v, n_c, j0 + j)[0];
            }
        }
    }
}

/// Entries j0..j0 + W of p = Σ_k v_k c_k, four modes to one addition.
#[inline(always)]
fn modal_block<const W: usize>(by_mode: &[f64], v: &[f64], n_c: usize, j0: usize) -> [f64; W] {
    let col = |k: usize| -> [f64; W] {
        by_mode[k * n_c + j0..k * n_c + j0 + W]
            .try_into()
            .expect("W values")
    };
    let whole = v.len() / 4 * 4;
    let mut acc = [0.0; W];
    for (k, vk) in v[..whole].chunks_exact(4).enumerate() {
        let (a, b, c, d) = (col(4 * k), col(4 * k + 1), col(4 * k + 2), col(4 * k + 3));
        for j in 0..W {
            acc[j] += (vk[0] * a[j] + vk[1] * b[j]) + (vk[2] * c[j] + vk[3] * d[j]);
        }
    }
    for (k, vk) in v.iter().enumerate().skip(whole) {
        let a = col(k);
        for j in 0..W {
            acc[j] += vk * a[j];
        }
    }
    acc
}

/// The iteration's linear system on the n_c nodal unknowns: for given
/// classes, u + S f = p with f = F (slipping) or D u (stuck).
pub(crate) struct NodalStep<'a> {
    op: &'a mut SchurOperator,
}

impl StepSystem for NodalStep<'_> {
    type Error = SolverError;

    fn solve(
        &mut self,
        surface: &ContactSurface,
        classes: &[SlipState],
        velocity: &mut [f64],
    ) -> Result<(), SolverError> {
        self.op.nodal_solve(surface, classes, velocity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// p = Φ_c v by modes: the dispatched kernel has the scalar body's
    /// bits and is the plain sum to rounding, for node counts around the
    /// 16-node blocks and mode counts around the groups of 4.
    #[test]
    fn modal_columns_is_the_plain_product() {
        for (n, n_c) in [(1, 1), (7, 5), (148, 16), (149, 17), (150, 33)] {
            let by_mode: Vec<f64> = (0..n * n_c)
                .map(|i| ((i * 37) % 101) as f64 / 7.0 - 6.0)
                .collect();
            let v: Vec<f64> = (0..n).map(|k| (k as f64 * 0.3).cos()).collect();
            let (mut fast, mut body) = (vec![0.0; n_c], vec![0.0; n_c]);
            modal_columns(&by_mode, &v, &mut fast);
            modal_columns_body(&by_mode, &v, &mut body);
            assert_eq!(fast, body, "n = {n}, n_c = {n_c}");
            for j in 0..n_c {
                let want: f64 = (0..n).map(|k| v[k] * by_mode[k * n_c + j]).sum();
                assert!((fast[j] - want).abs() < 1e-12, "n = {n}, node {j}");
            }
        }
    }
}
