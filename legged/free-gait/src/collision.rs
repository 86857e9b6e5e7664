//! Link shapes against the terrain: each collision shape of the model is covered by points
//! on its surface, checked against the highest ground around each (a disc as wide as the
//! points' spacing), after a cheap whole-shape test.

use nalgebra::{Isometry3, Point2, Point3};
use tca_legged_model::{RobotModel, Shape};

use crate::terrain::TerrainView;

/// Most points along one direction of a shape's surface.
const MAX_POINTS_PER_SIDE: usize = 60;

/// What a shape check found.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Hit {
    /// The link would come within the clearance of the ground.
    Ground { link: String, gap_m: f64 },
    /// The ground near the link is unknown.
    Unknown { link: String },
}

impl Hit {
    pub(crate) fn describe(&self) -> String {
        match self {
            Hit::Ground { link, gap_m } => format!(
                "link `{link}` would come {:.3} m from the ground (it must keep the clearance)",
                gap_m
            ),
            Hit::Unknown { link } => format!("the ground under link `{link}` is unknown"),
        }
    }
}

/// One collision shape of the model and the points covering its surface (shape frame).
#[derive(Debug, Clone)]
struct Probe {
    link: String,
    leg: Option<usize>,
    shape: Shape,
    points: Vec<Point3<f64>>,
    spacing: f64,
}

/// Every collision shape of the model, in the order of `RobotModel::collision_shapes`.
#[derive(Debug, Clone)]
pub(crate) struct Probes {
    probes: Vec<Probe>,
}

/// What to assume of unknown ground under a shape: a height, or `None` to count it as a
/// hit.
pub(crate) type Fallback<'a> = &'a dyn Fn(Option<usize>) -> Option<f64>;

impl Probes {
    pub(crate) fn new(model: &RobotModel, spacing: f64) -> Self {
        let posture = model.neutral_posture();
        let probes = model
            .collision_shapes(&posture)
            .map(|shapes| {
                shapes
                    .iter()
                    .map(|s| {
                        let leg = model.link(s.link).and_then(|l| l.leg());
                        let (points, spacing) = surface_points(&s.shape, spacing);
                        Probe {
                            link: s.link.to_string(),
                            leg,
                            shape: s.shape,
                            points,
                            spacing,
                        }
                    })
                    .collect()
            })
            .unwrap_or_default();
        Probes { probes }
    }

    /// Checks the shapes of the links `select` accepts (by leg, `None` for the body) at a
    /// body pose and posture. Unknown ground takes `fallback`'s height for the shape's leg.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn check(
        &self,
        model: &RobotModel,
        view: &dyn TerrainView,
        body: &Isometry3<f64>,
        posture: &[Vec<f64>],
        select: &dyn Fn(Option<usize>) -> bool,
        clearance: f64,
        fallback: Fallback<'_>,
    ) -> Result<(), Hit> {
        let Ok(shapes) = model.collision_shapes(posture) else {
            return Ok(());
        };
        for (placed, probe) in shapes.iter().zip(&self.probes) {
            if !select(probe.leg) {
                continue;
            }
            let pose = body * placed.pose;
            let lowest = pose.translation.z - probe.shape.depth_below(&pose);
            let centre = Point2::new(pose.translation.x, pose.translation.y);
            let reach = probe.shape.bounding_radius();
            let top = view.max_height_in_disc(centre, reach);
            if let Some(top) = top
                && lowest - clearance >= top
            {
                continue;
            }
            let fallback_height = fallback(probe.leg);
            for p in &probe.points {
                let w = pose * p;
                if let Some(top) = top
                    && w.z - clearance >= top
                {
                    continue;
                }
                let ground = match view.max_height_in_disc(Point2::new(w.x, w.y), probe.spacing) {
                    Some(h) => h,
                    None => match fallback_height {
                        Some(h) => h,
                        None => {
                            return Err(Hit::Unknown {
                                link: probe.link.clone(),
                            });
                        }
                    },
                };
                if w.z - clearance < ground {
                    return Err(Hit::Ground {
                        link: probe.link.clone(),
                        gap_m: w.z - ground,
                    });
                }
            }
        }
        Ok(())
    }
}

/// Points on the surface of a shape (its own frame) no farther apart than about `spacing`,
/// and the spacing used.
fn surface_points(shape: &Shape, spacing: f64) -> (Vec<Point3<f64>>, f64) {
    let spacing = spacing.max(1e-4);
    let count = |length: f64| ((length / spacing).ceil() as usize).clamp(1, MAX_POINTS_PER_SIDE);
    let mut points = Vec::new();
    let mut used = 0.0f64;
    let mut divide = |length: f64| {
        let n = count(length);
        used = used.max(length / n as f64);
        (0..=n)
            .map(move |k| -length / 2.0 + length * k as f64 / n as f64)
            .collect::<Vec<_>>()
    };
    match *shape {
        Shape::Box { size } => {
            let xs = divide(size.x);
            let ys = divide(size.y);
            let zs = divide(size.z);
            let (hx, hy, hz) = (size.x / 2.0, size.y / 2.0, size.z / 2.0);
            for &x in &xs {
                for &y in &ys {
                    points.push(Point3::new(x, y, -hz));
                    points.push(Point3::new(x, y, hz));
                }
                for &z in &zs {
                    points.push(Point3::new(x, -hy, z));
                    points.push(Point3::new(x, hy, z));
                }
            }
            for &y in &ys {
                for &z in &zs {
                    points.push(Point3::new(-hx, y, z));
                    points.push(Point3::new(hx, y, z));
                }
            }
        }
        Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
            let zs = divide(length);
            let around = count(std::f64::consts::TAU * radius).max(6);
            used = used.max(std::f64::consts::TAU * radius / around as f64);
            let ring = |z: f64, r: f64, points: &mut Vec<Point3<f64>>| {
                for k in 0..around {
                    let a = k as f64 * std::f64::consts::TAU / around as f64;
                    points.push(Point3::new(r * a.cos(), r * a.sin(), z));
                }
            };
            for &z in &zs {
                ring(z, radius, &mut points);
            }
            let capsule = matches!(shape, Shape::Capsule { .. });
            let layers = count(radius).max(2);
            for end in [-1.0, 1.0] {
                points.push(Point3::new(
                    0.0,
                    0.0,
                    end * (length / 2.0 + if capsule { radius } else { 0.0 }),
                ));
                for k in 1..layers {
                    let f = k as f64 / layers as f64;
                    if capsule {
                        let a = f * std::f64::consts::FRAC_PI_2;
                        ring(
                            end * (length / 2.0 + radius * a.sin()),
                            radius * a.cos(),
                            &mut points,
                        );
                    } else {
                        ring(end * length / 2.0, radius * f, &mut points);
                    }
                }
            }
        }
        Shape::Sphere { radius } => {
            let layers = count(std::f64::consts::PI * radius).max(4);
            used = used.max(std::f64::consts::PI * radius / layers as f64);
            for k in 0..=layers {
                let polar = std::f64::consts::PI * k as f64 / layers as f64;
                let r = radius * polar.sin();
                let z = -radius * polar.cos();
                let around = count(std::f64::consts::TAU * r).max(1);
                for j in 0..around {
                    let a = j as f64 * std::f64::consts::TAU / around as f64;
                    points.push(Point3::new(r * a.cos(), r * a.sin(), z));
                }
            }
        }
    }
    (points, used.max(spacing.min(1e-3)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn surface_points_lie_on_the_shapes() {
        let (pts, s) = surface_points(
            &Shape::Box {
                size: Vector3::new(1.0, 2.0, 0.5),
            },
            0.1,
        );
        assert!(s <= 0.1 + 1e-9);
        assert!(pts.iter().all(|p| {
            let on = (p.x.abs() - 0.5).abs() < 1e-9
                || (p.y.abs() - 1.0).abs() < 1e-9
                || (p.z.abs() - 0.25).abs() < 1e-9;
            on && p.x.abs() <= 0.5 + 1e-9 && p.y.abs() <= 1.0 + 1e-9 && p.z.abs() <= 0.25 + 1e-9
        }));
        let (pts, _) = surface_points(
            &Shape::Cylinder {
                radius: 0.1,
                length: 3.6,
            },
            0.1,
        );
        assert!(
            pts.iter()
                .all(|p| p.z.abs() <= 1.8 + 1e-9 && p.x.hypot(p.y) <= 0.1 + 1e-9)
        );
        assert!(pts.iter().any(|p| (p.z + 1.8).abs() < 1e-9));
    }
}
