//! The planner's trees and path as a picture over the elevation map.

use std::path::Path;

use nalgebra::Point2;
use tca_canvas::{Canvas, Rgb, grey};

use crate::rrt::Plan;
use crate::terrain::Terrain;

const START_TREE: Rgb = [255, 255, 255];
const GOAL_TREE: Rgb = [120, 200, 255];
const PATH: Rgb = [40, 220, 60];
const FEET: Rgb = [250, 160, 30];

/// What [`draw_route`] draws over the elevation map, world XY in metres.
#[derive(Debug, Clone, Copy, Default)]
pub struct RouteDrawing<'a> {
    /// The start tree's edges.
    pub start_tree: &'a [(Point2<f64>, Point2<f64>)],
    /// The goal tree's edges.
    pub goal_tree: &'a [(Point2<f64>, Point2<f64>)],
    /// The body's path, posture by posture.
    pub path: &'a [Point2<f64>],
    /// The planned footholds.
    pub footholds: &'a [Point2<f64>],
}

/// The elevation map in grey (dark low, light high) with both trees' edges (the start's
/// white, the goal's light blue), the path in green and the planned footholds in orange,
/// `pixels_per_m` pixels a metre, north up.
pub fn draw_route(terrain: &Terrain, route: &RouteDrawing<'_>, pixels_per_m: f64) -> Canvas {
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
    let to_px = |p: Point2<f64>| ((p.x - lo.x) * pixels_per_m, (hi.y - p.y) * pixels_per_m);
    for (a, b) in route.start_tree {
        c.line(to_px(*a), to_px(*b), 1, START_TREE);
    }
    for (a, b) in route.goal_tree {
        c.line(to_px(*a), to_px(*b), 1, GOAL_TREE);
    }
    for f in route.footholds {
        c.marker(to_px(*f), 1, FEET);
    }
    for w in route.path.windows(2) {
        c.line(to_px(w[0]), to_px(w[1]), 3, PATH);
    }
    if let (Some(s), Some(g)) = (route.path.first(), route.path.last()) {
        c.circle(to_px(*s), 6.0, 2, PATH);
        c.marker(to_px(*g), 5, PATH);
    }
    c
}

/// [`draw_route`] of a plan (or of nothing but the terrain and `trees`).
pub fn draw_plan(
    terrain: &Terrain,
    plan: Option<&Plan>,
    trees: &[(Point2<f64>, Point2<f64>)],
    pixels_per_m: f64,
) -> Canvas {
    let path: Vec<Point2<f64>> = plan
        .map(|p| p.postures.iter().map(|q| q.body.xy()).collect())
        .unwrap_or_default();
    let footholds: Vec<Point2<f64>> = plan
        .map(|p| {
            p.postures
                .iter()
                .flat_map(|q| q.feet.iter().map(|f| Point2::new(f.x, f.y)))
                .collect()
        })
        .unwrap_or_default();
    let mut start_tree = trees.to_vec();
    if let Some(p) = plan {
        start_tree.extend_from_slice(&p.start_tree);
    }
    let route = RouteDrawing {
        start_tree: &start_tree,
        goal_tree: plan.map(|p| p.goal_tree.as_slice()).unwrap_or_default(),
        path: &path,
        footholds: &footholds,
    };
    draw_route(terrain, &route, pixels_per_m)
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
