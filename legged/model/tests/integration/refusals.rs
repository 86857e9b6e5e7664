//! Descriptions that break the conventions are refused with the name of the joint or link,
//! the reason and what to do; bad input never panics.

use proptest::prelude::*;
use tca_legged_model::{BUILTIN_ROBOTS, JointProblem, LinkProblem, ModelError, RobotModel};

/// A valid one-legged robot; tests break one thing in it at a time.
const VALID: &str = r#"<?xml version="1.0"?>
<robot name="probe">
  <link name="base">
    <inertial><mass value="10"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><geometry><box size="0.4 0.3 0.1"/></geometry></collision>
  </link>
  <joint name="hip" type="revolute">
    <origin xyz="0.2 0.1 0"/>
    <parent link="base"/><child link="thigh"/>
    <axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" velocity="2" effort="10"/>
  </joint>
  <link name="thigh">
    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.05 0.05"/></geometry></collision>
  </link>
  <joint name="knee" type="prismatic">
    <origin xyz="0.3 0 0"/>
    <parent link="thigh"/><child link="shin"/>
    <axis xyz="0 0 -1"/>
    <limit lower="0" upper="0.4" velocity="0.1" effort="100"/>
  </joint>
  <link name="shin"/>
  <joint name="ankle" type="fixed">
    <origin xyz="0 0 -0.2"/>
    <parent link="shin"/><child link="probe_foot"/>
  </joint>
  <link name="probe_foot">
    <collision><geometry><sphere radius="0.02"/></geometry></collision>
  </link>
</robot>
"#;

fn refuse(urdf: &str) -> ModelError {
    match RobotModel::from_urdf_str(urdf) {
        Ok(robot) => panic!("accepted a robot that should be refused: {}", robot.name()),
        Err(e) => e,
    }
}

/// The message names every one of `needles`.
fn says(error: &ModelError, needles: &[&str]) {
    let message = error.to_string();
    assert!(
        !message.contains('\n'),
        "a message on one line: {message:?}"
    );
    for needle in needles {
        assert!(
            message.contains(needle),
            "`{needle}` missing from: {message}"
        );
    }
}

fn with(from: &str, to: &str) -> String {
    assert!(VALID.contains(from), "the probe robot has no `{from}`");
    VALID.replacen(from, to, 1)
}

#[test]
fn the_probe_robot_itself_loads() {
    let robot = RobotModel::from_urdf_str(VALID).expect("valid");
    assert_eq!(robot.legs().len(), 1);
    assert_eq!(robot.legs()[0].name(), "probe");
    assert_eq!(robot.legs()[0].dof(), 2);
}

#[test]
fn a_continuous_joint() {
    let e = refuse(&with(
        r#"name="hip" type="revolute""#,
        r#"name="hip" type="continuous""#,
    ));
    assert!(matches!(
        &e,
        ModelError::Joint { joint, problem: JointProblem::Continuous } if joint == "hip"
    ));
    says(
        &e,
        &[
            "`hip`",
            "continuous",
            "without position limits",
            "make it `revolute`",
            "<limit",
        ],
    );
}

#[test]
fn floating_and_planar_joints() {
    for kind in ["floating", "planar"] {
        let e = refuse(&with(
            r#"name="hip" type="revolute""#,
            &format!(r#"name="hip" type="{kind}""#),
        ));
        says(&e, &["`hip`", kind, "`revolute`, `prismatic` and `fixed`"]);
    }
}

#[test]
fn a_moving_joint_without_limits() {
    let e = refuse(&with(
        r#"<limit lower="-1" upper="1" velocity="2" effort="10"/>"#,
        "",
    ));
    assert!(matches!(
        &e,
        ModelError::Joint { joint, problem: JointProblem::MissingLimits { kind: "revolute" } }
            if joint == "hip"
    ));
    says(&e, &["`hip`", "no <limit>", "lower=", "velocity="]);
}

#[test]
fn limits_that_are_missing_in_urdf_1_2() {
    let urdf = with(
        r#"<robot name="probe">"#,
        r#"<robot name="probe" version="1.2">"#,
    )
    .replacen(
        r#"<limit lower="-1" upper="1" velocity="2" effort="10"/>"#,
        r#"<limit velocity="2" effort="10"/>"#,
        1,
    );
    let e = refuse(&urdf);
    says(
        &e,
        &["`hip`", "no finite position limits", "`lower` and `upper`"],
    );
}

#[test]
fn lower_above_upper() {
    let e = refuse(&with(r#"lower="-1" upper="1""#, r#"lower="1" upper="-1""#));
    says(
        &e,
        &["`hip`", "lower limit 1 above its upper limit -1", "swap"],
    );
}

#[test]
fn zero_velocity() {
    let e = refuse(&with(r#"velocity="2""#, r#"velocity="0""#));
    assert!(matches!(
        &e,
        ModelError::Joint {
            problem: JointProblem::ZeroVelocity,
            ..
        }
    ));
    says(&e, &["`hip`", "velocity limit of 0", "greater than 0"]);
}

#[test]
fn negative_effort_and_velocity() {
    says(
        &refuse(&with(r#"effort="10""#, r#"effort="-1""#)),
        &["`hip`", "effort"],
    );
    says(
        &refuse(&with(r#"velocity="2""#, r#"velocity="-2""#)),
        &["`hip`", "velocity limit of -2"],
    );
}

#[test]
fn a_zero_axis() {
    let e = refuse(&with(r#"<axis xyz="0 0 1"/>"#, r#"<axis xyz="0 0 0"/>"#));
    says(&e, &["`hip`", "axis (0, 0, 0)", "direction"]);
}

#[test]
fn a_mimic_joint() {
    let e = refuse(&with(
        r#"<axis xyz="0 0 -1"/>"#,
        r#"<axis xyz="0 0 -1"/><mimic joint="hip"/>"#,
    ));
    says(&e, &["`knee`", "<mimic>", "`hip`"]);
}

#[test]
fn a_mesh_collision() {
    let e = refuse(&with(
        r#"<box size="0.3 0.05 0.05"/>"#,
        r#"<mesh filename="package://probe/thigh.stl"/>"#,
    ));
    assert!(matches!(
        &e,
        ModelError::Link { link, problem: LinkProblem::MeshCollision { .. } } if link == "thigh"
    ));
    says(
        &e,
        &[
            "`thigh`",
            "mesh",
            "thigh.stl",
            "refused",
            "primitive shapes",
        ],
    );
}

#[test]
fn a_collision_shape_of_no_size() {
    let e = refuse(&with(
        r#"<box size="0.3 0.05 0.05"/>"#,
        r#"<box size="0.3 0 0.05"/>"#,
    ));
    says(&e, &["`thigh`", "box", "size y", "above 0"]);
}

#[test]
fn no_foot_links() {
    let e = refuse(&VALID.replace("probe_foot", "probe_toe"));
    assert!(matches!(e, ModelError::NoLegs));
    says(&e, &["no leg", "`_foot`", "left_front_foot"]);
}

#[test]
fn malformed_xml() {
    let e = refuse(&VALID.replacen("</robot>", "</robo", 1));
    assert!(matches!(e, ModelError::Parse { .. }));
    says(&e, &["not a readable URDF document", "well-formed XML"]);
    says(
        &refuse("this is not XML"),
        &["not a readable URDF document"],
    );
    says(&refuse(""), &["not a readable URDF document"]);
}

#[test]
fn a_document_that_is_not_a_robot() {
    let e = refuse(
        &VALID
            .replace("<robot", "<machine")
            .replace("</robot>", "</machine>"),
    );
    says(&e, &["top element is <machine>, not <robot>"]);
}

#[test]
fn a_required_attribute_missing() {
    let e = refuse(&with(r#"<child link="thigh"/>"#, "<child/>"));
    says(&e, &["not a readable URDF document", "link"]);
}

#[test]
fn a_moving_joint_shared_by_two_legs() {
    // A second foot hanging from the thigh: the hip moves both feet.
    let urdf = with(
        "</robot>",
        r#"<joint name="split" type="revolute">
    <parent link="thigh"/><child link="other_foot"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="1" effort="1"/>
  </joint>
  <link name="other_foot"/>
</robot>"#,
    );
    let e = refuse(&urdf);
    assert!(matches!(
        &e,
        ModelError::Joint { joint, problem: JointProblem::SharedByLegs { .. } } if joint == "hip"
    ));
    says(
        &e,
        &["`hip`", "`probe`", "`other`", "branches into two feet"],
    );
}

#[test]
fn a_shared_fixed_joint_belongs_to_the_body() {
    // Two legs hanging from one rigid mount: allowed, the mount is part of the body.
    let urdf = r#"<robot name="mount">
  <link name="base"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="bolt" type="fixed"><origin xyz="0 0 -0.1"/><parent link="base"/><child link="plate"/></joint>
  <link name="plate"/>
  <joint name="a_hip" type="revolute"><origin xyz="0.1 0 0"/><parent link="plate"/><child link="a_foot"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
  <link name="a_foot"/>
  <joint name="b_hip" type="revolute"><origin xyz="-0.1 0 0"/><parent link="plate"/><child link="b_foot"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
  <link name="b_foot"/>
</robot>"#;
    let robot = RobotModel::from_urdf_str(urdf).expect("shared fixed joints are the body's");
    assert_eq!(robot.legs().len(), 2);
    assert_eq!(robot.link("plate").and_then(|l| l.leg()), None);
    let base = robot.legs()[0].base_position();
    assert!((base - nalgebra::Point3::new(0.1, 0.0, -0.1)).norm() < 1e-12);
}

#[test]
fn a_moving_joint_that_leads_to_no_foot() {
    let urdf = with(
        "</robot>",
        r#"<joint name="camera_pan" type="revolute">
    <parent link="base"/><child link="camera"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/>
  </joint>
  <link name="camera"/>
</robot>"#,
    );
    let e = refuse(&urdf);
    says(
        &e,
        &[
            "`camera_pan`",
            "no foot is beyond it",
            "`fixed`",
            "`<leg>_foot`",
        ],
    );
}

#[test]
fn a_fixed_part_off_the_legs_is_body() {
    let urdf = with(
        "</robot>",
        r#"<joint name="mast" type="fixed"><origin xyz="0 0 0.5"/><parent link="base"/><child link="camera"/></joint>
  <link name="camera">
    <inertial><origin xyz="0 0 0.1"/><mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
</robot>"#,
    );
    let robot = RobotModel::from_urdf_str(&urdf).expect("fixed parts are fine");
    assert_eq!(robot.link("camera").and_then(|l| l.leg()), None);
    assert!((robot.total_mass() - 13.0).abs() < 1e-12);
}

#[test]
fn several_roots() {
    let e = refuse(&with("</robot>", r#"<link name="spare"/></robot>"#));
    assert!(matches!(&e, ModelError::SeveralRoots { roots } if roots == &["base", "spare"]));
    says(
        &e,
        &["several root links (base, spare)", "connect the others"],
    );
}

#[test]
fn a_link_that_cannot_be_reached() {
    let urdf = with(
        "</robot>",
        r#"<link name="ring_a"/><link name="ring_b"/>
  <joint name="ab" type="fixed"><parent link="ring_a"/><child link="ring_b"/></joint>
  <joint name="ba" type="fixed"><parent link="ring_b"/><child link="ring_a"/></joint>
</robot>"#,
    );
    let e = refuse(&urdf);
    says(
        &e,
        &["`ring_a`", "cannot be reached from the body `base`", "loop"],
    );
}

#[test]
fn a_loop_through_every_link() {
    let urdf = r#"<robot name="ring">
  <link name="a"/><link name="b_foot"/>
  <joint name="ab" type="fixed"><parent link="a"/><child link="b_foot"/></joint>
  <joint name="ba" type="fixed"><parent link="b_foot"/><child link="a"/></joint>
</robot>"#;
    says(&refuse(urdf), &["no root link", "loop"]);
}

#[test]
fn a_link_with_two_parents() {
    let urdf = with(
        "</robot>",
        r#"<joint name="brace" type="fixed"><parent link="base"/><child link="shin"/></joint></robot>"#,
    );
    says(
        &refuse(&urdf),
        &["`brace`", "`shin`", "joint `knee` already does"],
    );
}

#[test]
fn an_undefined_link() {
    let e = refuse(&with(r#"<child link="thigh"/>"#, r#"<child link="thgh"/>"#));
    says(&e, &["`hip`", "child link `thgh`", "does not define"]);
}

#[test]
fn duplicate_names() {
    let e = refuse(&with(r#"name="knee" type"#, r#"name="hip" type"#));
    says(&e, &["joint `hip`", "more than once"]);
    let e = refuse(&with(
        r#"<link name="shin"/>"#,
        r#"<link name="shin"/><link name="shin"/>"#,
    ));
    says(&e, &["link `shin`", "more than once"]);
}

#[test]
fn a_foot_that_is_not_a_sphere() {
    let e = refuse(&with(
        r#"<sphere radius="0.02"/>"#,
        r#"<box size="0.1 0.1 0.02"/>"#,
    ));
    assert!(matches!(
        &e,
        ModelError::Link {
            problem: LinkProblem::FootShape { .. },
            ..
        }
    ));
    says(&e, &["`probe_foot`", "one sphere", "box"]);
}

#[test]
fn a_foot_without_a_moving_joint() {
    let urdf = with(
        "</robot>",
        r#"<joint name="peg" type="fixed"><parent link="base"/><child link="peg_foot"/></joint>
  <link name="peg_foot"/></robot>"#,
    );
    says(
        &refuse(&urdf),
        &["`peg_foot`", "no revolute or prismatic joint"],
    );
}

#[test]
fn badly_named_feet() {
    says(
        &refuse(&VALID.replace("probe_foot", "_foot")),
        &["`_foot`", "`<leg>_foot`"],
    );
    let urdf = VALID.replace("\"base\"", "\"body_foot\"");
    says(&refuse(&urdf), &["`body_foot`", "root link", "rename"]);
}

#[test]
fn bad_masses() {
    let e = refuse(&with(r#"<mass value="10"/>"#, r#"<mass value="-10"/>"#));
    says(&e, &["`base`", "mass -10"]);
    let e = refuse(
        &VALID
            .replace(r#"<mass value="10"/>"#, r#"<mass value="0"/>"#)
            .replace(r#"<mass value="1"/>"#, r#"<mass value="0"/>"#),
    );
    assert!(matches!(e, ModelError::NoMass));
    says(&e, &["no mass", "<inertial>"]);
}

#[test]
fn numbers_that_are_not_finite() {
    let e = refuse(&with(
        r#"<origin xyz="0.3 0 0"/>"#,
        r#"<origin xyz="inf 0 0"/>"#,
    ));
    says(&e, &["`knee`", "not a finite number"]);
}

#[test]
fn missing_files_and_unknown_names() {
    let e = RobotModel::from_file("/nonexistent/robot.urdf").expect_err("no such file");
    assert!(matches!(e, ModelError::Read { .. }));
    says(&e, &["/nonexistent/robot.urdf"]);
    let e = RobotModel::builtin("walker").expect_err("no such robot");
    says(&e, &["`walker`", "ambler, hexapod, athlete"]);
    let e = RobotModel::load("no/such/robot.urdf").expect_err("neither");
    says(&e, &["`no/such/robot.urdf`", "path of a URDF file"]);
}

fn char_boundary_at_or_before(text: &str, mut at: usize) -> usize {
    at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// A file cut short anywhere is refused or read, never a panic.
    #[test]
    fn truncated_files_never_panic(robot in 0..BUILTIN_ROBOTS.len(), at in 0.0..1.0f64) {
        let text = BUILTIN_ROBOTS[robot].urdf;
        let cut = char_boundary_at_or_before(text, (at * text.len() as f64) as usize);
        let _ = RobotModel::from_urdf_str(&text[..cut]);
    }

    /// A file with a few bytes changed is refused or read, never a panic.
    #[test]
    fn corrupted_files_never_panic(
        edits in proptest::collection::vec((0.0..1.0f64, prop::sample::select(
            vec!['<', '>', '"', '/', '-', '0', 'x', ' ', '=', 'e', 'n', 'a', '.'])), 1..6),
    ) {
        let mut text = VALID.to_owned();
        for (at, c) in edits {
            let i = char_boundary_at_or_before(&text, (at * text.len() as f64) as usize);
            let end = if i < text.len() { i + 1 } else { i };
            let end = char_boundary_at_or_before(&text, end).max(i);
            text.replace_range(i..end, &c.to_string());
        }
        if let Ok(robot) = RobotModel::from_urdf_str(&text) {
            // Whatever was read must answer queries without panicking.
            let posture = robot.neutral_posture();
            prop_assert!(robot.centre_of_mass(&posture).is_ok());
            prop_assert!(robot.collision_shapes(&posture).is_ok());
        }
    }
}
