//! From a C-space path to a leg trajectory (§6.2.2, Figure 10c): joint-space way-points
//! whose vertical moves keep the foot as high as the optimal timing allows. All purely
//! vertical lifts happen at the start, the foot keeps rising at full speed while it moves
//! until it reaches the highest height the path needs, and it comes down only as late as
//! still arrives on time, then lowers purely vertically onto the footfall.
//!
//! With `tau` the horizontal joints' time along the path, `z_s` the height after the initial
//! lift, `z_e` the height on arrival above the footfall and `peak` the highest requirement,
//! the foot is at `min(z_s + v tau, peak, z_e + v (T - tau))`: each term is at or above every
//! requirement met (by the choice of `z_s`, `z_e` and `peak`), so the whole profile is.
//! [`check_clearance`] verifies the result against the configuration space independently.

use crate::cspace::{CCell, CSpace};
use crate::error::{PlanError, Result};

/// A point of a trajectory: shoulder (rad), elbow (rad), world height of the sole (m).
pub type TrajectoryPoint = [f64; 3];

/// Tolerance on heights in checks, metres.
const HEIGHT_EPS_M: f64 = 1e-9;

/// Joint-space polyline through the path's cells: the start, the cell centres where the
/// path turns, the goal. The first and last cell centres are skipped when going straight
/// from the start (to the goal) meets no higher requirement.
fn polyline(cs: &CSpace, cells: &[CCell], start: (f64, f64), goal: (f64, f64)) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = Vec::with_capacity(cells.len() + 2);
    pts.push(start);
    pts.extend(cells.iter().map(|&c| cs.centre(c)));
    pts.push(goal);
    // Shortcut the first and the last cell centre when it does not raise the requirement.
    let try_skip = |pts: &mut Vec<(f64, f64)>, k: usize| {
        if k == 0 || k + 1 >= pts.len() {
            return;
        }
        let before = cs
            .segment_required_m(pts[k - 1], pts[k])
            .max(cs.segment_required_m(pts[k], pts[k + 1]));
        if cs.segment_required_m(pts[k - 1], pts[k + 1]) <= before {
            pts.remove(k);
        }
    };
    try_skip(&mut pts, 1);
    let last = pts.len().saturating_sub(2);
    try_skip(&mut pts, last);
    // Merge straight runs and drop repeated points.
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
    for p in pts {
        if let Some(&q) = out.last()
            && (p.0 - q.0).abs() < 1e-12
            && (p.1 - q.1).abs() < 1e-12
        {
            continue;
        }
        if out.len() >= 2 {
            let a = out[out.len() - 2];
            let b = out[out.len() - 1];
            let (u, w) = ((b.0 - a.0, b.1 - a.1), (p.0 - b.0, p.1 - b.1));
            let cross = u.0 * w.1 - u.1 * w.0;
            let dot = u.0 * w.0 + u.1 * w.1;
            let scale = (u.0.hypot(u.1) * w.0.hypot(w.1)).max(1e-30);
            if cross.abs() <= 1e-9 * scale && dot > 0.0 {
                out.pop();
            }
        }
        out.push(p);
    }
    if out.len() == 1 {
        out.push(goal);
    }
    out
}

/// The trajectory from the start `(shoulder, elbow, z)` through the path's cells to the goal
/// `(shoulder, elbow, ground z)`: start point first, the footfall contact last.
pub fn extract(
    cs: &CSpace,
    cells: &[CCell],
    start: TrajectoryPoint,
    goal: TrajectoryPoint,
) -> Result<Vec<TrajectoryPoint>> {
    let speeds = *cs.speeds();
    let v = speeds.vertical_m_per_s;
    let (_, z_max) = cs.z_range_m();
    let pts = polyline(cs, cells, (start[0], start[1]), (goal[0], goal[1]));
    // Horizontal time at each vertex.
    let mut tau = Vec::with_capacity(pts.len());
    tau.push(0.0);
    for w in pts.windows(2) {
        let dt = speeds.horizontal_time_s(w[1].0 - w[0].0, w[1].1 - w[0].1);
        tau.push(tau.last().copied().unwrap_or(0.0) + dt);
    }
    let total = tau.last().copied().unwrap_or(0.0);
    // Requirements along the horizontal time.
    let mut reqs: Vec<(f64, f64, f64)> = Vec::new();
    for (k, w) in pts.windows(2).enumerate() {
        let dt = tau[k + 1] - tau[k];
        for c in cs.crossings(w[0], w[1]) {
            reqs.push((
                tau[k] + c.u0 * dt,
                tau[k] + c.u1 * dt,
                cs.required_m(c.cell),
            ));
        }
    }
    let z0 = start[2];
    let z_s = reqs.iter().fold(z0, |z, &(ta, _, r)| z.max(r - v * ta));
    let z_e = reqs
        .iter()
        .fold(goal[2].max(z_s - v * total), |z, &(_, tb, r)| {
            z.max(r - v * (total - tb))
        });
    let peak = reqs.iter().fold(z_s, |z, &(_, _, r)| z.max(r));
    if peak > z_max + HEIGHT_EPS_M {
        return Err(PlanError::Internal(format!(
            "the path needs the foot at {peak:.3} m, above its reach {z_max:.3} m"
        )));
    }
    let profile = |t: f64| (z_s + v * t).min(peak).min(z_e + v * (total - t));
    // Breakpoints of the profile inside the path.
    let (t_top, t_down) = ((peak - z_s) / v, total - (peak - z_e) / v);
    let mut breaks = if t_top <= t_down {
        vec![t_top, t_down]
    } else {
        vec![(z_e + v * total - z_s) / (2.0 * v)]
    };
    breaks.retain(|&t| t > 1e-9 && t < total - 1e-9);

    let mut out: Vec<TrajectoryPoint> = vec![start];
    if z_s > z0 + HEIGHT_EPS_M {
        out.push([start[0], start[1], z_s]);
    }
    for k in 1..pts.len() {
        let (t0, t1) = (tau[k - 1], tau[k]);
        for &t in &breaks {
            if t > t0 + 1e-9 && t < t1 - 1e-9 {
                let u = (t - t0) / (t1 - t0);
                let (a, b) = (pts[k - 1], pts[k]);
                out.push([a.0 + (b.0 - a.0) * u, a.1 + (b.1 - a.1) * u, profile(t)]);
            }
        }
        out.push([pts[k].0, pts[k].1, profile(t1)]);
    }
    out.push(goal);
    out.dedup_by(|a, b| (0..3).all(|j| (a[j] - b[j]).abs() < 1e-12));
    Ok(out)
}

/// Checks a trajectory against the configuration space: wherever the horizontal joints move,
/// the foot is at or above every cell's requirement it passes (heights vary linearly along a
/// segment, so checking each cell's entry and exit is exact), and every point is within the
/// vertical axis' range. Purely vertical segments (the lift at the start, the lowering onto
/// the footfall) are not checked against the grown terrain.
pub fn check_clearance(cs: &CSpace, points: &[TrajectoryPoint]) -> Result<(), String> {
    let (z_min, z_max) = cs.z_range_m();
    for (k, p) in points.iter().enumerate() {
        if !(p[2] >= z_min - HEIGHT_EPS_M && p[2] <= z_max + HEIGHT_EPS_M) {
            return Err(format!(
                "point {k} at {:.3} m is outside the foot's reach",
                p[2]
            ));
        }
    }
    for (k, w) in points.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        if (b[0] - a[0]).abs() < 1e-12 && (b[1] - a[1]).abs() < 1e-12 {
            continue;
        }
        for c in cs.crossings((a[0], a[1]), (b[0], b[1])) {
            let r = cs.required_m(c.cell);
            let z = |u: f64| a[2] + (b[2] - a[2]) * u;
            let low = z(c.u0).min(z(c.u1));
            if low < r - 1e-7 {
                return Err(format!(
                    "segment {k} passes cell ({}, {}) at {low:.4} m, below its requirement {r:.4} m",
                    c.cell.is, c.cell.ie
                ));
            }
        }
    }
    Ok(())
}
