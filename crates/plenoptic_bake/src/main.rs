//! The plenoptic command (being written).
fn main() {}
