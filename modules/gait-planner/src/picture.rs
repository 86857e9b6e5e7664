//! Debugging pictures of the cost maps (§6.3, §7.1): one panel per map, +Y (the walking
//! direction) up. Top row: footfall, filtered footfall, body advance, scanner visibility
//! (black = cost 0, white = cost 1, dark red = unknown). Bottom row: leg reachability,
//! terrain elevation, clear region (grey = allowed, red = eliminated) and the composite cost
//! (scaled between its best and worst cell; red = eliminated) with the chosen cell in yellow.

use tca_canvas::{Canvas, Rgb, grey};
use tca_robot::Grid;

use crate::planner::StepPlan;

/// Pixels per cost map cell.
pub const CELL_PIXELS: u32 = 6;
const GAP: u32 = 8;
const UNKNOWN: Rgb = [110, 20, 20];
const ELIMINATED: Rgb = [200, 40, 40];
const ALLOWED: Rgb = [90, 90, 90];

fn panel<T>(grid: &Grid<T>, colour: impl Fn(&T) -> Rgb) -> Canvas {
    let (nx, ny) = (grid.nx() as u32, grid.ny() as u32);
    let px = i64::from(CELL_PIXELS);
    let mut c = Canvas::new(nx * CELL_PIXELS, ny * CELL_PIXELS, [0, 0, 0]);
    for (cell, v) in grid.iter() {
        let y = (i64::from(ny) - 1 - cell.iy as i64) * px;
        c.fill_rect(cell.ix as i64 * px, y, px, px, colour(v));
    }
    c
}

/// The mosaic of a step's cost maps.
pub fn cost_maps_picture(plan: &StepPlan) -> Canvas {
    let m = &plan.maps;
    let graded = |v: &f64| grey(*v, 0.0, 1.0);
    let binary = |v: &bool| if *v { ALLOWED } else { ELIMINATED };
    let finite: Vec<f64> = m.total.cells().iter().flatten().copied().collect();
    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut total = panel(&m.total, |v| match v {
        Some(t) => grey(*t, lo, hi.max(lo + 1e-9)),
        None => ELIMINATED,
    });
    let ny = m.total.ny() as i64;
    let px = i64::from(CELL_PIXELS);
    total.fill_rect(
        plan.cell.ix as i64 * px,
        (ny - 1 - plan.cell.iy as i64) * px,
        px,
        px,
        [250, 220, 40],
    );
    let panels = [
        panel(&m.footfall, |v| v.map_or(UNKNOWN, |c| grey(c, 0.0, 1.0))),
        panel(&m.filtered_footfall, graded),
        panel(&m.body_advance, graded),
        panel(&m.scanner_visibility, graded),
        panel(&m.reachable, binary),
        panel(&m.elevation_ok, binary),
        panel(&m.clear, binary),
        total,
    ];
    let (w, h) = (panels[0].width(), panels[0].height());
    let mut out = Canvas::new(4 * w + 3 * GAP, 2 * h + GAP, [255, 255, 255]);
    for (k, p) in panels.iter().enumerate() {
        let (col, row) = ((k % 4) as u32, (k / 4) as u32);
        out.blit(p, i64::from(col * (w + GAP)), i64::from(row * (h + GAP)));
    }
    out
}
