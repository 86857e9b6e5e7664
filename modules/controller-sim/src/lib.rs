//! Simulated Controller (report 003, §4): the single leg, its carriage and the true terrain
//! behind the Controller's interface of §4.2.
//!
//! # Layout
//!
//! - [`sim`]: the pure, bus-free simulator core: [`sim::LegSimulator`] with `leg_move`,
//!   `body_move`, `set_trans_force` and the position and force queries, in simulated time,
//!   with fault injection for testing. The module wrapper that serves it on the message bus
//!   builds on it.

pub mod sim;
