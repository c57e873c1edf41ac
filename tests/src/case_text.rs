//! Case-file text the tests share.

use crate::paths::meshes_dir;

/// The start of a case on the paper's slab (the committed Q2 8 × 2 mesh,
/// E = 1000, ν = 0.3, ρ = 1): its `[mesh]` and `[material]` tables, one
/// key a line and a newline at the end, so a test appends its own tables
/// (or further `[material]` keys) and counts lines in the whole text.
pub fn paper_slab_head() -> String {
    format!(
        "[mesh]\nfile = \"{}\"\n[material]\nE = 1000.0\nnu = 0.3\nrho = 1.0\n",
        meshes_dir().join("slab-q2-8x2.msh").display()
    )
}
