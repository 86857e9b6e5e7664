//! [`RobotSummary`]: what a robot description says, worked out once for printing or JSON.

use std::fmt;

use serde::Serialize;
use tca_legged_model::{RobotModel, WorkspaceSummary};
use tca_stability::{
    conservative_support_polygon, ground_projection, stability_margin, support_polygon,
};

use crate::error::ViewError;

/// Joint positions sampled per leg for its workspace.
pub const WORKSPACE_SAMPLES: usize = 4096;

/// One moving joint of a leg.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointSummary {
    /// The joint's name in the description.
    pub name: String,
    /// `revolute` or `prismatic`.
    pub kind: String,
    /// Lower limit (radians or metres).
    pub lower: f64,
    /// Upper limit.
    pub upper: f64,
    /// Speed limit (per second).
    pub velocity: f64,
    /// `rad` or `m`.
    pub unit: String,
}

/// One leg.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LegSummary {
    /// The leg's name (its foot link's without `_foot`).
    pub name: String,
    /// The foot link.
    pub foot_link: String,
    /// Radius of the foot's contact sphere, metres (0: a point).
    pub foot_radius_m: f64,
    /// The foot's contact-sphere centre standing, body frame, metres.
    pub standing_foot_m: [f64; 3],
    /// The moving joints, from the body out.
    pub joints: Vec<JointSummary>,
    /// Where the foot can go (sampled over the joint ranges), body frame.
    pub workspace: WorkspaceSummary,
}

/// A robot description, summarised.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobotSummary {
    /// The robot's name.
    pub name: String,
    /// The body (root) link.
    pub body_link: String,
    /// Total mass, kilograms.
    pub mass_kg: f64,
    /// Moving joints in all.
    pub moving_joints: usize,
    /// Height of the body frame above level ground standing with every joint at 0 (or its
    /// nearest limit), metres.
    pub standing_height_m: f64,
    /// Centre of mass standing, body frame, metres.
    pub com_m: [f64; 3],
    /// Static stability margin standing on all feet: distance from the centre of mass
    /// (projected) to the nearest edge of the support polygon, metres; negative outside.
    pub stability_margin_m: f64,
    /// The same against the conservative support polygon (what stays supported whichever
    /// one leg lifts); `None` with fewer than four legs or when that polygon is empty.
    pub conservative_margin_m: Option<f64>,
    /// Lowest point of the robot's collision shapes (feet excluded) above level ground
    /// standing, metres.
    pub ground_clearance_m: Option<f64>,
    /// The legs.
    pub legs: Vec<LegSummary>,
}

fn array(p: &nalgebra::Point3<f64>) -> [f64; 3] {
    [p.x, p.y, p.z]
}

impl RobotSummary {
    /// Works out the summary of `robot` standing on level ground.
    pub fn of(robot: &RobotModel) -> Result<Self, ViewError> {
        let posture = robot.neutral_posture();
        let fail = |source| ViewError::Posture {
            robot: robot.name().to_owned(),
            source,
        };
        let com = robot.centre_of_mass(&posture).map_err(fail)?;
        let feet = robot.foot_positions(&posture).map_err(fail)?;
        let height = robot.neutral_height();
        let ground: Vec<_> = feet
            .iter()
            .map(|p| nalgebra::Point2::new(p.x, p.y))
            .collect();
        let support = support_polygon(&ground);
        let conservative = conservative_support_polygon(&ground);
        let foot_links: Vec<&str> = robot.legs().iter().map(|l| l.foot_link()).collect();
        let shapes = robot.collision_shapes(&posture).map_err(fail)?;
        let lowest = shapes
            .iter()
            .filter(|s| !foot_links.contains(&s.link))
            .map(|s| s.lowest_z())
            .fold(None, |m: Option<f64>, z| Some(m.map_or(z, |m| m.min(z))));
        let legs = robot
            .legs()
            .iter()
            .zip(&feet)
            .map(|(leg, foot)| LegSummary {
                name: leg.name().to_owned(),
                foot_link: leg.foot_link().to_owned(),
                foot_radius_m: leg.foot_radius(),
                standing_foot_m: array(foot),
                joints: leg
                    .joints()
                    .iter()
                    .map(|j| {
                        let l = j.limits();
                        JointSummary {
                            name: j.name().to_owned(),
                            kind: j.kind().urdf_name().to_owned(),
                            lower: l.lower,
                            upper: l.upper,
                            velocity: l.velocity,
                            unit: j.kind().unit().to_owned(),
                        }
                    })
                    .collect(),
                workspace: leg.workspace_summary(WORKSPACE_SAMPLES),
            })
            .collect();
        Ok(Self {
            name: robot.name().to_owned(),
            body_link: robot.body_link().to_owned(),
            mass_kg: robot.total_mass(),
            moving_joints: robot.dof(),
            standing_height_m: height,
            com_m: array(&com.centre),
            stability_margin_m: stability_margin(&support, com.centre),
            conservative_margin_m: (!conservative.is_degenerate())
                .then(|| conservative.signed_distance(ground_projection(com.centre))),
            ground_clearance_m: lowest.map(|z| z + height),
            legs,
        })
    }
}

impl fmt::Display for RobotSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "robot {}: body `{}`, {} legs, {} moving joints, {:.3} kg",
            self.name,
            self.body_link,
            self.legs.len(),
            self.moving_joints,
            self.mass_kg
        )?;
        let [x, y, z] = self.com_m;
        writeln!(
            f,
            "standing (every joint at 0): body frame {:.3} m above level ground, centre of mass \
             ({x:.3}, {y:.3}, {z:.3}) m",
            self.standing_height_m
        )?;
        let conservative = self
            .conservative_margin_m
            .map_or("none".to_owned(), |m| format!("{m:.3} m"));
        writeln!(
            f,
            "stability margin on all feet {:.3} m, whichever leg lifts {conservative}",
            self.stability_margin_m
        )?;
        if let Some(c) = self.ground_clearance_m {
            writeln!(
                f,
                "lowest part of the body and legs {c:.3} m above the ground"
            )?;
        }
        for leg in &self.legs {
            let [x, y, z] = leg.standing_foot_m;
            writeln!(
                f,
                "leg {}: foot `{}`, radius {} m, standing at ({x:.3}, {y:.3}, {z:.3}) m",
                leg.name, leg.foot_link, leg.foot_radius_m
            )?;
            for j in &leg.joints {
                writeln!(
                    f,
                    "  {:<28} {:<9} {:>8.3} .. {:<8.3} {:<3}  up to {} {}/s",
                    j.name, j.kind, j.lower, j.upper, j.unit, j.velocity, j.unit
                )?;
            }
            writeln!(f, "  workspace {}", leg.workspace)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_robots_stand_stably_and_are_summarised() {
        for name in ["ambler", "hexapod", "athlete"] {
            let robot = RobotModel::builtin(name).unwrap();
            let s = RobotSummary::of(&robot).unwrap();
            assert_eq!(s.legs.len(), 6, "{name}");
            assert!(
                s.stability_margin_m > 0.0,
                "{name}: {}",
                s.stability_margin_m
            );
            let conservative = s.conservative_margin_m.expect("six legs");
            assert!(conservative <= s.stability_margin_m + 1e-9, "{name}");
            assert!(s.ground_clearance_m.is_some_and(|c| c > 0.0), "{name}");
            // Standing feet are on the ground.
            for leg in &s.legs {
                let bottom = leg.standing_foot_m[2] - leg.foot_radius_m;
                assert!(
                    (bottom + s.standing_height_m).abs() < 1e-6,
                    "{name} {}",
                    leg.name
                );
                assert!(!leg.joints.is_empty());
            }
            let text = s.to_string();
            assert!(text.contains(name) && text.contains("workspace"), "{text}");
        }
    }

    #[test]
    fn the_ambler_is_as_its_file_says() {
        let s = RobotSummary::of(&RobotModel::builtin("ambler").unwrap()).unwrap();
        assert!((s.mass_kg - 2500.0).abs() < 1.0, "{}", s.mass_kg);
        assert_eq!(s.moving_joints, 18);
        for leg in &s.legs {
            let kinds: Vec<&str> = leg.joints.iter().map(|j| j.kind.as_str()).collect();
            assert_eq!(kinds, ["revolute", "revolute", "prismatic"], "{}", leg.name);
        }
    }
}
