//! Where the robot is and what a step does: [`GaitState`], [`StepPlan`], [`Action`].

use nalgebra::{Isometry3, Point3};
use serde::{Deserialize, Serialize};

/// One leg as the gait sees it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LegGaitState {
    /// Joint positions, one per moving joint from the body outwards.
    pub joints: Vec<f64>,
    /// Whether the foot stands on the ground.
    pub stance: bool,
    /// The foot's contact point in the world: the bottom of its contact sphere.
    pub foot: Point3<f64>,
}

/// The whole robot: the body pose in the world and every leg, in the model's leg order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitState {
    /// The body frame in the world frame.
    pub body: Isometry3<f64>,
    /// Every leg, in the model's order.
    pub legs: Vec<LegGaitState>,
}

impl GaitState {
    /// The indices of the standing legs.
    pub fn stance_legs(&self) -> Vec<usize> {
        (0..self.legs.len())
            .filter(|&i| self.legs[i].stance)
            .collect()
    }

    /// The joint positions of every leg.
    pub fn posture(&self) -> Vec<Vec<f64>> {
        self.legs.iter().map(|l| l.joints.clone()).collect()
    }
}

/// One move of a step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Action {
    /// Swing one leg through joint-space way-points (straight segments between them,
    /// starting from its current joints) and set it down: execute as `legged.legMove` with
    /// `transition = true`. The last way-point lies a little below the foothold so that the
    /// move ends at contact.
    Swing {
        /// The leg's index in the model's order.
        leg: usize,
        /// Joint positions to pass through, the last one a little below the foothold.
        waypoints: Vec<Vec<f64>>,
        /// Where the foot is expected to touch: the bottom of its contact sphere, world.
        foothold: Point3<f64>,
    },
    /// Move one leg's foot through joint-space way-points and leave it in the air (a part
    /// of a swing that goes on after a body move): execute as `legged.legMove` with
    /// `transition = false`. The free gait never plans one; planners that move the body
    /// while a leg swings do.
    Reach {
        /// The leg's index in the model's order.
        leg: usize,
        /// Joint positions to pass through; the foot stays at the last.
        waypoints: Vec<Vec<f64>>,
    },
    /// Move the body to a pose in a straight line (position lerp, orientation slerp), the
    /// standing feet staying where they are.
    Body {
        /// The body frame's target in the world.
        target: Isometry3<f64>,
    },
}

/// A step: its moves, in order, and where they leave the robot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepPlan {
    /// The moves, to execute one after the other.
    pub actions: Vec<Action>,
    /// The state after the last move, as planned.
    pub end: GaitState,
    /// The smallest stability margin along every move, metres.
    pub min_margin_m: f64,
}
