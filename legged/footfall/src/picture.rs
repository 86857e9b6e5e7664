//! Pictures for the operator: one leg's maps over the terrain seen from above (green, red,
//! orange, blue), the robot as it stands (body, legs, feet), its support polygon (white) and
//! conservative polygon (yellow) with the centre of mass; and a plan drawn over them as a
//! "ghost": the leg at every way-point, the wheel's path, the target, with the path's
//! profile underneath (the ground, the ground raised for planning, the wheel's bottom).

use nalgebra::{Point2, Point3};
pub use tca_canvas::Canvas;
use tca_canvas::{Rgb, grey};

use crate::maps::{Colour, LegMaps};
use crate::plan::FootfallPlan;
use crate::scene::Scene;

const GREEN: Rgb = [40, 190, 60];
const RED: Rgb = [210, 50, 40];
const ORANGE: Rgb = [245, 150, 20];
const BLUE: Rgb = [50, 110, 235];
const SUPPORT: Rgb = [255, 255, 255];
const CONSERVATIVE: Rgb = [255, 230, 40];
const ROBOT: Rgb = [150, 150, 160];
const GHOST: Rgb = [120, 240, 255];
const TARGET: Rgb = [255, 60, 255];
const TEXT: Rgb = [230, 230, 230];
/// The narrowest picture, pixels: room for the legend.
const MIN_WIDTH_PX: f64 = 900.0;

/// Writes a line of text at scale 2, or 1 when that does not fit.
fn label(c: &mut Canvas, x: i64, y: i64, text: &str) {
    let scale = if i64::from(tca_canvas::font::text_width(text, 2)) + x < i64::from(c.width()) {
        2
    } else {
        1
    };
    c.text(x, y, text, scale, TEXT);
}

fn colour_of(c: Colour) -> Rgb {
    match c {
        Colour::Green => GREEN,
        Colour::Red => RED,
        Colour::Orange => ORANGE,
        Colour::Blue => BLUE,
    }
}

fn mix(a: Rgb, b: Rgb, t: f64) -> Rgb {
    let m = |x: u8, y: u8| (f64::from(x) * (1.0 - t) + f64::from(y) * t).round() as u8;
    [m(a[0], b[0]), m(a[1], b[1]), m(a[2], b[2])]
}

/// A view of a world rectangle at a scale.
struct View {
    lo: Point2<f64>,
    hi: Point2<f64>,
    ppm: f64,
}

impl View {
    fn px(&self, p: Point2<f64>) -> (f64, f64) {
        ((p.x - self.lo.x) * self.ppm, (self.hi.y - p.y) * self.ppm)
    }

    fn size(&self) -> (u32, u32) {
        (
            ((self.hi.x - self.lo.x) * self.ppm).ceil() as u32,
            ((self.hi.y - self.lo.y) * self.ppm).ceil() as u32,
        )
    }
}

/// The maps of one leg with the robot and its polygons, seen from above, `ppm` pixels per
/// metre.
pub fn draw_maps(scene: &Scene, maps: &LegMaps, ppm: f64) -> Canvas {
    let (_, mut c) = top_view(scene, maps, ppm);
    legend(&mut c, scene, maps);
    c
}

fn top_view(scene: &Scene, maps: &LegMaps, ppm: f64) -> (View, Canvas) {
    // The rectangle holding the maps and every foot, with a margin.
    let half = 0.5 * maps.resolution_m;
    let mut lo = Point2::new(maps.origin[0] - half, maps.origin[1] - half);
    let mut hi = Point2::new(
        maps.origin[0] + (maps.nx as f64 - 0.5) * maps.resolution_m,
        maps.origin[1] + (maps.ny as f64 - 0.5) * maps.resolution_m,
    );
    for p in scene.touch_points() {
        lo = Point2::new(lo.x.min(p.x - 0.5), lo.y.min(p.y - 0.5));
        hi = Point2::new(hi.x.max(p.x + 0.5), hi.y.max(p.y + 0.5));
    }
    // Wide enough for the legend.
    let min_w = MIN_WIDTH_PX / ppm;
    if hi.x - lo.x < min_w {
        let pad = 0.5 * (min_w - (hi.x - lo.x));
        lo.x -= pad;
        hi.x += pad;
    }
    let view = View { lo, hi, ppm };
    let (w, h) = view.size();
    let mut c = Canvas::new(w, h + 40, [20, 20, 24]);
    let t = &scene.terrain;
    let (zmin, zmax) = (
        t.min_height_m(),
        t.max_height_m().max(t.min_height_m() + 1e-6),
    );
    for py in 0..h {
        for px in 0..w {
            let x = lo.x + (f64::from(px) + 0.5) / ppm;
            let y = hi.y - (f64::from(py) + 0.5) / ppm;
            // Grey by height, lit from the north-west so that rocks stand out.
            let n = t.normal_at(x, y);
            let light = (0.75 + 0.5 * (-n.x * 0.5 + n.y * 0.5 + n.z * 0.7)).clamp(0.3, 1.2);
            let g = grey(t.height_at(x, y), zmin - 0.3, zmax);
            let mut rgb = [0u8; 3];
            for k in 0..3 {
                rgb[k] = (f64::from(g[k]) * 0.7 * light).clamp(0.0, 255.0) as u8;
            }
            if let Some((ix, iy)) = maps.cell_of(Point2::new(x, y))
                && let Some(colour) = maps.colour(ix, iy)
            {
                let alpha = if colour == Colour::Red { 0.35 } else { 0.6 };
                rgb = mix(rgb, colour_of(colour), alpha);
            }
            c.set(i64::from(px), i64::from(py), rgb);
        }
    }
    draw_robot(&mut c, &view, scene, None);
    let poly = |c: &mut Canvas, pts: &[[f64; 2]], colour: Rgb| {
        for k in 0..pts.len() {
            let a = pts[k];
            let b = pts[(k + 1) % pts.len()];
            c.line(
                view.px(Point2::new(a[0], a[1])),
                view.px(Point2::new(b[0], b[1])),
                2,
                colour,
            );
        }
    };
    poly(&mut c, &maps.now.support, SUPPORT);
    poly(&mut c, &maps.now.conservative, CONSERVATIVE);
    let com = view.px(Point2::new(maps.now.com[0], maps.now.com[1]));
    c.marker(com, 5, CONSERVATIVE);
    (view, c)
}

/// The body, every leg as the chain of its joints and its wheel, seen from above; the
/// `ghost` leg (index, joints) drawn over it in the ghost's colour.
fn draw_robot(c: &mut Canvas, view: &View, scene: &Scene, ghost: Option<(usize, &[f64])>) {
    let body = scene.body;
    let flat = |p: Point3<f64>| Point2::new(p.x, p.y);
    let legs = scene.model.legs();
    let mut corners = Vec::new();
    for (i, leg) in legs.iter().enumerate() {
        let (q, colour) = match ghost {
            Some((g, q)) if g == i => (q, GHOST),
            Some(_) => continue,
            None => (scene.posture[i].as_slice(), ROBOT),
        };
        let Ok(frames) = leg.joint_frames(q) else {
            continue;
        };
        let mut prev = flat(body * leg.base_position());
        if ghost.is_none() {
            corners.push(prev);
        }
        for f in &frames {
            let p = flat(body * Point3::from(f.translation.vector));
            c.line(view.px(prev), view.px(p), 3, colour);
            prev = p;
        }
        if let Ok(foot) = leg.foot_position(q) {
            let f = flat(body * foot);
            c.line(view.px(prev), view.px(f), 3, colour);
            c.circle(view.px(f), leg.foot_radius() * view.ppm, 2, colour);
        }
    }
    if corners.len() > 2 {
        let centre = flat(body * Point3::origin());
        corners.sort_by(|a, b| {
            let ta = (a.y - centre.y).atan2(a.x - centre.x);
            let tb = (b.y - centre.y).atan2(b.x - centre.x);
            ta.total_cmp(&tb)
        });
        for k in 0..corners.len() {
            c.line(
                view.px(corners[k]),
                view.px(corners[(k + 1) % corners.len()]),
                2,
                ROBOT,
            );
        }
    }
}

fn legend(c: &mut Canvas, scene: &Scene, maps: &LegMaps) {
    let y = i64::from(c.height()) - 34;
    let k = maps.counts;
    label(
        c,
        8,
        y,
        &format!(
            "{} {}: green {} red {} orange {} blue {}",
            scene.model.name(),
            maps.leg,
            k.green,
            k.red,
            k.orange,
            k.blue
        ),
    );
    label(
        c,
        8,
        y + 18,
        &format!(
            "margin: support {:.2} m (white), conservative {:.2} m (yellow)",
            maps.now.support_margin_m, maps.now.conservative_margin_m
        ),
    );
}

/// A plan over its leg's maps: the ghost leg at each way-point, the wheel's path and the
/// target from above, and below it the path's profile.
pub fn draw_plan(scene: &Scene, maps: &LegMaps, plan: &FootfallPlan, ppm: f64) -> Canvas {
    let (view, mut top) = top_view(scene, maps, ppm);
    let leg = scene.model.leg_index(&plan.leg).unwrap_or(0);
    for w in &plan.waypoints {
        draw_robot(&mut top, &view, scene, Some((leg, w)));
    }
    let path: Vec<(f64, f64)> = plan
        .foot_path
        .iter()
        .map(|p| view.px(Point2::new(p[0], p[1])))
        .collect();
    for w in path.windows(2) {
        top.line(w[0], w[1], 2, GHOST);
    }
    top.marker(
        view.px(Point2::new(plan.target[0], plan.target[1])),
        7,
        TARGET,
    );
    legend(&mut top, scene, maps);
    // The profile along the wheel's path.
    let prof_h = 220u32;
    let mut c = Canvas::new(top.width(), top.height() + prof_h, [20, 20, 24]);
    c.blit(&top, 0, 0);
    let y0 = f64::from(top.height());
    let mut along = vec![0.0];
    for w in plan.foot_path.windows(2) {
        let d = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) + (w[1][2] - w[0][2]).abs();
        along.push(along.last().copied().unwrap_or(0.0) + d);
    }
    let total = along.last().copied().unwrap_or(1.0).max(1e-6);
    let raise = plan.heuristics.map_or(0.0, |h| h.raise_m);
    let r = scene.model.legs()[leg].foot_radius();
    let ground: Vec<f64> = plan
        .foot_path
        .iter()
        .map(|p| scene.terrain.height_at(p[0], p[1]))
        .collect();
    let zlo = ground.iter().copied().fold(f64::INFINITY, f64::min) - 0.05;
    let zhi = plan
        .foot_path
        .iter()
        .map(|p| p[2])
        .fold(f64::NEG_INFINITY, f64::max)
        + 0.05;
    let sx = (f64::from(c.width()) - 20.0) / total;
    let sz = (f64::from(prof_h) - 40.0) / (zhi - zlo).max(1e-6);
    let pt = |s: f64, z: f64| {
        (
            10.0 + s * sx,
            y0 + f64::from(prof_h) - 10.0 - (z - zlo) * sz,
        )
    };
    for k in 1..plan.foot_path.len() {
        let (a, b) = (along[k - 1], along[k]);
        c.line(pt(a, ground[k - 1]), pt(b, ground[k]), 2, [170, 130, 90]);
        if raise > 0.0 {
            c.line(
                pt(a, ground[k - 1] + raise),
                pt(b, ground[k] + raise),
                1,
                [120, 100, 80],
            );
        }
        let (p, q) = (&plan.foot_path[k - 1], &plan.foot_path[k]);
        c.line(pt(a, p[2] - r), pt(b, q[2] - r), 2, GHOST);
    }
    label(
        &mut c,
        8,
        y0 as i64 + 6,
        &format!(
            "{} plan: {} way-points in the swing, lift {:.0} cm, ground raised {:.0} cm. \
             profile: ground, raised ground, wheel bottom",
            plan.planner,
            plan.swing_waypoints,
            plan.lift_m * 100.0,
            raise * 100.0
        ),
    );
    c
}
