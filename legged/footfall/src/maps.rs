//! The maps of one chosen leg, coloured as the operator reads them:
//!
//! - **red**: the foot cannot be placed there: the ground under the wheel is too steep or
//!   too uneven (its fitted plane's slope and the ground's distance from it), or no joint
//!   positions within the limits put the wheel's centre on the ground there with its
//!   steering axis upright (the given foot orientation), or the leg placed there would
//!   come closer to another part of the robot than their margin (the wheel against its own
//!   shin, a knee against the chassis), or the wheel would leave the map;
//! - **blue**: reachable, but the way-point `waypoint_m` straight above the foot's place
//!   (where a step passes to make up for the limbs' sag) cannot be reached, or not without
//!   the leg breaking a margin to another part of the robot;
//! - **orange**: reachable with its way-point, but the robot would not be stable: with the
//!   foot placed there the centre of mass is closer than `min_margin_m` to the edge of the
//!   chosen polygon (the support polygon of the feet, or the conservative polygon that stays
//!   supported whichever one foot is lifted next), or, while this foot is in the air at the
//!   way-point above the cell, closer than `min_lift_margin_m` to the edge of the other
//!   standing feet's support polygon;
//! - **green**: the foot can be placed.
//!
//! The first rule that fails gives the colour, in that order. Cells cover the disc the leg
//! can reach, centred below its hip. The maps also carry the polygons and margins of the
//! robot as it stands now.
//!
//! [`brute_force_verdict`] applies the same rules to one cell by other means (the ground
//! sampled every centimetre, inverse kinematics from many random starts, polygons and
//! margins from first principles), to check the maps.

use nalgebra::{Point2, Point3, Vector3};
use serde::{Deserialize, Serialize};
use tca_legged_sim::collide::{rest_height, touch_point};
use tca_stability::{Polygon, conservative_support_polygon, stability_margin, support_polygon};

use crate::collision::{CheckerParams, LegChecker, Phase};
use crate::error::FootfallError;
use crate::ground::{GroundRules, fit_footprint, fit_points};
use crate::margins::MarginTable;
use crate::reach::{
    FootGoal, ReachTolerance, place_foot_thoroughly, place_foot_where, upright_axis,
};
use crate::scene::Scene;

/// A cell's colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Colour {
    /// The foot can be placed.
    Green,
    /// It cannot (ground, reach, off the map).
    Red,
    /// It can, but the robot would not be stable.
    Orange,
    /// It can, but the way-point above it cannot be reached.
    Blue,
}

impl Colour {
    /// One letter per colour (`G`, `R`, `O`, `B`), as the maps' rows print them.
    pub fn letter(self) -> char {
        match self {
            Colour::Green => 'G',
            Colour::Red => 'R',
            Colour::Orange => 'O',
            Colour::Blue => 'B',
        }
    }

    /// The colour of a letter.
    pub fn from_letter(c: char) -> Option<Colour> {
        match c {
            'G' => Some(Colour::Green),
            'R' => Some(Colour::Red),
            'O' => Some(Colour::Orange),
            'B' => Some(Colour::Blue),
            _ => None,
        }
    }
}

/// Which polygon judges the robot's stability with the foot placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PolygonKind {
    /// The convex hull of the standing feet.
    Support,
    /// The intersection of the support polygons left by lifting any one standing foot.
    Conservative,
}

/// How the maps are made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapParams {
    /// Cell size, metres.
    pub resolution_m: f64,
    /// The polygon stability is judged against with the foot placed.
    pub polygon: PolygonKind,
    /// Least distance of the centre of mass from that polygon's edge, metres.
    pub min_margin_m: f64,
    /// Least distance of the centre of mass from the edge of the other feet's support
    /// polygon while this foot is in the air, metres.
    pub min_lift_margin_m: f64,
    /// Height of the way-point above the foot's place, metres.
    pub waypoint_m: f64,
    /// What ground a foot may stand on.
    pub ground: GroundRules,
    /// How close a placement must come.
    pub reach: ReachTolerance,
    /// The margins between parts of the robot (and from the terrain, for the planners).
    pub margins: MarginTable,
}

impl Default for MapParams {
    /// 5 cm cells; the conservative polygon with 1 m of margin; 0.3 m while a foot is in
    /// the air; way-points 20 cm up; the default ground rules and reach tolerance.
    fn default() -> Self {
        Self {
            resolution_m: 0.05,
            polygon: PolygonKind::Conservative,
            min_margin_m: 1.0,
            min_lift_margin_m: 0.3,
            waypoint_m: 0.20,
            ground: GroundRules::default(),
            reach: ReachTolerance::default(),
            margins: MarginTable::default(),
        }
    }
}

impl MapParams {
    /// Refuses values that make no sense, naming them.
    pub fn check(&self) -> Result<(), FootfallError> {
        let positive = [
            ("resolution_m", self.resolution_m),
            ("max slope", self.ground.max_slope_rad),
            ("max roughness", self.ground.max_roughness_m),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(FootfallError::Params(format!(
                    "{name} is {v}; give a positive number"
                )));
            }
        }
        let finite = [
            ("min_margin_m", self.min_margin_m),
            ("min_lift_margin_m", self.min_lift_margin_m),
            ("waypoint_m", self.waypoint_m),
        ];
        for (name, v) in finite {
            if !v.is_finite() {
                return Err(FootfallError::Params(format!(
                    "{name} is {v}; give a finite number"
                )));
            }
        }
        if self.resolution_m < 0.005 {
            return Err(FootfallError::Params(format!(
                "a resolution of {} m makes too many cells; give 5 mm or more",
                self.resolution_m
            )));
        }
        Ok(())
    }
}

/// What the rules say of one place for the foot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    /// The colour.
    pub colour: Colour,
    /// Why it is not green.
    pub reason: Option<String>,
    /// The wheel's centre resting there, world frame.
    pub foot: Option<[f64; 3]>,
    /// Joint positions placing it there.
    pub joints: Option<Vec<f64>>,
    /// Joint positions placing it at the way-point above.
    pub waypoint: Option<Vec<f64>>,
    /// Stability margin with the foot placed (against the chosen polygon), metres.
    pub margin_m: Option<f64>,
    /// Stability margin while the foot is in the air at the way-point, metres.
    pub lift_margin_m: Option<f64>,
}

impl Verdict {
    fn red(reason: String) -> Verdict {
        Verdict {
            colour: Colour::Red,
            reason: Some(reason),
            foot: None,
            joints: None,
            waypoint: None,
            margin_m: None,
            lift_margin_m: None,
        }
    }
}

/// Applies the colour rules to places for one leg's foot.
#[derive(Debug)]
pub struct Evaluator<'a> {
    scene: &'a Scene,
    leg: usize,
    params: MapParams,
    /// Where the other standing feet touch, world XY.
    others: Vec<Point2<f64>>,
    axis: Option<nalgebra::Unit<Vector3<f64>>>,
    /// The robot's parts against each other (no terrain).
    parts: LegChecker,
}

impl<'a> Evaluator<'a> {
    /// The rules for leg `leg` of `scene`; the leg must be standing.
    pub fn new(scene: &'a Scene, leg: usize, params: &MapParams) -> Result<Self, FootfallError> {
        scene.check()?;
        params.check()?;
        let l = scene
            .model
            .leg_at(leg)
            .map_err(|e| FootfallError::Scene(e.to_string()))?;
        if !scene.stance[leg] {
            return Err(FootfallError::NotStanding {
                leg: l.name().to_owned(),
            });
        }
        let touches = scene.touch_points();
        let others = touches
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != leg && scene.stance[*i])
            .map(|(_, p)| Point2::new(p.x, p.y))
            .collect();
        let down = nalgebra::Unit::new_normalize(scene.body.rotation.inverse() * -Vector3::z());
        let parts = robot_checker(scene, leg, params)?;
        Ok(Evaluator {
            scene,
            leg,
            params: params.clone(),
            others,
            axis: upright_axis(l, down),
            parts,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &MapParams {
        &self.params
    }

    /// Where the other standing feet touch the ground, world XY.
    pub fn other_feet(&self) -> &[Point2<f64>] {
        &self.others
    }

    /// The foot's goal (body frame) for a wheel centre in the world.
    pub fn goal(&self, centre_world: &Point3<f64>) -> FootGoal {
        FootGoal {
            centre: self.scene.body.inverse() * centre_world,
            axis: self.axis,
        }
    }

    /// The joints placing the wheel's centre at `centre_world` with the foot upright and the
    /// leg clear of the rest of the robot, from `warm` (when given), the leg's current
    /// joints and its neutral ones.
    pub fn place(&self, centre_world: &Point3<f64>, warm: Option<&[f64]>) -> Option<Vec<f64>> {
        let l = &self.scene.model.legs()[self.leg];
        let current = &self.scene.posture[self.leg];
        let mut neutral = l.neutral();
        if let (Some(n), Some(c)) = (neutral.last_mut(), current.last()) {
            *n = *c;
        }
        let mut starts: Vec<&[f64]> = Vec::with_capacity(3);
        if let Some(w) = warm {
            starts.push(w);
        }
        starts.push(current);
        starts.push(&neutral);
        place_foot_where(
            l,
            &self.goal(centre_world),
            &starts,
            &self.params.reach,
            |q| self.parts.check(q, Phase::Free).is_none(),
        )
    }

    /// Whether joints `q` keep the leg clear of the rest of the robot.
    pub fn clear_of_robot(&self, q: &[f64]) -> bool {
        self.parts.check(q, Phase::Free).is_none()
    }

    /// The margin with the foot placed at `touch` and the leg at `q`.
    pub fn placed_margin(&self, touch: Point2<f64>, q: &[f64]) -> f64 {
        let mut feet = self.others.clone();
        feet.push(touch);
        let com = self.scene.centre_of_mass_with(self.leg, q);
        let polygon = match self.params.polygon {
            PolygonKind::Support => support_polygon(&feet),
            PolygonKind::Conservative => conservative_support_polygon(&feet),
        };
        stability_margin(&polygon, com)
    }

    /// The margin with the foot in the air and the leg at `q`.
    pub fn lifted_margin(&self, q: &[f64]) -> f64 {
        let com = self.scene.centre_of_mass_with(self.leg, q);
        stability_margin(&support_polygon(&self.others), com)
    }

    /// The rules applied to the foot's place at world `xy`, starting the inverse
    /// kinematics from `warm` when given.
    pub fn evaluate(&self, xy: Point2<f64>, warm: Option<&[f64]>) -> Verdict {
        let l = &self.scene.model.legs()[self.leg];
        let r = l.foot_radius();
        let terrain = &self.scene.terrain;
        let Some(fit) = fit_footprint(terrain, xy, r) else {
            return Verdict::red("the wheel would leave the map".into());
        };
        if let Some(why) = fit.rejection(&self.params.ground) {
            return Verdict::red(why);
        }
        let centre = Point3::new(xy.x, xy.y, rest_height(terrain, xy, r));
        let Some(q) = self.place(&centre, warm) else {
            return Verdict::red(
                "the leg cannot reach it with the wheel upright and clear of the robot".into(),
            );
        };
        let touch = touch_point(terrain, xy, r);
        let above = centre + Vector3::z() * self.params.waypoint_m;
        let waypoint = self.place(&above, Some(&q));
        let margin = self.placed_margin(Point2::new(touch.x, touch.y), &q);
        let lift = self.lifted_margin(waypoint.as_deref().unwrap_or(&q));
        decide(
            &self.params,
            [centre.x, centre.y, centre.z],
            q,
            waypoint,
            margin,
            lift,
        )
    }
}

/// The checker of the robot's own parts (no terrain) for leg `leg`.
fn robot_checker(
    scene: &Scene,
    leg: usize,
    params: &MapParams,
) -> Result<LegChecker, FootfallError> {
    LegChecker::new(
        std::sync::Arc::new(scene.clone()),
        leg,
        &CheckerParams {
            margins: params.margins.clone(),
            resolution_rad: 0.01,
            raise_m: 0.0,
            terrain: false,
        },
    )
}

/// The colour from what was found at a reachable place.
fn decide(
    params: &MapParams,
    foot: [f64; 3],
    q: Vec<f64>,
    waypoint: Option<Vec<f64>>,
    margin: f64,
    lift: f64,
) -> Verdict {
    let (colour, reason) = if waypoint.is_none() {
        (
            Colour::Blue,
            Some(format!(
                "the way-point {:.0} cm above it cannot be reached (or not clear of the robot)",
                params.waypoint_m * 100.0
            )),
        )
    } else if margin.is_nan() || margin < params.min_margin_m {
        (
            Colour::Orange,
            Some(format!(
                "with the foot there the centre of mass would be {margin:.2} m inside the {} \
                 polygon (at least {:.2} m wanted)",
                match params.polygon {
                    PolygonKind::Support => "support",
                    PolygonKind::Conservative => "conservative",
                },
                params.min_margin_m
            )),
        )
    } else if lift.is_nan() || lift < params.min_lift_margin_m {
        (
            Colour::Orange,
            Some(format!(
                "with this foot in the air the centre of mass would be {lift:.2} m inside the \
                 other feet's polygon (at least {:.2} m wanted)",
                params.min_lift_margin_m
            )),
        )
    } else {
        (Colour::Green, None)
    };
    Verdict {
        colour,
        reason,
        foot: Some(foot),
        joints: Some(q),
        waypoint,
        margin_m: Some(margin),
        lift_margin_m: Some(lift),
    }
}

/// Cells of each colour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ColourCounts {
    /// Green cells.
    pub green: usize,
    /// Red cells.
    pub red: usize,
    /// Orange cells.
    pub orange: usize,
    /// Blue cells.
    pub blue: usize,
}

impl ColourCounts {
    fn add(&mut self, c: Colour) {
        match c {
            Colour::Green => self.green += 1,
            Colour::Red => self.red += 1,
            Colour::Orange => self.orange += 1,
            Colour::Blue => self.blue += 1,
        }
    }

    /// All cells.
    pub fn total(&self) -> usize {
        self.green + self.red + self.orange + self.blue
    }
}

/// The robot's stability as it stands.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StabilityNow {
    /// The centre of mass, world frame.
    pub com: [f64; 3],
    /// The standing feet's support polygon (world XY, counter-clockwise).
    pub support: Vec<[f64; 2]>,
    /// The conservative support polygon.
    pub conservative: Vec<[f64; 2]>,
    /// The static stability margin against the support polygon, metres.
    pub support_margin_m: f64,
    /// Against the conservative polygon, metres.
    pub conservative_margin_m: f64,
    /// The other feet's support polygon, which holds the robot while the chosen leg is in
    /// the air.
    pub lifted_support: Vec<[f64; 2]>,
    /// The margin against it with the chosen leg lifted where it is, metres.
    pub lifted_margin_m: f64,
}

fn vertices(p: &Polygon) -> Vec<[f64; 2]> {
    p.vertices().iter().map(|v| [v.x, v.y]).collect()
}

/// The maps of one leg.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LegMaps {
    /// The leg.
    pub leg: String,
    /// The centre of cell (0, 0), world XY.
    pub origin: [f64; 2],
    /// Cell size, metres.
    pub resolution_m: f64,
    /// Columns (east).
    pub nx: usize,
    /// Rows (north).
    pub ny: usize,
    /// The colours, row by row from the south, one letter per cell (`G`, `R`, `O`, `B`, or
    /// `.` outside the leg's reach).
    pub rows: Vec<String>,
    /// Cells of each colour.
    pub counts: ColourCounts,
    /// The robot's stability as it stands.
    pub now: StabilityNow,
    /// The parameters the maps were made with.
    pub params: MapParams,
}

impl LegMaps {
    /// The colour of cell (ix, iy), or `None` outside the reach or the grid.
    pub fn colour(&self, ix: usize, iy: usize) -> Option<Colour> {
        self.rows
            .get(iy)
            .and_then(|r| r.as_bytes().get(ix))
            .and_then(|b| Colour::from_letter(*b as char))
    }

    /// The centre of cell (ix, iy), world XY.
    pub fn centre(&self, ix: usize, iy: usize) -> Point2<f64> {
        Point2::new(
            self.origin[0] + ix as f64 * self.resolution_m,
            self.origin[1] + iy as f64 * self.resolution_m,
        )
    }

    /// The cell holding world XY `p`.
    pub fn cell_of(&self, p: Point2<f64>) -> Option<(usize, usize)> {
        let gx = ((p.x - self.origin[0]) / self.resolution_m).round();
        let gy = ((p.y - self.origin[1]) / self.resolution_m).round();
        (gx >= 0.0 && gy >= 0.0 && (gx as usize) < self.nx && (gy as usize) < self.ny)
            .then_some((gx as usize, gy as usize))
    }

    /// Every cell of a colour, by index.
    pub fn cells_of(&self, colour: Colour) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for iy in 0..self.ny {
            for ix in 0..self.nx {
                if self.colour(ix, iy) == Some(colour) {
                    out.push((ix, iy));
                }
            }
        }
        out
    }
}

/// Builds the maps of leg `leg` of `scene`.
pub fn leg_maps(scene: &Scene, leg: usize, params: &MapParams) -> Result<LegMaps, FootfallError> {
    let eval = Evaluator::new(scene, leg, params)?;
    let l = &scene.model.legs()[leg];
    let base = scene.body * l.base_position();
    let radius = l.reach_bound() + params.resolution_m;
    let res = params.resolution_m;
    let n = (2.0 * radius / res).ceil() as usize + 1;
    let origin = Point2::new((base.x - radius) / res, (base.y - radius) / res);
    // Cells on the terrain's lattice when it shares the resolution.
    let origin = Point2::new(origin.x.round() * res, origin.y.round() * res);
    let mut rows = vec![vec![b'.'; n]; n];
    let mut counts = ColourCounts::default();
    for (iy, row) in rows.iter_mut().enumerate() {
        let mut warm: Option<Vec<f64>> = None;
        // Every other row right to left, so that each cell starts from its neighbour's
        // solution.
        let order: Vec<usize> = if iy % 2 == 0 {
            (0..n).collect()
        } else {
            (0..n).rev().collect()
        };
        for ix in order {
            let p = Point2::new(origin.x + ix as f64 * res, origin.y + iy as f64 * res);
            if (p - Point2::new(base.x, base.y)).norm() > radius {
                continue;
            }
            let v = eval.evaluate(p, warm.as_deref());
            if v.joints.is_some() {
                warm = v.joints.clone();
            }
            row[ix] = v.colour.letter() as u8;
            counts.add(v.colour);
        }
    }
    let touches = scene.touch_points();
    let standing: Vec<Point2<f64>> = touches
        .iter()
        .zip(&scene.stance)
        .filter(|(_, s)| **s)
        .map(|(p, _)| Point2::new(p.x, p.y))
        .collect();
    let com = scene.centre_of_mass_with(leg, &scene.posture[leg]);
    let support = support_polygon(&standing);
    let conservative = conservative_support_polygon(&standing);
    let lifted = support_polygon(eval.other_feet());
    let now = StabilityNow {
        com: [com.x, com.y, com.z],
        support_margin_m: stability_margin(&support, com),
        conservative_margin_m: stability_margin(&conservative, com),
        lifted_margin_m: stability_margin(&lifted, com),
        support: vertices(&support),
        conservative: vertices(&conservative),
        lifted_support: vertices(&lifted),
    };
    Ok(LegMaps {
        leg: l.name().to_owned(),
        origin: [origin.x, origin.y],
        resolution_m: res,
        nx: n,
        ny: n,
        rows: rows
            .into_iter()
            .map(|r| String::from_utf8(r).unwrap_or_default())
            .collect(),
        counts,
        now,
        params: params.clone(),
    })
}

/// The same rules as [`Evaluator::evaluate`], applied by other means: the ground's plane
/// fitted to the surface sampled every centimetre under the wheel; inverse kinematics from
/// the current and neutral joints and then 24 random starts, taking the first solution clear
/// of the robot's parts; the support polygon's margin
/// as the least distance to the edges of the hull found by testing every pair of feet, and
/// the conservative margin as the least of those over every foot left out.
pub fn brute_force_verdict(
    scene: &Scene,
    leg: usize,
    params: &MapParams,
    xy: Point2<f64>,
) -> Colour {
    let l = &scene.model.legs()[leg];
    let r = l.foot_radius();
    let terrain = &scene.terrain;
    if !crate::ground::disc_inside(terrain, xy, r) {
        return Colour::Red;
    }
    let mut pts = Vec::new();
    let step = 0.01;
    let k = (r / step).ceil() as i64;
    for i in -k..=k {
        for j in -k..=k {
            let (dx, dy) = (i as f64 * step, j as f64 * step);
            if dx * dx + dy * dy <= r * r {
                pts.push(Vector3::new(
                    dx,
                    dy,
                    terrain.height_at(xy.x + dx, xy.y + dy),
                ));
            }
        }
    }
    if !fit_points(&pts).acceptable(&params.ground) {
        return Colour::Red;
    }
    let down = nalgebra::Unit::new_normalize(scene.body.rotation.inverse() * -Vector3::z());
    let axis = upright_axis(l, down);
    let goal = |c: Point3<f64>| FootGoal {
        centre: scene.body.inverse() * c,
        axis,
    };
    let current = scene.posture[leg].clone();
    let mut neutral = l.neutral();
    if let (Some(n), Some(c)) = (neutral.last_mut(), current.last()) {
        *n = *c;
    }
    let centre = Point3::new(xy.x, xy.y, rest_height(terrain, xy, r));
    let starts: [&[f64]; 2] = [&current, &neutral];
    let seed = (xy.x * 1000.0) as u64 ^ ((xy.y * 1000.0) as u64).rotate_left(32);
    let Ok(parts) = robot_checker(scene, leg, params) else {
        return Colour::Red;
    };
    let clear = |q: &[f64]| parts.check(q, Phase::Free).is_none();
    let Some(q) = place_foot_thoroughly(l, &goal(centre), &starts, 24, seed, &params.reach, clear)
    else {
        return Colour::Red;
    };
    let above = centre + Vector3::z() * params.waypoint_m;
    let waypoint =
        place_foot_thoroughly(l, &goal(above), &[&q], 24, seed ^ 1, &params.reach, clear);
    let touches = scene.touch_points();
    let mut feet: Vec<Point2<f64>> = touches
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != leg && scene.stance[*i])
        .map(|(_, p)| Point2::new(p.x, p.y))
        .collect();
    let lifted_feet = feet.clone();
    let touch = touch_point(terrain, xy, r);
    feet.push(Point2::new(touch.x, touch.y));
    let com = |q: &[f64]| {
        let c = scene.centre_of_mass_with(leg, q);
        Point2::new(c.x, c.y)
    };
    let margin = match params.polygon {
        PolygonKind::Support => hull_margin(&feet, com(&q)),
        PolygonKind::Conservative => (0..feet.len())
            .map(|skip| {
                let rest: Vec<Point2<f64>> = feet
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != skip)
                    .map(|(_, p)| *p)
                    .collect();
                hull_margin(&rest, com(&q))
            })
            .fold(f64::INFINITY, f64::min),
    };
    let lift = hull_margin(&lifted_feet, com(waypoint.as_deref().unwrap_or(&q)));
    decide(
        params,
        [centre.x, centre.y, centre.z],
        q,
        waypoint,
        margin,
        lift,
    )
    .colour
}

/// The signed distance of `p` from the edge of the convex hull of `points`: positive
/// inside (the least distance to a hull edge's line), negative outside; the hull's edges
/// found by testing every ordered pair of points for all others on its left.
fn hull_margin(points: &[Point2<f64>], p: Point2<f64>) -> f64 {
    let mut inside = f64::INFINITY;
    let mut any = false;
    for (i, a) in points.iter().enumerate() {
        for (j, b) in points.iter().enumerate() {
            if i == j || (b - a).norm() < 1e-12 {
                continue;
            }
            let d = b - a;
            let left = |q: &Point2<f64>| d.x * (q.y - a.y) - d.y * (q.x - a.x);
            if points.iter().all(|q| left(q) >= -1e-12) {
                any = true;
                let dist = left(&p) / d.norm();
                inside = inside.min(dist);
            }
        }
    }
    if any { inside } else { f64::NEG_INFINITY }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_margin_of_a_square() {
        let sq = [
            Point2::new(0.0, 0.0),
            Point2::new(2.0, 0.0),
            Point2::new(2.0, 2.0),
            Point2::new(0.0, 2.0),
            Point2::new(1.0, 1.0),
        ];
        assert!((hull_margin(&sq, Point2::new(1.0, 1.0)) - 1.0).abs() < 1e-12);
        assert!((hull_margin(&sq, Point2::new(0.5, 1.0)) - 0.5).abs() < 1e-12);
        assert!(hull_margin(&sq, Point2::new(3.0, 1.0)) < 0.0);
        assert_eq!(
            hull_margin(&sq[..1], Point2::new(0.0, 0.0)),
            f64::NEG_INFINITY
        );
    }

    #[test]
    fn letters_round_trip() {
        for c in [Colour::Green, Colour::Red, Colour::Orange, Colour::Blue] {
            assert_eq!(Colour::from_letter(c.letter()), Some(c));
        }
        assert_eq!(Colour::from_letter('.'), None);
    }
}
