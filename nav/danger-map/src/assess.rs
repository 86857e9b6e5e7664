//! The danger of one cell from the heights around it.

use nalgebra::{Matrix3, Vector3};
use tca_robot::{CellIndex, Grid, HeightField};

use crate::DangerParams;

/// Heights of a grid's cells as a danger computation sees them: `None` where unknown
/// (never seen, too old, or outside the grid).
pub trait HeightView {
    /// The height of cell `(ix, iy)`, metres.
    fn height(&self, ix: isize, iy: isize) -> Option<f64>;
}

impl HeightView for HeightField {
    fn height(&self, ix: isize, iy: isize) -> Option<f64> {
        (ix >= 0 && iy >= 0)
            .then(|| self.sample(CellIndex::new(ix as usize, iy as usize)))
            .flatten()
    }
}

impl HeightView for Grid<Option<f64>> {
    fn height(&self, ix: isize, iy: isize) -> Option<f64> {
        if ix < 0 || iy < 0 {
            return None;
        }
        self.get(CellIndex::new(ix as usize, iy as usize))
            .copied()
            .flatten()
    }
}

/// What the danger computation found for one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellDanger {
    /// Danger in `[0, 1]`, or `∞` if untraversable; 1 if unknown.
    pub danger: f64,
    /// Known fraction of the robot's circle around the cell, `[0, 1]`.
    pub certainty: f64,
    /// Slope of the fitted plane, radians (0 if unknown).
    pub slope_rad: f64,
    /// Standard deviation of the heights from the plane, m (0 if unknown).
    pub roughness_m: f64,
    /// Step height, m (0 if none or unknown).
    pub step_m: f64,
}

impl CellDanger {
    /// A cell of which nothing is known.
    pub const UNKNOWN: CellDanger = CellDanger {
        danger: 1.0,
        certainty: 0.0,
        slope_rad: 0.0,
        roughness_m: 0.0,
        step_m: 0.0,
    };

    /// Whether the robot's centre may stand in this cell.
    pub fn is_traversable(&self) -> bool {
        self.danger.is_finite()
    }
}

/// The cells of the robot's circle and of the step window, as offsets in cells.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Footprint {
    pub(crate) circle: Vec<(isize, isize)>,
    pub(crate) radius: isize,
    pub(crate) window_half: isize,
}

impl Footprint {
    pub(crate) fn new(params: &DangerParams, resolution_m: f64) -> Self {
        let r = params.radius_cells(resolution_m);
        let radius = r.floor() as isize;
        let mut circle = Vec::new();
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                if ((dx * dx + dy * dy) as f64) <= r * r {
                    circle.push((dx, dy));
                }
            }
        }
        Self {
            circle,
            radius,
            window_half: (params.step_window_cells / 2) as isize,
        }
    }
}

/// The temporary step height of cell `(ix, iy)`: the largest height difference to a cell
/// of the square step window around it that is both higher than `h_crit` and steeper than
/// `s_crit` as seen from the centre; `None` if there is none or the centre is unknown.
pub fn temporary_step(
    params: &DangerParams,
    resolution_m: f64,
    view: &impl HeightView,
    ix: isize,
    iy: isize,
) -> Option<f64> {
    let h0 = view.height(ix, iy)?;
    let half = (params.step_window_cells / 2) as isize;
    let tan_crit = params.s_crit_rad().tan();
    let mut best: Option<f64> = None;
    for dy in -half..=half {
        for dx in -half..=half {
            if dx == 0 && dy == 0 {
                continue;
            }
            let Some(h) = view.height(ix + dx, iy + dy) else {
                continue;
            };
            let dh = (h - h0).abs();
            if dh <= params.h_crit_m {
                continue;
            }
            let dist = resolution_m * ((dx * dx + dy * dy) as f64).sqrt();
            if dh > tan_crit * dist && best.is_none_or(|b| dh > b) {
                best = Some(dh);
            }
        }
    }
    best
}

/// The danger of cell `(ix, iy)` from the heights of `view` over the robot's circle and
/// the temporary step heights `step` of the circle's cells (see [`temporary_step`]).
pub fn assess_cell(
    params: &DangerParams,
    resolution_m: f64,
    view: &impl HeightView,
    step: impl Fn(isize, isize) -> Option<f64>,
    ix: isize,
    iy: isize,
) -> CellDanger {
    assess_with(
        params,
        &Footprint::new(params, resolution_m),
        resolution_m,
        view,
        step,
        ix,
        iy,
    )
}

pub(crate) fn assess_with(
    params: &DangerParams,
    fp: &Footprint,
    res: f64,
    view: &impl HeightView,
    step: impl Fn(isize, isize) -> Option<f64>,
    ix: isize,
    iy: isize,
) -> CellDanger {
    // Least-squares plane z = a x + b y + c over the known heights of the circle.
    let mut m = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    let mut known = 0usize;
    let (mut h_max, mut n_st) = (0.0_f64, 0usize);
    for &(dx, dy) in &fp.circle {
        if let Some(t) = step(ix + dx, iy + dy) {
            h_max = h_max.max(t);
            n_st += 1;
        }
        let Some(z) = view.height(ix + dx, iy + dy) else {
            continue;
        };
        known += 1;
        let v = Vector3::new(dx as f64 * res, dy as f64 * res, 1.0);
        m += v * v.transpose();
        rhs += v * z;
    }
    let certainty = known as f64 / fp.circle.len() as f64;
    let unknown = CellDanger {
        certainty,
        ..CellDanger::UNKNOWN
    };
    if certainty < params.min_certainty || known < 3 {
        return unknown;
    }
    let Some(coef) = m.lu().solve(&rhs) else {
        return unknown;
    };
    let (a, b, c) = (coef.x, coef.y, coef.z);
    let mut sq = 0.0;
    for &(dx, dy) in &fp.circle {
        if let Some(z) = view.height(ix + dx, iy + dy) {
            let e = z - (a * dx as f64 * res + b * dy as f64 * res + c);
            sq += e * e;
        }
    }
    let slope = (a * a + b * b).sqrt().atan();
    let rough = (sq / known as f64).sqrt();
    let h = if n_st == 0 {
        0.0
    } else {
        h_max.min(h_max * n_st as f64 / params.n_crit as f64)
    };
    let s_crit = params.s_crit_rad();
    let danger = if slope > s_crit || rough > params.r_crit_m || h > params.h_crit_m {
        f64::INFINITY
    } else {
        params.alpha[0] * slope / s_crit
            + params.alpha[1] * rough / params.r_crit_m
            + params.alpha[2] * h / params.h_crit_m
    };
    CellDanger {
        danger,
        certainty,
        slope_rad: slope,
        roughness_m: rough,
        step_m: h,
    }
}
