//! The walk report: what a walk did, in a form an outside checker can verify against the
//! terrain.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use tca_legged_messages::SupportState;

/// One foot in a recorded state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootRecord {
    /// The foot's contact point (bottom of its contact sphere), world frame, metres.
    pub at: [f64; 3],
    /// Whether it stands.
    pub stance: bool,
}

/// The robot at one support change.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StateRecord {
    /// The Controller's motion clock: simulated seconds of moves carried out since the
    /// start of the walk (the robot standing still while a step is planned does not count;
    /// the report's `sim_time_s` does).
    pub t_s: f64,
    /// Body pose `[x, y, z, roll, pitch, yaw]`, world frame, metres and radians.
    pub body: [f64; 6],
    /// Centre of mass `[x, y, z]`, world frame, metres.
    pub com: [f64; 3],
    /// Every foot, by leg name.
    pub feet: BTreeMap<String, FootRecord>,
    /// Static stability margin of the centre of mass over the standing feet, metres.
    pub margin_m: f64,
}

impl From<&SupportState> for StateRecord {
    fn from(s: &SupportState) -> Self {
        StateRecord {
            t_s: s.t_s,
            body: s.body.to_array(),
            com: [s.com.x_m, s.com.y_m, s.com.z_m],
            feet: s
                .feet
                .iter()
                .map(|f| {
                    (
                        f.leg.clone(),
                        FootRecord {
                            at: [f.at.x_m, f.at.y_m, f.at.z_m],
                            stance: f.stance,
                        },
                    )
                })
                .collect(),
            margin_m: s.margin_m,
        }
    }
}

/// One plan of the RRT-Connect planner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RouteSummary {
    /// The step that asked for it.
    pub step: u32,
    /// Postures on the path.
    pub postures: usize,
    /// Nodes of both trees.
    pub nodes: u64,
    /// Iterations of the search.
    pub iterations: u64,
    /// Length of the body's path over the ground, metres.
    pub length_m: f64,
    /// Wall-clock planning time, milliseconds.
    pub planning_ms: f64,
    /// The body at each posture `[x, y, yaw]`, world frame.
    pub path: Vec<[f64; 3]>,
}

impl From<&crate::messages::RoutePlanned> for RouteSummary {
    fn from(r: &crate::messages::RoutePlanned) -> Self {
        RouteSummary {
            step: r.step,
            postures: r.path.len(),
            nodes: r.nodes,
            iterations: r.iterations,
            length_m: r.length_m,
            planning_ms: r.planning_ms,
            path: r.path.clone(),
        }
    }
}

/// What happened on a walk. The first fields are the summary; `states` holds every support
/// change so that the walk can be checked against the terrain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeggedWalkReport {
    /// The body reached the goal (within the tolerance).
    pub reached: bool,
    /// Why not, if not.
    pub reason: Option<String>,
    /// Steps planned.
    pub steps: usize,
    /// Tip-overs.
    pub falls: u32,
    /// Contacts of the robot's links with the terrain.
    pub collisions: u32,
    /// Contacts between parts of the robot (two legs' links, or a leg's link and the
    /// body).
    #[serde(default)]
    pub self_collisions: u32,
    /// The least stability margin over the recorded states, metres (`null` with no state).
    pub min_stability_margin_m: Option<f64>,
    /// Simulated time of the walk, seconds.
    pub sim_time_s: f64,
    /// Wall-clock time of the walk, seconds.
    pub wall_time_s: f64,
    /// Wall-clock planning time per step, milliseconds.
    pub planning_ms_per_step: f64,
    /// One entry per support change.
    pub states: Vec<StateRecord>,
    /// The robot.
    pub robot: String,
    /// The terrain.
    pub terrain: String,
    /// `sequential` or `concurrent`.
    pub mode: String,
    /// Where the body started: `[x, y, yaw]`.
    pub start: [f64; 3],
    /// The goal `[x, y]`.
    pub goal: [f64; 2],
    /// Horizontal distance from the body's origin to the goal at the end, metres.
    pub distance_to_goal_m: f64,
    /// Every foothold planned, in order: leg and world point.
    pub footholds: Vec<(String, [f64; 3])>,
    /// What [`crate::check_states`] finds wrong with `states` against the terrain (empty:
    /// every state consistent).
    #[serde(default)]
    pub state_problems: Vec<String>,
    /// What planned the steps: `free gait` or `RRT-Connect (tripod gait)`.
    #[serde(default)]
    pub planner: String,
    /// The RRT-Connect planner's plans of the walk (the first, and one after each failed
    /// move); empty for the free gait.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub routes: Vec<RouteSummary>,
    /// On the `hexapod-walls` course: what the body's path did at the walls and the steep
    /// hill.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub walls: Option<tca_legged_courses::walls::WallsChecks>,
    /// Files written.
    pub outputs: Vec<PathBuf>,
}

impl LeggedWalkReport {
    /// A few lines for people.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} on {} ({}): {}\n",
            self.robot,
            self.terrain,
            self.mode,
            if self.reached {
                "reached the goal".to_string()
            } else {
                format!(
                    "did not reach the goal: {}",
                    self.reason.as_deref().unwrap_or("no reason given")
                )
            }
        );
        s += &format!(
            "  {} steps, {} falls, {} collisions, {} self-collisions, least stability margin {}\n",
            self.steps,
            self.falls,
            self.collisions,
            self.self_collisions,
            self.min_stability_margin_m
                .map_or("-".to_string(), |m| format!("{m:.3} m"))
        );
        s += &format!(
            "  from ({:.2}, {:.2}) to ({:.2}, {:.2}): {:.2} m from the goal at the end\n",
            self.start[0], self.start[1], self.goal[0], self.goal[1], self.distance_to_goal_m
        );
        s += &format!(
            "  simulated {:.1} s, wall {:.1} s, planning {:.1} ms per step, {} states recorded\n",
            self.sim_time_s,
            self.wall_time_s,
            self.planning_ms_per_step,
            self.states.len()
        );
        if self.state_problems.is_empty() {
            s += &format!(
                "  every recorded state consistent with the terrain ({} checked)\n",
                self.states.len()
            );
        } else {
            s += &format!(
                "  {} recorded states inconsistent with the terrain, the first: {}\n",
                self.state_problems.len(),
                self.state_problems[0]
            );
        }
        if let Some(r) = self.routes.first() {
            s += &format!(
                "  planned by {}: {} plan(s), the first {} postures over {:.2} m from {} nodes in {:.0} ms\n",
                self.planner,
                self.routes.len(),
                r.postures,
                r.length_m,
                r.nodes,
                r.planning_ms
            );
        }
        if let Some(w) = &self.walls {
            s += &format!("  {}\n", w.describe());
        }
        for o in &self.outputs {
            s += &format!("  wrote {}\n", o.display());
        }
        s
    }
}
