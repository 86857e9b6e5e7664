//! CG-space built lazily, region by region, with a cap on the regions held.

use rustc_hash::{FxHashMap, FxHashSet};
use std::sync::Arc;

use tca_robot::HeightField;

use crate::error::CgError;
use crate::footmap::FootMap;
use crate::grid::{CgCell, CgGrid};
use crate::robot::{CgParams, CgRobot};
use crate::validity::{Verdict, assess};

/// Side of a region in cells (x and y); a region holds every heading bin.
pub const REGION_CELLS: i32 = 16;

const UNKNOWN: u8 = 0;
const VALID: u8 = 1;
const INVALID: u8 = 2;

#[derive(Debug, Clone)]
struct Region {
    cells: Vec<u8>,
    used: u64,
}

/// The key of a region: its column and row of regions.
pub type RegionKey = (i32, i32);

/// CG-space for one robot on one terrain: the foot map, and the CG cells' validity computed
/// on demand. Regions of [`REGION_CELLS`]² cells (all headings) are materialised when first
/// touched and their cells evaluated when first asked; with a cap, the least recently used
/// region is dropped beyond it (and recomputed if needed again). Cells marked invalid from
/// outside stay marked.
#[derive(Debug, Clone)]
pub struct CgSpace {
    robot: Arc<CgRobot>,
    grid: CgGrid,
    foot: Arc<FootMap>,
    regions: FxHashMap<RegionKey, Region>,
    marked: FxHashSet<CgCell>,
    max_regions: Option<usize>,
    tick: u64,
    evaluations: u64,
    materialised: u64,
}

impl CgSpace {
    /// CG-space for a robot on a terrain, covering the terrain's rectangle.
    pub fn new(robot: Arc<CgRobot>, terrain: &HeightField) -> Result<Self, CgError> {
        let (min, max) = terrain.extent();
        let grid = CgGrid::covering(min, max, robot.cell_m, robot.theta_bins())?;
        let foot = FootMap::build(&grid, terrain, robot.params.traction_slope_rad);
        Ok(Self::with_foot_map(robot, grid, Arc::new(foot)))
    }

    /// CG-space over a given grid and foot map (workers share one foot map).
    pub fn with_foot_map(robot: Arc<CgRobot>, grid: CgGrid, foot: Arc<FootMap>) -> Self {
        CgSpace {
            robot,
            grid,
            foot,
            regions: FxHashMap::default(),
            marked: FxHashSet::default(),
            max_regions: None,
            tick: 0,
            evaluations: 0,
            materialised: 0,
        }
    }

    /// Builds the robot's tables and the CG-space in one go.
    pub fn for_model(
        model: &tca_legged_model::RobotModel,
        terrain: &HeightField,
        params: CgParams,
    ) -> Result<Self, CgError> {
        let robot = CgRobot::new(model, terrain.grid().resolution_m(), params)?;
        Self::new(Arc::new(robot), terrain)
    }

    /// Holds at most `regions` regions at once (the oldest dropped beyond), `None` for no cap.
    pub fn with_region_cap(mut self, regions: Option<usize>) -> Self {
        self.max_regions = regions.map(|r| r.max(1));
        self
    }

    /// The grid.
    pub fn grid(&self) -> &CgGrid {
        &self.grid
    }

    /// The robot's tables.
    pub fn robot(&self) -> &Arc<CgRobot> {
        &self.robot
    }

    /// The foot map.
    pub fn foot(&self) -> &FootMap {
        &self.foot
    }

    /// The foot map, shared.
    pub fn foot_shared(&self) -> Arc<FootMap> {
        self.foot.clone()
    }

    /// The region holding a cell.
    pub fn region_of(c: CgCell) -> RegionKey {
        (c.ix.div_euclid(REGION_CELLS), c.iy.div_euclid(REGION_CELLS))
    }

    /// CG cells evaluated so far (a region dropped and rebuilt counts again).
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    /// Regions materialised so far.
    pub fn regions_materialised(&self) -> u64 {
        self.materialised
    }

    /// Regions held now.
    pub fn regions_held(&self) -> usize {
        self.regions.len()
    }

    fn slot(&self, c: CgCell) -> usize {
        let lx = c.ix.rem_euclid(REGION_CELLS);
        let ly = c.iy.rem_euclid(REGION_CELLS);
        ((usize::from(c.it) * REGION_CELLS as usize) + ly as usize) * REGION_CELLS as usize
            + lx as usize
    }

    fn region(&mut self, key: RegionKey) -> &mut Region {
        self.tick += 1;
        let tick = self.tick;
        if !self.regions.contains_key(&key) {
            if let Some(cap) = self.max_regions {
                while self.regions.len() >= cap {
                    let oldest = self
                        .regions
                        .iter()
                        .min_by_key(|(_, r)| r.used)
                        .map(|(k, _)| *k);
                    match oldest {
                        Some(k) => self.regions.remove(&k),
                        None => break,
                    };
                }
            }
            self.materialised += 1;
            let n = (REGION_CELLS * REGION_CELLS) as usize * usize::from(self.grid.theta_bins);
            self.regions.insert(
                key,
                Region {
                    cells: vec![UNKNOWN; n],
                    used: tick,
                },
            );
        }
        let r = self.regions.get_mut(&key).expect("inserted above");
        r.used = tick;
        r
    }

    /// Whether a CG cell is valid (evaluated now if it was not yet).
    pub fn is_valid(&mut self, c: CgCell) -> bool {
        if !self.grid.contains(c) || self.marked.contains(&c) {
            return false;
        }
        let slot = self.slot(c);
        let key = Self::region_of(c);
        let state = self.region(key).cells[slot];
        match state {
            VALID => true,
            INVALID => false,
            _ => {
                let valid = assess(&self.robot, &self.grid, &self.foot, c).is_valid();
                self.evaluations += 1;
                self.region(key).cells[slot] = if valid { VALID } else { INVALID };
                valid
            }
        }
    }

    /// Why a cell is valid or not (always evaluated afresh).
    pub fn verdict(&self, c: CgCell) -> Verdict {
        if self.marked.contains(&c) {
            return Verdict::Marked;
        }
        assess(&self.robot, &self.grid, &self.foot, c)
    }

    /// Evaluates every cell of a region.
    pub fn materialise(&mut self, key: RegionKey) {
        for it in 0..self.grid.theta_bins {
            for ly in 0..REGION_CELLS {
                for lx in 0..REGION_CELLS {
                    let c = CgCell::new(key.0 * REGION_CELLS + lx, key.1 * REGION_CELLS + ly, it);
                    if self.grid.contains(c) {
                        self.is_valid(c);
                    }
                }
            }
        }
    }

    /// Marks a cell invalid (the foot-level search's feedback).
    pub fn mark_invalid(&mut self, c: CgCell) {
        self.marked.insert(c);
    }

    /// Takes a mark back: the cell is judged by its own verdict again.
    pub fn unmark(&mut self, c: CgCell) {
        self.marked.remove(&c);
    }

    /// Marks a foot cell unusable (a foothold found unusable by other means, such as a
    /// swing to it that cannot be carried out): the CG cells' verdicts are evaluated again.
    pub fn forbid_foot(&mut self, ix: i32, iy: i32) {
        if self.foot.valid(ix, iy) {
            Arc::make_mut(&mut self.foot).forbid(ix, iy);
            self.regions.clear();
        }
    }

    /// The cells marked invalid from outside.
    pub fn marked(&self) -> &FxHashSet<CgCell> {
        &self.marked
    }
}
