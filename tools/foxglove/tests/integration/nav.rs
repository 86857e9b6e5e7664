//! Navigation traffic as Foxglove's well-known messages: depth images as `32FC1` images,
//! the danger map as a grid kept up to date by the mapped frames' changes, the estimated
//! and true base on `/tf`, the plan on `/plan` and the goal's course on `/log`. Checked on
//! hand-made messages and on the export of a whole hill-course navigation on the bus.

use std::collections::HashMap;
use std::sync::Arc;

use foxglove::Decode;
use foxglove::messages::{FrameTransforms, Grid, Log, RawImage, SceneUpdate};
use tca_foxglove::{WellKnown, WellKnownState};
use tca_messages::*;
use tca_nav_bus::{NavBase, NavSetup, run_on_bus};
use tca_nav_messages as nav;
use tca_nav_navigator::{RunOptions, WheeledParams, hill_course, wheeled_params};

fn envelope<T: serde::Serialize>(sender: &str, name: &str, class: Class, data: &T) -> Envelope {
    Envelope {
        id: MessageId::new(3, 1),
        class,
        name: MessageName::new(name).unwrap(),
        sender: ModuleName::new(sender).unwrap(),
        context: None,
        node: None,
        correlation: Some(MessageId::new(4, 1)),
        cause: None,
        timestamp_ns: 5,
        options: SendOptions::default(),
        redelivery: 0,
        data: encode_data(data).unwrap(),
    }
}

fn f32s(data: &[u8]) -> Vec<f32> {
    data.chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn pose(x_m: f64, y_m: f64, yaw_rad: f64) -> nav::PlanarPose {
    nav::PlanarPose { x_m, y_m, yaw_rad }
}

#[test]
fn hand_made_navigation_messages_become_well_known_ones() {
    let mut s = WellKnownState::new();
    // A depth image: 3 x 2 pixels, one without depth.
    let frame = nav::DepthFrame {
        frame: 0,
        width: 3,
        height: 2,
        depth_m: vec![1.0, 0.0, 2.5, 3.0, 3.5, 4.0],
        estimate: pose(1.0, 2.0, 0.0),
        base_z_m: 0.1,
        base_roll_rad: 0.0,
        base_pitch_rad: 0.0,
    };
    let out = s.feed(
        &envelope("ism", "nav.acquireDepth", Class::Reply, &frame),
        10,
    );
    let [WellKnown::Image { topic, image }] = &out[..] else {
        panic!("{out:?}")
    };
    assert_eq!(*topic, "/camera/depth");
    assert_eq!(
        (
            image.width,
            image.height,
            image.step,
            image.encoding.as_str()
        ),
        (3, 2, 12, "32FC1")
    );
    assert_eq!(image.frame_id, "camera");
    assert_eq!(f32s(&image.data), frame.depth_m);

    // Changes before any map are passed over (the map's size is not known).
    let changes = nav::DangerChanges {
        estimate: pose(1.0, 2.0, 0.0),
        registered: false,
        frames: 1,
        cells: vec![
            nav::CellDangerMsg {
                ix: 1,
                iy: 1,
                danger: Some(0.25),
                certainty: 0.5,
            },
            nav::CellDangerMsg {
                ix: 0,
                iy: 0,
                danger: None,
                certainty: 1.0,
            },
            nav::CellDangerMsg {
                ix: 9,
                iy: 0,
                danger: Some(0.0),
                certainty: 1.0,
            },
        ],
    };
    let reply = envelope("ltm", "nav.insertDepth", Class::Reply, &changes);
    assert!(s.feed(&reply, 11).is_empty());

    // The map: 2 x 2 cells of 0.5 m, cell (0, 0) centred at (1, 2), all unknown.
    let map = nav::DangerGrid {
        origin_x_m: 1.0,
        origin_y_m: 2.0,
        resolution_m: 0.5,
        nx: 2,
        ny: 2,
        danger: vec![1.0; 4],
        certainty: vec![0.0; 4],
        frames: 0,
    };
    let out = s.feed(&envelope("ltm", "nav.dangerMap", Class::Reply, &map), 12);
    let [WellKnown::Grid { topic, grid }] = &out[..] else {
        panic!("{out:?}")
    };
    assert_eq!(topic, "/map/danger");
    let names: Vec<_> = grid.fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["danger", "certainty"]);
    assert_eq!(
        (grid.column_count, grid.cell_stride, grid.row_stride),
        (2, 8, 16)
    );
    let p = grid.pose.as_ref().unwrap().position.as_ref().unwrap();
    assert_eq!((p.x, p.y), (0.75, 1.75), "the south-west corner");
    assert_eq!(f32s(&grid.data), [1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0]);

    // Now the changes apply: cell (1, 1) is the last, (0, 0) cannot be crossed, (9, 0) is
    // off the map.
    let out = s.feed(&reply, 13);
    let [WellKnown::Grid { grid, .. }] = &out[..] else {
        panic!("{out:?}")
    };
    let v = f32s(&grid.data);
    assert!(v[0].is_nan(), "an untraversable cell's danger is NaN");
    assert_eq!(&v[1..], [1.0, 1.0, 0.0, 1.0, 0.0, 0.25, 0.5]);

    // The frame: the estimate on /tf, the path and goal on /plan.
    let f = nav::NavFrame {
        frame: 4,
        estimate: pose(1.0, 2.0, std::f64::consts::FRAC_PI_2),
        goal: [3.0, 2.0],
        path: vec![[1.0, 2.0], [2.0, 2.0], [3.0, 2.0]],
        outcome: nav::FrameOutcome::Drive,
        forward_mps: 0.2,
        turn_rps: 0.0,
        replans: 1,
        exploration_turns: 0,
        registrations: 0,
        changed_cells: 2,
        loop_s: 0.01,
    };
    let out = s.feed(&envelope("navigator", "nav.frame", Class::Inform, &f), 14);
    let [WellKnown::Transforms(tf), WellKnown::Scene(scene)] = &out[..] else {
        panic!("{out:?}")
    };
    let t = &tf.transforms[0];
    assert_eq!(
        (t.parent_frame_id.as_str(), t.child_frame_id.as_str()),
        ("world", "base")
    );
    let r = t.rotation.as_ref().unwrap();
    assert!(
        (r.z - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12,
        "{r:?}"
    );
    let path = scene.entities.iter().find(|e| e.id == "nav_path").unwrap();
    assert_eq!(path.lines[0].points.len(), 3);
    let goal = scene.entities.iter().find(|e| e.id == "nav_goal").unwrap();
    assert_eq!(
        goal.spheres[0]
            .pose
            .as_ref()
            .unwrap()
            .position
            .as_ref()
            .unwrap()
            .x,
        3.0
    );

    // The truth on its own frame.
    let out = s.feed(
        &envelope(
            "controller",
            "nav.truePose",
            Class::Reply,
            &pose(1.1, 2.0, 0.0),
        ),
        15,
    );
    let [WellKnown::Transforms(tf)] = &out[..] else {
        panic!("{out:?}")
    };
    assert_eq!(tf.transforms[0].child_frame_id, "base_true");
    assert_eq!(tf.transforms[0].translation.as_ref().unwrap().x, 1.1);

    // The goal's start, success and failure on /log.
    let goal = nav::Navigate {
        dx_m: 1.4,
        dy_m: 0.0,
        max_frames: 100,
    };
    let mut lines = Vec::new();
    for e in [
        envelope("user", "nav.navigate", Class::Goal, &goal),
        envelope("navigator", "nav.navigate", Class::Success, &()),
        envelope(
            "navigator",
            "nav.navigate",
            Class::Failure,
            &Failure {
                reason: "no traversable path to the goal on the map as perceived".into(),
            },
        ),
    ] {
        for w in s.feed(&e, 16) {
            let WellKnown::Log(l) = w else {
                panic!("{w:?}")
            };
            lines.push(l);
        }
    }
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert!(
        lines[0].message.contains("navigate to (1.400, 0.000)"),
        "{lines:?}"
    );
    assert!(lines[1].message.contains("succeeded"), "{lines:?}");
    assert!(
        lines[2].message.contains("no traversable path"),
        "{lines:?}"
    );
    assert_eq!(lines[2].level, foxglove::messages::log::Level::Error as i32);

    // A depth image whose pixels do not match its size gives nothing.
    let bad = nav::DepthFrame {
        depth_m: vec![1.0],
        ..frame
    };
    assert!(
        s.feed(&envelope("ism", "nav.acquireDepth", Class::Reply, &bad), 17)
            .is_empty()
    );
}

/// The messages of each topic of an exported MCAP file, in order.
fn read(path: &std::path::Path) -> HashMap<String, (String, Vec<Vec<u8>>)> {
    let bytes = std::fs::read(path).unwrap();
    let mut out: HashMap<String, (String, Vec<Vec<u8>>)> = HashMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().map(|s| s.name.clone());
        out.entry(m.channel.topic.clone())
            .or_insert_with(|| (schema.unwrap_or_default(), Vec::new()))
            .1
            .push(m.data.to_vec());
    }
    out
}

fn decoded<T: Decode>(r: &HashMap<String, (String, Vec<Vec<u8>>)>, topic: &str) -> Vec<T> {
    r.get(topic)
        .unwrap_or_else(|| panic!("no {topic} in {:?}", r.keys()))
        .1
        .iter()
        .map(|m| T::decode(&m[..]).unwrap())
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_exported_hill_navigation_shows_camera_map_frames_and_plan() {
    let course = hill_course().unwrap();
    let params = wheeled_params();
    let (cam_w, cam_h) = (params.camera.width as u32, params.camera.height as u32);
    let (map_nx, map_ny) = (course.terrain.grid().nx(), course.terrain.grid().ny());
    let opts = RunOptions {
        start: course.start,
        goal_offset: course.goal_offset,
        drift: 0.0125,
        seed: 4,
        max_frames: 1500,
    };
    let setup = NavSetup {
        terrain: Arc::new(course.terrain.clone()),
        base: NavBase::Wheeled(WheeledParams::PIONEER),
        params,
        start: course.start,
        drift: opts.drift,
        seed: opts.seed,
    };
    let dir = tempfile::tempdir().unwrap();
    let log_path = dir.path().join("nav.mcap");
    let run = run_on_bus(&setup, &opts, Some(log_path.clone()))
        .await
        .unwrap();
    assert!(run.report.reached, "{}", run.report.reason);
    let log = tca_logs::LogFile::open(&log_path).unwrap();
    let out = dir.path().join("nav-fox.mcap");
    let summary = tca_foxglove::export_foxglove(&log, &out).unwrap();
    assert_eq!(summary.undecoded, 0, "{summary:?}");
    let r = read(&out);
    let frames = run.report.frames;

    // Depth images: one per frame the navigator took (and one the run asked at the end).
    assert_eq!(r["/camera/depth"].0, "foxglove.RawImage");
    let images: Vec<RawImage> = decoded(&r, "/camera/depth");
    assert!(
        images.len() >= frames,
        "{} images, {frames} frames",
        images.len()
    );
    for img in &images {
        assert_eq!(
            (img.width, img.height, img.step, img.encoding.as_str()),
            (cam_w, cam_h, 4 * cam_w, "32FC1")
        );
        assert_eq!(img.data.len(), (4 * cam_w * cam_h) as usize);
    }
    let depths = f32s(&images[0].data);
    let seen = depths.iter().filter(|d| **d > 0.0).count();
    assert!(seen > depths.len() / 10, "{seen} pixels with depth");
    assert!(
        depths
            .iter()
            .all(|d| d.is_finite() && *d >= 0.0 && *d < 10.0)
    );

    // The danger map: the map's size, once from the map query and after every mapped frame,
    // growing more certain as the camera sees more.
    assert_eq!(r["/map/danger"].0, "foxglove.Grid");
    let grids: Vec<Grid> = decoded(&r, "/map/danger");
    assert!(
        grids.len() > frames,
        "{} grids, {frames} frames",
        grids.len()
    );
    for g in &grids {
        assert_eq!(g.column_count as usize, map_nx);
        assert_eq!(g.data.len(), map_nx * map_ny * 8);
    }
    let certain =
        |g: &Grid| -> f64 { f32s(&g.data).chunks_exact(2).map(|c| f64::from(c[1])).sum() };
    let (first, last) = (&grids[0], grids.last().unwrap());
    assert_eq!(
        certain(first),
        0.0,
        "nothing is known before the first frame"
    );
    assert!(certain(last) > 100.0, "{}", certain(last));
    assert_ne!(first.data, last.data);
    // The last grid is the map the LTM Manager ended with.
    let mine = f32s(&last.data);
    for (i, c) in run.danger.cells().iter().enumerate() {
        let (d, k) = (mine[2 * i], mine[2 * i + 1]);
        if c.danger.is_finite() {
            assert!(
                (f64::from(d) - c.danger).abs() < 1e-6,
                "cell {i}: {d} {c:?}"
            );
        } else {
            assert!(d.is_nan(), "cell {i}: {d} {c:?}");
        }
        assert!(
            (f64::from(k) - c.certainty).abs() < 1e-6,
            "cell {i}: {k} {c:?}"
        );
    }

    // The estimated base every frame, the true one every image.
    let tfs: Vec<FrameTransforms> = decoded(&r, "/tf");
    let all: Vec<_> = tfs.iter().flat_map(|t| t.transforms.iter()).collect();
    let base: Vec<_> = all.iter().filter(|t| t.child_frame_id == "base").collect();
    let truth: Vec<_> = all
        .iter()
        .filter(|t| t.child_frame_id == "base_true")
        .collect();
    assert_eq!(base.len(), frames);
    assert!(truth.len() >= frames);
    assert!(all.iter().all(|t| t.parent_frame_id == "world"));
    let x = |t: &foxglove::messages::FrameTransform| t.translation.as_ref().unwrap().x;
    assert!((x(base[0]) - course.start.x).abs() < 1e-9);
    assert!(
        x(base.last().unwrap()) > course.start.x + 1.0,
        "the base moved east"
    );
    // The drift: the estimate and the truth part.
    let est_end = base.last().unwrap().translation.as_ref().unwrap();
    let true_end = truth.last().unwrap().translation.as_ref().unwrap();
    assert!((est_end.x - true_end.x).hypot(est_end.y - true_end.y) > 1e-4);

    // The plan: a path toward the goal every frame.
    let scenes: Vec<SceneUpdate> = decoded(&r, "/plan");
    assert_eq!(scenes.len(), frames);
    let paths: Vec<_> = scenes
        .iter()
        .flat_map(|s| s.entities.iter())
        .filter(|e| e.id == "nav_path")
        .collect();
    assert!(paths.iter().any(|p| p.lines[0].points.len() > 10));
    let goal = scenes[0]
        .entities
        .iter()
        .find(|e| e.id == "nav_goal")
        .unwrap();
    let g = goal.spheres[0]
        .pose
        .as_ref()
        .unwrap()
        .position
        .as_ref()
        .unwrap();
    assert!((g.x - (course.start.x + course.goal_offset[0])).abs() < 1e-9);

    // The goal's start and success.
    let logs: Vec<Log> = decoded(&r, "/log");
    assert!(
        logs.iter().any(|l| l.message.starts_with("navigate to")),
        "{logs:?}"
    );
    assert!(
        logs.iter().any(|l| l.message == "nav.navigate succeeded"),
        "{logs:?}"
    );
}
