//! Sag: a compliant robot droops under load when a leg lifts, so that a commanded lift
//! leaves the foot lower, and rises back when the foot is down again.

use crate::common;

use common::{ORIGIN, flat_for, model, through};
use nalgebra::Vector3;
use tca_legged_sim::{LeggedSim, SagParams, SimParams};

fn athlete(sag: Option<SagParams>) -> LeggedSim {
    let m = model("athlete");
    let t = flat_for(&m);
    let mut p = SimParams::for_model(&m);
    p.sag = sag;
    LeggedSim::new(m, t, ORIGIN, p).expect("stands")
}

#[test]
fn a_twenty_centimetre_lift_leaves_a_sagging_wheel_lower_and_the_body_rises_back() {
    for leg in 0..6 {
        let mut rigid = athlete(None);
        let mut soft = athlete(Some(SagParams::athlete()));
        let name = rigid.model().legs()[leg].name().to_owned();
        let start = soft.foot_centres()[leg];
        let up = through(&soft, leg, &[Vector3::new(0.0, 0.0, 0.2)]);
        rigid.leg_move(&name, &up, false).unwrap();
        soft.leg_move(&name, &up, false).unwrap();
        let rigid_rise = rigid.real_foot_centre(leg).unwrap().z - start.z;
        let soft_rise = soft.real_foot_centre(leg).unwrap().z - start.z;
        println!("{name}: rigid {rigid_rise:.3} m, sagging {soft_rise:.3} m");
        assert!((rigid_rise - 0.2).abs() < 1e-3, "{name}: {rigid_rise}");
        let drop = soft.sag_drop_m(leg);
        assert!(
            (0.10..0.15).contains(&drop),
            "{name}: the wheel sags {drop:.3} m"
        );
        assert!(
            (soft_rise - (0.2 - drop)).abs() < 2e-3,
            "{name}: {soft_rise} vs {drop}"
        );
        assert_eq!(soft.counters().collisions, 0);
        // Put it back down: it lands, and the robot's body is where it was.
        let body = soft.body();
        let down = through(&soft, leg, &[Vector3::new(0.0, 0.0, -0.3)]);
        soft.leg_move(&name, &down, true).unwrap();
        assert!(soft.stance()[leg]);
        assert_eq!(soft.body(), body);
        assert!(soft.sag_drop_m(leg).abs() < 1e-9);
        // It lands on the ground, a few centimetres in: the body leaned toward it.
        let landed = soft.foot_centres()[leg];
        assert!((landed.z - start.z).abs() < 1e-3, "{name}: landed {landed}");
        assert!(
            (landed - start).norm() < 0.08,
            "{name}: landed {landed} vs {start}"
        );
    }
}

#[test]
fn a_lift_smaller_than_the_sag_never_leaves_the_ground() {
    let mut soft = athlete(Some(SagParams::athlete()));
    let start = soft.foot_centres()[0];
    let up = through(&soft, 0, &[Vector3::new(0.0, 0.0, 0.05)]);
    let name = soft.model().legs()[0].name().to_owned();
    soft.leg_move(&name, &up, false).unwrap();
    let real = soft.real_foot_centre(0).unwrap();
    assert!((real.z - start.z).abs() < 2e-3, "{}", real.z - start.z);
}

#[test]
fn bad_sag_parameters_are_refused() {
    let m = model("athlete");
    let mut p = SimParams::for_model(&m);
    p.sag = Some(SagParams {
        leg_stiffness_n_per_m: 0.0,
        joint_compliance_rad_per_nm: 0.0,
    });
    let e = LeggedSim::new(m, flat_for(&model("athlete")), ORIGIN, p).unwrap_err();
    assert!(e.to_string().contains("leg_stiffness_n_per_m"), "{e}");
}
