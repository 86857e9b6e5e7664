//! The planner's trees and path as a picture over the elevation map.

use std::path::Path;

use tca_canvas::{Canvas, Rgb, grey};

use crate::rrt::Plan;
use crate::terrain::Terrain;

const START_TREE: Rgb = [255, 255, 255];
const GOAL_TREE: Rgb = [120, 200, 255];
const PATH: Rgb = [40, 220, 60];
const FEET: Rgb = [250, 160, 30];

/// The elevation map in grey (dark low, light high) with both trees' edges (the start's
/// white, the goal's light blue), the path in green and the planned footholds in orange,
/// `pixels_per_m` pixels a metre, north up.
pub fn draw_plan(
    terrain: &Terrain,
    plan: Option<&Plan>,
    trees: &[(nalgebra::Point2<f64>, nalgebra::Point2<f64>)],
    pixels_per_m: f64,
) -> Canvas {
    let field = terrain.height_field();
    let (lo, hi) = terrain.extent();
    let w = ((hi.x - lo.x) * pixels_per_m).ceil().max(1.0) as u32;
    let h = ((hi.y - lo.y) * pixels_per_m).ceil().max(1.0) as u32;
    let mut c = Canvas::new(w, h, [0, 0, 0]);
    let (zmin, zmax) = (
        field.min_height_m(),
        field.max_height_m().max(field.min_height_m() + 1e-6),
    );
    for py in 0..h {
        for px in 0..w {
            let x = lo.x + (f64::from(px) + 0.5) / pixels_per_m;
            let y = hi.y - (f64::from(py) + 0.5) / pixels_per_m;
            let g = grey(field.height_at(x, y), zmin, zmax);
            let dim = |v: u8| (f64::from(v) * 0.8) as u8;
            c.set(
                i64::from(px),
                i64::from(py),
                [dim(g[0]), dim(g[1]), dim(g[2])],
            );
        }
    }
    let to_px =
        |p: nalgebra::Point2<f64>| ((p.x - lo.x) * pixels_per_m, (hi.y - p.y) * pixels_per_m);
    for (a, b) in trees {
        c.line(to_px(*a), to_px(*b), 1, START_TREE);
    }
    if let Some(plan) = plan {
        for (a, b) in &plan.start_tree {
            c.line(to_px(*a), to_px(*b), 1, START_TREE);
        }
        for (a, b) in &plan.goal_tree {
            c.line(to_px(*a), to_px(*b), 1, GOAL_TREE);
        }
        for p in &plan.postures {
            for f in &p.feet {
                c.marker(to_px(nalgebra::Point2::new(f.x, f.y)), 1, FEET);
            }
        }
        for w in plan.postures.windows(2) {
            c.line(to_px(w[0].body.xy()), to_px(w[1].body.xy()), 3, PATH);
        }
        if let (Some(s), Some(g)) = (plan.postures.first(), plan.postures.last()) {
            c.circle(to_px(s.body.xy()), 6.0, 2, PATH);
            c.marker(to_px(g.body.xy()), 5, PATH);
        }
    }
    c
}

/// Writes [`draw_plan`] to a PNG file.
pub fn write_plan_png(
    path: impl AsRef<Path>,
    terrain: &Terrain,
    plan: Option<&Plan>,
    pixels_per_m: f64,
) -> Result<(), tca_canvas::CanvasError> {
    draw_plan(terrain, plan, &[], pixels_per_m).write_png(path)
}
