//! Leg kinematics: joint space, the carriage frame and the world frame.
//!
//! The leg is a SCARA-like arm: a shoulder and an elbow rotate the two horizontal links about
//! vertical axes in the plane of the carriage frame (z = 0), and the vertical prismatic member
//! hangs from the outer end of the lower link with the foot at its bottom. So the foot's
//! horizontal position depends only on the shoulder and elbow, and its height only on the
//! vertical extension: `z_C = -vertical_m`.

use std::fmt;

use nalgebra::{Matrix2, Point2, Point3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::frames::CarriagePose;
use crate::params::{CarriageParams, ComplianceParams, LegParams};

/// Position of the leg in joint space (the `legMove` way-point type).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JointPosition {
    /// Shoulder angle from carriage +X, counter-clockwise seen from above, radians.
    pub shoulder_rad: f64,
    /// Elbow angle relative to the upper link (0 = straight), radians.
    pub elbow_rad: f64,
    /// Extension of the vertical member from the link plane to the sole, metres.
    pub vertical_m: f64,
}

impl JointPosition {
    /// A joint position from its three coordinates.
    pub fn new(shoulder_rad: f64, elbow_rad: f64, vertical_m: f64) -> Self {
        Self {
            shoulder_rad,
            elbow_rad,
            vertical_m,
        }
    }

    /// The coordinates in the order shoulder, elbow, vertical.
    pub fn to_array(&self) -> [f64; 3] {
        [self.shoulder_rad, self.elbow_rad, self.vertical_m]
    }

    /// A joint position from coordinates in the order shoulder, elbow, vertical.
    pub fn from_array(a: [f64; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }

    /// The coordinate of one joint (radians or metres).
    pub fn get(&self, joint: Joint) -> f64 {
        match joint {
            Joint::Shoulder => self.shoulder_rad,
            Joint::Elbow => self.elbow_rad,
            Joint::Vertical => self.vertical_m,
        }
    }

    /// Whether every coordinate is a finite number.
    pub fn is_finite(&self) -> bool {
        self.to_array().iter().all(|v| v.is_finite())
    }
}

/// One of the leg's three joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Joint {
    /// The shoulder rotary joint (radians).
    Shoulder,
    /// The elbow rotary joint (radians).
    Elbow,
    /// The vertical prismatic axis (metres).
    Vertical,
}

impl Joint {
    /// All joints in the order of [`JointPosition::to_array`].
    pub const ALL: [Joint; 3] = [Joint::Shoulder, Joint::Elbow, Joint::Vertical];

    /// The unit of the joint's coordinate: `"rad"` or `"m"`.
    pub fn unit(self) -> &'static str {
        match self {
            Joint::Shoulder | Joint::Elbow => "rad",
            Joint::Vertical => "m",
        }
    }
}

impl fmt::Display for Joint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Joint::Shoulder => "shoulder",
            Joint::Elbow => "elbow",
            Joint::Vertical => "vertical axis",
        })
    }
}

/// Which of the two elbow solutions inverse kinematics returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ElbowBranch {
    /// `elbow_rad >= 0`: the lower link turns counter-clockwise from the upper link.
    Positive,
    /// `elbow_rad <= 0`: the lower link turns clockwise from the upper link.
    Negative,
}

impl ElbowBranch {
    /// The branch a joint position is on.
    pub fn of(q: &JointPosition) -> Self {
        if q.elbow_rad >= 0.0 {
            ElbowBranch::Positive
        } else {
            ElbowBranch::Negative
        }
    }
}

/// Limits of one joint, in the joint's unit (radians or metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisLimits {
    /// Lower soft limit.
    pub min: f64,
    /// Upper soft limit.
    pub max: f64,
    /// Lower limit switch.
    pub switch_min: f64,
    /// Upper limit switch.
    pub switch_max: f64,
    /// Speed limit per second.
    pub max_speed: f64,
    /// Acceleration limit per second squared.
    pub max_accel: f64,
}

impl AxisLimits {
    /// Whether `value` is within the soft limits.
    pub fn contains(&self, value: f64) -> bool {
        value >= self.min && value <= self.max
    }
}

/// Why a kinematic computation has no answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// An input coordinate is NaN or infinite.
    #[error("{what} is not a finite number; give finite coordinates")]
    NotFinite {
        /// Which input.
        what: &'static str,
    },
    /// The point is nearer to or farther from the shoulder axis than the links reach.
    #[error(
        "foot position is {horizontal_m:.3} m from the shoulder axis but the links reach only \
         {min_reach_m:.3} to {max_reach_m:.3} m; choose a nearer point"
    )]
    OutOfReach {
        /// Horizontal distance asked for.
        horizontal_m: f64,
        /// Nearest reachable distance within the elbow limits.
        min_reach_m: f64,
        /// Farthest reachable distance (links straight).
        max_reach_m: f64,
    },
    /// The solution (or the given joint position) is outside a joint's soft limits.
    #[error("{joint} at {value:.4} {unit} is outside its limits [{min:.4}, {max:.4}] {unit}", unit = joint.unit())]
    JointLimit {
        /// The joint.
        joint: Joint,
        /// Its value.
        value: f64,
        /// Lower soft limit.
        min: f64,
        /// Upper soft limit.
        max: f64,
    },
    /// The horizontal links are straight (or folded) and the Jacobian cannot be inverted.
    #[error("the Jacobian is singular at elbow {elbow_rad:.4} rad (links straight or folded)")]
    Singular {
        /// The elbow angle.
        elbow_rad: f64,
    },
}

/// Result of a kinematic computation.
pub type Result<T, E = KinematicsError> = std::result::Result<T, E>;

/// Forward and inverse kinematics, Jacobian, joint limits and the compliance deflection model
/// of the leg, built from [`LegParams`].
#[derive(Debug, Clone, PartialEq)]
pub struct LegKinematics {
    upper_m: f64,
    lower_m: f64,
    shoulder: AxisLimits,
    elbow: AxisLimits,
    vertical: AxisLimits,
    carriage: CarriageParams,
    compliance: ComplianceParams,
    /// The deflection model compensated in [`forward`](Self::forward) and
    /// [`inverse`](Self::inverse), when built with [`compensated`](Self::compensated).
    model: Option<(f64, f64)>,
}

/// Fixed-point iterations of the compensated inverse kinematics (the modelled deflection is
/// a few centimetres and varies slowly with the joints, so a handful converge to well under a
/// millimetre).
const COMPENSATION_ITERATIONS: usize = 6;

impl LegKinematics {
    /// Kinematics for the given parameters.
    pub fn new(params: &LegParams) -> Self {
        let l = &params.leg;
        let rotary = |a: &crate::params::RotaryAxisParams| AxisLimits {
            min: a.min_rad,
            max: a.max_rad,
            switch_min: a.limit_switch_min_rad,
            switch_max: a.limit_switch_max_rad,
            max_speed: a.max_speed_rad_per_s,
            max_accel: a.max_accel_rad_per_s2,
        };
        Self {
            upper_m: l.upper_link_m,
            lower_m: l.lower_link_m,
            shoulder: rotary(&l.shoulder),
            elbow: rotary(&l.elbow),
            vertical: AxisLimits {
                min: l.vertical.min_m,
                max: l.vertical.max_m,
                switch_min: l.vertical.limit_switch_min_m,
                switch_max: l.vertical.limit_switch_max_m,
                max_speed: l.vertical.max_speed_m_per_s,
                max_accel: l.vertical.max_accel_m_per_s2,
            },
            carriage: params.carriage,
            compliance: params.compliance,
            model: None,
        }
    }

    /// Kinematics that compensate the leg's deflection as the walking system's Controller and
    /// planners do: [`forward`](Self::forward) adds the calibrated model of the rails'
    /// torsion and sag (`compliance.model_*`) to the rigid kinematics, and
    /// [`inverse`](Self::inverse) solves for the joints that put the deflected foot on the
    /// target. The Jacobian and [`forward_horizontal`](Self::forward_horizontal) stay rigid.
    pub fn compensated(params: &LegParams) -> Self {
        let c = &params.compliance;
        Self {
            model: Some((c.model_sag_m_per_m_reach, c.model_torsion_rad_per_m_offset)),
            ..Self::new(params)
        }
    }

    /// Whether these kinematics compensate a deflection model.
    pub fn is_compensated(&self) -> bool {
        self.model.is_some()
    }

    /// The modelled (compensated) deflection at a joint position: zero for rigid kinematics.
    pub fn modelled_deflection(&self, q: &JointPosition) -> Vector3<f64> {
        let Some((sag, torsion)) = self.model else {
            return Vector3::zeros();
        };
        let h = self.forward_horizontal(q.shoulder_rad, q.elbow_rad);
        Vector3::new(torsion * h.x * q.vertical_m, 0.0, -sag * h.coords.norm())
    }

    /// The joint position with every joint clamped into its soft limits.
    pub fn clamp_to_limits(&self, q: &JointPosition) -> JointPosition {
        JointPosition::new(
            q.shoulder_rad.clamp(self.shoulder.min, self.shoulder.max),
            q.elbow_rad.clamp(self.elbow.min, self.elbow.max),
            q.vertical_m.clamp(self.vertical.min, self.vertical.max),
        )
    }

    /// Limits of one joint.
    pub fn limits(&self, joint: Joint) -> &AxisLimits {
        match joint {
            Joint::Shoulder => &self.shoulder,
            Joint::Elbow => &self.elbow,
            Joint::Vertical => &self.vertical,
        }
    }

    /// Nearest and farthest horizontal distance of the foot from the shoulder axis, metres
    /// (the nearest is set by the elbow limits).
    pub fn reach_range_m(&self) -> (f64, f64) {
        let max_fold = self
            .elbow
            .min
            .abs()
            .max(self.elbow.max.abs())
            .min(std::f64::consts::PI);
        (
            self.horizontal_reach_for_elbow(max_fold),
            self.upper_m + self.lower_m,
        )
    }

    fn horizontal_reach_for_elbow(&self, elbow_rad: f64) -> f64 {
        let (l1, l2) = (self.upper_m, self.lower_m);
        (l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * elbow_rad.cos())
            .max(0.0)
            .sqrt()
    }

    /// Checks a joint position against the soft limits (and finiteness).
    pub fn check_limits(&self, q: &JointPosition) -> Result<()> {
        if !q.is_finite() {
            return Err(KinematicsError::NotFinite {
                what: "joint position",
            });
        }
        for joint in Joint::ALL {
            let value = q.get(joint);
            let lim = self.limits(joint);
            if !lim.contains(value) {
                return Err(KinematicsError::JointLimit {
                    joint,
                    value,
                    min: lim.min,
                    max: lim.max,
                });
            }
        }
        Ok(())
    }

    /// The first joint (if any) at or past one of its limit switches.
    pub fn limit_switch_tripped(&self, q: &JointPosition) -> Option<Joint> {
        Joint::ALL.into_iter().find(|&joint| {
            let value = q.get(joint);
            let lim = self.limits(joint);
            value <= lim.switch_min || value >= lim.switch_max
        })
    }

    /// Horizontal (x, y) position of the foot in the carriage frame.
    pub fn forward_horizontal(&self, shoulder_rad: f64, elbow_rad: f64) -> Point2<f64> {
        let a = shoulder_rad;
        let b = shoulder_rad + elbow_rad;
        Point2::new(
            self.upper_m * a.cos() + self.lower_m * b.cos(),
            self.upper_m * a.sin() + self.lower_m * b.sin(),
        )
    }

    /// Foot sole centre in the carriage frame for a joint position: the rigid kinematics,
    /// plus the modelled deflection when [`compensated`](Self::compensated).
    pub fn forward(&self, q: &JointPosition) -> Point3<f64> {
        let h = self.forward_horizontal(q.shoulder_rad, q.elbow_rad);
        Point3::new(h.x, h.y, -q.vertical_m) + self.modelled_deflection(q)
    }

    /// Foot sole centre in the world frame for a carriage pose and joint position.
    pub fn forward_world(&self, pose: &CarriagePose, q: &JointPosition) -> Point3<f64> {
        pose.to_world(&self.carriage, &self.forward(q))
    }

    /// Joint position that puts the foot sole centre at `p` (carriage frame) on the given
    /// elbow branch; refused when out of reach or outside the joint limits. When
    /// [`compensated`](Self::compensated), the foot as deflected by the model.
    pub fn inverse(&self, p: &Point3<f64>, branch: ElbowBranch) -> Result<JointPosition> {
        if self.model.is_none() {
            return self.inverse_rigid(p, branch);
        }
        let mut q = self.inverse_rigid(p, branch)?;
        for _ in 0..COMPENSATION_ITERATIONS {
            let rigid_target = p - self.modelled_deflection(&q);
            q = self.inverse_rigid(&rigid_target, branch)?;
        }
        Ok(q)
    }

    /// [`inverse`](Self::inverse) of the rigid kinematics.
    fn inverse_rigid(&self, p: &Point3<f64>, branch: ElbowBranch) -> Result<JointPosition> {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(KinematicsError::NotFinite {
                what: "foot position",
            });
        }
        let (l1, l2) = (self.upper_m, self.lower_m);
        let r2 = p.x * p.x + p.y * p.y;
        let r = r2.sqrt();
        let (min_reach_m, max_reach_m) = self.reach_range_m();
        let cos_elbow = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
        if !(-1.0..=1.0).contains(&cos_elbow) {
            return Err(KinematicsError::OutOfReach {
                horizontal_m: r,
                min_reach_m,
                max_reach_m,
            });
        }
        let magnitude = cos_elbow.acos();
        let elbow_rad = match branch {
            ElbowBranch::Positive => magnitude,
            ElbowBranch::Negative => -magnitude,
        };
        let shoulder_rad =
            wrap_angle(p.y.atan2(p.x) - (l2 * elbow_rad.sin()).atan2(l1 + l2 * elbow_rad.cos()));
        let q = JointPosition::new(shoulder_rad, elbow_rad, -p.z);
        if !self.elbow.contains(elbow_rad) {
            return Err(KinematicsError::OutOfReach {
                horizontal_m: r,
                min_reach_m,
                max_reach_m,
            });
        }
        self.check_limits(&q)?;
        Ok(q)
    }

    /// Inverse kinematics choosing the elbow branch whose solution is within limits and
    /// nearest to `near` (the shoulder and elbow distance); the error of the preferred branch
    /// (the one `near` is on) when neither works.
    pub fn inverse_nearest(&self, p: &Point3<f64>, near: &JointPosition) -> Result<JointPosition> {
        let preferred = ElbowBranch::of(near);
        let other = match preferred {
            ElbowBranch::Positive => ElbowBranch::Negative,
            ElbowBranch::Negative => ElbowBranch::Positive,
        };
        let distance = |q: &JointPosition| {
            (q.shoulder_rad - near.shoulder_rad).abs() + (q.elbow_rad - near.elbow_rad).abs()
        };
        match (self.inverse(p, preferred), self.inverse(p, other)) {
            (Ok(a), Ok(b)) => Ok(if distance(&b) < distance(&a) { b } else { a }),
            (Ok(a), Err(_)) => Ok(a),
            (Err(_), Ok(b)) => Ok(b),
            (Err(e), Err(_)) => Err(e),
        }
    }

    /// Inverse kinematics for a world point at a carriage pose.
    pub fn inverse_world(
        &self,
        pose: &CarriagePose,
        p_world: &Point3<f64>,
        branch: ElbowBranch,
    ) -> Result<JointPosition> {
        self.inverse(&pose.to_carriage(&self.carriage, p_world), branch)
    }

    /// Jacobian of the horizontal links: `d(x, y)/d(shoulder, elbow)` in the carriage frame,
    /// metres per radian.
    pub fn jacobian(&self, shoulder_rad: f64, elbow_rad: f64) -> Matrix2<f64> {
        let (s1, c1) = shoulder_rad.sin_cos();
        let (s12, c12) = (shoulder_rad + elbow_rad).sin_cos();
        let (l1, l2) = (self.upper_m, self.lower_m);
        Matrix2::new(-l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12)
    }

    /// Inverse of the horizontal Jacobian: maps a foot velocity (carriage frame, m/s) to
    /// shoulder and elbow rates (rad/s). Refused near straight or folded links, where
    /// `|sin(elbow)| < 1e-6`.
    pub fn inverse_jacobian(&self, shoulder_rad: f64, elbow_rad: f64) -> Result<Matrix2<f64>> {
        if elbow_rad.sin().abs() < 1e-6 || !elbow_rad.is_finite() || !shoulder_rad.is_finite() {
            return Err(KinematicsError::Singular { elbow_rad });
        }
        self.jacobian(shoulder_rad, elbow_rad)
            .try_inverse()
            .ok_or(KinematicsError::Singular { elbow_rad })
    }

    /// Shoulder and elbow rates that move the foot with the horizontal velocity `v`
    /// (carriage frame, m/s).
    pub fn joint_rates_for(&self, q: &JointPosition, v: &Vector2<f64>) -> Result<Vector2<f64>> {
        Ok(self.inverse_jacobian(q.shoulder_rad, q.elbow_rad)? * v)
    }

    /// Compliance deflection of the foot (carriage frame, metres): where the real foot is
    /// relative to the rigid [`forward`](Self::forward) position, for a joint position and the
    /// force the ground exerts on the foot (carriage axes, newtons; zero in the air).
    ///
    /// The model (§4.3: deflection grows with extension and load; a few centimetres):
    /// * sag: the rails and carriage dip under the leg's weight, `-sag * reach` in z;
    /// * torsion: the rails roll by `torsion * x` (the foot's lateral offset), swinging the
    ///   foot outward by that angle times the vertical extension;
    /// * load: `(vertical / max vertical) * (lateral * F_x, lateral * F_y, vertical * F_z)`.
    pub fn deflection(&self, q: &JointPosition, force_on_foot_n: &Vector3<f64>) -> Vector3<f64> {
        let c = &self.compliance;
        let h = self.forward_horizontal(q.shoulder_rad, q.elbow_rad);
        let reach = h.coords.norm();
        let sag = -c.sag_m_per_m_reach * reach;
        let torsion = c.torsion_rad_per_m_offset * h.x * q.vertical_m;
        let scale = q.vertical_m / self.vertical.max;
        Vector3::new(
            torsion + scale * c.lateral_m_per_n * force_on_foot_n.x,
            scale * c.lateral_m_per_n * force_on_foot_n.y,
            sag + scale * c.vertical_m_per_n * force_on_foot_n.z,
        )
    }

    /// The fixed carriage placement these kinematics use.
    pub fn carriage(&self) -> &CarriageParams {
        &self.carriage
    }

    /// Lengths of the upper and lower horizontal links, metres.
    pub fn link_lengths_m(&self) -> (f64, f64) {
        (self.upper_m, self.lower_m)
    }
}

/// Wraps an angle into `(-pi, pi]`.
pub fn wrap_angle(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut w = a % two_pi;
    if w <= -std::f64::consts::PI {
        w += two_pi;
    } else if w > std::f64::consts::PI {
        w -= two_pi;
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn kin() -> LegKinematics {
        LegKinematics::new(&LegParams::default())
    }

    #[test]
    fn forward_of_straight_leg_along_x() {
        let k = kin();
        let p = k.forward(&JointPosition::new(0.0, 0.0, 3.5));
        assert!((p - Point3::new(2.5, 0.0, -3.5)).norm() < 1e-12);
        let p = k.forward(&JointPosition::new(std::f64::consts::FRAC_PI_2, 0.0, 3.0));
        assert!((p - Point3::new(0.0, 2.5, -3.0)).norm() < 1e-12);
    }

    #[test]
    fn both_branches_reach_the_same_point() {
        let k = kin();
        let target = Point3::new(0.4, 1.7, -3.8);
        let a = k.inverse(&target, ElbowBranch::Positive).unwrap();
        let b = k.inverse(&target, ElbowBranch::Negative).unwrap();
        assert!(a.elbow_rad > 0.0 && b.elbow_rad < 0.0);
        assert!((k.forward(&a) - target).norm() < 1e-9);
        assert!((k.forward(&b) - target).norm() < 1e-9);
    }

    #[test]
    fn out_of_reach_and_limits_are_refused() {
        let k = kin();
        let err = k
            .inverse(&Point3::new(2.6, 0.0, -3.5), ElbowBranch::Positive)
            .unwrap_err();
        assert!(matches!(err, KinematicsError::OutOfReach { .. }), "{err}");
        assert!(err.to_string().contains("2.600"));
        let err = k
            .inverse(&Point3::new(0.05, 0.0, -3.5), ElbowBranch::Positive)
            .unwrap_err();
        assert!(matches!(err, KinematicsError::OutOfReach { .. }), "{err}");
        let err = k
            .inverse(&Point3::new(1.0, 1.0, -4.8), ElbowBranch::Positive)
            .unwrap_err();
        assert!(
            matches!(
                err,
                KinematicsError::JointLimit {
                    joint: Joint::Vertical,
                    ..
                }
            ),
            "{err}"
        );
        let err = k
            .inverse(&Point3::new(f64::NAN, 1.0, -4.0), ElbowBranch::Positive)
            .unwrap_err();
        assert!(matches!(err, KinematicsError::NotFinite { .. }));
    }

    #[test]
    fn inverse_nearest_prefers_the_current_branch() {
        let k = kin();
        let target = Point3::new(1.0, 1.5, -3.5);
        let near = k.inverse(&target, ElbowBranch::Negative).unwrap();
        let q = k.inverse_nearest(&target, &near).unwrap();
        assert_eq!(ElbowBranch::of(&q), ElbowBranch::Negative);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let k = kin();
        let (s, e) = (0.7, -1.1);
        let j = k.jacobian(s, e);
        let h = 1e-6;
        let ds = (k.forward_horizontal(s + h, e) - k.forward_horizontal(s - h, e)) / (2.0 * h);
        let de = (k.forward_horizontal(s, e + h) - k.forward_horizontal(s, e - h)) / (2.0 * h);
        assert!((j.column(0) - ds).norm() < 1e-6);
        assert!((j.column(1) - de).norm() < 1e-6);
        let inv = k.inverse_jacobian(s, e).unwrap();
        assert!((inv * j - Matrix2::identity()).norm() < 1e-9);
        assert!(k.inverse_jacobian(0.3, 0.0).is_err());
    }

    #[test]
    fn deflection_is_up_to_some_decimetres_and_grows_with_extension_and_load() {
        let k = kin();
        let short = JointPosition::new(0.2, 0.5, 3.0);
        let long = JointPosition::new(0.2, 0.5, 4.5);
        let zero = Vector3::zeros();
        let load = Vector3::new(450.0, 450.0, 3558.6);
        let d_short = k.deflection(&short, &load).norm();
        let d_long = k.deflection(&long, &load).norm();
        assert!(d_long > d_short);
        assert!(k.deflection(&long, &load).norm() > k.deflection(&long, &zero).norm());
        // The rails' torsion dominates: a foot 2.2 m out to the side at full extension is
        // swung nearly 20 cm (the report's leg moves were off by up to about 20 cm).
        assert!(d_long > 0.01 && d_long < 0.25, "{d_long}");
    }

    #[test]
    fn limit_switches_sit_outside_the_soft_limits() {
        let k = kin();
        assert_eq!(
            k.limit_switch_tripped(&JointPosition::new(0.0, 0.5, 3.5)),
            None
        );
        assert_eq!(
            k.limit_switch_tripped(&JointPosition::new(0.0, 0.5, 4.53)),
            Some(Joint::Vertical)
        );
        assert_eq!(
            k.limit_switch_tripped(&JointPosition::new(-3.06, 0.5, 3.5)),
            Some(Joint::Shoulder)
        );
    }

    fn joints_within_limits() -> impl Strategy<Value = JointPosition> {
        let k = kin();
        let (s, e, v) = (
            *k.limits(Joint::Shoulder),
            *k.limits(Joint::Elbow),
            *k.limits(Joint::Vertical),
        );
        (
            s.min..s.max,
            prop_oneof![e.min..-0.01, 0.01..e.max],
            v.min..v.max,
        )
            .prop_map(|(a, b, c)| JointPosition::new(a, b, c))
    }

    proptest! {
        #[test]
        fn joint_to_cartesian_to_joint(q in joints_within_limits()) {
            let k = kin();
            let p = k.forward(&q);
            let back = k.inverse(&p, ElbowBranch::of(&q)).unwrap();
            prop_assert!((back.shoulder_rad - q.shoulder_rad).abs() < 1e-7, "{q:?} -> {back:?}");
            prop_assert!((back.elbow_rad - q.elbow_rad).abs() < 1e-7, "{q:?} -> {back:?}");
            prop_assert!((back.vertical_m - q.vertical_m).abs() < 1e-12);
        }

        #[test]
        fn cartesian_to_joint_to_cartesian_both_branches(
            r in 0.6f64..2.49, angle in -std::f64::consts::PI..std::f64::consts::PI, z in -4.5f64..-3.0,
        ) {
            let k = kin();
            let p = Point3::new(r * angle.cos(), r * angle.sin(), z);
            for branch in [ElbowBranch::Positive, ElbowBranch::Negative] {
                // Near -X the shoulder limits exclude a narrow wedge; any answer must be exact.
                if let Ok(q) = k.inverse(&p, branch) {
                    prop_assert_eq!(ElbowBranch::of(&q), branch);
                    prop_assert!(k.check_limits(&q).is_ok());
                    prop_assert!((k.forward(&q) - p).norm() < 1e-9);
                }
            }
            // Away from the shoulder's excluded wedge both branches exist.
            if angle.abs() < 1.8 {
                prop_assert!(k.inverse(&p, ElbowBranch::Positive).is_ok());
                prop_assert!(k.inverse(&p, ElbowBranch::Negative).is_ok());
            }
        }

        #[test]
        fn carriage_world_round_trip(
            y in 0.5f64..10.5, roll in -0.05f64..0.05, pitch in -0.05f64..0.05,
            x in -3.0f64..3.0, py in -3.0f64..3.0, z in -5.0f64..1.0,
        ) {
            let params = LegParams::default();
            let pose = CarriagePose { y_m: y, roll_rad: roll, pitch_rad: pitch };
            let p = Point3::new(x, py, z);
            let w = pose.to_world(&params.carriage, &p);
            prop_assert!((pose.to_carriage(&params.carriage, &w) - p).norm() < 1e-9);
            if roll == 0.0 && pitch == 0.0 {
                prop_assert!((w.y - (y + py)).abs() < 1e-12);
            }
        }

        #[test]
        fn world_inverse_matches_world_forward(q in joints_within_limits(), y in 0.5f64..10.5) {
            let k = kin();
            let pose = CarriagePose::level(y);
            let w = k.forward_world(&pose, &q);
            let back = k.inverse_world(&pose, &w, ElbowBranch::of(&q)).unwrap();
            prop_assert!((k.forward_world(&pose, &back) - w).norm() < 1e-9);
        }
    }
}

#[cfg(test)]
mod compensation_tests {
    use super::*;

    /// The largest error of an unloaded foot over the workspace, placed by `kin`'s inverse
    /// kinematics on a leg that deflects by the true compliance model: metres.
    fn worst_error(kin: &LegKinematics, truth: &LegKinematics) -> f64 {
        let mut worst: f64 = 0.0;
        for ix in -10..=10 {
            for iy in -10..=10 {
                for vertical in [3.2, 3.8, 4.4] {
                    let p = Point3::new(ix as f64 * 0.25, iy as f64 * 0.25, -vertical);
                    let Ok(q) = kin.inverse(&p, ElbowBranch::Positive) else {
                        continue;
                    };
                    let real = truth.forward(&q) + truth.deflection(&q, &Vector3::zeros());
                    worst = worst.max((real - p).norm());
                }
            }
        }
        worst
    }

    #[test]
    fn the_calibrated_kinematics_bring_leg_moves_from_about_20_cm_to_about_5_cm() {
        // The report (§4.3, §7.1): uncompensated leg moves were off by up to about 20 cm; the
        // calibrated inverse kinematics brought that to about 5 cm.
        let params = LegParams::default();
        let rigid = LegKinematics::new(&params);
        let calibrated = LegKinematics::compensated(&params);
        let uncompensated = worst_error(&rigid, &rigid);
        let compensated = worst_error(&calibrated, &rigid);
        eprintln!(
            "worst unloaded foot error: {uncompensated:.3} m rigid, {compensated:.3} m calibrated"
        );
        assert!(
            (0.15..=0.25).contains(&uncompensated),
            "uncompensated {uncompensated:.3} m"
        );
        assert!(
            (0.01..=0.06).contains(&compensated),
            "compensated {compensated:.3} m"
        );
    }

    #[test]
    fn compensated_inverse_kinematics_inverts_the_compensated_forward() {
        let kin = LegKinematics::compensated(&LegParams::default());
        let p = Point3::new(1.5, 1.2, -3.9);
        let q = kin.inverse(&p, ElbowBranch::Negative).unwrap();
        assert!((kin.forward(&q) - p).norm() < 1e-4, "{}", kin.forward(&q));
        assert!(kin.is_compensated());
        assert!(!LegKinematics::new(&LegParams::default()).is_compensated());
    }
}
