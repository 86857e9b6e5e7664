//! The Controller's state behind the bus: the simulator, the move in progress (in wall-clock
//! time), the simulated clock and the collision count. Synchronous and bus-free: every method
//! takes the wall-clock instant, so the timing logic is tested without sleeping.
//!
//! A command runs the simulator to the end of the move at once; the move then *plays out*
//! over `duration / k` of wall-clock time. Queries during that time see the leg part-way:
//! joints along the planned trajectory (leg moves) or interpolated between start and end
//! (body moves, with the carriage), and the force and foot contact of before the move.

use std::time::Duration;

use nalgebra::Point3;
use tca_robot::{CarriagePose, JointPosition, LegKinematics};
use tokio::time::Instant;

use crate::config::{ControllerConfig, Result, SpeedFactor};
use crate::convert::{Raised, exception_for};
use crate::sim::{ForceReading, JointTrajectory, LegSimulator, SimError};

/// What the Controller's queries answer at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snapshot {
    /// Carriage pose (`bodyPosition`).
    pub carriage: CarriagePose,
    /// Joint encoders (`jointLegPosition`).
    pub joints: JointPosition,
    /// Foot in the carriage frame (`cartLegPosition`).
    pub cart_leg: Point3<f64>,
    /// Foot in the world frame (`globalLegPosition`).
    pub global_leg: Point3<f64>,
    /// Force/torque sensor (`readForce`).
    pub force: ForceReading,
    /// Whether the foot stands on the ground.
    pub foot_planted: bool,
    /// Simulated time since the Controller started.
    pub clock: Duration,
    /// Collisions with the terrain so far.
    pub collisions: u32,
}

/// A Controller's state as [`Controller::saved`] returns it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SavedController {
    /// The simulator's leg, carriage, contact and clock.
    pub sim: crate::sim::SimState,
    /// Collisions so far.
    pub collisions: u32,
    /// Simulated idle time banked, nanoseconds.
    pub idle_ns: u64,
}

/// Why a command ended with failure.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CommandFailure {
    /// The reason sent back as the command's failure.
    pub reason: String,
    /// The exception to raise in the command's context (none for a refused
    /// `setTransForce`, which no planner recovers from).
    pub exception: Option<Raised>,
}

/// The result of starting a command: how long its handler must wait (wall clock) and how it
/// ends.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandRun {
    /// When it started.
    pub started: Instant,
    /// Wall-clock time the move plays out over.
    pub wall: Duration,
    /// Simulated time the move took.
    pub simulated: Duration,
    /// How it ends.
    pub outcome: std::result::Result<(), CommandFailure>,
}

/// A move playing out in wall-clock time.
#[derive(Debug, Clone)]
struct Motion {
    started: Instant,
    /// Simulated duration.
    duration: Duration,
    /// Wall-clock duration.
    wall: Duration,
    clock_before: Duration,
    carriage_before: CarriagePose,
    joints_before: JointPosition,
    force_before: ForceReading,
    planted_before: bool,
    /// Whether the move ends in a collision (counted once it has played out).
    collides: bool,
    path: MotionPath,
}

#[derive(Debug, Clone)]
enum MotionPath {
    /// A leg move along this trajectory.
    Leg(JointTrajectory),
    /// A body move: joints and carriage interpolated to the end state.
    Body,
}

/// The simulated Controller's state.
#[derive(Debug)]
pub struct Controller {
    sim: LegSimulator,
    speed: SpeedFactor,
    motion: Option<Motion>,
    collisions: u32,
    /// Simulated time accrued while idle (only when the speed factor is finite).
    idle: Duration,
    /// Since when the Controller is idle (meaningful when no move plays out).
    idle_since: Instant,
    /// The calibrated kinematics the joint interface compensates with, if any.
    calibrated: Option<LegKinematics>,
}

impl Controller {
    /// A Controller from its configuration, idle from `now`.
    pub fn new(config: &ControllerConfig, now: Instant) -> Result<Self> {
        config.speed.validate()?;
        let mut sim =
            LegSimulator::new(config.params.clone(), config.terrain.clone(), config.start)?;
        sim.set_faults(config.faults)?;
        sim.set_body_move_law(config.body_move_law);
        Ok(Self {
            sim,
            speed: config.speed,
            motion: None,
            collisions: 0,
            idle: Duration::ZERO,
            idle_since: now,
            calibrated: config
                .compensate_deflection
                .then(|| LegKinematics::compensated(&config.params)),
        })
    }

    /// The real joints that put the deflected foot where the ideal rigid leg at `ideal`
    /// would put it (the calibrated inverse kinematics); `ideal` itself without calibration
    /// or when the model has no solution.
    fn to_real(&self, ideal: &JointPosition) -> JointPosition {
        let Some(cal) = &self.calibrated else {
            return *ideal;
        };
        let target = self.sim.kinematics().forward(ideal);
        cal.inverse_nearest(&target, ideal).unwrap_or(*ideal)
    }

    /// The ideal rigid leg's joints for where the model says the real joints `real` put the
    /// foot.
    fn to_ideal(&self, real: &JointPosition) -> JointPosition {
        let Some(cal) = &self.calibrated else {
            return *real;
        };
        let foot = cal.forward(real);
        self.sim
            .kinematics()
            .inverse_nearest(&foot, real)
            .unwrap_or(*real)
    }

    /// The simulator (its state is the end of the move in progress, if any).
    pub fn simulator(&self) -> &LegSimulator {
        &self.sim
    }

    /// What a restarted Controller needs to go on from here: the end of the move in progress
    /// (the simulator has computed it already), the collisions and the simulated idle time.
    pub fn saved(&self) -> SavedController {
        SavedController {
            sim: self.sim.state(),
            collisions: self.collisions,
            idle_ns: u64::try_from(self.idle.as_nanos()).unwrap_or(u64::MAX),
        }
    }

    /// Puts this Controller where a saved one was, idle from `now`.
    pub fn restore(&mut self, saved: &SavedController, now: Instant) {
        self.sim.restore(&saved.sim);
        self.collisions = saved.collisions;
        self.idle = Duration::from_nanos(saved.idle_ns);
        self.motion = None;
        self.idle_since = now;
    }

    /// Puts the Controller on a time base: instants of `now`'s kind, moves playing out at
    /// `speed`. Switching base (a Controller that joins a central keeping simulated time, or
    /// leaves one) settles what was moving and starts idle from `now`.
    pub fn set_timeline(&mut self, speed: SpeedFactor, now: Instant) {
        if speed == self.speed {
            return;
        }
        self.motion = None;
        self.speed = speed;
        self.idle_since = now;
    }

    /// The speed factor.
    pub fn speed(&self) -> SpeedFactor {
        self.speed
    }

    /// Whether a move is still playing out at `now`.
    pub fn moving(&self, now: Instant) -> bool {
        self.motion
            .as_ref()
            .is_some_and(|m| now.saturating_duration_since(m.started) < m.wall)
    }

    /// What the queries answer at `now`.
    pub fn snapshot(&self, now: Instant) -> Snapshot {
        let settled = |idle_since: Instant| {
            let clock = self.sim.clock()
                + self.idle
                + self
                    .speed
                    .simulated_time(now.saturating_duration_since(idle_since));
            self.snapshot_of(
                self.sim.body_position(),
                self.sim.joint_leg_position(),
                self.sim.read_force(),
                self.sim.foot_planted(),
                clock,
                self.collisions,
            )
        };
        let Some(m) = &self.motion else {
            return settled(self.idle_since);
        };
        let wall_elapsed = now.saturating_duration_since(m.started);
        if wall_elapsed >= m.wall {
            return settled(m.started + m.wall);
        }
        let elapsed = self.speed.simulated_time(wall_elapsed).min(m.duration);
        let fraction = if m.duration.is_zero() {
            1.0
        } else {
            elapsed.as_secs_f64() / m.duration.as_secs_f64()
        };
        let end_carriage = self.sim.body_position();
        let (carriage, joints) = match &m.path {
            MotionPath::Leg(traj) => (m.carriage_before, traj.position_at(elapsed.as_secs_f64())),
            MotionPath::Body => {
                let lerp = |a: f64, b: f64| a + (b - a) * fraction;
                let end = self.sim.joint_leg_position();
                let start = m.joints_before;
                (
                    CarriagePose {
                        y_m: lerp(m.carriage_before.y_m, end_carriage.y_m),
                        roll_rad: lerp(m.carriage_before.roll_rad, end_carriage.roll_rad),
                        pitch_rad: lerp(m.carriage_before.pitch_rad, end_carriage.pitch_rad),
                    },
                    JointPosition::new(
                        lerp(start.shoulder_rad, end.shoulder_rad),
                        lerp(start.elbow_rad, end.elbow_rad),
                        lerp(start.vertical_m, end.vertical_m),
                    ),
                )
            }
        };
        self.snapshot_of(
            carriage,
            joints,
            m.force_before,
            m.planted_before,
            m.clock_before + self.idle + elapsed,
            self.collisions.saturating_sub(u32::from(m.collides)),
        )
    }

    fn snapshot_of(
        &self,
        carriage: CarriagePose,
        joints: JointPosition,
        force: ForceReading,
        foot_planted: bool,
        clock: Duration,
        collisions: u32,
    ) -> Snapshot {
        let kin = self.sim.kinematics();
        let joints = self.to_ideal(&joints);
        let cart_leg = kin.forward(&joints);
        Snapshot {
            carriage,
            joints,
            cart_leg,
            global_leg: carriage.to_world(kin.carriage(), &cart_leg),
            force,
            foot_planted,
            clock,
            collisions,
        }
    }

    /// `legMove` at `now`.
    pub fn leg_move(
        &mut self,
        waypoints: &[JointPosition],
        transition: bool,
        now: Instant,
    ) -> CommandRun {
        self.begin(now);
        let start = self.sim.joint_leg_position();
        let before = self.before(now);
        let real: Vec<JointPosition> = waypoints.iter().map(|q| self.to_real(q)).collect();
        let waypoints = &real[..];
        let result = self.sim.leg_move(waypoints, transition).map(|_| ());
        let path = match &result {
            Err(e) if e.is_rejected() => None,
            _ => Some(MotionPath::Leg(JointTrajectory::plan(
                self.sim.kinematics(),
                &start,
                waypoints,
            ))),
        };
        self.finish("legMove", before, path, result)
    }

    /// `bodyMove` at `now`.
    pub fn body_move(&mut self, target_y_m: f64, now: Instant) -> CommandRun {
        self.begin(now);
        let before = self.before(now);
        let result = self.sim.body_move(target_y_m).map(|_| ());
        let path = match &result {
            Err(e) if e.is_rejected() => None,
            _ => Some(MotionPath::Body),
        };
        self.finish("bodyMove", before, path, result)
    }

    /// `setTransForce` at `now` (instantaneous).
    pub fn set_trans_force(&mut self, force_n: f64, now: Instant) -> CommandRun {
        self.begin(now);
        let outcome = self
            .sim
            .set_trans_force(force_n)
            .map_err(|e| CommandFailure {
                reason: format!("setTransForce: {e}"),
                exception: None,
            });
        self.idle_since = now;
        CommandRun {
            started: now,
            wall: Duration::ZERO,
            simulated: Duration::ZERO,
            outcome,
        }
    }

    /// Ends the move that played out (if it has, or was abandoned) at `now`.
    pub fn settle(&mut self, now: Instant) {
        if let Some(m) = self.motion.take() {
            self.idle_since = (m.started + m.wall).min(now);
        }
    }

    /// Before a command: settle the last move and bank the idle time.
    fn begin(&mut self, now: Instant) {
        self.settle(now);
        self.idle += self
            .speed
            .simulated_time(now.saturating_duration_since(self.idle_since));
        self.idle_since = now;
    }

    fn before(&self, now: Instant) -> Motion {
        Motion {
            started: now,
            duration: Duration::ZERO,
            wall: Duration::ZERO,
            clock_before: self.sim.clock(),
            carriage_before: self.sim.body_position(),
            joints_before: self.sim.joint_leg_position(),
            force_before: self.sim.read_force(),
            planted_before: self.sim.foot_planted(),
            collides: false,
            path: MotionPath::Body,
        }
    }

    /// Records the move (if anything moved) and builds the command's outcome.
    fn finish(
        &mut self,
        command: &str,
        mut motion: Motion,
        path: Option<MotionPath>,
        result: crate::sim::Result<()>,
    ) -> CommandRun {
        let motion_started = motion.started;
        let simulated = self.sim.clock().saturating_sub(motion.clock_before);
        let wall = self.speed.wall_time(simulated);
        motion.collides = matches!(result, Err(SimError::Collision { .. }));
        if motion.collides {
            self.collisions = self.collisions.saturating_add(1);
        }
        let outcome = result.map_err(|error| {
            let foot = self.sim.global_leg_position();
            CommandFailure {
                reason: format!("{command}: {error}"),
                exception: Some(exception_for(command, &error, &foot)),
            }
        });
        match path {
            Some(path) if !wall.is_zero() => {
                motion.duration = simulated;
                motion.wall = wall;
                motion.path = path;
                self.motion = Some(motion);
            }
            _ => self.idle_since = motion.started,
        }
        CommandRun {
            started: motion_started,
            wall,
            simulated,
            outcome,
        }
    }
}

#[cfg(test)]
mod tests;
