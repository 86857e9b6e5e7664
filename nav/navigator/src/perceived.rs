//! The map side of the loop: depth images into the frame-aged terrain map and the danger
//! map, patch by patch (what the LTM Manager keeps).

use nalgebra::{Isometry2, Point2, Point3, Translation2, UnitComplex, Vector2};
use tca_nav_danger_map::{CellDanger, DangerMap};
use tca_nav_sensing::{Attitude, DepthImage, Pose2};
use tca_nav_terrain_map::{Registration, TerrainMap};
use tca_robot::CellIndex;

use crate::{NavError, NavParams};

/// One cell whose danger or certainty an update changed, with its new assessment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellChange {
    /// The cell.
    pub cell: CellIndex,
    /// Its new danger and certainty.
    pub danger: CellDanger,
}

/// What inserting a frame did.
#[derive(Debug, Clone, PartialEq)]
pub struct Inserted {
    /// The cells whose danger or certainty changed.
    pub changes: Vec<CellChange>,
    /// The pose the frame was placed with: the odometry's estimate, corrected by the LTM
    /// Matcher when it is on.
    pub estimate: Pose2,
    /// This frame's registration, when the matcher found one.
    pub registration: Option<Registration>,
}

/// The terrain map and the danger map built from depth images placed with the estimated
/// pose (corrected by the LTM Matcher when it is on).
#[derive(Debug, Clone)]
pub struct PerceivedMap {
    params: NavParams,
    terrain: TerrainMap,
    danger: DangerMap,
    frames: u64,
    /// Correction of odometry estimates, world frame (identity without the matcher).
    correction: Isometry2<f64>,
    registrations: u64,
}

impl PerceivedMap {
    /// An empty map of `nx` x `ny` cells of `resolution_m`, cell (0, 0) centred at
    /// `origin`.
    pub fn new(
        params: NavParams,
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
    ) -> Result<Self, NavError> {
        let terrain = TerrainMap::new(origin, resolution_m, nx, ny, params.ageing)?;
        let danger = DangerMap::new(params.danger.clone(), origin, resolution_m, nx, ny)?;
        Ok(Self {
            params,
            terrain,
            danger,
            frames: 0,
            correction: Isometry2::identity(),
            registrations: 0,
        })
    }

    /// The danger map as perceived so far.
    pub fn danger(&self) -> &DangerMap {
        &self.danger
    }

    /// The frame-aged terrain map.
    pub fn terrain(&self) -> &TerrainMap {
        &self.terrain
    }

    /// Frames inserted so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Frames the LTM Matcher corrected.
    pub fn registrations(&self) -> u64 {
        self.registrations
    }

    /// An odometry estimate corrected as the map corrects them so far.
    pub fn corrected(&self, estimate: Pose2) -> Pose2 {
        let p = self.correction * Point2::new(estimate.x, estimate.y);
        Pose2::new(
            p.x,
            p.y,
            tca_nav_sensing::wrap(estimate.yaw + self.correction.rotation.angle()),
        )
    }

    /// Inserts one depth image taken from the odometry's estimate `estimate` with the
    /// measured height and tilt `attitude`, and recomputes the danger of the patch it saw plus a robot-sized border.
    /// With the matcher on, the frame is first registered against the map so far and placed
    /// with the corrected pose.
    pub fn insert(&mut self, estimate: Pose2, attitude: &Attitude, image: &DepthImage) -> Inserted {
        self.frames += 1;
        let mut pose = self.corrected(estimate);
        let cam = self.params.mount.camera_pose(&pose, attitude);
        let mut points = image.points(&self.params.camera, &cam, self.params.map_range_m);
        let mut registration = None;
        if let Some(m) = &self.params.matcher {
            let pivot = Point2::new(pose.x, pose.y);
            if let Some(r) = self.terrain.register(&points, pivot, m) {
                let step = r.scaled(m.gain);
                for p in &mut points {
                    let q = step.apply(pivot, Point2::new(p.x, p.y));
                    *p = Point3::new(q.x, q.y, p.z);
                }
                let delta = Isometry2::from_parts(
                    Translation2::from(pivot.coords + Vector2::new(step.dx_m, step.dy_m)),
                    UnitComplex::new(step.dyaw_rad),
                ) * Isometry2::from_parts(
                    Translation2::from(-pivot.coords),
                    UnitComplex::identity(),
                );
                self.correction = delta * self.correction;
                pose = self.corrected(estimate);
                self.registrations += 1;
                registration = Some(r);
            }
        }
        let changes = match self.terrain.insert_frame(points) {
            None => Vec::new(),
            Some(rect) => self
                .danger
                .update(rect, &self.terrain.recent(), &self.terrain.older())
                .into_iter()
                .map(|cell| CellChange {
                    cell,
                    danger: self.danger.cell(cell),
                })
                .collect(),
        };
        Inserted {
            changes,
            estimate: pose,
            registration,
        }
    }
}
