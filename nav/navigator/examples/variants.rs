//! Experiment harness (temporary).
use tca_nav_navigator::*;
fn env(k: &str, d: f64) -> f64 { std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d) }
fn main() {
    let course = course_by_name(&std::env::var("COURSE").unwrap_or("ramps".into())).unwrap().unwrap();
    let seeds: Vec<u64> = std::env::var("SEEDS").unwrap_or("0,1,2,3".into()).split(',').map(|s| s.parse().unwrap()).collect();
    let mut ok = 0;
    for seed in seeds.iter().copied() {
        let mut p = wheeled_params();
        p.beta = env("BETA", p.beta);
        p.clearance_m = env("CLEAR", p.clearance_m);
        p.map_range_m = env("RANGE", p.map_range_m);
        p.lookahead_m = env("LOOK", p.lookahead_m);
        p.explore_spacing_m = env("SPACING", p.explore_spacing_m);
        let mut base = WheeledBase::new(WheeledParams::PIONEER, &course.terrain, course.start);
        let opts = RunOptions { start: course.start, goal_offset: course.goal_offset, drift: 0.0125, seed, max_frames: 3000 };
        let (r, nav) = run(&course.terrain, &mut base, p, &opts).unwrap();
        let best = r.true_map_path_m.unwrap_or(f64::NAN);
        let acc = r.reached && r.final_error_m <= 0.03*r.distance_m && r.untraversable_frames==0 && r.distance_m <= 1.25*best && r.collisions==0;
        ok += acc as usize;
        println!("seed {seed}: reached {} {:.2} m / {:.2} = {:.3}, err {:.3}, untrav {}, turns {}, frames {}", r.reached, r.distance_m, best, r.distance_m/best, r.final_error_m, r.untraversable_frames, r.exploration_turns, r.frames);
        if std::env::var("PIC").is_ok() { write_picture(nav.danger(), &r, format!("/tmp/var-{seed}.png")).unwrap(); }
    }
    println!("accepted {ok}/{}", seeds.len());
}
