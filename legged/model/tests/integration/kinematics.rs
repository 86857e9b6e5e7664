//! Forward kinematics, collision placement and the centre of mass of a small robot whose
//! answers are known by hand; fixed joints folded into the legs; point feet and offset feet.

use std::f64::consts::FRAC_PI_2;

use nalgebra::{Point3, Vector3};
use tca_legged_model::{JointKind, RobotModel, Shape};

/// Two legs on a 10 kg body.
///
/// `arm`: a revolute joint about z at (1, 0, 0), a 0.5 m link along x with a fixed joint
/// in the middle of it (the link `arm_outer` carries a box), a prismatic joint sliding
/// along -z, and a foot sphere of radius 0.05 whose centre is 0.1 m below the foot link's
/// origin.
/// `peg`: a prismatic joint along -z at (-1, 0, 0) with limits 0..0.3, a point foot.
const TWO_LEGS: &str = r#"<robot name="two_legs">
  <link name="base">
    <inertial><origin xyz="0 0 0.1"/><mass value="10"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <joint name="arm_yaw" type="revolute">
    <origin xyz="1 0 0"/>
    <parent link="base"/><child link="arm_inner"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1" effort="1"/>
  </joint>
  <link name="arm_inner">
    <inertial><origin xyz="0.125 0 0"/><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <joint name="arm_splice" type="fixed">
    <origin xyz="0.25 0 0" rpy="0 0 0"/>
    <parent link="arm_inner"/><child link="arm_outer"/>
  </joint>
  <link name="arm_outer">
    <inertial><origin xyz="0.125 0 0"/><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision>
      <origin xyz="0.125 0 0" rpy="0 0 0"/>
      <geometry><box size="0.25 0.04 0.02"/></geometry>
    </collision>
  </link>
  <joint name="arm_slide" type="prismatic">
    <origin xyz="0.25 0 0"/>
    <parent link="arm_outer"/><child link="arm_foot"/>
    <axis xyz="0 0 -1"/><limit lower="0" upper="0.5" velocity="0.1" effort="1"/>
  </joint>
  <link name="arm_foot">
    <inertial><mass value="0.5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><origin xyz="0 0 -0.1"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="peg_slide" type="prismatic">
    <origin xyz="-1 0 0" rpy="0 0 1.5707963267948966"/>
    <parent link="base"/><child link="peg_foot"/>
    <axis xyz="0 0 -1"/><limit lower="0" upper="0.3" velocity="0.1" effort="1"/>
  </joint>
  <link name="peg_foot">
    <inertial><mass value="0.5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <joint name="peg_sensor_mount" type="fixed">
    <origin xyz="0 0 0.05"/>
    <parent link="peg_foot"/><child link="peg_sensor"/>
  </joint>
  <link name="peg_sensor">
    <collision><geometry><cylinder radius="0.03" length="0.02"/></geometry></collision>
  </link>
</robot>"#;

fn robot() -> RobotModel {
    RobotModel::from_urdf_str(TWO_LEGS).expect("the two-legged robot loads")
}

fn close(a: Point3<f64>, b: Point3<f64>) {
    assert!((a - b).norm() < 1e-12, "{a} vs {b}");
}

#[test]
fn legs_are_found_and_fixed_joints_folded() {
    let robot = robot();
    assert_eq!(robot.legs().len(), 2);
    let arm = robot.leg("arm").expect("arm");
    let names: Vec<&str> = arm.joints().iter().map(|j| j.name()).collect();
    assert_eq!(
        names,
        ["arm_yaw", "arm_slide"],
        "the fixed splice is not a leg joint"
    );
    assert!(matches!(arm.joints()[0].kind(), JointKind::Revolute { .. }));
    assert!(matches!(
        arm.joints()[1].kind(),
        JointKind::Prismatic { .. }
    ));
    // The splice is folded into the slide's origin: 0.25 + 0.25 m out along the arm.
    let slide = arm.joints()[1].origin().translation.vector;
    assert!((slide - Vector3::new(0.5, 0.0, 0.0)).norm() < 1e-12);
    assert_eq!(arm.joints()[1].child_link(), "arm_foot");
    assert_eq!(arm.foot_radius(), 0.05);
    close(arm.contact_centre(), Point3::new(0.0, 0.0, -0.1));
    let peg = robot.leg("peg").expect("peg");
    assert_eq!(peg.dof(), 1);
    assert_eq!(
        peg.foot_radius(),
        0.0,
        "a foot without collision is a point"
    );
    assert_eq!(robot.leg_index("peg"), Some(1));
    assert_eq!(robot.link("arm_outer").and_then(|l| l.leg()), Some(0));
    assert_eq!(robot.link("arm_outer").map(|l| l.stage()), Some(1));
    assert_eq!(robot.link("base").and_then(|l| l.leg()), None);
    assert!((robot.total_mass() - 13.0).abs() < 1e-12);
}

#[test]
fn forward_kinematics_matches_the_hand_computation() {
    let robot = robot();
    let arm = robot.leg("arm").expect("arm");
    for (yaw, slide) in [(0.0, 0.0), (FRAC_PI_2, 0.2), (-1.0, 0.5), (0.3, 0.1)] {
        let q = [yaw, slide];
        let foot_link = arm.forward_kinematics(&q).expect("fk");
        let expected = Point3::new(1.0 + 0.5 * yaw.cos(), 0.5 * yaw.sin(), -slide);
        close(Point3::from(foot_link.translation.vector), expected);
        // The contact sphere's centre is 0.1 m below the foot link's origin.
        close(
            arm.foot_position(&q).expect("fk"),
            expected - Vector3::new(0.0, 0.0, 0.1),
        );
        // The foot link turns with the arm.
        let x = foot_link.rotation * Vector3::x();
        assert!((x - Vector3::new(yaw.cos(), yaw.sin(), 0.0)).norm() < 1e-12);
    }
    let peg = robot.leg("peg").expect("peg");
    close(
        peg.foot_position(&[0.25]).expect("fk"),
        Point3::new(-1.0, 0.0, -0.25),
    );
    close(peg.base_position(), Point3::new(-1.0, 0.0, 0.0));
}

#[test]
fn collision_shapes_ride_on_their_links() {
    let robot = robot();
    let posture = [vec![FRAC_PI_2, 0.3], vec![0.2]];
    let shapes = robot.collision_shapes(&posture).expect("shapes");
    // The foot spheres are contacts, not obstacle shapes: the box and the sensor remain.
    let links: Vec<&str> = shapes.iter().map(|s| s.link).collect();
    assert_eq!(links, ["arm_outer", "peg_sensor"]);
    let arm_box = shapes[0];
    assert!(matches!(arm_box.shape, Shape::Box { .. }));
    // With the arm turned to +y, the box's centre is 0.375 m out along y from the hip.
    close(
        Point3::from(arm_box.pose.translation.vector),
        Point3::new(1.0, 0.375, 0.0),
    );
    assert!((arm_box.pose.rotation * Vector3::x() - Vector3::y()).norm() < 1e-12);
    assert!((arm_box.lowest_z() + 0.01).abs() < 1e-12);
    // The sensor rides 5 cm above the peg's foot, after the leg's last joint.
    close(
        Point3::from(shapes[1].pose.translation.vector),
        Point3::new(-1.0, 0.0, -0.15),
    );
    assert_eq!(robot.link("peg_sensor").and_then(|l| l.leg()), Some(1));
}

#[test]
fn the_centre_of_mass_matches_the_hand_computation() {
    let robot = robot();
    let (yaw, slide, peg) = (FRAC_PI_2, 0.4, 0.3);
    let com = robot
        .centre_of_mass(&[vec![yaw, slide], vec![peg]])
        .expect("com");
    // base 10 kg at (0, 0, 0.1); arm_inner 1 kg at 0.125 m along the arm, arm_outer 1 kg at
    // 0.375 m, arm_foot 0.5 kg at 0.5 m and `slide` down; peg_foot 0.5 kg at (-1, 0, -peg).
    let arm = |r: f64| Vector3::new(1.0 + r * yaw.cos(), r * yaw.sin(), 0.0);
    let moment = Vector3::new(0.0, 0.0, 0.1) * 10.0
        + arm(0.125)
        + arm(0.375)
        + (arm(0.5) - Vector3::new(0.0, 0.0, slide)) * 0.5
        + Vector3::new(-1.0, 0.0, -peg) * 0.5;
    assert!((com.mass - 13.0).abs() < 1e-12);
    close(com.centre, Point3::from(moment / 13.0));
}

#[test]
fn link_poses_list_every_link_in_file_order() {
    let robot = robot();
    let poses = robot
        .link_poses(&[vec![0.0, 0.0], vec![0.0]])
        .expect("poses");
    let names: Vec<&str> = poses.iter().map(|p| p.link).collect();
    assert_eq!(
        names,
        [
            "base",
            "arm_inner",
            "arm_outer",
            "arm_foot",
            "peg_foot",
            "peg_sensor"
        ]
    );
    close(
        Point3::from(poses[2].pose.translation.vector),
        Point3::new(1.25, 0.0, 0.0),
    );
    // The peg's joint turns its frame by a quarter turn about z.
    let peg_x = poses[4].pose.rotation * Vector3::x();
    assert!((peg_x - Vector3::y()).norm() < 1e-12);
}

#[test]
fn the_neutral_posture_clamps_zero_into_the_limits() {
    let urdf = TWO_LEGS.replace(
        r#"<limit lower="0" upper="0.3" velocity="0.1" effort="1"/>"#,
        r#"<limit lower="0.1" upper="0.3" velocity="0.1" effort="1"/>"#,
    );
    let robot = RobotModel::from_urdf_str(&urdf).expect("loads");
    assert_eq!(robot.neutral_posture(), vec![vec![0.0, 0.0], vec![0.1]]);
    let peg = robot.leg("peg").expect("peg");
    assert_eq!(peg.middle(), vec![0.2]);
    assert!(peg.within_limits(&[0.3]) && !peg.within_limits(&[0.31]) && !peg.within_limits(&[]));
    assert_eq!(peg.clamp(&[5.0]), vec![0.3]);
    // The neutral height averages the legs: the arm's sphere bottom at 0.15 m, the peg's
    // point at 0.1 m below the body.
    assert!((robot.neutral_height() - 0.125).abs() < 1e-12);
}

#[test]
fn one_legs_shapes_are_its_share_of_the_whole_robots() {
    let robot = RobotModel::builtin("athlete").expect("loads");
    let mut posture = robot.neutral_posture();
    posture[2] = vec![0.3, 0.5, -0.4, 0.2, 0.1, 1.0];
    let all = robot.collision_shapes(&posture).expect("placed");
    for (leg, q) in posture.iter().enumerate() {
        let mine = robot.leg_collision_shapes(leg, q).expect("placed");
        let share: Vec<_> = all
            .iter()
            .filter(|s| robot.link(s.link).and_then(|l| l.leg()) == Some(leg))
            .collect();
        assert_eq!(mine.len(), share.len());
        for (a, b) in mine.iter().zip(share) {
            assert_eq!(a.link, b.link);
            assert!((a.pose.translation.vector - b.pose.translation.vector).norm() < 1e-12);
        }
    }
    assert!(robot.leg_collision_shapes(9, &posture[0]).is_err());
    assert!(robot.leg_collision_shapes(0, &[0.0]).is_err());
}
