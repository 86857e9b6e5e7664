//! The ISM module on an in-process central, with a fake Controller answering `bodyPosition`.

use std::sync::Arc;
use tca_testkit::within;

use nalgebra::Point2;
use tca_ism::stored::write_sequence_image;
use tca_ism::{ImageFrames, IsmConfig, SensorSpec, StoredSequence, VirtualScanner};
use tca_module::{Connector, Module};
use tca_robot::{CarriagePose, HeightField, LegParams};
use tca_single_leg_messages::{AcquireImage, BodyPose, BodyPosition, SensorKind};

fn flat() -> Arc<HeightField> {
    Arc::new(HeightField::flat(Point2::new(-5.0, -5.0), Point2::new(12.0, 25.0), 0.1, 0.0).unwrap())
}

async fn controller(c: &Connector, y_m: f64) -> Module {
    Module::builder("controller")
        .handle(move |_ctx, _q: BodyPosition| async move {
            Ok(BodyPose {
                y_m,
                roll_rad: 0.0,
                pitch_rad: 0.0,
            })
        })
        .connect(c)
        .await
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn acquire_image_is_tagged_with_the_controllers_pose() {
    let (_central, c) = tca_testkit::in_process_central().await;
    let _controller = within("controller", controller(&c, 2.5)).await;
    let params = LegParams::default();
    let config =
        IsmConfig::new().with_sensor(VirtualScanner::new(SensorSpec::erim(), flat(), &params));
    assert_eq!(config.kinds(), vec![SensorKind::Erim]);
    let _ism = within("ism", tca_ism::connect(&c, config)).await.unwrap();
    let client = within("client", Module::builder("client").connect(&c))
        .await
        .unwrap();

    let image = within(
        "acquire",
        client.query(&AcquireImage {
            sensor: SensorKind::Erim,
        }),
    )
    .await
    .unwrap();
    SensorSpec::erim().check_image(&image).unwrap();
    let frames = ImageFrames::of(&image).unwrap();
    assert!((frames.body_origin_world().y - 2.5).abs() < 1e-12);
    assert_eq!(image.sequence, 0);
    assert!(image.reflectance.iter().filter(|&&r| r > 0).count() > 10_000);
    let next = within(
        "acquire",
        client.query(&AcquireImage {
            sensor: SensorKind::Erim,
        }),
    )
    .await
    .unwrap();
    assert_eq!(next.sequence, 1);

    let e = within(
        "missing sensor",
        client.query(&AcquireImage {
            sensor: SensorKind::Perceptron,
        }),
    )
    .await
    .unwrap_err()
    .to_string();
    assert!(e.contains("no Perceptron sensor"), "{e}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stored_sequence_serves_its_images_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let params = LegParams::default();
    let scanner = VirtualScanner::new(SensorSpec::perceptron(), flat(), &params);
    let recorded: Vec<_> = (0..2)
        .map(|k| {
            scanner
                .cast(&CarriagePose::level(1.0 + k as f64), k)
                .unwrap()
        })
        .collect();
    for image in &recorded {
        write_sequence_image(dir.path(), image).unwrap();
    }
    let (_central, c) = tca_testkit::in_process_central().await;
    let _controller = within("controller", controller(&c, 7.0)).await;
    let stored = StoredSequence::open(dir.path(), SensorKind::Perceptron, false).unwrap();
    let _ism = within(
        "ism",
        tca_ism::connect(&c, IsmConfig::new().with_sensor(stored)),
    )
    .await
    .unwrap();
    let client = within("client", Module::builder("client").connect(&c))
        .await
        .unwrap();
    let ask = AcquireImage {
        sensor: SensorKind::Perceptron,
    };
    for expected in &recorded {
        let got = within("acquire", client.query(&ask)).await.unwrap();
        assert_eq!(&got, expected, "stored images keep their own poses");
    }
    let e = within("past the end", client.query(&ask))
        .await
        .unwrap_err()
        .to_string();
    assert!(e.contains("have been played"), "{e}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_sensors_of_one_kind_are_refused() {
    let (_central, c) = tca_testkit::in_process_central().await;
    let params = LegParams::default();
    let config = IsmConfig::simulated(flat(), &params, 0).with_sensor(VirtualScanner::new(
        SensorSpec::erim(),
        flat(),
        &params,
    ));
    let e = tca_ism::connect(&c, config).await.unwrap_err().to_string();
    assert!(e.contains("two Erim sensors"), "{e}");
}
