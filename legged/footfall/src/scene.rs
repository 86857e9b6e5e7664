//! What the tools plan from: the robot model, the terrain, and the robot's state (body pose,
//! joint positions, which feet stand), as telemetry reports it.

use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Point3};
use tca_legged_model::RobotModel;
use tca_legged_sim::{LeggedSim, SimParams, StartPose};
use tca_robot::HeightField;

use crate::error::FootfallError;

/// The robot standing on its terrain: everything the maps and planners read.
///
/// Poses and points are in the world frame (ROS REP 103: X east, Y north, Z up) unless a
/// name says otherwise; joint positions are per leg in model order, body outwards.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The robot.
    pub model: Arc<RobotModel>,
    /// The terrain (the planner's digital elevation model).
    pub terrain: Arc<HeightField>,
    /// The body's pose in the world.
    pub body: Isometry3<f64>,
    /// Every leg's joint positions.
    pub posture: Vec<Vec<f64>>,
    /// Which feet stand on the ground.
    pub stance: Vec<bool>,
}

impl Scene {
    /// The robot stood up at `start` on `terrain` as the simulator stands it (body level at
    /// its neutral height over the ground under its feet, every foot resting on the
    /// terrain).
    pub fn standing(
        model: Arc<RobotModel>,
        terrain: Arc<HeightField>,
        start: StartPose,
    ) -> Result<Scene, FootfallError> {
        let params = SimParams::for_model(&model);
        let sim = LeggedSim::new(model, terrain, start, params)
            .map_err(|e| FootfallError::Scene(format!("the robot cannot stand there: {e}")))?;
        Ok(Scene::from_sim(&sim))
    }

    /// The state a simulator is in.
    pub fn from_sim(sim: &LeggedSim) -> Scene {
        Scene {
            model: sim.model().clone(),
            terrain: sim.terrain().clone(),
            body: sim.body(),
            posture: sim.posture().to_vec(),
            stance: sim.stance(),
        }
    }

    /// The shipped `athlete` standing at the start of the built-in `rock-field` course of
    /// `seed`.
    pub fn rock_field(seed: u64) -> Result<Scene, FootfallError> {
        let course = tca_legged_courses::Course::builtin("rock-field", seed)
            .map_err(|e| FootfallError::Scene(e.to_string()))?;
        let model = RobotModel::builtin(course.robot_hint)
            .map_err(|e| FootfallError::Scene(e.to_string()))?;
        let start = StartPose {
            x_m: course.start.x_m,
            y_m: course.start.y_m,
            yaw_rad: course.start.yaw_rad,
        };
        Scene::standing(Arc::new(model), Arc::new(course.terrain), start)
    }

    /// Refuses a state that does not fit the model (leg count, joint counts, numbers).
    pub fn check(&self) -> Result<(), FootfallError> {
        self.model
            .check_posture(&self.posture)
            .map_err(|e| FootfallError::Scene(format!("the robot's joint positions: {e}")))?;
        if self.stance.len() != self.model.legs().len() {
            return Err(FootfallError::Scene(format!(
                "the stance names {} feet, the robot has {} legs",
                self.stance.len(),
                self.model.legs().len()
            )));
        }
        let t = self.body.translation.vector;
        if !(t.iter().all(|v| v.is_finite())
            && self.body.rotation.coords.iter().all(|v| v.is_finite()))
        {
            return Err(FootfallError::Scene(
                "the body pose has a number that is not finite".into(),
            ));
        }
        Ok(())
    }

    /// The index of the leg called `name`, or an error listing the legs.
    pub fn leg_index(&self, name: &str) -> Result<usize, FootfallError> {
        self.model
            .leg_index(name)
            .ok_or_else(|| FootfallError::UnknownLeg {
                leg: name.to_owned(),
                legs: self
                    .model
                    .legs()
                    .iter()
                    .map(|l| l.name().to_owned())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// The centre of a leg's foot sphere, world frame, for the leg's joints `q`.
    pub fn foot_centre(&self, leg: usize, q: &[f64]) -> Point3<f64> {
        let l = &self.model.legs()[leg];
        self.body * l.foot_position(q).unwrap_or_else(|_| Point3::origin())
    }

    /// Where every foot touches the terrain now (its sphere's contact point, world frame).
    pub fn touch_points(&self) -> Vec<Point3<f64>> {
        self.model
            .legs()
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let c = self.foot_centre(i, &self.posture[i]);
                tca_legged_sim::collide::touch_point(
                    &self.terrain,
                    Point2::new(c.x, c.y),
                    l.foot_radius(),
                )
            })
            .collect()
    }

    /// The centre of mass in the world with leg `leg` at joints `q` and the others as they
    /// are.
    pub fn centre_of_mass_with(&self, leg: usize, q: &[f64]) -> Point3<f64> {
        let mut posture = self.posture.clone();
        posture[leg] = q.to_vec();
        match self.model.centre_of_mass(&posture) {
            Ok(m) => self.body * m.centre,
            Err(_) => Point3::new(f64::NAN, f64::NAN, f64::NAN),
        }
    }

    /// The same robot with leg `leg` at joints `q` (a step carried out in the plan's
    /// imagination: the body does not move, the foot stands).
    pub fn with_leg(&self, leg: usize, q: &[f64]) -> Scene {
        let mut next = self.clone();
        next.posture[leg] = q.to_vec();
        next.stance[leg] = true;
        next
    }
}
