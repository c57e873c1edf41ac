//! The implicit Newmark step by a Schur complement on the contact DOFs
//! (METHOD.md §4-5).
//!
//! The step's operator is A₀ + C with A₀ = (β/γ)ΔtK + M/(γΔt) and C the
//! damping of the stuck nodes, which lives on the contact tangential DOFs
//! only: C = Pᵀ D P, P the n_c × n restriction whose row J is τ_J on node
//! J's free DOFs, D = diag(w_J g_J/ε) over stuck nodes. So A₀ is factorized
//! once per distinct Δt (one symbolic analysis for the run), and with
//! S = P A₀⁻¹ Pᵀ (dense n_c × n_c) a step is
//!
//! * v₀ = A₀⁻¹ b, needed only at the contact DOFs: p = P v₀;
//! * the nodal tangential velocities u solve u + S f(u) = p, where
//!   f_J = w_J g_J φ_ε(u_J): the stick/slip iteration of §5 with Remark 4.2
//!   runs on these n_c unknowns (a [`ContactSurface`] of unit nodes, so it
//!   is literally [`stickslip_contact::iterate`]); for given classes,
//!   f = F on slipping nodes and f_s = D_s u_s on stuck ones, with u_s from
//!   the SPD system (I + W S_ss W) y = W (p_s − S_sl F_l), W = D_s^{1/2},
//!   f_s = W y;
//! * v = A₀⁻¹(b − Pᵀf) (Woodbury: (A₀ + PᵀDP)v = b − PᵀF gives the same v).
//!
//! The two solves share their work (`stickslip_linalg::Supernodal`): v₀ is
//! only needed at the contact DOFs, and A₀⁻¹(b − Pᵀf) differs from A₀⁻¹b
//! only on the paths from the contact DOFs to the root, so a step is one
//! forward solve, the restricted parts, the iteration, and one back solve.
//! The restricted parts are products with W = L⁻¹Pᵀ, whose columns live on
//! those paths only, where W's 12 bytes a value are fewer than the reach's
//! part of L (8 bytes a value); else solves restricted to the reach.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltError, LltParams};
use faer::{MatMut, Par, Side, Spec};
use nalgebra_sparse::CsrMatrix;
use stickslip_contact::{CompliantNode, ContactNode, ContactSurface, SlipState, StepSystem};
use stickslip_linalg::{csc_view, FillOrder, PathOperator, SolverError, Supernodal};

use super::Operator;
use crate::initial::SharedAnalysis;

/// How many Δt keep their factor (the normal and the reduced step).
const CACHE: usize = 2;

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
    /// W = L⁻¹Pᵀ on its paths (`Supernodal::schur_complement`), when the
    /// step goes through it rather than through solves on the reach.
    paths: Option<PathOperator>,
    /// S and W are made for this factor (a factor made ahead of its
    /// step, [`SchurOperator::factorize_dt`], has them made later).
    schur: bool,
    /// Distinguishes entries for the dense factor's cache.
    id: u64,
    last_used: u64,
}

/// The dense Cholesky factor of I + W S_ss W for one (entry, stuck set).
struct DenseFactor {
    entry_id: u64,
    stuck: Vec<bool>,
    /// The bounds' revision W was formed with.
    revision: u64,
    valid: bool,
    /// Stuck node indices.
    index: Vec<usize>,
    /// W = √(w g/ε) of the stuck nodes.
    w: Vec<f64>,
    /// The factor, column-major n_s × n_s in the first n_s² values.
    l: Vec<f64>,
    /// 1 / the factor's diagonal (the solves multiply: a division's
    /// latency per column would be most of their chains).
    inv_diag: Vec<f64>,
    /// Lᵀ column-major (L by rows), for the back solve by columns.
    lt: Vec<f64>,
    /// The nodes with f ≠ 0 at this solve (slipping).
    slip: Vec<usize>,
    scratch: MemBuffer,
}

/// A₀'s factors per Δt and the Schur complement on the contact DOFs.
pub(crate) struct SchurOperator {
    n: usize,
    analysis: stickslip_linalg::Analysis,
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
    /// Some(true/false) forces the step through W or through solves on
    /// the reach (tests); None picks by bytes.
    use_paths: Option<bool>,
    /// The contact nodes as seen by P.
    nodes: Vec<ContactNode>,
    /// A compliant foundation's nodes: P gains a row ν_J after the n_c
    /// tangential ones for each (`compliance.rs`); empty otherwise.
    pub(super) compliant: Vec<CompliantNode>,
    /// The same nodes as unit nodes on the n_c nodal unknowns, for the
    /// iteration.
    pub reduced: Option<ContactSurface>,
    dense: DenseFactor,
    /// p = P v₀.
    pub(super) p: Vec<f64>,
    /// f of the last solve of the iteration.
    pub(super) f: Vec<f64>,
    pub factorizations: u64,
}

impl SchurOperator {
    /// The analysis of K's pattern its factors use.
    pub(crate) fn analysis(&self) -> &stickslip_linalg::Analysis {
        &self.analysis
    }

    /// Analyses K's pattern (which M shares) once for the run, or takes
    /// its `analysis`, made already.
    pub fn new(
        stiffness: &CsrMatrix<f64>,
        order: &FillOrder,
        analysis: SharedAnalysis,
        contact: Option<&ContactSurface>,
        use_paths: Option<bool>,
    ) -> Result<SchurOperator, SolverError> {
        let n = stiffness.nrows();
        if n != stiffness.ncols() {
            return Err(SolverError::NotSquare {
                rows: n,
                cols: stiffness.ncols(),
            });
        }
        let analysis = stickslip_linalg::Analysis::shared_or_of(analysis, stiffness, order)?;
        let mut sn = Supernodal::new(analysis.symbolic()).ok_or_else(|| {
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
        let compliant = contact.map(|c| c.compliance.clone()).unwrap_or_default();
        let rows = n_c + compliant.len();
        let reduced = contact
            .filter(|_| n_c > 0)
            .map(ContactSurface::on_tangential_unknowns);
        let dense = DenseFactor {
            entry_id: u64::MAX,
            stuck: vec![false; n_c],
            revision: 0,
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
            analysis,
            sn,
            perm,
            correction: Vec::with_capacity(contact_dofs.len()),
            entries: Vec::with_capacity(CACHE),
            current: usize::MAX,
            clock: 0,
            next_id: 0,
            use_paths,
            nodes,
            compliant,
            reduced,
            dense,
            p: vec![0.0; rows],
            f: vec![0.0; rows],
            factorizations: 0,
        })
    }

    /// Values of L held per Δt.
    pub fn factor_len(&self) -> usize {
        self.analysis.symbolic().len_val()
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
    /// cache, or factorized (with S and W) once.
    pub fn set_dt(&mut self, operator: Operator) -> Result<(), SolverError> {
        self.factorize_dt(operator)?;
        if !self.entries[self.current].schur {
            self.build_schur(self.current);
        }
        Ok(())
    }

    /// [`Self::set_dt`] without S and W, which the next `set_dt` of this
    /// Δt makes: the factorization alone runs on the calling thread
    /// (faer's kernels), S and W on the pool.
    pub fn factorize_dt(&mut self, operator: Operator) -> Result<(), SolverError> {
        self.clock += 1;
        let bits = operator.dt.to_bits();
        if let Some(k) = self.entries.iter().position(|e| e.dt_bits == bits) {
            self.current = k;
            self.entries[k].last_used = self.clock;
            return Ok(());
        }
        // A₀'s values (K and M share one pattern) and the factorization's
        // workspace live only while it runs: the step holds K, M and the
        // factors, not a third matrix.
        let a0: Vec<f64> = operator.values().collect();
        let mut factor_scratch = MemBuffer::new(
            self.analysis
                .symbolic()
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        );
        let slot = self.free_slot(bits);
        let entry = &mut self.entries[slot];
        entry.dt_bits = u64::MAX; // invalid until factorized
        let result = self.analysis.symbolic().factorize_numeric_llt(
            &mut entry.l_values,
            csc_view(operator.k, &a0),
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
        Ok(())
    }

    /// Entry `slot`, formed for Δt `bits`, becomes the current one: a new
    /// id (for the dense factor's cache) and one more factorization.
    fn make_current(&mut self, slot: usize, bits: u64) {
        let entry = &mut self.entries[slot];
        entry.dt_bits = bits;
        entry.schur = false;
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
                l_values: vec![0.0; self.analysis.symbolic().len_val()],
                s: Vec::new(),
                paths: None,
                schur: false,
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

    /// S = P A₀⁻¹ Pᵀ (and W) for entry `slot`: W = L⁻¹Pᵀ by forward solves
    /// on the contact DOFs' paths, eight columns per pass, and S = WᵀW
    /// (`Supernodal::schur_complement`; S is made exactly symmetric here).
    fn build_schur(&mut self, slot: usize) {
        let n_c = self.rows();
        let entry = &mut self.entries[slot];
        entry.schur = true;
        entry.s.clear();
        entry.s.resize(n_c * n_c, 0.0);
        entry.paths = None;
        if n_c == 0 {
            return;
        }
        let row = |node: &ContactNode, along: [f64; 2]| -> Vec<(usize, f64)> {
            node.dofs
                .iter()
                .zip(along)
                .filter_map(|(d, t)| d.map(|i| (self.perm[i], t)))
                .collect()
        };
        let rows: Vec<Vec<(usize, f64)>> = self
            .nodes
            .iter()
            .map(|node| row(node, node.tangent))
            .chain(
                self.compliant
                    .iter()
                    .map(|c| row(&self.nodes[c.index], c.normal)),
            )
            .collect();
        let mut op = self.sn.schur_complement(&entry.l_values, &rows);
        entry.s = std::mem::take(&mut op.s);
        symmetrize(&mut entry.s, n_c);
        // W (12 bytes a value) against the reach's part of L (8): whichever
        // streams fewer bytes serves the step.
        let paths = self
            .use_paths
            .unwrap_or(12 * op.w_len() < 8 * self.sn.reach_len());
        entry.paths = paths.then_some(op);
    }

    /// Rows of P: the n_c tangential ones, then a compliant node's normal.
    pub(super) fn rows(&self) -> usize {
        self.nodes.len() + self.compliant.len()
    }

    /// S = P A₀⁻¹ Pᵀ of the current Δt, column-major, [`Self::rows`]
    /// square.
    pub(super) fn schur(&self) -> &[f64] {
        &self.entries[self.current].s
    }

    fn solve(&mut self, x: &mut [f64]) {
        let entry = &self.entries[self.current];
        self.sn.solve(&entry.l_values, x);
    }

    /// v = A₀⁻¹ b without friction.
    pub fn solve_plain(&mut self, b: &[f64], v: &mut [f64]) {
        v.copy_from_slice(b);
        self.solve(v);
    }

    /// p = P A₀⁻¹ b: the start of a step with friction ([`Self::finish`]
    /// ends it).
    pub fn begin(&mut self, b: &[f64]) {
        let entry = &self.entries[self.current];
        if let Some(op) = &entry.paths {
            self.sn.begin_paths(&entry.l_values, op, b, &mut self.p);
            return;
        }
        self.sn.begin_reach(&entry.l_values, b);
        for (p, node) in self.p.iter_mut().zip(&self.nodes) {
            let mut sum = 0.0;
            for (d, t) in node.dofs.iter().zip(node.tangent) {
                if let Some(i) = d {
                    sum += t * self.sn.reach_value(self.perm[*i]);
                }
            }
            *p = sum;
        }
        let n_c = self.nodes.len();
        for (p, c) in self.p[n_c..].iter_mut().zip(&self.compliant) {
            let node = &self.nodes[c.index];
            let mut sum = 0.0;
            for (d, n) in node.dofs.iter().zip(c.normal) {
                if let Some(i) = d {
                    sum += n * self.sn.reach_value(self.perm[*i]);
                }
            }
            *p = sum;
        }
    }

    /// The nodal system of this step for the iteration.
    pub fn nodal_system(&mut self) -> NodalStep<'_> {
        NodalStep { op: self }
    }

    /// v = A₀⁻¹(b − Pᵀf) with the f of the converged iteration.
    pub fn finish(&mut self, v: &mut [f64]) {
        let entry = &self.entries[self.current];
        if let Some(op) = &entry.paths {
            self.sn.finish_paths(&entry.l_values, op, &self.f, v);
            return;
        }
        self.correction.clear();
        for (node, f) in self.nodes.iter().zip(&self.f) {
            for (d, t) in node.dofs.iter().zip(node.tangent) {
                if let Some(i) = d {
                    self.correction.push((self.perm[*i], f * t));
                }
            }
        }
        let n_c = self.nodes.len();
        for (c, f) in self.compliant.iter().zip(&self.f[n_c..]) {
            for (d, n) in self.nodes[c.index].dofs.iter().zip(c.normal) {
                if let Some(i) = d {
                    self.correction.push((self.perm[*i], f * n));
                }
            }
        }
        self.sn.finish_reach(&entry.l_values, &self.correction, v);
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
            && d.revision == reduced.revision
            && d.stuck.iter().zip(classes).all(|(&k, c)| k == c.is_stuck());
        if !same {
            d.valid = false;
            d.index.clear();
            d.w.clear();
            for (j, (node, c)) in reduced.nodes.iter().zip(classes).enumerate() {
                d.stuck[j] = c.is_stuck();
                if c.is_stuck() {
                    d.index.push(j);
                    d.w.push(node.stuck_damping(&reduced.law_of(j)).sqrt());
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
            d.revision = reduced.revision;
            d.valid = true;
        }
        let m = d.index.len();
        if m > 0 {
            // y = (I + W S_ss W)⁻¹ W (p_s − S_s· F); f_s = W y.
            let y = &mut u[..m];
            d.slip.clear();
            d.slip.extend((0..n_c).filter(|&j| self.f[j] != 0.0));
            for (a, &ja) in d.index.iter().enumerate() {
                // A stuck node's force D(u − V): the slip p − V on the
                // right (METHOD.md §9), p itself at rest.
                let mut r = reduced.slip(ja, self.p[ja]);
                for &j in &d.slip {
                    r -= s[j * n_c + ja] * self.f[j];
                }
                y[a] = d.w[a] * r;
            }
            // L Lᵀ y = rhs by plain loops: at n_s ≤ n_c (16 on the paper
            // mesh) faer's dispatch cost more than the 2·n_s² operations.
            // Both by columns: a column's updates are independent, so a
            // step waits on one multiplication, where a back solve by rows
            // sums each row in a chain (docs/performance.md).
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
