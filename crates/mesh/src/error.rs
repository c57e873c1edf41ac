//! Typed mesh errors. Every error says where (file, line or byte offset) and
//! what to do; none of the reader's paths panics on bad input.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in the file a problem was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number (ASCII parts of a file).
    Line(usize),
    /// 0-based byte offset (binary parts of a file).
    Byte(usize),
    /// Not tied to a place in the file (e.g. an unknown group name).
    Nowhere,
}

/// What went wrong.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshErrorKind {
    /// The file could not be read.
    #[error("cannot read the file: {0}")]
    Io(String),
    /// The path names a directory.
    #[error("is a directory, not a mesh file; give the .msh file in it")]
    IsDirectory,
    /// The path names a device, FIFO or socket: it has no end to read to
    /// (`/dev/zero` would be read until memory runs out).
    #[error("not a regular file (a device, FIFO or socket); give the .msh file")]
    NotRegularFile,
    /// A physical group name that the mesh does not have.
    #[error("the mesh has no physical group {name:?}; it has: {}", available.join(", "))]
    UnknownGroup {
        /// The name asked for.
        name: String,
        /// The names the mesh has.
        available: Vec<String>,
    },
    /// A physical group name given to groups of several dimensions.
    #[error("the mesh has several physical groups called {name:?} ({}), so which one is meant is unknown; rename all but one in the .geo (e.g. Physical Curve(\"{name}_edge\")) and mesh again", groups.iter().map(|(d, t)| format!("dim {d} tag {t}")).collect::<Vec<_>>().join(", "))]
    AmbiguousGroup {
        /// The name asked for.
        name: String,
        /// Dimension and physical tag of each group with that name, in mesh order.
        groups: Vec<(u8, i32)>,
    },
    /// The file is empty or blank.
    #[error("the file is empty (it holds no text, or only blank space): the mesh was not saved into it; mesh and save again (`gmsh -2 FILE.geo -o FILE.msh`, or File > Export in Gmsh)")]
    EmptyFile,
    /// The file does not start with `$MeshFormat`.
    #[error("this is not a Gmsh .msh file (it does not start with $MeshFormat); export the mesh from Gmsh with File > Export > .msh or `gmsh -2 FILE.geo -o FILE.msh`")]
    NotMsh,
    /// A `$MeshFormat` version other than 2.2 or 4.1.
    #[error("MSH version {version} is not supported; write the mesh as MSH 4.1 or 2.2 (`gmsh -2 FILE.geo -format msh41` or `-format msh22`, or Mesh.MshFileVersion = 4.1)")]
    UnsupportedVersion {
        /// The version as written in the file.
        version: String,
    },
    /// A binary file written on a big-endian machine.
    #[error("the binary .msh file is big-endian; only little-endian binary files are read: re-export it as ASCII (Mesh.Binary = 0) or on a little-endian machine")]
    BigEndian,
    /// A binary file whose data size is not 8 bytes.
    #[error("the binary .msh file declares data-size {size}; only 8 (64-bit Gmsh) is read: re-export it as ASCII (Mesh.Binary = 0)")]
    UnsupportedDataSize {
        /// The data size from `$MeshFormat`.
        size: u64,
    },
    /// The file ends in the middle of a section.
    #[error("the file ends in the middle of {what}; it was probably cut short: copy it again or re-export it from Gmsh")]
    Truncated {
        /// What was being read.
        what: &'static str,
    },
    /// A section without its closing keyword.
    #[error("the {section} section has no closing {end}; the file is damaged or was edited by hand: re-export it from Gmsh")]
    MissingEnd {
        /// The section keyword, e.g. `$Nodes`.
        section: String,
        /// The closing keyword expected, e.g. `$EndNodes`.
        end: String,
    },
    /// An MSH 4.1 file of a partitioned mesh.
    #[error("the mesh is partitioned (it has $PartitionedEntities, as `gmsh -part N` writes); stickslip reads unpartitioned meshes only: mesh and save without `-part` (or call gmsh.model.mesh.unpartition() before writing)")]
    Partitioned,
    /// A section the reader needs is not in the file.
    #[error("the file has no {section} section; a mesh file needs $MeshFormat, $Nodes and $Elements: generate the 2-D mesh (`gmsh -2`) before saving")]
    MissingSection {
        /// The missing section keyword.
        section: &'static str,
    },
    /// A section given twice, or out of order.
    #[error("{found} appears where it cannot ({why}); the file is damaged or was assembled by hand: re-export it from Gmsh")]
    SectionOrder {
        /// The section keyword found.
        found: String,
        /// Why it is out of place.
        why: &'static str,
    },
    /// The number of entries in a section disagrees with its header.
    #[error("{section} declares {expected} {what}, but the section holds a different number; the file is damaged or was edited by hand: re-export it from Gmsh")]
    WrongCount {
        /// The section keyword.
        section: &'static str,
        /// What is counted ("nodes", "elements", "entity blocks" ...).
        what: &'static str,
        /// The count the header declares.
        expected: u64,
    },
    /// A field that should be a number is not (or does not fit its type).
    #[error("expected {what}, found {found:?}; the file is damaged or was edited by hand: fix that field or re-export the mesh from Gmsh")]
    NotANumber {
        /// What the field is.
        what: &'static str,
        /// The text found (shortened).
        found: String,
    },
    /// An ASCII record (one line) with too few or too many numbers.
    #[error("{record}, this line has {found}; every record of the mesh must be one whole line: the file is damaged or was edited by hand, re-export the mesh from Gmsh")]
    FieldCount {
        /// What the record needs, e.g. "a quad4 element needs 5 numbers
        /// (its tag and 4 node tags)".
        record: String,
        /// How many numbers its line has.
        found: usize,
    },
    /// Binary data in a file whose `$MeshFormat` says ASCII (file-type 0).
    #[error("binary data in a file whose $MeshFormat says ASCII (file-type 0): the header does not match the content; re-export the mesh from Gmsh, or, if the file was written binary, set its file-type back to 1 (`2.2 1 8` or `4.1 1 8` on the line after $MeshFormat)")]
    BinaryInAscii,
    /// ASCII text where a file whose `$MeshFormat` says binary has its
    /// byte-order integer.
    #[error("$MeshFormat says binary (file-type 1), but the file is ASCII text: the header does not match the content; set the file-type in $MeshFormat to 0 (the line `2.2 0 8` or `4.1 0 8`), or re-export the mesh from Gmsh")]
    AsciiInBinary,
    /// A `(dimension, tag)` named twice in `$PhysicalNames`.
    #[error("physical group (dim {dim}, tag {tag}) is named {name:?} here, but {} already named it {first_name:?}; a group has one name, so one of the two lines has a wrong tag (or is a copy): name each group once in the .geo (Physical {}(\"name\", TAG) = {{...}};) and mesh again, or fix the tag on one of the lines", place(first), physical_kind(*dim))]
    DuplicatePhysicalName {
        /// The group's dimension.
        dim: u8,
        /// The group's physical tag.
        tag: i32,
        /// The name given here.
        name: String,
        /// Where the first name was given.
        first: Location,
        /// The first name.
        first_name: String,
    },
    /// A binary file whose line ends were converted to CR LF.
    #[error("the binary .msh file was transferred in text mode: its line ends were turned into CR LF (\\r\\n), which also changes bytes inside the binary data; copy the file again in binary mode (e.g. FTP `binary`, or `*.msh binary` in .gitattributes) or re-export it from Gmsh")]
    TextModeTransfer,
    /// Something else that does not follow the MSH format.
    #[error("malformed file: {what}; re-export the mesh from Gmsh")]
    Malformed {
        /// What is wrong.
        what: String,
    },
    /// Two nodes with the same tag.
    #[error("node tag {tag} is given twice; node tags must be unique: re-export the mesh from Gmsh (Mesh.Renumber = 1)")]
    DuplicateNode {
        /// The repeated node tag.
        tag: u64,
    },
    /// An element uses a node tag that `$Nodes` does not define.
    #[error("element {element} uses node {node}, which $Nodes does not define; re-export the mesh from Gmsh (with Mesh.SaveAll = 0 only nodes of saved elements are written, so save the whole mesh)")]
    MissingNode {
        /// The element's Gmsh tag.
        element: u64,
        /// The undefined node tag.
        node: i64,
    },
    /// An element block refers to a geometric entity that `$Entities` does not
    /// list, so its physical groups are unknown.
    #[error("elements are on entity (dim {dim}, tag {tag}), which $Entities does not list, so their physical groups are unknown; re-export the mesh from Gmsh")]
    UnknownEntity {
        /// Entity dimension.
        dim: i32,
        /// Entity tag.
        tag: i32,
    },
    /// An element block whose type's dimension is not its entity's: a
    /// quad9 block on a curve took that curve's physical groups.
    #[error("a block of {name} elements (dim {type_dim}) is on entity (dim {dim}, tag {tag}): an element's dimension is its entity's; re-export the mesh from Gmsh")]
    BlockDimension {
        /// The block's element type name.
        name: &'static str,
        /// That type's dimension.
        type_dim: i32,
        /// Entity dimension.
        dim: i32,
        /// Entity tag.
        tag: i32,
    },
    /// An element type that stickslip cannot use.
    #[error("element {element} has type {type_id} ({name}); stickslip reads 2-D meshes of quad4 or quad9 cells with line2/line3 boundary elements and points: mesh in 2-D (`gmsh -2`) and keep 3-D entities out of the physical groups")]
    UnsupportedElement {
        /// The element's Gmsh tag.
        element: u64,
        /// Gmsh element type number.
        type_id: i32,
        /// Its Gmsh name, when known.
        name: &'static str,
    },
    /// An element of order 3 or more (`gmsh -order 3` and up).
    #[error("element {element} is a {name} (Gmsh type {type_id}), of order {order}; stickslip reads elements of order 1 or 2 only (quad4 or quad9 cells, line2 or line3 boundaries): mesh with `gmsh -order 1` or `-order 2` (Mesh.ElementOrder = 1 or 2)")]
    UnsupportedOrder {
        /// The element's Gmsh tag.
        element: u64,
        /// Gmsh element type number.
        type_id: i32,
        /// Its Gmsh name.
        name: &'static str,
        /// Its polynomial order (3 or more).
        order: u8,
    },
    /// 2-D cells that are not all quad4 or all quad9.
    #[error("the 2-D cells include {found}; stickslip needs all quad4 or all quad9 cells: in Gmsh add `Recombine Surface{{...}};` (or Mesh.RecombineAll = 1) for quadrilaterals, and for quad9 use Mesh.ElementOrder = 2 (or `gmsh -order 2`) with Mesh.SecondOrderIncomplete = 0")]
    NotQuads {
        /// The offending cell types, e.g. "tri3 (type 2)" or "quad4 and quad9".
        found: String,
    },
    /// Boundary elements of another order than the cells (line2 with quad9, line3 with quad4).
    #[error("boundary element {element} is a {line} but the cells are {cells}; regenerate the whole mesh with one element order (`gmsh -order 1` or `-order 2`)")]
    OrderMismatch {
        /// The element's Gmsh tag.
        element: u64,
        /// "line2" or "line3".
        line: &'static str,
        /// "quad4" or "quad9".
        cells: &'static str,
    },
    /// A cell with zero area or a non-positive Jacobian at a corner.
    #[error("cell {element} is degenerate or tangled (zero area, or a corner angle of 180 degrees or more); fix the geometry or the mesh size there and mesh again")]
    DegenerateCell {
        /// The cell's Gmsh tag.
        element: u64,
    },
    /// A quad9 whose corners are fine but whose mid-side or centre node
    /// turns it inside out somewhere inside.
    #[error("cell {element} is inverted inside: its Jacobian determinant is not positive at every node and Gauss point, so a mid-side or centre node lies outside the cell or across its middle; move that node, or mesh again with the curved cells untangled (Mesh.HighOrderOptimize = 2) or a finer size there")]
    InvertedCell {
        /// The cell's Gmsh tag.
        element: u64,
    },
    /// A boundary element of a physical group that is not the side of any cell.
    #[error("boundary element {element} of group {group:?} is not a side of any cell; a boundary group must consist of lines of the meshed surface's boundary (mesh curves and surface together, and do not mix meshes)")]
    EdgeNotOnCell {
        /// The element's Gmsh tag.
        element: u64,
        /// The group's name.
        group: String,
    },
    /// The file has no 2-D cells.
    #[error("the file has no quad cells; mesh the surface (`gmsh -2`), and either put the surface in a physical group or save all elements (Mesh.SaveAll = 1)")]
    NoCells,
    /// A node off the plane z = const the others lie in.
    #[error("node {node} has z = {z:?}, while the nodes' mean z is {plane:?}: the mesh is not in one plane z = const; stickslip reads plane meshes parallel to the xy-plane: build the geometry in the xy-plane and mesh it in 2-D (`gmsh -2`)")]
    NotPlanar {
        /// The node's tag.
        node: u64,
        /// Its z coordinate.
        z: f64,
        /// The mean z of the nodes.
        plane: f64,
    },
    /// More nodes or cells than the reader indexes.
    #[error("the mesh has more than {limit} {what}; split the problem")]
    TooLarge {
        /// What is too many.
        what: &'static str,
        /// The limit.
        limit: u64,
    },
}

/// "line 8", "byte 120": a place in the file for a message.
fn place(at: &Location) -> String {
    match at {
        Location::Line(l) => format!("line {l}"),
        Location::Byte(b) => format!("byte {b}"),
        Location::Nowhere => "an earlier line".into(),
    }
}

/// How a .geo declares a physical group of dimension `dim`.
fn physical_kind(dim: u8) -> &'static str {
    match dim {
        0 => "Point",
        1 => "Curve",
        2 => "Surface",
        _ => "Volume",
    }
}

/// A mesh error with its file and location.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshError {
    /// The file, when the mesh came from one.
    pub path: Option<PathBuf>,
    /// Line or byte offset.
    pub location: Location,
    /// The problem.
    pub kind: MeshErrorKind,
}

impl MeshError {
    /// An error not tied to a place in a file.
    pub fn new(kind: MeshErrorKind) -> Self {
        MeshError {
            path: None,
            location: Location::Nowhere,
            kind,
        }
    }
    /// An error at a place in the file.
    pub fn at(location: Location, kind: MeshErrorKind) -> Self {
        MeshError {
            path: None,
            location,
            kind,
        }
    }
    /// An I/O error on `path`.
    pub fn io(path: &Path, e: std::io::Error) -> Self {
        // What to do, where the OS says what is wrong.
        let next = match e.kind() {
            std::io::ErrorKind::NotFound => "; check the path, or make the mesh with Gmsh",
            std::io::ErrorKind::PermissionDenied => "; make it readable, or copy it where it is",
            _ => "",
        };
        MeshError {
            path: Some(path.to_path_buf()),
            location: Location::Nowhere,
            kind: MeshErrorKind::Io(format!("{e}{next}")),
        }
    }
    /// Attaches the file name.
    pub fn with_path(mut self, path: &Path) -> Self {
        self.path = Some(path.to_path_buf());
        self
    }
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.path {
            write!(f, "{}", p.display())?;
            match self.location {
                Location::Line(l) => write!(f, ":{l}")?,
                Location::Byte(b) => write!(f, " (byte {b})")?,
                Location::Nowhere => {}
            }
            write!(f, ": ")?;
        } else {
            match self.location {
                Location::Line(l) => write!(f, "line {l}: ")?,
                Location::Byte(b) => write!(f, "byte {b}: ")?,
                Location::Nowhere => {}
            }
        }
        write!(f, "{}", self.kind)
    }
}

impl std::error::Error for MeshError {}
