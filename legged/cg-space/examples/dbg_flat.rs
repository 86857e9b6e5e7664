use nalgebra::Point2;
use tca_cg_space::{CgParams, CgSpace, PlanParams, plan};
use tca_legged_model::RobotModel;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let course = args.get(1).cloned().unwrap_or("flat".into());
    let model = RobotModel::builtin("ambler").unwrap();
    let (t, s, g) = if course == "flat" {
        (tca_robot::HeightField::flat(Point2::new(0.0, -8.0), Point2::new(30.0, 8.0), 0.1, 0.0).unwrap(), Point2::new(4.0, 0.0), Point2::new(24.0, 0.0))
    } else {
        let seed: u64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(1); let c = tca_legged_courses::Course::builtin(&course, seed).unwrap();
        (c.terrain, Point2::new(4.0,0.0), Point2::new(24.0,0.0))
    };
    let mut space = CgSpace::for_model(&model, &t, CgParams { theta_bins: Some(1), stability_margin_m: Some(0.165), ..CgParams::default() }).unwrap();
    let mut params = PlanParams::default();
    params.search.stall_nodes = 1000;
    params.mark_radius = 2;
    params.max_replans = 60;
    let began = std::time::Instant::now();
    let r = plan(&mut space, (s, 0.0), (g, 0.0), None, &params);
    match r {
        Ok(p) => println!("ok: {} steps, {} cells, marked {:?}, counts {:?}, {:.2}s", p.feet.steps.len(), p.feet.route.len(), p.marked, p.counts, began.elapsed().as_secs_f64()),
        Err(e) => println!("err {e} {:.2}s", began.elapsed().as_secs_f64()),
    }
    for (i, c) in tca_cg_space::footcheck::DBG.iter().enumerate() {
        let v = c.load(std::sync::atomic::Ordering::Relaxed);
        if v > 0 { println!("dbg {i}: {v}"); }
    }
}
#[allow(dead_code)]
fn dump() {}
