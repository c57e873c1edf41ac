//! The stability map.
use std::path::Path;
/// Runs the stability study.
///
/// # Errors
/// Any failure.
pub fn main(_out: &Path, _quick: bool) -> Result<(), String> {
    Ok(())
}
