//! The fill-reducing ordering of the Cholesky factors (the static solve,
//! Newmark's A₀, the consistent mass): faer's AMD on the smallest systems
//! (the paper's meshes), a nested dissection by cells from
//! [`DISSECTION_MIN_DOFS`] unless AMD's factor is clearly smaller
//! ([`FillOrder`]).
//!
//! Nested dissection: the cells are split at the median of their centroids
//! across the longer side of their bounding box, the nodes the two halves
//! share are the separator and are numbered after both halves, and each
//! half is split again down to single cells. The separator is the line of
//! nodes between two rows of cells, one node wide for Q1 and Q2 alike.
//! Against AMD (faer's symbolic and numeric factorization of K), the
//! dissection's factor has fewer values and factorizes faster on
//! unstructured meshes of a few hundred thousand DOFs and more; on grids
//! numbered row by row its fill is AMD's within a few per cent either way
//! (up to 13% more below 2k DOFs), its analysis costs a fraction of AMD's,
//! and its larger supernodes make the Newmark step's solves faster: whole
//! runs of the structured slabs from 552 DOFs take fewer instructions (an
//! unstructured 10k-DOF slab's Newmark run 1.4% more: it analyses both
//! orders and keeps AMD's). Below
//! [`DISSECTION_MIN_DOFS`] AMD stays: there the analysis and the factor
//! cost well under a millisecond either way, and the paper's meshes keep
//! the order their runs were verified in. The figures are in
//! docs/performance.md; `cargo
//! run --release -p stickslip-fem --example fill_order -- MESH...` prints
//! them for any mesh.
//!
//! Not every mesh above [`DISSECTION_MIN_DOFS`] gains: on non-convex
//! domains and long thin strips the dissection's factor is larger than
//! AMD's (`cargo run --release -p stickslip-fem --example
//! fill_order_shapes`). So from [`DISSECTION_MIN_DOFS`] the first
//! factorization of a run analyses its pattern in both orders and keeps
//! the dissection unless AMD's factor has [`stickslip_linalg::AMD_MARGIN`] fewer values
//! ([`choose`]); K, A₀ and M share the pattern, and the later
//! factorizations reuse the choice. The price is AMD's analysis beside the
//! dissection's, which on large meshes costs less than the dissection
//! saves of the factorization, and on small ones a little more (an
//! explicit run's lone factor skips it).
//!
//! Leaves are single cells and separators the nodes two halves of cells
//! share: larger leaves, and separators taken on the node graph, gave more
//! fill (docs/performance.md). On an unstructured mesh the cells'
//! centroids make that separator a staircase; a split of
//! `CUT_MIN_CELLS` cells or more moves the band's cells to the sides of
//! the shortest path of cell sides across it where that path is shorter
//! (`cut.rs`): a quarter fewer nodes at the top of the 500k-DOF slab, a
//! fifth fewer flops in its factor.

use stickslip_linalg::FillOrder;
use stickslip_mesh::Mesh;

use crate::cut::{Band, Cut};
use crate::dofs::DofMap;

/// Free DOFs from which the factors are ordered by nested dissection
/// (module documentation): whole runs take fewer instructions on every
/// structured slab measured from 552 DOFs up; below lie the paper's meshes
/// (docs/performance.md, "Nested dissection from 500 DOFs").
pub const DISSECTION_MIN_DOFS: usize = 500;

/// Environment variable that overrides the choice, for comparisons:
/// `amd` or `nd` (as [`crate::dofs::ORDER_ENV`] keeps the file's node
/// order); any other value, or none, chooses by size.
pub const FILL_ORDER_ENV: &str = "STICKSLIP_FILL_ORDER";

/// The ordering of the model's factors: AMD below [`DISSECTION_MIN_DOFS`]
/// free DOFs, else the dissection or AMD by their factors
/// ([`stickslip_linalg::AMD_MARGIN`]), unless [`FILL_ORDER_ENV`] says which.
/// `made`: the mesh's [`dissection_nodes`] if made already (beside the
/// DOF map, [`wanted`]).
pub fn choose(mesh: &Mesh, dofs: &DofMap, made: Option<NodeDissection>) -> FillOrder {
    let dissection = || made.unwrap_or_else(|| dissection_nodes(mesh));
    match std::env::var(FILL_ORDER_ENV).as_deref() {
        Ok("amd") => FillOrder::amd(),
        Ok("nd") => FillOrder::dissection(dissection().of_dofs(dofs).0),
        _ if dofs.n_free() < DISSECTION_MIN_DOFS => FillOrder::amd(),
        _ => {
            let (order, halves) = dissection().of_dofs(dofs);
            let order = FillOrder::dissection_unless_amd(order);
            match halves {
                Some(h) => order.with_halves(h),
                None => order,
            }
        }
    }
}

/// Whether [`choose`] will read the dissection of a mesh of `n_nodes`
/// nodes, at most 2 `n_nodes` of them free: false only where it surely
/// will not.
pub fn wanted(n_nodes: usize) -> bool {
    match std::env::var(FILL_ORDER_ENV).as_deref() {
        Ok("amd") => false,
        Ok("nd") => true,
        _ => 2 * n_nodes >= DISSECTION_MIN_DOFS,
    }
}

/// The free DOFs of `dofs` in nested-dissection order (module
/// documentation), each node's DOFs together, x before y. Deterministic:
/// the same mesh gives the same order.
pub fn nested_dissection(mesh: &Mesh, dofs: &DofMap) -> Vec<usize> {
    dissection_with_halves(mesh, dofs).0
}

/// [`nested_dissection`], with the free DOFs of the first split's two
/// halves, which the order numbers first (the first half's, then the
/// second's; its separator follows): `None` where the first split left a
/// half empty.
pub fn dissection_with_halves(mesh: &Mesh, dofs: &DofMap) -> (Vec<usize>, Option<[usize; 2]>) {
    dissection_nodes(mesh).of_dofs(dofs)
}

/// The dissection's order of the mesh's nodes, before the DOF map: it
/// reads the cells only, so it can be made beside the DOF map.
#[derive(Clone, Debug)]
pub struct NodeDissection {
    /// Every node once, in the order their DOFs are numbered.
    nodes: Vec<usize>,
    /// Where the first split's second half begins and where its
    /// separator does, in `nodes`: `None` where the mesh has one cell.
    marks: Option<[usize; 2]>,
}

impl NodeDissection {
    /// Every node once, in the order their DOFs are numbered.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// The free DOFs in this order, each node's x before its y, and the
    /// first split's halves ([`dissection_with_halves`]).
    pub fn of_dofs(&self, dofs: &DofMap) -> (Vec<usize>, Option<[usize; 2]>) {
        let free_dofs = |nodes: &[usize]| {
            nodes
                .iter()
                .flat_map(|&v| (0..2).filter_map(move |k| dofs.free(v, k)))
                .collect::<Vec<usize>>()
        };
        let halves = self.marks.and_then(|[second, separator]| {
            let first = free_dofs(&self.nodes[..second]).len();
            let second = free_dofs(&self.nodes[second..separator]).len();
            (first > 0 && second > 0).then_some([first, second])
        });
        (free_dofs(&self.nodes), halves)
    }
}

/// The nested dissection of the mesh's nodes (module documentation).
pub fn dissection_nodes(mesh: &Mesh) -> NodeDissection {
    let n_nodes = mesh.nodes.len();
    // Each split reorders its range of `cells` in place: its first half,
    // then its second. A cell carries its centroid, read at every level.
    let mut cells: Vec<Placed> = (0..mesh.n_cells())
        .map(|c| {
            // Corners first in both cell kinds.
            let corners = &mesh.cell(c)[..4];
            let mut x = [0.0; 2];
            for &v in corners {
                x[0] += 0.25 * mesh.nodes[v][0];
                x[1] += 0.25 * mesh.nodes[v][1];
            }
            Placed { x, cell: c as u32 }
        })
        .collect();
    // Two cells that share a node have centroids at most 2·reach apart
    // along either axis (reach: how far a node lies from its cell's
    // centroid), so a split's separator lies in the cells within that
    // band of the split: only they are read for it. The band is widened
    // beyond 2·reach against the rounding of the comparisons.
    let mut reach = [0.0f64; 2];
    for p in &cells {
        for &v in mesh.cell(p.cell as usize) {
            for d in 0..2 {
                reach[d] = reach[d].max((mesh.nodes[v][d] - p.x[d]).abs());
            }
        }
    }
    let band = reach.map(|r| 3.0 * r);
    // A mesh file's coordinates are finite (the reader refuses others); a
    // mesh built otherwise with some that are not has every cell read.
    let finite = cells.iter().all(|p| p.x.iter().all(|v| v.is_finite()));
    let mut state = vec![State::Open; n_nodes];
    let mut in_first = vec![u32::MAX; n_nodes];
    let mut nodes = Vec::with_capacity(n_nodes);
    enum Job {
        /// Cells `cells[start..end]`.
        Split(usize, usize),
        Number(Vec<usize>),
        /// Where the first split's second half begins, and where its
        /// separator does: the nodes numbered so far.
        Mark,
    }
    let mut second_half = Vec::new();
    let mut jobs = vec![Job::Split(0, cells.len())];
    let mut marks = Vec::with_capacity(2);
    let mut split = 0u32;
    let mut stamp = 0u32;
    let mut cut = Cut::new(n_nodes);
    while let Some(job) = jobs.pop() {
        let (start, end) = match job {
            Job::Mark => {
                marks.push(nodes.len());
                continue;
            }
            Job::Number(separator) => {
                for v in separator {
                    state[v] = State::Numbered;
                    nodes.push(v);
                }
                continue;
            }
            Job::Split(start, end) => (start, end),
        };
        let range = &mut cells[start..end];
        if range.len() <= 1 {
            for p in range.iter() {
                for &v in mesh.cell(p.cell as usize) {
                    if state[v] == State::Open {
                        state[v] = State::Numbered;
                        nodes.push(v);
                    }
                }
            }
            continue;
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in range.iter() {
            for d in 0..2 {
                lo[d] = lo[d].min(p.x[d]);
                hi[d] = hi[d].max(p.x[d]);
            }
        }
        let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
        let key = |p: &Placed| p.x[axis];
        let mid = range.len() / 2;
        range.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        // Split at a coordinate, so that cells of one row or column (equal
        // centroids on a grid) stay on one side and the separator is a
        // straight line; by position when none lies below the median.
        let at = key(&range[mid]);
        let mut first_len = if range[..mid].iter().any(|c| key(c) < at) {
            stable_partition(range, &mut second_half, |_, c| key(c) < at)
        } else {
            mid
        };
        let mut separator = shared_nodes(
            mesh,
            range.split_at(first_len),
            |p| !finite || (key(p) - at).abs() <= band[axis],
            (&mut in_first, &mut stamp),
            &mut state,
        );
        // On a large split, a shorter separator across a band around it
        // (`cut.rs`); a split whose staircase is a straight line keeps it.
        // The band is at least 6·reach wide on each side, so that no cell
        // before it shares a node with one after it, and every node the
        // halves then share lies in cells within width + band of the split.
        if finite && range.len() >= CUT_MIN_CELLS {
            let width = (CUT_WIDTH * (hi[axis] - lo[axis])).max(2.0 * band[axis]);
            for &v in &separator {
                state[v] = State::Open;
            }
            let open = |v: usize| state[v] == State::Open;
            let limit = separator.len();
            let sides = cut
                .shorter(
                    mesh,
                    range,
                    Band { axis, at, width },
                    band[axis],
                    open,
                    limit,
                )
                // Both halves keep cells, or the split would repeat.
                .filter(|s| s.contains(&true) && s.contains(&false));
            match sides {
                Some(sides) => {
                    first_len = stable_partition(range, &mut second_half, |i, _| sides[i]);
                    separator = shared_nodes(
                        mesh,
                        range.split_at(first_len),
                        |p| (key(p) - at).abs() <= width + band[axis],
                        (&mut in_first, &mut stamp),
                        &mut state,
                    );
                }
                None => {
                    for &v in &separator {
                        state[v] = State::Separator;
                    }
                }
            }
        }
        let first_split = split == 0;
        split += 1;
        jobs.push(Job::Number(separator));
        if first_split {
            jobs.push(Job::Mark);
        }
        jobs.push(Job::Split(start + first_len, end));
        if first_split {
            jobs.push(Job::Mark);
        }
        jobs.push(Job::Split(start, start + first_len));
    }
    // Nodes in no cell (a mesh may carry them) last.
    nodes.extend((0..n_nodes).filter(|&v| state[v] == State::Open));
    let marks = match marks[..] {
        [second, separator] => Some([second, separator]),
        _ => None,
    };
    NodeDissection { nodes, marks }
}

/// Reorders `range` stably: the cells `first` takes (by index and cell),
/// then the others; returns how many `first` took. `scratch` holds the
/// others meanwhile.
fn stable_partition(
    range: &mut [Placed],
    scratch: &mut Vec<Placed>,
    first: impl Fn(usize, &Placed) -> bool,
) -> usize {
    scratch.clear();
    let mut taken = 0;
    for i in 0..range.len() {
        let c = range[i];
        if first(i, &c) {
            range[taken] = c;
            taken += 1;
        } else {
            scratch.push(c);
        }
    }
    range[taken..].copy_from_slice(scratch);
    taken
}

/// A node in the dissection: not yet numbered, in the separator of the
/// split at hand, numbered.
#[derive(Clone, Copy, PartialEq)]
enum State {
    Open,
    Separator,
    Numbered,
}

/// Splits from which a shorter separator is sought (`cut.rs`): the first
/// four levels of the 500k-DOF slab (250k cells), where most of the
/// factor's flops are; from 4,096 cells the search costs the dissection
/// more than the factor saves (docs/performance.md).
const CUT_MIN_CELLS: usize = 16384;

/// The band a shorter separator is sought in: this fraction of the split
/// range's extent on each side, and at least 6·reach (docs/performance.md: 189 nodes within
/// ±5% of the 500k slab's length, 192 within ±2%, 248 within ±0.1%).
const CUT_WIDTH: f64 = 0.03;

/// The open nodes that cells of both halves hold, marked as the separator;
/// `near` filters the cells that can hold one (those within reach of the
/// split).
fn shared_nodes(
    mesh: &Mesh,
    (first, second): (&[Placed], &[Placed]),
    near: impl Fn(&Placed) -> bool,
    (in_first, stamp): (&mut [u32], &mut u32),
    state: &mut [State],
) -> Vec<usize> {
    *stamp += 1;
    for p in first.iter().filter(|p| near(p)) {
        for &v in mesh.cell(p.cell as usize) {
            in_first[v] = *stamp;
        }
    }
    let mut separator = Vec::new();
    for p in second.iter().filter(|p| near(p)) {
        for &v in mesh.cell(p.cell as usize) {
            if in_first[v] == *stamp && state[v] == State::Open {
                state[v] = State::Separator;
                separator.push(v);
            }
        }
    }
    separator
}

/// A cell as the dissection sorts it: its centroid and its index.
#[derive(Clone, Copy)]
pub(crate) struct Placed {
    pub x: [f64; 2],
    pub cell: u32,
}
