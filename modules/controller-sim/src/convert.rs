//! Conversions between the message vocabulary (`tca_single_leg_messages`) and the simulator's
//! types, and how a simulator error is reported on the bus.

use nalgebra::Point3;
use tca_robot::{CarriagePose, JointPosition};
use tca_single_leg_messages::{
    BodyPose, CarriagePoint, ForceReading as ForceMessage, HardwareFault, Joints, MoveFailed,
    MoveFailureKind, WorldPoint,
};

use crate::sim::{FailureKind, ForceReading, SimError};

/// Joints of a message to the simulator's joint position.
pub fn joints_from_message(j: &Joints) -> JointPosition {
    JointPosition::new(j.shoulder_rad, j.elbow_rad, j.vertical_m)
}

/// The simulator's joint position as a message.
pub fn joints_to_message(q: &JointPosition) -> Joints {
    Joints {
        shoulder_rad: q.shoulder_rad,
        elbow_rad: q.elbow_rad,
        vertical_m: q.vertical_m,
    }
}

/// The carriage pose as a message.
pub fn body_pose_to_message(p: &CarriagePose) -> BodyPose {
    BodyPose {
        y_m: p.y_m,
        roll_rad: p.roll_rad,
        pitch_rad: p.pitch_rad,
    }
}

/// A carriage-frame point as a message.
pub fn carriage_point_to_message(p: &Point3<f64>) -> CarriagePoint {
    CarriagePoint {
        x_m: p.x,
        y_m: p.y,
        z_m: p.z,
    }
}

/// A world-frame point as a message.
pub fn world_point_to_message(p: &Point3<f64>) -> WorldPoint {
    WorldPoint {
        x_m: p.x,
        y_m: p.y,
        z_m: p.z,
    }
}

/// A force/torque reading as a message.
pub fn force_to_message(f: &ForceReading) -> ForceMessage {
    ForceMessage {
        force_n: [f.force_n.x, f.force_n.y, f.force_n.z],
        moment_n_m: [f.moment_nm.x, f.moment_nm.y, f.moment_nm.z],
    }
}

/// The exception a failed command raises.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Raised {
    /// A move failed or was refused; the planner replans from where the leg is.
    MoveFailed(MoveFailed),
    /// The hardware stopped itself; the walk must halt.
    HardwareFault(HardwareFault),
}

/// The exception that reports `error` of `command` (`legMove` or `bodyMove`), with the foot
/// at `foot` (world frame) afterwards.
pub fn exception_for(command: &str, error: &SimError, foot: &Point3<f64>) -> Raised {
    let detail = format!("{command}: {error}");
    let kind = match (error.kind(), error) {
        (FailureKind::HardwareFault, _) => return Raised::HardwareFault(HardwareFault { detail }),
        (FailureKind::Rejected, _) => MoveFailureKind::Refused,
        (_, SimError::Collision { .. }) => MoveFailureKind::Collision,
        (_, SimError::NoContact { .. }) => MoveFailureKind::NoContact,
        (_, SimError::Slip { .. }) => MoveFailureKind::Slip,
        (_, SimError::ExtensionLimit { .. }) => MoveFailureKind::ExtensionLimit,
        // A move failure the mapping above does not know: still a move failure the planner
        // can recover from; the detail says what it was.
        (FailureKind::MoveFailure, _) => MoveFailureKind::Collision,
    };
    Raised::MoveFailed(MoveFailed {
        command: command.to_owned(),
        kind,
        detail,
        foot: world_point_to_message(foot),
    })
}

#[cfg(test)]
mod tests {
    use tca_robot::{Joint, KinematicsError};

    use super::*;

    fn foot() -> Point3<f64> {
        Point3::new(3.8, 1.2, 0.0)
    }

    fn kind_of(error: SimError) -> Option<MoveFailureKind> {
        match exception_for("legMove", &error, &foot()) {
            Raised::MoveFailed(m) => {
                assert_eq!(m.command, "legMove");
                assert!(m.detail.starts_with("legMove: "), "{}", m.detail);
                assert_eq!(m.foot.x_m, 3.8);
                Some(m.kind)
            }
            Raised::HardwareFault(h) => {
                assert!(h.detail.starts_with("legMove: "), "{}", h.detail);
                None
            }
        }
    }

    #[test]
    fn errors_map_to_their_exceptions() {
        let q = JointPosition::new(0.0, 1.0, 3.5);
        assert_eq!(
            kind_of(SimError::EmptyWaypoints),
            Some(MoveFailureKind::Refused)
        );
        assert_eq!(
            kind_of(SimError::WaypointOutOfLimits {
                index: 0,
                source: KinematicsError::NotFinite { what: "shoulder" },
            }),
            Some(MoveFailureKind::Refused)
        );
        assert_eq!(
            kind_of(SimError::FootNotPlanted),
            Some(MoveFailureKind::Refused)
        );
        assert_eq!(
            kind_of(SimError::Collision {
                foot_world: foot(),
                terrain_height_m: 0.1,
                joints: q,
                dragged: false,
            }),
            Some(MoveFailureKind::Collision)
        );
        assert_eq!(
            kind_of(SimError::NoContact {
                force_n: 0.0,
                set_point_n: 889.6,
                joints: q,
            }),
            Some(MoveFailureKind::NoContact)
        );
        assert_eq!(
            kind_of(SimError::Slip {
                slid_m: 0.05,
                carriage_y_m: 1.2,
            }),
            Some(MoveFailureKind::Slip)
        );
        assert_eq!(
            kind_of(SimError::ExtensionLimit {
                reached_y_m: 1.2,
                target_y_m: 2.0,
                joint: Joint::Elbow,
            }),
            Some(MoveFailureKind::ExtensionLimit)
        );
        for fault in [
            SimError::LimitSwitch {
                joint: Joint::Vertical,
                position: 4.51,
            },
            SimError::ForceDropOff {
                carriage_y_m: 1.3,
                force_before_n: 2224.1,
                force_after_n: 0.0,
            },
            SimError::ServoError {
                joint: Joint::Shoulder,
                error: 0.05,
            },
        ] {
            assert_eq!(kind_of(fault), None);
        }
    }

    #[test]
    fn joints_round_trip() {
        let q = JointPosition::new(0.3, -1.2, 3.7);
        assert_eq!(joints_from_message(&joints_to_message(&q)), q);
    }
}
