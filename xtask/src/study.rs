//! `cargo xtask chart` and `cargo xtask stability`: run the stickslip-study
//! binary (the integrators in-process, no HDF5) in the dev profile.

use std::path::Path;

/// `cargo xtask chart [--quick] [--out DIR]`: the work-precision study,
/// docs/work-precision.csv, .png and .svg (`--quick`: a smoke test into
/// target/study-quick/).
pub fn chart(root: &Path, args: &[String]) -> Result<(), String> {
    crate::cargo_run(root, "stickslip-study", "chart", args)
}

/// `cargo xtask stability [--quick] [--out DIR]`: the stability map,
/// docs/stability-*.csv, .png and .svg.
pub fn stability(root: &Path, args: &[String]) -> Result<(), String> {
    crate::cargo_run(root, "stickslip-study", "stability", args)
}
