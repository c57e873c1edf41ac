//! Forward and back substitution with faer's supernodal LLᵀ factor, for
//! one right-hand side.
//!
//! faer's own solve handles a block of right-hand sides through its
//! general triangular-solve and matmul kernels; for one column its
//! per-supernode dispatch and temporaries cost more than the arithmetic.
//! Here each supernode is a column-major (k + m) × k block, the k × k
//! diagonal triangle above the m rows of its pattern, and the loops run
//! straight over its columns: the forward solve pushes L_bot x_top into the
//! pattern rows (a contiguous axpy per column, then one scatter), the back
//! solve gathers the pattern rows once and takes contiguous dot products.
//!
//! Solves restricted to a few rows P of the system: (A⁻¹b) at those rows,
//! and A⁻¹Pᵀf whose right-hand side lives on them, involve only the
//! supernodes on the paths from their supernodes to the root (a column's
//! solution in the back solve depends only on its ancestors; a forward push
//! from a supernode only reaches its ancestors), the *reach*. A solve
//! with a correction on those rows then costs one full forward solve, the
//! reach's share twice, and one full back solve ([`Supernodal::begin_reach`],
//! [`Supernodal::finish_reach`]), or with the rows' paths stored
//! ([`PathOperator`]) one pass over W instead of the reach's solves.

use faer::linalg::matmul::matmul;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::{Accum, Mat, Par};
use rayon::prelude::*;

/// A value of the factor the solves read: f64, or f32 for a factor
/// computed in single precision (the preconditioner of a refined solve,
/// `refine.rs`), each read as f64 and the arithmetic done in double: for
/// f64 the conversion is the identity, so a double factor's solves keep
/// their bits.
pub trait FactorValue: Copy + Into<f64> + Send + Sync {}

impl FactorValue for f64 {}

impl FactorValue for f32 {}

/// P A⁻¹ Pᵀ and W = L⁻¹ Perm Pᵀ for the rows of P given to
/// [`Supernodal::schur_complement`]: S dense (column-major p × p), W by
/// columns on the permuted indices. Each column of W is nonzero only on the
/// paths from its DOFs to the root, so W is a fraction of the reach's part
/// of L, and p = Wᵀy, the correction W f replace the two solves restricted
/// to the reach.
#[derive(Clone, Debug, Default)]
pub struct PathOperator {
    /// S = P A⁻¹ Pᵀ, column-major.
    pub s: Vec<f64>,
    w_ptr: Vec<usize>,
    w_idx: Vec<u32>,
    w_val: Vec<f64>,
}

impl PathOperator {
    /// Stored values of W.
    pub fn w_len(&self) -> usize {
        self.w_val.len()
    }
}

/// W's products go to the thread pool from this many values (the same
/// arithmetic either way; below it a dispatch costs more than the pass).
const PATHS_PARALLEL_MIN: usize = 1 << 16;

/// One column of W: (reach-local index, value) on its paths.
type PathColumn = Vec<(u32, f64)>;

/// Columns solved together by [`Supernodal::schur_complement`].
const GROUP: usize = 8;

/// One thread's scratch for [`Supernodal::schur_complement`]'s groups: the
/// group's columns interleaved on the reach, a supernode's rows, and the
/// supernodes on the group's paths to the root.
struct GroupScratch {
    x: Vec<f64>,
    tmp: Vec<f64>,
    on_path: Vec<bool>,
    path: Vec<u32>,
}

/// Marks the supernodes from `from` up to the root of the tree `parent`,
/// stopping at one marked already, and gives each newly marked one to
/// `visit`.
fn up_to_root(
    parent: &[Option<usize>],
    from: usize,
    marked: &mut [bool],
    mut visit: impl FnMut(usize),
) {
    let mut s = Some(from);
    while let Some(k) = s.filter(|&k| !marked[k]) {
        marked[k] = true;
        visit(k);
        s = parent[k];
    }
}

/// Owner of a column that belongs to neither thread's subtrees.
const TOP: u8 = 2;

/// Factors from this many values split the tree between two threads; below
/// it a thread's dispatch costs more than the passes.
const SPLIT_MIN: usize = 1 << 20;

/// Supernodes to visit, ascending: two groups of disjoint subtrees (one per
/// thread) and the rest (the top of the tree, visited on the calling
/// thread after the groups in the forward solve, before them in the back
/// solve).
#[derive(Default)]
struct Plan {
    bins: [Vec<u32>; 2],
    top: Vec<u32>,
}

/// One thread's working copy of its columns, its pushes into the top
/// columns and its pattern buffer.
#[derive(Default)]
struct BinScratch {
    x: Vec<f64>,
    acc: Vec<f64>,
    tmp: Vec<f64>,
}

/// The structure of a supernodal factor, copied out of faer's symbolic
/// factor (u32 row indices: half the index bytes of the scatter/gather),
/// and the split of its tree between two threads.
///
/// The split is a property of the factor, not of the number of threads:
/// each group's arithmetic is the same whether the groups run in turn or
/// at once, so results do not depend on the thread count.
pub struct Supernodal {
    n: usize,
    /// x_perm[i] = x[fwd[i]].
    fwd: Vec<u32>,
    /// Supernode s owns columns begin[s]..begin[s + 1].
    begin: Vec<usize>,
    /// Pattern (rows below the diagonal block) of s: rows[row_ptr[s]..row_ptr[s + 1]].
    row_ptr: Vec<usize>,
    rows: Vec<u32>,
    /// Values of s: l[val_ptr[s]..val_ptr[s + 1]].
    val_ptr: Vec<usize>,
    /// Per column: its group (0, 1) or TOP, and its index in the group's
    /// columns or in the top columns.
    owner: Vec<u8>,
    slot: Vec<u32>,
    bin_cols: [Vec<u32>; 2],
    top_cols: Vec<u32>,
    full: Plan,
    reach: Plan,
    /// Values of L inside the reach.
    reach_len: usize,
    /// The reach's supernodes, ascending, and its columns' local numbering
    /// (u32::MAX outside the reach).
    reach_list: Vec<u32>,
    reach_local: Vec<u32>,
    reach_global: Vec<u32>,
    reach_cols: usize,
    /// The permuted vector, the reach solution, the reach correction.
    xp: Vec<f64>,
    xr: Vec<f64>,
    w: Vec<f64>,
    tmp: Vec<f64>,
    scratch: [BinScratch; 2],
}

impl std::fmt::Debug for Supernodal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Supernodal")
            .field("n", &self.n)
            .field("supernodes", &self.supernodes())
            .field("values", &self.val_ptr.last())
            .field("split", &self.is_split())
            .finish()
    }
}

impl Supernodal {
    /// The solver for `symbolic`'s layout (`None` only for a layout it does
    /// not know).
    pub fn new(symbolic: &SymbolicCholesky<usize>) -> Option<Supernodal> {
        Supernodal::with_split_min(symbolic, SPLIT_MIN)
    }

    /// As [`Supernodal::new`], splitting the tree from `split_min` values.
    pub fn with_split_min(
        symbolic: &SymbolicCholesky<usize>,
        split_min: usize,
    ) -> Option<Supernodal> {
        let n = symbolic.nrows();
        let (begin, row_ptr, rows, val_ptr): (Vec<usize>, Vec<usize>, Vec<u32>, Vec<usize>) =
            match symbolic.raw() {
                SymbolicCholeskyRaw::Supernodal(sym) => {
                    let ns = sym.n_supernodes();
                    let mut begin: Vec<usize> = sym.supernode_begin().to_vec();
                    begin.push(n);
                    // faer packs the patterns: row_ptr[s + 1] − row_ptr[s] is
                    // s's length.
                    (
                        begin,
                        sym.col_ptr_for_row_idx()[..=ns].to_vec(),
                        sym.row_idx().iter().map(|&r| r as u32).collect(),
                        sym.col_ptr_for_val()[..=ns].to_vec(),
                    )
                }
                SymbolicCholeskyRaw::Simplicial(sym) => {
                    // faer keeps tiny factors simplicial even when asked for
                    // supernodes: a column with its diagonal first is a
                    // supernode of one column in the same layout.
                    let (col_ptr, row_idx) = (sym.col_ptr(), sym.row_idx());
                    let mut row_ptr = vec![0];
                    let mut rows = Vec::with_capacity(row_idx.len());
                    for j in 0..n {
                        let col = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                        if col.first() != Some(&j) {
                            return None;
                        }
                        rows.extend(col[1..].iter().map(|&r| r as u32));
                        row_ptr.push(rows.len());
                    }
                    ((0..=n).collect(), row_ptr, rows, col_ptr.to_vec())
                }
            };
        let ns = begin.len() - 1;
        let fwd: Vec<u32> = match symbolic.perm() {
            Some(p) => p.arrays().0.iter().map(|&i| i as u32).collect(),
            None => (0..n as u32).collect(),
        };
        let max_pattern = (0..ns)
            .map(|s| row_ptr[s + 1] - row_ptr[s])
            .max()
            .unwrap_or(0);
        let mut this = Supernodal {
            n,
            fwd,
            begin,
            row_ptr,
            rows,
            val_ptr,
            owner: vec![TOP; n],
            slot: vec![0; n],
            bin_cols: Default::default(),
            top_cols: Vec::new(),
            full: Plan::default(),
            reach: Plan::default(),
            reach_len: 0,
            reach_list: Vec::new(),
            reach_local: Vec::new(),
            reach_global: Vec::new(),
            reach_cols: 0,
            xp: vec![0.0; n],
            xr: vec![0.0; n],
            w: vec![0.0; n],
            tmp: vec![0.0; max_pattern],
            scratch: Default::default(),
        };
        this.split_tree(split_min);
        this.reach = Plan {
            bins: this.full.bins.clone(),
            top: this.full.top.clone(),
        };
        this.reach_len = this.val_ptr[ns];
        Some(this)
    }

    /// Number of supernodes (columns, for a simplicial factor).
    pub fn supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    fn len(&self, s: usize) -> usize {
        self.val_ptr[s + 1] - self.val_ptr[s]
    }

    /// The supernode owning each (permuted) column.
    fn column_owners(&self) -> Vec<u32> {
        let mut owner = vec![0u32; self.n];
        for s in 0..self.supernodes() {
            owner[self.begin[s]..self.begin[s + 1]].fill(s as u32);
        }
        owner
    }

    /// The parent of each supernode: the one holding its first pattern row
    /// (`owner`: [`Supernodal::column_owners`]).
    fn parents(&self, owner: &[u32]) -> Vec<Option<usize>> {
        (0..self.supernodes())
            .map(|s| {
                let pattern = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
                pattern.iter().min().map(|&r| owner[r as usize] as usize)
            })
            .collect()
    }

    /// Splits the tree into two groups of subtrees of about equal weight
    /// (values of L) and a top: starting from the roots, the heaviest
    /// subtree is opened (its root goes to the top, its children become
    /// candidates) while that lowers max(group) + top, the time of a solve
    /// on two threads.
    fn split_tree(&mut self, split_min: usize) {
        let ns = self.supernodes();
        let total: usize = self.val_ptr[ns];
        let mut group = vec![TOP; ns];
        if total >= split_min {
            let parent = self.parents(&self.column_owners());
            let mut children = vec![Vec::new(); ns];
            let mut weight: Vec<usize> = (0..ns).map(|s| self.len(s)).collect();
            let mut roots = Vec::new();
            for s in 0..ns {
                match parent[s] {
                    Some(p) => {
                        children[p].push(s);
                        weight[p] += weight[s];
                    }
                    None => roots.push(s),
                }
            }
            let mut candidates = roots;
            let mut top: Vec<usize> = Vec::new();
            let mut top_weight = 0;
            let mut best: Option<(usize, Vec<usize>, Vec<[usize; 2]>)> = None;
            for _ in 0..256 {
                candidates.sort_by_key(|&s| std::cmp::Reverse((weight[s], s)));
                // Longest processing time first into the lighter group.
                let mut loads = [0usize; 2];
                let mut assign = Vec::with_capacity(candidates.len());
                for &s in &candidates {
                    let g = usize::from(loads[1] < loads[0]);
                    loads[g] += weight[s];
                    assign.push([s, g]);
                }
                let cost = loads[0].max(loads[1]) + top_weight;
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, top.clone(), assign));
                }
                let Some(&h) = candidates.first() else { break };
                if weight[h] * 8 < total {
                    break;
                }
                candidates.remove(0);
                top.push(h);
                top_weight += self.len(h);
                candidates.extend(&children[h]);
            }
            if let Some((cost, _top, assign)) = best {
                // Splitting pays only if it saves a fifth of a solve.
                if cost * 5 < total * 4 {
                    for [s, g] in assign {
                        group[s] = g as u8;
                    }
                    // Descendants follow their subtree's root; the top and
                    // the parents come later in the descending walk.
                    for s in (0..ns).rev() {
                        if group[s] == TOP {
                            if let Some(p) = parent[s] {
                                if group[p] != TOP {
                                    group[s] = group[p];
                                }
                            }
                        }
                    }
                }
            }
        }
        let mut counts = [0u32; 3];
        for s in 0..ns {
            let g = group[s];
            for c in self.begin[s]..self.begin[s + 1] {
                self.owner[c] = g;
                self.slot[c] = counts[g as usize];
                counts[g as usize] += 1;
                match g {
                    TOP => self.top_cols.push(c as u32),
                    _ => self.bin_cols[g as usize].push(c as u32),
                }
            }
            match g {
                TOP => self.full.top.push(s as u32),
                _ => self.full.bins[g as usize].push(s as u32),
            }
        }
        for (b, sc) in self.scratch.iter_mut().enumerate() {
            if !self.full.bins[b].is_empty() {
                sc.x = vec![0.0; self.bin_cols[b].len()];
                sc.acc = vec![0.0; self.top_cols.len()];
                sc.tmp = vec![0.0; self.tmp.len()];
            }
        }
    }

    /// Marks the supernodes on the paths from the supernodes holding `dofs`
    /// (unpermuted indices) to the root.
    pub fn set_reach(&mut self, dofs: &[usize]) {
        let ns = self.supernodes();
        let owner = self.column_owners();
        let parent = self.parents(&owner);
        let mut inv = vec![0usize; self.n];
        for (i, &f) in self.fwd.iter().enumerate() {
            inv[f as usize] = i;
        }
        let mut marked = vec![false; ns];
        for &d in dofs {
            up_to_root(&parent, owner[inv[d]] as usize, &mut marked, |_| {});
        }
        let keep = |list: &[u32]| -> Vec<u32> {
            list.iter()
                .copied()
                .filter(|&s| marked[s as usize])
                .collect()
        };
        self.reach = Plan {
            bins: [keep(&self.full.bins[0]), keep(&self.full.bins[1])],
            top: keep(&self.full.top),
        };
        self.reach_len = (0..ns).filter(|&s| marked[s]).map(|s| self.len(s)).sum();
        self.reach_list = (0..ns).filter(|&s| marked[s]).map(|s| s as u32).collect();
        self.reach_local = vec![u32::MAX; self.n];
        self.reach_global.clear();
        let mut next = 0u32;
        for &s in &self.reach_list {
            for c in self.begin[s as usize]..self.begin[s as usize + 1] {
                self.reach_local[c] = next;
                self.reach_global.push(c as u32);
                next += 1;
            }
        }
        self.reach_cols = next as usize;
        // `finish_paths` keeps two sums on the reach in `w`.
        let len = self.n.max(2 * self.reach_cols);
        self.w.resize(len, 0.0);
    }

    /// G = P A⁻¹ Pᵀ (column-major, p × p) for the p sparse rows of P given
    /// as (permuted index, value) lists, whose indices must lie in the
    /// DOFs given to [`Supernodal::set_reach`].
    ///
    /// G = WᵀW with W = L⁻¹Pᵀ, whose column j lies on the paths from row
    /// j's DOFs to the root: a forward solve restricted to those paths
    /// ([`Supernodal::gram`] forms the product; no back solve). `GROUP`
    /// columns go through each supernode together (its values are read
    /// once per group and the inner loops run over the group), groups in
    /// parallel from [`PATHS_PARALLEL_MIN`] reach values (p times the
    /// reach's DOFs); a column's arithmetic is the same on any thread.
    pub fn schur_complement(&self, l: &[f64], rows: &[Vec<(usize, f64)>]) -> PathOperator {
        let p = rows.len();
        let groups: Vec<usize> = (0..p).step_by(GROUP).collect();
        let owner = self.column_owners();
        let parent = self.parents(&owner);
        let scratch = || GroupScratch {
            x: vec![0.0; self.reach_cols * GROUP],
            tmp: vec![0.0; self.tmp.len() * GROUP],
            on_path: vec![false; self.supernodes()],
            path: Vec::new(),
        };
        let column = |sc: &mut GroupScratch, &start: &usize| {
            let GroupScratch {
                x,
                tmp,
                on_path,
                path,
            } = sc;
            let width = GROUP.min(p - start);
            path.clear();
            for c in 0..width {
                for &(i, v) in &rows[start + c] {
                    x[self.reach_local[i] as usize * GROUP + c] += v;
                    up_to_root(&parent, owner[i] as usize, on_path, |k| path.push(k as u32));
                }
            }
            // The forward solve's right-hand sides live on the paths from
            // their rows to the root, and so does its solution (a column's
            // pattern holds only its ancestors): the reach's other
            // supernodes would only add zeros.
            path.sort_unstable();
            for &s in path.iter() {
                on_path[s as usize] = false;
                self.group_forward(l, s as usize, x, tmp);
            }
            // W's columns, L⁻¹Pᵀe_j, on those paths, by ascending local
            // index (the reach numbers its supernodes' columns in order);
            // x is zero again after them.
            let local = |s: &u32| {
                let (a, e) = (self.begin[*s as usize], self.begin[*s as usize + 1]);
                let first = self.reach_local[a] as usize;
                first..first + (e - a)
            };
            let w: Vec<PathColumn> = (0..width)
                .map(|c| {
                    path.iter()
                        .flat_map(local)
                        .filter_map(|li| {
                            let v = x[li * GROUP + c];
                            (v != 0.0).then_some((li as u32, v))
                        })
                        .collect()
                })
                .collect();
            for li in path.iter().flat_map(local) {
                x[li * GROUP..(li + 1) * GROUP].fill(0.0);
            }
            w
        };
        // On the pool where the reach is large (as W's products): a small
        // model starts no threads.
        let columns: Vec<Vec<PathColumn>> = if p * self.reach_cols >= PATHS_PARALLEL_MIN {
            groups.par_iter().map_init(scratch, column).collect()
        } else {
            let mut state = scratch();
            groups.iter().map(|g| column(&mut state, g)).collect()
        };
        let columns: Vec<PathColumn> = columns.into_iter().flatten().collect();
        let mut op = PathOperator {
            s: self.gram(&columns),
            w_ptr: vec![0],
            w_idx: Vec::new(),
            w_val: Vec::new(),
        };
        for col in columns {
            for (i, v) in col {
                op.w_idx.push(i);
                op.w_val.push(v);
            }
            op.w_ptr.push(op.w_idx.len());
        }
        op
    }

    /// WᵀW (column-major, p × p) for W's p columns on the reach: P A⁻¹ Pᵀ =
    /// (L⁻¹Pᵀ)ᵀ(L⁻¹Pᵀ). By the reach's supernodes in ascending order: the
    /// rows of one supernode hold the columns whose paths pass it, a dense
    /// block B (consecutive supernodes with the same columns together),
    /// and BᵀB (faer's product, on this thread) is added to those columns'
    /// entries, so the sums' order depends on the factor only.
    fn gram(&self, w: &[PathColumn]) -> Vec<f64> {
        let p = w.len();
        // W by rows of the reach: (column, value), columns ascending.
        let mut ptr = vec![0usize; self.reach_cols + 1];
        for col in w {
            for &(i, _) in col {
                ptr[i as usize + 1] += 1;
            }
        }
        for i in 0..self.reach_cols {
            ptr[i + 1] += ptr[i];
        }
        let mut next = ptr.clone();
        let mut entries = vec![(0u32, 0.0); ptr[self.reach_cols]];
        for (j, col) in w.iter().enumerate() {
            for &(i, v) in col {
                entries[next[i as usize]] = (j as u32, v);
                next[i as usize] += 1;
            }
        }
        let mut s = vec![0.0; p * p];
        let mut at = vec![u32::MAX; p];
        // BᵀB of the block of rows `rows`, whose entries lie in `cols`
        // (ascending), added to S.
        let mut add = |rows: std::ops::Range<usize>, cols: &[u32]| {
            for (a, &j) in cols.iter().enumerate() {
                at[j as usize] = a as u32;
            }
            let mut b = Mat::<f64>::zeros(rows.len(), cols.len());
            for (r, row) in rows.enumerate() {
                for &(j, v) in &entries[ptr[row]..ptr[row + 1]] {
                    b[(r, at[j as usize] as usize)] = v;
                }
            }
            let mut g = Mat::<f64>::zeros(cols.len(), cols.len());
            matmul(
                g.as_mut(),
                Accum::Replace,
                b.transpose(),
                b.as_ref(),
                1.0,
                Par::Seq,
            );
            for (a, &ja) in cols.iter().enumerate() {
                for (c, &jc) in cols.iter().enumerate() {
                    s[jc as usize * p + ja as usize] += g[(a, c)];
                }
            }
        };
        // Consecutive supernodes whose rows hold the same columns (the
        // chain at the top of the tree, every column's path) make one
        // block: one product and one pass over S for the run.
        let (mut run, mut run_cols): (Option<std::ops::Range<usize>>, Vec<u32>) =
            (None, Vec::new());
        let mut cols: Vec<u32> = Vec::new();
        let mut first = 0;
        for &sn in &self.reach_list {
            let k = self.begin[sn as usize + 1] - self.begin[sn as usize];
            let rows = first..first + k;
            first += k;
            cols.clear();
            cols.extend(
                entries[ptr[rows.start]..ptr[rows.end]]
                    .iter()
                    .map(|&(j, _)| j),
            );
            cols.sort_unstable();
            cols.dedup();
            match run.as_mut() {
                Some(r) if cols == run_cols => r.end = rows.end,
                _ => {
                    if let Some(r) = run.take() {
                        add(r, &run_cols);
                    }
                    if !cols.is_empty() {
                        run = Some(rows);
                        std::mem::swap(&mut run_cols, &mut cols);
                    }
                }
            }
        }
        if let Some(r) = run {
            add(r, &run_cols);
        }
        s
    }

    /// A restricted solve's start with a [`PathOperator`]: the forward solve
    /// y = L⁻¹(Perm b) into the internal vector and p_j = W_jᵀ y = (P A⁻¹ b)_j
    /// (one pass over W instead of a back solve over the reach; the rows
    /// in parallel, each its own sum).
    pub fn begin_paths(&mut self, l: &[f64], op: &PathOperator, b: &[f64], p: &mut [f64]) {
        let mut xp = std::mem::take(&mut self.xp);
        permute_in(&self.fwd, b, &mut xp);
        self.forward(l, false, &mut xp);
        let mut yr = std::mem::take(&mut self.xr);
        for (y, &g) in yr.iter_mut().zip(&self.reach_global) {
            *y = xp[g as usize];
        }
        let yr_ref = &yr;
        let row = |(j, pj): (usize, &mut f64)| {
            let (a, e) = (op.w_ptr[j], op.w_ptr[j + 1]);
            *pj = op.w_idx[a..e]
                .iter()
                .zip(&op.w_val[a..e])
                .map(|(&i, v)| v * yr_ref[i as usize])
                .sum();
        };
        if op.w_len() >= PATHS_PARALLEL_MIN {
            p.par_iter_mut().enumerate().with_min_len(8).for_each(row);
        } else {
            p.iter_mut().enumerate().for_each(row);
        }
        self.xr = yr;
        self.xp = xp;
    }

    /// A restricted solve's end: x = A⁻¹(b − Pᵀf) = Perm⁻¹ L⁻ᵀ(y − W f). W f in two
    /// halves of its columns at once, each into its own sums on the reach,
    /// added in a fixed order (the same bits on one thread and on two).
    pub fn finish_paths(&mut self, l: &[f64], op: &PathOperator, f: &[f64], x: &mut [f64]) {
        let mut xp = std::mem::take(&mut self.xp);
        let half = f.len() / 2;
        let mut acc = std::mem::take(&mut self.w);
        let (a0, a1) = acc[..2 * self.reach_cols].split_at_mut(self.reach_cols);
        let scatter = |cols: std::ops::Range<usize>, acc: &mut [f64]| {
            acc.fill(0.0);
            for j in cols {
                let fj = f[j];
                if fj != 0.0 {
                    let (a, e) = (op.w_ptr[j], op.w_ptr[j + 1]);
                    for (&i, v) in op.w_idx[a..e].iter().zip(&op.w_val[a..e]) {
                        acc[i as usize] += v * fj;
                    }
                }
            }
        };
        if op.w_len() >= PATHS_PARALLEL_MIN {
            rayon::join(|| scatter(0..half, a0), || scatter(half..f.len(), a1));
        } else {
            scatter(0..half, a0);
            scatter(half..f.len(), a1);
        }
        for ((&g, s0), s1) in self.reach_global.iter().zip(a0.iter()).zip(a1.iter()) {
            xp[g as usize] -= s0 + s1;
        }
        self.w = acc;
        self.backward(l, false, &mut xp);
        permute_out(&self.fwd, &xp, x);
        self.xp = xp;
    }

    /// The permutation: `x_perm[i] = x[fwd[i]]`.
    pub fn forward_permutation(&self) -> &[u32] {
        &self.fwd
    }

    /// Supernode s's first (permuted) column.
    pub fn first_column(&self, s: usize) -> usize {
        self.begin[s]
    }

    /// Supernode s's pattern: the permuted rows below its diagonal block.
    pub fn pattern(&self, s: usize) -> &[u32] {
        &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]]
    }

    /// Supernode s's number of columns and pattern length.
    pub fn block_shape(&self, s: usize) -> (usize, usize) {
        (
            self.begin[s + 1] - self.begin[s],
            self.row_ptr[s + 1] - self.row_ptr[s],
        )
    }

    /// Where supernode s's block lies in the factor's values.
    pub(crate) fn value_range(&self, s: usize) -> std::ops::Range<usize> {
        self.val_ptr[s]..self.val_ptr[s + 1]
    }

    /// The forward solve L y = x on the permuted numbering, in place.
    pub(crate) fn forward_permuted<T: FactorValue>(&mut self, l: &[T], x: &mut [f64]) {
        self.forward(l, false, x);
    }

    /// The back solve Lᵀ x = y on the permuted numbering, in place.
    pub(crate) fn backward_permuted<T: FactorValue>(&mut self, l: &[T], x: &mut [f64]) {
        self.backward(l, false, x);
    }

    /// Supernode s of the factor with values `l`, for solvers built on
    /// this layout: its first (permuted) column, its number of columns k,
    /// its pattern (the m permuted rows below its diagonal block) and its
    /// block of L, column-major (k + m) × k.
    pub fn block<'a>(&'a self, l: &'a [f64], s: usize) -> (usize, usize, &'a [u32], &'a [f64]) {
        self.supernode(l, s)
    }

    /// Supernode s: its first column, its number of columns, its pattern
    /// and its block of L.
    #[inline]
    fn supernode<'a>(&'a self, l: &'a [f64], s: usize) -> (usize, usize, &'a [u32], &'a [f64]) {
        let c0 = self.begin[s];
        (
            c0,
            self.begin[s + 1] - c0,
            &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]],
            &l[self.val_ptr[s]..self.val_ptr[s + 1]],
        )
    }

    /// [`Supernodal::forward`]'s step for GROUP interleaved columns on the
    /// reach's local numbering (x[local·GROUP + c]).
    fn group_forward(&self, l: &[f64], s: usize, x: &mut [f64], tmp: &mut [f64]) {
        let (c0, k, pattern, block) = self.supernode(l, s);
        let m = pattern.len();
        let ld = k + m;
        let lo = self.reach_local[c0] as usize * GROUP;
        let xs = &mut x[lo..lo + k * GROUP];
        for j in 0..k {
            let col = &block[j * ld..j * ld + k];
            let (head, tail) = xs.split_at_mut((j + 1) * GROUP);
            let xj = &mut head[j * GROUP..];
            for v in xj.iter_mut() {
                *v /= col[j];
            }
            for (xi, lij) in tail.chunks_exact_mut(GROUP).zip(&col[j + 1..]) {
                for (a, b) in xi.iter_mut().zip(xj.iter()) {
                    *a -= lij * b;
                }
            }
        }
        if m == 0 {
            return;
        }
        let tmp = &mut tmp[..m * GROUP];
        tmp.fill(0.0);
        for j in 0..k {
            let xj = &xs[j * GROUP..(j + 1) * GROUP];
            for (t, lrj) in tmp
                .chunks_exact_mut(GROUP)
                .zip(&block[j * ld + k..(j + 1) * ld])
            {
                for (a, b) in t.iter_mut().zip(xj) {
                    *a += lrj * b;
                }
            }
        }
        for (&r, t) in pattern.iter().zip(tmp.chunks_exact(GROUP)) {
            let at = self.reach_local[r as usize] as usize * GROUP;
            for (a, b) in x[at..at + GROUP].iter_mut().zip(t) {
                *a -= b;
            }
        }
    }

    /// Columns inside the reach.
    pub fn reach_columns(&self) -> usize {
        self.reach_cols
    }

    /// Values of L inside the reach (for the cost figures).
    pub fn reach_len(&self) -> usize {
        self.reach_len
    }

    /// True when the solves run on two groups of subtrees.
    pub fn is_split(&self) -> bool {
        !self.full.bins[0].is_empty()
    }

    /// x ← A⁻¹x with the factor values `l` (double, or single read as
    /// double: [`FactorValue`]).
    pub fn solve<T: FactorValue>(&mut self, l: &[T], x: &mut [f64]) {
        let mut xp = std::mem::take(&mut self.xp);
        permute_in(&self.fwd, x, &mut xp);
        self.forward(l, false, &mut xp);
        self.backward(l, false, &mut xp);
        permute_out(&self.fwd, &xp, x);
        self.xp = xp;
    }

    /// Forward solve L y = P b into the internal vector, and the back solve
    /// restricted to the reach: afterwards [`Supernodal::reach_value`] gives
    /// (A⁻¹b) at the DOFs given to [`Supernodal::set_reach`].
    pub fn begin_reach(&mut self, l: &[f64], b: &[f64]) {
        let mut xp = std::mem::take(&mut self.xp);
        permute_in(&self.fwd, b, &mut xp);
        self.forward(l, false, &mut xp);
        let mut xr = std::mem::take(&mut self.xr);
        xr.copy_from_slice(&xp);
        self.backward(l, true, &mut xr);
        self.xp = xp;
        self.xr = xr;
    }

    /// (A⁻¹b) at the permuted index i after [`Supernodal::begin_reach`].
    pub fn reach_value(&self, permuted: usize) -> f64 {
        self.xr[permuted]
    }

    /// The permuted index of each DOF.
    pub fn permuted_indices(&self) -> Vec<usize> {
        let mut inv = vec![0usize; self.n];
        for (i, &f) in self.fwd.iter().enumerate() {
            inv[f as usize] = i;
        }
        inv
    }

    /// Finishes a restricted solve: x = A⁻¹(b − c) with c nonzero only at DOFs given
    /// to [`Supernodal::set_reach`], as (permuted index, value).
    pub fn finish_reach(&mut self, l: &[f64], c: &[(usize, f64)], x: &mut [f64]) {
        let mut buffer = std::mem::take(&mut self.w);
        let w = &mut buffer[..self.n];
        w.fill(0.0);
        for &(i, v) in c {
            w[i] += v;
        }
        // L⁻¹c is zero outside the reach, so L⁻¹(b − c) = L⁻¹b − L⁻¹c
        // changes only the reach's columns.
        self.forward(l, true, w);
        let mut xp = std::mem::take(&mut self.xp);
        for (y, wi) in xp.iter_mut().zip(w.iter()) {
            *y -= wi;
        }
        self.backward(l, false, &mut xp);
        permute_out(&self.fwd, &xp, x);
        self.xp = xp;
        self.w = buffer;
    }

    /// The forward solve L y = x over the plan's supernodes, in place.
    fn forward<T: FactorValue>(&mut self, l: &[T], reach: bool, x: &mut [f64]) {
        if !self.full.bins[0].is_empty() {
            let scratch = self.run_bins(reach, x, |me, b, list, x, sc| {
                me.bin_forward(b, l, list, x, sc)
            });
            for (&c, (a0, a1)) in self
                .top_cols
                .iter()
                .zip(scratch[0].acc.iter().zip(&scratch[1].acc))
            {
                let xc = &mut x[c as usize];
                *xc = (*xc - a0) - a1;
            }
            self.scratch = scratch;
        }
        let plan = if reach { &self.reach } else { &self.full };
        for &s in &plan.top {
            let s = s as usize;
            let (c0, c1) = (self.begin[s], self.begin[s + 1]);
            let pattern = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
            let tmp = &mut self.tmp[..pattern.len()];
            block_forward(
                &l[self.val_ptr[s]..self.val_ptr[s + 1]],
                &mut x[c0..c1],
                tmp,
            );
            for (&r, t) in pattern.iter().zip(tmp.iter()) {
                x[r as usize] -= t;
            }
        }
    }

    /// Runs `work` on the two groups at once (each on its own copy of its
    /// columns, reading `x`), then writes the groups' columns back; returns
    /// the scratch (the forward solve still needs its sums for the top).
    fn run_bins<F>(&mut self, reach: bool, x: &mut [f64], work: F) -> [BinScratch; 2]
    where
        F: Fn(&Self, usize, &[u32], &[f64], &mut BinScratch) + Sync,
    {
        let mut scratch = std::mem::take(&mut self.scratch);
        let plan = if reach { &self.reach } else { &self.full };
        let (s0, s1) = scratch.split_at_mut(1);
        let shared = &*x;
        rayon::join(
            || work(self, 0, &plan.bins[0], shared, &mut s0[0]),
            || work(self, 1, &plan.bins[1], shared, &mut s1[0]),
        );
        for (b, sc) in scratch.iter().enumerate() {
            for (&c, v) in self.bin_cols[b].iter().zip(&sc.x) {
                x[c as usize] = *v;
            }
        }
        scratch
    }

    /// One group's forward solve on its own copy of its columns; pushes
    /// into the top columns are summed in `sc.acc`.
    fn bin_forward<T: FactorValue>(
        &self,
        b: usize,
        l: &[T],
        list: &[u32],
        x: &[f64],
        sc: &mut BinScratch,
    ) {
        for (v, &c) in sc.x.iter_mut().zip(&self.bin_cols[b]) {
            *v = x[c as usize];
        }
        sc.acc.fill(0.0);
        for &s in list {
            let s = s as usize;
            let c0 = self.slot[self.begin[s]] as usize;
            let k = self.begin[s + 1] - self.begin[s];
            let pattern = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
            let tmp = &mut sc.tmp[..pattern.len()];
            block_forward(
                &l[self.val_ptr[s]..self.val_ptr[s + 1]],
                &mut sc.x[c0..c0 + k],
                tmp,
            );
            for (&r, t) in pattern.iter().zip(tmp.iter()) {
                let r = r as usize;
                let i = self.slot[r] as usize;
                if self.owner[r] == TOP {
                    sc.acc[i] += t;
                } else {
                    sc.x[i] -= t;
                }
            }
        }
    }

    /// The back solve Lᵀ x = y over the plan's supernodes, in place.
    fn backward<T: FactorValue>(&mut self, l: &[T], reach: bool, x: &mut [f64]) {
        let plan = if reach { &self.reach } else { &self.full };
        for &s in plan.top.iter().rev() {
            let s = s as usize;
            let (c0, c1) = (self.begin[s], self.begin[s + 1]);
            let pattern = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
            let tmp = &mut self.tmp[..pattern.len()];
            for (t, &r) in tmp.iter_mut().zip(pattern) {
                *t = x[r as usize];
            }
            block_backward(
                &l[self.val_ptr[s]..self.val_ptr[s + 1]],
                &mut x[c0..c1],
                tmp,
            );
        }
        if !self.full.bins[0].is_empty() {
            self.scratch = self.run_bins(reach, x, |me, b, list, x, sc| {
                me.bin_backward(b, l, list, x, sc)
            });
        }
    }

    /// One group's back solve on its own copy of its columns, reading the
    /// (finished) top columns from `x`.
    fn bin_backward<T: FactorValue>(
        &self,
        b: usize,
        l: &[T],
        list: &[u32],
        x: &[f64],
        sc: &mut BinScratch,
    ) {
        for (v, &c) in sc.x.iter_mut().zip(&self.bin_cols[b]) {
            *v = x[c as usize];
        }
        for &s in list.iter().rev() {
            let s = s as usize;
            let c0 = self.slot[self.begin[s]] as usize;
            let k = self.begin[s + 1] - self.begin[s];
            let pattern = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
            let tmp = &mut sc.tmp[..pattern.len()];
            for (t, &r) in tmp.iter_mut().zip(pattern) {
                let r = r as usize;
                *t = if self.owner[r] == TOP {
                    x[r]
                } else {
                    sc.x[self.slot[r] as usize]
                };
            }
            block_backward(
                &l[self.val_ptr[s]..self.val_ptr[s + 1]],
                &mut sc.x[c0..c0 + k],
                tmp,
            );
        }
    }
}

fn permute_in(fwd: &[u32], b: &[f64], xp: &mut [f64]) {
    for (y, &f) in xp.iter_mut().zip(fwd) {
        *y = b[f as usize];
    }
}

fn permute_out(fwd: &[u32], xp: &[f64], x: &mut [f64]) {
    for (y, &f) in xp.iter().zip(fwd) {
        x[f as usize] = *y;
    }
}

/// A supernode's forward step: the k × k triangle solved on its columns
/// `xs`, and tmp = L_bot xs (m rows). The block is column-major
/// (k + m) × k, and each column is read once, in one run from its
/// diagonal down (rather than the triangle's pass, then L_bot's: same
/// bits, docs/performance.md). Dispatched (`crate::simd`): the loops
/// vectorize as wide as the CPU allows, with the same operations.
fn block_forward<T: FactorValue>(block: &[T], xs: &mut [f64], tmp: &mut [f64]) {
    struct Forward<'a, T>(&'a [T], &'a mut [f64], &'a mut [f64]);
    impl<T: FactorValue> crate::simd::Kernel for Forward<'_, T> {
        type Output = ();
        #[inline(always)]
        fn run<S: crate::simd::Simd>(self, _simd: S) {
            block_forward_body(self.0, self.1, self.2)
        }
    }
    crate::simd::vectorized(Forward(block, xs, tmp))
}

#[inline(always)]
fn block_forward_body<T: FactorValue>(block: &[T], xs: &mut [f64], tmp: &mut [f64]) {
    let k = xs.len();
    let ld = k + tmp.len();
    tmp.fill(0.0);
    // Column by column, each read once from its diagonal down: the
    // triangle's rows update xs, the rows below it tmp.
    for j in 0..k {
        let col = &block[j * ld..(j + 1) * ld];
        let xj = xs[j] / col[j].into();
        xs[j] = xj;
        for (xi, lij) in xs[j + 1..].iter_mut().zip(&col[j + 1..k]) {
            *xi -= (*lij).into() * xj;
        }
        for (t, lij) in tmp.iter_mut().zip(&col[k..]) {
            *t += (*lij).into() * xj;
        }
    }
}

/// A supernode's back step: xs −= L_botᵀ tmp (tmp = the pattern rows of
/// x) and the k × k transposed triangle, each column read once below its
/// diagonal, from the last. Dispatched as [`block_forward`].
fn block_backward<T: FactorValue>(block: &[T], xs: &mut [f64], tmp: &[f64]) {
    struct Backward<'a, T>(&'a [T], &'a mut [f64], &'a [f64]);
    impl<T: FactorValue> crate::simd::Kernel for Backward<'_, T> {
        type Output = ();
        #[inline(always)]
        fn run<S: crate::simd::Simd>(self, _simd: S) {
            block_backward_body(self.0, self.1, self.2)
        }
    }
    crate::simd::vectorized(Backward(block, xs, tmp))
}

#[inline(always)]
fn block_backward_body<T: FactorValue>(block: &[T], xs: &mut [f64], tmp: &[f64]) {
    let k = xs.len();
    let ld = k + tmp.len();
    // Column by column from the last, each read once below its diagonal:
    // (x_j − L_botᵀ tmp − the triangle's row) / l_jj.
    for j in (0..k).rev() {
        let col = &block[j * ld..(j + 1) * ld];
        // An empty tmp (the root) gives +0, which changes no x_j.
        let below = dot(&col[k..], tmp);
        let s = dot(&col[j + 1..k], &xs[j + 1..]);
        xs[j] = ((xs[j] - below) - s) / col[j].into();
    }
}

/// Σ aᵢbᵢ with four independent partial sums (the adder's latency, not
/// memory, would bind a single chain).
#[inline(always)]
fn dot<T: FactorValue>(a: &[T], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (a4, ar) = a.split_at(a.len() - a.len() % 4);
    let (b4, br) = b.split_at(a4.len());
    for (x, y) in a4.chunks_exact(4).zip(b4.chunks_exact(4)) {
        acc[0] += x[0].into() * y[0];
        acc[1] += x[1].into() * y[1];
        acc[2] += x[2].into() * y[2];
        acc[3] += x[3].into() * y[3];
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ar.iter().zip(br) {
        s += (*x).into() * y;
    }
    s
}
