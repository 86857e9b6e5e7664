//! The LTM Manager module on an in-process central, with the real ISM module and a fake
//! Controller answering `bodyPosition`.

use crate::common;

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use tca_testkit::within;

use common::{BOX, params, rect, terrain};
use tca_ism::{IsmConfig, SensorSpec, VirtualScanner};
use tca_ltm::LtmConfig;
use tca_module::Module;
use tca_single_leg_messages::{BodyPose, BodyPosition, MapCell, MapKind, MapRegion};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn map_region_takes_an_image_when_it_has_none_or_is_asked_to() {
    let (_central, c) = tca_testkit::in_process_central().await;
    let poses = Arc::new(AtomicUsize::new(0));
    let counter = poses.clone();
    let _controller = within(
        "controller",
        Module::builder("controller")
            .handle(move |_ctx, _q: BodyPosition| {
                counter.fetch_add(1, Ordering::SeqCst);
                async {
                    Ok(BodyPose {
                        y_m: 1.0,
                        roll_rad: 0.0,
                        pitch_rad: 0.0,
                    })
                }
            })
            .connect(&c),
    )
    .await
    .unwrap();
    let scanner = VirtualScanner::new(SensorSpec::erim(), terrain(&[BOX]), &params());
    let _ism = within(
        "ism",
        tca_ism::connect(&c, IsmConfig::new().with_sensor(scanner)),
    )
    .await
    .unwrap();
    let _ltm = within("ltm", tca_ltm::connect(&c, LtmConfig::default()))
        .await
        .unwrap();
    let client = within("client", Module::builder("client").connect(&c))
        .await
        .unwrap();

    let mut request = MapRegion {
        kind: MapKind::Elevation,
        polygon: rect(2.0, 7.0, 4.0, 9.0),
        resolution_m: 0.1,
        refresh: false,
    };
    // No map yet: the LTM asks the ISM, which asks the Controller.
    let grid = within("first query", client.query(&request)).await.unwrap();
    assert_eq!(poses.load(Ordering::SeqCst), 1);
    assert_eq!((grid.nx, grid.ny), (21, 21));
    let at = |x: f64, y: f64| {
        let ix = ((x - grid.origin_x_m) / grid.resolution_m).round() as usize;
        let iy = ((y - grid.origin_y_m) / grid.resolution_m).round() as usize;
        grid.cells[iy * grid.nx as usize + ix]
    };
    match at(3.0, 8.0) {
        MapCell::Known { value, .. } => assert!((value - 0.5).abs() < 0.1, "box top {value}"),
        other => panic!("box top is {other:?}"),
    }
    assert!(matches!(at(3.0, 8.9), MapCell::Occluded { .. }));
    // A map exists: no new image.
    within("cached query", client.query(&request))
        .await
        .unwrap();
    assert_eq!(poses.load(Ordering::SeqCst), 1);
    // A bad region is refused before any image is taken.
    let bad = MapRegion {
        polygon: rect(0.0, 0.0, 1.0, 1.0)[..2].to_vec(),
        refresh: true,
        ..request.clone()
    };
    let e = within("bad query", client.query(&bad))
        .await
        .unwrap_err()
        .to_string();
    assert!(e.contains("at least three polygon corners"), "{e}");
    let nan = MapRegion {
        resolution_m: f64::NAN,
        ..request.clone()
    };
    let e = within("NaN resolution", client.query(&nan))
        .await
        .unwrap_err()
        .to_string();
    assert!(e.contains("resolution NaN m is not valid"), "{e}");
    assert_eq!(poses.load(Ordering::SeqCst), 1);
    // Refresh: a new image.
    request.refresh = true;
    within("refresh", client.query(&request)).await.unwrap();
    assert_eq!(poses.load(Ordering::SeqCst), 2);
}
