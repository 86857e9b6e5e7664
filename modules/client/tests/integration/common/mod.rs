//! Helpers shared by this crate's integration tests: the test kit's.

#![allow(unused_imports, unreachable_pub)]

pub use tca_testkit::{STEP, free_endpoint, unique_local_endpoint, within};
