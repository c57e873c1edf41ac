//! Where the tests find the workspace's files and put their own: the
//! workspace root and its committed meshes, found from this crate's
//! folder (the libraries know no path of the repository), and a scratch
//! directory per test.

use std::path::{Path, PathBuf};

use stickslip_mesh::Mesh;

use crate::scene::SceneError;

/// The workspace root (the folder holding `cases/`): the parent of this
/// crate's folder `tests/`, without symbolic links (paths the binary
/// prints compare equal).
pub fn workspace_root() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits inside the workspace");
    root.canonicalize().unwrap_or_else(|_| root.to_path_buf())
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
    Mesh::from_file(&path).map_err(|source| SceneError::Mesh {
        path,
        source: Box::new(source),
    })
}

/// A fresh, empty directory for one test's files, `tmp/BINARY-NAME` in the
/// target directory of the running test binary (Cargo's
/// `CARGO_TARGET_TMPDIR`, which a library cannot read): each worktree has
/// its own, a new run empties and reuses it, and `name` need only be
/// unique among the tests of one binary.
pub fn scratch(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    // Test binaries live in target/PROFILE/deps (examples in
    // target/PROFILE/examples) and are named NAME-HASH.
    let target = exe.ancestors().nth(3).expect("target/PROFILE/deps/BINARY");
    let stem = exe.file_stem().map(|s| s.to_string_lossy().into_owned());
    let stem = stem.unwrap_or_default();
    let binary = stem.rsplit_once('-').map_or(stem.as_str(), |(b, _)| b);
    let dir = target.join("tmp").join(format!("{binary}-{name}"));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir)
        .unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    dir
}
