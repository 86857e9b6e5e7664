//! An ideal executor of step plans on the true terrain, and terrains to walk.

#![allow(dead_code, unreachable_pub)]

use std::sync::Arc;

use nalgebra::{Isometry3, Point2, Point3, Vector3};
use tca_free_gait::{Action, FreeGait, GaitError, GaitParams, GaitState, GridView, stand};
use tca_legged_model::{IkOptions, RobotModel, Shape};
use tca_robot::HeightField;
use tca_stability::{stability_margin, support_polygon};

/// Applies plans with the model's kinematics, refusing what a careful simulator would.
pub struct Executor {
    pub model: Arc<RobotModel>,
    pub terrain: Arc<HeightField>,
    /// Sample spacing along moves, metres.
    pub step: f64,
    /// Surface point spacing of the shapes, metres.
    pub spacing: f64,
    pub min_margin: f64,
}

fn margin_of(
    model: &RobotModel,
    body: &Isometry3<f64>,
    posture: &[Vec<f64>],
    feet: &[Point3<f64>],
) -> f64 {
    let polygon = support_polygon(
        &feet
            .iter()
            .map(|p| Point2::new(p.x, p.y))
            .collect::<Vec<_>>(),
    );
    let com = body * model.centre_of_mass(posture).expect("posture").centre;
    stability_margin(&polygon, com)
}

impl Executor {
    pub fn new(model: Arc<RobotModel>, terrain: Arc<HeightField>) -> Self {
        let s = GaitParams::for_model(&model).scale;
        Executor {
            model,
            terrain,
            step: 0.02 * s,
            spacing: 0.04 * s,
            min_margin: f64::INFINITY,
        }
    }

    /// How far the lowest point of a foot sphere is above the terrain under it (negative:
    /// in the ground).
    fn foot_gap(&self, c: &Point3<f64>, r: f64) -> f64 {
        let mut gap = f64::INFINITY;
        for ring in 0..=6 {
            let d = r * ring as f64 / 6.0;
            let count = if ring == 0 { 1 } else { 24 };
            for k in 0..count {
                let a = k as f64 * std::f64::consts::TAU / count as f64;
                let h = self.terrain.height_at(c.x + d * a.cos(), c.y + d * a.sin());
                gap = gap.min(c.z - (r * r - d * d).max(0.0).sqrt() - h);
            }
        }
        gap
    }

    /// The first link shape touching the terrain, if any.
    fn touching(&self, body: &Isometry3<f64>, posture: &[Vec<f64>]) -> Option<String> {
        for s in self.model.collision_shapes(posture).expect("posture") {
            let pose = body * s.pose;
            let lowest = pose.translation.z - s.shape.depth_below(&pose);
            let centre = Point2::new(pose.translation.x, pose.translation.y);
            let top = self
                .terrain
                .max_height_in_disc(centre, s.shape.bounding_radius());
            if lowest > top {
                continue;
            }
            for p in surface(&s.shape, self.spacing) {
                let w = pose * p;
                if w.z < top && w.z < self.terrain.height_at(w.x, w.y) {
                    return Some(format!(
                        "{} at ({:.2}, {:.2}, {:.2})",
                        s.link, w.x, w.y, w.z
                    ));
                }
            }
        }
        None
    }

    fn record(&mut self, m: f64) -> Result<(), String> {
        self.min_margin = self.min_margin.min(m);
        if m > 0.0 {
            Ok(())
        } else {
            Err(format!("margin {m:.3} m: the robot tips over"))
        }
    }

    pub fn apply(&mut self, state: &mut GaitState, action: &Action) -> Result<(), String> {
        match action {
            Action::Body { target } => self.body(state, target),
            Action::Swing { leg, waypoints, .. } => self.swing(state, *leg, waypoints),
            Action::Reach { .. } => Err("the free gait never leaves a foot in the air".into()),
        }
    }

    fn body(&mut self, state: &mut GaitState, target: &Isometry3<f64>) -> Result<(), String> {
        let stance = state.stance_legs();
        if stance.len() < 3 {
            return Err("a body move on fewer than three feet".into());
        }
        let feet: Vec<Point3<f64>> = stance.iter().map(|&i| state.legs[i].foot).collect();
        let from = state.body;
        let travel = (target.translation.vector - from.translation.vector).norm()
            + from.rotation.angle_to(&target.rotation) * 3.0;
        let n = ((travel / self.step).ceil() as usize).max(1);
        let mut posture = state.posture();
        for k in 1..=n {
            let pose = from.lerp_slerp(target, k as f64 / n as f64);
            for &i in &stance {
                let leg = &self.model.legs()[i];
                let centre = state.legs[i].foot + Vector3::z() * leg.foot_radius();
                let s = leg
                    .inverse_kinematics(
                        &(pose.inverse() * centre),
                        &IkOptions::starting_at(&posture[i]),
                    )
                    .map_err(|e| format!("body move: {e}"))?;
                posture[i] = s.joints;
            }
            self.record(margin_of(&self.model, &pose, &posture, &feet))?;
            if let Some(t) = self.touching(&pose, &posture) {
                return Err(format!("body move: collision of {t}"));
            }
        }
        state.body = *target;
        for (l, q) in state.legs.iter_mut().zip(posture) {
            l.joints = q;
        }
        Ok(())
    }

    fn swing(
        &mut self,
        state: &mut GaitState,
        leg: usize,
        waypoints: &[Vec<f64>],
    ) -> Result<(), String> {
        let others: Vec<Point3<f64>> = (0..state.legs.len())
            .filter(|&i| i != leg && state.legs[i].stance)
            .map(|i| state.legs[i].foot)
            .collect();
        if others.len() < 3 {
            return Err("lifting would leave fewer than three feet".into());
        }
        let model = self.model.clone();
        let l = &model.legs()[leg];
        let r = l.foot_radius();
        let mut posture = state.posture();
        let mut from = posture[leg].clone();
        let body = state.body;
        state.legs[leg].stance = false;
        for (w, to) in waypoints.iter().enumerate() {
            if !l.within_limits(to) {
                return Err(format!(
                    "way-point {w} of leg {} is outside its joint limits",
                    l.name()
                ));
            }
            let last = w + 1 == waypoints.len();
            let fa = l.foot_position(&from).unwrap();
            let fb = l.foot_position(to).unwrap();
            let n = (((fb - fa).norm() * 2.0 / self.step).ceil() as usize).max(2);
            for k in 1..=n {
                let t = k as f64 / n as f64;
                let q: Vec<f64> = from.iter().zip(to).map(|(a, b)| a + (b - a) * t).collect();
                let centre = body * l.foot_position(&q).unwrap();
                let gap = self.foot_gap(&centre, r);
                if last && gap <= 0.0 {
                    posture[leg] = q.clone();
                    state.legs[leg] = tca_free_gait::LegGaitState {
                        joints: q,
                        stance: true,
                        foot: centre - Vector3::z() * r,
                    };
                    return Ok(());
                }
                if gap < -0.002 * (1.0 + r) && !(w == 0 && t < 0.5) {
                    return Err(format!(
                        "leg {} drives its foot into the ground (gap {gap:.3})",
                        l.name()
                    ));
                }
                posture[leg] = q.clone();
                self.record(margin_of(&self.model, &body, &posture, &others))?;
                if let Some(t) = self.touching(&body, &posture) {
                    return Err(format!("swing of {}: collision of {t}", l.name()));
                }
            }
            from = to.clone();
        }
        Err(format!(
            "leg {} reached its last way-point without contact",
            l.name()
        ))
    }
}

/// Points on a shape's surface, its own frame.
fn surface(shape: &Shape, d: f64) -> Vec<Point3<f64>> {
    let n = |l: f64| ((l / d).ceil() as usize).clamp(1, 200);
    let lin = |l: f64| {
        let k = n(l);
        (0..=k).map(move |i| -l / 2.0 + l * i as f64 / k as f64)
    };
    let mut out = Vec::new();
    match *shape {
        Shape::Box { size } => {
            for x in lin(size.x) {
                for y in lin(size.y) {
                    for z in lin(size.z) {
                        let on = (x.abs() - size.x / 2.0).abs() < 1e-12
                            || (y.abs() - size.y / 2.0).abs() < 1e-12
                            || (z.abs() - size.z / 2.0).abs() < 1e-12;
                        if on {
                            out.push(Point3::new(x, y, z));
                        }
                    }
                }
            }
        }
        Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
            let around = n(std::f64::consts::TAU * radius).max(8);
            let cap = if matches!(shape, Shape::Capsule { .. }) {
                radius
            } else {
                0.0
            };
            for z in lin(length + 2.0 * cap) {
                let rr = if z.abs() > length / 2.0 {
                    (radius * radius - (z.abs() - length / 2.0).powi(2))
                        .max(0.0)
                        .sqrt()
                } else {
                    radius
                };
                for f in [1.0, 0.5, 0.0] {
                    if f < 1.0 && z.abs() < (length / 2.0 + cap) - 1e-12 {
                        continue;
                    }
                    for k in 0..around {
                        let a = k as f64 * std::f64::consts::TAU / around as f64;
                        out.push(Point3::new(f * rr * a.cos(), f * rr * a.sin(), z));
                    }
                }
            }
        }
        Shape::Sphere { radius } => {
            for i in 0..=n(std::f64::consts::PI * radius).max(6) {
                let polar = std::f64::consts::PI * i as f64
                    / n(std::f64::consts::PI * radius).max(6) as f64;
                let around = n(std::f64::consts::TAU * radius * polar.sin()).max(1);
                for k in 0..around {
                    let a = k as f64 * std::f64::consts::TAU / around as f64;
                    out.push(Point3::new(
                        radius * polar.sin() * a.cos(),
                        radius * polar.sin() * a.sin(),
                        -radius * polar.cos(),
                    ));
                }
            }
        }
    }
    out
}

/// How a walk ended.
#[derive(Debug)]
pub struct Walk {
    pub steps: usize,
    pub reached: bool,
    pub error: Option<GaitError>,
    pub min_margin: f64,
    pub min_planned_margin: f64,
    pub final_distance: f64,
    pub seconds: f64,
    pub planning_ms_per_step: f64,
}

impl Walk {
    /// One line saying how the walk went, for the test output.
    pub fn describe(&self, name: &str) -> String {
        format!(
            "{name}: reached {} in {} steps, {:.2} s ({:.1} ms planning per step), min margin {:.4} m executed / {:.4} m planned, {:.2} m left{}",
            self.reached,
            self.steps,
            self.seconds,
            self.planning_ms_per_step,
            self.min_margin,
            self.min_planned_margin,
            self.final_distance,
            self.error
                .as_ref()
                .map(|e| format!(": {e}"))
                .unwrap_or_default()
        )
    }
}

/// Walks from (x, y, yaw) toward the goal with the ideal executor, at most `max_steps`.
/// Panics on any refused or unstable action.
pub fn walk(
    robot: &str,
    model: Arc<RobotModel>,
    terrain: Arc<HeightField>,
    start: (f64, f64, f64),
    goal: Point2<f64>,
    max_steps: usize,
) -> Walk {
    let params = GaitParams::for_model(&model);
    let gait = FreeGait::new(model.clone(), params.clone());
    let view = GridView::new(terrain.clone());
    let mut state =
        stand(&model, &view, start.0, start.1, start.2).expect("the robot stands at the start");
    let mut exec = Executor::new(model, terrain);
    let began = std::time::Instant::now();
    let mut min_planned = f64::INFINITY;
    let mut error = None;
    let mut steps = 0;
    let mut planning = 0.0;
    for _ in 0..max_steps {
        let t0 = std::time::Instant::now();
        let planned = gait.plan_step(&state, &view, goal);
        planning += t0.elapsed().as_secs_f64();
        match planned {
            Ok(plan) => {
                assert!(
                    plan.min_margin_m >= params.min_margin_m - 1e-9,
                    "{robot}: planned margin {} below the minimum",
                    plan.min_margin_m
                );
                min_planned = min_planned.min(plan.min_margin_m);
                for action in &plan.actions {
                    if let Err(e) = exec.apply(&mut state, action) {
                        panic!("{robot} step {steps}: {e}\naction {action:?}");
                    }
                }
                steps += 1;
            }
            Err(GaitError::GoalReached { .. }) => break,
            Err(e) => {
                if std::env::var_os("GAIT_DEBUG").is_some() {
                    let t = state.body.translation.vector;
                    eprintln!(
                        "{robot}: stuck with the body at ({:.2}, {:.2}, {:.2})",
                        t.x, t.y, t.z
                    );
                    for (i, l) in state.legs.iter().enumerate() {
                        let local = state.body.inverse() * l.foot;
                        eprintln!(
                            "  leg {i}: foot ({:.2}, {:.2}, {:.2}) body frame ({:.2}, {:.2}, {:.2}) joints {:.2?}",
                            l.foot.x, l.foot.y, l.foot.z, local.x, local.y, local.z, l.joints
                        );
                    }
                }
                error = Some(e);
                break;
            }
        }
    }
    let t = state.body.translation.vector;
    let final_distance = (Point2::new(t.x, t.y) - goal).norm();
    Walk {
        steps,
        reached: final_distance <= params.goal_tolerance_m,
        error,
        min_margin: exec.min_margin,
        min_planned_margin: min_planned,
        final_distance,
        seconds: began.elapsed().as_secs_f64(),
        planning_ms_per_step: planning * 1e3 / (steps.max(1) as f64),
    }
}

/// A height field from a function over a rectangle.
pub fn field(
    min: (f64, f64),
    max: (f64, f64),
    cell: f64,
    f: impl Fn(f64, f64) -> f64,
) -> Arc<HeightField> {
    let nx = ((max.0 - min.0) / cell).round() as usize + 1;
    let ny = ((max.1 - min.1) / cell).round() as usize + 1;
    let mut h = Vec::with_capacity(nx * ny);
    for iy in 0..ny {
        for ix in 0..nx {
            h.push(f(min.0 + ix as f64 * cell, min.1 + iy as f64 * cell));
        }
    }
    Arc::new(HeightField::new(Point2::new(min.0, min.1), cell, nx, ny, h).expect("height field"))
}

/// Smooth deterministic noise in [-1, 1].
pub fn noise(x: f64, y: f64, seed: f64) -> f64 {
    let a = (x * 1.7 + seed).sin() * (y * 1.3 - seed * 0.7).cos();
    let b = (x * 3.1 - y * 2.3 + seed * 1.9).sin();
    let c = (x * 0.6 + y * 0.9 + seed * 0.3).cos();
    (a * 0.5 + b * 0.3 + c * 0.2).clamp(-1.0, 1.0)
}

/// Flat around (x0, y0) within `r`, `f` beyond, blended over a metre.
pub fn with_flat_start(
    x0: f64,
    y0: f64,
    r: f64,
    blend: f64,
    f: impl Fn(f64, f64) -> f64,
) -> impl Fn(f64, f64) -> f64 {
    move |x, y| {
        let d = (x - x0).hypot(y - y0);
        let w = ((d - r) / blend).clamp(0.0, 1.0);
        w * f(x, y)
    }
}

/// The Ambler's courses, about 28 x 14 m at 0.1 m, start (3, 0), goal (23, 0).
pub mod ambler_courses {
    use super::*;

    pub const START: (f64, f64, f64) = (3.0, 0.0, 0.0);
    pub const GOAL: (f64, f64) = (23.0, 0.0);

    fn make(f: impl Fn(f64, f64) -> f64) -> Arc<HeightField> {
        field((0.0, -7.0), (28.0, 7.0), 0.1, f)
    }

    pub fn flat() -> Arc<HeightField> {
        make(|_, _| 0.0)
    }

    /// Smooth bumps of up to about 0.25 m.
    pub fn rough() -> Arc<HeightField> {
        make(with_flat_start(3.0, 0.0, 3.5, 1.5, |x, y| {
            0.25 * noise(x, y, 1.0)
        }))
    }

    /// Boulders (spherical caps) up to 1 m high over x 7..21.
    pub fn boulders() -> Arc<HeightField> {
        let mut rocks = Vec::new();
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..40 {
            let x = 7.0 + 14.0 * rnd();
            let y = -5.0 + 10.0 * rnd();
            let h = 0.3 + 0.7 * rnd();
            let r = 0.5 + 0.7 * rnd();
            rocks.push((x, y, h, r));
        }
        make(move |x, y| {
            rocks
                .iter()
                .map(|&(bx, by, h, r)| {
                    let d2 = (x - bx).powi(2) + (y - by).powi(2);
                    // A spherical cap of height h and base radius r.
                    let big = (r * r + h * h) / (2.0 * h);
                    let z = (big * big - d2).max(0.0).sqrt() - (big - h);
                    z.max(0.0)
                })
                .fold(0.0, f64::max)
        })
    }

    /// A ditch 1 m wide and 1.5 m deep across the course at x 12..13.
    pub fn ditch() -> Arc<HeightField> {
        make(|x, _| {
            if (12.0..=13.0).contains(&x) {
                -1.5
            } else {
                0.0
            }
        })
    }

    /// A 25 degree climb from x = 9 to x = 15, then a plateau.
    pub fn slope() -> Arc<HeightField> {
        let t = 25f64.to_radians().tan();
        make(move |x, _| ((x - 9.0).clamp(0.0, 6.0)) * t)
    }

    /// A chasm 5 m wide and 3 m deep at x 10..15: no way across.
    pub fn chasm() -> Arc<HeightField> {
        make(|x, _| {
            if (10.0..=15.0).contains(&x) {
                -3.0
            } else {
                0.0
            }
        })
    }
}

/// URDF text of a walker with insect-like coxa-femur-tibia legs (the shipped hexapod's
/// leg), one at each hip `(name, x, y, yaw)`, on a body plate of `length` x `width`.
pub fn insect_urdf(name: &str, length: f64, width: f64, hips: &[(&str, f64, f64, f64)]) -> String {
    let mut s = format!(
        r#"<?xml version="1.0"?>
<robot name="{name}">
  <link name="body">
    <inertial><origin xyz="0 0 0"/><mass value="1.5"/><inertia ixx="0.005" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.014"/></inertial>
    <collision><origin xyz="0 0 0"/><geometry><box size="{length} {width} 0.06"/></geometry></collision>
  </link>
"#
    );
    for (leg, x, y, yaw) in hips {
        s.push_str(&format!(
            r#"  <joint name="{leg}_hip_yaw" type="revolute">
    <origin xyz="{x} {y} 0" rpy="0 0 {yaw}"/>
    <parent link="body"/><child link="{leg}_coxa"/>
    <axis xyz="0 0 1"/><limit lower="-0.7" upper="0.7" velocity="5" effort="2.5"/>
  </joint>
  <link name="{leg}_coxa">
    <inertial><origin xyz="0.0275 0 0"/><mass value="0.04"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>
    <collision><origin xyz="0.0275 0 0"/><geometry><box size="0.055 0.03 0.03"/></geometry></collision>
  </link>
  <joint name="{leg}_hip_pitch" type="revolute">
    <origin xyz="0.055 0 0"/>
    <parent link="{leg}_coxa"/><child link="{leg}_femur"/>
    <axis xyz="0 -1 0"/><limit lower="-1" upper="1.4" velocity="5" effort="2.5"/>
  </joint>
  <link name="{leg}_femur">
    <inertial><origin xyz="0.08 0 0"/><mass value="0.08"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <collision><origin xyz="0.08 0 0"/><geometry><box size="0.16 0.03 0.02"/></geometry></collision>
  </link>
  <joint name="{leg}_knee" type="revolute">
    <origin xyz="0.16 0 0" rpy="0 1.5708 0"/>
    <parent link="{leg}_femur"/><child link="{leg}_tibia"/>
    <axis xyz="0 -1 0"/><limit lower="-1.2" upper="1.2" velocity="5" effort="2.5"/>
  </joint>
  <link name="{leg}_tibia">
    <inertial><origin xyz="0.1 0 0" rpy="0 1.5708 0"/><mass value="0.06"/><inertia ixx="2e-4" ixy="0" ixz="0" iyy="2e-4" iyz="0" izz="3e-6"/></inertial>
    <collision><origin xyz="0.1 0 0" rpy="0 1.5708 0"/><geometry><cylinder radius="0.01" length="0.2"/></geometry></collision>
  </link>
  <joint name="{leg}_tip" type="fixed">
    <origin xyz="0.23 0 0"/><parent link="{leg}_tibia"/><child link="{leg}_foot"/>
  </joint>
  <link name="{leg}_foot">
    <inertial><origin xyz="0 0 0"/><mass value="0.02"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial>
    <collision><origin xyz="0 0 0"/><geometry><sphere radius="0.012"/></geometry></collision>
  </link>
"#
        ));
    }
    s.push_str("</robot>\n");
    s
}

/// The hexapod's courses, about 3.5 x 1.5 m at 0.02 m, start (0.3, 0), goal (3.2, 0).
pub mod hexapod_courses {
    use super::*;

    pub const START: (f64, f64, f64) = (0.3, 0.0, 0.0);
    pub const GOAL: (f64, f64) = (3.2, 0.0);

    fn make(f: impl Fn(f64, f64) -> f64) -> Arc<HeightField> {
        field((-0.2, -0.75), (3.6, 0.75), 0.02, f)
    }

    pub fn flat() -> Arc<HeightField> {
        make(|_, _| 0.0)
    }

    /// Waves of up to about 4 cm.
    pub fn rough() -> Arc<HeightField> {
        make(with_flat_start(0.3, 0.0, 0.35, 0.15, |x, y| {
            0.04 * noise(x * 10.0, y * 10.0, 2.0)
        }))
    }
}
