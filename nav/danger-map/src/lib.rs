//! The danger map of Chilian and Hirschmüller, "Stereo Camera Based Navigation of Mobile
//! Robots on Rough Terrain": how hard each cell of a height grid is to cross for a robot
//! whose centre stands in it, whatever its heading.
//!
//! Over a circle of the robot's diameter around each cell:
//!
//! * **slope** `s`: the angle from vertical of the normal of the least-squares plane
//!   through the known heights;
//! * **roughness** `r`: the standard deviation of the heights from that plane;
//! * **step height** `h`: each cell of the circle gets a *temporary step height*, the
//!   largest height difference to a cell of a square window around it (11 x 11 cells by
//!   default) that is both higher than `h_crit` and steeper than `s_crit`; then
//!   `h = min(h_max, h_max * n_st / n_crit)` with `h_max` the largest temporary step height
//!   in the circle and `n_st` the number of its cells that have one.
//!
//! The danger is `d = α₁·s/s_crit + α₂·r/r_crit + α₃·h/h_crit`, or `∞` when any of `s`,
//! `r`, `h` passes its critical value. A cell whose circle holds too few known heights
//! (less than [`DangerParams::min_certainty`] of it) is unknown and gets `d = 1`. Every
//! cell also carries its *certainty*, the known fraction of its circle.
//!
//! [`DangerMap::update`] recomputes a patch (a new local map) plus a border of the robot's
//! radius, reading heights through [`HeightView`]: one view for cells that were
//! traversable and another, usually reaching further back in time, for cells that were
//! not (the terrain map's frame ageing).

mod assess;
mod error;
mod map;
mod params;

pub use assess::{CellDanger, HeightView, assess_cell, temporary_step};
pub use error::DangerError;
pub use map::{CellRect, DangerMap};
pub use params::DangerParams;
