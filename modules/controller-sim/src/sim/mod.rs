//! The pure simulator core: the Controller interface of §4.2 as a plain struct, with no
//! bus, no async and no sleeping.
//!
//! [`LegSimulator`] holds the true terrain, the carriage position, the joint positions, the
//! foot's contact with the ground, the transition force set point and a simulated clock.
//! Commands (`leg_move`, `body_move`, `set_trans_force`) advance the clock by the time the
//! real mechanism would take; queries (`body_position`, `joint_leg_position`,
//! `cart_leg_position`, `global_leg_position`, `read_force`) answer from the state.
//!
//! The foot is modelled as a disc of the foot's radius at the bottom of the vertical member;
//! the member is no wider than the foot, so checking the terrain under the disc covers it,
//! and the horizontal links run far above the highest terrain (checked at start).
//! A foot on the ground is *planted*: its world position is pinned, and the force on it is
//! the contact stiffness times how far the vertical axis has pressed past the touch point.
//!
//! # Layout
//!
//! - [`trajectory`]: joint-space trajectories through way-points (speed-scaled segments,
//!   constant-acceleration blends).
//! - `leg_move.rs`: `legMove`, with terrain checks along the path and transition mode.
//! - `body_move.rs`: `bodyMove`: compress, relieve, propel (servo or open loop), relieve
//!   strain; `body_move_law.rs`: the choice of [`BodyMoveLaw`].
//! - `drive.rs`: how the planted foot drives the carriage: the compliant leg, the rails'
//!   breakaway and rolling friction, the foot's traction.
//! - [`faults`]: fault injection ([`FaultConfig`]).
//! - [`report`]: move reports and force readings.
//! - [`error`]: [`SimError`] and its [`FailureKind`].

#[cfg(test)]
mod accuracy_tests;
mod body_move;
mod body_move_law;
mod drive;
pub mod error;
pub mod faults;
mod leg_move;
pub mod report;
pub mod trajectory;

use std::time::Duration;

use nalgebra::{Point2, Point3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tca_robot::{CarriagePose, ElbowBranch, HeightField, JointPosition, LegKinematics, LegParams};

pub use body_move_law::{BodyMoveLaw, UnknownBodyMoveLaw};
pub use error::{FailureKind, Result, SimError};
pub use faults::{FaultConfig, FaultKind, JointNoise, ScheduledFault};
pub use report::{BodyMoveReport, Contact, ForceReading, MoveReport, PathSample};
pub use trajectory::JointTrajectory;

/// Clearance kept between the horizontal links and the highest terrain, metres.
const LINK_CLEARANCE_M: f64 = 0.5;
/// A start pose may put the foot this far into the terrain (rounding), metres.
const START_TOLERANCE_M: f64 = 1e-3;

/// Where the leg starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StartPose {
    /// The leg at these joints, the foot in the air (or just touching the ground).
    Joints {
        /// Carriage position along the rails, metres.
        carriage_y_m: f64,
        /// Joint position.
        joints: JointPosition,
    },
    /// The foot planted on the ground under a world XY point, loaded with `force_n`.
    PlantedAt {
        /// Carriage position along the rails, metres.
        carriage_y_m: f64,
        /// World XY of the foot.
        foot_xy: Point2<f64>,
        /// Elbow branch of the leg.
        branch: ElbowBranch,
        /// Force on the foot, newtons (0 = just touching).
        force_n: f64,
    },
}

/// The dynamic state of a [`LegSimulator`] ([`LegSimulator::state`]), saved so a restarted
/// Controller finds the leg where it was.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimState {
    /// The carriage.
    pub carriage: CarriagePose,
    /// The joints.
    pub joints: JointPosition,
    /// Where the planted foot is pinned (world frame, metres), if it stands.
    pub planted: Option<[f64; 3]>,
    /// Horizontal ground force on the foot (carriage axes), newtons.
    pub lateral_force_n: [f64; 2],
    /// Transition force set point, newtons.
    pub trans_force_n: f64,
    /// Simulated clock, nanoseconds.
    pub clock_ns: u64,
}

/// The simulated leg, carriage and terrain behind the Controller interface.
///
/// # Example
///
/// ```
/// use nalgebra::Point2;
/// use tca_controller_sim::sim::{LegSimulator, StartPose};
/// use tca_robot::{Course, ElbowBranch, JointPosition, LegParams};
///
/// let terrain = Course::builtin(1)?.height_field()?;
/// let start = StartPose::PlantedAt {
///     carriage_y_m: 1.0,
///     foot_xy: Point2::new(3.8, 1.2),
///     branch: ElbowBranch::Positive,
///     force_n: 2224.1,
/// };
/// let mut sim = LegSimulator::new(LegParams::default(), terrain, start)?;
/// // Lift the foot 30 cm, then lower it again in transition mode: it stops on the ground
/// // when the force reaches the set point.
/// let q = sim.joint_leg_position();
/// sim.leg_move(&[JointPosition { vertical_m: q.vertical_m - 0.3, ..q }], false)?;
/// let report = sim.leg_move(&[q], true)?;
/// assert!(report.contact.is_some());
/// // Walk the carriage half a metre forward over the planted foot.
/// sim.body_move(1.5)?;
/// assert!((sim.body_position().y_m - 1.5).abs() <= 0.01);
/// assert!(sim.clock().as_secs_f64() > 20.0); // simulated time; nothing slept
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct LegSimulator {
    params: LegParams,
    kin: LegKinematics,
    terrain: HeightField,
    carriage: CarriagePose,
    joints: JointPosition,
    /// World position of the foot when it stands on the ground.
    planted: Option<Point3<f64>>,
    /// Horizontal force of the ground on the foot (carriage axes), newtons.
    lateral_force_n: [f64; 2],
    trans_force_n: f64,
    clock: Duration,
    faults: FaultConfig,
    rng: ChaCha8Rng,
    /// Body moves started so far (for scheduled faults).
    body_moves: u32,
    /// How body moves drive the joints.
    body_move_law: BodyMoveLaw,
}

impl LegSimulator {
    /// A simulator over `terrain` with the leg at `start`, no faults.
    pub fn new(params: LegParams, terrain: HeightField, start: StartPose) -> Result<Self> {
        params.validate().map_err(|e| SimError::InvalidStart {
            reason: e.to_string(),
        })?;
        let kin = LegKinematics::new(&params);
        let link_plane = params.carriage.link_plane_height_m;
        if terrain.max_height_m() > link_plane - LINK_CLEARANCE_M {
            return Err(SimError::InvalidStart {
                reason: format!(
                    "the terrain rises to {:.2} m, within {LINK_CLEARANCE_M} m of the horizontal links at {link_plane:.2} m",
                    terrain.max_height_m()
                ),
            });
        }
        let (carriage_y_m, joints, planted) = match start {
            StartPose::Joints {
                carriage_y_m,
                joints,
            } => (carriage_y_m, joints, None),
            StartPose::PlantedAt {
                carriage_y_m,
                foot_xy,
                branch,
                force_n,
            } => {
                if !(force_n.is_finite() && force_n >= 0.0) {
                    return Err(SimError::InvalidStart {
                        reason: format!("start force {force_n} N must be 0 or more"),
                    });
                }
                let h = terrain.max_height_in_disc(foot_xy, params.leg.foot_radius_m);
                let foot = Point3::new(foot_xy.x, foot_xy.y, h);
                let mut q = kin
                    .inverse_world(&CarriagePose::level(carriage_y_m), &foot, branch)
                    .map_err(|e| SimError::InvalidStart {
                        reason: format!("the foot cannot reach {foot}: {e}"),
                    })?;
                q.vertical_m += force_n / params.contact.stiffness_n_per_m;
                (carriage_y_m, q, Some(foot))
            }
        };
        if !(carriage_y_m >= params.rails.y_min_m && carriage_y_m <= params.rails.y_max_m) {
            return Err(SimError::InvalidStart {
                reason: format!(
                    "carriage y = {carriage_y_m} m is off the rails [{}, {}] m",
                    params.rails.y_min_m, params.rails.y_max_m
                ),
            });
        }
        kin.check_limits(&joints)
            .map_err(|e| SimError::InvalidStart {
                reason: e.to_string(),
            })?;
        let trans_force_n = params.contact.default_transition_force_n;
        let sim = Self {
            params,
            kin,
            terrain,
            carriage: CarriagePose::level(carriage_y_m),
            joints,
            planted,
            lateral_force_n: [0.0; 2],
            trans_force_n,
            clock: Duration::ZERO,
            faults: FaultConfig::none(),
            rng: ChaCha8Rng::seed_from_u64(0),
            body_moves: 0,
            body_move_law: BodyMoveLaw::Servo,
        };
        if sim.planted.is_none() {
            let foot = sim.free_foot(&sim.joints);
            let gap = sim.gap(&foot);
            if gap < -START_TOLERANCE_M {
                return Err(SimError::InvalidStart {
                    reason: format!(
                        "the start pose puts the foot {:.3} m into the terrain",
                        -gap
                    ),
                });
            }
        }
        Ok(sim)
    }

    /// Sets the faults to inject (and reseeds their generator).
    pub fn set_faults(&mut self, faults: FaultConfig) -> Result<()> {
        faults.validate()?;
        self.rng = ChaCha8Rng::seed_from_u64(faults.seed);
        self.faults = faults;
        Ok(())
    }

    /// Chooses how body moves drive the joints (the servo unless set).
    pub fn set_body_move_law(&mut self, law: BodyMoveLaw) {
        self.body_move_law = law;
    }

    /// How body moves drive the joints.
    pub fn body_move_law(&self) -> BodyMoveLaw {
        self.body_move_law
    }

    /// The faults being injected.
    pub fn faults(&self) -> &FaultConfig {
        &self.faults
    }

    /// `setTransForce`: the force at which transition moves stop, newtons (above 0, at most
    /// the body move's compression force).
    pub fn set_trans_force(&mut self, newtons: f64) -> Result<()> {
        let max_n = self.params.body_move.compress_force_n;
        if !(newtons.is_finite() && newtons > 0.0 && newtons <= max_n) {
            return Err(SimError::InvalidForce { newtons, max_n });
        }
        self.trans_force_n = newtons;
        Ok(())
    }

    /// The transition force set point, newtons.
    pub fn trans_force_n(&self) -> f64 {
        self.trans_force_n
    }

    /// `bodyPosition`: the carriage pose (world Y, roll, pitch).
    pub fn body_position(&self) -> CarriagePose {
        self.carriage
    }

    /// `jointLegPosition`: the joint encoders.
    pub fn joint_leg_position(&self) -> JointPosition {
        self.joints
    }

    /// `cartLegPosition`: the foot in the carriage frame from the rigid kinematics of the
    /// joint encoders (what the real Controller computed; compliance is not in it).
    pub fn cart_leg_position(&self) -> Point3<f64> {
        self.kin.forward(&self.joints)
    }

    /// `globalLegPosition`: [`cart_leg_position`](Self::cart_leg_position) in the world frame.
    pub fn global_leg_position(&self) -> Point3<f64> {
        self.carriage
            .to_world(self.kin.carriage(), &self.cart_leg_position())
    }

    /// `readForce`: the force/torque sensor.
    pub fn read_force(&self) -> ForceReading {
        let f = Vector3::new(
            self.lateral_force_n[0],
            self.lateral_force_n[1],
            self.vertical_force_n(),
        );
        let h = self.params.leg.force_sensor_above_sole_m;
        // Moment about the sensor of the force applied at the sole, h below it.
        let r = Vector3::new(0.0, 0.0, -h);
        ForceReading {
            force_n: f,
            moment_nm: r.cross(&f),
        }
    }

    /// Simulated time since the simulator started.
    pub fn clock(&self) -> Duration {
        self.clock
    }

    /// Whether the foot stands on the ground.
    pub fn foot_planted(&self) -> bool {
        self.planted.is_some()
    }

    /// What changes as the leg moves (the terrain, parameters and faults are the
    /// configuration's): enough to put a new simulator where this one is.
    pub fn state(&self) -> SimState {
        SimState {
            carriage: self.carriage,
            joints: self.joints,
            planted: self.planted.map(|p| [p.x, p.y, p.z]),
            lateral_force_n: self.lateral_force_n,
            trans_force_n: self.trans_force_n,
            clock_ns: u64::try_from(self.clock.as_nanos()).unwrap_or(u64::MAX),
        }
    }

    /// Puts the leg, carriage, contact and clock where `state` says (from [`Self::state`] of a
    /// simulator on the same terrain).
    pub fn restore(&mut self, state: &SimState) {
        self.carriage = state.carriage;
        self.joints = state.joints;
        self.planted = state.planted.map(|[x, y, z]| Point3::new(x, y, z));
        self.lateral_force_n = state.lateral_force_n;
        self.trans_force_n = state.trans_force_n;
        self.clock = Duration::from_nanos(state.clock_ns);
    }

    /// Ground truth (not part of the Controller interface): where the foot sole centre
    /// really is, world frame, including compliance deflection.
    pub fn true_foot_position(&self) -> Point3<f64> {
        self.planted.unwrap_or_else(|| self.free_foot(&self.joints))
    }

    /// The true terrain.
    pub fn terrain(&self) -> &HeightField {
        &self.terrain
    }

    /// The parameters.
    pub fn params(&self) -> &LegParams {
        &self.params
    }

    /// The leg's kinematics.
    pub fn kinematics(&self) -> &LegKinematics {
        &self.kin
    }

    /// How long `leg_move` through these way-points would take from the current joints,
    /// without moving (nor checking terrain).
    pub fn move_duration(&self, waypoints: &[JointPosition]) -> Result<Duration> {
        self.validate_waypoints(waypoints)?;
        Ok(JointTrajectory::plan(&self.kin, &self.joints, waypoints).duration())
    }

    /// Where the foot is when not pinned to the ground: rigid kinematics plus the scaled
    /// compliance deflection for an unloaded foot.
    fn free_foot(&self, q: &JointPosition) -> Point3<f64> {
        let mut p = self.kin.forward(q);
        if self.faults.compliance_scale > 0.0 {
            p += self.faults.compliance_scale * self.kin.deflection(q, &Vector3::zeros());
        }
        self.carriage.to_world(self.kin.carriage(), &p)
    }

    /// Height of the foot sole above the highest terrain under the foot disc (negative when
    /// pressed into it), and that terrain height.
    fn gap_and_height(&self, foot: &Point3<f64>) -> (f64, f64) {
        let h = self
            .terrain
            .max_height_in_disc(Point2::new(foot.x, foot.y), self.params.leg.foot_radius_m);
        (foot.z - h, h)
    }

    fn gap(&self, foot: &Point3<f64>) -> f64 {
        self.gap_and_height(foot).0
    }

    /// Vertical force on a planted foot: stiffness times how far the free foot is below
    /// the pinned one.
    fn vertical_force_n(&self) -> f64 {
        self.planted.map_or(0.0, |p| {
            let free = self.free_foot(&self.joints);
            (self.params.contact.stiffness_n_per_m * (p.z - free.z)).max(0.0)
        })
    }

    fn validate_waypoints(&self, waypoints: &[JointPosition]) -> Result<()> {
        if waypoints.is_empty() {
            return Err(SimError::EmptyWaypoints);
        }
        for (index, w) in waypoints.iter().enumerate() {
            if !w.is_finite() {
                return Err(SimError::NotFinite {
                    what: format!("way-point {index} ({w:?})"),
                });
            }
            self.kin
                .check_limits(w)
                .map_err(|source| SimError::WaypointOutOfLimits { index, source })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
