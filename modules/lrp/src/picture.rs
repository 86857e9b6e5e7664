//! Debugging pictures (§7.1): the configuration space with the search and the trajectory
//! over it, drawn on a [`Canvas`].
//!
//! In the C-space picture the shoulder runs left to right and the elbow bottom to top. A
//! cell's grey level is its requirement (black = the foot's lowest reach, white = its
//! highest); red cells are obstacles; blue tints the cells the search expanded; the path's
//! cells are green with the trajectory drawn in yellow, the start cyan and the goal magenta.

use tca_canvas::{Canvas, grey};

use crate::cspace::{CCell, CSpace};
use crate::planner::LegPlan;

/// Pixels per C-space cell in [`cspace_picture`].
pub const CELL_PIXELS: u32 = 8;

/// The configuration space, with the search and the trajectory of a plan if given.
pub fn cspace_picture(cs: &CSpace, plan: Option<&LegPlan>) -> Canvas {
    let (ns, ne) = cs.dims();
    let px = CELL_PIXELS as i64;
    let (w, h) = (ns as u32 * CELL_PIXELS, ne as u32 * CELL_PIXELS);
    let mut canvas = Canvas::new(w, h, [0, 0, 0]);
    let (z_min, z_max) = cs.z_range_m();
    let on_path: std::collections::HashSet<CCell> = plan
        .map(|p| p.cells.iter().copied().collect())
        .unwrap_or_default();
    for ie in 0..ne {
        for is in 0..ns {
            let c = CCell { is, ie };
            let mut colour = if cs.is_free(c) {
                grey(cs.required_m(c), z_min, z_max)
            } else {
                [150, 20, 20]
            };
            if plan.is_some_and(|p| p.expanded.get(cs.index(c)).copied().unwrap_or(false)) {
                colour = [colour[0] / 2, colour[1] / 2, colour[2] / 2 + 110];
            }
            if on_path.contains(&c) {
                colour = [40, 170, 60];
            }
            let y = (ne - 1 - ie) as i64 * px;
            canvas.fill_rect(is as i64 * px, y, px - 1, px - 1, colour);
        }
    }
    if let Some(plan) = plan {
        let (ds, de) = cs.cell_size_rad();
        let origin = cs.centre(CCell { is: 0, ie: 0 });
        let to_px = |s: f64, e: f64| {
            let x = ((s - origin.0) / ds + 0.5) * px as f64;
            let y = h as f64 - ((e - origin.1) / de + 0.5) * px as f64;
            (x, y)
        };
        for wp in plan.points.windows(2) {
            let (a, b) = (to_px(wp[0][0], wp[0][1]), to_px(wp[1][0], wp[1][1]));
            canvas.line(a, b, 1, [250, 220, 40]);
        }
        if let (Some(first), Some(last)) = (plan.points.first(), plan.points.last()) {
            let a = to_px(first[0], first[1]);
            let b = to_px(last[0], last[1]);
            canvas.marker(a, 3, [40, 220, 230]);
            canvas.marker(b, 3, [230, 40, 220]);
        }
    }
    canvas
}
