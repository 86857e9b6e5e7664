//! FootFall's operator loop across processes: `tca up footfall.toml` starts central, the
//! rover's Controller (sagging), the robot-side executor and the ground-side planner, each
//! its own process; `tca footfall maps|plan|send --connect` is the operator.

use std::time::Duration;

use crate::common::*;

const LIMIT: Duration = Duration::from_secs(300);

fn last_json(stdout: &str, stderr: &str) -> serde_json::Value {
    let line = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {stdout}\n{stderr}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_operator_maps_plans_and_sends_a_step_to_the_robot() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let endpoint = free_endpoint();
    let launch = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/footfall.toml"))
        .expect("the shipped launch file")
        .replace("tcp/127.0.0.1:7449", &endpoint)
        .replace(
            "out/up-footfall",
            dir.path().to_str().expect("a UTF-8 path"),
        );
    let file = dir.path().join("footfall.toml");
    std::fs::write(&file, launch).expect("the launch file written");
    let mut up = spawn_tca(&["up", file.to_str().expect("a UTF-8 path")]);
    wait_for_modules(
        &endpoint,
        &["controller", "footfall-exec", "footfall-planner"],
    )
    .await;

    let png = dir.path().join("pictures");
    let png = png.to_str().unwrap();
    let (status, stdout, stderr) = run_tca(
        "the maps",
        &[
            "footfall",
            "maps",
            "--leg",
            "left_front",
            "--resolution",
            "0.1",
            "--png",
            png,
            "--json",
            "--connect",
            &endpoint,
        ],
        LIMIT,
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let maps = last_json(&stdout, &stderr);
    assert!(maps["counts"]["green"].as_u64().unwrap() > 20, "{maps}");
    assert!(dir.path().join("pictures/maps-left_front.png").exists());

    let step = dir.path().join("step.json");
    let step = step.to_str().unwrap();
    let (status, stdout, stderr) = run_tca(
        "the plan",
        &[
            "footfall",
            "plan",
            "--leg",
            "left_front",
            "--to",
            "9.2,0.8",
            "--out",
            step,
            "--png",
            png,
            "--json",
            "--connect",
            &endpoint,
        ],
        LIMIT,
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let plan = last_json(&stdout, &stderr);
    assert_eq!(plan["planned"], true, "{plan}");
    assert_eq!(plan["check"]["margins_kept"], true, "{plan}");
    assert!(dir.path().join("pictures/plan-left_front.png").exists());

    let (status, stdout, stderr) = run_tca(
        "the step sent",
        &["footfall", "send", step, "--json", "--connect", &endpoint],
        LIMIT,
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("\"stance\":false") && stdout.contains("\"stance\":true"),
        "{stdout}"
    );
    assert_eq!(last_json(&stdout, &stderr)["achieved"], true);

    // The same plan again: the leg stands elsewhere now.
    let (status, stdout, stderr) = run_tca(
        "the stale step",
        &["footfall", "send", step, "--connect", &endpoint],
        LIMIT,
    )
    .await;
    assert_eq!(status.code(), Some(2), "{stdout}\n{stderr}");
    assert!(stdout.contains("plan again"), "{stdout}");
    up.interrupt_and_wait("tca up stops").await;
}

#[test]
fn bad_requests_are_refused_saying_what_to_give() {
    let out = tca_output(&["footfall", "plan", "--leg", "tail", "--to", "9,1"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no leg `tail`") && err.contains("left_front"),
        "{err}"
    );
    let out = tca_output(&["footfall", "plan", "--leg", "left_front", "--to", "far"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("X,Y"));
    let out = tca_output(&["footfall", "plan", "--leg", "left_front", "--to", "13,6"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot reach"));
    let out = tca_output(&["footfall", "send", "/nonexistent/step.json"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read the plan"));
    let out = tca_output(&[
        "footfall",
        "maps",
        "--leg",
        "left_front",
        "--terrain",
        "moon.asc",
    ]);
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("course"),
        "{:?}",
        out
    );
}
