//! `cargo xtask verify` and `cargo xtask figures`: run the stickslip-verify
//! binary (the integrators in-process, no HDF5) in the dev profile.

use std::path::Path;

/// `cargo xtask verify [--quick] [--bless] [--only SUITE]`: the table of
/// checks; fails when any check fails.
pub fn verify(root: &Path, args: &[String]) -> Result<(), String> {
    crate::cargo_run(root, "stickslip-verify", "verify", args)
}

/// `cargo xtask figures [--out DIR]`: docs/figures/*.png and *.svg.
pub fn figures(root: &Path, args: &[String]) -> Result<(), String> {
    crate::cargo_run(root, "stickslip-verify", "figures", args)
}
