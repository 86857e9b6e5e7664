//! Single moves for a planner above the free gait that chooses footholds and body poses
//! itself (CG-space planning, say): each move is checked as the free gait checks its own
//! (reach along the way, the stability margin with the centre of mass from the links, the
//! robot's parts against the terrain, the legs against each other).

use nalgebra::{Isometry3, Point2, Point3};
use tca_stability::margin_along_path;

use super::{BodyMove, Foothold, FreeGait, Segment};
use crate::geometry::{contact_of_centre, polygon_of, rest_height};
use crate::state::{Action, GaitState, LegGaitState, StepPlan};
use crate::terrain::TerrainView;

impl FreeGait {
    /// The body's move to `target` with every standing foot where it stands (a foot in the
    /// air goes with the body).
    pub fn move_body_to(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        target: &Isometry3<f64>,
    ) -> Result<StepPlan, String> {
        let m = self.body_move(state, terrain, target)?;
        let mut legs = state.legs.clone();
        for (i, l) in legs.iter_mut().enumerate() {
            l.joints = m.posture[i].clone();
            if !l.stance {
                l.foot = target * (state.body.inverse() * l.foot);
            }
        }
        Ok(StepPlan {
            actions: vec![Action::Body { target: *target }],
            end: GaitState {
                body: *target,
                legs,
            },
            min_margin_m: m.min_margin,
        })
    }

    /// A swing of `leg`, the body still, from where its foot is (on the ground or in the
    /// air) to where the foot sphere comes to rest on the ground over `at` (world X, Y).
    pub fn swing_to(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        leg: usize,
        at: Point2<f64>,
    ) -> Result<StepPlan, String> {
        let info = self
            .legs
            .get(leg)
            .ok_or_else(|| format!("the robot has no leg number {leg}"))?;
        let r = info.radius;
        let z = rest_height(terrain, at, r)
            .ok_or_else(|| format!("the ground under ({:.2}, {:.2}) is unknown", at.x, at.y))?;
        let centre = Point3::new(at.x, at.y, z);
        let posture = state.posture();
        let joints = self
            .ik(leg, &(state.body.inverse() * centre), &posture[leg], 4)
            .ok_or_else(|| {
                format!(
                    "leg `{}` cannot reach ({:.2}, {:.2}, {:.2}) from the body where it is",
                    info.name, centre.x, centre.y, centre.z
                )
            })?;
        let mut at_foothold = posture.clone();
        at_foothold[leg] = joints.clone();
        if let Some(contact) = self.legs_touch(&at_foothold, Some(leg)) {
            return Err(format!(
                "with its foot at ({:.2}, {:.2}), leg `{}`: {contact}",
                at.x, at.y, info.name
            ));
        }
        let foothold = Foothold {
            centre,
            joints,
            score: 0.0,
            progress: 0.0,
        };
        let polygon = polygon_of(
            state
                .stance_legs()
                .into_iter()
                .filter(|&i| i != leg)
                .map(|i| state.legs[i].foot),
        );
        let swing = self.swing(
            terrain,
            &state.body,
            &posture,
            leg,
            &posture[leg],
            &foothold,
            &polygon,
        )?;
        let body = BodyMove {
            target: state.body,
            posture: posture.clone(),
            min_margin: self.margin_of(state, &state.body, &posture, Some(leg)),
        };
        Ok(self.assemble(state, &body, leg, swing, foothold))
    }

    /// Lifts the foot of a standing `leg` by `rise` metres (world Z) and holds it there, the
    /// body still.
    pub fn lift_leg(
        &self,
        state: &GaitState,
        terrain: &dyn TerrainView,
        leg: usize,
        rise: f64,
    ) -> Result<StepPlan, String> {
        let info = self
            .legs
            .get(leg)
            .ok_or_else(|| format!("the robot has no leg number {leg}"))?;
        let posture = state.posture();
        let lifted = self
            .raise(&state.body, leg, &posture[leg], rise)
            .ok_or_else(|| format!("leg `{}` cannot lift its foot {rise:.2} m", info.name))?;
        let mut com_path = Vec::new();
        self.segment(
            terrain,
            &state.body,
            &posture,
            leg,
            &posture[leg],
            &lifted,
            Segment::Lift,
            &mut com_path,
        )?;
        let polygon = polygon_of(
            state
                .stance_legs()
                .into_iter()
                .filter(|&i| i != leg)
                .map(|i| state.legs[i].foot),
        );
        let worst = margin_along_path(&polygon, &com_path)
            .map(|m| m.margin_m)
            .unwrap_or(f64::NEG_INFINITY);
        if worst.is_nan() || worst < self.params.min_margin_m {
            return Err(format!(
                "lifting leg `{}` would leave a margin of {worst:.3} m",
                info.name
            ));
        }
        let centre = self.foot_centre(&state.body, leg, &lifted);
        let mut end = state.clone();
        end.legs[leg] = LegGaitState {
            joints: lifted.clone(),
            stance: false,
            foot: contact_of_centre(&centre, info.radius),
        };
        Ok(StepPlan {
            actions: vec![Action::Reach {
                leg,
                waypoints: vec![lifted],
            }],
            end,
            min_margin_m: worst,
        })
    }

    /// The foot-sphere radius of `leg`, metres (0 for a leg the robot does not have).
    pub fn foot_radius(&self, leg: usize) -> f64 {
        self.legs.get(leg).map(|l| l.radius).unwrap_or(0.0)
    }

    /// The free gait's stability margin of `state` as it stands (every standing foot), with
    /// the centre of mass from the links; negative outside the support polygon.
    pub fn margin_standing(&self, state: &GaitState) -> f64 {
        self.margin_of(state, &state.body, &state.posture(), None)
    }
}
