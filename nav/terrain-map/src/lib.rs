//! The terrain map of Chilian and Hirschmüller, "Stereo Camera Based Navigation of Mobile
//! Robots on Rough Terrain": a digital elevation model built from one local map per
//! camera frame, each cell remembering the number of the frame that last wrote it.
//!
//! A frame's points (world frame, placed with the robot's *estimated* pose) are binned
//! into cells keeping the highest point per cell; the local map then overwrites the
//! global one. Odometry drift makes old heights disagree with new ones, so the danger
//! computation reads the map through an age window ([`TerrainMap::view`]): the last
//! `recent_frames` (Δf, 20 in the paper) for cells that were traversable, the last
//! `older_frames` (Δf', 200) for cells that were not.

mod matcher;

pub use matcher::{MatchParams, Registration};

use nalgebra::{Point2, Point3};
use tca_nav_danger_map::{CellRect, HeightView};
use tca_robot::{CellIndex, Grid, GridError};

/// Why a terrain map could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TerrainMapError {
    /// The grid is not valid.
    #[error("the terrain map's grid is not valid: {0}")]
    Grid(#[from] GridError),
    /// The age windows are not ordered.
    #[error(
        "age windows recent = {recent} and older = {older} frames are not valid; give 1 <= recent <= older"
    )]
    BadAges {
        /// Δf.
        recent: u32,
        /// Δf'.
        older: u32,
    },
}

/// The age windows, in frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ageing {
    /// Δf: heights at most this many frames old are used for cells that were traversable.
    pub recent_frames: u32,
    /// Δf': the window for cells that were untraversable.
    pub older_frames: u32,
}

impl Ageing {
    /// The paper's windows: Δf = 20, Δf' = 200.
    pub const PAPER: Ageing = Ageing {
        recent_frames: 20,
        older_frames: 200,
    };
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Cell {
    height_m: f64,
    frame: u32,
}

/// The frame-aged height grid.
#[derive(Debug, Clone)]
pub struct TerrainMap {
    cells: Grid<Option<Cell>>,
    ageing: Ageing,
    /// Number of the last frame inserted (0 before any).
    frame: u32,
}

impl TerrainMap {
    /// An empty map of `nx` x `ny` cells of `resolution_m`, cell (0, 0) centred at `origin`.
    pub fn new(
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
        ageing: Ageing,
    ) -> Result<Self, TerrainMapError> {
        if ageing.recent_frames == 0 || ageing.recent_frames > ageing.older_frames {
            return Err(TerrainMapError::BadAges {
                recent: ageing.recent_frames,
                older: ageing.older_frames,
            });
        }
        Ok(Self {
            cells: Grid::filled(origin, resolution_m, nx, ny, None)?,
            ageing,
            frame: 0,
        })
    }

    /// Number of the last frame inserted.
    pub fn frame(&self) -> u32 {
        self.frame
    }

    /// The age windows.
    pub fn ageing(&self) -> Ageing {
        self.ageing
    }

    /// The grid's geometry: origin, resolution, columns, rows.
    pub fn geometry(&self) -> (Point2<f64>, f64, usize, usize) {
        (
            self.cells.origin(),
            self.cells.resolution_m(),
            self.cells.nx(),
            self.cells.ny(),
        )
    }

    /// Inserts one frame's local map from its points (world frame); points outside the grid
    /// are dropped. Returns the rectangle of cells written, `None` if none was.
    pub fn insert_frame(
        &mut self,
        points: impl IntoIterator<Item = Point3<f64>>,
    ) -> Option<CellRect> {
        self.frame += 1;
        let mut local: std::collections::HashMap<usize, f64> = std::collections::HashMap::new();
        for p in points {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                continue;
            }
            let Some(c) = self.cells.cell_at(Point2::new(p.x, p.y)) else {
                continue;
            };
            let Some(i) = self.cells.index_of(c) else {
                continue;
            };
            let h = local.entry(i).or_insert(f64::NEG_INFINITY);
            *h = h.max(p.z);
        }
        let mut rect: Option<CellRect> = None;
        let frame = self.frame;
        for (i, h) in local {
            let Some(c) = self.cells.cell_of_index(i) else {
                continue;
            };
            self.cells.cells_mut()[i] = Some(Cell { height_m: h, frame });
            rect = Some(match rect {
                None => CellRect {
                    x0: c.ix,
                    y0: c.iy,
                    x1: c.ix,
                    y1: c.iy,
                },
                Some(r) => CellRect {
                    x0: r.x0.min(c.ix),
                    y0: r.y0.min(c.iy),
                    x1: r.x1.max(c.ix),
                    y1: r.y1.max(c.iy),
                },
            });
        }
        rect
    }

    /// The height of a cell and the frame that wrote it.
    pub fn cell(&self, c: CellIndex) -> Option<(f64, u32)> {
        self.cells
            .get(c)
            .copied()
            .flatten()
            .map(|k| (k.height_m, k.frame))
    }

    /// The map as seen through an age window: heights written at most `max_age` frames
    /// before the last one.
    pub fn view(&self, max_age: u32) -> AgedView<'_> {
        AgedView {
            map: self,
            oldest: self.frame.saturating_sub(max_age),
        }
    }

    /// The window for traversable cells (Δf).
    pub fn recent(&self) -> AgedView<'_> {
        self.view(self.ageing.recent_frames)
    }

    /// The window for untraversable cells (Δf').
    pub fn older(&self) -> AgedView<'_> {
        self.view(self.ageing.older_frames)
    }

    /// Every height, regardless of age.
    pub fn all(&self) -> AgedView<'_> {
        AgedView {
            map: self,
            oldest: 0,
        }
    }
}

/// A [`TerrainMap`] seen through an age window.
#[derive(Debug, Clone, Copy)]
pub struct AgedView<'a> {
    map: &'a TerrainMap,
    oldest: u32,
}

impl HeightView for AgedView<'_> {
    fn height(&self, ix: isize, iy: isize) -> Option<f64> {
        if ix < 0 || iy < 0 {
            return None;
        }
        let c = self
            .map
            .cells
            .get(CellIndex::new(ix as usize, iy as usize))?
            .as_ref()?;
        (c.frame >= self.oldest).then_some(c.height_m)
    }
}
