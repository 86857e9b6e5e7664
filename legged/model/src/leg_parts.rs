//! One leg's parts at given joints, on their own: the capsules of its links and its mass
//! moment, so that a planner trying many foot positions per leg can work each out once and
//! pair them up (what [`RobotModel::legs_touching`] and
//! [`RobotModel::centre_of_mass`] do for a whole posture).

use nalgebra::{Point3, Vector3};

use crate::error::KinematicsError;
use crate::model::RobotModel;

/// One capsule of a leg link: axis ends and radius in the body frame, the ball that holds
/// the link's whole shape (centre, radius), and the capsule's own axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Part {
    a: Point3<f64>,
    b: Point3<f64>,
    r: f64,
    ball: (Point3<f64>, f64),
    lo: Point3<f64>,
    hi: Point3<f64>,
}

impl Part {
    fn new(a: Point3<f64>, b: Point3<f64>, r: f64, ball: (Point3<f64>, f64)) -> Self {
        let grow = Vector3::repeat(r);
        Part {
            a,
            b,
            r,
            ball,
            lo: a.inf(&b) - grow,
            hi: a.sup(&b) + grow,
        }
    }

    /// Whether the two capsules' boxes are further apart than `gap` along some axis (then
    /// the capsules' surfaces are too).
    fn boxes_apart(&self, other: &Part, gap: f64) -> bool {
        (0..3).any(|i| other.lo[i] - self.hi[i] > gap || self.lo[i] - other.hi[i] > gap)
    }
}

/// A leg's links at some joint positions: their capsules and their mass moment, body frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LegParts {
    leg: usize,
    parts: Vec<Part>,
    mass: f64,
    moment: Vector3<f64>,
}

impl LegParts {
    /// The leg.
    pub fn leg(&self) -> usize {
        self.leg
    }

    /// The leg's mass, kilograms.
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// The sum of each of its links' mass times its centre of mass (body frame), kg m.
    pub fn moment(&self) -> Vector3<f64> {
        self.moment
    }

    /// The capsules filling the links: axis ends (body frame) and radius.
    pub fn capsules(&self) -> impl Iterator<Item = (Point3<f64>, Point3<f64>, f64)> + '_ {
        self.parts.iter().map(|p| (p.a, p.b, p.r))
    }

    /// Whether a capsule of these links and one of `other`'s (another leg) are nearer than
    /// their radii plus twice `margin_m`: the test [`RobotModel::legs_touching`] makes
    /// between two legs.
    pub fn touches(&self, other: &LegParts, margin_m: f64) -> bool {
        self.parts.iter().any(|a| {
            other.parts.iter().any(|b| {
                let reach = a.ball.1 + b.ball.1 + 2.0 * margin_m;
                (a.ball.0 - b.ball.0).norm_squared() <= reach * reach
                    && !a.boxes_apart(b, 2.0 * margin_m)
                    && crate::segment_distance(a.a, a.b, b.a, b.b) < a.r + b.r + 2.0 * margin_m
            })
        })
    }
}

impl RobotModel {
    /// The parts of leg `leg` at joints `q` (checked against its limits).
    pub fn leg_parts(&self, leg: usize, q: &[f64]) -> Result<LegParts, KinematicsError> {
        let l = self.leg_at(leg)?;
        l.check(q)?;
        let stages = l.stage_frames(q);
        let mut parts = Vec::new();
        let (mut mass, mut moment) = (0.0, Vector3::zeros());
        for link in self.links.iter().filter(|k| k.placement.leg == Some(leg)) {
            let pose = stages[link.placement.stage] * link.placement.offset;
            if link.mass > 0.0 {
                mass += link.mass;
                moment += (pose * link.centre_of_mass).coords * link.mass;
            }
            for c in &link.collisions {
                let placed = pose * c.origin;
                let ball = (
                    Point3::from(placed.translation.vector),
                    c.shape.bounding_radius(),
                );
                for (a, b, r) in c.shape.capsules() {
                    parts.push(Part::new(placed * a, placed * b, r, ball));
                }
            }
        }
        Ok(LegParts {
            leg,
            parts,
            mass,
            moment,
        })
    }

    /// The mass and mass moment (sum of mass times centre, body frame) of the links that
    /// ride on the body, legs left out.
    pub fn body_mass_moment(&self) -> (f64, Vector3<f64>) {
        self.links
            .iter()
            .filter(|k| k.placement.leg.is_none() && k.mass > 0.0)
            .fold((0.0, Vector3::zeros()), |(m, s), k| {
                let c = k.placement.offset * k.centre_of_mass;
                (m + k.mass, s + c.coords * k.mass)
            })
    }
}

#[cfg(test)]
mod tests {
    use crate::RobotModel;

    #[test]
    fn parts_agree_with_the_whole_posture_queries() {
        let model = RobotModel::builtin("ambler").expect("the ambler");
        let leg = |name: &str| {
            model
                .legs()
                .iter()
                .position(|l| l.name() == name)
                .expect("a leg of the ambler")
        };
        // Left middle and left rear: the rear foot far forward while the middle one is far
        // back brings the rear shaft against the middle leg's links.
        let (a, b) = (leg("left_middle"), leg("left_rear"));
        let (body_mass, body_moment) = model.body_mass_moment();
        let values = [-0.9, -0.3, 0.3, 0.9];
        let (mut touching, mut clear) = (0, 0);
        for &s1 in &values {
            for &e1 in &values {
                for &s2 in &values {
                    for &e2 in &values {
                        let mut posture = model.neutral_posture();
                        posture[a] = model.legs()[a].clamp(&[s1, e1, 0.2]);
                        posture[b] = model.legs()[b].clamp(&[s2, e2, -0.2]);
                        // Some pair of legs' parts touch exactly when the posture's legs do.
                        let parts: Vec<_> = posture
                            .iter()
                            .enumerate()
                            .map(|(i, q)| model.leg_parts(i, q).expect("parts"))
                            .collect();
                        let pairs = parts
                            .iter()
                            .enumerate()
                            .any(|(i, p)| parts.iter().skip(i + 1).any(|o| p.touches(o, 0.01)));
                        let whole = model
                            .legs_touching(&posture, None, 0.01)
                            .expect("posture")
                            .is_some();
                        assert_eq!(pairs, whole, "{posture:?}");
                        if whole {
                            touching += 1;
                        } else {
                            clear += 1;
                        }
                        // The centre of mass from the parts is the whole robot's.
                        let (mut mass, mut moment) = (body_mass, body_moment);
                        for p in &parts {
                            mass += p.mass();
                            moment += p.moment();
                        }
                        let com = model.centre_of_mass(&posture).expect("com");
                        assert!((mass - com.mass).abs() < 1e-9);
                        assert!((moment / mass - com.centre.coords).norm() < 1e-9);
                    }
                }
            }
        }
        assert!(
            touching > 0 && clear > 0,
            "{touching} touching, {clear} clear"
        );
    }
}
