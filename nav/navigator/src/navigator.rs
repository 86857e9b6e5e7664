//! The navigation loop's decisions, from the estimated pose and the depth image alone.

use nalgebra::Point2;
use tca_nav_danger_map::{CellDanger, DangerError, DangerMap, DangerParams};
use tca_nav_dstar_lite::{Cell, CostGrid, DStarLite, PlanError};
use tca_nav_sensing::{CameraMount, CameraParams, Pose2, wrap};
use tca_nav_terrain_map::{Ageing, MatchParams, TerrainMapError};
use tca_robot::{CellIndex, Grid};

use crate::CellChange;

/// Why navigation could not start or go on.
#[derive(Debug, thiserror::Error)]
pub enum NavError {
    /// The danger parameters or map are not valid.
    #[error(transparent)]
    Danger(#[from] DangerError),
    /// The terrain map could not be made.
    #[error(transparent)]
    Terrain(#[from] TerrainMapError),
    /// The camera's parameters are not valid.
    #[error(transparent)]
    Camera(#[from] tca_nav_sensing::SensingError),
    /// The planner refused.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// A changed cell lies outside the navigator's map (the map side's grid differs).
    #[error(
        "a danger change names cell ({ix}, {iy}), outside the navigator's map; the map side and the navigator must use the same grid"
    )]
    ChangeOffMap {
        /// Column.
        ix: usize,
        /// Row.
        iy: usize,
    },
    /// The base has not moved for this many frames while told to: the navigator gives up.
    #[error(
        "no progress: the robot stayed at ({x:.3}, {y:.3}) m for {frames} frames while told to move (its base cannot do what it is told there: it collides, or a walking base finds no step); try another start, goal or robot"
    )]
    NoProgress {
        /// Frames it stood still.
        frames: usize,
        /// East, m (the estimate).
        x: f64,
        /// North, m (the estimate).
        y: f64,
    },
    /// The start or goal lies outside the map.
    #[error("the {what} ({x:.3}, {y:.3}) m lies outside the map; give one on the terrain")]
    OffMap {
        /// "start" or "goal".
        what: &'static str,
        /// East, m.
        x: f64,
        /// North, m.
        y: f64,
    },
}

/// The navigator's parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct NavParams {
    /// The robot's danger parameters.
    pub danger: DangerParams,
    /// Weight of danger against length in D* Lite's edge cost (per cell). 2: one cell of
    /// unknown or just-barely-traversable ground (d = 1) costs as much as three cells of
    /// flat ground, so a detour is taken when it is less than about three times as long
    /// as the crossing it avoids; above 1 as the paper asks, and low enough that the path
    /// still runs through unknown ground toward the goal rather than hugging what is
    /// already mapped.
    pub beta: f64,
    /// Clearance kept from untraversable cells when planning, m: a traversable cell this
    /// close to an untraversable one is planned as if its danger were at least 1 (just
    /// barely traversable). The danger map already sizes the untraversable area to the
    /// robot; this margin is for what the map and the position estimate cannot know
    /// exactly (a boundary seen from one side, drift since the boundary was mapped, the
    /// follower's tracking error), so that the path does not run along the edge of an
    /// untraversable area where being off by a few centimetres puts the robot in it.
    pub clearance_m: f64,
    /// The terrain map's age windows.
    pub ageing: Ageing,
    /// The camera.
    pub camera: CameraParams,
    /// Where the camera sits.
    pub mount: CameraMount,
    /// Farthest point put into the map, m (and the farthest path cell an exploration turn
    /// looks at). 2.2 by default: there the default camera's range error, 0.004 z², is
    /// about one 2 cm map cell. Nearer cuts see too little of the way ahead (at 1.6 m the
    /// wheeled base on the ramps drove 1.22-1.27 times the true-map path, wandering north
    /// along a platform it saw end too soon; at 2.2 m, 0.99-1.03 times).
    pub map_range_m: f64,
    /// Goal reached when the estimate is this close, m.
    pub goal_tolerance_m: f64,
    /// Half the angle of an exploration turn, rad (ε).
    pub explore_half_angle_rad: f64,
    /// Spacing of exploration turns, m (l).
    pub explore_spacing_m: f64,
    /// Fastest forward speed, m/s.
    pub max_forward_mps: f64,
    /// Fastest turn, rad/s.
    pub max_turn_rps: f64,
    /// Gain of the turn speed on the heading error, 1/s.
    pub turn_gain: f64,
    /// Distance ahead on the path the follower steers to, m.
    pub lookahead_m: f64,
    /// Line of sight along the path, m (0: off). When above 0 the follower steers to the
    /// farthest path cell within this distance that a straight line reaches over cells no
    /// more dangerous and no less known than the path's own up to there (and no nearer an
    /// untraversable cell than the path comes), so the grid path's corners are cut where
    /// the ground allows it and is known to. 0.6 by default.
    pub sight_m: f64,
    /// Time between frames, s: each command holds for one frame.
    pub frame_period_s: f64,
    /// The LTM Matcher: register each frame against the map so far and correct the pose
    /// frames are placed with (and the navigator steers by); `None`: the odometry alone.
    pub matcher: Option<MatchParams>,
    /// Frames in a row the estimate may stay where it is (within [`STILL_M`] and
    /// [`STILL_RAD`]) while the navigator commands motion before it gives up with
    /// [`NavError::NoProgress`]: the base cannot carry out what it is told (it collides, or
    /// a walking base finds no step). 0: never give up.
    pub stall_frames: usize,
}

/// How far the estimate may move, m, and still count as standing still.
pub const STILL_M: f64 = 0.01;
/// How far the estimate may turn, rad, and still count as standing still.
pub const STILL_RAD: f64 = 0.02;

impl NavParams {
    /// Defaults for a robot with these danger parameters and camera mount.
    pub fn new(danger: DangerParams, mount: CameraMount, max_forward_mps: f64) -> Self {
        Self {
            danger,
            beta: 2.0,
            clearance_m: 0.06,
            ageing: Ageing::PAPER,
            camera: CameraParams::stereo_default(),
            mount,
            map_range_m: 2.2,
            goal_tolerance_m: 0.04,
            explore_half_angle_rad: std::f64::consts::PI / 8.0,
            explore_spacing_m: 0.2,
            max_forward_mps,
            max_turn_rps: 0.6,
            turn_gain: 1.5,
            lookahead_m: 0.12,
            sight_m: 0.6,
            frame_period_s: 0.25,
            matcher: None,
            stall_frames: 60,
        }
    }
}

/// What the navigator wants done this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Drive at these speeds for the frame.
    Drive {
        /// Forward, m/s.
        forward_mps: f64,
        /// Turn, rad/s (positive to the left).
        turn_rps: f64,
    },
    /// The goal is reached by the estimate.
    Reached,
}

#[derive(Debug, Clone)]
struct Exploration {
    /// Headings to turn to, in order.
    targets: Vec<f64>,
}

/// The navigator: D* Lite over the danger map as the map side reports it, and motion
/// control. It keeps its own copy of every cell's danger and certainty, updated from the
/// changes it is given.
#[derive(Debug, Clone)]
pub struct Navigator {
    params: NavParams,
    cells: Grid<CellDanger>,
    /// Per cell, the untraversable cells within the clearance (row-major).
    near_untraversable: Vec<u32>,
    /// Offsets of the cells within the clearance.
    clearance_disc: Vec<(isize, isize)>,
    planner: DStarLite,
    goal: Point2<f64>,
    path: Vec<Cell>,
    replans: u64,
    replanned_since_turn: bool,
    exploration: Option<Exploration>,
    last_explored: Option<(Point2<f64>, Pose2)>,
    travelled_since_turn_m: f64,
    /// Distance travelled since the last turn toward a blind path cell.
    travelled_since_blind_m: f64,
    last_pose: Option<Pose2>,
    /// Where the estimate has stood since, and for how many frames.
    still: Option<(Pose2, usize)>,
    turns: u64,
}

impl Navigator {
    /// A navigator over a map of `nx` x `ny` cells of `resolution_m` (cell (0, 0) centred
    /// at `origin`) from `start` to `goal` (world frame). The first path runs straight
    /// through the unknown map.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        params: NavParams,
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
        start: Pose2,
        goal: Point2<f64>,
    ) -> Result<Self, NavError> {
        let cells = DangerMap::new(params.danger.clone(), origin, resolution_m, nx, ny)?
            .cells()
            .clone();
        let grid = CostGrid::filled(nx, ny, params.beta, 1.0)?;
        let cell_of = |what, x: f64, y: f64| {
            cells
                .cell_at(Point2::new(x, y))
                .map(|c| Cell::new(c.ix, c.iy))
                .ok_or(NavError::OffMap { what, x, y })
        };
        let s = cell_of("start", start.x, start.y)?;
        let g = cell_of("goal", goal.x, goal.y)?;
        let mut planner = DStarLite::new(grid, s, g)?;
        let path = planner.plan()?.cells;
        let r = (params.clearance_m / resolution_m).max(0.0);
        let reach = r.floor() as isize;
        let mut clearance_disc = Vec::new();
        for dy in -reach..=reach {
            for dx in -reach..=reach {
                if ((dx * dx + dy * dy) as f64) <= r * r {
                    clearance_disc.push((dx, dy));
                }
            }
        }
        Ok(Self {
            params,
            near_untraversable: vec![0; nx * ny],
            clearance_disc,
            cells,
            planner,
            goal,
            path,
            replans: 0,
            replanned_since_turn: false,
            exploration: None,
            last_explored: None,
            travelled_since_turn_m: 0.0,
            travelled_since_blind_m: f64::INFINITY,
            last_pose: None,
            still: None,
            turns: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &NavParams {
        &self.params
    }

    /// The danger map as the navigator knows it.
    pub fn danger(&self) -> &Grid<CellDanger> {
        &self.cells
    }

    /// The goal, world frame.
    pub fn goal(&self) -> Point2<f64> {
        self.goal
    }

    /// The planned path, world frame.
    pub fn path(&self) -> Vec<Point2<f64>> {
        self.path
            .iter()
            .map(|c| self.cells.cell_center(CellIndex::new(c.ix, c.iy)))
            .collect()
    }

    /// Times changed cells touched the path and the new plan left the old one.
    pub fn replans(&self) -> u64 {
        self.replans
    }

    /// Exploration turns started.
    pub fn exploration_turns(&self) -> u64 {
        self.turns
    }

    /// D* Lite's expansions so far.
    pub fn expansions(&self) -> u64 {
        self.planner.total_expansions()
    }

    /// One frame: the estimated pose `estimate` and the cells whose danger or certainty
    /// this frame's depth image changed (from [`crate::PerceivedMap::insert`], in this process or in the
    /// LTM Manager). Returns what to do, or [`PlanError::NoPath`] when the goal is cut off.
    pub fn step(&mut self, estimate: Pose2, changes: &[CellChange]) -> Result<Command, NavError> {
        if let Some(last) = self.last_pose {
            let moved = last.distance(&estimate);
            self.travelled_since_turn_m += moved;
            self.travelled_since_blind_m += moved;
        }
        self.last_pose = Some(estimate);
        let here = Point2::new(estimate.x, estimate.y);
        let mut affected = false;
        if !changes.is_empty() {
            let near_path = self.path_neighbourhood();
            let mut replanned = Vec::new();
            for change in changes {
                let c = change.cell;
                let Some(slot) = self.cells.get_mut(c) else {
                    return Err(NavError::ChangeOffMap { ix: c.ix, iy: c.iy });
                };
                let (before, certainty_before) = (slot.danger, slot.certainty);
                *slot = change.danger;
                if before == change.danger.danger && certainty_before == change.danger.certainty {
                    continue;
                }
                replanned.push(c);
                let (was, is) = (before.is_finite(), change.danger.danger.is_finite());
                if was != is {
                    self.count_untraversable(c, if is { -1 } else { 1 }, &mut replanned);
                }
            }
            replanned.sort_unstable_by_key(|c| (c.iy, c.ix));
            replanned.dedup();
            for c in replanned {
                let cell = Cell::new(c.ix, c.iy);
                if self.planner.set_danger(cell, self.planned_danger(c))?
                    && near_path.contains(&cell)
                {
                    affected = true;
                }
            }
        }
        if (self.goal - here).norm() <= self.params.goal_tolerance_m {
            return Ok(Command::Reached);
        }
        self.check_progress(estimate)?;
        let me = self.cells.nearest_cell(here);
        self.planner.move_start(Cell::new(me.ix, me.iy))?;
        let path = self.planner.plan()?.cells;
        if affected && !self.path.ends_with(&path) {
            self.replans += 1;
            self.replanned_since_turn = true;
        }
        self.path = path;
        Ok(self.motion(estimate))
    }

    /// Counts the frames the estimate has stood still; past [`NavParams::stall_frames`] the
    /// navigator gives up.
    fn check_progress(&mut self, estimate: Pose2) -> Result<(), NavError> {
        if self.params.stall_frames == 0 {
            return Ok(());
        }
        let (anchor, frames) = self.still.get_or_insert((estimate, 0));
        let turned = (estimate.yaw - anchor.yaw)
            .sin()
            .atan2((estimate.yaw - anchor.yaw).cos());
        if anchor.distance(&estimate) <= STILL_M && turned.abs() <= STILL_RAD {
            *frames += 1;
        } else {
            *anchor = estimate;
            *frames = 0;
        }
        if *frames >= self.params.stall_frames {
            return Err(NavError::NoProgress {
                frames: *frames,
                x: estimate.x,
                y: estimate.y,
            });
        }
        Ok(())
    }

    /// Counts an untraversable cell in (`delta` 1) or out (-1) of the clearance of the
    /// cells around it, noting the cells whose clearance changes.
    fn count_untraversable(&mut self, c: CellIndex, delta: i32, noted: &mut Vec<CellIndex>) {
        let (nx, ny) = (self.cells.nx() as isize, self.cells.ny() as isize);
        for &(dx, dy) in &self.clearance_disc {
            let (x, y) = (c.ix as isize + dx, c.iy as isize + dy);
            if x < 0 || y < 0 || x >= nx || y >= ny {
                continue;
            }
            let i = (y * nx + x) as usize;
            let before = self.near_untraversable[i];
            let after = before.saturating_add_signed(delta);
            self.near_untraversable[i] = after;
            if (before == 0) != (after == 0) {
                noted.push(CellIndex::new(x as usize, y as usize));
            }
        }
    }

    /// The danger D* Lite plans a cell with: the map's, with the unknown part of the cell's
    /// circle counted as d = 1 (`certainty * d + (1 - certainty)`, so that a circle seen
    /// only in part, which may miss a slope beside it, does not plan as flat), raised to 1
    /// within the clearance of an untraversable cell.
    fn planned_danger(&self, c: CellIndex) -> f64 {
        let d = self.cells.get(c).map_or(1.0, |d| {
            if d.danger.is_finite() {
                let k = d.certainty.clamp(0.0, 1.0);
                k * d.danger + (1.0 - k)
            } else {
                d.danger
            }
        });
        let i = c.iy * self.cells.nx() + c.ix;
        if d.is_finite() && self.near_untraversable.get(i).is_some_and(|&n| n > 0) {
            d.max(1.0)
        } else {
            d
        }
    }

    fn path_neighbourhood(&self) -> std::collections::HashSet<Cell> {
        let mut set = std::collections::HashSet::new();
        for c in &self.path {
            for dy in -1isize..=1 {
                for dx in -1isize..=1 {
                    let (x, y) = (c.ix as isize + dx, c.iy as isize + dy);
                    if x >= 0 && y >= 0 {
                        set.insert(Cell::new(x as usize, y as usize));
                    }
                }
            }
        }
        set
    }

    /// The known fraction of a cell's circle (0 off the map).
    fn certainty(&self, c: CellIndex) -> f64 {
        self.cells.get(c).map_or(0.0, |k| k.certainty)
    }

    fn cell_point(&self, c: Cell) -> Point2<f64> {
        self.cells.cell_center(CellIndex::new(c.ix, c.iy))
    }

    fn motion(&mut self, est: Pose2) -> Command {
        let here = Point2::new(est.x, est.y);
        if let Some(cmd) = self.continue_exploration(est) {
            return cmd;
        }
        if let Some((cell, blind)) = self.cell_to_explore(est) {
            if blind {
                self.travelled_since_blind_m = 0.0;
            }
            let b = bearing(here, cell);
            let e = self.params.explore_half_angle_rad;
            self.exploration = Some(Exploration {
                targets: vec![wrap(b + e), wrap(b - e), b],
            });
            self.last_explored = Some((cell, est));
            self.travelled_since_turn_m = 0.0;
            self.replanned_since_turn = false;
            self.turns += 1;
            if let Some(cmd) = self.continue_exploration(est) {
                return cmd;
            }
        }
        self.follow(est)
    }

    fn continue_exploration(&mut self, est: Pose2) -> Option<Command> {
        let dt_turn = 0.08; // rad: close enough to a target heading
        let ex = self.exploration.as_mut()?;
        while let Some(&t) = ex.targets.first() {
            let err = wrap(t - est.yaw);
            if err.abs() > dt_turn {
                let turn = (self.params.turn_gain * 2.0 * err)
                    .clamp(-self.params.max_turn_rps, self.params.max_turn_rps);
                return Some(Command::Drive {
                    forward_mps: 0.0,
                    turn_rps: turn,
                });
            }
            ex.targets.remove(0);
        }
        self.exploration = None;
        None
    }

    /// The path cell to turn and look at, and whether it is a blind one: the first path
    /// cell within camera range too little known for a danger, if one is due; else the
    /// first whose certainty is below 1, if the spacing rules allow a turn for it.
    fn cell_to_explore(&self, est: Pose2) -> Option<(Point2<f64>, bool)> {
        let here = Point2::new(est.x, est.y);
        let l = self.params.explore_spacing_m;
        // The first path cell in range known less than `below`.
        let first_below = |below: f64| {
            self.path.iter().skip(1).find_map(|c| {
                let p = self.cell_point(*c);
                let d = (p - here).norm();
                if d > self.params.map_range_m {
                    return None;
                }
                let known = self.certainty(CellIndex::new(c.ix, c.iy));
                (d >= 0.3 && known < below).then_some(p)
            })
        };
        // A path cell too little known for a danger (the plan crosses it blind, at d = 1)
        // is looked at first, at most once per `explore_spacing_m` travelled: a circle
        // known only in part can read as flat beside a slope it has not seen.
        if self.travelled_since_blind_m >= l
            && let Some(blind) = first_below(self.params.danger.min_certainty)
            && self
                .last_explored
                .is_none_or(|(prev, _)| (blind - prev).norm() >= l)
        {
            return Some((blind, true));
        }
        let candidate = first_below(1.0)?;
        let Some((prev, _)) = self.last_explored else {
            return Some((candidate, false));
        };
        if (candidate - prev).norm() < l {
            return None;
        }
        let angle = (bearing(here, candidate) - bearing(here, prev)).abs();
        let angle = wrap(angle).abs();
        (self.travelled_since_turn_m >= l
            || angle >= self.params.explore_half_angle_rad
            || self.replanned_since_turn)
            .then_some((candidate, false))
    }

    fn follow(&self, est: Pose2) -> Command {
        let here = Point2::new(est.x, est.y);
        let dist_goal = (self.goal - here).norm();
        // The point `lookahead_m` along the path from the robot (the goal near the end).
        let mut target = self.goal;
        let mut along = 0.0;
        let mut prev = here;
        for c in self.path.iter().skip(1) {
            let p = self.cell_point(*c);
            along += (p - prev).norm();
            prev = p;
            if along >= self.params.lookahead_m {
                target = p;
                break;
            }
        }
        if let Some(seen) = self.farthest_in_sight(here)
            && (seen - here).norm() > (target - here).norm()
        {
            target = seen;
        }
        if dist_goal < self.params.lookahead_m {
            target = self.goal;
        }
        let err = wrap(bearing(here, target) - est.yaw);
        let turn = (self.params.turn_gain * err)
            .clamp(-self.params.max_turn_rps, self.params.max_turn_rps);
        let forward = if err.abs() > 0.6 {
            0.0
        } else {
            self.params.max_forward_mps * err.cos()
        };
        Command::Drive {
            forward_mps: forward.min(dist_goal / self.params.frame_period_s),
            turn_rps: turn,
        }
    }
}

impl Navigator {
    /// The farthest path cell within `sight_m` that a straight line from `here` reaches
    /// over ground no worse and no less known than the path's own up to that cell: a cut
    /// corner never crosses ground seen less well than the path it shortens (a cell planned
    /// at d = 1 because it is blind is not the same as one seen to be barely traversable).
    fn farthest_in_sight(&self, here: Point2<f64>) -> Option<Point2<f64>> {
        let sight = self.params.sight_m;
        if sight <= 0.0 {
            return None;
        }
        let nx = self.cells.nx();
        let near = |c: CellIndex| self.near_untraversable[c.iy * nx + c.ix] > 0;
        let mut worst = 0.0f64;
        let mut least_known = 1.0f64;
        let mut path_near = false;
        let mut best = None;
        for c in self.path.iter().skip(1) {
            let ci = CellIndex::new(c.ix, c.iy);
            worst = worst.max(self.planned_danger(ci));
            least_known = least_known.min(self.certainty(ci));
            path_near |= near(ci);
            let p = self.cell_point(*c);
            let d = (p - here).norm();
            if d > sight {
                break;
            }
            if self.line_clear(here, p, worst, least_known, path_near, &near) {
                best = Some(p);
            }
        }
        best
    }

    /// Whether every cell on the segment `a`-`b` is finite, no more dangerous than
    /// `worst`, known at least `least_known`, and (unless `near_allowed`) clear of
    /// untraversable cells.
    fn line_clear(
        &self,
        a: Point2<f64>,
        b: Point2<f64>,
        worst: f64,
        least_known: f64,
        near_allowed: bool,
        near: &dyn Fn(CellIndex) -> bool,
    ) -> bool {
        let step = self.cells.resolution_m() * 0.5;
        let n = ((b - a).norm() / step).ceil().max(1.0) as usize;
        (0..=n).all(|i| {
            let p = a + (b - a) * (i as f64 / n as f64);
            let Some(c) = self.cells.cell_at(p) else {
                return false;
            };
            let d = self.planned_danger(c);
            let known = self.certainty(c);
            known >= least_known - 1e-9
                && d.is_finite()
                && d <= worst + 1e-9
                && (near_allowed || !near(c))
        })
    }
}

fn bearing(from: Point2<f64>, to: Point2<f64>) -> f64 {
    (to.y - from.y).atan2(to.x - from.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A navigator on an unknown 2 x 2 m map of 2 cm cells, at (0.2, 1.0) facing east,
    /// its goal 1.6 m east: the first path runs straight along the row y = 1.0.
    fn navigator() -> Navigator {
        let mount = CameraMount {
            forward_m: 0.1,
            height_m: 0.3,
            pitch_down_rad: 0.4,
        };
        let params = NavParams::new(DangerParams::paper(0.3), mount, 0.2);
        Navigator::new(
            params,
            Point2::new(0.0, 0.0),
            0.02,
            100,
            100,
            Pose2::new(0.2, 1.0, 0.0),
            Point2::new(1.8, 1.0),
        )
        .expect("a valid navigator")
    }

    /// Gives every path cell east of `from_x` up to `to_x` this certainty (danger 0).
    fn know(nav: &mut Navigator, from_x: f64, to_x: f64, certainty: f64) {
        for c in nav.path.clone() {
            let x = nav.cell_point(c).x;
            if x >= from_x && x < to_x {
                let slot = nav.cells.get_mut(CellIndex::new(c.ix, c.iy)).unwrap();
                slot.danger = 0.0;
                slot.certainty = certainty;
            }
        }
    }

    #[test]
    fn a_path_cell_planned_blind_is_looked_at_before_a_nearer_partly_known_one() {
        let mut nav = navigator();
        // Known in part (enough for a danger) up to x = 0.8 m, blind beyond.
        know(&mut nav, 0.0, 0.8, 0.6);
        let here = Pose2::new(0.2, 1.0, 0.0);
        let (cell, blind) = nav.cell_to_explore(here).expect("a cell to look at");
        assert!(blind, "the blind cell comes first");
        assert!(
            (cell.x - 0.8).abs() < 0.011 && (cell.y - 1.0).abs() < 0.011,
            "the first blind path cell, not {cell:?}"
        );
    }

    #[test]
    fn without_a_blind_cell_the_first_cell_not_wholly_known_is_looked_at() {
        let mut nav = navigator();
        // Wholly known up to 0.7 m, partly known beyond: nothing on the path is blind.
        know(&mut nav, 0.0, 0.7, 1.0);
        know(&mut nav, 0.7, 2.0, 0.6);
        let (cell, blind) = nav
            .cell_to_explore(Pose2::new(0.2, 1.0, 0.0))
            .expect("a cell to look at");
        assert!(!blind);
        assert!((cell.x - 0.7).abs() < 0.011, "got {cell:?}");
        // A path wholly known in camera range gives no turn at all.
        know(&mut nav, 0.0, 2.0, 1.0);
        assert_eq!(nav.cell_to_explore(Pose2::new(0.2, 1.0, 0.0)), None);
    }

    #[test]
    fn blind_turns_come_at_most_once_per_spacing_travelled() {
        let mut nav = navigator();
        know(&mut nav, 0.0, 0.8, 0.6);
        let start = Pose2::new(0.2, 1.0, 0.0);
        // The first frame turns toward the blind cell at 0.8 m.
        let Command::Drive { forward_mps, .. } = nav.step(start, &[]).unwrap() else {
            panic!("not reached yet");
        };
        assert_eq!(forward_mps, 0.0, "an exploration turn stands still");
        assert_eq!(nav.exploration_turns(), 1);
        assert_eq!(nav.travelled_since_blind_m, 0.0);
        let (first, _) = nav.last_explored.unwrap();
        assert!((first.x - 0.8).abs() < 0.011);
        nav.exploration = None;

        // Farther on, the path is blind from 1.1 m: a cell far enough from the last one
        // looked at, but only 0.1 m travelled since the blind turn, so no blind turn yet.
        know(&mut nav, 0.8, 1.1, 0.6);
        let on = Pose2::new(0.3, 1.0, 0.0);
        nav.travelled_since_blind_m = 0.1;
        match nav.cell_to_explore(on) {
            None => {}
            Some((cell, blind)) => {
                assert!(
                    !blind,
                    "a blind turn before the spacing was travelled: {cell:?}"
                );
            }
        }
        // After the spacing, the blind cell at 1.1 m is due.
        nav.travelled_since_blind_m = nav.params.explore_spacing_m;
        let (cell, blind) = nav.cell_to_explore(on).expect("a blind cell is due");
        assert!(blind);
        assert!((cell.x - 1.1).abs() < 0.011, "got {cell:?}");
        // A blind cell within the spacing of the last one looked at is not looked at again.
        nav.last_explored = Some((cell, on));
        let again = nav.cell_to_explore(on);
        assert!(
            again.is_none_or(|(_, blind)| !blind),
            "the same blind cell twice: {again:?}"
        );
    }
    #[test]
    fn a_cut_corner_never_crosses_ground_less_known_than_the_path() {
        let mut nav = navigator();
        // An L-shaped path: 0.3 m east, then 0.3 m north, every cell of it seen and
        // barely traversable (planned d = 1), so danger alone would let a straight line cross
        // the blind corner (also planned at d = 1).
        let (x0, y0) = (10usize, 50usize);
        let mut path: Vec<Cell> = (0..=15).map(|i| Cell::new(x0 + i, y0)).collect();
        path.extend((1..=15).map(|i| Cell::new(x0 + 15, y0 + i)));
        for c in &path {
            let slot = nav.cells.get_mut(CellIndex::new(c.ix, c.iy)).unwrap();
            slot.danger = 1.0;
            slot.certainty = 1.0;
        }
        nav.path = path;
        let here = nav.cell_point(Cell::new(x0, y0));
        let corner = nav.cell_point(Cell::new(x0 + 15, y0));
        let beyond = nav
            .farthest_in_sight(here)
            .expect("the straight run is in sight");
        assert!(
            (beyond - corner).norm() < 1e-9,
            "the line stops at the corner, not at {beyond:?}"
        );
        // Once the corner's inside is seen (as barely traversable), the corner is cut.
        for ix in x0..=x0 + 15 {
            for iy in y0..=y0 + 15 {
                let slot = nav.cells.get_mut(CellIndex::new(ix, iy)).unwrap();
                slot.danger = 1.0;
                slot.certainty = 1.0;
            }
        }
        let cut = nav.farthest_in_sight(here).expect("a cell in sight");
        assert!(cut.y > corner.y + 0.1, "the corner is cut: {cut:?}");
    }
}
