//! What tca hands to Foxglove, checked with Foxglove's own client packages in Node
//! (`tools/foxglove/node`, installed by the test with `npm ci` from the lock file): the
//! exported MCAP files of a single-leg walk, of a hexapod walk and of a navigation on the
//! hill course pass the official MCAP reader (`@mcap/core`) and validate against Foxglove's
//! published JSON schemas (`@foxglove/schemas`), and a Foxglove WebSocket client
//! (`@foxglove/ws-protocol`) subscribed to `tca foxglove` during a walk across processes
//! receives the map, the transforms, the scene and the robot's description, decoded and
//! valid.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::OnceLock;
use std::time::Duration;

use crate::common::*;
use tokio::io::{AsyncBufReadExt, BufReader};

/// The checker's directory, its packages installed once for every test here; `None` (the
/// test then says it is skipped) where Node.js is not installed, except on CI
/// (`CI` set), where that is a failure.
fn checker() -> Option<&'static Path> {
    static READY: OnceLock<Result<Option<PathBuf>, String>> = OnceLock::new();
    let ready = READY.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/foxglove/node");
        for tool in ["node", "npm"] {
            let found = std::process::Command::new(tool).arg("--version").output();
            if !found.is_ok_and(|o| o.status.success()) {
                let why = format!(
                    "`{tool}` is not on the PATH: these tests run Foxglove's own Node packages \
                     (install Node.js 20 or later)"
                );
                if std::env::var_os("CI").is_some() {
                    return Err(why);
                }
                eprintln!("skipped: {why}");
                return Ok(None);
            }
        }
        let out = std::process::Command::new("npm")
            .args(["ci", "--no-audit", "--no-fund", "--ignore-scripts"])
            .current_dir(&dir)
            .output()
            .map_err(|e| format!("npm ci cannot start: {e}"))?;
        if !out.status.success() {
            return Err(format!(
                "npm ci failed in {}: {}",
                dir.display(),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        Ok(Some(dir))
    });
    match ready {
        Ok(dir) => dir.as_deref(),
        Err(e) => panic!("{e}"),
    }
}

/// `node check.mjs ARGS` in `dir`: exit status, stdout, stderr.
fn node_check(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new("node")
        .arg(dir.join("check.mjs"))
        .args(args)
        .output()
        .expect("node runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The per-topic message counts of the checker's last line.
fn topics(stdout: &str) -> BTreeMap<String, u64> {
    let last = stdout.lines().last().unwrap_or_default();
    let v: serde_json::Value = serde_json::from_str(last)
        .unwrap_or_else(|e| panic!("not the checker's counts ({e}): {stdout}"));
    v["topics"]
        .as_object()
        .unwrap_or_else(|| panic!("no topics: {stdout}"))
        .iter()
        .map(|(k, n)| (k.clone(), n.as_u64().unwrap_or(0)))
        .collect()
}

/// How a command is told where to leave its traffic log.
#[derive(Clone, Copy)]
enum Logged {
    /// `--out DIR`, the log at `DIR/traffic.mcap` (walks).
    OutDir,
    /// `--log DIR/traffic.mcap` (navigations).
    LogFile,
}

/// Runs `tca` with `run_args`, its traffic logged in `dir`, exports the log for Foxglove and
/// checks the file.
async fn export_and_check(
    checker: &Path,
    dir: &Path,
    run_args: &[&str],
    logged: Logged,
    wanted: &[&str],
) {
    let out = dir.to_string_lossy().into_owned();
    let log = dir.join("traffic.mcap");
    let log_arg = log.to_string_lossy().into_owned();
    let mut args = run_args.to_vec();
    match logged {
        Logged::OutDir => args.extend(["--out", &out]),
        Logged::LogFile => {
            std::fs::create_dir_all(dir).unwrap();
            args.extend(["--log", &log_arg]);
        }
    }
    let (status, stdout, stderr) = run_tca("the run", &args, Duration::from_secs(300)).await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let exported = dir.join("foxglove.mcap");
    let (status, stdout, stderr) = run_tca(
        "the export",
        &[
            "log",
            "export",
            log.to_str().unwrap(),
            "--foxglove",
            exported.to_str().unwrap(),
        ],
        Duration::from_secs(120),
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let (ok, stdout, stderr) = node_check(checker, &["mcap", exported.to_str().unwrap()]);
    assert!(ok, "the exported file fails Foxglove's checks: {stderr}");
    let counts = topics(&stdout);
    for topic in wanted {
        assert!(
            counts.get(*topic).copied().unwrap_or(0) > 0,
            "no {topic} in {counts:?}"
        );
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn exported_walks_pass_the_mcap_reader_and_foxglove_schemas() {
    let Some(checker) = checker() else { return };
    let dir = tempfile::tempdir().unwrap();
    export_and_check(
        checker,
        &dir.path().join("leg"),
        &["walk"],
        Logged::OutDir,
        &[
            "/map/elevation",
            "/map/footfall",
            "/tf",
            "/plan",
            "/scanner/range",
            "/log",
            "bodyMove",
        ],
    )
    .await;
    export_and_check(
        checker,
        &dir.path().join("hexapod"),
        &["walk", "--robot", "hexapod", "--course", "hexapod-flat"],
        Logged::OutDir,
        &[
            "/map/elevation",
            "/tf",
            "/plan",
            "/robot_description",
            "/scanner/range",
            "/log",
            "legged.legMove",
        ],
    )
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_exported_navigation_passes_the_mcap_reader_and_foxglove_schemas() {
    let Some(checker) = checker() else { return };
    let dir = tempfile::tempdir().unwrap();
    export_and_check(
        checker,
        &dir.path().join("nav"),
        &["navigate", "--terrain", "hill"],
        Logged::LogFile,
        &[
            "/camera/depth",
            "/map/danger",
            "/tf",
            "/plan",
            "/log",
            "nav.frame",
        ],
    )
    .await;
}

#[test]
fn the_checker_refuses_a_message_its_schema_does_not_allow() {
    let Some(checker) = checker() else { return };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcap");
    {
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut w = mcap::WriteOptions::new().profile("").create(file).unwrap();
        let schema =
            br#"{"type":"object","properties":{"x_m":{"type":"number"}},"required":["x_m"]}"#;
        let s = w.add_schema("tca.test", "jsonschema", schema).unwrap();
        let c = w
            .add_channel(s, "bodyMove", "json", &BTreeMap::new())
            .unwrap();
        let header = |sequence| mcap::records::MessageHeader {
            channel_id: c,
            sequence,
            log_time: sequence.into(),
            publish_time: sequence.into(),
        };
        w.write_to_known_channel(&header(1), br#"{"x_m": 1.5}"#)
            .unwrap();
        w.write_to_known_channel(&header(2), br#"{"y_m": 1.5}"#)
            .unwrap();
        w.finish().unwrap();
    }
    let (ok, _, stderr) = node_check(checker, &["mcap", path.to_str().unwrap()]);
    assert!(!ok, "a message without its required field passed");
    assert!(
        stderr.contains("bodyMove") && stderr.contains("x_m"),
        "{stderr}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_foxglove_client_receives_the_walk_live() {
    let Some(checker) = checker() else { return };
    let checker = checker.join("check.mjs");
    let dir = tempfile::tempdir().unwrap();
    let (mut up, endpoint) = start_legged_system(dir.path()).await;
    let port = free_port().to_string();
    let mut view = spawn_tca(&[
        "foxglove",
        "--connect",
        &endpoint,
        "--port",
        &port,
        "--timeout",
        "240",
    ]);
    let url = format!("ws://127.0.0.1:{port}");
    retry("the live view listens", || async {
        tokio::net::TcpStream::connect(format!("127.0.0.1:{port}"))
            .await
            .map(|_| ())
    })
    .await;
    let mut client = tokio::process::Command::new("node")
        .arg(&checker)
        .args([
            "live",
            &url,
            "200",
            "/map/elevation",
            "/tf",
            "/plan",
            "/robot_description",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("node runs");
    let mut lines = BufReader::new(client.stdout.take().unwrap()).lines();
    let first = within_for(
        Duration::from_secs(60),
        "the client connects",
        lines.next_line(),
    )
    .await
    .expect("the client's output");
    assert_eq!(first.as_deref(), Some("open"));
    let (status, stdout, stderr) = run_tca(
        "the walk",
        &[
            "walk",
            "--robot",
            "hexapod",
            "--course",
            "hexapod-rough",
            "--seed",
            "1",
            "--connect",
            &endpoint,
            "--out",
            dir.path().join("walk").to_str().unwrap(),
        ],
        Duration::from_secs(300),
    )
    .await;
    assert!(status.success(), "{stdout}\n{stderr}");
    let ended = within_for(Duration::from_secs(240), "the client ends", client.wait())
        .await
        .expect("the client's status");
    let mut rest = String::new();
    while let Ok(Some(line)) = lines.next_line().await {
        rest.push_str(&line);
        rest.push('\n');
    }
    let mut err = String::new();
    if let Some(mut e) = client.stderr.take() {
        use tokio::io::AsyncReadExt;
        let _ = e.read_to_string(&mut err).await;
    }
    assert!(ended.success(), "the live client: {rest}\n{err}");
    let counts = topics(&rest);
    for topic in ["/map/elevation", "/tf", "/plan", "/robot_description"] {
        assert!(counts.get(topic).copied().unwrap_or(0) > 0, "{counts:?}");
    }
    view.kill();
    up.interrupt_and_wait("tca up stops").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_foxglove_client_watches_a_navigation_served_from_its_own_process() {
    let Some(checker) = checker() else { return };
    let checker = checker.join("check.mjs");
    let port = free_port().to_string();
    // One command: central, the navigation modules and the live view in one process.
    let mut run = spawn_tca(&[
        "navigate",
        "--terrain",
        "ramps",
        "--seed",
        "1",
        "--foxglove",
        &port,
    ]);
    retry("the live view listens", || async {
        tokio::net::TcpStream::connect(format!("127.0.0.1:{port}"))
            .await
            .map(|_| ())
    })
    .await;
    let out = within_for(
        Duration::from_secs(240),
        "the live client",
        tokio::process::Command::new("node")
            .arg(&checker)
            .args([
                "live",
                &format!("ws://127.0.0.1:{port}"),
                "200",
                "/camera/depth",
                "/map/danger",
                "/tf",
                "/plan",
            ])
            .kill_on_drop(true)
            .output(),
    )
    .await
    .expect("node runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "the live client: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let counts = topics(&stdout);
    for topic in ["/camera/depth", "/map/danger", "/tf", "/plan"] {
        assert!(counts.get(topic).copied().unwrap_or(0) > 0, "{counts:?}");
    }
    run.kill();
}
