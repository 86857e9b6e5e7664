//! The hill course (Figure 9's) walked by the shipped hexapod over several seeds, with the
//! acceptance limits checked as `tca navigate --robot hexapod --terrain hill --direct
//! --seeds N` checks them:
//! `cargo run --release -p tca-nav-hexapod --example hexapod_campaign -- [FIRST_SEED] [SEEDS]`.

use std::sync::Arc;

use tca_legged_model::RobotModel;
use tca_nav_hexapod::{HexapodBase, StepperParams, hexapod_params};
use tca_nav_navigator::{RunOptions, hill_course, run};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<u64>());
    let first = args.next().transpose()?.unwrap_or(0);
    let seeds = args.next().transpose()?.unwrap_or(8);
    let course = hill_course()?;
    let model = Arc::new(RobotModel::builtin("hexapod")?);
    let terrain = Arc::new(course.terrain.clone());
    let params = hexapod_params(&model)?;
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
        let (r, _) = run(&course.terrain, &mut base, params.clone(), &opts)?;
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
    }
    println!("hill (hexapod): {ok} of {seeds} accepted");
    Ok(())
}
