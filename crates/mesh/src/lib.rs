//! Gmsh `.msh` import for 2-D quadrilateral meshes.
//!
//! This crate owns the mesh as the user made it in Gmsh: node coordinates,
//! quadrilateral cells (Q1 = quad4 or Q2 = quad9), and the physical groups
//! that name parts of the boundary ("contact", "support", "load"). It reads
//! MSH 2.2 and 4.1, ASCII and binary, checks what it read (orientation,
//! degenerate cells, boundary elements that are not on a cell edge) and says
//! clearly what is wrong. It knows nothing of materials, matrices or friction.
//!
//! Everything downstream reaches boundaries by group name only
//! ([`Mesh::group`]); Gmsh's node tags are kept ([`Mesh::node_tags`]) but all
//! indices in this crate's API are dense and 0-based.

#![forbid(unsafe_code)]

use std::collections::BTreeMap;

mod basis;
mod error;
mod msh;
mod quality;

pub use error::{Location, MeshError, MeshErrorKind};
pub use quality::{degenerate_cells, jacobian_ratio, Degenerate, DEGENERATE_RATIO};

/// Node order of a quad9 cell as used everywhere in stickslip (and by VTK /
/// XDMF `Quadrilateral_9`): the four corners counter-clockwise, then the
/// mid-side nodes of edges (0,1), (1,2), (2,3), (3,0), then the centre.
/// Gmsh writes exactly this order, so the conversion from Gmsh's order is the
/// identity permutation; it is kept as a table so the one place to change
/// it is here: `fem_node[i] = gmsh_node[GMSH_TO_FEM_QUAD9[i]]`.
pub const GMSH_TO_FEM_QUAD9: [usize; 9] = [0, 1, 2, 3, 4, 5, 6, 7, 8];

/// The kind of 2-D cell a mesh is made of (one kind per mesh).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellKind {
    /// 4-node bilinear quadrilateral (Gmsh type 3), corners counter-clockwise.
    Quad4,
    /// 9-node biquadratic quadrilateral (Gmsh type 10), order [`GMSH_TO_FEM_QUAD9`].
    Quad9,
}

impl CellKind {
    /// Nodes per cell: 4 or 9.
    pub fn nodes_per_cell(self) -> usize {
        match self {
            CellKind::Quad4 => 4,
            CellKind::Quad9 => 9,
        }
    }
    /// Nodes per boundary edge: 2 (line2) or 3 (line3).
    pub fn nodes_per_edge(self) -> usize {
        match self {
            CellKind::Quad4 => 2,
            CellKind::Quad9 => 3,
        }
    }
    /// Gmsh-style name used in reports and JSON: "quad4" / "quad9".
    pub fn name(self) -> &'static str {
        match self {
            CellKind::Quad4 => "quad4",
            CellKind::Quad9 => "quad9",
        }
    }
}

/// One boundary edge (a Gmsh line2/line3 element of a dimension-1 group),
/// oriented so that the cell it bounds lies on its left: walking from
/// `nodes[0]` to `nodes[1]` traverses that cell counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// Start and end node (dense indices).
    pub nodes: [usize; 2],
    /// Mid-side node of a line3 edge.
    pub mid: Option<usize>,
    /// The cell this edge is a side of.
    pub cell: usize,
}

/// A physical group: a named (or numbered, `"#3"`) set of elements.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// Name from `$PhysicalNames`, or `"#TAG"` for an unnamed group.
    pub name: String,
    /// Gmsh's physical tag.
    pub tag: i32,
    /// Dimension: 0 (points), 1 (boundary lines) or 2 (cells).
    pub dim: u8,
    /// Dimension-1 groups: the edges, in file order.
    pub edges: Vec<Edge>,
    /// Dimension-2 groups: the cell indices.
    pub cells: Vec<usize>,
    /// Dimension-0 groups: the point nodes.
    pub points: Vec<usize>,
    /// Every node touched by the group's elements, sorted, without repeats.
    pub nodes: Vec<usize>,
    /// Number of Gmsh elements in the group.
    pub elements: usize,
}

impl Group {
    /// The kind of Gmsh physical group it is declared as in a .geo:
    /// `"Point"`, `"Curve"` or `"Surface"` (`Physical Curve(..) = {..};`).
    pub fn physical_kind(&self) -> &'static str {
        match self.dim {
            0 => "Point",
            1 => "Curve",
            _ => "Surface",
        }
    }

    /// What to do about a group without elements, which Gmsh writes for a
    /// physical group whose entities are missing: "check the entities of
    /// its Physical Curve in the .geo".
    pub fn empty_remedy(&self) -> String {
        format!(
            "check the entities of its Physical {} in the .geo",
            self.physical_kind()
        )
    }
}

/// Where a mesh came from and what the checks did to it.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct SourceInfo {
    /// "2.2" or "4.1".
    pub version: String,
    /// Binary (`file-type 1`) or ASCII.
    pub binary: bool,
    /// Cells given clockwise by the file and re-oriented counter-clockwise.
    pub reoriented: usize,
    /// Boundary elements by type name ("line2", "line3", "point") → count.
    pub boundary_elements: BTreeMap<String, usize>,
    /// Nodes of the file used by no cell (geometry points saved with
    /// Gmsh's `Mesh.SaveAll = 1`, hand-edited leftovers), dropped on import.
    pub unused_nodes: usize,
    /// Dimension-1 groups with edges inside the body (sides of two cells,
    /// e.g. an embedded curve, `Line{5} In Surface{1}`): physical tag →
    /// number of such edges; groups on the boundary only are absent. Read
    /// it with [`Mesh::interior_edges`]. (Here rather than in [`Group`],
    /// whose literals other crates build.)
    pub interior_edges: BTreeMap<i32, usize>,
}

/// A 2-D quadrilateral mesh with named groups.
///
/// Invariants (established by the reader and its checks): every node is
/// used by a cell; every cell has `kind.nodes_per_cell()` valid node
/// indices, is counter-clockwise with a positive Jacobian determinant at its
/// corners (quad9: also at its other nodes and 3×3 Gauss points); every
/// edge of a dimension-1 group is a side of its `cell` and oriented with that cell on its left.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Node coordinates (x, y); z is dropped (must be 0 in a 2-D mesh).
    pub nodes: Vec<[f64; 2]>,
    /// Gmsh's tag of each node (`nodes[i]` had tag `node_tags[i]`).
    pub node_tags: Vec<u64>,
    /// Cell kind, the same for all cells.
    pub kind: CellKind,
    /// Cell connectivity, flat: cell `c` is
    /// `cells[c * n .. (c + 1) * n]` with `n = kind.nodes_per_cell()`.
    pub cells: Vec<usize>,
    /// Gmsh's element tag of each cell.
    pub cell_tags: Vec<u64>,
    /// Physical groups, sorted by dimension then tag.
    pub groups: Vec<Group>,
    /// Format details and check results.
    pub source: SourceInfo,
}

impl Mesh {
    /// Reads and checks a `.msh` file.
    ///
    /// # Errors
    /// Any I/O problem, a path that is not a regular file (a directory, a
    /// device, a FIFO), malformed or unsupported content, or failed check,
    /// as a [`MeshError`] naming the file and the line or byte offset.
    pub fn from_file(path: impl AsRef<std::path::Path>) -> Result<Mesh, MeshError> {
        let path = path.as_ref();
        // Only regular files, as a case's mesh.file: a device has no end
        // (`/dev/zero` was read until memory ran out) and opening a FIFO
        // blocks, so both are refused before the file is opened.
        let not_a_file = |meta: &std::fs::Metadata| {
            let kind = if meta.is_dir() {
                MeshErrorKind::IsDirectory
            } else {
                MeshErrorKind::NotRegularFile
            };
            MeshError::new(kind).with_path(path)
        };
        let meta = std::fs::metadata(path).map_err(|e| MeshError::io(path, e))?;
        if !meta.is_file() {
            return Err(not_a_file(&meta));
        }
        let file = std::fs::File::open(path).map_err(|e| MeshError::io(path, e))?;
        // What was opened, in case the path changed in between.
        let meta = file.metadata().map_err(|e| MeshError::io(path, e))?;
        if !meta.is_file() {
            return Err(not_a_file(&meta));
        }
        // Streamed through a window of 1 MiB: the file's bytes are never
        // all resident next to the mesh (the reader's peak-memory target,
        // below twice the mesh).
        msh::read_file(path, file, meta.len(), msh::CHUNK).map_err(|e| e.with_path(path))
    }

    /// Reads and checks a `.msh` file held in memory.
    ///
    /// # Errors
    /// As [`Mesh::from_file`], without a file name.
    pub fn from_bytes(bytes: &[u8]) -> Result<Mesh, MeshError> {
        msh::read(bytes)
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.cell_tags.len()
    }

    /// The node indices of cell `c`.
    pub fn cell(&self, c: usize) -> &[usize] {
        let n = self.kind.nodes_per_cell();
        &self.cells[c * n..(c + 1) * n]
    }

    /// The physical group called `name` (`"#3"` for an unnamed group 3).
    ///
    /// # Errors
    /// [`MeshErrorKind::UnknownGroup`] listing the names the mesh has;
    /// [`MeshErrorKind::AmbiguousGroup`] if groups of several dimensions
    /// have that name (Gmsh allows it; which one was meant is unknowable).
    pub fn group(&self, name: &str) -> Result<&Group, MeshError> {
        let named: Vec<&Group> = self.groups.iter().filter(|g| g.name == name).collect();
        match named[..] {
            [one] => Ok(one),
            [] => Err(MeshError::new(MeshErrorKind::UnknownGroup {
                name: name.to_string(),
                available: self.group_names().iter().map(|s| s.to_string()).collect(),
            })),
            _ => Err(MeshError::new(MeshErrorKind::AmbiguousGroup {
                name: name.to_string(),
                groups: named.iter().map(|g| (g.dim, g.tag)).collect(),
            })),
        }
    }

    /// How many edges of `group` lie inside the body, each a side of two
    /// cells: 0 for a boundary group (and for groups of dimension 0 or 2).
    /// Not an error (an interior line can be harmless), but as a traction or
    /// contact surface such a group would act inside the body.
    pub fn interior_edges(&self, group: &Group) -> usize {
        if group.dim != 1 {
            return 0;
        }
        self.source
            .interior_edges
            .get(&group.tag)
            .copied()
            .unwrap_or(0)
    }

    /// Names of all physical groups, in the order of [`Mesh::groups`].
    pub fn group_names(&self) -> Vec<&str> {
        self.groups.iter().map(|g| g.name.as_str()).collect()
    }

    /// Bounding box `[[xmin, ymin], [xmax, ymax]]` of the nodes.
    pub fn bbox(&self) -> [[f64; 2]; 2] {
        bounding_box(self.nodes.iter().copied())
    }
}

/// Bounding box `[[xmin, ymin], [xmax, ymax]]` of `points` (infinite bounds
/// the wrong way round when there are none).
pub fn bounding_box(points: impl IntoIterator<Item = [f64; 2]>) -> [[f64; 2]; 2] {
    let mut b = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
    for p in points {
        for k in 0..2 {
            b[0][k] = b[0][k].min(p[k]);
            b[1][k] = b[1][k].max(p[k]);
        }
    }
    b
}
