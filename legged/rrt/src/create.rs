//! Posture creation: the body's roll and pitch from a robust plane fit of the ground under
//! the robot, its height keeping the body's clearance over the highest ground under it,
//! and a foothold for every leg; the posture is kept only if it passes every check.

use nalgebra::{Point2, Point3, UnitQuaternion, Vector3};

use crate::checks::{margin, self_collision, statically_stable, terrain_collision};
use crate::foothold::select_foothold;
use crate::params::RrtParams;
use crate::pose::{BodyPose, Posture};
use crate::robot::Robot;
use crate::terrain::{Terrain, robust_plane};

/// Spacing of the ground samples of the plane fit and the clearance test, in cells.
const SAMPLE_CELLS: f64 = 2.0;

/// Why no posture was made at a place.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Refusal {
    /// Too near the edge of the map.
    OffMap,
    /// The ground under the robot is steeper than the body may tilt.
    TooSteep,
    /// A leg found no acceptable foothold within reach.
    NoFoothold,
    /// The centre of mass is not over the shrunk support polygon.
    Unstable,
    /// Two parts of the robot touch.
    SelfCollision,
    /// A link touches the ground.
    TerrainCollision,
    /// Some posture along the move fails a check (the reason inside).
    Move(String),
}

impl Refusal {
    /// A sentence saying what was wrong.
    pub fn describe(&self) -> String {
        match self {
            Refusal::OffMap => "too near the edge of the map".to_owned(),
            Refusal::TooSteep => "the ground is steeper than the body may tilt".to_owned(),
            Refusal::NoFoothold => "a leg finds no acceptable foothold in reach".to_owned(),
            Refusal::Unstable => "the centre of mass leaves the shrunk support polygon".to_owned(),
            Refusal::SelfCollision => "two parts of the robot would touch".to_owned(),
            Refusal::TerrainCollision => "a link would touch the ground".to_owned(),
            Refusal::Move(why) => format!("a move fails: {why}"),
        }
    }
}

/// Makes the robot's posture with its body over `xy` facing `yaw` (the paper's
/// CREATE_POSTURE), starting the legs' joint searches from `initial` (joint positions of
/// each leg).
pub fn create_posture(
    robot: &Robot,
    terrain: &Terrain,
    params: &RrtParams,
    xy: Point2<f64>,
    yaw: f64,
    initial: &[Vec<f64>],
) -> Result<Posture, Refusal> {
    let reach = robot
        .neutral_feet
        .iter()
        .map(|f| f.coords.xy().norm())
        .fold(0.0, f64::max)
        + params.foothold_search_m
        + 2.0 * terrain.resolution_m();
    if !terrain.inside(xy, reach) {
        return Err(Refusal::OffMap);
    }
    let (c, s) = (yaw.cos(), yaw.sin());
    let to_world = |u: f64, v: f64| Point2::new(xy.x + c * u - s * v, xy.y + s * u + c * v);
    // The ground under the robot: the box of its neutral feet.
    let (mut lo, mut hi) = (
        Point2::new(f64::INFINITY, f64::INFINITY),
        Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for f in &robot.neutral_feet {
        lo = Point2::new(lo.x.min(f.x), lo.y.min(f.y));
        hi = Point2::new(hi.x.max(f.x), hi.y.max(f.y));
    }
    let step = SAMPLE_CELLS * terrain.resolution_m();
    let mut samples = Vec::new();
    let mut u = lo.x;
    while u <= hi.x + 1e-9 {
        let mut v = lo.y;
        while v <= hi.y + 1e-9 {
            samples.push((u, v, terrain.height(to_world(u, v))));
            v += step;
        }
        u += step;
    }
    let fit = robust_plane(&samples).ok_or(Refusal::OffMap)?;
    let pitch = -fit.slope_u.atan();
    let roll = fit.slope_v.atan();
    if pitch.abs() > params.max_inclination_rad || roll.abs() > params.max_inclination_rad {
        return Err(Refusal::TooSteep);
    }
    let rotation = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
    // The body's height: its neutral height over the fitted plane, raised if the bottom of
    // the body would come nearer the highest ground under it than the clearance.
    let mut z = fit.height_m + robot.neutral_height() / (roll.cos() * pitch.cos());
    let h = robot.body_half;
    let bc = robot.body_centre;
    let mut u = -h.x;
    while u <= h.x + 1e-9 {
        let mut v = -h.y;
        while v <= h.y + 1e-9 {
            let p = rotation * (bc + Vector3::new(u, v, -h.z));
            let w = Point2::new(xy.x + p.x, xy.y + p.y);
            let ground = terrain.max_in_disc(w, step);
            z = z.max(ground + params.body_clearance_m - p.z);
            v += step;
        }
        u += step;
    }
    let body = BodyPose {
        x: xy.x,
        y: xy.y,
        z,
        roll,
        pitch,
        yaw,
    };
    let iso = body.isometry();
    let mut feet = Vec::with_capacity(robot.leg_count());
    let mut joints = Vec::with_capacity(robot.leg_count());
    for leg in 0..robot.leg_count() {
        let start = initial
            .get(leg)
            .cloned()
            .unwrap_or_else(|| robot.model().legs()[leg].neutral());
        let f = select_foothold(robot, terrain, params, &iso, leg, &start)
            .ok_or(Refusal::NoFoothold)?;
        feet.push(f.foot);
        joints.push(f.joints);
    }
    let com = iso
        * robot
            .model()
            .centre_of_mass(&joints)
            .map_err(|_| Refusal::NoFoothold)?
            .centre;
    let feet_xy: Vec<Point2<f64>> = feet.iter().map(|f| Point2::new(f.x, f.y)).collect();
    let com_xy = Point2::new(com.x, com.y);
    if !statically_stable(&feet_xy, com_xy, params.stability_margin_m) {
        return Err(Refusal::Unstable);
    }
    let poses = robot
        .shape_poses(&iso, &joints)
        .ok_or(Refusal::NoFoothold)?;
    if self_collision(robot, &joints).is_some() {
        return Err(Refusal::SelfCollision);
    }
    if terrain_collision(robot, terrain, &poses, 0.0).is_some() {
        return Err(Refusal::TerrainCollision);
    }
    Ok(Posture {
        body,
        feet,
        joints,
        com: Point3::from(com.coords),
        margin_m: margin(&feet_xy, com_xy),
    })
}
