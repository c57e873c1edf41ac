//! The one error type that means "the user's input is wrong" (exit code 2).
//!
//! Anything the user can fix by editing a case file, a mesh or the command
//! line is an [`InputError`]; `main` maps it to exit code 2 and any other
//! failure of a started run to exit code 1. `run.rs` constructs it too (e.g. a
//! group the mesh does not have), so `main` finds it with
//! `anyhow::Error::downcast_ref::<InputError>()`.

use std::fmt;

/// Bad input: the message names the file, the line where there is one, what
/// is wrong and what to do. Several problems are separated by newlines.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputError(pub String);

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InputError {}

impl From<stickslip_mesh::MeshError> for InputError {
    fn from(e: stickslip_mesh::MeshError) -> Self {
        InputError(e.to_string())
    }
}
