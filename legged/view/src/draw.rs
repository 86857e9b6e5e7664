//! [`draw`]: a robot standing on level ground, seen from above (x forward to the right, y left
//! up the picture) and from the side (x to the right, z up), to one scale.
//!
//! Drawn: the outline of every collision shape (the body's in blue, the legs' in orange), each
//! leg's chain of joints in black, the feet's contact circles, the ground in the side view,
//! the support polygon of the standing feet (green) and the conservative one (dark green)
//! from above, the centre of mass (red cross) and each foot's sampled workspace (grey dots).

use nalgebra::{Point2, Point3};
use tca_canvas::{Canvas, Rgb};
use tca_legged_model::{PlacedShape, RobotModel, Shape};
use tca_stability::{conservative_support_polygon, support_polygon};

use crate::error::ViewError;

const WIDTH: u32 = 960;
const MARGIN_PX: f64 = 40.0;
const PANEL_GAP_PX: f64 = 60.0;
const WORKSPACE_DOTS: usize = 600;

const BACKGROUND: Rgb = [255, 255, 255];
const BODY: Rgb = [40, 90, 200];
const LEG_SHAPE: Rgb = [230, 130, 30];
const CHAIN: Rgb = [20, 20, 20];
const FOOT: Rgb = [120, 60, 20];
const GROUND: Rgb = [120, 100, 80];
const SUPPORT: Rgb = [40, 170, 60];
const CONSERVATIVE: Rgb = [10, 90, 30];
const COM: Rgb = [220, 20, 20];
const WORKSPACE: Rgb = [200, 200, 200];
const TEXT: Rgb = [0, 0, 0];

/// Which plane a panel shows.
#[derive(Clone, Copy)]
enum View {
    /// Body x to the right, y up.
    Top,
    /// Body x to the right, z up.
    Side,
}

impl View {
    fn project(self, p: &Point3<f64>) -> Point2<f64> {
        match self {
            View::Top => Point2::new(p.x, p.y),
            View::Side => Point2::new(p.x, p.z),
        }
    }
}

/// Points on the surface of a placed shape, enough that the convex hull of their projection
/// is its silhouette (exact for boxes, to a few percent for round shapes).
fn outline_points(shape: &PlacedShape<'_>) -> Vec<Point3<f64>> {
    let ring = |radius: f64, z: f64| -> Vec<Point3<f64>> {
        (0..24)
            .map(|i| {
                let a = f64::from(i) * std::f64::consts::TAU / 24.0;
                Point3::new(radius * a.cos(), radius * a.sin(), z)
            })
            .collect()
    };
    let local: Vec<Point3<f64>> = match shape.shape {
        Shape::Box { size } => {
            let h = size / 2.0;
            let mut corners = Vec::with_capacity(8);
            for sx in [-1.0, 1.0] {
                for sy in [-1.0, 1.0] {
                    for sz in [-1.0, 1.0] {
                        corners.push(Point3::new(sx * h.x, sy * h.y, sz * h.z));
                    }
                }
            }
            corners
        }
        Shape::Cylinder { radius, length } => {
            let mut p = ring(radius, -length / 2.0);
            p.extend(ring(radius, length / 2.0));
            p
        }
        Shape::Capsule { radius, length } => {
            // The cylinder's end rings, then rings over each end's half ball.
            let mut p = Vec::new();
            for end in [-1.0, 1.0] {
                for k in 0..=3 {
                    let a = f64::from(k) * std::f64::consts::PI / 6.0;
                    p.extend(ring(
                        radius * a.cos(),
                        end * (length / 2.0 + radius * a.sin()),
                    ));
                }
            }
            p
        }
        Shape::Sphere { radius } => {
            let mut p = ring(radius, 0.0);
            for point in ring(radius, 0.0) {
                p.push(Point3::new(point.x, 0.0, point.y));
                p.push(Point3::new(0.0, point.x, point.y));
            }
            p
        }
    };
    local.iter().map(|p| shape.pose * p).collect()
}

/// A panel's mapping from metres to pixels.
struct Frame {
    scale: f64,
    min: Point2<f64>,
    top_px: f64,
    height_px: f64,
}

impl Frame {
    fn px(&self, p: Point2<f64>) -> (f64, f64) {
        (
            MARGIN_PX + (p.x - self.min.x) * self.scale,
            self.top_px + self.height_px - (p.y - self.min.y) * self.scale,
        )
    }
}

fn bounds(points: impl Iterator<Item = Point2<f64>>) -> (Point2<f64>, Point2<f64>) {
    let mut min = Point2::new(f64::INFINITY, f64::INFINITY);
    let mut max = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in points {
        min = min.inf(&p);
        max = max.sup(&p);
    }
    (min, max)
}

fn polygon(canvas: &mut Canvas, frame: &Frame, vertices: &[Point2<f64>], c: Rgb, width: u32) {
    for (i, a) in vertices.iter().enumerate() {
        let b = vertices[(i + 1) % vertices.len()];
        canvas.line(frame.px(*a), frame.px(b), width, c);
    }
}

/// The robot standing on level ground (every joint at 0 or its nearest limit), from above
/// and from the side, as a canvas ready for [`Canvas::write_png`].
pub fn draw(robot: &RobotModel) -> Result<Canvas, ViewError> {
    let posture = robot.neutral_posture();
    let fail = |source| ViewError::Posture {
        robot: robot.name().to_owned(),
        source,
    };
    let shapes = robot.collision_shapes(&posture).map_err(fail)?;
    let feet = robot.foot_positions(&posture).map_err(fail)?;
    let com = robot.centre_of_mass(&posture).map_err(fail)?.centre;
    let ground_z = -robot.neutral_height();
    let leg_links: Vec<&str> = robot
        .legs()
        .iter()
        .flat_map(|l| l.joints().iter().map(|j| j.child_link()))
        .collect();
    let outlines: Vec<(bool, Vec<Point3<f64>>)> = shapes
        .iter()
        .map(|s| (leg_links.contains(&s.link), outline_points(s)))
        .collect();
    let mut chains = Vec::new();
    for (leg, q) in robot.legs().iter().zip(&posture) {
        let mut chain = vec![leg.base_position()];
        chain.extend(
            leg.joint_frames(q)
                .map_err(fail)?
                .iter()
                .map(|f| Point3::from(f.translation.vector)),
        );
        chain.push(leg.foot_position(q).map_err(fail)?);
        chains.push(chain);
    }
    let workspaces: Vec<Vec<Point3<f64>>> = robot
        .legs()
        .iter()
        .map(|l| l.workspace_samples(WORKSPACE_DOTS))
        .collect();

    // One scale for both panels, from everything drawn.
    let everything = || {
        outlines
            .iter()
            .flat_map(|(_, p)| p.iter().copied())
            .chain(chains.iter().flatten().copied())
            .chain(workspaces.iter().flatten().copied())
            .chain(feet.iter().copied())
    };
    let (top_min, top_max) = bounds(everything().map(|p| View::Top.project(&p)));
    let (side_min, mut side_max) = bounds(
        everything()
            .chain(std::iter::once(Point3::new(0.0, 0.0, ground_z)))
            .map(|p| View::Side.project(&p)),
    );
    side_max.y = side_max.y.max(side_min.y + 1e-3);
    let span_x = (top_max.x - top_min.x)
        .max(side_max.x - side_min.x)
        .max(1e-3);
    let scale = (f64::from(WIDTH) - 2.0 * MARGIN_PX) / span_x;
    let top_height = (top_max.y - top_min.y).max(1e-3) * scale;
    let side_height = (side_max.y - side_min.y) * scale;
    let height = (2.0 * MARGIN_PX + top_height + PANEL_GAP_PX + side_height).ceil() as u32;
    let mut canvas = Canvas::new(WIDTH, height, BACKGROUND);
    let top = Frame {
        scale,
        min: Point2::new(top_min.x.min(side_min.x), top_min.y),
        top_px: MARGIN_PX,
        height_px: top_height,
    };
    let side = Frame {
        scale,
        min: Point2::new(top_min.x.min(side_min.x), side_min.y),
        top_px: MARGIN_PX + top_height + PANEL_GAP_PX,
        height_px: side_height,
    };

    for (view, frame) in [(View::Top, &top), (View::Side, &side)] {
        if let View::Top = view {
            for ws in &workspaces {
                for p in ws {
                    let (x, y) = frame.px(view.project(p));
                    canvas.set(x.round() as i64, y.round() as i64, WORKSPACE);
                }
            }
            let ground: Vec<Point2<f64>> = feet.iter().map(|p| view.project(p)).collect();
            polygon(
                &mut canvas,
                frame,
                support_polygon(&ground).vertices(),
                SUPPORT,
                2,
            );
            let conservative = conservative_support_polygon(&ground);
            if !conservative.is_degenerate() {
                polygon(&mut canvas, frame, conservative.vertices(), CONSERVATIVE, 1);
            }
        } else {
            let a = frame.px(Point2::new(frame.min.x, ground_z));
            let b = frame.px(Point2::new(frame.min.x + span_x, ground_z));
            canvas.line(a, b, 2, GROUND);
        }
        for (on_leg, points) in &outlines {
            let projected: Vec<Point2<f64>> = points.iter().map(|p| view.project(p)).collect();
            let hull = support_polygon(&projected);
            let colour = if *on_leg { LEG_SHAPE } else { BODY };
            if hull.is_degenerate() {
                for w in projected.windows(2) {
                    canvas.line(frame.px(w[0]), frame.px(w[1]), 1, colour);
                }
            } else {
                polygon(&mut canvas, frame, hull.vertices(), colour, 1);
            }
        }
        for chain in &chains {
            for w in chain.windows(2) {
                let (a, b) = (view.project(&w[0]), view.project(&w[1]));
                canvas.line(frame.px(a), frame.px(b), 2, CHAIN);
            }
        }
        for (leg, foot) in robot.legs().iter().zip(&feet) {
            let r = (leg.foot_radius() * scale).max(2.0);
            canvas.circle(frame.px(view.project(foot)), r, 2, FOOT);
        }
        canvas.marker(frame.px(view.project(&com)), 5, COM);
    }
    let metres_per_100px = 100.0 / scale;
    canvas.text(
        MARGIN_PX as i64,
        10,
        &format!(
            "{}: FROM ABOVE (X FORWARD TO THE RIGHT, Y LEFT UP)   100 PX = {metres_per_100px:.2} M",
            robot.name().to_uppercase()
        ),
        2,
        TEXT,
    );
    canvas.text(
        MARGIN_PX as i64,
        (side.top_px - 30.0) as i64,
        "FROM THE SIDE (X FORWARD TO THE RIGHT, Z UP), STANDING ON LEVEL GROUND",
        2,
        TEXT,
    );
    Ok(canvas)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_shipped_robot_is_drawn_with_its_parts_in_their_colours() {
        for name in ["ambler", "hexapod", "athlete"] {
            let robot = RobotModel::builtin(name).unwrap();
            let canvas = draw(&robot).unwrap();
            assert_eq!(canvas.width(), WIDTH);
            let mut seen = [false; 5];
            for y in 0..canvas.height() {
                for x in 0..canvas.width() {
                    let c = canvas.pixel(x, y).unwrap();
                    for (i, want) in [BODY, CHAIN, SUPPORT, COM, GROUND].iter().enumerate() {
                        seen[i] |= c == *want;
                    }
                }
            }
            assert_eq!(seen, [true; 5], "{name}: body, legs, support, com, ground");
            assert!(canvas.to_png().unwrap().len() > 1000);
        }
    }

    #[test]
    fn a_box_outline_has_its_eight_corners() {
        let shape = PlacedShape {
            link: "body",
            shape: Shape::Box {
                size: nalgebra::Vector3::new(2.0, 1.0, 0.5),
            },
            pose: nalgebra::Isometry3::translation(1.0, 0.0, 0.0),
        };
        let points = outline_points(&shape);
        assert_eq!(points.len(), 8);
        let (min, max) = bounds(points.iter().map(|p| View::Side.project(p)));
        assert_eq!((min.x, max.x, min.y, max.y), (0.0, 2.0, -0.25, 0.25));
    }
}
