//! FootFall: single-step planning for one limb of an ATHLETE-like rover, after SunSpiral
//! et al.'s ground tools for ATHLETE. A pure algorithm crate: no bus, no clock.

pub mod astar;
pub mod campaign;
pub mod collision;
pub mod error;
pub mod ground;
pub mod maps;
pub mod margins;
pub mod picture;
pub mod plan;
pub mod reach;
pub mod reference;
pub mod sbl;
pub mod scene;
pub mod smooth;
pub mod terrain;
pub mod verify;

pub use error::{FootfallError, Result};
pub use nalgebra;
pub use scene::Scene;
