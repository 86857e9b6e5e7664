//! Sag: a compliant robot drooping under load when a leg is lifted, as a real rover's
//! joints and wheels give (an option, off by default).
//!
//! Each standing leg is a vertical spring of the same stiffness under the body. With the
//! body rigid, the springs' deflections lie on a plane over the feet; the plane is the one
//! whose spring forces carry the robot's weight with the centre of mass where it is (three
//! equations: the force and the two moments). Lifting a leg moves that load onto the
//! others: the body sinks and tilts toward the lifted leg, by the difference between the
//! planes of the two stances. The lifted limb droops besides: each of its joints gives by
//! a compliance times the gravity torque of the limb beyond it.
//!
//! The load comes off the lifting foot gradually: while its commanded rise is less than the
//! full sag at the foot, the body sinks by as much as the foot is raised and the foot stays
//! on the ground, still bearing load; beyond that the robot hangs fully sagged and the foot
//! rises by the difference. So a lift commanded to 20 cm leaves the foot lower by the sag,
//! or on the ground when the sag is larger. A foot still on the ground that is moved more
//! than [`DRAG_TOLERANCE_M`] sideways is dragged across the ground: a collision. When the
//! foot is put down again the load returns and the body rises back; the foot stays where it
//! touched.

use nalgebra::{Isometry3, Matrix3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use tca_legged_model::{JointKind, RobotModel};

/// How far a foot still bearing load may move sideways before it counts as dragged,
/// metres.
pub const DRAG_TOLERANCE_M: f64 = 0.01;

/// Standard gravity, m/s².
pub(crate) const GRAVITY: f64 = 9.80665;

/// How compliant the simulated robot is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SagParams {
    /// Vertical stiffness of each standing leg, newtons per metre.
    pub leg_stiffness_n_per_m: f64,
    /// How much each joint of a lifted limb gives per newton metre of gravity torque on it,
    /// radians.
    pub joint_compliance_rad_per_nm: f64,
}

impl SagParams {
    /// A compliance in the range of ATHLETE's in the field for the shipped `athlete`
    /// (12 kN/m per leg, 2e-5 rad per N m): lifting one of six legs sinks and tilts the body
    /// toward it and the limb droops, so that a 20 cm lift leaves the wheel about 12.5 cm
    /// lower than commanded (7.5 cm up), and a lift of less than that never leaves the
    /// ground.
    pub fn athlete() -> Self {
        Self {
            leg_stiffness_n_per_m: 1.2e4,
            joint_compliance_rad_per_nm: 2.0e-5,
        }
    }

    /// Refuses values that make no sense.
    pub(crate) fn check(&self) -> Result<(), String> {
        if !(self.leg_stiffness_n_per_m.is_finite() && self.leg_stiffness_n_per_m > 0.0) {
            return Err(format!(
                "sag: leg_stiffness_n_per_m is {}; give a positive stiffness",
                self.leg_stiffness_n_per_m
            ));
        }
        if !(self.joint_compliance_rad_per_nm.is_finite()
            && self.joint_compliance_rad_per_nm >= 0.0)
        {
            return Err(format!(
                "sag: joint_compliance_rad_per_nm is {}; give 0 or more",
                self.joint_compliance_rad_per_nm
            ));
        }
        Ok(())
    }
}

/// The sag of one lifted leg: the full droop of the body and the limb, and how much of it
/// the robot has taken so far.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Sag {
    /// The leg lifted.
    pub(crate) leg: usize,
    /// The body's full displacement, in the body frame.
    pub(crate) body: Isometry3<f64>,
    /// The foot's centre at lift-off, world frame.
    pub(crate) from: Point3<f64>,
    /// The share of the sag taken, 0..1.
    pub(crate) taken: f64,
    /// Whether the foot has left the ground (the whole sag taken); from then on it stays
    /// fully sagged until it is put down.
    pub(crate) lifted: bool,
}

/// The plane of spring deflections `h + a x + b y` (body frame) that carries `weight` with
/// the centre of mass over `com` on springs of `stiffness` at `feet`.
fn deflection_plane(
    feet: &[Point3<f64>],
    com: &Point3<f64>,
    weight: f64,
    stiffness: f64,
) -> Option<Vector3<f64>> {
    let mut m = Matrix3::zeros();
    for f in feet {
        let row = Vector3::new(1.0, f.x, f.y);
        m += row * row.transpose();
    }
    let rhs = Vector3::new(1.0, com.x, com.y) * (weight / stiffness);
    m.try_inverse().map(|inv| inv * rhs)
}

/// The body's displacement (body frame) when the stance changes from `before` to `after`:
/// feet given in the body frame.
pub(crate) fn body_sag(
    feet: &[Point3<f64>],
    before: &[bool],
    after: &[bool],
    com: &Point3<f64>,
    weight: f64,
    stiffness: f64,
) -> Isometry3<f64> {
    let pick = |stance: &[bool]| -> Vec<Point3<f64>> {
        feet.iter()
            .zip(stance)
            .filter(|(_, s)| **s)
            .map(|(p, _)| *p)
            .collect()
    };
    let (Some(p0), Some(p1)) = (
        deflection_plane(&pick(before), com, weight, stiffness),
        deflection_plane(&pick(after), com, weight, stiffness),
    ) else {
        return Isometry3::identity();
    };
    let d = p1 - p0;
    // The body point (x, y) sinks by d.x + d.y x + d.z y: a drop and small pitch and roll.
    Isometry3::from_parts(
        Translation3::new(0.0, 0.0, -d.x),
        UnitQuaternion::from_euler_angles(-d.z, d.y, 0.0),
    )
}

/// A fraction `f` of a displacement.
pub(crate) fn partial(full: &Isometry3<f64>, f: f64) -> Isometry3<f64> {
    let t = full.translation.vector * f;
    let r = UnitQuaternion::identity().slerp(&full.rotation, f);
    Isometry3::from_parts(Translation3::from(t), r)
}

/// How much each joint of leg `leg` gives under gravity with the leg at `q` (the others as
/// in `posture`), radians.
pub(crate) fn limb_droop(
    model: &RobotModel,
    posture: &[Vec<f64>],
    leg: usize,
    q: &[f64],
    gravity_body: &Vector3<f64>,
    compliance: f64,
) -> Vec<f64> {
    let l = &model.legs()[leg];
    let mut out = vec![0.0; l.dof()];
    if compliance == 0.0 {
        return out;
    }
    let mut p = posture.to_vec();
    p[leg] = q.to_vec();
    let (Ok(poses), Ok(frames)) = (model.link_poses(&p), l.joint_frames(q)) else {
        return out;
    };
    for (k, joint) in l.joints().iter().enumerate() {
        let JointKind::Revolute { axis } = joint.kind() else {
            continue;
        };
        let frame = &frames[k];
        let o = Point3::from(frame.translation.vector);
        let w = frame.rotation * axis.into_inner();
        let mut torque = 0.0;
        for (link, pose) in model.links().iter().zip(&poses) {
            if link.leg() != Some(leg) || link.stage() <= k || link.mass() <= 0.0 {
                continue;
            }
            let c = pose.pose * link.centre_of_mass();
            torque += w.dot(&(c - o).cross(&(gravity_body * link.mass())));
        }
        out[k] = compliance * torque;
    }
    out
}
