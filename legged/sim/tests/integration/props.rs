//! Property tests: whatever moves are asked for, the simulator never panics, its clock never
//! goes back, a refused move changes nothing, and the robot is never left unstable.

use crate::common;

use common::standing;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use proptest::prelude::*;
use tca_legged_sim::{LeggedSim, MoveError};

/// A move to try: a leg (possibly unknown) with way-points as offsets from its joints, or
/// a body move by an offset and a turn.
#[derive(Debug, Clone)]
enum Try {
    Leg {
        leg: usize,
        offsets: Vec<Vec<f64>>,
        transition: bool,
    },
    Body {
        d: [f64; 3],
        yaw: f64,
    },
}

fn tries() -> impl Strategy<Value = Try> {
    prop_oneof![
        (
            0usize..7,
            prop::collection::vec(prop::collection::vec(-0.4f64..0.4, 2..5), 0..4),
            any::<bool>()
        )
            .prop_map(|(leg, offsets, transition)| Try::Leg {
                leg,
                offsets,
                transition
            }),
        (prop::array::uniform3(-0.08f64..0.08), -0.1f64..0.1)
            .prop_map(|(d, yaw)| Try::Body { d, yaw }),
    ]
}

fn apply(sim: &mut LeggedSim, t: &Try) -> Result<(), MoveError> {
    let h = sim.model().neutral_height();
    match t {
        Try::Leg {
            leg,
            offsets,
            transition,
        } => {
            let legs = sim.model().legs();
            let name = legs
                .get(*leg)
                .map(|l| l.name().to_owned())
                .unwrap_or_else(|| "tail".to_owned());
            let q = sim.posture().get(*leg).cloned().unwrap_or_default();
            let waypoints: Vec<Vec<f64>> = offsets
                .iter()
                .map(|o| {
                    // Offsets of the right length most of the time, so that moves happen.
                    let mut w = q.clone();
                    for (k, v) in w.iter_mut().enumerate() {
                        *v += o.get(k % o.len()).copied().unwrap_or(0.0);
                    }
                    if o.len() == 2 && !w.is_empty() {
                        w.pop();
                    }
                    w
                })
                .collect();
            sim.leg_move(&name, &waypoints, *transition).map(|_| ())
        }
        Try::Body { d, yaw } => {
            let b = sim.body();
            let target = Isometry3::from_parts(
                Translation3::from(b.translation.vector + nalgebra::Vector3::from(*d) * h),
                UnitQuaternion::from_euler_angles(0.0, 0.0, *yaw) * b.rotation,
            );
            sim.body_move(&target).map(|_| ())
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn moves_keep_the_simulator_consistent(
        robot in 0usize..3,
        moves in prop::collection::vec(tries(), 1..8),
    ) {
        let mut sim = standing(common::ROBOTS[robot]);
        let h = sim.model().neutral_height();
        for t in &moves {
            let before = (sim.body(), sim.posture().to_vec(), sim.stance(), sim.clock_s(), sim.counters());
            let anchors: Vec<_> = sim.contact_points();
            let result = apply(&mut sim, t);
            prop_assert!(sim.clock_s() >= before.3, "the clock went back");
            prop_assert!(!sim.fallen(), "told to refuse unstable moves, the robot never falls");
            match &result {
                Err(e) if !e.moved() => {
                    prop_assert_eq!(sim.body(), before.0);
                    prop_assert_eq!(sim.posture(), &before.1[..]);
                    prop_assert_eq!(sim.stance(), before.2.clone());
                    prop_assert_eq!(sim.clock_s(), before.3);
                    prop_assert_eq!(sim.counters(), before.4);
                    prop_assert!(!e.to_string().is_empty());
                }
                _ => {
                    prop_assert_eq!(sim.counters().moves, before.4.moves + 1);
                }
            }
            // Joint limits hold and at least three feet stand with the centre of mass over them.
            for (leg, q) in sim.model().legs().iter().zip(sim.posture()) {
                prop_assert!(leg.within_limits(q), "{:?}", q);
            }
            prop_assert!(sim.stance().iter().filter(|&&s| s).count() >= 3);
            prop_assert!(sim.margin() >= -1e-9, "margin {}", sim.margin());
            // Feet that stood before and stand now have not slid (the moved leg may have
            // lifted off and touched down elsewhere).
            let moved = match t {
                Try::Leg { leg, .. } => Some(*leg),
                Try::Body { .. } => None,
            };
            let now = sim.contact_points();
            for i in 0..now.len() {
                if before.2[i] && sim.stance()[i] && moved != Some(i) {
                    prop_assert!((now[i] - anchors[i]).norm() < 1e-3 * h, "{}: {:?} -> {:?}", i, anchors[i], now[i]);
                }
            }
            // Standing feet are on the ground.
            for (i, p) in now.iter().enumerate() {
                if sim.stance()[i] {
                    let ground = sim.terrain().height_at(p.x, p.y);
                    prop_assert!((p.z - ground).abs() < 2e-3 * h, "{}: {:?} over {}", i, p, ground);
                }
            }
        }
    }

    #[test]
    fn nan_and_infinite_inputs_are_refused(
        leg in 0usize..6,
        k in 0usize..3,
        bad in prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)],
    ) {
        let mut sim = standing("ambler");
        let mut q = sim.posture()[leg].clone();
        q[k] = bad;
        let name = sim.model().legs()[leg].name().to_owned();
        let err = sim.leg_move(&name, &[q], true).unwrap_err();
        prop_assert_eq!(err.kind(), tca_legged_messages::MoveFailureKind::Refused);
        let mut target = sim.body();
        target.translation.vector[k] = bad;
        prop_assert!(sim.body_move(&target).is_err());
        prop_assert_eq!(sim.clock_s(), 0.0);
    }
}
