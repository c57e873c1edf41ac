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
    /// A physical group name that the mesh does not have.
    #[error("the mesh has no physical group {name:?}; it has: {}", available.join(", "))]
    UnknownGroup {
        /// The name asked for.
        name: String,
        /// The names the mesh has.
        available: Vec<String>,
    },
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
        MeshError { path: None, location: Location::Nowhere, kind }
    }
    /// An error at a place in the file.
    pub fn at(location: Location, kind: MeshErrorKind) -> Self {
        MeshError { path: None, location, kind }
    }
    /// An I/O error on `path`.
    pub fn io(path: &Path, e: std::io::Error) -> Self {
        MeshError { path: Some(path.to_path_buf()), location: Location::Nowhere, kind: MeshErrorKind::Io(e.to_string()) }
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
