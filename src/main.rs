//! The `tca` command.
fn main() {}
