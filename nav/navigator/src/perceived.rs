//! The map side of the loop: depth images into the frame-aged terrain map and the danger
//! map, patch by patch (what the LTM Manager keeps).

use nalgebra::Point2;
use tca_nav_danger_map::{CellDanger, DangerMap};
use tca_nav_sensing::{DepthImage, Pose2};
use tca_nav_terrain_map::TerrainMap;
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

/// The terrain map and the danger map built from depth images placed with the estimated
/// pose.
#[derive(Debug, Clone)]
pub struct PerceivedMap {
    params: NavParams,
    terrain: TerrainMap,
    danger: DangerMap,
    frames: u64,
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

    /// Inserts one depth image taken from the estimated pose `estimate` standing on
    /// `ground_m`, and recomputes the danger of the patch it saw plus a robot-sized border.
    /// Returns the cells whose danger or certainty changed.
    pub fn insert(
        &mut self,
        estimate: Pose2,
        ground_m: f64,
        image: &DepthImage,
    ) -> Vec<CellChange> {
        self.frames += 1;
        let cam = self.params.mount.camera_pose(&estimate, ground_m);
        let points = image.points(&self.params.camera, &cam, self.params.map_range_m);
        let Some(rect) = self.terrain.insert_frame(points) else {
            return Vec::new();
        };
        let changed = self
            .danger
            .update(rect, &self.terrain.recent(), &self.terrain.older());
        changed
            .into_iter()
            .map(|cell| CellChange {
                cell,
                danger: self.danger.cell(cell),
            })
            .collect()
    }
}
