//! After a walk: the map picture (elevation with the footfalls and the leg paths), the figures
//! taken from the traffic log, the timeline of Figure 18, and the summary text.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;
use tca_logs::{Direction, LogFile, RecordKind, TimeBase};
use tca_messages::{Class, Message, decode_data};
use tca_module::Module;
use tca_robot::{CarriagePose, LegKinematics, LegParams};
use tca_single_leg_messages::{
    BodyMove, BodyPose, LegMove, MapKind, MapRegion, Overlay, PlanePoint, RenderMap, WorldPoint,
};

use crate::system::SystemSetup;
use crate::walk::WalkReport;

/// Asks the PDM to draw the elevation map of the whole pit with the footfalls and the leg
/// paths, to `out/map.png`.
pub async fn map_picture(
    walker: &Module,
    setup: &SystemSetup,
    report: &WalkReport,
    leg_paths: Vec<Vec<WorldPoint>>,
) -> anyhow::Result<()> {
    let (lo, hi) = setup.terrain.extent();
    let polygon = vec![
        PlanePoint {
            x_m: lo.x,
            y_m: lo.y,
        },
        PlanePoint {
            x_m: hi.x,
            y_m: lo.y,
        },
        PlanePoint {
            x_m: hi.x,
            y_m: hi.y,
        },
        PlanePoint {
            x_m: lo.x,
            y_m: hi.y,
        },
    ];
    let mut overlays: Vec<Overlay> = report
        .footfalls
        .iter()
        .enumerate()
        .map(|(i, f)| Overlay::Point {
            at: *f,
            label: format!("{}", i + 1),
        })
        .collect();
    overlays.extend(
        leg_paths
            .into_iter()
            .enumerate()
            .map(|(i, points)| Overlay::Path {
                points,
                label: format!("leg {}", i + 1),
            }),
    );
    let task = walker.send_watched(
        &RenderMap {
            region: MapRegion {
                kind: MapKind::Elevation,
                polygon,
                resolution_m: 0.05,
                refresh: false,
            },
            overlays,
            path: "map.png".into(),
        },
        [],
    )?;
    let outcome = task.outcome().await?;
    if outcome != tca_messages::control::TaskOutcome::Achieved {
        anyhow::bail!("the map picture was not drawn: {outcome:?}");
    }
    Ok(())
}

/// The leg's foot paths, from the `legMove` commands the Controller received and where the
/// carriage was then: the Controller's latest `bodyPosition` answer (a body move may fall
/// short of its target), else the target of the latest `bodyMove`.
pub fn leg_paths(log: &LogFile, start_y_m: f64) -> Vec<Vec<WorldPoint>> {
    let params = LegParams::default();
    let kin = LegKinematics::new(&params);
    let mut carriage_y = start_y_m;
    let mut paths = Vec::new();
    for record in &log.records {
        let RecordKind::Frame(f) = &record.kind else {
            continue;
        };
        if f.direction != Direction::Out || !matches!(f.class, Class::Command | Class::Reply) {
            continue;
        }
        let Ok(env) = LogFile::envelope(f) else {
            continue;
        };
        if f.class == Class::Reply {
            if env.name.as_str() == "bodyPosition"
                && let Ok(pose) = decode_data::<BodyPose>(&env.data)
            {
                carriage_y = pose.y_m;
            }
            continue;
        }
        match env.name.as_str() {
            "bodyMove" => {
                if let Ok(m) = decode_data::<BodyMove>(&env.data) {
                    carriage_y = m.target_y_m;
                }
            }
            "legMove" => {
                if let Ok(m) = decode_data::<LegMove>(&env.data) {
                    let pose = CarriagePose::level(carriage_y);
                    let path = m
                        .waypoints
                        .iter()
                        .map(|j| {
                            let q = tca_robot::JointPosition::new(
                                j.shoulder_rad,
                                j.elbow_rad,
                                j.vertical_m,
                            );
                            let p = kin.forward_world(&pose, &q);
                            WorldPoint {
                                x_m: p.x,
                                y_m: p.y,
                                z_m: p.z,
                            }
                        })
                        .collect();
                    paths.push(path);
                }
            }
            _ => {}
        }
    }
    paths
}

/// Fills in the figures that come from the traffic log and draws the timeline.
pub fn from_log(report: &mut WalkReport, log_path: &Path, out: &Path) -> anyhow::Result<()> {
    let log = LogFile::open(log_path)
        .with_context(|| format!("cannot read the walk's log {}", log_path.display()))?;
    let sim = tca_logs::stats(&log, TimeBase::Envelope);
    let wall = tca_logs::stats(&log, TimeBase::Central);
    report.messages = Some(sim.messages);
    if report.steps > 0 {
        report.messages_per_step = Some(sim.messages as f64 / report.steps as f64);
        let planning_s: f64 = wall
            .modules
            .iter()
            .filter(|m| m.module == "gait" || m.module == "lrp")
            .map(|m| m.computing_s)
            .sum();
        report.planning_ms_per_step = Some(planning_s * 1e3 / report.steps as f64);
    }
    report.step_ends_s = body_move_ends_s(&log);
    let timeline = out.join("timeline.png");
    tca_timeline::write_png(&sim, &timeline)?;
    report.outputs.push(timeline);
    std::fs::write(
        out.join("timeline.txt"),
        tca_timeline::text(&sim, report.steps),
    )?;
    report.outputs.push(out.join("timeline.txt"));
    report.outputs.push(log_path.to_owned());
    Ok(())
}

/// When each body move ended, simulated seconds: the stamps of the Controller's successes of
/// `bodyMove`.
fn body_move_ends_s(log: &LogFile) -> Vec<f64> {
    let mut moves = std::collections::HashSet::new();
    let mut ends = Vec::new();
    for record in &log.records {
        let RecordKind::Frame(f) = &record.kind else {
            continue;
        };
        let Ok(env) = LogFile::envelope(f) else {
            continue;
        };
        match (f.direction, env.class) {
            (Direction::Out, Class::Command) if env.name.as_str() == BodyMove::NAME => {
                moves.insert(env.id);
            }
            (Direction::In, Class::Success)
                if env.correlation.is_some_and(|c| moves.remove(&c)) =>
            {
                ends.push(env.timestamp_ns as f64 / 1e9);
            }
            _ => {}
        }
    }
    ends
}

/// The human summary.
pub fn summary(report: &WalkReport) -> String {
    let mut s = String::new();
    let verdict = if report.reached {
        "reached the goal".to_owned()
    } else {
        format!(
            "did NOT reach the goal: {}",
            report.reason.as_deref().unwrap_or("unknown reason")
        )
    };
    let _ = writeln!(s, "walk on {} ({}): {verdict}", report.terrain, report.mode);
    for leg in &report.legs {
        let _ = writeln!(
            s,
            "  to y = {:.2} m: {} in {} steps, {:.1} simulated min",
            leg.goal_y_m,
            if leg.reached { "reached" } else { "stopped" },
            leg.steps,
            leg.sim_time_s / 60.0
        );
    }
    let _ = writeln!(
        s,
        "  {} steps, {:.2} m travelled (y {:.2} -> {:.2} m), {} collisions",
        report.steps, report.distance_m, report.start_y_m, report.final_y_m, report.collisions
    );
    let _ = writeln!(
        s,
        "  simulated time {:.1} min ({:.0} cm/min), wall time {:.2} s",
        report.sim_time_s / 60.0,
        if report.sim_time_s > 0.0 {
            report.distance_m * 100.0 / (report.sim_time_s / 60.0)
        } else {
            0.0
        },
        report.wall_time_s
    );
    if let (Some(m), Some(per)) = (report.messages, report.messages_per_step) {
        let _ = writeln!(s, "  {m} messages ({per:.1} per step)");
    }
    if !report.step_ends_s.is_empty() {
        let mut at = 0.0;
        let took: Vec<String> = report
            .step_ends_s
            .iter()
            .map(|&end| {
                let t = format!("{:.0}", end - at);
                at = end;
                t
            })
            .collect();
        let _ = writeln!(s, "  steps took {} simulated s", took.join(", "));
    }
    if let Some(p) = report.planning_ms_per_step {
        let _ = writeln!(
            s,
            "  planning {p:.1} ms per step (Gait Planner + Leg Recovery Planner)"
        );
    }
    for o in &report.outputs {
        let _ = writeln!(s, "  wrote {}", o.display());
    }
    s
}
