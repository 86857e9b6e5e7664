//! The `tca` command itself: ping (in-process, over zenoh, over mutual TLS), `tca up` with a
//! launch file, registry and tree over zenoh, log show, and its errors.

use std::process::Command;
use std::time::Duration;

use crate::common::*;

fn tca(args: &[&str]) -> std::process::Output {
    tca_output(args)
}

fn stdout(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The process ids with which module `echo` connected, from central's log so far.
fn echo_pids(log: &std::path::Path) -> Vec<u32> {
    let Ok(file) = tca_logs::LogFile::open(log) else {
        return Vec::new();
    };
    file.records
        .iter()
        .filter_map(|r| match &r.kind {
            tca_logs::RecordKind::Link(l)
                if l.event == tca_logs::LinkEvent::Connected
                    && l.module.as_ref().is_some_and(|m| m.as_str() == "echo") =>
            {
                l.detail
                    .strip_prefix("pid ")?
                    .split(' ')
                    .next()?
                    .parse()
                    .ok()
            }
            _ => None,
        })
        .collect()
}

#[test]
fn ping_in_process_prints_json() {
    let out = tca(&["ping", "-n", "200", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let line = stdout(&out);
    let v: serde_json::Value = serde_json::from_str(line.trim().lines().last().unwrap()).unwrap();
    assert_eq!(v["n"], 200);
    for k in ["min_us", "p50_us", "p99_us", "max_us"] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k}: {v}");
    }
    assert!(v["min_us"].as_f64() <= v["p50_us"].as_f64());
    assert!(v["p99_us"].as_f64() <= v["max_us"].as_f64());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn up_starts_central_and_modules_that_the_other_commands_reach() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = free_endpoint();
    let log = dir.path().join("up.mcap");
    let launch = dir.path().join("bus.toml");
    std::fs::write(
        &launch,
        format!(
            "[central]\nlisten = [\"{endpoint}\"]\nlog = \"{}\"\n\n[[module]]\nname = \"echo\"\n",
            log.display()
        ),
    )
    .unwrap();
    let mut up = spawn_tca(&["up", launch.to_str().unwrap()]);
    // The echo module registers once it has started: poll the registry until it shows.
    let registry = retry("echo registered", || async {
        let out = tokio::task::spawn_blocking({
            let e = endpoint.clone();
            move || tca(&["registry", "--connect", &e])
        })
        .await
        .unwrap();
        let text = stdout(&out);
        if out.status.success() && text.contains("tca-ping") && !text.contains("(down)") {
            Ok(text)
        } else {
            Err(format!("{}{}", text, stderr(&out)))
        }
    })
    .await;
    assert!(registry.contains("echo"), "{registry}");
    let e = endpoint.clone();
    let out =
        tokio::task::spawn_blocking(move || tca(&["ping", "--connect", &e, "-n", "50", "--json"]))
            .await
            .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    // A module that crashes is started again by `tca up`, and answers again.
    let first = echo_pids(&log);
    assert_eq!(first.len(), 1, "{first:?}");
    let _ = Command::new("kill")
        .args(["-KILL", &first[0].to_string()])
        .status();
    retry("echo started again", || async {
        let pids = echo_pids(&log);
        if pids.len() >= 2 {
            Ok(())
        } else {
            Err(format!("echo pids so far: {pids:?}"))
        }
    })
    .await;
    let e = endpoint.clone();
    let out =
        tokio::task::spawn_blocking(move || tca(&["ping", "--connect", &e, "-n", "20", "--json"]))
            .await
            .unwrap();
    assert!(out.status.success(), "after the restart: {}", stderr(&out));
    let e = endpoint.clone();
    let out = tokio::task::spawn_blocking(move || tca(&["tree", "--connect", &e]))
        .await
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("no live task nodes"),
        "{}",
        stdout(&out)
    );
    // Ctrl-C stops central and the modules; the log is complete.
    let _ = Command::new("kill")
        .args(["-INT", &up.0.id().to_string()])
        .status();
    let stopped = within("tca up stops", async {
        loop {
            if let Ok(Some(status)) = up.0.try_wait() {
                return status;
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    })
    .await;
    assert!(stopped.success());
    let out = tca(&["log", "show", log.to_str().unwrap(), "--class", "query"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("tca-ping"), "{text}");
    assert!(!text.contains("note: the log ends early"), "{text}");
    let out = tca(&["log", "show", log.to_str().unwrap(), "--tree"]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn bad_input_gets_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.mcap");
    std::fs::write(&junk, b"not a log at all").unwrap();
    let out = tca(&["log", "show", junk.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("MCAP magic"), "{}", stderr(&out));

    let launch = dir.path().join("bad.toml");
    std::fs::write(&launch, "[[module]]\nname = \"no-such-module\"\n").unwrap();
    let out = tca(&["up", launch.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("not a built-in module"),
        "{}",
        stderr(&out)
    );

    let out = tca(&["module", "nope", "--connect", "tcp/127.0.0.1:1"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("no built-in module named"),
        "{}",
        stderr(&out)
    );

    // An open central on every interface, with no policy: refused, saying what to do.
    let out = tca(&["central", "--listen", "tcp/0.0.0.0:7"]);
    assert!(!out.status.success());
    for hint in ["reachable from other machines", "--policy", "--insecure"] {
        assert!(stderr(&out).contains(hint), "{hint}: {}", stderr(&out));
    }

    let out = tca(&["ping", "-n", "0"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("at least 1"), "{}", stderr(&out));

    // A goal off the rails is refused before anything walks.
    for goal in ["100", "0.2", "-3"] {
        let out = tca(&[
            "walk",
            "--goal",
            goal,
            "--out",
            dir.path().to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(1), "--goal {goal}");
        assert!(
            stderr(&out).contains("off the rails, which run from 0.50 to 10.50 m"),
            "--goal {goal}: {}",
            stderr(&out)
        );
        assert!(!stderr(&out).contains("step  1"), "{}", stderr(&out));
    }

    // An unknown body-move law, and the open-loop one with concurrent planning.
    let out = tca(&["walk", "--body-move", "closed"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("use servo"), "{}", stderr(&out));
    let out = tca(&[
        "walk",
        "--body-move",
        "open-loop",
        "--concurrent",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("walk sequentially with --body-move open-loop"),
        "{}",
        stderr(&out)
    );
    assert!(!stderr(&out).contains("step  1"), "{}", stderr(&out));
}

/// Central on a zenoh Unix socket and pings through it: neither side warns (zenoh's link
/// warns about every connecting socket's missing name unless told not to).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_zenoh_unix_socket_central_works_with_no_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = format!("unixsock-stream/{}", dir.path().join("c.sock").display());
    let mut central = tca_testkit::ChildProcess(
        Command::new(env!("CARGO_BIN_EXE_tca"))
            .args(["central", "--listen", &endpoint])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("tca central starts"),
    );
    let ping = retry("a ping through the unix socket", || async {
        let (status, out, err) = run_tca(
            "tca ping",
            &["ping", "--connect", &endpoint, "-n", "100"],
            Duration::from_secs(60),
        )
        .await;
        if status.success() {
            Ok((out, err))
        } else {
            Err(err)
        }
    })
    .await;
    assert!(ping.0.contains("100 query round trips"), "{}", ping.0);
    for bad in ["WARN", "ERROR", "warning"] {
        assert!(
            !ping.1.contains(bad),
            "{bad} in the ping's stderr:\n{}",
            ping.1
        );
    }
    central.interrupt_and_wait("central stops").await;
    let mut err = String::new();
    if let Some(mut e) = central.0.stderr.take() {
        use std::io::Read as _;
        let _ = e.read_to_string(&mut err);
    }
    for bad in ["WARN", "ERROR", "warning"] {
        assert!(!err.contains(bad), "{bad} in central's stderr:\n{err}");
    }
}

/// `tca central --listen tls/...` with `[transport.tls]` in its policy, and `tca ping` over it
/// with the certificate of `TCA_ZENOH_TLS_*`: a certificate signed by central's CA connects,
/// as the identity its common name names; none, or one of another CA, does not.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ping_over_mutual_tls_with_certificates_from_the_environment() {
    let dir = tempfile::tempdir().unwrap();
    let ca = tca_testkit::TestCa::new(dir.path(), "tca");
    let central_files = ca.central();
    let tools = ca.module("tools");
    let rogue_dir = dir.path().join("rogue");
    std::fs::create_dir(&rogue_dir).unwrap();
    let rogue = tca_testkit::TestCa::new(&rogue_dir, "rogue").module("tools");
    let policy = dir.path().join("policy.toml");
    std::fs::write(
        &policy,
        format!(
            "[transport.tls]\ncertificate = {:?}\nprivate_key = {:?}\nca = {:?}\n\
             [[identity]]\nname = \"tools\"\nmodules = [\"*\"]\nregister = [\"*\"]\n\
             send = [\"*\"]\n",
            central_files.certificate.display().to_string(),
            central_files.private_key.display().to_string(),
            central_files.ca.display().to_string(),
        ),
    )
    .unwrap();
    let endpoint = format!("tls/127.0.0.1:{}", free_port());
    let _central = spawn_tca(&[
        "central",
        "--listen",
        &endpoint,
        "--policy",
        policy.to_str().unwrap(),
    ]);
    let ping = |files: Option<tca_link::zenoh::TlsFiles>| {
        let mut command =
            crate::common::tca().command(&["ping", "--connect", &endpoint, "-n", "50"]);
        if let Some(f) = files {
            command
                .env("TCA_ZENOH_TLS_CERT", &f.certificate)
                .env("TCA_ZENOH_TLS_KEY", &f.private_key)
                .env("TCA_ZENOH_TLS_CA", &f.ca);
        }
        async move {
            let out = tokio::task::spawn_blocking(move || command.output())
                .await
                .unwrap()
                .unwrap();
            (out.status.success(), stdout(&out), stderr(&out))
        }
    };
    let (_, out, _) = retry("a ping over TLS", || {
        let run = ping(Some(tools.clone()));
        async move {
            let (ok, out, err) = run.await;
            if ok { Ok((ok, out, err)) } else { Err(err) }
        }
    })
    .await;
    assert!(out.contains("50 query round trips"), "{out}");

    let (ok, _, err) = ping(None).await;
    assert!(!ok, "a ping without a certificate succeeded");
    assert!(err.contains("TCA_ZENOH_TLS_CERT"), "{err}");
    let forged = tca_link::zenoh::TlsFiles::new(&rogue.certificate, &rogue.private_key, ca.ca());
    let (ok, _, err) = ping(Some(forged)).await;
    assert!(!ok, "a ping with a certificate of another CA succeeded");
    assert!(err.contains("no central at"), "{err}");

    // TLS endpoints need TLS files in the policy.
    let plain = dir.path().join("plain.toml");
    std::fs::write(&plain, "[[identity]]\nname = \"tools\"\n").unwrap();
    let other = format!("tls/127.0.0.1:{}", free_port());
    let out = tca(&[
        "central",
        "--listen",
        &other,
        "--policy",
        plain.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("[transport.tls]"), "{}", stderr(&out));
}

#[test]
fn a_normal_walk_prints_no_warnings() {
    let dir = tempfile::tempdir().unwrap();
    for mode in [&[][..], &["--concurrent"][..]] {
        let mut args = vec!["walk", "--backward", "--out", dir.path().to_str().unwrap()];
        args.extend_from_slice(mode);
        let out = tca(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let err = stderr(&out);
        for bad in ["WARN", "ERROR", "warning"] {
            assert!(!err.contains(bad), "{mode:?}: {bad} in\n{err}");
        }
        assert!(
            stdout(&out).contains("reached the goal"),
            "{}",
            stdout(&out)
        );
    }
}

#[test]
fn robot_show_describes_the_shipped_robots_and_refuses_bad_files() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["ambler", "hexapod", "athlete"] {
        let png = dir.path().join(format!("{name}.png"));
        let out = tca(&["robot", "show", name, "--png", png.to_str().unwrap()]);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let text = stdout(&out);
        assert!(
            text.contains("6 legs") && text.contains("workspace"),
            "{text}"
        );
        assert!(text.contains("stability margin"), "{text}");
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{name}");
    }
    let out = tca(&["robot", "show", "hexapod", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_str(stdout(&out).trim()).unwrap();
    assert_eq!(v["legs"].as_array().unwrap().len(), 6);
    assert!(v["stability_margin_m"].as_f64().unwrap() > 0.0);
    assert!(v["legs"][0]["workspace"]["reach_max_m"].as_f64().unwrap() > 0.0);
    // A user's own file, and a broken one.
    let own = dir.path().join("own.urdf");
    std::fs::write(
        &own,
        r#"<robot name="stool">
  <link name="base"><inertial><mass value="2"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="a_foot"/><link name="b_foot"/><link name="c_foot"/>
  <joint name="a" type="prismatic"><parent link="base"/><child link="a_foot"/><origin xyz="0.3 0 0"/><axis xyz="0 0 -1"/><limit lower="0.2" upper="0.5" velocity="0.1" effort="10"/></joint>
  <joint name="b" type="prismatic"><parent link="base"/><child link="b_foot"/><origin xyz="-0.15 0.26 0"/><axis xyz="0 0 -1"/><limit lower="0.2" upper="0.5" velocity="0.1" effort="10"/></joint>
  <joint name="c" type="prismatic"><parent link="base"/><child link="c_foot"/><origin xyz="-0.15 -0.26 0"/><axis xyz="0 0 -1"/><limit lower="0.2" upper="0.5" velocity="0.1" effort="10"/></joint>
</robot>"#,
    )
    .unwrap();
    let out = tca(&["robot", "show", own.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("robot stool") && stdout(&out).contains("3 legs"));
    let bad = dir.path().join("bad.urdf");
    std::fs::write(&bad, r#"<robot name="x"><link name="base"/><link name="a_foot"/><joint name="spin" type="continuous"><parent link="base"/><child link="a_foot"/></joint></robot>"#).unwrap();
    let out = tca(&["robot", "show", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("spin") && stderr(&out).contains("continuous"),
        "{}",
        stderr(&out)
    );
    assert!(!stderr(&out).contains("panicked"));
    let out = tca(&["robot", "show", "no-such-robot"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("ambler"), "{}", stderr(&out));
}
