//! Standing: postures that put every foot on level ground under a level body.

use nalgebra::Point3;

use crate::error::KinematicsError;
use crate::ik::IkOptions;
use crate::model::RobotModel;

impl RobotModel {
    /// The height of the body origin above level ground when every leg is in its
    /// [`neutral`](crate::Leg::neutral) position: the mean over the legs of how far the
    /// bottom of the foot's contact sphere lies below the body origin. The shipped robots
    /// stand in their neutral posture, so this is their nominal standing height.
    pub fn neutral_height(&self) -> f64 {
        let total: f64 = self
            .legs
            .iter()
            .map(|leg| leg.foot_radius() - leg.foot_position_unchecked(&leg.neutral()).z)
            .sum();
        total / self.legs.len() as f64
    }

    /// The foot positions (contact-sphere centres, body frame) for standing level at
    /// `height` above level ground: each foot where its neutral position puts it in x and
    /// y, with its sphere touching the ground at `z = -height`.
    pub fn standing_feet(&self, height: f64) -> Vec<Point3<f64>> {
        self.legs
            .iter()
            .map(|leg| {
                let neutral = leg.foot_position_unchecked(&leg.neutral());
                Point3::new(neutral.x, neutral.y, leg.foot_radius() - height)
            })
            .collect()
    }

    /// A posture that stands the body level at `height` above level ground with the feet
    /// at [`standing_feet`](Self::standing_feet), found by the inverse kinematics from the
    /// neutral positions. Fails with the first leg that cannot reach.
    pub fn standing_posture(&self, height: f64) -> Result<Vec<Vec<f64>>, KinematicsError> {
        self.legs
            .iter()
            .zip(self.standing_feet(height))
            .map(|(leg, foot)| {
                let options = IkOptions::starting_at(&leg.neutral());
                leg.inverse_kinematics(&foot, &options).map(|s| s.joints)
            })
            .collect()
    }
}
