//! `tca navigate`'s planning, following and sensing options: `--beta`, `--lookahead`,
//! `--sight`, `--clearance`, `--map-range` and the camera's change the run (and the true-map
//! path it is judged against), and values that cannot work are refused saying what to give.

use crate::common::*;

fn report(stdout: &str, stderr: &str) -> serde_json::Value {
    let line = stdout.lines().last().unwrap_or_default();
    serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {stdout}\n{stderr}"))
}

#[test]
fn planning_and_following_options_change_the_run_and_bad_values_are_refused() {
    let run = |extra: &[&str]| {
        let mut args = vec![
            "navigate",
            "--terrain",
            "hill",
            "--seed",
            "1",
            "--direct",
            "--json",
        ];
        args.extend_from_slice(extra);
        let out = tca_output(&args);
        let (stdout, stderr) = (
            String::from_utf8_lossy(&out.stdout).to_string(),
            String::from_utf8_lossy(&out.stderr).to_string(),
        );
        assert!(out.status.success(), "{stderr}");
        report(&stdout, &stderr)
    };
    let default = run(&[]);
    let heavy = run(&["--beta", "8"]);
    let long = run(&["--lookahead", "0.4"]);
    let no_sight = run(&["--sight", "0"]);
    let wide = run(&["--clearance", "0.15"]);
    let near = run(&["--map-range", "1.0"]);
    let wide_eye = run(&["--camera-fov", "90", "--camera-pixels", "200x120"]);
    // A goal west and north of the start, given as `--goal -DX,DY` without `=`.
    let west = run(&["--goal", "-0.3,0.2"]);
    assert_eq!(west["reached"], true, "{west}");
    let end = west["path"].as_array().and_then(|p| p.last()).cloned();
    let end = end.unwrap_or_else(|| panic!("no path: {west}"));
    let (x, y) = (end[0].as_f64().unwrap(), end[1].as_f64().unwrap());
    assert!(
        (x - 0.25).hypot(y - 1.3) < 0.1,
        "ended at ({x}, {y}), not 0.3 m west and 0.2 m north of the start: {west}"
    );
    for r in [&default, &heavy, &long, &no_sight, &wide, &near, &wide_eye] {
        assert_eq!(r["untraversable_frames"], 0, "{r}");
        assert_eq!(r["untraversable_at"], serde_json::json!([]), "{r}");
        assert_eq!(r["reached"], true, "{r}");
    }
    assert_ne!(
        default["path"], heavy["path"],
        "--beta 8 drove the same path"
    );
    assert_ne!(
        default["path"], long["path"],
        "--lookahead 0.4 drove the same path"
    );
    assert_ne!(
        default["path"], no_sight["path"],
        "--sight 0 drove the same path"
    );
    assert_ne!(
        default["path"], wide["path"],
        "--clearance 0.15 drove the same path"
    );
    assert_ne!(
        default["path"], wide_eye["path"],
        "a wider camera drove the same path"
    );
    assert_ne!(
        default["path"], near["path"],
        "--map-range 1.0 drove the same path"
    );
    assert_ne!(
        default["true_map_path_m"], heavy["true_map_path_m"],
        "the true-map path is planned with the same beta"
    );
    for (args, says) in [
        (vec!["--beta=-1"], "--beta -1 is not valid"),
        (vec!["--beta", "NaN"], "--beta NaN is not valid"),
        (vec!["--lookahead", "0"], "--lookahead 0 is not valid"),
        (vec!["--sight=-0.5"], "--sight -0.5 is not valid"),
        (vec!["--clearance=-0.1"], "--clearance -0.1 is not valid"),
        (vec!["--map-range", "0"], "--map-range 0 is not valid"),
        (
            vec!["--camera-pixels", "wide"],
            "--camera-pixels wide is not valid",
        ),
        (vec!["--camera-pixels", "0x120"], "at least 1 x 1 pixels"),
        (vec!["--camera-fov", "200"], "an angle between 0 and pi"),
        (vec!["--camera-noise=-1"], "noise_per_m"),
    ] {
        let mut all = vec!["navigate", "--terrain", "hill", "--direct"];
        all.extend_from_slice(&args);
        let out = tca_output(&all);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{err}");
    }
    let out = tca_output(&[
        "navigate",
        "--terrain",
        "hill",
        "--beta",
        "3",
        "--connect",
        "tcp/127.0.0.1:1",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--beta") && err.contains("--connect"), "{err}");
    // Modules in other processes keep their own danger files: one given here would only
    // change how the run is judged, so it is refused.
    let out = tca_output(&[
        "navigate",
        "--terrain",
        "hill",
        "--danger",
        "nav/danger-map/robots/wheeled.toml",
        "--connect",
        "tcp/127.0.0.1:1",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--danger") && err.contains("--connect"),
        "{err}"
    );
}
