//! An exact reference search over (shoulder, elbow, foot height), to measure the ETFA.
//!
//! The lattice is scaled to the joint speeds: one step of any joint takes the same time
//! `step_time_s` at full speed (0.02 rad of shoulder, 0.03 rad of elbow and 7.2 mm of
//! vertical travel with the defaults). Moves go to any of the 26 neighbours and take one step
//! of time, so the time of a path (the slowest joint's) and its energy (each joint's own
//! travel) are represented without grid bias: the only approximation left is the lattice's
//! resolution, four times finer than the ETFA's cells. The obstacle model is the same
//! configuration space the ETFA searches (the lowest foot height per C-space cell), so the
//! comparison isolates the ETFA's own approximations: moves between cell centres, one
//! envelope per state, the turn penalty.
//!
//! The foot may move purely vertically below the grown terrain only above the start (lifting
//! off); it lowers onto the footfall from wherever it arrives above it, as the ETFA's
//! trajectories do.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::cost::{CostModel, MotionCost};
use crate::cspace::CSpace;
use crate::trajectory::TrajectoryPoint;

/// Options of the exact search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactOptions {
    /// Time of one lattice step of any joint, seconds.
    pub step_time_s: f64,
    /// The search window: the box around the start and goal joint angles grown by this
    /// much, radians.
    pub window_pad_rad: f64,
    /// Refuse (return `None`) when the window has more lattice states than this.
    pub max_states: usize,
}

impl Default for ExactOptions {
    fn default() -> Self {
        Self {
            step_time_s: 0.2,
            window_pad_rad: 1.6,
            max_states: 20_000_000,
        }
    }
}

/// The optimum found by the exact search.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactSolution {
    /// Time and energy down to the contact.
    pub motion: MotionCost,
    /// Weighted cost (no turn penalties).
    pub cost: f64,
    /// The path: (shoulder rad, elbow rad, sole height m), start to contact.
    pub points: Vec<TrajectoryPoint>,
    /// States expanded.
    pub expansions: usize,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    f: f64,
    state: u32,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .f
            .total_cmp(&self.f)
            .then_with(|| other.state.cmp(&self.state))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// The least-cost motion from `start` to `goal` (each `(shoulder, elbow, sole height)`; the
/// goal's height is the ground) in the configuration space `cs`. `None` when there is none
/// within the window, or the window is too large.
pub fn exact_search(
    cs: &CSpace,
    model: &CostModel,
    start: TrajectoryPoint,
    goal: TrajectoryPoint,
    options: &ExactOptions,
) -> Option<ExactSolution> {
    let sp = *cs.speeds();
    let dt = options.step_time_s;
    let (ds, de, dz) = (
        sp.shoulder_rad_per_s * dt,
        sp.elbow_rad_per_s * dt,
        sp.vertical_m_per_s * dt,
    );
    let (ns_cells, ne_cells) = cs.dims();
    let (cell_s, cell_e) = cs.cell_size_rad();
    let first = cs.centre(crate::CCell { is: 0, ie: 0 });
    let (s_min, e_min) = (first.0 - 0.5 * cell_s, first.1 - 0.5 * cell_e);
    let (s_max, e_max) = (
        s_min + ns_cells as f64 * cell_s,
        e_min + ne_cells as f64 * cell_e,
    );
    let (z_lo, z_hi) = cs.z_range_m();
    let pad = options.window_pad_rad;
    let range = |a: f64, b: f64, lo: f64, hi: f64, origin: f64, step: f64| {
        let l = (a.min(b) - pad).max(lo);
        let h = (a.max(b) + pad).min(hi);
        (
            ((l - origin) / step).ceil() as i64,
            ((h - origin) / step).floor() as i64,
        )
    };
    let (i0, i1) = range(start[0], goal[0], s_min, s_max, start[0], ds);
    let (j0, j1) = range(start[1], goal[1], e_min, e_max, start[1], de);
    let k0 = ((start[2].min(goal[2]).max(z_lo) - start[2]) / dz).floor() as i64;
    let k1 = ((z_hi - start[2]) / dz).floor() as i64;
    if i0 > 0 || j0 > 0 || i1 < 0 || j1 < 0 || k0 > 0 || k1 < 0 {
        return None;
    }
    let (ni, nj, nk) = (
        (i1 - i0 + 1) as usize,
        (j1 - j0 + 1) as usize,
        (k1 - k0 + 1) as usize,
    );
    let states = ni.checked_mul(nj)?.checked_mul(nk)?;
    if states > options.max_states || states >= u32::MAX as usize {
        return None;
    }
    let s_of = |i: usize| start[0] + (i as i64 + i0) as f64 * ds;
    let e_of = |j: usize| start[1] + (j as i64 + j0) as f64 * de;
    let z_of = |k: usize| start[2] + (k as i64 + k0) as f64 * dz;
    // Requirement at each lattice column (the cells whose closure holds the point).
    let mut column_req = vec![0.0; ni * nj];
    for j in 0..nj {
        for i in 0..ni {
            column_req[j * ni + i] = cs
                .cells_at_point(s_of(i), e_of(j))
                .into_iter()
                .map(|c| cs.required_m(c))
                .fold(f64::NEG_INFINITY, f64::max);
        }
    }
    let start_col = ((-i0) as usize, (-j0) as usize);
    let goal_col = (
        (((goal[0] - start[0]) / ds).round() as i64 - i0).clamp(0, ni as i64 - 1) as usize,
        (((goal[1] - start[1]) / de).round() as i64 - j0).clamp(0, nj as i64 - 1) as usize,
    );
    // The last small move from the goal's lattice column to the goal itself, at the arrival
    // height, must clear the cells it passes; then the foot lowers onto the footfall.
    let snap_required =
        cs.segment_required_m((s_of(goal_col.0), e_of(goal_col.1)), (goal[0], goal[1]));
    let snap = model.segment(
        &sp,
        goal[0] - s_of(goal_col.0),
        goal[1] - e_of(goal_col.1),
        0.0,
    );
    let w = model.energy_weight_s_per_kj * 1e-3;
    let heuristic = |i: usize, j: usize| {
        let di = i.abs_diff(goal_col.0) as f64;
        let dj = j.abs_diff(goal_col.1) as f64;
        di.max(dj) * dt + w * (model.shoulder_power_w * di + model.elbow_power_w * dj) * dt
    };
    let index = |i: usize, j: usize, k: usize| (k * nj + j) * ni + i;
    let unpack = |s: usize| (s % ni, (s / ni) % nj, s / (ni * nj));

    let mut g = vec![f64::INFINITY; states];
    let mut parent = vec![u32::MAX; states];
    let mut closed = vec![false; states];
    let mut heap = BinaryHeap::new();
    let s0 = index(start_col.0, start_col.1, (-k0) as usize);
    g[s0] = 0.0;
    heap.push(Entry {
        f: heuristic(start_col.0, start_col.1),
        state: s0 as u32,
    });
    let mut best: Option<(f64, usize)> = None;
    let mut expansions = 0;
    let final_descent = |z: f64| {
        let down = (z - goal[2]).max(0.0);
        MotionCost {
            time_s: down / sp.vertical_m_per_s,
            energy_j: model.vertical_energy_j(&sp, -down),
        }
    };
    while let Some(Entry { f, state }) = heap.pop() {
        let state = state as usize;
        if best.is_some_and(|(b, _)| f >= b) {
            break;
        }
        if closed[state] {
            continue;
        }
        closed[state] = true;
        expansions += 1;
        let (i, j, k) = unpack(state);
        let gs = g[state];
        if (i, j) == goal_col && z_of(k) >= snap_required {
            let total = gs + model.cost(final_descent(z_of(k)) + snap);
            if best.is_none_or(|(b, _)| total < b) {
                best = Some((total, state));
            }
        }
        let z = z_of(k);
        for dk in -1i64..=1 {
            for dj in -1i64..=1 {
                for di in -1i64..=1 {
                    if di == 0 && dj == 0 && dk == 0 {
                        continue;
                    }
                    let (ni2, nj2, nk2) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                    if ni2 < 0
                        || nj2 < 0
                        || nk2 < 0
                        || ni2 >= ni as i64
                        || nj2 >= nj as i64
                        || nk2 >= nk as i64
                    {
                        continue;
                    }
                    let (i2, j2, k2) = (ni2 as usize, nj2 as usize, nk2 as usize);
                    let z2 = z_of(k2);
                    let low = z.min(z2);
                    let ok = if di == 0 && dj == 0 {
                        (i, j) == start_col || low >= column_req[j * ni + i]
                    } else {
                        let r = column_req[j * ni + i]
                            .max(column_req[j2 * ni + i2])
                            .max(column_req[j * ni + i2])
                            .max(column_req[j2 * ni + i]);
                        low >= r
                    };
                    if !ok {
                        continue;
                    }
                    let mut energy = 0.0;
                    if di != 0 {
                        energy += model.shoulder_power_w * dt;
                    }
                    if dj != 0 {
                        energy += model.elbow_power_w * dt;
                    }
                    if dk > 0 {
                        energy += model.lift_power_w * dt;
                    } else if dk < 0 {
                        energy += model.lower_power_w * dt;
                    }
                    let g2 = gs + dt + w * energy;
                    let s2 = index(i2, j2, k2);
                    if !closed[s2] && g2 < g[s2] {
                        g[s2] = g2;
                        parent[s2] = state as u32;
                        heap.push(Entry {
                            f: g2 + heuristic(i2, j2),
                            state: s2 as u32,
                        });
                    }
                }
            }
        }
    }
    let (cost, end) = best?;
    let mut chain = Vec::new();
    let mut s = end as u32;
    while s != u32::MAX {
        chain.push(unpack(s as usize));
        s = parent[s as usize];
    }
    chain.reverse();
    // Time and energy along the lattice path, one step of time per move.
    let mut motion = MotionCost::default();
    for w2 in chain.windows(2) {
        let (a, b) = (w2[0], w2[1]);
        motion.time_s += dt;
        if a.0 != b.0 {
            motion.energy_j += model.shoulder_power_w * dt;
        }
        if a.1 != b.1 {
            motion.energy_j += model.elbow_power_w * dt;
        }
        if b.2 > a.2 {
            motion.energy_j += model.lift_power_w * dt;
        } else if b.2 < a.2 {
            motion.energy_j += model.lower_power_w * dt;
        }
    }
    let mut points: Vec<TrajectoryPoint> = chain
        .iter()
        .map(|&(i, j, k)| [s_of(i), e_of(j), z_of(k)])
        .collect();
    let end_z = points.last().map_or(start[2], |p| p[2]);
    motion += final_descent(end_z) + snap;
    points.push([goal[0], goal[1], end_z]);
    points.push(goal);
    points.dedup_by(|a, b| (0..3).all(|x| (a[x] - b[x]).abs() < 1e-12));
    Some(ExactSolution {
        motion,
        cost,
        points,
        expansions,
    })
}
