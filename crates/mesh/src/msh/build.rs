//! Collects what the version-specific parsers read (nodes, then elements)
//! into a [`Mesh`], checking as it goes: node tags map to dense indices,
//! every cell is oriented counter-clockwise with a positive Jacobian at its
//! corners (quad9: also at its other nodes and Gauss points), boundary
//! elements of groups lie on cell sides and are oriented with their cell on
//! the left, nodes in no cell are dropped.

use std::collections::{BTreeMap, HashMap};

use super::cursor::{Cursor, Result};
use crate::{CellKind, Edge, Group, Mesh, MeshError, MeshErrorKind, SourceInfo, GMSH_TO_FEM_QUAD9};

/// Gmsh element types the reader knows by name.
pub(crate) const POINT: i32 = 15;
pub(crate) const LINE2: i32 = 1;
pub(crate) const LINE3: i32 = 8;
pub(crate) const QUAD4: i32 = 3;
pub(crate) const QUAD9: i32 = 10;

/// Nodes per element for the types the reader accepts.
pub(crate) fn nodes_of(type_id: i32) -> Option<usize> {
    match type_id {
        POINT => Some(1),
        LINE2 => Some(2),
        LINE3 => Some(3),
        QUAD4 => Some(4),
        QUAD9 => Some(9),
        _ => None,
    }
}

/// "1 node tag", "4 node tags": `n` and `noun`, plural unless `n` is 1.
pub(crate) fn counted(n: u64, noun: &str) -> String {
    let s = if n == 1 { "" } else { "s" };
    format!("{n} {noun}{s}")
}

/// The name of a type [`nodes_of`] accepts, for messages.
pub(crate) fn type_name(type_id: i32) -> &'static str {
    match type_id {
        POINT => "point",
        LINE2 => "line2",
        LINE3 => "line3",
        QUAD4 => "quad4",
        QUAD9 => "quad9",
        _ => "element",
    }
}

/// Gmsh's name and dimension of an element type of order 1 or 2 (for
/// messages; higher orders are [`high_order`]).
fn describe(type_id: i32) -> (&'static str, u8) {
    match type_id {
        2 => ("tri3", 2),
        9 => ("tri6", 2),
        16 => ("quad8", 2),
        4 => ("tet4", 3),
        5 => ("hex8", 3),
        6 => ("prism6", 3),
        7 => ("pyramid5", 3),
        11 => ("tet10", 3),
        12 => ("hex27", 3),
        13 => ("prism18", 3),
        14 => ("pyramid14", 3),
        17 => ("hex20", 3),
        18 => ("prism15", 3),
        19 => ("pyramid13", 3),
        _ => ("unknown type", 9),
    }
}

/// Gmsh's name and the order of a line, triangle or quadrangle type of
/// order 3 or more (GmshDefines.h; "incomplete" types have no interior
/// nodes). These come from `gmsh -order 3` and up: the problem is the order,
/// not the dimension or the shape.
fn high_order(type_id: i32) -> Option<(&'static str, u8)> {
    Some(match type_id {
        26 => ("line4", 3),
        27 => ("line5", 4),
        28 => ("line6", 5),
        62 => ("line7", 6),
        63 => ("line8", 7),
        64 => ("line9", 8),
        65 => ("line10", 9),
        66 => ("line11", 10),
        20 => ("tri9", 3),
        21 => ("tri10", 3),
        22 => ("tri12", 4),
        23 => ("tri15", 4),
        24 => ("tri15 (incomplete)", 5),
        25 => ("tri21", 5),
        42 => ("tri28", 6),
        43 => ("tri36", 7),
        44 => ("tri45", 8),
        45 => ("tri55", 9),
        46 => ("tri66", 10),
        52 => ("tri18", 6),
        53 => ("tri21 (incomplete)", 7),
        54 => ("tri24", 8),
        55 => ("tri27", 9),
        56 => ("tri30", 10),
        36 => ("quad16", 3),
        37 => ("quad25", 4),
        38 => ("quad36", 5),
        39 => ("quad12", 3),
        40 => ("quad16 (incomplete)", 4),
        41 => ("quad20", 5),
        47 => ("quad49", 6),
        48 => ("quad64", 7),
        49 => ("quad81", 8),
        50 => ("quad100", 9),
        51 => ("quad121", 10),
        57 => ("quad24", 6),
        58 => ("quad28", 7),
        59 => ("quad32", 8),
        60 => ("quad36 (incomplete)", 9),
        61 => ("quad40", 10),
        _ => return None,
    })
}

/// The error for an element type the reader does not take.
pub(crate) fn unsupported(cur: &Cursor<'_>, pos: usize, element: u64, type_id: i32) -> MeshError {
    if let Some((name, order)) = high_order(type_id) {
        return cur.error(
            pos,
            MeshErrorKind::UnsupportedOrder {
                element,
                type_id,
                name,
                order,
            },
        );
    }
    let (name, dim) = describe(type_id);
    if dim == 2 {
        cur.error(
            pos,
            MeshErrorKind::NotQuads {
                found: format!("{name} (Gmsh type {type_id})"),
            },
        )
    } else {
        cur.error(
            pos,
            MeshErrorKind::UnsupportedElement {
                element,
                type_id,
                name,
            },
        )
    }
}

/// Dense indices from Gmsh node tags.
#[derive(Debug)]
enum NodeIndex {
    /// Tags are `first, first + 1, …` in file order (Gmsh's usual output).
    Offset(u64),
    /// `table[tag - min]`, `u32::MAX` where no node has that tag.
    Table { min: u64, table: Vec<u32> },
    /// Sparse tags.
    Map(HashMap<u64, u32>),
}

/// Relative tolerance on corner Jacobians: `det <= TOL * |a| |b|` means the
/// corner angle is 0 or 180 degrees within rounding of Gmsh's coordinates.
const JACOBIAN_TOL: f64 = 1e-10;

/// Nodes whose z spread up to this times the xy extent plus |z| lie in one
/// plane z = const (Gmsh writes rounded coordinates).
const Z_TOL: f64 = 1e-12;

/// Which physical groups an element belongs to: an index into
/// `Builder::memberships` (0 is "no group").
pub(crate) type Membership = u32;

/// The previous element, to merge the copies MSH 2.2 writes of an element
/// that is in several physical groups (one copy per group, consecutive).
#[derive(Debug, Default)]
struct Previous {
    type_id: i32,
    elementary: i32,
    nodes: [u64; 9],
    /// Index of the element in its list (cells, lines or points).
    index: usize,
    valid: bool,
}

#[derive(Debug)]
pub(crate) struct Builder {
    pub(crate) version: &'static str,
    pub(crate) binary: bool,
    pub(crate) nodes: Vec<[f64; 2]>,
    pub(crate) node_tags: Vec<u64>,
    /// The z farthest from the first node's seen, the node's tag and its
    /// position.
    pub(crate) max_z: (f64, u64, usize),
    /// The least z seen, its node's tag and position.
    pub(crate) min_z: (f64, u64, usize),
    /// Σ z over the nodes read.
    pub(crate) sum_z: f64,
    index: Option<NodeIndex>,
    /// The largest node tag read so far.
    max_tag: Option<u64>,
    /// (index, position) of each node whose tag is not above all tags
    /// before it: only there can a duplicate be, and Gmsh's increasing tags
    /// leave this empty. Gives a duplicate's line without a position a node.
    late_tags: Vec<(usize, usize)>,
    /// Physical tag lists; entry 0 is empty.
    pub(crate) memberships: Vec<Vec<i32>>,
    membership_ids: HashMap<Vec<i32>, Membership>,
    pub(crate) names: BTreeMap<(u8, i32), String>,
    kind: Option<CellKind>,
    cells: Vec<usize>,
    cell_tags: Vec<u64>,
    cell_member: Vec<Membership>,
    reoriented: usize,
    /// Boundary lines: end, end, mid (`usize::MAX` for line2).
    lines: Vec<[usize; 3]>,
    line_tags: Vec<u64>,
    line_member: Vec<Membership>,
    line_pos: Vec<usize>,
    points: Vec<usize>,
    point_member: Vec<Membership>,
    counts: [usize; 3],
    prev: Previous,
}

impl Builder {
    pub(crate) fn new(version: &'static str, binary: bool) -> Self {
        Builder {
            version,
            binary,
            nodes: Vec::new(),
            node_tags: Vec::new(),
            max_z: (f64::NEG_INFINITY, 0, 0),
            min_z: (f64::INFINITY, 0, 0),
            sum_z: 0.0,
            index: None,
            max_tag: None,
            late_tags: Vec::new(),
            memberships: vec![Vec::new()],
            membership_ids: HashMap::new(),
            names: BTreeMap::new(),
            kind: None,
            cells: Vec::new(),
            cell_tags: Vec::new(),
            cell_member: Vec::new(),
            reoriented: 0,
            lines: Vec::new(),
            line_tags: Vec::new(),
            line_member: Vec::new(),
            line_pos: Vec::new(),
            points: Vec::new(),
            point_member: Vec::new(),
            counts: [0; 3],
            prev: Previous::default(),
        }
    }

    /// The membership id of a list of physical tags (sorted, without repeats).
    pub(crate) fn membership(&mut self, mut tags: Vec<i32>) -> Membership {
        tags.sort_unstable();
        tags.dedup();
        if tags.is_empty() {
            return 0;
        }
        if let Some(&id) = self.membership_ids.get(&tags) {
            return id;
        }
        let id = self.memberships.len() as Membership;
        self.memberships.push(tags.clone());
        self.membership_ids.insert(tags, id);
        id
    }

    /// A node read at `pos` (any position on its line, or its record).
    #[inline]
    pub(crate) fn push_node(&mut self, tag: u64, x: f64, y: f64, z: f64, pos: usize) {
        self.push_tag(tag, pos);
        self.push_xyz(x, y, z, tag, pos);
    }

    /// A node's tag, read at `pos`.
    #[inline]
    pub(crate) fn push_tag(&mut self, tag: u64, pos: usize) {
        match self.max_tag {
            Some(m) if tag <= m => self.late_tags.push((self.node_tags.len(), pos)),
            _ => self.max_tag = Some(tag),
        }
        self.node_tags.push(tag);
    }

    /// The error for a second node of tag `tag`, node `index`: at its line
    /// (or record), else at the `$Nodes` header.
    fn duplicate(&self, cur: &Cursor<'_>, header: usize, index: usize, tag: u64) -> MeshError {
        let pos = self
            .late_tags
            .binary_search_by_key(&index, |&(i, _)| i)
            .map_or(header, |k| self.late_tags[k].1);
        cur.error(pos, MeshErrorKind::DuplicateNode { tag })
    }

    /// Coordinates of a node whose tag was pushed before (4.1 gives a
    /// block's tags first, then its coordinates), read at `pos`.
    #[inline]
    pub(crate) fn push_xyz(&mut self, x: f64, y: f64, z: f64, tag: u64, pos: usize) {
        // The plane is the first node's z = const (a mesh drawn at z = 0.5
        // is as planar as one at 0): the node farthest off it is kept.
        if z > self.max_z.0 {
            self.max_z = (z, tag, pos);
        }
        if z < self.min_z.0 {
            self.min_z = (z, tag, pos);
        }
        self.sum_z += z;
        self.nodes.push([x, y]);
    }

    /// Called once all nodes are read: builds the tag → index map.
    pub(crate) fn finish_nodes(&mut self, cur: &Cursor<'_>, pos: usize) -> Result<()> {
        // z must be 0 up to rounding relative to the mesh size. Checked
        // here, before any cell: a mesh in another plane has flat cells in
        // xy, and "degenerate cell" would hide the cause.
        // One plane z = const (any const: a mesh drawn at z = 0.5 is as
        // planar as one at 0); else the node farthest from the nodes' mean z
        // is named, with that mean.
        if !self.nodes.is_empty() && self.max_z.0 != self.min_z.0 {
            let mean = self.sum_z / self.nodes.len() as f64;
            let bb = crate::bounding_box(self.nodes.iter().copied());
            let extent = (bb[1][0] - bb[0][0]).max(bb[1][1] - bb[0][1]).max(0.0);
            if self.max_z.0 - self.min_z.0 > Z_TOL * (extent + mean.abs()) {
                let (z, tag, at) = if self.max_z.0 - mean >= mean - self.min_z.0 {
                    self.max_z
                } else {
                    self.min_z
                };
                return Err(cur.error(
                    at,
                    MeshErrorKind::NotPlanar {
                        node: tag,
                        z,
                        plane: mean,
                    },
                ));
            }
        }
        let n = self.node_tags.len();
        if n >= u32::MAX as usize {
            return Err(cur.error(
                pos,
                MeshErrorKind::TooLarge {
                    what: "nodes",
                    limit: u64::from(u32::MAX) - 1,
                },
            ));
        }
        let first = self.node_tags.first().copied().unwrap_or(0);
        let consecutive = self
            .node_tags
            .iter()
            .enumerate()
            .all(|(i, &t)| first.checked_add(i as u64) == Some(t));
        let index = if consecutive {
            NodeIndex::Offset(first)
        } else {
            let min = self.node_tags.iter().copied().min().unwrap_or(0);
            let max = self.node_tags.iter().copied().max().unwrap_or(0);
            let span = max - min;
            if span <= 4 * n as u64 + 1024 {
                let mut table = vec![u32::MAX; span as usize + 1];
                for (i, &t) in self.node_tags.iter().enumerate() {
                    let slot = &mut table[(t - min) as usize];
                    if *slot != u32::MAX {
                        return Err(self.duplicate(cur, pos, i, t));
                    }
                    *slot = i as u32;
                }
                NodeIndex::Table { min, table }
            } else {
                let mut map = HashMap::with_capacity(n);
                for (i, &t) in self.node_tags.iter().enumerate() {
                    if map.insert(t, i as u32).is_some() {
                        return Err(self.duplicate(cur, pos, i, t));
                    }
                }
                NodeIndex::Map(map)
            }
        };
        self.index = Some(index);
        Ok(())
    }

    /// Reserves room for `count` more cells of `nodes` nodes, each taking at
    /// least `min_bytes` of the input left (so a false count cannot make a
    /// large allocation).
    pub(crate) fn expect_cells(
        &mut self,
        cur: &Cursor<'_>,
        count: u64,
        nodes: usize,
        min_bytes: usize,
    ) {
        let n = cur.capped(count, min_bytes);
        self.cells.reserve(n * nodes);
        self.cell_tags.reserve(n);
        self.cell_member.reserve(n);
    }

    #[inline]
    fn node_index(&self, tag: u64) -> Option<usize> {
        match self.index.as_ref()? {
            NodeIndex::Offset(first) => {
                let i = tag.checked_sub(*first)?;
                (i < self.nodes.len() as u64).then_some(i as usize)
            }
            NodeIndex::Table { min, table } => {
                let i = *table.get(usize::try_from(tag.checked_sub(*min)?).ok()?)?;
                (i != u32::MAX).then_some(i as usize)
            }
            NodeIndex::Map(map) => map.get(&tag).map(|&i| i as usize),
        }
    }

    /// Adds one element. `nodes` holds its Gmsh node tags (negative tags of
    /// 2.2 files are passed as `-1`, which never matches a node).
    /// `elementary` is the 2.2 elementary tag (to merge per-group copies);
    /// 4.1 passes `None` since it writes each element once.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn element(
        &mut self,
        cur: &Cursor<'_>,
        pos: usize,
        type_id: i32,
        tag: u64,
        nodes: &[u64],
        member: Membership,
        elementary: Option<i32>,
    ) -> Result<()> {
        if let Some(elementary) = elementary {
            let p = &self.prev;
            if p.valid
                && p.type_id == type_id
                && p.elementary == elementary
                && p.nodes.first() == nodes.first()
                && p.nodes.get(..nodes.len()) == Some(nodes)
            {
                return self.merge_previous(type_id, member);
            }
        }
        let mut idx = [0usize; 9];
        for (k, &t) in nodes.iter().enumerate() {
            match self.node_index(t) {
                Some(i) => idx[k] = i,
                None => {
                    let node = i64::try_from(t).unwrap_or(-1);
                    return Err(cur.error(pos, MeshErrorKind::MissingNode { element: tag, node }));
                }
            }
        }
        let index = match type_id {
            QUAD4 | QUAD9 => {
                let kind = if type_id == QUAD4 {
                    CellKind::Quad4
                } else {
                    CellKind::Quad9
                };
                match self.kind {
                    None => self.kind = Some(kind),
                    Some(k) if k != kind => {
                        return Err(cur.error(
                            pos,
                            MeshErrorKind::NotQuads {
                                found: "quad4 and quad9 cells together".into(),
                            },
                        ))
                    }
                    Some(_) => {}
                }
                if kind == CellKind::Quad9 {
                    // Gmsh's node order to the fem crate's, in one table (lib.rs).
                    let gmsh = idx;
                    for (fem, &g) in idx.iter_mut().zip(&GMSH_TO_FEM_QUAD9) {
                        *fem = gmsh[g];
                    }
                }
                let cell = &mut idx[..nodes.len()];
                match self.orientation(cell) {
                    Some(true) => {}
                    Some(false) => {
                        reverse(cell);
                        self.reoriented += 1;
                    }
                    None => {
                        return Err(cur.error(pos, MeshErrorKind::DegenerateCell { element: tag }))
                    }
                }
                if kind == CellKind::Quad9 {
                    let p: [[f64; 2]; 9] = std::array::from_fn(|k| self.nodes[cell[k]]);
                    if !quad9_inside_positive(&p) {
                        return Err(cur.error(pos, MeshErrorKind::InvertedCell { element: tag }));
                    }
                }
                self.cells.extend_from_slice(cell);
                self.cell_tags.push(tag);
                self.cell_member.push(member);
                self.cell_tags.len() - 1
            }
            LINE2 | LINE3 => {
                let mid = if type_id == LINE3 { idx[2] } else { usize::MAX };
                self.lines.push([idx[0], idx[1], mid]);
                self.line_tags.push(tag);
                self.line_member.push(member);
                self.line_pos.push(pos);
                self.counts[usize::from(type_id == LINE3)] += 1;
                self.lines.len() - 1
            }
            POINT => {
                self.points.push(idx[0]);
                self.point_member.push(member);
                self.counts[2] += 1;
                self.points.len() - 1
            }
            _ => return Err(unsupported(cur, pos, tag, type_id)),
        };
        if let Some(elementary) = elementary {
            self.prev.type_id = type_id;
            self.prev.elementary = elementary;
            self.prev.nodes[..nodes.len()].copy_from_slice(nodes);
            self.prev.index = index;
            self.prev.valid = true;
        }
        Ok(())
    }

    /// A 2.2 copy of the previous element for another physical group.
    fn merge_previous(&mut self, type_id: i32, member: Membership) -> Result<()> {
        let i = self.prev.index;
        let slot = match type_id {
            QUAD4 | QUAD9 => self.cell_member.get_mut(i),
            LINE2 | LINE3 => self.line_member.get_mut(i),
            _ => self.point_member.get_mut(i),
        };
        if let Some(slot) = slot {
            let old = *slot as usize;
            let mut tags = self.memberships.get(old).cloned().unwrap_or_default();
            tags.extend(
                self.memberships
                    .get(member as usize)
                    .into_iter()
                    .flatten()
                    .copied(),
            );
            let id = self.membership(tags);
            if let Some(slot) = match type_id {
                QUAD4 | QUAD9 => self.cell_member.get_mut(i),
                LINE2 | LINE3 => self.line_member.get_mut(i),
                _ => self.point_member.get_mut(i),
            } {
                *slot = id;
            }
        }
        Ok(())
    }

    /// `Some(true)` if the cell is counter-clockwise with positive Jacobian
    /// determinants at all four corners, `Some(false)` if all four are
    /// negative (clockwise), `None` if degenerate or tangled.
    fn orientation(&self, cell: &[usize]) -> Option<bool> {
        let p = |k: usize| self.nodes[cell[k]];
        let sq = |v: [f64; 2]| v[0] * v[0] + v[1] * v[1];
        let mut sign = 0i8;
        if cell.len() == 4 {
            // Quad4: the tangents at corner i are the sides e_i = p_{i+1} - p_i
            // and -e_{i-1}; each side and its squared length is computed
            // once for its two corners (the same numbers, bit for bit, as
            // computing them per corner).
            let c = [p(0), p(1), p(2), p(3)];
            let e: [[f64; 2]; 4] = std::array::from_fn(|i| {
                let n = c[(i + 1) % 4];
                [n[0] - c[i][0], n[1] - c[i][1]]
            });
            let l2 = e.map(sq);
            for i in 0..4 {
                let prev = (i + 3) % 4;
                let b = [-e[prev][0], -e[prev][1]];
                corner_sign(e[i], b, l2[i], l2[prev], &mut sign)?;
            }
        } else {
            for i in 0..4 {
                let (next, prev) = ((i + 1) % 4, (i + 3) % 4);
                let c = p(i);
                // Quad9: the tangents of the two sides leaving corner i are
                // the derivatives of the quadratic side through corner,
                // mid-side node and far corner, (-3 c + 4 m - far) / 2.
                let (mn, mp) = (p(4 + i), p(4 + prev));
                let (fnx, fpr) = (p(next), p(prev));
                let t = |m: [f64; 2], f: [f64; 2]| {
                    [
                        0.5 * (-3.0 * c[0] + 4.0 * m[0] - f[0]),
                        0.5 * (-3.0 * c[1] + 4.0 * m[1] - f[1]),
                    ]
                };
                let (a, b) = (t(mn, fnx), t(mp, fpr));
                corner_sign(a, b, sq(a), sq(b), &mut sign)?;
            }
        }
        Some(sign > 0)
    }

    /// Checks the whole mesh and assembles the groups.
    pub(crate) fn finish(self, cur: &Cursor<'_>) -> Result<Mesh> {
        let Builder {
            version,
            binary,
            mut nodes,
            mut node_tags,
            memberships,
            names,
            kind,
            mut cells,
            cell_tags,
            cell_member,
            reoriented,
            lines,
            line_tags,
            line_member,
            line_pos,
            points,
            point_member,
            counts,
            ..
        } = self;
        let Some(kind) = kind else {
            return Err(MeshError::new(MeshErrorKind::NoCells));
        };
        let npc = kind.nodes_per_cell();

        // Groups, keyed (dim, tag) so the BTreeMap gives the required order.
        let mut acc: BTreeMap<(u8, i32), Group> = BTreeMap::new();
        fn ensure(
            acc: &mut BTreeMap<(u8, i32), Group>,
            names: &BTreeMap<(u8, i32), String>,
            dim: u8,
            tag: i32,
        ) -> (u8, i32) {
            acc.entry((dim, tag)).or_insert_with(|| Group {
                name: names
                    .get(&(dim, tag))
                    .cloned()
                    .unwrap_or_else(|| format!("#{tag}")),
                tag,
                dim,
                edges: Vec::new(),
                cells: Vec::new(),
                points: Vec::new(),
                nodes: Vec::new(),
                elements: 0,
            });
            (dim, tag)
        }
        let group =
            |acc: &mut BTreeMap<(u8, i32), Group>, dim: u8, tag: i32| ensure(acc, &names, dim, tag);
        // Named groups of dimension 0-2 exist even without elements.
        for &(dim, tag) in names.keys() {
            if dim <= 2 {
                group(&mut acc, dim, tag);
            }
        }
        // Cells by runs of equal membership (Gmsh writes a surface's cells
        // together): one group lookup per run, and each group's cell list
        // allocated once at its final length.
        let mut per_member = vec![0usize; memberships.len()];
        for &m in &cell_member {
            if let Some(n) = per_member.get_mut(m as usize) {
                *n += 1;
            }
        }
        for (m, &n) in per_member.iter().enumerate().filter(|&(_, &n)| n > 0) {
            for &t in memberships.get(m).into_iter().flatten() {
                let k = group(&mut acc, 2, t);
                if let Some(g) = acc.get_mut(&k) {
                    g.cells.reserve_exact(n);
                }
            }
        }
        let mut c0 = 0;
        while let Some(&m) = cell_member.get(c0) {
            let run = cell_member[c0..].iter().take_while(|&&x| x == m).count();
            for &t in memberships.get(m as usize).into_iter().flatten() {
                let k = group(&mut acc, 2, t);
                if let Some(g) = acc.get_mut(&k) {
                    g.cells.extend(c0..c0 + run);
                    g.elements += run;
                }
            }
            c0 += run;
        }
        for (i, &m) in point_member.iter().enumerate() {
            for &t in memberships.get(m as usize).into_iter().flatten() {
                let k = group(&mut acc, 0, t);
                if let Some(g) = acc.get_mut(&k) {
                    g.points.push(points[i]);
                    g.elements += 1;
                }
            }
        }

        // Boundary lines of groups: find the cell side each one is.
        let grouped: Vec<usize> = (0..lines.len()).filter(|&l| line_member[l] != 0).collect();
        let mut marked = vec![false; if grouped.is_empty() { 0 } else { nodes.len() }];
        // Side → the first cell having it (cell, side), and whether a second
        // cell has it too (the line is inside the body).
        type Side = (Option<(usize, usize)>, bool);
        let mut sides: HashMap<(usize, usize), Side> = HashMap::with_capacity(grouped.len());
        for &l in &grouped {
            let [a, b, mid] = lines[l];
            if (mid == usize::MAX) != (kind == CellKind::Quad4) {
                let line = if mid == usize::MAX { "line2" } else { "line3" };
                return Err(cur.error(
                    line_pos[l],
                    MeshErrorKind::OrderMismatch {
                        element: line_tags[l],
                        line,
                        cells: kind.name(),
                    },
                ));
            }
            marked[a] = true;
            marked[b] = true;
            sides.insert((a.min(b), a.max(b)), (None, false));
        }
        if !grouped.is_empty() {
            for (c, cell) in cells.chunks_exact(npc).enumerate() {
                for i in 0..4 {
                    let (a, b) = (cell[i], cell[(i + 1) % 4]);
                    if marked[a] && marked[b] {
                        if let Some(slot) = sides.get_mut(&(a.min(b), a.max(b))) {
                            match slot.0 {
                                None => slot.0 = Some((c, i)),
                                Some(_) => slot.1 = true,
                            }
                        }
                    }
                }
            }
        }
        let mut interior_edges = BTreeMap::new();
        for &l in &grouped {
            let [a, b, mid] = lines[l];
            let (found, shared) = sides
                .get(&(a.min(b), a.max(b)))
                .copied()
                .unwrap_or((None, false));
            let edge = found.and_then(|(c, i)| {
                let cell = cells.get(c * npc..(c + 1) * npc)?;
                if mid != usize::MAX && cell.get(4 + i) != Some(&mid) {
                    return None;
                }
                let nodes = if cell[i] == a { [a, b] } else { [b, a] };
                Some(Edge {
                    nodes,
                    mid: (mid != usize::MAX).then_some(mid),
                    cell: c,
                })
            });
            for &t in memberships
                .get(line_member[l] as usize)
                .into_iter()
                .flatten()
            {
                let k = group(&mut acc, 1, t);
                let Some(g) = acc.get_mut(&k) else { continue };
                match edge {
                    Some(e) => {
                        g.edges.push(e);
                        g.elements += 1;
                        if shared {
                            *interior_edges.entry(t).or_insert(0) += 1;
                        }
                    }
                    None => {
                        return Err(cur.error(
                            line_pos[l],
                            MeshErrorKind::EdgeNotOnCell {
                                element: line_tags[l],
                                group: g.name.clone(),
                            },
                        ))
                    }
                }
            }
        }

        // Nodes in no cell (Gmsh's Mesh.SaveAll = 1 saves geometry points
        // such as a circle's centre) would be free, unloaded DOFs that make
        // K singular: drop them. Edges of groups are cell sides, so only
        // cells and points refer to dropped nodes.
        let mut used = vec![false; nodes.len()];
        for &n in &cells {
            used[n] = true;
        }
        let unused_nodes = used.iter().filter(|&&u| !u).count();
        if unused_nodes > 0 {
            let mut new = vec![usize::MAX; nodes.len()];
            let mut k = 0;
            for (i, &u) in used.iter().enumerate() {
                if u {
                    new[i] = k;
                    nodes[k] = nodes[i];
                    node_tags[k] = node_tags[i];
                    k += 1;
                }
            }
            nodes.truncate(k);
            node_tags.truncate(k);
            for n in &mut cells {
                *n = new[*n];
            }
            for g in acc.values_mut() {
                for e in &mut g.edges {
                    e.nodes = e.nodes.map(|n| new[n]);
                    e.mid = e.mid.map(|n| new[n]);
                }
                // A point on a dropped node leaves its group.
                let before = g.points.len();
                g.points.retain(|&p| used[p]);
                g.elements -= before - g.points.len();
                for p in &mut g.points {
                    *p = new[*p];
                }
            }
        }

        // Node sets: a mark array for big groups, sort + dedup for small ones.
        let mut mark = Vec::new();
        for g in acc.values_mut() {
            let touched: usize = g.cells.len() * npc + g.edges.len() * 3 + g.points.len();
            let mut list = Vec::with_capacity(touched.min(nodes.len()));
            let push_all = |f: &mut dyn FnMut(usize)| {
                for &c in &g.cells {
                    for &n in &cells[c * npc..(c + 1) * npc] {
                        f(n);
                    }
                }
                for e in &g.edges {
                    f(e.nodes[0]);
                    f(e.nodes[1]);
                    if let Some(m) = e.mid {
                        f(m);
                    }
                }
                for &p in &g.points {
                    f(p);
                }
            };
            if touched > nodes.len() / 8 {
                mark.clear();
                mark.resize(nodes.len(), false);
                push_all(&mut |n| mark[n] = true);
                list.extend(mark.iter().enumerate().filter(|(_, &m)| m).map(|(i, _)| i));
            } else {
                push_all(&mut |n| list.push(n));
                list.sort_unstable();
                list.dedup();
            }
            g.nodes = list;
        }

        let mut boundary_elements = BTreeMap::new();
        for (name, n) in ["line2", "line3", "point"].into_iter().zip(counts) {
            if n > 0 {
                boundary_elements.insert(name.to_string(), n);
            }
        }
        Ok(Mesh {
            nodes,
            node_tags,
            kind,
            cells,
            cell_tags,
            groups: acc.into_values().collect(),
            source: SourceInfo {
                version: version.to_string(),
                binary,
                reoriented,
                boundary_elements,
                unused_nodes,
                interior_edges,
            },
        })
    }
}

/// One corner of [`Builder::orientation`]: tangents `a`, `b` with squared
/// lengths `a2`, `b2`. `None` if the corner is degenerate
/// (`|det| <= TOL |a| |b|`) or its sign differs from the corners before.
#[inline(always)]
fn corner_sign(a: [f64; 2], b: [f64; 2], a2: f64, b2: f64, sign: &mut i8) -> Option<()> {
    let det = a[0] * b[1] - a[1] * b[0];
    // |det| > TOL |a| |b|, squared to save two square roots per corner:
    // hypot on every corner is a large share of the read
    // (docs/performance.md).
    let scale2 = a2 * b2;
    let bound2 = JACOBIAN_TOL * JACOBIAN_TOL * scale2;
    let clear = if bound2 >= f64::MIN_POSITIVE && scale2.is_finite() {
        // No square overflowed or lost precision below the normal range
        // (a det² that did is below bound2 either way). False also for NaN.
        det * det > bound2
    } else {
        // Extreme coordinates (below ~1e-70 or above ~1e150), a zero-length
        // side, or NaN: decide unsquared, as hypot neither overflows nor
        // underflows.
        det.abs() > JACOBIAN_TOL * a[0].hypot(a[1]) * b[0].hypot(b[1])
    };
    if !clear {
        return None;
    }
    let s = if det > 0.0 { 1 } else { -1 };
    if *sign != 0 && s != *sign {
        return None;
    }
    *sign = s;
    Some(())
}

/// Whether the Jacobian determinant of a counter-clockwise quad9 is positive
/// at its 9 nodes and 9 Gauss points. The corner test sees only the
/// corners; a mid-side or centre node pulled across the cell inverts it
/// inside.
fn quad9_inside_positive(p: &[[f64; 2]; 9]) -> bool {
    // Most cells of a Gmsh mesh are straight-sided (mid-side nodes at the
    // sides' midpoints, the centre at the corners' mean): their map is the
    // bilinear one, whose determinant is affine in ξ and in η and so
    // positive inside once it is at the corners. The full check, five
    // times dearer, is for curved cells only.
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let bilinear = [
        mid(p[0], p[1]),
        mid(p[1], p[2]),
        mid(p[2], p[3]),
        mid(p[3], p[0]),
        mid(mid(p[0], p[2]), mid(p[1], p[3])),
    ];
    let mut dev = 0.0f64;
    let mut size = 0.0f64;
    for k in 0..5 {
        let (q, b) = (p[4 + k], bilinear[k]);
        dev = dev.max((q[0] - b[0]).abs()).max((q[1] - b[1]).abs());
        let c = p[k % 4];
        size = size.max((c[0] - p[0][0]).abs()).max((c[1] - p[0][1]).abs());
    }
    // Rounding of Gmsh's coordinates (ASCII %.16g) is far below this.
    if dev <= 1e-12 * size {
        return true;
    }
    // False for NaN too.
    crate::basis::quad9_dets(&crate::basis::quad9_grid(p))
        .iter()
        .all(|&d| d > 0.0)
}

/// Reverses a cell's orientation keeping node 0: corners 0 3 2 1, and for
/// quad9 the mid-side nodes follow their sides (7 6 5 4), the centre stays.
fn reverse(cell: &mut [usize]) {
    cell.swap(1, 3);
    if cell.len() == 9 {
        cell.swap(4, 7);
        cell.swap(5, 6);
    }
}

#[cfg(test)]
mod tests {
    use super::{Builder, JACOBIAN_TOL};

    /// The corner test as first written (hypot per corner): the reference
    /// the squared form must agree with.
    fn reference(p: &[[f64; 2]]) -> Option<bool> {
        let mut sign = 0i8;
        for i in 0..4 {
            let (next, prev) = ((i + 1) % 4, (i + 3) % 4);
            let c = p[i];
            let (a, b) = if p.len() == 9 {
                let t = |m: [f64; 2], f: [f64; 2]| {
                    [
                        0.5 * (-3.0 * c[0] + 4.0 * m[0] - f[0]),
                        0.5 * (-3.0 * c[1] + 4.0 * m[1] - f[1]),
                    ]
                };
                (t(p[4 + i], p[next]), t(p[4 + prev], p[prev]))
            } else {
                let (n, q) = (p[next], p[prev]);
                ([n[0] - c[0], n[1] - c[1]], [q[0] - c[0], q[1] - c[1]])
            };
            let det = a[0] * b[1] - a[1] * b[0];
            let scale = a[0].hypot(a[1]) * b[0].hypot(b[1]);
            let s = if det > JACOBIAN_TOL * scale {
                1
            } else if det < -JACOBIAN_TOL * scale {
                -1
            } else {
                return None;
            };
            if sign != 0 && s != sign {
                return None;
            }
            sign = s;
        }
        Some(sign > 0)
    }

    /// Random quads (convex, clockwise, tangled, nearly flat, repeated
    /// corners) at magnitudes from 1e-200 to 1e200: same decision as the
    /// reference. Cells whose |det| is within rounding of the tolerance
    /// could differ in principle; none of these is that close.
    #[test]
    fn squared_corner_test_decides_as_hypot_does() {
        let mut x: u64 = 0x2545_f491_4f6c_dd1d;
        let mut rnd = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut seen = [0usize; 3];
        for k in 0..200_000 {
            let scale = [1e-200, 1e-160, 1e-75, 1e-3, 1.0, 1e6, 1e150, 1e160, 1e200][k % 9];
            let n = if k % 2 == 0 { 4 } else { 9 };
            let mut p: Vec<[f64; 2]> = (0..n).map(|_| [rnd(), rnd()]).collect();
            match k % 7 {
                // A unit square with small perturbations (valid, maybe flipped).
                0 | 1 => {
                    let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
                    for (i, q) in p.iter_mut().enumerate().take(4) {
                        *q = [sq[i][0] + 0.1 * rnd(), sq[i][1] + 0.1 * rnd()];
                    }
                    if n == 9 {
                        for i in 0..4 {
                            let (a, b) = (p[i], p[(i + 1) % 4]);
                            p[4 + i] = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                        }
                        p[8] = [0.5, 0.5];
                    }
                    if k % 7 == 1 {
                        p.swap(1, 3);
                        if n == 9 {
                            p.swap(4, 7);
                            p.swap(5, 6);
                        }
                    }
                }
                // Nearly flat: corner 2 almost on the line through 1 and 3.
                2 => {
                    let t = 1e-9 * (rnd() - 0.5);
                    p[2] = [0.5 * (p[1][0] + p[3][0]) + t, 0.5 * (p[1][1] + p[3][1]) - t];
                }
                // Two corners equal.
                3 => p[2] = p[1],
                _ => {}
            }
            for q in &mut p {
                q[0] *= scale;
                q[1] *= scale;
            }
            let mut b = Builder::new("4.1", false);
            for (i, q) in p.iter().enumerate() {
                b.push_node(i as u64 + 1, q[0], q[1], 0.0, 0);
            }
            let cell: Vec<usize> = (0..n).collect();
            let got = b.orientation(&cell);
            assert_eq!(got, reference(&p), "cell {p:?}");
            seen[match got {
                Some(true) => 0,
                Some(false) => 1,
                None => 2,
            }] += 1;
        }
        // All three outcomes occur, or the test checks little.
        assert!(seen.iter().all(|&s| s > 1000), "{seen:?}");
    }
}
