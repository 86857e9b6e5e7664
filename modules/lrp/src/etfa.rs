//! The Envelope Trajectory Finding Algorithm (§6.2.2): A* over the shoulder x elbow grid in
//! which every search state carries the envelope of foot heights reachable on arrival, so a
//! 2D search finds time- and power-efficient 3D motions.
//!
//! A state is a cell and the direction it was entered from (so turns can be charged, §6.3).
//! Each state keeps its best label only (as the 1990 planner kept one envelope per cell),
//! which is what makes the search fast and, in rare cases, not exactly optimal.
//!
//! The cost of a label is `time + turn_penalty * turns + weight * energy`, where the time
//! includes the waits for lifts the envelope could not absorb, and the energy counts the
//! horizontal joints' motion and lifting the leg to the highest requirement met so far (the
//! trajectory never lowers the foot before the end). Reaching a goal cell adds the final
//! lowering onto the footfall. The heuristic is the time and energy of the horizontal joints
//! at full speed in a straight line: admissible and consistent.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::cost::{CostModel, MotionCost};
use crate::cspace::{CCell, CSpace, DIRECTIONS};
use crate::envelope::ReachEnvelope;

/// A footfall as a search goal: its cell and the ground (contact) height there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchGoal {
    /// The goal's cell.
    pub cell: CCell,
    /// World Z of the ground under the foot at the goal, metres.
    pub ground_m: f64,
}

/// What the search found.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchOutcome {
    /// Cells from the start's to the goal's.
    pub cells: Vec<CCell>,
    /// Which goal was reached (index into the goals given).
    pub goal: usize,
    /// The search's cost, turn penalties included.
    pub cost: f64,
    /// Estimated time and energy down to the footfall (turn penalties excluded).
    pub motion: MotionCost,
    /// Turns along the path.
    pub turns: usize,
    /// Cells whose states were expanded (for pictures), row-major like the space.
    pub expanded: Vec<bool>,
    /// Number of states expanded.
    pub expansions: usize,
}

/// Index of the "no direction yet" state of a cell.
const NO_DIRECTION: usize = 8;
const STATES_PER_CELL: usize = 9;
const NO_PARENT: u32 = u32::MAX;

#[derive(Debug, Clone, Copy)]
struct Label {
    g: f64,
    time_s: f64,
    energy_j: f64,
    turns: u32,
    peak_m: f64,
    env: ReachEnvelope,
    parent: u32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    f: f64,
    g: f64,
    state: u32,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        // A max-heap: the lowest f first; among equals the deepest (highest g).
        other
            .f
            .total_cmp(&self.f)
            .then_with(|| self.g.total_cmp(&other.g))
            .then_with(|| other.state.cmp(&self.state))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Whether label `b` of a cell makes label `l` of the same cell (another direction)
/// useless: anything `l` can do next, `b` can do too after at most one more turn, after
/// waiting until its envelope covers `l`'s (the envelope widens while the leg waits), and
/// after paying the lift energy `l` has already paid for. Costs within the search's label
/// model (one envelope per state).
fn dominates(b: &Label, l: &Label, model: &CostModel, v: f64, energy_weight: f64) -> bool {
    let wait = ((l.env.hi_m - b.env.hi_m) / v)
        .max((b.env.lo_m - l.env.lo_m) / v)
        .max(0.0);
    let lift = energy_weight * model.lift_power_w * (l.peak_m - b.peak_m).max(0.0) / v;
    b.g + model.turn_penalty_s + wait + lift < l.g
}

/// Runs the ETFA from the foot at height `start_z_m` in cell `start` to the nearest (in cost)
/// of `goals`. The start cell must be free. `None` when no goal can be reached.
pub fn search(
    cs: &CSpace,
    model: &CostModel,
    start: CCell,
    start_z_m: f64,
    goals: &[SearchGoal],
) -> Option<SearchOutcome> {
    let (ns, ne) = cs.dims();
    let cells = ns * ne;
    let speeds = *cs.speeds();
    let v = speeds.vertical_m_per_s;
    let (_, z_max) = cs.z_range_m();
    let (ts, te) = cs.cell_time_s();
    let (cell_s, cell_e) = cs.cell_size_rad();
    let energy_weight = model.energy_weight_s_per_kj * 1e-3;
    // The heuristic of every cell, computed once.
    let h_cell: Vec<f64> = (0..ns * ne)
        .map(|i| {
            let c = cs.cell(i);
            goals
                .iter()
                .map(|g| {
                    let di = c.is.abs_diff(g.cell.is) as f64;
                    let dj = c.ie.abs_diff(g.cell.ie) as f64;
                    let time = (di * ts).max(dj * te);
                    let energy = model.shoulder_power_w * di * ts + model.elbow_power_w * dj * te;
                    time + energy_weight * energy
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let heuristic = |c: CCell| -> f64 { h_cell.get(cs.index(c)).copied().unwrap_or(f64::INFINITY) };
    if goals.is_empty() || !cs.is_free(start) {
        return None;
    }

    let mut labels: Vec<Option<Label>> = vec![None; cells * STATES_PER_CELL];
    let mut closed = vec![false; cells * STATES_PER_CELL];
    let mut expanded = vec![false; cells];
    // The cheapest label of each cell: a label of another direction that it dominates (see
    // `dominates`) is dropped, which removes most of the direction dimension's work.
    let mut best_in_cell: Vec<Option<Label>> = vec![None; cells];
    let dominated = |best: &Option<Label>, l: &Label| {
        best.is_some_and(|b| dominates(&b, l, model, speeds.vertical_m_per_s, energy_weight))
    };
    let mut heap = BinaryHeap::new();

    // Lift at the start until the foot clears its own cell.
    let r0 = cs.required_m(start);
    let lift = (r0 - start_z_m).max(0.0);
    let peak = start_z_m.max(r0);
    let start_label = Label {
        g: 0.0,
        time_s: lift / v,
        energy_j: model.vertical_energy_j(&speeds, peak - start_z_m),
        turns: 0,
        peak_m: peak,
        env: ReachEnvelope::at(start_z_m.max(r0)),
        parent: NO_PARENT,
    };
    let g0 = start_label.time_s + energy_weight * start_label.energy_j;
    let start_label = Label {
        g: g0,
        ..start_label
    };
    let start_state = cs.index(start) * STATES_PER_CELL + NO_DIRECTION;
    labels[start_state] = Some(start_label);
    best_in_cell[cs.index(start)] = Some(start_label);
    heap.push(Entry {
        f: g0 + heuristic(start),
        g: g0,
        state: start_state as u32,
    });

    let mut best: Option<(f64, usize, usize, MotionCost)> = None;
    let mut expansions = 0usize;
    while let Some(Entry { f, state, .. }) = heap.pop() {
        let state = state as usize;
        if best.is_some_and(|(cost, ..)| f >= cost) {
            break;
        }
        if closed[state] {
            continue;
        }
        closed[state] = true;
        let Some(label) = labels[state] else { continue };
        let cell_index = state / STATES_PER_CELL;
        if dominated(&best_in_cell[cell_index], &label) {
            continue;
        }
        expansions += 1;
        let dir = state % STATES_PER_CELL;
        let cell = cs.cell(cell_index);
        expanded[cell_index] = true;

        for (k, goal) in goals.iter().enumerate() {
            if goal.cell == cell {
                let down = (label.env.lo_m - goal.ground_m).max(0.0);
                let motion = MotionCost {
                    time_s: label.time_s + down / v,
                    energy_j: label.energy_j
                        + model
                            .vertical_energy_j(&speeds, -(label.peak_m - goal.ground_m).max(0.0)),
                };
                let cost = model.cost(motion) + model.turn_penalty_s * f64::from(label.turns);
                if best.is_none_or(|(b, ..)| cost < b) {
                    best = Some((cost, state, k, motion));
                }
            }
        }

        let r_here = cs.required_m(cell);
        for (next_dir, &(di, dj)) in DIRECTIONS.iter().enumerate() {
            let (Some(is), Some(ie)) = (
                cell.is.checked_add_signed(isize::from(di)),
                cell.ie.checked_add_signed(isize::from(dj)),
            ) else {
                continue;
            };
            if is >= ns || ie >= ne {
                continue;
            }
            let next = CCell { is, ie };
            let next_state = cs.index(next) * STATES_PER_CELL + next_dir;
            if closed[next_state] {
                continue;
            }
            let r_next = cs.required_m(next);
            let border = cs.step_required_m(cell, next);
            let (ds, de) = (f64::from(di) * cell_s, f64::from(dj) * cell_e);
            let dt = speeds.horizontal_time_s(ds, de);
            let Some((env, wait)) = label.env.step(dt, v, r_here, border, r_next, z_max) else {
                continue;
            };
            let turned = dir != NO_DIRECTION && dir != next_dir;
            let peak = label.peak_m.max(border);
            let energy_j = label.energy_j
                + model.horizontal_energy_j(&speeds, ds, de)
                + model.vertical_energy_j(&speeds, peak - label.peak_m);
            let time_s = label.time_s + dt + wait;
            let turns = label.turns + u32::from(turned);
            let g = time_s + model.turn_penalty_s * f64::from(turns) + energy_weight * energy_j;
            let next_index = next_state / STATES_PER_CELL;
            let next_label = Label {
                g,
                time_s,
                energy_j,
                turns,
                peak_m: peak,
                env,
                parent: state as u32,
            };
            if labels[next_state].is_some_and(|l| l.g <= g)
                || dominated(&best_in_cell[next_index], &next_label)
            {
                continue;
            }
            if best_in_cell[next_index].is_none_or(|b| g < b.g) {
                best_in_cell[next_index] = Some(next_label);
            }
            labels[next_state] = Some(next_label);
            heap.push(Entry {
                f: g + heuristic(next),
                g,
                state: next_state as u32,
            });
        }
    }

    let (cost, end_state, goal, motion) = best?;
    let mut path = Vec::new();
    let mut state = end_state as u32;
    let mut turns = 0;
    while state != NO_PARENT {
        let s = state as usize;
        path.push(cs.cell(s / STATES_PER_CELL));
        let label = labels[s]?;
        if path.len() == 1 {
            turns = label.turns as usize;
        }
        state = label.parent;
    }
    path.reverse();
    Some(SearchOutcome {
        cells: path,
        goal,
        cost,
        motion,
        turns,
        expanded,
        expansions,
    })
}
