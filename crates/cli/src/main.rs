//! The `stickslip` command (being written).
fn main() {}
