//! Whole-system tests: the mission's promises, checked through the built `tca` binary, the
//! library crates and outside clients.
//!
//! One test binary holds every whole-system test, a module per subject. Linking one binary
//! instead of one per file keeps CI's build short, and the test harness can run a short test
//! of one subject beside a long one of another. Run one subject with its module's name as the
//! filter, for example `cargo test --release --test system bridge::`. The load check keeps
//! a binary of its own (`tests/load.rs`): the peak memory it measures must be its own.

mod common;

mod bridge;
mod bus;
mod bus_cli;
mod central_crash;
mod cgspace_workers;
mod chaos;
mod cli;
mod determinism;
mod footfall_processes;
mod foxglove_clients;
mod launcher_gone;
mod legged_processes;
mod legged_walk;
mod local_link;
mod map;
mod nav_options;
mod nav_processes;
mod plan_cgspace;
mod realtime;
mod replay;
mod tree;
mod walk;
mod walk_cgspace;
mod walk_processes;
mod walker_leaves;
