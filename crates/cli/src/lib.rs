//! The `stickslip` command's library: case files ([`case`]), the HDF5
//! results and checkpoints ([`output`]), runs and checks ([`run`]), the
//! `mesh` report ([`mesh_cmd`]), the `probe` reader ([`probe`]), the
//! results file's protection ([`results_file`]) and the `advise` command
//! ([`advise`]: the cheapest configuration for a tolerance).
//!
//! This crate owns everything that touches files other than meshes and the
//! terminal; the numerics live in the library crates below it. It is a
//! library as well as the binary (`main.rs`, the command line) so that the
//! fuzz targets and tests can call the case reader directly.
//!
//! Exit codes (used by `main.rs`): 0 success; 2 bad input (case, mesh,
//! arguments); 1 a run that failed after it started; 130 interrupted.

pub mod advise;
pub mod case;
pub mod error;
pub mod mesh_cmd;
pub mod output;
pub mod probe;
pub mod results_file;
pub mod run;
pub mod stress_cmd;
pub mod views;
pub mod xdmf;
