//! Driving the walking system by hand over zenoh: `tca list`, `tca echo`, `tca call`,
//! `tca send`, `tca kill` and `tca stop` against central and the six walking modules, each
//! its own process (`tca up walk.toml`), and their refusals of bad data, unknown names and
//! the wrong class.

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::common::*;

/// How long one command may take.
const RUN: Duration = Duration::from_secs(30);

/// A `tca` command in the background, its output collected; killed when dropped.
struct Background {
    child: Child,
    stdout: Arc<Mutex<String>>,
    stderr: Arc<Mutex<String>>,
}

impl Background {
    fn start(args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_tca"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("tca starts");
        let stdout = Arc::new(Mutex::new(String::new()));
        let stderr = Arc::new(Mutex::new(String::new()));
        let mut out = child.stdout.take().unwrap();
        let o = stdout.clone();
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = out.read_to_string(&mut s);
            o.lock().unwrap().push_str(&s);
        });
        let err = child.stderr.take().unwrap();
        let e = stderr.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                let mut e = e.lock().unwrap();
                e.push_str(&line);
                e.push('\n');
            }
        });
        Background {
            child,
            stdout,
            stderr,
        }
    }

    /// Waits until its stderr says `what`.
    async fn said(&self, what: &str) {
        retry(what, || async {
            let e = self.stderr.lock().unwrap().clone();
            if e.contains(what) { Ok(()) } else { Err(e) }
        })
        .await
    }

    /// Waits for its end: status, stdout, stderr.
    async fn finish(mut self) -> (ExitStatus, String, String) {
        let status = within_for(RUN, "a background tca ends", async {
            loop {
                if let Some(s) = self.child.try_wait().unwrap() {
                    return s;
                }
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        })
        .await;
        // The reader threads finish with the pipes.
        tokio::time::sleep(Duration::from_millis(100)).await;
        let out = self.stdout.lock().unwrap().clone();
        let err = self.stderr.lock().unwrap().clone();
        (status, out, err)
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs `tca ARGS --connect ENDPOINT` to its end.
async fn tca_at(endpoint: &str, args: &[&str]) -> (ExitStatus, String, String) {
    let mut all: Vec<&str> = args.to_vec();
    all.extend(["--connect", endpoint]);
    run_tca(&args.join(" "), &all, RUN).await
}

/// Runs it and expects success; its stdout.
async fn ok(endpoint: &str, args: &[&str]) -> String {
    let (status, out, err) = tca_at(endpoint, args).await;
    assert!(status.success(), "tca {args:?} failed: {out}\n{err}");
    out
}

/// Runs it and expects it to be refused with an error saying each of `says`.
async fn refused(endpoint: &str, args: &[&str], says: &[&str]) {
    let (status, out, err) = tca_at(endpoint, args).await;
    assert!(!status.success(), "tca {args:?} was not refused: {out}");
    for s in says {
        assert!(err.contains(s), "tca {args:?}: {s:?} not in: {err}");
    }
}

/// The carriage's Y from `tca call bodyPosition '{}'`.
async fn carriage_y(endpoint: &str) -> f64 {
    let out = ok(endpoint, &["call", "bodyPosition", "{}"]).await;
    let pose: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    pose["y_m"]
        .as_f64()
        .unwrap_or_else(|| panic!("no y_m: {out}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_walking_system_is_driven_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = free_endpoint();
    // The walking system on the simulated clock; the Controller's moves play out at 20 times
    // the real mechanism's speed, so that a walk lasts long enough to be stopped.
    let launch = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/walk.toml"))
        .unwrap()
        .replace("tcp/127.0.0.1:7447", &endpoint)
        .replace("out/up", dir.path().to_str().unwrap())
        .replace(
            "name = \"controller\"\nargs = [\"--course\", \"3\"]",
            "name = \"controller\"\nargs = [\"--course\", \"3\", \"--speed\", \"20\"]",
        );
    assert!(launch.contains("\"--speed\", \"20\""), "walk.toml changed");
    let file = dir.path().join("walk.toml");
    std::fs::write(&file, launch).unwrap();
    let mut up = Up(spawn_tca(&["up", file.to_str().unwrap()]));
    wait_for_modules(
        &endpoint,
        &["controller", "ism", "ltm", "pdm", "lrp", "gait"],
    )
    .await;
    let e = endpoint.as_str();

    // tca list: every module, its messages and their JSON templates.
    let list: serde_json::Value =
        serde_json::from_str(ok(e, &["list", "--json"]).await.trim()).unwrap();
    let controller = list["modules"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "controller")
        .unwrap_or_else(|| panic!("no controller: {list}"));
    let body_move = controller["messages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "bodyMove")
        .unwrap_or_else(|| panic!("no bodyMove: {controller}"));
    assert_eq!(body_move["class"], "command");
    assert_eq!(
        body_move["template"],
        serde_json::json!({"target_y_m": 0.0})
    );
    let text = ok(e, &["list", "bodyMove"]).await;
    assert!(
        text.contains("bodyMove: command handled by controller (connected)"),
        "{text}"
    );
    let text = ok(e, &["list"]).await;
    assert!(text.contains("gait:"), "{text}");
    assert!(!text.contains("list-"), "the tool lists itself: {text}");

    // tca call: the carriage stands at the start of the rails.
    let y0 = carriage_y(e).await;
    assert!((y0 - 1.0).abs() < 0.01, "{y0}");

    // tca send of a command, echoed as it happens.
    let echo = Background::start(&[
        "echo",
        "bodyMove",
        "--count",
        "2",
        "--timeout",
        "30",
        "--connect",
        e,
    ]);
    echo.said("echoing bodyMove").await;
    let out = ok(e, &["send", "bodyMove", r#"{"target_y_m": 2.0}"#]).await;
    assert!(out.contains("command bodyMove ("), "{out}");
    assert!(out.trim().ends_with("achieved"), "{out}");
    let (status, echoed, err) = echo.finish().await;
    assert!(status.success(), "{echoed}\n{err}");
    let lines: Vec<&str> = echoed.lines().collect();
    assert_eq!(lines.len(), 2, "{echoed}");
    assert!(lines[0].contains("command"), "{echoed}");
    assert!(lines[0].contains(r#"{"target_y_m":2.0}"#), "{echoed}");
    assert!(lines[1].contains("success"), "{echoed}");
    assert!(lines[1].contains("controller"), "{echoed}");
    let y1 = carriage_y(e).await;
    assert!((y1 - 2.0).abs() < 0.02, "the carriage moved to {y1}");

    // Refusals name what was wrong.
    let mv = |json: &'static str| ["send", "bodyMove", json];
    refused(
        e,
        &mv(r#"{"target_y": 2.0}"#),
        &["$.target_y", "did you mean \"target_y_m\""],
    )
    .await;
    refused(
        e,
        &mv(r#"{"target_y_m": "far"}"#),
        &["$.target_y_m", "expected a number (f64)"],
    )
    .await;
    refused(e, &mv(r#"{}"#), &["$.target_y_m", "missing field"]).await;
    refused(e, &mv(r#"{target_y_m: 2}"#), &["not valid JSON"]).await;
    refused(
        e,
        &["send", "walk", r#"{"goal_y_m": 3.0, "mode": "Sideways"}"#],
        &["$.mode", "no variant \"Sideways\""],
    )
    .await;
    refused(
        e,
        &["send", "bodyPosition", "{}"],
        &["is a query", "tca call"],
    )
    .await;
    refused(e, &["send", "moveFailed", "{}"], &["is an exception"]).await;
    refused(
        e,
        &["call", "bodyMove", r#"{"target_y_m": 2.0}"#],
        &["not a query", "tca send"],
    )
    .await;
    refused(e, &["call", "bodyPositon"], &["did you mean bodyPosition"]).await;
    refused(e, &["echo", "bodyMov"], &["did you mean bodyMove"]).await;
    refused(
        e,
        &["kill", "m999.1"],
        &["no live task was created by message m999.1"],
    )
    .await;
    for bad in ["soon", "m3", "x", "n", "m3.x", "m-1.2"] {
        refused(e, &["kill", bad], &["names no task"]).await;
    }
    // A node's number, with or without its `n`, reaches central (which has no such node).
    refused(e, &["kill", "n999999"], &["cannot kill n999999"]).await;
    refused(e, &["kill", "999999"], &["cannot kill 999999"]).await;
    // A name like none of the registry's gets no suggestion.
    let (status, _, err) = tca_at(e, &["call", "acquireImage"]).await;
    assert!(!status.success() && !err.contains("did you mean"), "{err}");
    assert_eq!(
        carriage_y(e).await,
        y1,
        "nothing refused moved the carriage"
    );

    // tca kill by the id of a task's message: the second of three moves, queued or running.
    let mut ids = Vec::new();
    for y in ["1.0", "2.0", "1.5"] {
        let json = format!(r#"{{"target_y_m": {y}}}"#);
        let out = ok(e, &["send", "bodyMove", &json, "--no-wait", "--json"]).await;
        let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
        assert_eq!(v["outcome"], "sent", "{v}");
        ids.push(v["id"].as_str().unwrap().to_owned());
    }
    let out = ok(e, &["kill", &ids[1]]).await;
    assert!(
        out.contains(&format!("killed the task of {}", ids[1])),
        "{out}"
    );
    refused(e, &["kill", &ids[1]], &["no live task"]).await;
    retry("the moves ended", || async {
        let out = ok(e, &["tree"]).await;
        if out.contains("no live task nodes") {
            Ok(())
        } else {
            Err(out)
        }
    })
    .await;
    let y2 = carriage_y(e).await;
    assert!((y2 - 1.5).abs() < 0.02, "the last move went to 1.5: {y2}");

    // tca stop during a walk: the tree is killed, the walk's sender told, the Controller
    // halted.
    let echo = Background::start(&[
        "echo",
        "bodyMove",
        "--count",
        "1",
        "--timeout",
        "30",
        "--connect",
        e,
    ]);
    echo.said("echoing bodyMove").await;
    let walk = Background::start(&[
        "send",
        "walk",
        r#"{"goal_y_m": 9.5, "mode": "Sequential"}"#,
        "--json",
        "--connect",
        e,
    ]);
    walk.said("waiting for its end").await;
    let (status, echoed, err) = echo.finish().await;
    assert!(
        status.success(),
        "the walk sent no body move: {echoed}\n{err}"
    );
    let tree = ok(e, &["tree"]).await;
    assert!(tree.contains("walk"), "{tree}");
    let out = ok(e, &["stop"]).await;
    assert!(out.contains("killed 1 task tree"), "{out}");
    assert!(
        out.contains("command halt to controller: achieved"),
        "{out}"
    );
    let (status, out, err) = walk.finish().await;
    assert_eq!(status.code(), Some(3), "{out}\n{err}");
    let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(v["outcome"], "killed", "{v}");
    assert_eq!(v["class"], "goal", "{v}");
    assert!(ok(e, &["tree"]).await.contains("no live task nodes"));
    // Halted, the Controller still answers but moves nothing until resumed.
    let y3 = carriage_y(e).await;
    let (status, out, err) = tca_at(e, &["send", "bodyMove", r#"{"target_y_m": 2.0}"#]).await;
    assert_eq!(status.code(), Some(2), "a move while halted: {out}\n{err}");
    assert!(
        out.contains("halted by an emergency stop") && out.contains("resume"),
        "{out}"
    );
    assert_eq!(carriage_y(e).await, y3, "nothing moved while halted");
    let out = ok(e, &["send", "resume", "{}"]).await;
    assert!(out.contains("achieved"), "{out}");
    ok(e, &["send", "bodyMove", r#"{"target_y_m": 2.0}"#]).await;
    let y4 = carriage_y(e).await;
    assert!(
        (y4 - 2.0).abs() < 0.02,
        "resumed, the move went to 2.0: {y4}"
    );
    // Ctrl-C stops tca up and every module it started.
    up.0.interrupt_and_wait("tca up stops").await;
}

/// `tca up`, stopped with Ctrl-C (which stops its modules too) when the test ends, even by
/// a failure.
struct Up(ChildProcess);

impl Drop for Up {
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .args(["-INT", &self.0.0.id().to_string()])
            .status();
        for _ in 0..100 {
            if self.0.0.try_wait().ok().flatten().is_some() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}
