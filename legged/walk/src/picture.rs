//! The walk's map picture: the terrain from above (grey by height, light high), the body's
//! path, every foothold (one colour per leg), the start and the goal, and a legend.

use tca_canvas::{Canvas, Rgb, grey};
use tca_robot::HeightField;

use crate::report::LeggedWalkReport;

/// Longest side of the picture's map area, pixels.
const MAP_PX: f64 = 1400.0;
/// Height of the legend strip under the map, pixels.
const LEGEND_PX: u32 = 60;

const PATH: Rgb = [220, 30, 30];
const START: Rgb = [30, 160, 30];
const GOAL: Rgb = [30, 60, 220];
const LEG_COLOURS: [Rgb; 8] = [
    [230, 120, 0],
    [0, 170, 200],
    [200, 0, 200],
    [240, 200, 0],
    [0, 200, 90],
    [120, 70, 255],
    [255, 90, 150],
    [130, 200, 30],
];

/// Draws the walk over its terrain.
pub fn map_picture(terrain: &HeightField, report: &LeggedWalkReport) -> Canvas {
    let (lo, hi) = terrain.extent();
    let (w_m, h_m) = ((hi.x - lo.x).max(1e-6), (hi.y - lo.y).max(1e-6));
    let scale = MAP_PX / w_m.max(h_m);
    let (w, h) = ((w_m * scale).ceil() as u32, (h_m * scale).ceil() as u32);
    let mut c = Canvas::new(w.max(200), h + LEGEND_PX, [255, 255, 255]);
    let (zmin, zmax) = (
        terrain.min_height_m(),
        terrain.max_height_m().max(terrain.min_height_m() + 1e-6),
    );
    for py in 0..h {
        for px in 0..w {
            let x = lo.x + (f64::from(px) + 0.5) / scale;
            let y = hi.y - (f64::from(py) + 0.5) / scale;
            c.set(
                i64::from(px),
                i64::from(py),
                grey(terrain.height_at(x, y), zmin, zmax),
            );
        }
    }
    let to_px = |x: f64, y: f64| ((x - lo.x) * scale, (hi.y - y) * scale);
    // Footholds under the path.
    let mut legs: Vec<&str> = Vec::new();
    for (leg, p) in &report.footholds {
        let i = legs.iter().position(|l| l == leg).unwrap_or_else(|| {
            legs.push(leg);
            legs.len() - 1
        });
        c.circle(
            to_px(p[0], p[1]),
            3.0,
            2,
            LEG_COLOURS[i % LEG_COLOURS.len()],
        );
    }
    for pair in report.states.windows(2) {
        let (a, b) = (&pair[0].body, &pair[1].body);
        c.line(to_px(a[0], a[1]), to_px(b[0], b[1]), 2, PATH);
    }
    c.marker(to_px(report.start[0], report.start[1]), 5, START);
    c.marker(to_px(report.goal[0], report.goal[1]), 5, GOAL);
    // Legend.
    let y0 = i64::from(h) + 8;
    let status = if report.reached {
        "reached"
    } else {
        "not reached"
    };
    c.text(
        8,
        y0,
        &format!(
            "{} on {}: {status}, {} steps, {} falls, {} collisions; heights {zmin:.2}..{zmax:.2} m",
            report.robot, report.terrain, report.steps, report.falls, report.collisions
        ),
        2,
        [0, 0, 0],
    );
    let mut x = 8;
    for (text, colour) in [("path", PATH), ("start", START), ("goal", GOAL)] {
        c.fill_rect(x, y0 + 26, 12, 12, colour);
        c.text(x + 16, y0 + 26, text, 2, [0, 0, 0]);
        x += 16 + 14 * text.len() as i64 + 16;
    }
    for (i, leg) in legs.iter().enumerate() {
        let colour = LEG_COLOURS[i % LEG_COLOURS.len()];
        c.circle((x as f64 + 6.0, y0 as f64 + 32.0), 5.0, 2, colour);
        c.text(x + 16, y0 + 26, leg, 2, [0, 0, 0]);
        x += 16 + 12 * leg.len() as i64 + 16;
    }
    c
}

/// The RRT-Connect planner's plans of a walk over the terrain: every plan's trees, path
/// and footholds (see `tca_rrt::draw_route`), at 100 pixels a metre or less for a large
/// terrain.
pub fn route_picture(
    terrain: &std::sync::Arc<HeightField>,
    foot_radius_m: f64,
    routes: &[crate::messages::RoutePlanned],
) -> Canvas {
    use tca_rrt::nalgebra::Point2;
    let p = |x: f64, y: f64| Point2::new(x, y);
    let edges = |pick: fn(&crate::messages::RoutePlanned) -> &Vec<[f64; 4]>| {
        routes
            .iter()
            .flat_map(|r| pick(r).iter().map(|v| (p(v[0], v[1]), p(v[2], v[3]))))
            .collect::<Vec<_>>()
    };
    let (start_tree, goal_tree) = (edges(|r| &r.start_tree), edges(|r| &r.goal_tree));
    // Each plan's path up to where the next plan starts.
    let mut path: Vec<Point2<f64>> = Vec::new();
    for r in routes {
        let from = r.path.first().map(|q| p(q[0], q[1]));
        if let Some(from) = from {
            let cut = path
                .iter()
                .enumerate()
                .min_by(|a, b| {
                    (a.1 - from)
                        .norm()
                        .partial_cmp(&(b.1 - from).norm())
                        .unwrap_or(std::cmp::Ordering::Equal)
                })
                .map_or(0, |(i, _)| i);
            path.truncate(cut);
        }
        path.extend(r.path.iter().map(|q| p(q[0], q[1])));
    }
    let footholds: Vec<Point2<f64>> = routes
        .iter()
        .flat_map(|r| r.footholds.iter().map(|f| p(f[0], f[1])))
        .collect();
    let (lo, hi) = terrain.extent();
    let pixels_per_m = (MAP_PX / (hi.x - lo.x).max(hi.y - lo.y).max(1e-6)).min(100.0);
    let view = tca_rrt::Terrain::new(terrain.clone(), foot_radius_m);
    tca_rrt::draw_route(
        &view,
        &tca_rrt::RouteDrawing {
            start_tree: &start_tree,
            goal_tree: &goal_tree,
            path: &path,
            footholds: &footholds,
        },
        pixels_per_m,
    )
}
