//! The navigation loop closed in simulation: camera, odometry, navigator, base.

use std::time::Instant;

use nalgebra::Point2;
use serde::Serialize;
use tca_nav_danger_map::DangerMap;
use tca_nav_dstar_lite::{Cell, CostGrid, DStarLite, PlanError};
use tca_nav_sensing::{DepthCamera, DriftingOdometry, Pose2};
use tca_robot::{CellIndex, HeightField};

use crate::{Base, Command, NavError, NavParams, Navigator, PerceivedMap};

/// What to run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOptions {
    /// The true start pose.
    pub start: Pose2,
    /// The goal, m east and north of the start.
    pub goal_offset: [f64; 2],
    /// Odometry drift, fraction of the distance travelled.
    pub drift: f64,
    /// Seed of the camera's and the odometry's noise.
    pub seed: u64,
    /// Frames before giving up.
    pub max_frames: usize,
}

/// The outcome of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunReport {
    /// The base driven.
    pub robot: String,
    /// Whether the estimate reached the goal.
    pub reached: bool,
    /// Why the run ended.
    pub reason: String,
    /// True distance travelled, m.
    pub distance_m: f64,
    /// True final position against the goal, m.
    pub final_error_m: f64,
    /// True final position against the estimate, m.
    pub estimate_error_m: f64,
    /// The true positions, world frame, one per frame.
    pub path: Vec<[f64; 2]>,
    /// The estimated positions, one per frame.
    pub estimated_path: Vec<[f64; 2]>,
    /// The path as planned at the last replan (the first plan if there was none), from
    /// where the robot then stood to the goal, estimated frame.
    pub planned_path: Vec<[f64; 2]>,
    /// Replans because changed cells touched the path.
    pub replans: u64,
    /// Exploration turns.
    pub exploration_turns: u64,
    /// Frames the LTM Matcher corrected (0 without it).
    pub registrations: u64,
    /// Frames run.
    pub frames: usize,
    /// Frames per second of computing (capture, mapping, danger, planning, control).
    pub loop_hz: f64,
    /// Drive commands the base could not carry out (blocked by a step).
    pub collisions: u64,
    /// Frames in which the base tipped over.
    pub falls: u64,
    /// Frames in which the robot truly stood in, or on its way to the next frame passed
    /// through, a cell that is untraversable on the true terrain.
    pub untraversable_frames: u64,
    /// For each of those frames the first such point, `[x, y]` m, world frame.
    pub untraversable_at: Vec<[f64; 2]>,
    /// Length of the D* Lite path on the true danger map, m (`None` if there is none).
    pub true_map_path_m: Option<f64>,
}

impl RunReport {
    /// Whether the run passes every acceptance limit: reached, final error within 3 % of the
    /// distance, no collision, fall or frame in an untraversable cell, and a path at most
    /// 1.25 times the true-map path.
    pub fn meets_acceptance(&self) -> bool {
        self.reached
            && self.final_error_m <= 0.03 * self.distance_m
            && self.collisions == 0
            && self.falls == 0
            && self.untraversable_frames == 0
            && self
                .true_map_path_m
                .is_some_and(|m| self.distance_m <= 1.25 * m)
    }
}

/// The danger map of the whole true terrain, for judging a run.
pub fn true_danger_map(terrain: &HeightField, params: &NavParams) -> Result<DangerMap, NavError> {
    let g = terrain.grid();
    Ok(DangerMap::from_view(
        params.danger.clone(),
        g.origin(),
        g.resolution_m(),
        g.nx(),
        g.ny(),
        terrain,
    )?)
}

/// Where a true path meets untraversable cells of the true danger map: for each pose, the
/// first point in such a cell on the straight way from it to the next pose (sampled every
/// half cell, both ends included; the last pose alone), if there is one. A base moves
/// several cells a frame, so looking at the poses alone would miss a corner clipped between
/// two frames.
pub fn untraversable_along(truth: &DangerMap, path: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let cells = truth.cells();
    let step = 0.5 * cells.resolution_m();
    let bad = |p: Point2<f64>| {
        cells
            .cell_at(p)
            .is_some_and(|c| !truth.cell(c).is_traversable())
    };
    let mut out = Vec::new();
    for (i, a) in path.iter().enumerate() {
        let a = Point2::new(a[0], a[1]);
        let b = path.get(i + 1).map_or(a, |b| Point2::new(b[0], b[1]));
        let n = ((b - a).norm() / step).ceil().max(1.0) as usize;
        if let Some(p) = (0..=n)
            .map(|k| a + (b - a) * (k as f64 / n as f64))
            .find(|p| bad(*p))
        {
            out.push([p.x, p.y]);
        }
    }
    out
}

/// Keeps the path as planned at the last replan: shown each frame's replan count in
/// order, it takes the frame's path whenever the count moves (the first frame's if it
/// never does).
#[derive(Debug, Clone, Default)]
pub struct LastReplan {
    replans: Option<u64>,
    path: Vec<[f64; 2]>,
}

impl LastReplan {
    /// One frame: its replan count and (asked for only when the count moved) its path.
    pub fn frame(&mut self, replans: u64, path: impl FnOnce() -> Vec<[f64; 2]>) {
        if self.replans != Some(replans) {
            self.replans = Some(replans);
            self.path = path();
        }
    }

    /// The path kept.
    pub fn into_path(self) -> Vec<[f64; 2]> {
        self.path
    }
}

/// Length of the D* Lite path from `start` to `goal` on a danger map, m.
pub fn true_map_path_m(
    truth: &DangerMap,
    beta: f64,
    start: Point2<f64>,
    goal: Point2<f64>,
) -> Result<Option<f64>, NavError> {
    let cells = truth.cells();
    let dangers = cells.cells().iter().map(|c| c.danger).collect();
    let grid = CostGrid::from_dangers(cells.nx(), cells.ny(), beta, dangers)?;
    let s = cells.nearest_cell(start);
    let g = cells.nearest_cell(goal);
    let mut planner = DStarLite::new(grid, Cell::new(s.ix, s.iy), Cell::new(g.ix, g.iy))?;
    match planner.plan() {
        Ok(p) => Ok(Some(
            p.cells
                .windows(2)
                .map(|w| {
                    let (a, b) = (w[0], w[1]);
                    (cells.cell_center(CellIndex::new(a.ix, a.iy))
                        - cells.cell_center(CellIndex::new(b.ix, b.iy)))
                    .norm()
                })
                .sum(),
        )),
        Err(PlanError::NoPath { .. }) => Ok(None),
        Err(e) => Err(e.into()),
    }
}

/// Runs the navigator on `base` over `terrain` until the goal, a dead end or
/// `max_frames`. Returns the report and the navigator as it ended (for the picture).
///
/// This is the loop in one function; the same modules on the bus (camera and odometry in
/// the ISM, the maps in the LTM Manager, the base behind its Controller) take the same
/// steps in the same order and give the same report.
pub fn run(
    terrain: &HeightField,
    base: &mut dyn Base,
    params: NavParams,
    opts: &RunOptions,
) -> Result<(RunReport, Navigator), NavError> {
    let g = terrain.grid();
    let goal = Point2::new(
        opts.start.x + opts.goal_offset[0],
        opts.start.y + opts.goal_offset[1],
    );
    let truth = true_danger_map(terrain, &params)?;
    let true_path = true_map_path_m(
        &truth,
        params.beta,
        Point2::new(opts.start.x, opts.start.y),
        goal,
    )?;
    let mut camera = DepthCamera::new(params.camera.clone(), opts.seed)?;
    let mut odometry = DriftingOdometry::new(opts.start, opts.drift, opts.seed);
    let period = params.frame_period_s;
    let mount = params.mount;
    let mut map = PerceivedMap::new(params.clone(), g.origin(), g.resolution_m(), g.nx(), g.ny())?;
    let mut nav = Navigator::new(
        params,
        g.origin(),
        g.resolution_m(),
        g.nx(),
        g.ny(),
        opts.start,
        goal,
    )?;
    let mut report = RunReport {
        robot: base.name().to_string(),
        reached: false,
        reason: format!("no goal within {} frames", opts.max_frames),
        distance_m: 0.0,
        final_error_m: 0.0,
        estimate_error_m: 0.0,
        path: Vec::new(),
        estimated_path: Vec::new(),
        planned_path: Vec::new(),
        replans: 0,
        exploration_turns: 0,
        registrations: 0,
        frames: 0,
        loop_hz: 0.0,
        collisions: 0,
        falls: 0,
        untraversable_frames: 0,
        untraversable_at: Vec::new(),
        true_map_path_m: true_path,
    };
    let mut computing = 0.0;
    let mut planned = LastReplan::default();
    let mut pose = base.true_pose();
    for _ in 0..opts.max_frames {
        report.frames += 1;
        report.path.push([pose.x, pose.y]);
        let est = odometry.estimate();
        let t0 = Instant::now();
        let attitude = base.attitude();
        let image = camera.capture(terrain, &mount.camera_pose(&pose, &attitude));
        let inserted = map.insert(est, &attitude, &image);
        let est = inserted.estimate;
        report.estimated_path.push([est.x, est.y]);
        let step = nav.step(est, &inserted.changes);
        computing += t0.elapsed().as_secs_f64();
        planned.frame(nav.replans(), || {
            nav.path().iter().map(|p| [p.x, p.y]).collect()
        });
        match step {
            Ok(Command::Reached) => {
                report.reached = true;
                report.reason = "goal reached by the estimate".into();
                break;
            }
            Ok(Command::Drive {
                forward_mps,
                turn_rps,
            }) => {
                let m = base.drive(forward_mps, turn_rps, period);
                report.collisions += u64::from(m.collided);
                report.falls += u64::from(m.fell);
                report.distance_m += pose.distance(&m.pose);
                odometry.update(&pose, &m.pose);
                pose = m.pose;
            }
            Err(NavError::Plan(PlanError::NoPath { .. })) => {
                report.reason = "no traversable path to the goal on the map as perceived".into();
                break;
            }
            Err(e @ NavError::NoProgress { .. }) => {
                report.reason = e.to_string();
                break;
            }
            Err(e) => return Err(e),
        }
    }
    let est = map.corrected(odometry.estimate());
    report.registrations = map.registrations();
    report.final_error_m = (Point2::new(pose.x, pose.y) - goal).norm();
    report.estimate_error_m = pose.distance(&est);
    report.planned_path = planned.into_path();
    report.untraversable_at = untraversable_along(&truth, &report.path);
    report.untraversable_frames = report.untraversable_at.len() as u64;
    report.replans = nav.replans();
    report.exploration_turns = nav.exploration_turns();
    report.loop_hz = if computing > 0.0 {
        report.frames as f64 / computing
    } else {
        0.0
    };
    Ok((report, nav))
}

#[cfg(test)]
mod tests {
    use super::*;
    use tca_nav_danger_map::DangerParams;

    /// A flat field with a tall narrow wall across x = 1.0 m.
    fn walled() -> DangerMap {
        let (nx, ny) = (100, 60);
        let h = (0..nx * ny)
            .map(|i| if i % nx == 50 { 0.3 } else { 0.0 })
            .collect();
        let terrain = HeightField::new(Point2::new(0.0, 0.0), 0.02, nx, ny, h).unwrap();
        true_danger_map(
            &terrain,
            &NavParams::new(DangerParams::paper(0.3), crate::WHEELED_MOUNT, 0.2),
        )
        .unwrap()
    }

    #[test]
    fn a_wall_crossed_between_two_frames_is_counted() {
        let truth = walled();
        // Both poses on flat ground well clear of the wall, the way between them across it.
        let (a, b) = ([0.4, 0.6], [1.6, 0.6]);
        for p in [a, b] {
            let c = truth.cells().cell_at(Point2::new(p[0], p[1])).unwrap();
            assert!(truth.cell(c).is_traversable(), "{p:?} is not clear");
        }
        let hits = untraversable_along(&truth, &[a, b]);
        assert_eq!(hits.len(), 1, "{hits:?}");
        assert!(hits[0][0] > 0.4 && hits[0][0] < 1.0, "{hits:?}");
        // Alongside the wall, never across it: nothing.
        assert!(untraversable_along(&truth, &[[0.3, 0.2], [0.3, 1.0], [0.3, 0.6]]).is_empty());
    }

    #[test]
    fn the_planned_path_is_the_one_of_the_last_replan() {
        let kept = |frames: &[(u64, f64)]| {
            let mut last = LastReplan::default();
            for &(replans, x) in frames {
                last.frame(replans, || vec![[x, 0.0]]);
            }
            last.into_path()
        };
        assert_eq!(
            kept(&[(0, 0.0), (0, 1.0), (1, 2.0), (1, 3.0)]),
            vec![[2.0, 0.0]]
        );
        assert_eq!(kept(&[(0, 0.0), (0, 1.0)]), vec![[0.0, 0.0]]);
        assert!(kept(&[]).is_empty());
    }
}
