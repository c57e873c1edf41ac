//! The one error type that means "the user's input is wrong".
//!
//! Anything the user can fix by editing a case file, a mesh or the command
//! line is an [`InputError`]: reading a case, building its model and the
//! binary's own checks all return it, and the binary maps it to exit code 2
//! (any other failure of a started run is exit code 1).

/// Bad input: the message names the file, the line where there is one, what
/// is wrong and what to do. Several problems are separated by newlines.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InputError(pub String);

/// Problems listed at once, at most this many (thousands of tables with one
/// mistake each would bury the first).
pub const SHOWN: usize = 50;

/// `problems` one to a line, the first [`SHOWN`] and a count of the rest.
pub fn listed(mut problems: Vec<String>) -> String {
    if problems.len() > SHOWN {
        let more = problems.len() - SHOWN;
        problems.truncate(SHOWN);
        problems.push(format!(
            "and {more} more problems; fix the ones above and check again"
        ));
    }
    problems.join("\n")
}

impl From<stickslip_mesh::MeshError> for InputError {
    fn from(e: stickslip_mesh::MeshError) -> Self {
        InputError(e.to_string())
    }
}
