//! Small geometric helpers: feet and the centre of mass in the world, where a foot sphere
//! comes to rest on the terrain, stability margins.

use nalgebra::{Isometry3, Point2, Point3, Vector3};
use tca_legged_model::RobotModel;
use tca_stability::{Polygon, stability_margin, support_polygon};

use crate::terrain::TerrainView;

/// Rings (fractions of the radius) and directions sampled under a foot sphere.
const RINGS: [f64; 4] = [0.0, 0.35, 0.7, 1.0];
const DIRECTIONS: usize = 12;

/// The height at which a sphere of radius `r` lowered straight down over `c` first touches
/// the terrain: the highest of `ground(d) + sqrt(r² - d²)` over sampled points `d` of its
/// footprint. `None` when any of them is unknown.
pub(crate) fn rest_height(view: &dyn TerrainView, c: Point2<f64>, r: f64) -> Option<f64> {
    highest_rest(c, r, |p| view.height_at(p))
}

/// The highest of `ground(d) + sqrt(r² - d²)` over the sampled footprint of a sphere.
fn highest_rest(
    c: Point2<f64>,
    r: f64,
    ground: impl Fn(Point2<f64>) -> Option<f64>,
) -> Option<f64> {
    let mut best = f64::NEG_INFINITY;
    for ring in RINGS {
        let d = ring * r;
        let lift = (r * r - d * d).max(0.0).sqrt();
        let count = if ring == 0.0 { 1 } else { DIRECTIONS };
        for k in 0..count {
            let a = k as f64 * std::f64::consts::TAU / DIRECTIONS as f64 + ring;
            let h = ground(Point2::new(c.x + d * a.cos(), c.y + d * a.sin()))?;
            best = best.max(h + lift);
        }
    }
    Some(best)
}

/// How far a foot sphere centred at `c` is above resting on the terrain (negative when it
/// would be in the ground), over the highest the ground can be; `None` when the ground
/// under it is unknown and unbounded.
pub(crate) fn sphere_clearance(view: &dyn TerrainView, c: &Point3<f64>, r: f64) -> Option<f64> {
    highest_rest(Point2::new(c.x, c.y), r, |p| view.height_bound_at(p)).map(|h| c.z - h)
}

/// The world centre of a foot sphere from its contact point (the sphere's bottom).
pub(crate) fn centre_of_contact(contact: &Point3<f64>, r: f64) -> Point3<f64> {
    contact + Vector3::z() * r
}

/// The contact point (the sphere's bottom) of a foot sphere centred at `c`.
pub(crate) fn contact_of_centre(c: &Point3<f64>, r: f64) -> Point3<f64> {
    c - Vector3::z() * r
}

/// The centre of mass in the world for a body pose and posture.
pub(crate) fn com_world(
    model: &RobotModel,
    body: &Isometry3<f64>,
    posture: &[Vec<f64>],
) -> Option<Point3<f64>> {
    model.centre_of_mass(posture).ok().map(|m| body * m.centre)
}

/// The support polygon of some feet (world contact points).
pub(crate) fn polygon_of(feet: impl Iterator<Item = Point3<f64>>) -> Polygon {
    let points: Vec<Point2<f64>> = feet.map(|p| Point2::new(p.x, p.y)).collect();
    support_polygon(&points)
}

/// The stability margin of a centre of mass over a polygon.
pub(crate) fn margin(polygon: &Polygon, com: Point3<f64>) -> f64 {
    stability_margin(polygon, com)
}

/// The angle wrapped into (-pi, pi].
pub(crate) fn wrap(a: f64) -> f64 {
    let t = a.rem_euclid(std::f64::consts::TAU);
    if t > std::f64::consts::PI {
        t - std::f64::consts::TAU
    } else {
        t
    }
}

/// The yaw of a pose (rotation about world Z, applied last).
pub(crate) fn yaw_of(pose: &Isometry3<f64>) -> f64 {
    pose.rotation.euler_angles().2
}
