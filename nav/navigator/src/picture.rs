//! A picture of the danger map with the planned, estimated and driven paths.

use std::path::Path;

use tca_canvas::{Canvas, CanvasError, Rgb};
use tca_nav_danger_map::CellDanger;
use tca_robot::Grid;

use crate::RunReport;

/// Writes a PNG of the danger map `cells` (green safe to red barely traversable, black untraversable,
/// grey by how little is known) with the planned path (blue), the estimated path (yellow)
/// and the true path (white), 3 pixels per cell, north up.
pub fn write_picture(
    cells: &Grid<CellDanger>,
    report: &RunReport,
    path: impl AsRef<Path>,
) -> Result<(), CanvasError> {
    let scale = 3i64;
    let (w, h) = (cells.nx() as i64 * scale, cells.ny() as i64 * scale);
    let mut canvas = Canvas::new(w as u32, h as u32, [128, 128, 128]);
    for (c, d) in cells.iter() {
        let color: Rgb = if d.certainty == 0.0 {
            [110, 110, 110]
        } else if d.danger.is_infinite() {
            [0, 0, 0]
        } else {
            let t = d.danger.clamp(0.0, 1.0);
            let k = 0.4 + 0.6 * d.certainty;
            [
                (255.0 * t * k) as u8,
                (255.0 * (1.0 - t) * k) as u8,
                (40.0 * k) as u8,
            ]
        };
        let (x, y) = (c.ix as i64 * scale, h - (c.iy as i64 + 1) * scale);
        canvas.fill_rect(x, y, scale, scale, color);
    }
    let origin = cells.origin();
    let res = cells.resolution_m();
    let to_px = |p: &[f64; 2]| {
        (
            ((p[0] - origin.x) / res + 0.5) * scale as f64,
            h as f64 - ((p[1] - origin.y) / res + 0.5) * scale as f64,
        )
    };
    let draw = |canvas: &mut Canvas, pts: &[[f64; 2]], color: Rgb| {
        for w in pts.windows(2) {
            canvas.line(to_px(&w[0]), to_px(&w[1]), 1, color);
        }
    };
    draw(&mut canvas, &report.planned_path, [40, 90, 255]);
    draw(&mut canvas, &report.estimated_path, [255, 230, 0]);
    draw(&mut canvas, &report.path, [255, 255, 255]);
    if let Some(g) = report.planned_path.last() {
        canvas.circle(to_px(g), 4.0, 1, [40, 90, 255]);
    }
    canvas.write_png(path)
}
