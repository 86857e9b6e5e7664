//! The PDM module on an in-process central with the real LTM Manager and ISM modules and a
//! fake Controller: `renderMap` writes a picture; failures end the command with a reason.

use std::sync::Arc;
use tca_testkit::within;

use nalgebra::Point2;
use tca_ism::{IsmConfig, SensorSpec, VirtualScanner};
use tca_ltm::LtmConfig;
use tca_messages::control::TaskOutcome;
use tca_module::Module;
use tca_pdm::{PdmConfig, RenderOptions, render_map};
use tca_robot::{HeightField, LegParams};
use tca_single_leg_messages::{
    BodyPose, BodyPosition, MapKind, MapRegion, Overlay, PlanePoint, RenderMap, WorldPoint,
};

fn region(kind: MapKind) -> MapRegion {
    MapRegion {
        kind,
        polygon: [(1.0, 5.0), (5.0, 5.0), (3.0, 10.0)]
            .iter()
            .map(|&(x_m, y_m)| PlanePoint { x_m, y_m })
            .collect(),
        resolution_m: 0.05,
        refresh: false,
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn render_map_writes_a_picture_of_the_ltm_map() {
    let (_central, c) = tca_testkit::in_process_central().await;
    let _controller = within(
        "controller",
        Module::builder("controller")
            .handle(|_ctx, _q: BodyPosition| async {
                Ok(BodyPose {
                    y_m: 1.0,
                    roll_rad: 0.0,
                    pitch_rad: 0.0,
                })
            })
            .connect(&c),
    )
    .await
    .unwrap();
    let terrain = Arc::new(
        HeightField::flat(Point2::new(-4.0, -4.0), Point2::new(10.0, 24.0), 0.05, 0.0).unwrap(),
    );
    let scanner = VirtualScanner::new(SensorSpec::erim(), terrain, &LegParams::default());
    let _ism = within(
        "ism",
        tca_ism::connect(&c, IsmConfig::new().with_sensor(scanner)),
    )
    .await
    .unwrap();
    let _ltm = within("ltm", tca_ltm::connect(&c, LtmConfig::default()))
        .await
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let config = PdmConfig {
        output_dir: Some(dir.path().to_owned()),
        ..PdmConfig::default()
    };
    let _pdm = within("pdm", tca_pdm::connect(&c, config)).await.unwrap();
    let client = within("client", Module::builder("client").connect(&c))
        .await
        .unwrap();
    let command = RenderMap {
        region: region(MapKind::Footfall),
        overlays: vec![Overlay::Point {
            at: WorldPoint {
                x_m: 3.0,
                y_m: 7.0,
                z_m: 0.0,
            },
            label: "footfall".into(),
        }],
        path: "footfall.png".into(),
    };
    let task = client.send_watched(&command, []).unwrap();
    let outcome = within("renderMap", task.outcome()).await.unwrap();
    assert_eq!(outcome, TaskOutcome::Achieved);
    let file = std::fs::File::open(dir.path().join("footfall.png")).unwrap();
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    assert!(reader.info().width > 400);

    // The same from a command-line tool's module.
    let path = dir.path().join("cli.png");
    within(
        "render_map",
        render_map(&client, &command, &RenderOptions::default(), &path),
    )
    .await
    .unwrap();
    assert!(path.exists());

    // Failures end the command with their reason.
    let unwritable = RenderMap {
        path: "no/such/dir/x.png".into(),
        ..command.clone()
    };
    let task = client.send_watched(&unwritable, []).unwrap();
    match within("unwritable", task.outcome()).await.unwrap() {
        TaskOutcome::Failed(reason) => assert!(reason.contains("cannot write"), "{reason}"),
        other => panic!("{other:?}"),
    }
    let bad_region = RenderMap {
        region: MapRegion {
            resolution_m: 0.0,
            ..region(MapKind::Elevation)
        },
        ..command
    };
    let task = client.send_watched(&bad_region, []).unwrap();
    match within("bad region", task.outcome()).await.unwrap() {
        TaskOutcome::Failed(reason) => {
            assert!(reason.contains("resolution 0 m is not valid"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
}
