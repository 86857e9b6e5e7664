//! The configuration space of the horizontal joints (§6.2.2): a grid over shoulder x elbow
//! whose every cell holds the lowest foot height (world Z of the sole) at which the foot may
//! pass anywhere through the cell without striking terrain.
//!
//! Obstacles are the terrain grown by the foot's radius, an uncertainty margin, and how far
//! the foot itself travels within the cell (bounded exactly by the link geometry: at most
//! `r_max * half_shoulder_cell + lower_link * half_elbow_cell`), plus a vertical clearance.
//! A cell whose requirement is above the foot's highest reach is an obstacle.
//!
//! Cells are scaled to the joint speeds (the elbow's cells are wider by the elbow's speed
//! over the shoulder's), so every cell takes the same time to cross at full speed and a
//! diagonal step moves both joints at full speed: the search's time has no grid bias on
//! straight paths.

use nalgebra::{Point2, Point3};
use tca_robot::{CarriagePose, Joint, JointPosition, LegKinematics, LegParams};

use crate::cost::JointSpeeds;
use crate::error::{PlanError, Result};
use crate::params::LrpParams;
use crate::terrain_grid::{ObstacleHeights, TerrainGrid};

/// A cell of the configuration space: shoulder index and elbow index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CCell {
    /// Shoulder index (0 at the shoulder's lower limit).
    pub is: usize,
    /// Elbow index (0 at the elbow's lower limit).
    pub ie: usize,
}

/// Where a straight joint-space segment is inside one cell: the parameter interval
/// `[u0, u1]` (0 = start of the segment, 1 = its end). Points where the segment touches a
/// cell only on its border (a corner) come as intervals of zero length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// The cell.
    pub cell: CCell,
    /// Entry parameter.
    pub u0: f64,
    /// Exit parameter.
    pub u1: f64,
}

/// Tolerance for points on cell borders, radians.
const BORDER_EPS_RAD: f64 = 1e-9;

/// The configuration space: grid layout, requirements and the leg it was built for.
#[derive(Debug, Clone)]
pub struct CSpace {
    kin: LegKinematics,
    pose: CarriagePose,
    link_plane_m: f64,
    upper_link_m: f64,
    lower_link_m: f64,
    speeds: JointSpeeds,
    s_min: f64,
    e_min: f64,
    ds: f64,
    de: f64,
    ns: usize,
    ne: usize,
    required_m: Vec<f64>,
    z_min_m: f64,
    z_max_m: f64,
    foot_radius_m: f64,
    /// Radius obstacles are grown by before the cell's own growth: foot plus margin, metres.
    base_radius_m: f64,
    clearance_m: f64,
    obstacles: ObstacleHeights,
}

impl CSpace {
    /// Builds the configuration space for a (level) carriage at `pose` over an elevation map.
    pub fn build(
        leg: &LegParams,
        params: &LrpParams,
        pose: &CarriagePose,
        elevation: &TerrainGrid,
    ) -> Result<Self> {
        params.validate()?;
        if !(pose.y_m.is_finite() && pose.roll_rad.is_finite() && pose.pitch_rad.is_finite()) {
            return Err(PlanError::NotFinite {
                what: "carriage pose",
            });
        }
        if elevation.known_cells() == 0 {
            return Err(PlanError::EmptyMap);
        }
        let kin = LegKinematics::new(leg);
        let speeds = JointSpeeds::of(&kin);
        let shoulder = *kin.limits(Joint::Shoulder);
        let elbow = *kin.limits(Joint::Elbow);
        let vertical = *kin.limits(Joint::Vertical);
        let s_range = shoulder.max - shoulder.min;
        let e_range = elbow.max - elbow.min;
        let ns = ((s_range / params.shoulder_cell_rad).round() as usize).max(1);
        let elbow_cell =
            params.shoulder_cell_rad * speeds.elbow_rad_per_s / speeds.shoulder_rad_per_s;
        let ne = ((e_range / elbow_cell).round() as usize).max(1);
        let (ds, de) = (s_range / ns as f64, e_range / ne as f64);
        let (l1, l2) = kin.link_lengths_m();
        let link_plane_m = leg.carriage.link_plane_height_m;
        let obstacles =
            ObstacleHeights::new(elevation, params.sigma_factor, params.unknown_height_m);
        let mut cs = Self {
            kin,
            pose: *pose,
            link_plane_m,
            upper_link_m: l1,
            lower_link_m: l2,
            speeds,
            s_min: shoulder.min,
            e_min: elbow.min,
            ds,
            de,
            ns,
            ne,
            required_m: Vec::with_capacity(ns * ne),
            z_min_m: link_plane_m - vertical.max,
            z_max_m: link_plane_m - vertical.min,
            foot_radius_m: leg.leg.foot_radius_m,
            base_radius_m: leg.leg.foot_radius_m + params.uncertainty_margin_m,
            clearance_m: params.clearance_m,
            obstacles,
        };
        let base = cs.base_radius_m;
        for ie in 0..ne {
            let e = cs.e_min + (ie as f64 + 0.5) * de;
            let growth = cs.cell_growth_m(ie);
            for is in 0..ns {
                let s = cs.s_min + (is as f64 + 0.5) * ds;
                let h = cs
                    .obstacles
                    .max_height_in_disc(cs.foot_xy(s, e), base + growth);
                cs.required_m.push(h + params.clearance_m);
            }
        }
        Ok(cs)
    }

    /// How far the foot can be from the centre of a cell of elbow row `ie` while the joints
    /// stay in the cell, metres (the growth of obstacles for that row).
    fn cell_growth_m(&self, ie: usize) -> f64 {
        let (ds, de) = (self.ds, self.de);
        let e = self.e_min + (ie as f64 + 0.5) * de;
        self.reach_max_m(e - 0.5 * de, e + 0.5 * de) * 0.5 * ds + self.lower_link_m * 0.5 * de
    }

    /// The requirement of a start cell counting known terrain only: the leg stands in the
    /// cell, so the occluded and unknown terrain around it was crossed to get there and is
    /// not taken as an obstacle (known obstacles still are). Metres, world Z.
    pub fn start_requirement_m(&self, c: CCell) -> f64 {
        let (s, e) = self.centre(c);
        let radius = self.base_radius_m + self.cell_growth_m(c.ie);
        self.obstacles
            .max_known_in_disc(self.foot_xy(s, e), radius)
            .unwrap_or(f64::NEG_INFINITY)
            + self.clearance_m
    }

    /// A copy of the space with one cell's requirement lowered to `required_m` (a start
    /// cell relaxed by [`start_requirement_m`](Self::start_requirement_m)).
    pub fn with_relaxed_cell(&self, c: CCell, required_m: f64) -> Self {
        let mut cs = self.clone();
        let i = cs.index(c);
        if let Some(r) = cs.required_m.get_mut(i) {
            *r = r.min(required_m);
        }
        cs
    }

    /// Largest distance of the foot from the shoulder axis for elbows in `[lo, hi]`.
    fn reach_max_m(&self, lo: f64, hi: f64) -> f64 {
        let (l1, l2) = (self.upper_link_m, self.lower_link_m);
        let nearest_straight = if lo <= 0.0 && hi >= 0.0 {
            0.0
        } else {
            lo.abs().min(hi.abs())
        };
        (l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * nearest_straight.cos())
            .max(0.0)
            .sqrt()
    }

    /// World XY of the foot at shoulder and elbow angles.
    pub fn foot_xy(&self, shoulder_rad: f64, elbow_rad: f64) -> Point2<f64> {
        let h = self.kin.forward_horizontal(shoulder_rad, elbow_rad);
        let w = self
            .pose
            .to_world(self.kin.carriage(), &Point3::new(h.x, h.y, 0.0));
        Point2::new(w.x, w.y)
    }

    /// Joint position putting the sole at world height `z_m` (level carriage).
    pub fn joints(&self, shoulder_rad: f64, elbow_rad: f64, z_m: f64) -> JointPosition {
        JointPosition::new(shoulder_rad, elbow_rad, self.link_plane_m - z_m)
    }

    /// World height of the sole for a joint position (level carriage).
    pub fn foot_z_m(&self, q: &JointPosition) -> f64 {
        self.link_plane_m - q.vertical_m
    }

    /// The leg's kinematics.
    pub fn kinematics(&self) -> &LegKinematics {
        &self.kin
    }

    /// The carriage pose the space was built for.
    pub fn pose(&self) -> &CarriagePose {
        &self.pose
    }

    /// Joint speed limits.
    pub fn speeds(&self) -> &JointSpeeds {
        &self.speeds
    }

    /// The obstacle heights the space was built from.
    pub fn obstacles(&self) -> &ObstacleHeights {
        &self.obstacles
    }

    /// Radius of the foot, metres.
    pub fn foot_radius_m(&self) -> f64 {
        self.foot_radius_m
    }

    /// Number of cells along the shoulder and the elbow.
    pub fn dims(&self) -> (usize, usize) {
        (self.ns, self.ne)
    }

    /// Cell widths along the shoulder and the elbow, radians.
    pub fn cell_size_rad(&self) -> (f64, f64) {
        (self.ds, self.de)
    }

    /// Lowest and highest world height of the sole (vertical axis limits), metres.
    pub fn z_range_m(&self) -> (f64, f64) {
        (self.z_min_m, self.z_max_m)
    }

    /// Time to cross one cell along the shoulder and along the elbow at full speed, seconds.
    pub fn cell_time_s(&self) -> (f64, f64) {
        (
            self.ds / self.speeds.shoulder_rad_per_s,
            self.de / self.speeds.elbow_rad_per_s,
        )
    }

    /// Row-major index of a cell.
    pub fn index(&self, c: CCell) -> usize {
        c.ie * self.ns + c.is
    }

    /// The cell at a row-major index.
    pub fn cell(&self, index: usize) -> CCell {
        CCell {
            is: index % self.ns,
            ie: index / self.ns,
        }
    }

    /// Centre of a cell: (shoulder, elbow), radians.
    pub fn centre(&self, c: CCell) -> (f64, f64) {
        (
            self.s_min + (c.is as f64 + 0.5) * self.ds,
            self.e_min + (c.ie as f64 + 0.5) * self.de,
        )
    }

    /// The cell containing joint angles (clamped to the grid).
    pub fn cell_at(&self, shoulder_rad: f64, elbow_rad: f64) -> CCell {
        let idx = |v: f64, min: f64, d: f64, n: usize| {
            let f = ((v - min) / d).floor();
            if f.is_nan() || f < 0.0 {
                0
            } else {
                (f as usize).min(n - 1)
            }
        };
        CCell {
            is: idx(shoulder_rad, self.s_min, self.ds, self.ns),
            ie: idx(elbow_rad, self.e_min, self.de, self.ne),
        }
    }

    /// Lowest foot height for passing through a cell, metres (world Z).
    pub fn required_m(&self, c: CCell) -> f64 {
        self.required_m
            .get(self.index(c))
            .copied()
            .unwrap_or(f64::INFINITY)
    }

    /// Whether the foot can pass through a cell at all.
    pub fn is_free(&self, c: CCell) -> bool {
        self.required_m(c) <= self.z_max_m
    }

    /// The cells whose closed square contains the point (up to four on a corner).
    pub fn cells_at_point(&self, shoulder_rad: f64, elbow_rad: f64) -> Vec<CCell> {
        let range = |v: f64, min: f64, d: f64, n: usize| {
            let f = (v - min) / d;
            let eps = BORDER_EPS_RAD / d;
            let lo = (f - eps).floor().clamp(0.0, (n - 1) as f64) as usize;
            let hi = (f + eps).floor().clamp(0.0, (n - 1) as f64) as usize;
            lo..=hi
        };
        let mut out = Vec::with_capacity(4);
        for ie in range(elbow_rad, self.e_min, self.de, self.ne) {
            for is in range(shoulder_rad, self.s_min, self.ds, self.ns) {
                out.push(CCell { is, ie });
            }
        }
        out
    }

    /// The cells a straight joint-space segment from `a` to `b` (shoulder, elbow) passes
    /// through, with where it is in each; corners it only touches are included.
    pub fn crossings(&self, a: (f64, f64), b: (f64, f64)) -> Vec<Crossing> {
        let mut us = vec![0.0, 1.0];
        let mut lines = |p0: f64, p1: f64, min: f64, d: f64, n: usize| {
            if (p1 - p0).abs() < 1e-15 {
                return;
            }
            let (lo, hi) = (p0.min(p1), p0.max(p1));
            let k0 = ((lo - min) / d).ceil().max(1.0) as usize;
            let k1 = (((hi - min) / d).floor().max(0.0) as usize).min(n.saturating_sub(1));
            for k in k0..=k1 {
                let line = min + k as f64 * d;
                let u = (line - p0) / (p1 - p0);
                if (0.0..=1.0).contains(&u) {
                    us.push(u);
                }
            }
        };
        lines(a.0, b.0, self.s_min, self.ds, self.ns);
        lines(a.1, b.1, self.e_min, self.de, self.ne);
        us.sort_by(f64::total_cmp);
        us.dedup_by(|x, y| (*x - *y).abs() < 1e-12);
        let at = |u: f64| (a.0 + (b.0 - a.0) * u, a.1 + (b.1 - a.1) * u);
        let mut out = Vec::with_capacity(2 * us.len());
        for (k, &u) in us.iter().enumerate() {
            let (s, e) = at(u);
            for cell in self.cells_at_point(s, e) {
                out.push(Crossing { cell, u0: u, u1: u });
            }
            if let Some(&next) = us.get(k + 1) {
                let (s, e) = at(0.5 * (u + next));
                out.push(Crossing {
                    cell: self.cell_at(s, e),
                    u0: u,
                    u1: next,
                });
            }
        }
        out
    }

    /// The highest requirement of the cells a segment passes through, metres.
    pub fn segment_required_m(&self, a: (f64, f64), b: (f64, f64)) -> f64 {
        self.crossings(a, b)
            .iter()
            .map(|c| self.required_m(c.cell))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The 8 neighbours of a cell that are on the grid, with their step `(dis, die)`.
    pub fn neighbours(&self, c: CCell) -> impl Iterator<Item = (CCell, (i8, i8))> + '_ {
        DIRECTIONS.iter().filter_map(move |&(di, dj)| {
            let is = c.is.checked_add_signed(isize::from(di))?;
            let ie = c.ie.checked_add_signed(isize::from(dj))?;
            (is < self.ns && ie < self.ne).then_some((CCell { is, ie }, (di, dj)))
        })
    }

    /// Requirement at the border between a cell and its neighbour: both cells, and for a
    /// diagonal step the two cells whose corner it passes.
    pub fn step_required_m(&self, from: CCell, to: CCell) -> f64 {
        let mut r = self.required_m(from).max(self.required_m(to));
        if from.is != to.is && from.ie != to.ie {
            r = r
                .max(self.required_m(CCell {
                    is: from.is,
                    ie: to.ie,
                }))
                .max(self.required_m(CCell {
                    is: to.is,
                    ie: from.ie,
                }));
        }
        r
    }
}

/// The 8 grid directions; their index is the direction's id in the search.
pub(crate) const DIRECTIONS: [(i8, i8); 8] = [
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
];

#[cfg(test)]
mod tests {
    use super::*;
    use tca_robot::{Grid, HeightField};

    fn flat_map(height: f64) -> TerrainGrid {
        let hf =
            HeightField::flat(Point2::new(0.0, 0.0), Point2::new(6.0, 6.0), 0.05, height).unwrap();
        TerrainGrid::elevation_from_height_field(
            &hf,
            Point2::new(0.0, 0.0),
            Point2::new(6.0, 6.0),
            0.05,
        )
        .unwrap()
    }

    fn space(map: &TerrainGrid) -> CSpace {
        CSpace::build(
            &LegParams::default(),
            &LrpParams::default(),
            &CarriagePose::level(3.0),
            map,
        )
        .unwrap()
    }

    #[test]
    fn cells_take_the_same_time_along_both_joints() {
        let cs = space(&flat_map(0.0));
        let (ts, te) = cs.cell_time_s();
        assert!((ts - te).abs() < 0.02 * ts, "{ts} {te}");
        let (ds, de) = cs.cell_size_rad();
        assert!(
            (ds - 0.08).abs() < 1e-9 && (de - 0.12).abs() < 1e-9,
            "{ds} {de}"
        );
        assert_eq!(cs.dims(), (75, 45));
    }

    #[test]
    fn flat_ground_needs_only_the_clearance() {
        let cs = space(&flat_map(0.1));
        // A cell whose grown disc stays on the map.
        let c = cs.cell_at(1.5, 0.8);
        let clearance = LrpParams::default().clearance_m;
        assert!(
            (cs.required_m(c) - (0.1 + clearance)).abs() < 1e-9,
            "{}",
            cs.required_m(c)
        );
        assert!(cs.is_free(c));
    }

    #[test]
    fn a_tall_box_blocks_the_cells_over_it_and_a_low_one_only_raises_them() {
        let build = |height: f64| {
            let grid = Grid::from_fn(Point2::new(0.0, 0.0), 0.05, 121, 121, |_, p| {
                if (p - Point2::new(3.0, 5.0)).norm() < 0.3 {
                    height
                } else {
                    0.0
                }
            })
            .unwrap();
            let hf = HeightField::from_grid(grid).unwrap();
            let map = TerrainGrid::elevation_from_height_field(
                &hf,
                Point2::new(0.0, 0.0),
                Point2::new(6.0, 6.0),
                0.05,
            )
            .unwrap();
            space(&map)
        };
        // The foot at (3, 5) is 2 m straight ahead of the column at (3, 3).
        let kin = LegKinematics::new(&LegParams::default());
        let q = kin
            .inverse(
                &Point3::new(0.0, 2.0, -3.5),
                tca_robot::ElbowBranch::Positive,
            )
            .unwrap();
        let tall = build(1.2);
        let c = tall.cell_at(q.shoulder_rad, q.elbow_rad);
        assert!(!tall.is_free(c));
        let low = build(0.4);
        assert!(low.is_free(c));
        let clearance = LrpParams::default().clearance_m;
        assert!((low.required_m(c) - (0.4 + clearance)).abs() < 1e-9);
    }

    #[test]
    fn crossings_cover_the_segment_and_its_corners() {
        let cs = space(&flat_map(0.0));
        let a = cs.centre(CCell { is: 10, ie: 10 });
        let b = cs.centre(CCell { is: 11, ie: 11 });
        let cells: Vec<CCell> = cs.crossings(a, b).iter().map(|c| c.cell).collect();
        for want in [(10, 10), (11, 11), (10, 11), (11, 10)] {
            assert!(
                cells.contains(&CCell {
                    is: want.0,
                    ie: want.1
                }),
                "{want:?} missing from {cells:?}"
            );
        }
        // A straight step along the shoulder touches only its two cells.
        let b = cs.centre(CCell { is: 12, ie: 10 });
        let mut cells: Vec<CCell> = cs.crossings(a, b).iter().map(|c| c.cell).collect();
        cells.sort();
        cells.dedup();
        assert_eq!(cells.len(), 3);
        // Interior intervals tile [0, 1].
        let mut covered = 0.0;
        for c in cs.crossings(a, b) {
            covered += c.u1 - c.u0;
        }
        assert!((covered - 1.0).abs() < 1e-12);
    }
}
