//! `tca map`: pictures of the LTM Manager's maps from a walk's traffic log (rebuilt from the
//! recorded range images, at any time of the walk, with the chosen footfalls) and from a
//! running system over zenoh; and its errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;

use crate::common::*;
use tca_central::StartOptions;
use tca_module::Module;
use tca_single_leg_messages::{MapCell, MapGrid, MapKind};
use tca_walk::{SystemSetup, TerrainChoice};

fn tca(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tca"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("tca runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `tca map ARGS --json`, which must succeed, and returns what it printed.
fn map(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["map", "--json"];
    all.extend_from_slice(args);
    let out = tca(&all);
    assert!(out.status.success(), "tca {all:?}: {}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.trim().lines().last().unwrap_or_default())
        .unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

/// Runs `tca map ARGS`, which must fail, and returns its error output.
fn map_fails(args: &[&str]) -> String {
    let mut all = vec!["map"];
    all.extend_from_slice(args);
    let out = tca(&all);
    assert!(
        !out.status.success(),
        "tca {all:?} succeeded: {}",
        stderr(&out)
    );
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
    stderr(&out)
}

/// A decoded PNG: width, height, RGB bytes.
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("a buffer size")];
    let info = reader.next_frame(&mut buf).expect("a PNG frame");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// The traffic log of `tca walk --course 4`, made once for all the tests here.
fn walk_log() -> &'static Path {
    static DIR: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, log) = DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let out = tca(&[
            "walk",
            "--course",
            "4",
            "--out",
            dir.path().to_str().unwrap(),
        ]);
        assert!(out.status.success(), "the walk: {}", stderr(&out));
        let log = dir.path().join("traffic.mcap");
        (dir, log)
    });
    log
}

fn out_path(dir: &tempfile::TempDir, name: &str) -> String {
    dir.path().join(name).to_string_lossy().into_owned()
}

/// The size of the picture the PDM draws of an `nx x ny` grid of `kind`.
fn picture_size(kind: MapKind, nx: u32, ny: u32, resolution_m: f64) -> (u32, u32) {
    let grid = MapGrid {
        kind,
        origin_x_m: 0.0,
        origin_y_m: 0.0,
        resolution_m,
        nx,
        ny,
        cells: vec![MapCell::Unknown; (nx * ny) as usize],
    };
    let p = tca_pdm::render(&grid, &[], &tca_pdm::RenderOptions::default()).unwrap();
    (p.width(), p.height())
}

#[test]
fn a_walk_log_gives_a_picture_of_the_whole_mapped_area() {
    let dir = tempfile::tempdir().unwrap();
    let log = walk_log().to_str().unwrap();
    let out = out_path(&dir, "map.png");
    let v = map(&["--log", log, "-o", &out]);
    let (w, h, _) = decode(Path::new(&out));
    assert_eq!(
        (v["width_px"].as_u64(), v["height_px"].as_u64()),
        (Some(w.into()), Some(h.into()))
    );
    assert_eq!(v["kind"], "elevation");
    assert_eq!(v["resolution_m"], 0.05);
    assert!(v["images"].as_u64().unwrap() >= 5, "{v}");
    // The scanner sees the course pit (6 x 11 m) from the rails.
    let (x0, x1) = (
        v["x_min_m"].as_f64().unwrap(),
        v["x_max_m"].as_f64().unwrap(),
    );
    let (y0, y1) = (
        v["y_min_m"].as_f64().unwrap(),
        v["y_max_m"].as_f64().unwrap(),
    );
    assert!(x0 >= -0.5 && x1 <= 6.5 && x1 - x0 > 4.0, "{v}");
    assert!(y0 >= -0.5 && y1 <= 11.5 && y1 - y0 > 8.0, "{v}");
    let known = v["known_cells"].as_u64().unwrap();
    let cells = v["nx"].as_u64().unwrap() * v["ny"].as_u64().unwrap();
    assert!(known * 2 > cells, "mostly known: {v}");
    assert!(v["occluded_cells"].as_u64().unwrap() > 0, "{v}");
    assert_eq!(
        (w, h),
        picture_size(
            MapKind::Elevation,
            v["nx"].as_u64().unwrap() as u32,
            v["ny"].as_u64().unwrap() as u32,
            0.05
        )
    );
}

#[test]
fn the_picture_follows_the_region_and_the_resolution() {
    let dir = tempfile::tempdir().unwrap();
    let log = walk_log().to_str().unwrap();
    for (region, res, nx, ny) in [
        ("0,0,6,11", "0.1", 61, 111),
        ("1,2,4,6", "0.05", 61, 81),
        ("4,6,1,2", "0.25", 13, 17),
    ] {
        let out = out_path(&dir, &format!("r{res}.png"));
        let v = map(&[
            "--log",
            log,
            "--region",
            region,
            "--resolution",
            res,
            "-o",
            &out,
        ]);
        assert_eq!(
            (v["nx"].as_u64(), v["ny"].as_u64()),
            (Some(nx), Some(ny)),
            "{v}"
        );
        let (w, h, _) = decode(Path::new(&out));
        let res: f64 = res.parse().unwrap();
        assert_eq!(
            (w, h),
            picture_size(MapKind::Elevation, nx as u32, ny as u32, res),
            "{region} at {res}"
        );
    }
    // A polygon: its enclosing grid, cells outside it unknown.
    let out = out_path(&dir, "poly.png");
    let tri = map(&["--log", log, "--polygon", "1,2 5,2 3,8", "-o", &out]);
    let rect = map(&["--log", log, "--region", "1,2,5,8", "-o", &out]);
    assert_eq!(
        (tri["nx"].clone(), tri["ny"].clone()),
        (rect["nx"].clone(), rect["ny"].clone())
    );
    assert!(
        tri["unknown_cells"].as_u64().unwrap() > rect["unknown_cells"].as_u64().unwrap() + 1000,
        "{tri} {rect}"
    );
}

#[test]
fn the_map_kinds_are_different_pictures() {
    let dir = tempfile::tempdir().unwrap();
    let log = walk_log().to_str().unwrap();
    let mut pictures = Vec::new();
    for kind in ["elevation", "uncertainty", "footfall", "slope"] {
        let out = out_path(&dir, &format!("{kind}.png"));
        let v = map(&[
            "--log", log, "--kind", kind, "--region", "0,1,6,9", "-o", &out,
        ]);
        assert_eq!(v["kind"], kind);
        assert!(v["known_cells"].as_u64().unwrap() > 1000, "{v}");
        pictures.push((kind, decode(Path::new(&out)).2));
    }
    for (i, (a, pa)) in pictures.iter().enumerate() {
        for (b, pb) in &pictures[i + 1..] {
            assert_ne!(pa, pb, "{a} and {b} look the same");
        }
    }
}

/// Pixels of the PDM's overlay colour.
fn overlay_pixels(rgb: &[u8]) -> usize {
    rgb.chunks_exact(3)
        .filter(|p| *p == tca_pdm::render::OVERLAY)
        .count()
}

#[test]
fn footfalls_and_earlier_maps_come_from_the_log() {
    let dir = tempfile::tempdir().unwrap();
    let log = walk_log();
    let recorded = tca_map_view::read_walk(
        &tca_logs::LogFile::open(log).unwrap(),
        tca_logs::TimeBase::Envelope,
    );
    assert!(recorded.images.len() >= 5);
    assert!(recorded.footfalls.len() >= 5);
    let log = log.to_str().unwrap();
    let plain = out_path(&dir, "plain.png");
    let with = out_path(&dir, "with.png");
    map(&["--log", log, "--region", "0,0,6,11", "-o", &plain]);
    let v = map(&[
        "--log",
        log,
        "--region",
        "0,0,6,11",
        "--overlay-footfalls",
        "-o",
        &with,
    ]);
    assert_eq!(
        v["footfalls"].as_u64(),
        Some(recorded.footfalls.len() as u64)
    );
    assert_eq!(overlay_pixels(&decode(Path::new(&plain)).2), 0);
    assert!(overlay_pixels(&decode(Path::new(&with)).2) > 50);

    // Between the second and third images: the map of two images, and fewer footfalls.
    let at = 0.5 * (recorded.images[1].at_s + recorded.images[2].at_s);
    let at_text = format!("{at}");
    let then = out_path(&dir, "then.png");
    let early = map(&[
        "--log",
        log,
        "--region",
        "0,0,6,11",
        "--at",
        &at_text,
        "--overlay-footfalls",
        "-o",
        &then,
    ]);
    assert_eq!(early["images"], 2, "{early}");
    let footfalls_then = recorded.footfalls.iter().filter(|f| f.at_s <= at).count();
    assert_eq!(early["footfalls"].as_u64(), Some(footfalls_then as u64));
    assert!(footfalls_then < recorded.footfalls.len());
    let end = map(&["--log", log, "--region", "0,0,6,11", "-o", &plain]);
    assert!(
        early["known_cells"].as_u64() < end["known_cells"].as_u64(),
        "{early} {end}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_arguments_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let log = walk_log().to_str().unwrap().to_owned();
    let out = out_path(&dir, "x.png");
    let cases: &[(&[&str], &str)] = &[
        (&["--region", "0,0,6"], "3 numbers, not 4"),
        (&["--region", "0,0,x,6"], "not a number"),
        (&["--region", "2,0,2,6"], "no area"),
        (&["--polygon", "1,2 5,2"], "at least three points, got 2"),
        (&["--polygon", "1,2 5 3,6"], "is not x,y"),
        (&["--polygon", "0,0 1,1 2,2"], "zero area"),
        (&["--resolution", "0"], "greater than zero"),
        (&["--resolution", "NaN"], "greater than zero"),
        (&["--resolution", "-0.1"], "greater than zero"),
        (
            &["--region", "0,0,6,11", "--resolution", "0.0001"],
            "coarser resolution",
        ),
        (
            &["--kind", "height"],
            "give elevation, uncertainty, footfall or slope",
        ),
        (&["--at", "-1"], "--at must be"),
        (&["--at", "0.1"], "give a later --at"),
    ];
    for (args, expected) in cases {
        let mut all = vec!["--log", log.as_str(), "-o", out.as_str()];
        all.extend_from_slice(args);
        let e = map_fails(&all);
        assert!(e.contains(expected), "{args:?}: {e}");
    }
    assert!(!Path::new(&out).exists(), "nothing is written on bad input");

    // Not a log; no such file; a directory that does not exist.
    let png = out_path(&dir, "not-a-log.png");
    std::fs::write(&png, b"\x89PNG").unwrap();
    assert!(map_fails(&["--log", &png, "-o", &out]).contains("MCAP magic"));
    let missing = out_path(&dir, "missing.mcap");
    assert!(map_fails(&["--log", &missing, "-o", &out]).contains("cannot read the traffic log"));
    let nowhere = out_path(&dir, "no/such/dir/x.png");
    assert!(map_fails(&["--log", &log, "-o", &nowhere]).contains("directory exists"));

    // Options that belong to the other source.
    assert!(
        map_fails(&["--connect", "tcp/127.0.0.1:1", "--at", "3", "-o", &out]).contains("--log")
    );
    assert!(map_fails(&["--log", &log, "--pdm", "-o", &out]).contains("cannot be used with"));

    // A log with no range images in it.
    let empty = dir.path().join("empty.mcap");
    let central = TestCentral::start_with(
        TransportKind::InProcess,
        StartOptions {
            log: Some(empty.clone()),
            ..StartOptions::default()
        },
    )
    .await;
    let m = within(
        "a module connects",
        Module::builder("someone").connect(&central.connector),
    )
    .await
    .unwrap();
    m.close().await;
    central.stop().await;
    let e = map_fails(&["--log", empty.to_str().unwrap(), "-o", &out]);
    assert!(e.contains("holds no range images"), "{e}");

    // Nobody at the endpoint.
    let endpoint = free_endpoint();
    let e = map_fails(&["--connect", &endpoint, "-o", &out]);
    assert!(
        e.contains("cannot reach central") && e.contains("tca up"),
        "{e}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_running_system_draws_its_map_over_zenoh() {
    let central = TestCentral::start(TransportKind::Zenoh).await;
    let endpoint = central.endpoint.clone().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let run = |args: Vec<String>| async move {
        tokio::task::spawn_blocking(move || {
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            tca(&args)
        })
        .await
        .unwrap()
    };
    let args = |extra: &[&str]| -> Vec<String> {
        ["map", "--json", "--connect", &endpoint]
            .iter()
            .chain(extra)
            .map(|s| s.to_string())
            .collect()
    };
    // Without an LTM Manager: a clear error.
    let out = out_path(&dir, "none.png");
    let failed = within("tca map", run(args(&["--region", "0,0,6,11", "-o", &out]))).await;
    assert!(!failed.status.success());
    assert!(
        stderr(&failed).contains("ltm module"),
        "{}",
        stderr(&failed)
    );

    // The Controller, ISM, LTM and PDM of course 4, connected over zenoh.
    let setup = SystemSetup::new(TerrainChoice::Course(4), 1).unwrap();
    let mut modules = Vec::new();
    for name in ["controller", "ism", "ltm", "pdm"] {
        modules.push(
            within(
                name,
                tca_walk::connect_module(name, &central.connector, &setup),
            )
            .await
            .unwrap(),
        );
    }
    let json = |out: &Output| -> serde_json::Value {
        assert!(out.status.success(), "{}", stderr(out));
        let stdout = String::from_utf8_lossy(&out.stdout);
        serde_json::from_str(stdout.trim().lines().last().unwrap_or_default())
            .unwrap_or_else(|e| panic!("{e}: {stdout}"))
    };
    // The whole mapped area: the LTM Manager takes its first image for it.
    let whole = out_path(&dir, "whole.png");
    let v = json(&within("tca map", run(args(&["-o", &whole]))).await);
    let (w, h, _) = decode(Path::new(&whole));
    assert_eq!(
        (v["width_px"].as_u64(), v["height_px"].as_u64()),
        (Some(w.into()), Some(h.into()))
    );
    assert!(v["known_cells"].as_u64().unwrap() > 1000, "{v}");
    assert_eq!(v["images"], serde_json::Value::Null);

    // A region, drawn by the system's PDM, and a footfall map drawn here.
    let by_pdm = out_path(&dir, "by-pdm.png");
    let v = json(
        &within(
            "tca map --pdm",
            run(args(&[
                "--region",
                "1,1,5,5",
                "--resolution",
                "0.1",
                "--pdm",
                "-o",
                &by_pdm,
            ])),
        )
        .await,
    );
    assert_eq!((v["nx"].as_u64(), v["ny"].as_u64()), (Some(41), Some(41)));
    assert!(v["drawn_by"].as_str().unwrap().contains("PDM"), "{v}");
    let (w, h, _) = decode(Path::new(&by_pdm));
    assert_eq!((w, h), picture_size(MapKind::Elevation, 41, 41, 0.1));
    let foot = out_path(&dir, "foot.png");
    let v = json(
        &within(
            "tca map --kind footfall",
            run(args(&[
                "--region", "1,1,5,5", "--kind", "footfall", "-o", &foot,
            ])),
        )
        .await,
    );
    assert_eq!(v["kind"], "footfall");
    assert_ne!(decode(Path::new(&foot)).2, decode(Path::new(&by_pdm)).2);

    for m in modules {
        m.close().await;
    }
    central.stop().await;
}
