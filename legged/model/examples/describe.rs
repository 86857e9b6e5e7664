//! Prints a robot's legs, joints, mass, standing height and each foot's workspace.
//!
//! `cargo run -p tca-legged-model --example describe -- ambler` (or `hexapod`, `athlete`,
//! or the path of a URDF file).

use std::process::ExitCode;

use tca_legged_model::RobotModel;

fn main() -> ExitCode {
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "ambler".to_owned());
    let robot = match RobotModel::load(&name) {
        Ok(robot) => robot,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let posture = robot.neutral_posture();
    println!(
        "{}: body `{}`, {} legs, {} moving joints, {:.3} kg",
        robot.name(),
        robot.body_link(),
        robot.legs().len(),
        robot.dof(),
        robot.total_mass()
    );
    if let Ok(com) = robot.centre_of_mass(&posture) {
        let c = com.centre;
        println!(
            "neutral posture: body {:.3} m above level ground, centre of mass ({:.3}, {:.3}, {:.3}) m",
            robot.neutral_height(),
            c.x,
            c.y,
            c.z
        );
    }
    for (leg, q) in robot.legs().iter().zip(&posture) {
        let foot = leg
            .foot_position(q)
            .map(|p| format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z));
        println!(
            "leg {}: foot `{}` radius {} m, neutral foot at {} m",
            leg.name(),
            leg.foot_link(),
            leg.foot_radius(),
            foot.unwrap_or_else(|e| e.to_string())
        );
        for joint in leg.joints() {
            let l = joint.limits();
            println!(
                "  {:<24} {:<9} {:>7.3}..{:<7.3} {}  {} {}/s",
                joint.name(),
                joint.kind().urdf_name(),
                l.lower,
                l.upper,
                joint.kind().unit(),
                l.velocity,
                joint.kind().unit()
            );
        }
        println!("  {}", leg.workspace_summary(4096));
    }
    ExitCode::SUCCESS
}
