use tca_messages::{Class, Message, class_of};

use super::*;

fn check<M: Message>(class: Class) {
    let f = M::format().unwrap_or_else(|e| panic!("{}: {e}", M::NAME));
    f.validate().unwrap();
    assert_eq!(class_of::<M>(), class, "{}", M::NAME);
    assert!(M::NAME.starts_with("nav."), "{}", M::NAME);
    if class == Class::Query {
        assert!(M::reply_format().unwrap().is_some(), "{}", M::NAME);
    }
}

#[test]
fn every_message_has_a_format_its_class_and_the_namespace() {
    check::<Drive>(Class::Query);
    check::<TruePose>(Class::Query);
    check::<SimStatus>(Class::Query);
    check::<AcquireDepth>(Class::Query);
    check::<InsertDepth>(Class::Query);
    check::<DangerMapQuery>(Class::Query);
    check::<Navigate>(Class::Goal);
    check::<NavFrame>(Class::Inform);
}

#[test]
fn a_depth_frame_survives_the_wire() {
    let f = DepthFrame {
        frame: 3,
        width: 2,
        height: 1,
        depth_m: vec![0.0, 1.5],
        estimate: PlanarPose {
            x_m: 1.0,
            y_m: -2.0,
            yaw_rad: 0.5,
        },
        base_z_m: 0.25,
        base_roll_rad: 0.01,
        base_pitch_rad: -0.02,
    };
    let bytes = postcard::to_allocvec(&InsertDepth { frame: f.clone() }).unwrap();
    assert_eq!(
        postcard::from_bytes::<InsertDepth>(&bytes).unwrap().frame,
        f
    );
    let c = DangerChanges {
        frames: 1,
        estimate: PlanarPose::default(),
        registered: true,
        cells: vec![CellDangerMsg {
            ix: 1,
            iy: 2,
            danger: None,
            certainty: 0.5,
        }],
    };
    let bytes = postcard::to_allocvec(&c).unwrap();
    assert_eq!(postcard::from_bytes::<DangerChanges>(&bytes).unwrap(), c);
}
