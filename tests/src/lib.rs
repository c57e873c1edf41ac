//! End-to-end tests of the `stickslip` binary live in `tests/tests/*.rs`; this
//! library only holds helpers they share.

use std::path::PathBuf;

/// The workspace root (the folder holding `cases/`).
pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ sits inside the workspace")
        .to_path_buf()
}
