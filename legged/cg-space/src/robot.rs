//! What CG-space needs of a robot: each leg's range (where in the body's plane its foot can
//! go) with its reach (how far down and up it goes there), the inverse height map of the
//! under-carriage, and these tabulated for every heading bin on the CG grid.

use std::collections::HashSet;
use std::f64::consts::TAU;
use std::sync::Arc;

use nalgebra::{Point2, Vector2};
use tca_legged_model::{RobotModel, Shape};

use crate::error::CgError;

/// Joint samples per leg for its range map.
const RANGE_SAMPLES: usize = 16_384;

/// A map over the body's (x, y) plane in square bins: per bin an interval of heights
/// (body frame z, metres), `lo > hi` where the bin holds nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyMap {
    origin: Point2<f64>,
    bin_m: f64,
    nx: usize,
    ny: usize,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl BodyMap {
    /// A map covering `min..max`. Bin edges lie half a bin off the multiples of `bin_m`, so
    /// that points on those multiples (the CG grid's cell centres at heading 0) fall in the
    /// middle of a bin: a point and its mirror image land in mirrored bins.
    fn covering(min: Point2<f64>, max: Point2<f64>, bin_m: f64) -> Self {
        let snap = |v: f64| ((v / bin_m).floor() - 1.5) * bin_m;
        let origin = Point2::new(snap(min.x), snap(min.y));
        let nx = ((max.x - origin.x) / bin_m).ceil().max(1.0) as usize + 2;
        let ny = ((max.y - origin.y) / bin_m).ceil().max(1.0) as usize + 2;
        BodyMap {
            origin,
            bin_m,
            nx,
            ny,
            lo: vec![f64::INFINITY; nx * ny],
            hi: vec![f64::NEG_INFINITY; nx * ny],
        }
    }

    fn index(&self, p: Point2<f64>) -> Option<usize> {
        let fx = ((p.x - self.origin.x) / self.bin_m).floor();
        let fy = ((p.y - self.origin.y) / self.bin_m).floor();
        (fx >= 0.0 && fy >= 0.0 && (fx as usize) < self.nx && (fy as usize) < self.ny)
            .then(|| fy as usize * self.nx + fx as usize)
    }

    fn add(&mut self, p: Point2<f64>, z: f64) {
        if let Some(i) = self.index(p) {
            self.lo[i] = self.lo[i].min(z);
            self.hi[i] = self.hi[i].max(z);
        }
    }

    /// Keeps only the bins whose eight neighbours hold something too: a foot cell's centre
    /// in a kept bin is then inside the sampled workspace, not on its ragged edge.
    fn erode(&mut self) {
        let filled = |m: &BodyMap, x: usize, y: usize| {
            let i = y * m.nx + x;
            m.lo[i] <= m.hi[i]
        };
        let mut keep = vec![false; self.nx * self.ny];
        for y in 1..self.ny.saturating_sub(1) {
            for x in 1..self.nx.saturating_sub(1) {
                keep[y * self.nx + x] =
                    (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| filled(self, xx, yy)));
            }
        }
        for (i, k) in keep.iter().enumerate() {
            if !k {
                self.lo[i] = f64::INFINITY;
                self.hi[i] = f64::NEG_INFINITY;
            }
        }
    }

    /// The height interval at a body-frame point, if its bin holds anything.
    pub fn at(&self, p: Point2<f64>) -> Option<(f64, f64)> {
        let i = self.index(p)?;
        (self.lo[i] <= self.hi[i]).then(|| (self.lo[i], self.hi[i]))
    }

    /// The largest distance from the body origin to a bin that holds anything, metres.
    fn radius(&self) -> f64 {
        let mut r: f64 = 0.0;
        for iy in 0..self.ny {
            for ix in 0..self.nx {
                let i = iy * self.nx + ix;
                if self.lo[i] <= self.hi[i] {
                    for (cx, cy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                        let p = self.origin
                            + Vector2::new(
                                (ix as f64 + cx) * self.bin_m,
                                (iy as f64 + cy) * self.bin_m,
                            );
                        r = r.max(p.coords.norm());
                    }
                }
            }
        }
        r
    }
}

/// One cell of a leg's range on the CG grid for one heading bin: the foot cell's offset from
/// the CG cell and the heights (body frame, metres) the foot's contact centre can take
/// there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeCell {
    /// Columns east of the CG cell.
    pub di: i32,
    /// Rows north of the CG cell.
    pub dj: i32,
    /// Lowest contact-centre height below the body origin the foot reaches (body z).
    pub z_lo: f64,
    /// Highest contact-centre height (body z).
    pub z_hi: f64,
    /// The quadrant about the CG (0 front-left, 1 rear-left, 2 rear-right, 3 front-right),
    /// or 4 for a cell whose centre is within half a cell of an axis through the CG.
    pub quadrant: u8,
}

/// One cell of the under-carriage on the CG grid for one heading bin: its offset from the
/// CG cell and its depth below the body origin, metres (positive down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnderCell {
    /// Columns east of the CG cell.
    pub di: i32,
    /// Rows north of the CG cell.
    pub dj: i32,
    /// Depth of the under-carriage's lowest point over this cell below the body origin.
    pub depth: f64,
}

/// The ranges and under-carriage for one heading bin.
#[derive(Debug, Clone, PartialEq)]
pub struct HeadingTable {
    /// The heading, radians.
    pub theta: f64,
    /// Per leg, its range cells.
    pub legs: Vec<Vec<RangeCell>>,
    /// The under-carriage's cells.
    pub under: Vec<UnderCell>,
}

/// How a robot's CG-space is laid out; the defaults follow the paper.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CgParams {
    /// Side of a CG cell, metres; `None`: the smallest foot's footprint (its diameter), at
    /// least the terrain's resolution.
    pub cell_m: Option<f64>,
    /// Heading bins; `None`: 1 for a radially symmetric robot, otherwise 8.
    pub theta_bins: Option<u16>,
    /// The steepest ground a foot keeps traction on, radians.
    pub traction_slope_rad: f64,
    /// Clearance kept between the under-carriage and the ground, metres.
    pub clearance_m: f64,
    /// Least distance of the CG from the edge of the support polygon in the foot-level
    /// search, metres; `None`: a fifth of a cell.
    pub stability_margin_m: Option<f64>,
    /// Leave out of each leg's range the bins on the edge of its sampled workspace (a bin
    /// whose neighbours are not all reached), so that every foot cell in range can be
    /// reached at its centre.
    pub conservative_ranges: bool,
    /// Room the foot-level search keeps between the links of different legs (each link's
    /// capsules widened by this), metres; `None`: a thirtieth of a cell.
    pub leg_clearance_m: Option<f64>,
    /// How far above the higher of its two ends a swinging foot must be able to rise,
    /// metres; `None`: a third of a cell.
    pub swing_rise_m: Option<f64>,
}

impl Default for CgParams {
    fn default() -> Self {
        CgParams {
            cell_m: None,
            theta_bins: None,
            traction_slope_rad: 30f64.to_radians(),
            clearance_m: 0.05,
            stability_margin_m: None,
            conservative_ranges: true,
            leg_clearance_m: None,
            swing_rise_m: None,
        }
    }
}

/// A robot as CG-space sees it, tabulated for one CG cell size.
#[derive(Debug, Clone)]
pub struct CgRobot {
    /// The robot itself: the foot-level search checks its moves on its legs' kinematics,
    /// links and masses.
    pub model: Arc<RobotModel>,
    /// The robot's name.
    pub name: String,
    /// Leg names, in the model's order.
    pub leg_names: Vec<String>,
    /// Each foot's contact radius, metres.
    pub foot_radius: Vec<f64>,
    /// The centre of mass in the body frame (x, y) in the neutral posture, metres.
    pub com: Point2<f64>,
    /// Side of a CG cell, metres.
    pub cell_m: f64,
    /// One table per heading bin.
    pub headings: Vec<HeadingTable>,
    /// Each leg's range map in the body frame (bins of half a cell).
    pub ranges: Vec<BodyMap>,
    /// The under-carriage's depth map in the body frame: the interval's low end is the
    /// lowest body z of the under-carriage over the bin.
    pub under: BodyMap,
    /// The parameters used.
    pub params: CgParams,
    /// The stability margin used by the foot-level search, metres.
    pub stability_margin_m: f64,
    /// Room kept between the links of different legs, metres.
    pub leg_clearance_m: f64,
    /// How far a swinging foot must be able to rise above its ends, metres.
    pub swing_rise_m: f64,
}

impl CgRobot {
    /// Tabulates a robot for a terrain of resolution `terrain_res_m`.
    pub fn new(model: &RobotModel, terrain_res_m: f64, params: CgParams) -> Result<Self, CgError> {
        if !(params.traction_slope_rad > 0.0 && params.traction_slope_rad < TAU / 4.0) {
            return Err(CgError::BadParameter {
                what: "the traction slope limit",
                value: params.traction_slope_rad,
                hint: "give an angle between 0 and π/2 radians",
            });
        }
        if !(params.clearance_m >= 0.0 && params.clearance_m.is_finite()) {
            return Err(CgError::BadParameter {
                what: "the under-carriage clearance",
                value: params.clearance_m,
                hint: "give a distance of 0 m or more",
            });
        }
        let legs = model.legs();
        if legs.len() < 3 {
            return Err(CgError::Robot {
                robot: model.name().to_string(),
                reason: format!("it has {} legs; standing needs at least three", legs.len()),
            });
        }
        let foot_radius: Vec<f64> = legs.iter().map(|l| l.foot_radius()).collect();
        let smallest = foot_radius.iter().copied().fold(f64::INFINITY, f64::min);
        let cell_m = params
            .cell_m
            .unwrap_or((2.0 * smallest).max(terrain_res_m))
            .max(1e-3);
        if !cell_m.is_finite() {
            return Err(CgError::BadParameter {
                what: "the CG cell size",
                value: cell_m,
                hint: "give a positive size in metres",
            });
        }
        let bin = cell_m / 2.0;
        let mut ranges = Vec::with_capacity(legs.len());
        for leg in legs {
            let points = leg.workspace_samples(RANGE_SAMPLES);
            let (mut min, mut max) = (
                Point2::new(f64::INFINITY, f64::INFINITY),
                Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
            );
            for p in &points {
                min = min.inf(&Point2::new(p.x, p.y));
                max = max.sup(&Point2::new(p.x, p.y));
            }
            let mut map = BodyMap::covering(min, max, bin);
            for p in &points {
                map.add(Point2::new(p.x, p.y), p.z);
            }
            if params.conservative_ranges {
                map.erode();
            }
            ranges.push(map);
        }
        let posture = model.neutral_posture();
        let com3 = model.centre_of_mass(&posture).map_err(|e| CgError::Robot {
            robot: model.name().to_string(),
            reason: e.to_string(),
        })?;
        let com = Point2::new(com3.centre.x, com3.centre.y);
        let shapes = model
            .collision_shapes(&posture)
            .map_err(|e| CgError::Robot {
                robot: model.name().to_string(),
                reason: e.to_string(),
            })?;
        let body_links: HashSet<&str> = model
            .links()
            .iter()
            .filter(|l| l.leg().is_none())
            .map(|l| l.name())
            .collect();
        let mut footprints = Vec::new();
        for s in shapes.iter().filter(|s| body_links.contains(s.link)) {
            let c = Point2::new(s.pose.translation.x, s.pose.translation.y);
            let half = match s.shape {
                Shape::Box { size } => {
                    let r = s.pose.rotation.to_rotation_matrix();
                    let m = r.matrix();
                    let hx = (m[(0, 0)] * size.x).abs()
                        + (m[(0, 1)] * size.y).abs()
                        + (m[(0, 2)] * size.z).abs();
                    let hy = (m[(1, 0)] * size.x).abs()
                        + (m[(1, 1)] * size.y).abs()
                        + (m[(1, 2)] * size.z).abs();
                    Vector2::new(hx / 2.0, hy / 2.0)
                }
                other => Vector2::new(other.bounding_radius(), other.bounding_radius()),
            };
            let round = !matches!(s.shape, Shape::Box { .. });
            footprints.push((c, half, round, s.lowest_z()));
        }
        if footprints.is_empty() {
            return Err(CgError::Robot {
                robot: model.name().to_string(),
                reason: "its body has no collision shape, so its under-carriage is unknown; give the body link a <collision>".into(),
            });
        }
        let (mut min, mut max) = (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for (c, h, _, _) in &footprints {
            min = min.inf(&(c - h));
            max = max.sup(&(c + h));
        }
        let mut under = BodyMap::covering(min, max, bin);
        let steps = ((max.x - min.x).max(max.y - min.y) / bin * 2.0).ceil() as usize + 1;
        for (c, h, round, z) in &footprints {
            for i in 0..=steps {
                for j in 0..=steps {
                    let p = Point2::new(
                        c.x - h.x + 2.0 * h.x * i as f64 / steps as f64,
                        c.y - h.y + 2.0 * h.y * j as f64 / steps as f64,
                    );
                    if *round && (p - c).norm() > h.x {
                        continue;
                    }
                    under.add(p, *z);
                }
            }
        }
        let stability_margin_m = params.stability_margin_m.unwrap_or(cell_m / 5.0);
        let leg_clearance_m = params.leg_clearance_m.unwrap_or(cell_m / 30.0).max(0.0);
        let swing_rise_m = params.swing_rise_m.unwrap_or(cell_m / 3.0).max(0.0);
        let mut robot = CgRobot {
            model: Arc::new(model.clone()),
            name: model.name().to_string(),
            leg_names: legs.iter().map(|l| l.name().to_string()).collect(),
            foot_radius,
            com,
            cell_m,
            headings: Vec::new(),
            ranges,
            under,
            params: params.clone(),
            stability_margin_m,
            leg_clearance_m,
            swing_rise_m,
        };
        let bins = match params.theta_bins {
            Some(0) => {
                return Err(CgError::BadParameter {
                    what: "the number of heading bins",
                    value: 0.0,
                    hint: "give 1 (no turning) or at least 8",
                });
            }
            Some(b) => b,
            None if robot.radially_symmetric() => 1,
            None => 8,
        };
        robot.headings = (0..bins)
            .map(|b| robot.table(f64::from(b) * TAU / f64::from(bins)))
            .collect();
        Ok(robot)
    }

    /// The number of heading bins.
    pub fn theta_bins(&self) -> u16 {
        self.headings.len() as u16
    }

    /// The number of legs.
    pub fn leg_count(&self) -> usize {
        self.leg_names.len()
    }

    /// Tabulates the ranges and under-carriage on the CG grid at a heading.
    pub fn table(&self, theta: f64) -> HeadingTable {
        let (s, c) = theta.sin_cos();
        let to_body = |dx: f64, dy: f64| Point2::new(c * dx + s * dy, -s * dx + c * dy);
        let cell = self.cell_m;
        let mut legs = Vec::with_capacity(self.ranges.len());
        for map in &self.ranges {
            let n = (map.radius() / cell).ceil() as i32 + 1;
            let mut cells = Vec::new();
            for dj in -n..=n {
                for di in -n..=n {
                    let b = to_body(f64::from(di) * cell, f64::from(dj) * cell);
                    if let Some((z_lo, z_hi)) = map.at(b) {
                        let r = b - self.com;
                        // A foot cell straddling an axis through the CG counts in no
                        // quadrant: its footprint is on both sides.
                        let on_axis = r.x.abs() < cell / 2.0 || r.y.abs() < cell / 2.0;
                        let quadrant = if on_axis {
                            4
                        } else {
                            match (r.x > 0.0, r.y > 0.0) {
                                (true, true) => 0,
                                (false, true) => 1,
                                (false, false) => 2,
                                (true, false) => 3,
                            }
                        };
                        cells.push(RangeCell {
                            di,
                            dj,
                            z_lo,
                            z_hi,
                            quadrant,
                        });
                    }
                }
            }
            legs.push(cells);
        }
        let n = (self.under.radius() / cell).ceil() as i32 + 1;
        let mut under = Vec::new();
        for dj in -n..=n {
            for di in -n..=n {
                let mut low = f64::INFINITY;
                for (ox, oy) in [
                    (0.0, 0.0),
                    (-0.5, -0.5),
                    (0.5, -0.5),
                    (-0.5, 0.5),
                    (0.5, 0.5),
                ] {
                    let b = to_body((f64::from(di) + ox) * cell, (f64::from(dj) + oy) * cell);
                    if let Some((lo, _)) = self.under.at(b) {
                        low = low.min(lo);
                    }
                }
                if low.is_finite() {
                    under.push(UnderCell {
                        di,
                        dj,
                        depth: -low,
                    });
                }
            }
        }
        HeadingTable { theta, legs, under }
    }

    /// Whether the legs' ranges and the under-carriage look the same turned by any eighth
    /// of a turn, so that one heading bin suffices: turned by a quarter, nine-tenths of
    /// their cells in common; turned by an eighth (which no square grid maps onto itself),
    /// nine-tenths of the cells of each within one cell of the other's.
    pub fn radially_symmetric(&self) -> bool {
        let footprint = |t: &HeadingTable| -> HashSet<(i32, i32)> {
            t.legs
                .iter()
                .flatten()
                .map(|c| (c.di, c.dj))
                .chain(t.under.iter().map(|u| (u.di, u.dj)))
                .collect()
        };
        let near = |set: &HashSet<(i32, i32)>, (i, j): (i32, i32)| {
            (-1..=1).any(|a| (-1..=1).any(|b| set.contains(&(i + a, j + b))))
        };
        let base = footprint(&self.table(0.0));
        (1..8).all(|k| {
            let other = footprint(&self.table(f64::from(k) * TAU / 8.0));
            let share = if k % 2 == 0 {
                base.intersection(&other).count() as f64 / base.union(&other).count().max(1) as f64
            } else {
                let matched = other.iter().filter(|&&c| near(&base, c)).count()
                    + base.iter().filter(|&&c| near(&other, c)).count();
                matched as f64 / (base.len() + other.len()).max(1) as f64
            };
            share >= 0.9
        })
    }

    /// The body-frame range map's height interval for leg `leg` at a body-frame point.
    pub fn reach_at(&self, leg: usize, body: Point2<f64>) -> Option<(f64, f64)> {
        self.ranges.get(leg)?.at(body)
    }
}
