//! Integration tests of this crate, one module per area, linked into a single test
//! binary: each separate binary re-linked the whole dependency graph, which made test
//! builds the larger part of CI's time. Run one area with
//! `cargo test --release --test integration <module>::`.

mod common;

mod properties;
mod walking;
