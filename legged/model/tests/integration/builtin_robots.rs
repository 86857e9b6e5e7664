//! The shipped robots load, have the legs, joints and masses their files document, and stand.

use nalgebra::{Point3, Vector3};
use tca_legged_model::{BUILTIN_ROBOTS, JointKind, RobotModel};

const LEG_NAMES: [&str; 6] = [
    "left_front",
    "left_middle",
    "left_rear",
    "right_front",
    "right_middle",
    "right_rear",
];

/// Leg names of the eight-legged and the numbered six-legged robots.
const NUMBERED: [&str; 8] = [
    "left_1", "left_2", "left_3", "left_4", "right_1", "right_2", "right_3", "right_4",
];
const NUMBERED6: [&str; 6] = [
    "left_1", "left_2", "left_3", "right_1", "right_2", "right_3",
];

/// Name, leg names, joints per leg, total mass (kg), foot radius (m), neutral standing
/// height (m).
type Expected = (&'static str, &'static [&'static str], usize, f64, f64, f64);
const EXPECTED: [Expected; 6] = [
    ("ambler", &LEG_NAMES, 3, 2500.0, 0.15, 2.6),
    ("hexapod", &LEG_NAMES, 3, 2.5, 0.012, 0.242),
    ("athlete", &LEG_NAMES, 6, 850.0, 0.25, 1.55),
    ("spider", &NUMBERED, 3, 67.6, 0.05, 0.55),
    ("polybot6", &NUMBERED6, 3, 7.72, 0.015, 0.135),
    ("polybot8", &NUMBERED, 3, 10.16, 0.015, 0.135),
];

fn robot(name: &str) -> RobotModel {
    RobotModel::builtin(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn every_shipped_robot_loads_with_its_documented_shape() {
    assert_eq!(BUILTIN_ROBOTS.len(), EXPECTED.len());
    for (name, legs, dof, mass, radius, height) in EXPECTED {
        let robot = robot(name);
        assert_eq!(robot.name(), name);
        assert_eq!(robot.body_link(), "body");
        let names: Vec<&str> = robot.legs().iter().map(|l| l.name()).collect();
        assert_eq!(names, legs, "{name}");
        for leg in robot.legs() {
            assert_eq!(leg.dof(), dof, "{name} {}", leg.name());
            assert_eq!(leg.foot_link(), format!("{}_foot", leg.name()));
            assert_eq!(leg.foot_radius(), radius, "{name} {}", leg.name());
        }
        assert_eq!(robot.dof(), legs.len() * dof);
        assert!(
            (robot.total_mass() - mass).abs() < 1e-9 * mass,
            "{name}: {} kg",
            robot.total_mass()
        );
        assert!(
            (robot.neutral_height() - height).abs() < 1e-9,
            "{name}: stands at {} m",
            robot.neutral_height()
        );
    }
}

#[test]
fn load_finds_shipped_robots_by_name_and_files_by_path() {
    let by_name = RobotModel::load("hexapod").expect("by name");
    let dir = tempfile::tempdir().expect("temporary directory");
    let path = dir.path().join("my_hexapod.urdf");
    std::fs::write(&path, BUILTIN_ROBOTS[1].urdf).expect("write");
    let by_path = RobotModel::load(path.to_str().expect("utf-8 path")).expect("by path");
    assert_eq!(by_name, by_path);
    assert_eq!(RobotModel::from_file(&path).expect("from_file"), by_name);
}

#[test]
fn the_amblers_legs_are_the_testbeds_kind() {
    let robot = robot("ambler");
    for leg in robot.legs() {
        let q = leg.neutral();
        let frames = leg.joint_frames(&q).expect("frames");
        let kinds: Vec<JointKind> = leg.joints().iter().map(|j| j.kind()).collect();
        assert!(matches!(kinds[0], JointKind::Revolute { .. }));
        assert!(matches!(kinds[1], JointKind::Revolute { .. }));
        assert!(matches!(kinds[2], JointKind::Prismatic { .. }));
        for (i, joint) in leg.joints().iter().enumerate() {
            // The axis in the body frame: vertical for the rotary joints, down for the slide.
            let axis = frames[i].rotation * joint.kind().axis().into_inner();
            let expected = if i < 2 { Vector3::z() } else { -Vector3::z() };
            assert!(
                (axis - expected).norm() < 1e-9,
                "{} axis {axis:?}",
                joint.name()
            );
        }
        // Positive vertical motion lowers the foot, 2.4 m of travel.
        let mut down = q.clone();
        down[2] = leg.joints()[2].limits().upper;
        let mut up = q.clone();
        up[2] = leg.joints()[2].limits().lower;
        let low = leg.foot_position(&down).expect("fk").z;
        let high = leg.foot_position(&up).expect("fk").z;
        assert!(
            (high - low - 2.4).abs() < 1e-9,
            "{}: travel {}",
            leg.name(),
            high - low
        );
    }
}

#[test]
fn the_ambler_clears_boulders_and_reaches_into_ditches() {
    let robot = robot("ambler");
    let height = robot.neutral_height();
    let posture = robot.neutral_posture();
    let lowest_body = robot
        .collision_shapes(&posture)
        .expect("shapes")
        .iter()
        .filter(|s| robot.link(s.link).and_then(|l| l.leg()).is_none())
        .map(|s| s.lowest_z())
        .fold(f64::INFINITY, f64::min);
    assert!(
        lowest_body + height >= 2.0 - 1e-9,
        "the body's underside is {:.2} m up",
        lowest_body + height
    );
    for leg in robot.legs() {
        let reach = leg.workspace_summary(512);
        let ground = -height + leg.foot_radius();
        // The foot reaches onto a one-metre boulder and to the bottom of a one-metre ditch.
        assert!(reach.max.z >= ground + 1.0 - 1e-9, "{reach}");
        assert!(reach.min.z <= ground - 1.0 + 1e-9, "{reach}");
        // Horizontal links of 1.5 and 1.3 m.
        assert!(
            reach.reach_max_m > 2.5 && reach.reach_max_m <= 2.8,
            "{reach}"
        );
    }
}

#[test]
fn every_foot_reaches_the_ground_at_the_nominal_standing_pose_and_around_it() {
    for (name, ..) in EXPECTED {
        let robot = robot(name);
        let nominal = robot.neutral_height();
        for factor in [1.0, 0.9, 1.1] {
            let height = nominal * factor;
            let posture = robot
                .standing_posture(height)
                .unwrap_or_else(|e| panic!("{name} at {height:.3} m: {e}"));
            let feet = robot.foot_positions(&posture).expect("feet");
            for ((leg, foot), target) in robot
                .legs()
                .iter()
                .zip(&feet)
                .zip(robot.standing_feet(height))
            {
                assert!(leg.within_limits(&posture[robot.leg_index(leg.name()).unwrap()]));
                assert!(
                    (foot - target).norm() < 1e-3,
                    "{name} {}: {foot} vs {target}",
                    leg.name()
                );
                assert!((foot.z - leg.foot_radius() + height).abs() < 1e-3);
            }
        }
    }
}

#[test]
fn standing_neutral_nothing_but_the_feet_touches_level_ground() {
    for (name, ..) in EXPECTED {
        let robot = robot(name);
        let ground = -robot.neutral_height();
        let posture = robot.neutral_posture();
        for shape in robot.collision_shapes(&posture).expect("shapes") {
            assert!(
                shape.lowest_z() > ground + 0.01,
                "{name}: {} reaches down to {:.3} m (ground at {ground:.3})",
                shape.link,
                shape.lowest_z()
            );
        }
    }
}

#[test]
fn standing_neutral_the_centre_of_mass_is_over_the_feet() {
    for (name, ..) in EXPECTED {
        let robot = robot(name);
        let posture = robot.neutral_posture();
        let com = robot.centre_of_mass(&posture).expect("com");
        assert!((com.mass - robot.total_mass()).abs() < 1e-12);
        let feet = robot.foot_positions(&posture).expect("feet");
        // The feet's bounding box in x and y holds the centre of mass well inside.
        let (min, max) = feet.iter().fold(
            (
                Point3::new(f64::INFINITY, f64::INFINITY, 0.0),
                Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0),
            ),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        for axis in 0..2 {
            let margin = (max[axis] - min[axis]) / 4.0;
            assert!(
                com.centre[axis] > min[axis] + margin && com.centre[axis] < max[axis] - margin,
                "{name}: centre of mass {:?} near the edge of the feet {min:?}..{max:?}",
                com.centre
            );
        }
        // Left-right symmetric robots have it on the centre line, below the body origin.
        assert!(com.centre.y.abs() < 1e-9, "{name}: {:?}", com.centre);
        assert!(com.centre.z < 0.0, "{name}: {:?}", com.centre);
    }
}

#[test]
fn link_poses_agree_with_each_legs_forward_kinematics() {
    for (name, ..) in EXPECTED {
        let robot = robot(name);
        let posture: Vec<Vec<f64>> = robot.legs().iter().map(|l| l.middle()).collect();
        let poses = robot.link_poses(&posture).expect("poses");
        assert_eq!(poses.len(), robot.links().len());
        for (i, leg) in robot.legs().iter().enumerate() {
            let foot = robot.forward_kinematics(i, &posture[i]).expect("fk");
            let listed = poses
                .iter()
                .find(|p| p.link == leg.foot_link())
                .expect("foot listed");
            assert!((foot.translation.vector - listed.pose.translation.vector).norm() < 1e-12);
            assert!(foot.rotation.angle_to(&listed.pose.rotation) < 1e-12);
            // The last joint frame is the child link of the last joint.
            let frames = leg.joint_frames(&posture[i]).expect("frames");
            let last = leg.joints().last().expect("joints");
            let child = poses
                .iter()
                .find(|p| p.link == last.child_link())
                .expect("child listed");
            let frame = frames.last().expect("frame");
            assert!((frame.translation.vector - child.pose.translation.vector).norm() < 1e-12);
        }
    }
}

#[test]
fn workspace_summaries_print_and_hold_the_neutral_foot() {
    for (name, ..) in EXPECTED {
        let robot = robot(name);
        for leg in robot.legs() {
            let summary = leg.workspace_summary(2000);
            assert_eq!(summary.samples, 2000);
            let text = summary.to_string();
            assert!(text.starts_with(leg.name()), "{text}");
            let foot = leg.foot_position(&leg.neutral()).expect("fk");
            for axis in 0..3 {
                assert!(
                    summary.min[axis] <= foot[axis] && foot[axis] <= summary.max[axis],
                    "{text}"
                );
            }
            assert!(summary.reach_min_m <= summary.reach_max_m);
            assert_eq!(
                leg.workspace_samples(100),
                leg.workspace_samples(100),
                "deterministic"
            );
        }
    }
}

#[test]
fn the_ambler_stands_level_on_a_30_degree_slope_walked_up_or_down() {
    let robot = robot("ambler");
    let height = robot.neutral_height();
    let rise = 30f64.to_radians().tan();
    for direction in [1.0, -1.0] {
        for (leg, flat) in robot.legs().iter().zip(robot.standing_feet(height)) {
            // The ground under the body origin stays `height` below it; it rises with x.
            let target = Point3::new(flat.x, flat.y, flat.z + direction * rise * flat.x);
            let options = tca_legged_model::IkOptions::starting_at(&leg.neutral());
            let solution = leg
                .inverse_kinematics(&target, &options)
                .unwrap_or_else(|e| panic!("slope {direction:+}: {e}"));
            assert!(leg.within_limits(&solution.joints));
        }
    }
}
