//! The free gait's parameters and their defaults for a robot.

use serde::{Deserialize, Serialize};
use tca_legged_model::{JointKind, RobotModel};

/// How the free gait plans. [`GaitParams::for_model`] scales every length to the robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitParams {
    /// Smallest static stability margin any planned move may reach, metres.
    pub min_margin_m: f64,
    /// Clearance kept between every link (and a swinging foot) and the terrain, metres.
    pub clearance_m: f64,
    /// How far below the foothold the last way-point of a swing lies, metres, so that the
    /// executor's transition move ends at contact.
    pub below_foothold_m: f64,
    /// Longest body translation of one step, metres.
    pub max_body_step_m: f64,
    /// Largest body turn of one step, radians.
    pub max_turn_rad: f64,
    /// Spacing of the samples along moves checked for reach, stability and collision,
    /// metres of foot or body travel.
    pub sample_m: f64,
    /// Spacing of candidate footholds in a leg's workspace, metres.
    pub foothold_spacing_m: f64,
    /// Weight of the terrain's foothold cost in ranking footholds.
    pub cost_weight: f64,
    /// Weight of the stability margin a foothold gives (per metre of margin, relative to
    /// the robot's size).
    pub margin_weight: f64,
    /// Body within this horizontal distance of the goal counts as arrived, metres.
    pub goal_tolerance_m: f64,
    /// Height of unknown terrain under body-fixed shapes, above the highest standing foot,
    /// assumed when checking body moves, metres (the ground under the body is rarely seen).
    pub unknown_rise_m: f64,
    /// A step must advance the body or a foot toward the goal by at least this, metres.
    pub min_progress_m: f64,
    /// Where the level body stands between the lowest and the highest height every
    /// standing foot allows (0 lowest, 1 highest): high leaves room to lift feet over
    /// obstacles and up slopes. `None`: at the neutral height over the standing feet,
    /// brought within that range (for legs of revolute joints, whose workspace reaches
    /// above the body as well as below it, the middle of the range can be a body on the
    /// ground).
    pub height_bias: Option<f64>,
    /// Room kept between the links of different legs (each link's capsules widened by
    /// this), metres: no planned posture or move brings two legs nearer.
    #[serde(default)]
    pub leg_clearance_m: f64,
    /// Length scale of the robot: about 1.1 for the Ambler, about 0.1 for the hexapod.
    pub scale: f64,
}

/// The size (mean horizontal distance of the standing feet from the body centre), metres,
/// of a robot that gets the defaults unscaled; every length scales from it.
const REFERENCE_SIZE_M: f64 = 3.1;

impl GaitParams {
    /// Defaults for a robot, every length scaled by its size (the mean horizontal distance
    /// of its standing feet from the body centre) against a reference size of 3.1 m.
    pub fn for_model(model: &RobotModel) -> Self {
        let legs = model.legs();
        let size = if legs.is_empty() {
            REFERENCE_SIZE_M
        } else {
            let total: f64 = legs
                .iter()
                .filter_map(|l| l.foot_position(&l.neutral()).ok())
                .map(|p| p.x.hypot(p.y))
                .sum();
            (total / legs.len() as f64).max(1e-3)
        };
        let s = size / REFERENCE_SIZE_M;
        let height = model.neutral_height();
        let clearance_under_body = model
            .standing_posture(height)
            .ok()
            .and_then(|p| model.collision_shapes(&p).ok())
            .map(|shapes| {
                shapes
                    .iter()
                    .filter(|sh| model.link(sh.link).is_some_and(|l| l.leg().is_none()))
                    .map(|sh| sh.lowest_z() + height)
                    .fold(f64::INFINITY, f64::min)
            })
            .filter(|c| c.is_finite())
            .unwrap_or(height * 0.5);
        // Legs that lift with a vertical slide (the Ambler's kind) keep their reach over the
        // ground at any height, so their body rides high.
        let lifts_vertically = !legs.is_empty()
            && legs.iter().all(|l| {
                l.joint_frames(&l.neutral()).is_ok_and(|frames| {
                    l.joints().iter().zip(&frames).any(|(j, f)| match j.kind() {
                        JointKind::Prismatic { axis } => {
                            (f.rotation * axis.into_inner()).z.abs() > 0.99
                        }
                        JointKind::Revolute { .. } => false,
                    })
                })
            });
        GaitParams {
            min_margin_m: 0.10 * s,
            clearance_m: 0.05 * s,
            below_foothold_m: 0.03 * s,
            max_body_step_m: 0.6 * s,
            max_turn_rad: 0.15,
            sample_m: 0.05 * s,
            foothold_spacing_m: 0.12 * s,
            cost_weight: 1.0,
            margin_weight: 2.0,
            goal_tolerance_m: 0.3 * s,
            unknown_rise_m: (clearance_under_body * 0.5).max(0.0),
            min_progress_m: 0.02 * s,
            leg_clearance_m: 0.01 * s,
            height_bias: lifts_vertically.then_some(0.8),
            scale: s,
        }
    }
}
