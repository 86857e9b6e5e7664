//! What a move reports and what the simulator counts.

use nalgebra::Point3;
use serde::Serialize;
use tca_legged_messages::SupportState;

/// What the simulator has counted since it started.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Counters {
    /// Tip-overs.
    pub falls: u32,
    /// Contacts of link shapes (or of swinging feet driven into the ground) with the
    /// terrain: one per link found in contact when a move stopped.
    pub collisions: u32,
    /// Moves during which parts of the robot touched (two legs' links, or a leg's link and
    /// the body): counted once a move; the move is carried out.
    pub self_collisions: u32,
    /// Leg and body moves carried out (wholly or until they stopped); refused ones are not
    /// counted.
    pub moves: u32,
}

/// A foot lifting off or touching down during a move.
#[derive(Debug, Clone, PartialEq)]
pub struct FootEvent {
    /// The leg's index in model order.
    pub leg: usize,
    /// The leg's name.
    pub leg_name: String,
    /// True at touch-down, false at lift-off.
    pub stance: bool,
    /// The foot's contact point (bottom of its sphere), world frame.
    pub at: Point3<f64>,
    /// The simulator clock then, seconds.
    pub t_s: f64,
    /// The whole robot's support state just after the change.
    pub state: SupportState,
}

/// How a move went.
#[derive(Debug, Clone, PartialEq)]
pub struct MoveReport {
    /// The clock when it started, seconds.
    pub start_s: f64,
    /// How long it took, seconds (the clock advanced by this).
    pub duration_s: f64,
    /// The number of collision samples taken along it.
    pub samples: usize,
    /// The smallest stability margin of the standing feet along it, metres.
    pub min_margin_m: f64,
    /// Feet that lifted off or touched down, in order.
    pub events: Vec<FootEvent>,
    /// For a leg move that ended at ground contact: the foot's contact point, world frame.
    pub contact: Option<Point3<f64>>,
}
