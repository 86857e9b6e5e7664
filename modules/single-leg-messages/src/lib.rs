//! The walking system's vocabulary: every message the single-leg modules exchange (§4–§6),
//! with its units. SI units and radians throughout; world frame everywhere except
//! [`LegMove`], which is in joint space (§8.2).
//!
//! Frames (see `tca-robot`): world X across the 6 m pit, Y along the rails (the walking
//! direction), Z up, origin at a pit corner at the nominal sand level.
//!
//! # Layout
//!
//! One file, in sections by the module that handles the messages: geometry shared by all,
//! the Controller (§4.2), the Imaging Sensor Manager (§5.2.1), the Local Terrain Map Manager
//! (§5.2.2), the Perception Display Manager (§5.2.3), and planning (§6: the Gait Planner and
//! the Leg Recovery Planner).

use serde::{Deserialize, Serialize};

use tca_messages::message;

// ---------------------------------------------------------------------------------------------
// Geometry

/// A point in the world frame, metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldPoint {
    /// Across the pit.
    pub x_m: f64,
    /// Along the rails.
    pub y_m: f64,
    /// Up.
    pub z_m: f64,
}

/// A point in the carriage frame, metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CarriagePoint {
    /// Carriage X.
    pub x_m: f64,
    /// Carriage Y.
    pub y_m: f64,
    /// Carriage Z.
    pub z_m: f64,
}

/// A point on the ground plane (world X, Y), metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanePoint {
    /// World X.
    pub x_m: f64,
    /// World Y.
    pub y_m: f64,
}

/// Joint-space leg position.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joints {
    /// Shoulder angle from carriage +X, counter-clockwise seen from above.
    pub shoulder_rad: f64,
    /// Elbow angle relative to the upper link (0 = straight).
    pub elbow_rad: f64,
    /// Extension of the vertical member, link plane to foot sole.
    pub vertical_m: f64,
}

/// The carriage pose: position along the rails and rotations about world X and Y.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyPose {
    /// World Y of the carriage.
    pub y_m: f64,
    /// Rotation about world X.
    pub roll_rad: f64,
    /// Rotation about world Y.
    pub pitch_rad: f64,
}

/// The force/torque sensor's reading, in the foot frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ForceReading {
    /// Forces along X, Y, Z, newtons.
    pub force_n: [f64; 3],
    /// Moments about X, Y, Z, newton-metres.
    pub moment_n_m: [f64; 3],
}

// ---------------------------------------------------------------------------------------------
// Controller (§4.2)

/// Command: propel the carriage along the rails to a world Y position (compress the terrain at
/// 800 lb, relieve to 500 lb, then velocity control). The foot must be planted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyMove {
    /// Target world Y of the carriage.
    pub target_y_m: f64,
}
message!(BodyMove: command "bodyMove");

/// Command: move the leg through joint-space way-points (all joints arrive together at each).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LegMove {
    /// Way-points, in order; at least one.
    pub waypoints: Vec<Joints>,
    /// Make the last segment in transition mode: stop when the set force is reached; reaching
    /// the way-point without contact is an error.
    pub transition: bool,
}
message!(LegMove: command "legMove");

/// Command: set the force servoed to in transition moves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SetTransForce {
    /// Newtons.
    pub force_n: f64,
}
message!(SetTransForce: command "setTransForce");

/// Command: the emergency stop. From now on the Controller refuses every command, each
/// refusal raising [`HardwareFault`] (which halts a walk), until [`Resume`]. A move already
/// under way is carried out to its end.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Halt;
message!(Halt: command "halt");

/// Command: lifts an emergency stop ([`Halt`]): the Controller carries out commands again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resume;
message!(Resume: command "resume");

/// Query: the carriage pose in world coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyPosition;
message!(BodyPosition: query "bodyPosition" -> BodyPose);

/// Query: the leg position in joint coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointLegPosition;
message!(JointLegPosition: query "jointLegPosition" -> Joints);

/// Query: the leg (foot sole centre) position in the carriage frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CartLegPosition;
message!(CartLegPosition: query "cartLegPosition" -> CarriagePoint);

/// Query: the leg (foot sole centre) position in the world frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GlobalLegPosition;
message!(GlobalLegPosition: query "globalLegPosition" -> WorldPoint);

/// Query: the force/torque sensor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReadForce;
message!(ReadForce: query "readForce" -> ForceReading);

/// Query: the Controller's simulated clock and state (for timing reports).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ControllerStatus;
/// The Controller's status.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ControllerState {
    /// Simulated (or real) time since the Controller started, seconds.
    pub clock_s: f64,
    /// Whether the foot is on the ground carrying load.
    pub foot_planted: bool,
    /// Collisions of the leg with terrain so far.
    pub collisions: u32,
}
message!(ControllerStatus: query "controllerStatus" -> ControllerState);

/// What went wrong with a move.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MoveFailureKind {
    /// The leg or foot struck terrain.
    Collision,
    /// A transition move reached its way-point without touching the ground.
    NoContact,
    /// The foot slipped during a body move.
    Slip,
    /// The body move stopped at the leg's full extension.
    ExtensionLimit,
    /// The command was refused (bad way-points, beyond the rails, foot not planted...).
    Refused,
}

/// Exception: a leg or body move failed; the step ends and the Gait Planner replans from where
/// the leg is (§6.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MoveFailed {
    /// The command that failed (`legMove` or `bodyMove`).
    pub command: String,
    /// What happened.
    pub kind: MoveFailureKind,
    /// A sentence for people.
    pub detail: String,
    /// Where the foot is now, world frame.
    pub foot: WorldPoint,
}
message!(MoveFailed: exception "moveFailed");

/// Exception: a hardware fault (limit switch, force drop-off, servo error); the walk is killed
/// and the system halts gracefully (§6.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HardwareFault {
    /// A sentence for people.
    pub detail: String,
}
message!(HardwareFault: exception "hardwareFault");

// ---------------------------------------------------------------------------------------------
// Imaging Sensor Manager (§5.2.1)

/// The laser rangefinders of §2.2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SensorKind {
    /// 64 x 256 pixels, 80° x 30°, 8-bit range, 20 m ambiguity interval.
    Erim,
    /// 256 x 256 pixels, 60° x 60°, 12-bit range, 40 m ambiguity interval.
    Perceptron,
}

/// A homogeneous transform, row-major 4 x 4.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Row-major entries.
    pub m: [f64; 16],
}

/// Query: acquire one range/reflectance image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AcquireImage {
    /// Which scanner.
    pub sensor: SensorKind,
}

/// A range/reflectance image tagged with the scanner pose at acquisition.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangeImage {
    /// The scanner.
    pub sensor: SensorKind,
    /// Columns (azimuth).
    pub width: u32,
    /// Rows (elevation).
    pub height: u32,
    /// Range in counts of `range_resolution_m`, row-major, wrapped at the ambiguity interval.
    pub range_counts: Vec<u16>,
    /// Reflectance in counts, row-major.
    pub reflectance: Vec<u16>,
    /// Metres per range count.
    pub range_resolution_m: f64,
    /// Range ambiguity interval, metres.
    pub ambiguity_m: f64,
    /// Horizontal field of view, radians.
    pub azimuth_fov_rad: f64,
    /// Vertical field of view, radians.
    pub elevation_fov_rad: f64,
    /// Locus frame <- scanner frame (fixed).
    pub locus_from_scanner: Transform,
    /// Scanner frame <- body frame (calibration).
    pub scanner_from_body: Transform,
    /// Body frame <- global frame (the carriage pose at acquisition, from the Controller).
    pub body_from_global: Transform,
    /// Sequence number of the image since the ISM started.
    pub sequence: u64,
}
message!(AcquireImage: query "acquireImage" -> RangeImage);

// ---------------------------------------------------------------------------------------------
// Local Terrain Map Manager (§5.2.2)

/// Kinds of maps the LTM Manager serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum MapKind {
    /// Terrain elevation, metres.
    Elevation,
    /// Elevation, with each cell's uncertainty (standard deviation, metres).
    ElevationUncertainty,
    /// Footfall evaluation: how bad the terrain is for the 30 cm foot (0 = flat, larger is
    /// worse; metres of deviation from a plane over the foot's area).
    Footfall,
    /// Mean slope over the foot's area, radians.
    Slope,
    /// Whether the foot can reach each cell (value 1) or not (0), from the Leg Recovery
    /// Planner.
    Reachability,
}

/// One cell of a map.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum MapCell {
    /// Outside the polygon asked for, or never seen.
    Unknown,
    /// Hidden from the scanner by something in front; the terrain is at most this high.
    Occluded {
        /// Greatest elevation known possible there, metres.
        max_elevation_m: f32,
    },
    /// Seen.
    Known {
        /// The map's value (elevation m, footfall cost, slope rad).
        value: f32,
        /// Uncertainty of the elevation there (standard deviation, metres).
        sigma_m: f32,
    },
}

/// A rectangular grid of map cells; cell (ix, iy) is centred at
/// `(origin_x_m + ix * resolution_m, origin_y_m + iy * resolution_m)`, row-major by iy.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapGrid {
    /// The map kind.
    pub kind: MapKind,
    /// World X of cell (0, 0)'s centre.
    pub origin_x_m: f64,
    /// World Y of cell (0, 0)'s centre.
    pub origin_y_m: f64,
    /// Cell size.
    pub resolution_m: f64,
    /// Cells along X.
    pub nx: u32,
    /// Cells along Y.
    pub ny: u32,
    /// `nx * ny` cells.
    pub cells: Vec<MapCell>,
}

/// Query: a map of a region: a polygon (at least three points) and a resolution; the answer is
/// the enclosing rectangular grid with cells outside the polygon unknown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapRegion {
    /// The kind of map.
    pub kind: MapKind,
    /// The polygon's corners, world frame.
    pub polygon: Vec<PlanePoint>,
    /// Cell size, metres (> 0).
    pub resolution_m: f64,
    /// Acquire a fresh image first (when the carriage has moved since the last one).
    pub refresh: bool,
}
message!(MapRegion: query "mapRegion" -> MapGrid);

// ---------------------------------------------------------------------------------------------
// Perception Display Manager (§5.2.3)

/// Something drawn over a map picture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Overlay {
    /// A marker at a 3D position (its X, Y are drawn).
    Point {
        /// The position.
        at: WorldPoint,
        /// A label.
        label: String,
    },
    /// A polyline through positions (a leg path).
    Path {
        /// The positions.
        points: Vec<WorldPoint>,
        /// A label.
        label: String,
    },
}

/// Command: render a map of a region to a PNG file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderMap {
    /// The map to draw.
    pub region: MapRegion,
    /// What to draw over it.
    pub overlays: Vec<Overlay>,
    /// Where to write the PNG.
    pub path: String,
}
message!(RenderMap: command "renderMap");

// ---------------------------------------------------------------------------------------------
// Planning (§6)

/// Sequential or concurrent stepping (§3.3, §7.2): the same tree, different constraints.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum WalkMode {
    /// A step is planned only after the previous body move is achieved.
    Sequential,
    /// The next step is planned while the current one executes.
    Concurrent,
}

/// Goal: walk the carriage to a position on the rails (the user's one message).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Walk {
    /// Target world Y of the carriage.
    pub goal_y_m: f64,
    /// Stepping mode.
    pub mode: WalkMode,
}
message!(Walk: goal "walk");

/// Where a step starts, when it is planned ahead (concurrent walking): the carriage and the
/// foot as the previous step will leave them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepStart {
    /// Carriage Y after the previous body move.
    pub body_y_m: f64,
    /// The foot, planted at the previous footfall.
    pub foot: WorldPoint,
}

/// Goal: plan one step (footfall and body move), send its leg and body moves, and the next
/// step unless this one reaches the goal. Sent by the `walk` goal's handler for the first step
/// and by each step for the next (Figure 5), under the `walk` node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanStep {
    /// Step number, from 1.
    pub step: u32,
    /// Target world Y of the walk.
    pub goal_y_m: f64,
    /// Sequential or concurrent stepping.
    pub mode: WalkMode,
    /// Where the step starts, when planned before the previous step has executed
    /// (concurrent mode); `None`: ask the Controller.
    pub start: Option<StepStart>,
    /// The previous step's body move (concurrent mode): this step's leg move is planned and
    /// executed only after it is achieved.
    pub after_body_move: Option<tca_messages::MessageId>,
}
message!(PlanStep: goal "planStep");

/// Goal for the Leg Recovery Planner: move the foot to a footfall without striking terrain,
/// ending with a transition move onto the ground.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecoverLeg {
    /// The planned footfall (foot sole centre), world frame.
    pub footfall: WorldPoint,
    /// The carriage Y during the move.
    pub body_y_m: f64,
    /// The way the elbow must bend at the footfall (the body move that follows keeps it, so
    /// its reach depends on it); `None`: either.
    pub elbow: Option<ElbowSide>,
    /// Where the foot will stand when the move starts, world frame, when it is planned ahead
    /// (while the previous step still executes); `None`: where the foot is now.
    pub start_foot: Option<WorldPoint>,
}

/// The way the leg's elbow bends: the sign of the elbow angle (the two inverse-kinematics
/// solutions for one foot position).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ElbowSide {
    /// Elbow angle at or above zero.
    Positive,
    /// Elbow angle below zero.
    Negative,
}
message!(RecoverLeg: goal "recoverLeg");

/// Query to the Leg Recovery Planner: which cells of a region the foot can reach from where it
/// is without striking terrain (binary map: value 1 reachable, 0 not).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LegReachability {
    /// The region.
    pub polygon: Vec<PlanePoint>,
    /// Cell size, metres.
    pub resolution_m: f64,
    /// The carriage Y during the move.
    pub body_y_m: f64,
    /// Where the foot will start from, when planned ahead (concurrent walking); `None`: where
    /// the leg is now.
    pub start_foot: Option<WorldPoint>,
}
message!(LegReachability: query "legReachability" -> MapGrid);

/// Inform: a step's plan, for displays and logs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepPlanned {
    /// Step number.
    pub step: u32,
    /// Chosen footfall.
    pub footfall: WorldPoint,
    /// Planned carriage target.
    pub body_target_y_m: f64,
    /// Cost of the chosen cell.
    pub cost: f64,
}
message!(StepPlanned: inform "stepPlanned");

#[cfg(test)]
mod tests {
    use tca_messages::{Class, Message, class_of};

    use super::*;

    #[test]
    fn every_message_has_a_format() {
        fn check<M: Message>() {
            let f = M::format().unwrap_or_else(|e| panic!("{}: {e}", M::NAME));
            f.validate().unwrap();
            if class_of::<M>() == Class::Query {
                assert!(M::reply_format().unwrap().is_some(), "{}", M::NAME);
            }
        }
        check::<BodyMove>();
        check::<LegMove>();
        check::<SetTransForce>();
        check::<BodyPosition>();
        check::<JointLegPosition>();
        check::<CartLegPosition>();
        check::<GlobalLegPosition>();
        check::<ReadForce>();
        check::<ControllerStatus>();
        check::<MoveFailed>();
        check::<HardwareFault>();
        check::<AcquireImage>();
        check::<MapRegion>();
        check::<RenderMap>();
        check::<Walk>();
        check::<PlanStep>();
        check::<RecoverLeg>();
        check::<LegReachability>();
        check::<StepPlanned>();
    }
}
