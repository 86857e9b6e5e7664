//! Shared models of the single-leg walking testbed (the report, §2): leg kinematics and its
//! parameters, terrain height fields with ray casting, generic grids, the obstacle courses of
//! §7, random courses and ESRI ASCII terrain files.
//!
//! # Layout
//!
//! - [`params`]: every parameter of the mechanism, carriage, rails, scanner mount and the
//!   simulator, loaded from one TOML file (`params/leg.toml`, embedded as the default).
//! - [`frames`]: the carriage pose on the rails and the carriage/world/scanner transforms.
//! - [`kinematics`]: joint positions, forward and inverse kinematics (with an explicit elbow
//!   branch), the horizontal Jacobian, joint limits, limit switches and the compliance
//!   deflection model.
//! - [`grid`]: [`Grid<T>`], a regular XY grid with cell/world conversions, for terrain, maps
//!   and planners.
//! - [`terrain`]: [`HeightField`]: bilinear heights, foot-disc maxima and fast exact ray
//!   casting; [`terrain::asc`] reads and writes ESRI ASCII grid (`.asc`) files.
//! - [`course`]: the 11 x 6 m test pit with obstacle courses 1-4 and random courses, as
//!   public lists of named features rendered into height fields.
//!
//! # Frames
//!
//! - **World**: origin at a corner of the test pit at the nominal sand level; +X across the
//!   6 m pit, +Y along the rails (the 11 m direction, the direction of walking), +Z up.
//! - **Carriage**: origin on the leg's central (shoulder) column at the height of the
//!   horizontal links, axes parallel to the world's when level. The carriage moves along
//!   world Y only; its pose is [`CarriagePose`] `(y, roll, pitch)` with X and height fixed in
//!   the parameters: `p_W = (x, y, h) + Ry(pitch) Rx(roll) p_C`.
//! - **Joint space**: [`JointPosition`] `{ shoulder_rad, elbow_rad, vertical_m }`. The
//!   shoulder angle is measured from carriage +X, counter-clockwise seen from above; the elbow
//!   angle is the lower link's turn from the upper link (0 = straight); the vertical member
//!   hangs from the outer end of the lower link (as on the Ambler) and `vertical_m` is its
//!   extension from the link plane to the foot sole, so the sole is at carriage
//!   `z = -vertical_m`. The "leg position" is the centre of the foot sole.
//! - **Scanner**: fixed to the carriage, looking forward (+Y) and down; +X along the
//!   boresight, +Y left, +Z up ([`ScannerMount::carriage_from_scanner`]).
//!
//! With the shipped parameters the links are 1.3 + 1.2 m (2.5 m reach), the vertical member
//! extends 3.0 to 4.5 m and the link plane is 4.0 m above the sand, so the foot reaches from
//! 1.0 m above to 0.5 m below the nominal sand level.
//!
//! # Terrain files
//!
//! ESRI ASCII grids: a header (`ncols`, `nrows`, `xllcorner` or `xllcenter`, `yllcorner` or
//! `yllcenter`, `cellsize`, optional `NODATA_value`) then `nrows` lines of `ncols` heights.
//! **File row 0 is the northernmost row, i.e. the largest world Y**; columns run along +X;
//! each value is the height at its cell's centre. See [`terrain::asc`].
//!
//! Units are SI everywhere: metres, radians, seconds, newtons.

pub mod course;
pub mod frames;
pub mod grid;
pub mod kinematics;
pub mod params;
pub mod terrain;

pub use course::{Course, CourseError, Feature, FeatureKind, RandomCourseOptions};
pub use frames::CarriagePose;
pub use grid::{CellIndex, Grid, GridError};
pub use kinematics::{
    AxisLimits, ElbowBranch, Joint, JointPosition, KinematicsError, LegKinematics,
};
pub use params::{LegParams, ParamsError, RailParams, ScannerMount};
pub use terrain::{HeightField, RayHit, TerrainError};
