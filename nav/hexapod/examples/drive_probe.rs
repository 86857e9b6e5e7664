use std::sync::Arc;
use tca_legged_model::RobotModel;
use tca_nav_hexapod::*;
use tca_nav_navigator::{Base, Pose2, hill_course};
use tca_free_gait::GaitState;

fn main() {
    let course = hill_course().unwrap();
    let model = Arc::new(RobotModel::builtin("hexapod").unwrap());
    let terrain = Arc::new(course.terrain.clone());
    let params = StepperParams::for_model(&model);
    println!("{params:?}");
    let stepper = Stepper::new(model.clone(), terrain.clone(), params.clone());
    let mut base = HexapodBase::new(model, terrain, course.start, params).unwrap();
    let _ = (&stepper, GaitState::clone);
    for (v, w) in [(0.06, 0.0), (0.06, 0.0), (0.0, 0.4), (0.06, 0.2)] {
        for _ in 0..5 {
            let t = std::time::Instant::now();
            let m = base.drive(v, w, 0.25);
            println!("{v} {w}: {:?} {:?} stalls {} clock {:.2} moves {} in {:?}", m.pose, (m.collided, m.fell), base.stalls(), base.sim().clock_s(), base.sim().counters().moves, t.elapsed());
        }
    }
    let _ = Pose2::default();
}
