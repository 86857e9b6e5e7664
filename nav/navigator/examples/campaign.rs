//! The two courses over 8 seeds with the wheeled base, as `tca navigate --seeds 8` runs
//! them: `cargo run --release -p tca-nav-navigator --example campaign`.

use tca_nav_navigator::{
    RunOptions, WheeledBase, WheeledParams, hill_course, ramps_course, run, wheeled_params,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for course in [ramps_course()?, hill_course()?] {
        let mut ok = 0;
        for seed in 0..8 {
            let mut base = WheeledBase::new(WheeledParams::PIONEER, &course.terrain, course.start);
            let opts = RunOptions {
                start: course.start,
                goal_offset: course.goal_offset,
                drift: 0.0125,
                seed,
                max_frames: 3000,
            };
            let (r, _) = run(&course.terrain, &mut base, wheeled_params(), &opts)?;
            let best = r.true_map_path_m.unwrap_or(f64::NAN);
            let accepted = r.meets_acceptance();
            ok += usize::from(accepted);
            println!(
                "{} seed {seed}: reached {}, {:.2} m (true-map path {best:.2} m, ratio {:.2}), final error {:.3} m ({:.2} %), estimate error {:.3} m ({:.2} %), {} replans, {} turns, {:.1} Hz, collisions {}, falls {}, untraversable frames {}",
                course.name,
                r.reached,
                r.distance_m,
                r.distance_m / best,
                r.final_error_m,
                100.0 * r.final_error_m / r.distance_m,
                r.estimate_error_m,
                100.0 * r.estimate_error_m / r.distance_m,
                r.replans,
                r.exploration_turns,
                r.loop_hz,
                r.collisions,
                r.falls,
                r.untraversable_frames
            );
        }
        println!("{}: {ok} of 8 accepted", course.name);
    }
    Ok(())
}
