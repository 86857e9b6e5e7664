use tca_messages::{Class, Message, class_of};

use super::*;

fn check<M: Message>(class: Class) {
    let f = M::format().unwrap_or_else(|e| panic!("{}: {e}", M::NAME));
    f.validate().unwrap();
    assert_eq!(class_of::<M>(), class, "{}", M::NAME);
    assert!(M::NAME.starts_with("legged."), "{}", M::NAME);
    if class == Class::Query {
        assert!(M::reply_format().unwrap().is_some(), "{}", M::NAME);
    }
}

#[test]
fn every_message_has_a_format_its_class_and_the_namespace() {
    check::<RobotModel>(Class::Query);
    check::<BodyPose>(Class::Query);
    check::<LegState>(Class::Query);
    check::<LegMove>(Class::Command);
    check::<BodyMove>(Class::Command);
    check::<FootContact>(Class::Inform);
    check::<MoveFailed>(Class::Exception);
    check::<HardwareFault>(Class::Exception);
    check::<TipOver>(Class::Exception);
    check::<LeggedWalk>(Class::Goal);
    check::<SupportState>(Class::Inform);
    check::<LeggedStatus>(Class::Query);
    check::<Telemetry>(Class::Inform);
    check::<LatestTelemetry>(Class::Query);
}

#[test]
fn messages_survive_the_wire() {
    let m = LegMove {
        leg: "left_front".into(),
        waypoints: vec![vec![0.1, -0.2, 0.5], vec![0.0, 0.0, 0.3]],
        transition: true,
    };
    let bytes = postcard::to_allocvec(&m).unwrap();
    assert_eq!(postcard::from_bytes::<LegMove>(&bytes).unwrap(), m);
    let t = TipOver {
        com: WorldPoint {
            x_m: 1.0,
            y_m: 2.0,
            z_m: 2.5,
        },
        margin_m: -0.05,
        standing: vec!["left_front".into(), "right_rear".into()],
        detail: "two feet stood".into(),
    };
    let bytes = postcard::to_allocvec(&t).unwrap();
    assert_eq!(postcard::from_bytes::<TipOver>(&bytes).unwrap(), t);
    // A truncated frame is an error, not a panic.
    assert!(postcard::from_bytes::<TipOver>(&bytes[..bytes.len() / 2]).is_err());
}

#[test]
fn a_pose_lists_in_report_order() {
    let p = Pose {
        x_m: 1.0,
        y_m: 2.0,
        z_m: 3.0,
        roll_rad: 0.1,
        pitch_rad: 0.2,
        yaw_rad: 0.3,
    };
    assert_eq!(p.to_array(), [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]);
    assert!(p.is_finite());
    assert!(
        !Pose {
            yaw_rad: f64::NAN,
            ..p
        }
        .is_finite()
    );
}
