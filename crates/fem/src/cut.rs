//! A shorter separator for a split of the nested dissection: the fewest
//! nodes on a path of cell sides across a band around the split.
//!
//! A split by cell centroids leaves as separator the nodes the two sets of
//! cells share, a staircase along the split on an unstructured mesh; a
//! path of cell sides that wanders across a band of a few per cent of the
//! length has a quarter fewer nodes (docs/performance.md, "The
//! dissection's separators against METIS's"). Here one breadth-first
//! search along the sides of the band's cells goes from the nodes where
//! the band meets the split range's rim on one end (below the band's
//! middle, across the split) to those on the other end, through open
//! nodes (neither in an ancestor's separator nor numbered with a sibling
//! half). The rim: sides of one cell of the range (the mesh's boundary)
//! and cells beside a node not open. The path found is the candidate
//! separator. A second
//! search then collects the nodes reached from the cells before the band
//! without crossing the path, the first side: a band cell with one of them
//! goes first. Where a node of the cells after the band is reached the
//! path does not separate (a range that is not convex, a band that meets
//! the rim elsewhere), and the split keeps its staircase; so it does
//! where the path is not shorter (a split whose staircase is a straight
//! line, as on an exact grid).

use stickslip_mesh::{CellKind, Mesh};

use crate::ordering::Placed;

/// No node: an unset local index.
const NONE: u32 = u32::MAX;

/// The sides of a cell as pairs of its nodes' positions, a Q2 side as its
/// two halves (corner, middle, corner: Gmsh's order).
const QUAD4_SIDES: [(usize, usize); 4] = [(0, 1), (1, 2), (2, 3), (3, 0)];
const QUAD9_SIDES: [(usize, usize); 8] = [
    (0, 4),
    (4, 1),
    (1, 5),
    (5, 2),
    (2, 6),
    (6, 3),
    (3, 7),
    (7, 0),
];

/// Buffers reused from split to split.
#[derive(Default)]
pub(crate) struct Cut {
    /// Local index of each mesh node in the current band, or [`NONE`].
    local: Vec<u32>,
    /// The band's mesh nodes, by local index.
    nodes: Vec<usize>,
    /// Per local node, bits: 1 in a cell before the band, 2 in one after
    /// it, 4 on the range's rim, 8 on the path, 16 reached.
    flags: Vec<u8>,
    /// Local nodes joined by a side (CSR), and the band cells of a node.
    side_ptr: Vec<u32>,
    side_to: Vec<u32>,
    cell_ptr: Vec<u32>,
    cell_of: Vec<u32>,
    parent: Vec<u32>,
    queue: Vec<u32>,
    /// The split's cells within the band or beside it (indices into its
    /// cells), and the sides of their local nodes.
    near: Vec<u32>,
    sides: Vec<(u32, u32)>,
}

/// The band around a split: the cells whose centroids lie within `width`
/// of `at` along `axis`.
#[derive(Clone, Copy)]
pub(crate) struct Band {
    pub axis: usize,
    pub at: f64,
    pub width: f64,
}

impl Band {
    /// How far a centroid lies from the split, along its axis.
    fn distance(&self, x: [f64; 2]) -> f64 {
        (x[self.axis] - self.at).abs()
    }

    fn contains(&self, x: [f64; 2]) -> bool {
        self.distance(x) <= self.width
    }

    /// Whether a centroid lies before the split.
    fn before(&self, x: [f64; 2]) -> bool {
        x[self.axis] < self.at
    }
}

const BEFORE: u8 = 1;
const AFTER: u8 = 2;
const RIM: u8 = 4;
const PATH: u8 = 8;
const REACHED: u8 = 16;

impl Cut {
    pub fn new(n_nodes: usize) -> Cut {
        Cut {
            local: vec![NONE; n_nodes],
            ..Cut::default()
        }
    }

    /// The side of each cell of `cells` (`true`: first) for a separator of
    /// fewer than `limit` nodes, where the path finds one: `cells` are the
    /// split's, `band` the split and its band, `near`
    /// how far from the band a cell that shares a node with it can lie,
    /// `open` the nodes in neither an ancestor's separator nor a numbered
    /// half.
    pub fn shorter(
        &mut self,
        mesh: &Mesh,
        cells: &[Placed],
        band: Band,
        near: f64,
        open: impl Fn(usize) -> bool,
        limit: usize,
    ) -> Option<Vec<bool>> {
        self.nodes.clear();
        self.near.clear();
        for (i, &Placed { x, cell: c }) in cells.iter().enumerate() {
            let d = band.distance(x);
            if d <= band.width + near {
                self.near.push(i as u32);
            }
            if d <= band.width {
                for &v in mesh.cell(c as usize) {
                    if open(v) && self.local[v] == NONE {
                        self.local[v] = self.nodes.len() as u32;
                        self.nodes.push(v);
                    }
                }
            }
        }
        let sides = self.path(mesh, cells, band, &open, limit);
        for &v in &self.nodes {
            self.local[v] = NONE;
        }
        sides
    }

    fn path(
        &mut self,
        mesh: &Mesh,
        cells: &[Placed],
        band: Band,
        open: &impl Fn(usize) -> bool,
        limit: usize,
    ) -> Option<Vec<bool>> {
        let n = self.nodes.len();
        if n == 0 {
            return None;
        }
        let pairs: &[(usize, usize)] = match mesh.kind {
            CellKind::Quad4 => &QUAD4_SIDES,
            CellKind::Quad9 => &QUAD9_SIDES,
        };
        self.flags.clear();
        self.flags.resize(n, 0);
        // The sides of the band's cells and of the cells beside it, by
        // their end nodes: a side of one cell of the range is on its rim.
        self.sides.clear();
        let other = 1 - band.axis;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..self.near.len() {
            let Placed { x, cell: c } = cells[self.near[k] as usize];
            let cell = mesh.cell(c as usize);
            if band.contains(x) {
                lo = lo.min(x[other]);
                hi = hi.max(x[other]);
                // Beside a node not open (an ancestor's separator, a
                // numbered half): the rim of a range inside the mesh.
                if cell.iter().any(|&v| !open(v)) {
                    for &v in cell {
                        let l = self.local[v];
                        if l != NONE {
                            self.flags[l as usize] |= RIM;
                        }
                    }
                }
            } else {
                let end = if band.before(x) { BEFORE } else { AFTER };
                for &v in cell {
                    let l = self.local[v];
                    if l != NONE {
                        self.flags[l as usize] |= end;
                    }
                }
            }
            for &(a, b) in pairs {
                let (la, lb) = (self.local[cell[a]], self.local[cell[b]]);
                if la != NONE && lb != NONE {
                    self.sides.push((la.min(lb), la.max(lb)));
                }
            }
        }
        if self
            .flags
            .iter()
            .any(|&f| f & (BEFORE | AFTER) == BEFORE | AFTER)
        {
            return None;
        }
        // A side of one cell: on the rim.
        self.sides.sort_unstable();
        let mut k = 0;
        while k < self.sides.len() {
            let run = self.sides[k..].partition_point(|&e| e == self.sides[k]);
            if run == 1 {
                let (a, b) = self.sides[k];
                self.flags[a as usize] |= RIM;
                self.flags[b as usize] |= RIM;
            }
            k += run;
        }
        // Sides and cells of each local node, within the band (CSR).
        self.side_ptr.clear();
        self.side_ptr.resize(n + 1, 0);
        self.cell_ptr.clear();
        self.cell_ptr.resize(n + 1, 0);
        for pass in 0..2 {
            if pass == 1 {
                for ptr in [&mut self.side_ptr, &mut self.cell_ptr] {
                    for i in 0..n {
                        ptr[i + 1] += ptr[i];
                    }
                }
                self.side_to.clear();
                self.side_to.resize(self.side_ptr[n] as usize, 0);
                self.cell_of.clear();
                self.cell_of.resize(self.cell_ptr[n] as usize, 0);
            }
            for k in 0..self.near.len() {
                let i = self.near[k] as usize;
                let Placed { x, cell: c } = cells[i];
                if !band.contains(x) {
                    continue;
                }
                let cell = mesh.cell(c as usize);
                for &v in cell {
                    let l = self.local[v];
                    if l != NONE {
                        let l = l as usize;
                        if pass == 0 {
                            self.cell_ptr[l + 1] += 1;
                        } else {
                            self.cell_ptr[l] += 1;
                            self.cell_of[self.cell_ptr[l] as usize - 1] = i as u32;
                        }
                    }
                }
                for &(a, b) in pairs {
                    let (la, lb) = (self.local[cell[a]], self.local[cell[b]]);
                    if la == NONE || lb == NONE {
                        continue;
                    }
                    for (p, q) in [(la, lb), (lb, la)] {
                        let p = p as usize;
                        if pass == 0 {
                            self.side_ptr[p + 1] += 1;
                        } else {
                            self.side_ptr[p] += 1;
                            self.side_to[self.side_ptr[p] as usize - 1] = q;
                        }
                    }
                }
            }
            if pass == 1 {
                // The fill advanced each start to the next's: shift back.
                for ptr in [&mut self.side_ptr, &mut self.cell_ptr] {
                    for i in (1..=n).rev() {
                        ptr[i] = ptr[i - 1];
                    }
                    ptr[0] = 0;
                }
            }
        }
        // The path: from the rim below the band's middle (across the
        // split) to the rim above it, fewest nodes first.
        let middle = 0.5 * (lo + hi);
        let coordinate = |me: &Self, l: usize| mesh.nodes[me.nodes[l]][other];
        self.parent.clear();
        self.parent.resize(n, NONE);
        self.queue.clear();
        for l in 0..n {
            if self.flags[l] & RIM != 0 && coordinate(self, l) < middle {
                self.parent[l] = l as u32;
                self.queue.push(l as u32);
            }
        }
        let mut head = 0;
        let mut end = None;
        while head < self.queue.len() {
            let l = self.queue[head] as usize;
            head += 1;
            if self.flags[l] & RIM != 0 && coordinate(self, l) >= middle {
                end = Some(l);
                break;
            }
            for s in self.side_ptr[l]..self.side_ptr[l + 1] {
                let m = self.side_to[s as usize] as usize;
                if self.parent[m] == NONE {
                    self.parent[m] = l as u32;
                    self.queue.push(m as u32);
                }
            }
        }
        let mut l = end?;
        let mut length = 1;
        self.flags[l] |= PATH;
        while self.parent[l] as usize != l {
            l = self.parent[l] as usize;
            self.flags[l] |= PATH;
            length += 1;
            if length >= limit {
                return None;
            }
        }
        // The first side: reached from the cells before the band through
        // the band's cells, the path not crossed.
        self.queue.clear();
        for l in 0..n {
            if self.flags[l] & (BEFORE | PATH) == BEFORE {
                self.flags[l] |= REACHED;
                self.queue.push(l as u32);
            }
        }
        let mut head = 0;
        while head < self.queue.len() {
            let l = self.queue[head] as usize;
            head += 1;
            if self.flags[l] & AFTER != 0 {
                return None;
            }
            for k in self.cell_ptr[l]..self.cell_ptr[l + 1] {
                let c = cells[self.cell_of[k as usize] as usize].cell;
                for &v in mesh.cell(c as usize) {
                    let m = self.local[v];
                    if m != NONE && self.flags[m as usize] & (PATH | REACHED) == 0 {
                        self.flags[m as usize] |= REACHED;
                        self.queue.push(m);
                    }
                }
            }
        }
        Some(
            cells
                .iter()
                .map(|&Placed { x, cell: c }| {
                    if !band.contains(x) {
                        return band.before(x);
                    }
                    mesh.cell(c as usize).iter().any(|&v| {
                        let l = self.local[v];
                        l != NONE && self.flags[l as usize] & REACHED != 0
                    })
                })
                .collect(),
        )
    }
}
