//! The hill course (Figure 9's) walked by the shipped hexapod over several seeds, with the
//! acceptance limits checked as `tca navigate --robot hexapod --terrain hill --direct
//! --seeds N` checks them:
//! `cargo run --release -p tca-nav-hexapod --example hexapod_campaign -- [FIRST_SEED] [SEEDS]`.

use std::sync::Arc;

use tca_legged_model::RobotModel;
use tca_nav_danger_map::{CellDanger, DangerMap};
use tca_nav_hexapod::{HexapodBase, StepperParams, hexapod_params};
use tca_nav_navigator::{RunOptions, hill_course, run, true_danger_map};
use tca_robot::{CellIndex, Grid};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<u64>());
    let first = args.next().transpose()?.unwrap_or(0);
    let seeds = args.next().transpose()?.unwrap_or(8);
    let course = hill_course()?;
    let model = Arc::new(RobotModel::builtin("hexapod")?);
    let terrain = Arc::new(course.terrain.clone());
    let params = hexapod_params(&model)?;
    let truth = true_danger_map(&course.terrain, &params)?;
    let mut ok = 0;
    for seed in first..first + seeds {
        let mut base = HexapodBase::new(
            model.clone(),
            terrain.clone(),
            course.start,
            StepperParams::for_model(&model),
        )?;
        let opts = RunOptions {
            start: course.start,
            goal_offset: course.goal_offset,
            drift: 0.0125,
            seed,
            max_frames: 600,
        };
        let (r, nav) = run(&course.terrain, &mut base, params.clone(), &opts)?;
        let best = r.true_map_path_m.unwrap_or(f64::NAN);
        let accepted = r.meets_acceptance();
        ok += usize::from(accepted);
        println!(
            "hill (hexapod) seed {seed}: reached {} ({}), {:.2} m (true-map path {best:.2} m, ratio {:.3}), final error {:.3} m ({:.2} %), estimate error {:.3} m, {} replans, {} turns, {} frames, {:.1} Hz, collisions {}, falls {}, untraversable frames {}, stalls {}",
            r.reached,
            r.reason,
            r.distance_m,
            r.distance_m / best,
            r.final_error_m,
            100.0 * r.final_error_m / r.distance_m.max(1e-9),
            r.estimate_error_m,
            r.replans,
            r.exploration_turns,
            r.frames,
            r.loop_hz,
            r.collisions,
            r.falls,
            r.untraversable_frames,
            base.stalls()
        );
        for (frame, p, depth) in untraversable_depths(&truth, &r.path) {
            let here = nalgebra::Point2::new(p[0], p[1]);
            let (seen, certainty, gap) = perceived_near(nav.danger(), here);
            println!(
                "  frame {frame}: true position ({:.3}, {:.3}) m, {:.3} m from the nearest traversable cell; at the run's end the navigator's map gives its cell danger {seen:.2} (certainty {certainty:.2}) and its nearest untraversable cell is {gap:.3} m away",
                p[0], p[1], depth
            );
        }
    }
    println!("hill (hexapod): {ok} of {seeds} accepted");
    Ok(())
}

/// For each true position in a cell that is untraversable on the true terrain: the frame, the
/// position and how deep it is, the distance to the centre of the nearest traversable cell.
fn untraversable_depths(truth: &DangerMap, path: &[[f64; 2]]) -> Vec<(usize, [f64; 2], f64)> {
    let grid = truth.cells();
    let mut out = Vec::new();
    for (frame, p) in path.iter().enumerate() {
        let here = nalgebra::Point2::new(p[0], p[1]);
        if grid
            .cell_at(here)
            .is_some_and(|c| !truth.cell(c).is_traversable())
        {
            out.push((frame, *p, nearest(grid, here, CellDanger::is_traversable)));
        }
    }
    out
}

/// The danger and certainty of the cell at `here` in `map`, and the distance from `here` to
/// the centre of the nearest untraversable cell of `map` (within 0.5 m; infinite if none).
fn perceived_near(map: &Grid<CellDanger>, here: nalgebra::Point2<f64>) -> (f64, f64, f64) {
    let Some(d) = map.cell_at(here).and_then(|c| map.get(c)) else {
        return (f64::NAN, f64::NAN, f64::INFINITY);
    };
    let gap = nearest(map, here, |d| d.danger.is_infinite());
    (d.danger, d.certainty, gap)
}

/// The distance from `here` to the centre of the nearest cell of `grid` within 0.5 m for
/// which `wanted` holds; infinite if none.
fn nearest(
    grid: &Grid<CellDanger>,
    here: nalgebra::Point2<f64>,
    wanted: impl Fn(&CellDanger) -> bool,
) -> f64 {
    let Some(c) = grid.cell_at(here) else {
        return f64::INFINITY;
    };
    let reach = (0.5 / grid.resolution_m()).ceil() as isize;
    let mut best = f64::INFINITY;
    for dy in -reach..=reach {
        for dx in -reach..=reach {
            let (ix, iy) = (c.ix as isize + dx, c.iy as isize + dy);
            if ix < 0 || iy < 0 {
                continue;
            }
            let n = CellIndex::new(ix as usize, iy as usize);
            if grid.get(n).is_some_and(&wanted) {
                best = best.min((grid.cell_center(n) - here).norm());
            }
        }
    }
    best
}
