//! The danger map: a grid of [`CellDanger`] kept up to date patch by patch.

use nalgebra::Point2;
use tca_robot::{CellIndex, Grid};

use crate::assess::{Footprint, assess_with, temporary_step};
use crate::{CellDanger, DangerError, DangerParams, HeightView};

/// A rectangle of cells, both corners included.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellRect {
    /// Lowest column.
    pub x0: usize,
    /// Lowest row.
    pub y0: usize,
    /// Highest column.
    pub x1: usize,
    /// Highest row.
    pub y1: usize,
}

impl CellRect {
    /// The rectangle grown by `n` cells on every side and clipped to an `nx` x `ny` grid.
    pub fn grown(&self, n: usize, nx: usize, ny: usize) -> CellRect {
        CellRect {
            x0: self.x0.saturating_sub(n),
            y0: self.y0.saturating_sub(n),
            x1: (self.x1 + n).min(nx - 1),
            y1: (self.y1 + n).min(ny - 1),
        }
    }

    fn width(&self) -> usize {
        self.x1 + 1 - self.x0
    }

    fn height(&self) -> usize {
        self.y1 + 1 - self.y0
    }

    fn contains(&self, ix: isize, iy: isize) -> bool {
        ix >= self.x0 as isize
            && iy >= self.y0 as isize
            && ix <= self.x1 as isize
            && iy <= self.y1 as isize
    }
}

/// The danger map of a grid.
#[derive(Debug, Clone)]
pub struct DangerMap {
    params: DangerParams,
    footprint: Footprint,
    cells: Grid<CellDanger>,
}

impl DangerMap {
    /// A map of `nx` x `ny` cells of `resolution_m`, cell (0, 0) centred at `origin`, all
    /// unknown.
    pub fn new(
        params: DangerParams,
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
    ) -> Result<Self, DangerError> {
        params.validate()?;
        let cells = Grid::filled(origin, resolution_m, nx, ny, CellDanger::UNKNOWN)?;
        Ok(Self {
            footprint: Footprint::new(&params, resolution_m),
            params,
            cells,
        })
    }

    /// The map of every cell of a grid whose heights `view` gives (e.g. the true terrain).
    pub fn from_view(
        params: DangerParams,
        origin: Point2<f64>,
        resolution_m: f64,
        nx: usize,
        ny: usize,
        view: &impl HeightView,
    ) -> Result<Self, DangerError> {
        let mut map = Self::new(params, origin, resolution_m, nx, ny)?;
        let all = CellRect {
            x0: 0,
            y0: 0,
            x1: nx - 1,
            y1: ny - 1,
        };
        map.update(all, view, view);
        Ok(map)
    }

    /// The parameters.
    pub fn params(&self) -> &DangerParams {
        &self.params
    }

    /// The cells.
    pub fn cells(&self) -> &Grid<CellDanger> {
        &self.cells
    }

    /// One cell (unknown outside the map).
    pub fn cell(&self, c: CellIndex) -> CellDanger {
        self.cells.get(c).copied().unwrap_or(CellDanger::UNKNOWN)
    }

    /// The robot's radius in cells, rounded down: the border an update adds to its patch.
    pub fn border_cells(&self) -> usize {
        self.footprint.radius as usize
    }

    /// Recomputes the cells of `patch` plus a border of the robot's radius. Cells that were
    /// untraversable read their heights from `older`, the others from `recent`. Returns
    /// the cells whose danger or certainty changed.
    pub fn update(
        &mut self,
        patch: CellRect,
        recent: &impl HeightView,
        older: &impl HeightView,
    ) -> Vec<CellIndex> {
        let (nx, ny) = (self.cells.nx(), self.cells.ny());
        let patch = CellRect {
            x0: patch.x0.min(nx - 1),
            y0: patch.y0.min(ny - 1),
            x1: patch.x1.min(nx - 1),
            y1: patch.y1.min(ny - 1),
        };
        let border = self.footprint.radius as usize;
        let region = patch.grown(border, nx, ny);
        let any_blocked = (region.y0..=region.y1).any(|iy| {
            (region.x0..=region.x1).any(|ix| !self.cell(CellIndex::new(ix, iy)).is_traversable())
        });
        let step_rect = region.grown(border, nx, ny);
        let res = self.cells.resolution_m();
        // Heights copied once into a dense patch: the circles and windows read them many
        // times each.
        let heights_rect = step_rect.grown(self.footprint.window_half as usize, nx, ny);
        let recent = &Dense::copy(recent, heights_rect);
        let older_dense = any_blocked.then(|| Dense::copy(older, heights_rect));
        let recent_steps = StepPatch::compute(&self.params, res, recent, step_rect);
        let older_steps = older_dense.as_ref().map(|older| {
            (
                older,
                StepPatch::compute(&self.params, res, older, step_rect),
            )
        });
        let mut changed = Vec::new();
        for iy in region.y0..=region.y1 {
            for ix in region.x0..=region.x1 {
                let c = CellIndex::new(ix, iy);
                let before = self.cell(c);
                let (ixs, iys) = (ix as isize, iy as isize);
                let after = match (&older_steps, before.is_traversable()) {
                    (Some((older, steps)), false) => assess_with(
                        &self.params,
                        &self.footprint,
                        res,
                        *older,
                        |x, y| steps.at(x, y),
                        ixs,
                        iys,
                    ),
                    _ => assess_with(
                        &self.params,
                        &self.footprint,
                        res,
                        recent,
                        |x, y| recent_steps.at(x, y),
                        ixs,
                        iys,
                    ),
                };
                if after.danger != before.danger || after.certainty != before.certainty {
                    changed.push(c);
                }
                if let Some(slot) = self.cells.get_mut(c) {
                    *slot = after;
                }
            }
        }
        changed
    }
}

/// Temporary step heights over a rectangle.
struct StepPatch {
    rect: CellRect,
    steps: Vec<Option<f64>>,
}

impl StepPatch {
    fn compute(params: &DangerParams, res: f64, view: &impl HeightView, rect: CellRect) -> Self {
        let mut steps = Vec::with_capacity(rect.width() * rect.height());
        for iy in rect.y0..=rect.y1 {
            for ix in rect.x0..=rect.x1 {
                steps.push(temporary_step(params, res, view, ix as isize, iy as isize));
            }
        }
        Self { rect, steps }
    }

    fn at(&self, ix: isize, iy: isize) -> Option<f64> {
        if !self.rect.contains(ix, iy) {
            return None;
        }
        let i = (iy as usize - self.rect.y0) * self.rect.width() + (ix as usize - self.rect.x0);
        self.steps[i]
    }
}

/// Heights of a rectangle copied out of a [`HeightView`] (NaN where unknown).
struct Dense {
    rect: CellRect,
    h: Vec<f64>,
}

impl Dense {
    fn copy(view: &impl HeightView, rect: CellRect) -> Self {
        let mut h = Vec::with_capacity(rect.width() * rect.height());
        for iy in rect.y0..=rect.y1 {
            for ix in rect.x0..=rect.x1 {
                h.push(view.height(ix as isize, iy as isize).unwrap_or(f64::NAN));
            }
        }
        Self { rect, h }
    }
}

impl HeightView for Dense {
    #[inline]
    fn height(&self, ix: isize, iy: isize) -> Option<f64> {
        if !self.rect.contains(ix, iy) {
            return None;
        }
        let i = (iy as usize - self.rect.y0) * self.rect.width() + (ix as usize - self.rect.x0);
        let v = self.h[i];
        (!v.is_nan()).then_some(v)
    }
}
