//! Stereo-camera navigation as modules on the bus.
//!
//! | module | what | answers |
//! | --- | --- | --- |
//! | `controller` | the simulated differential-drive base, or a walking robot's body-level Controller (its speeds into free-gait moves for the legged Controller) | `nav.drive`, `nav.truePose`, `nav.simStatus` |
//! | `legged-controller` | a walking robot's legged Controller (the quasi-static simulator; walking bases only) | `legged.legMove`, `legged.bodyMove`, `legged.bodyPose`, `legged.legState`, ... |
//! | `ism` | the simulated stereo camera (on the body of a walking robot) and drifting visual odometry | `nav.acquireDepth` |
//! | `ltm` | the frame-aged terrain map and the danger map | `nav.insertDepth`, `nav.dangerMap` |
//! | `navigator` | D* Lite over the danger map, exploration turns, the path follower | the `nav.navigate` goal, informing `nav.frame` every frame |
//!
//! The algorithms are those of `tca-nav-navigator`; these modules only carry its steps over
//! the bus, in the same order as its one-process loop, so a run here gives the same report
//! (apart from the loop rate, which here includes the round trips). [`run_on_bus`] runs one
//! with central in this process.

pub mod controller;
pub mod convert;
pub mod ism;
pub mod ltm;
pub mod navigator;
mod run;
mod system;
pub mod walking;

pub use run::{BusRun, RUN_TIMEOUT, run_on_bus, run_on_bus_with, run_with};
pub use system::{
    LEGGED_NAV_MODULES, LeggedBase, NAV_MODULES, NavBase, NavSetup, connect_all, connect_module,
};
