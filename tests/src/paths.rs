//! Where the tests find the workspace's files and put their own: the
//! workspace root and its committed meshes, found from this crate's
//! folder (the libraries know no path of the repository), and a scratch
//! directory per test.

use std::path::{Path, PathBuf};

use stickslip_mesh::Mesh;

use crate::scene::SceneError;

/// The workspace root (the folder holding `cases/`): the parent of this
/// crate's folder `tests/`.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits inside the workspace")
        .to_path_buf()
}

/// The committed mesh directory (`cases/meshes` of the workspace).
pub fn meshes_dir() -> PathBuf {
    workspace_root().join("cases/meshes")
}

/// Reads a committed mesh by file name.
///
/// # Errors
/// The file is missing or unreadable (the error names it).
pub fn read_mesh(name: &str) -> Result<Mesh, SceneError> {
    let path = meshes_dir().join(name);
    Mesh::from_file(&path).map_err(|source| SceneError::Mesh { path, source })
}
