//! Imaging from a legged robot's body: the mast geometry at both scales, the transform chain
//! of images taken at any orientation, and the ISM module asking `legged.bodyPose`.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::{Point2, Point3, Vector3};
use tca_ism::{
    BodyDimensions, ImageFrames, IsmConfig, NoiseModel, PoseSource, SensorSpec, VirtualScanner,
    world_from_body,
};
use tca_legged_messages::Pose;
use tca_module::Module;
use tca_single_leg_messages::{AcquireImage, SensorKind};
use tca_testkit::within;

fn flat(lo: f64, hi: f64, cell: f64) -> Arc<tca_robot::HeightField> {
    Arc::new(
        tca_robot::HeightField::flat(Point2::new(lo, lo), Point2::new(hi, hi), cell, 0.0).unwrap(),
    )
}

/// The world points of an image (pixels with a return).
fn points(image: &tca_single_leg_messages::RangeImage) -> Vec<Point3<f64>> {
    let spec = SensorSpec::of(image.sensor);
    let g = ImageFrames::of(image).unwrap().global_from_locus();
    let w = spec.width_px as usize;
    image
        .range_counts
        .iter()
        .zip(&image.reflectance)
        .enumerate()
        .filter(|(_, (_, r))| **r > 0)
        .map(|(k, (c, _))| {
            let d = spec.pixel_direction((k / w) as u32, (k % w) as u32);
            g * Point3::from(d * spec.count_range_m(*c))
        })
        .collect()
}

fn pose(x: f64, y: f64, z: f64, roll: f64, pitch: f64, yaw: f64) -> Pose {
    Pose {
        x_m: x,
        y_m: y,
        z_m: z,
        roll_rad: roll,
        pitch_rad: pitch,
        yaw_rad: yaw,
    }
}

/// On level ground, with the body turned and tilted, every return lies on the ground and the
/// image covers the ground under the body and two leg reaches ahead, across the body and
/// the legs, at both scales.
#[test]
fn the_mast_sees_under_the_body_to_two_reaches_ahead_at_any_heading() {
    for (body, cell) in [
        (BodyDimensions::AMBLER, 0.1),
        (BodyDimensions::HEXAPOD, 0.02),
    ] {
        let s = body.standing_height_m;
        let terrain = flat(-40.0 * s, 40.0 * s, cell);
        let scanner = VirtualScanner::on_body(SensorSpec::perceptron(), terrain, body.mast_mount())
            .with_noise(NoiseModel::none());
        let p = pose(3.0 * s, -2.0 * s, s, 0.05, -0.04, 0.7);
        let image = scanner.cast_from_body(&world_from_body(&p), 0).unwrap();
        SensorSpec::perceptron().check_image(&image).unwrap();
        let frames = ImageFrames::of(&image).unwrap();
        let origin = frames.body_origin_world();
        assert!((origin - Vector3::new(p.x_m, p.y_m, p.z_m)).norm() < 1e-12);
        let pts = points(&image);
        assert!(pts.len() > 60_000, "{} returns", pts.len());
        let q = SensorSpec::perceptron().range_resolution_m();
        let (c, sn) = (p.yaw_rad.cos(), p.yaw_rad.sin());
        let (mut min_fwd, mut max_fwd, mut max_side) = (f64::INFINITY, f64::NEG_INFINITY, 0.0_f64);
        for w in &pts {
            assert!(w.z.abs() < q, "a return {} m off the ground", w.z);
            // Body-heading coordinates of the point.
            let (dx, dy) = (w.x - p.x_m, w.y - p.y_m);
            let fwd = c * dx + sn * dy;
            let side = -sn * dx + c * dy;
            min_fwd = min_fwd.min(fwd);
            max_fwd = max_fwd.max(fwd);
            if fwd.abs() < 0.5 * body.length_m {
                max_side = max_side.max(side.abs());
            }
        }
        let reach = body.leg_reach_m();
        assert!(
            min_fwd < -0.5 * body.length_m,
            "{body:?}: nearest {min_fwd}"
        );
        assert!(
            max_fwd > 0.5 * body.length_m + 2.0 * reach,
            "{body:?}: farthest {max_fwd}"
        );
        assert!(
            max_side > 0.5 * body.width_m + reach,
            "{body:?}: widest {max_side} beside the body"
        );
    }
}

/// The cost of one legged image (printed; asserted loosely so slow machines pass).
#[test]
fn one_legged_image_is_cheap() {
    let course = flat(-20.0, 40.0, 0.1);
    let body = BodyDimensions::AMBLER;
    let scanner = VirtualScanner::on_body(SensorSpec::perceptron(), course, body.mast_mount());
    let at = world_from_body(&pose(3.0, 0.0, 2.6, 0.0, 0.0, 0.3));
    scanner.cast_from_body(&at, 0).unwrap();
    let began = Instant::now();
    let n = 5;
    for k in 0..n {
        scanner.cast_from_body(&at, k).unwrap();
    }
    let ms = began.elapsed().as_secs_f64() * 1e3 / n as f64;
    println!("one legged Perceptron image: {ms:.1} ms");
    assert!(ms < 500.0, "{ms} ms per image");
}

#[test]
fn bad_poses_and_bodies_are_refused() {
    let scanner = VirtualScanner::on_body(
        SensorSpec::perceptron(),
        flat(-5.0, 5.0, 0.1),
        BodyDimensions::AMBLER.mast_mount(),
    );
    let e = scanner
        .cast_from_body(
            &world_from_body(&pose(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0)),
            0,
        )
        .unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
    let bad = BodyDimensions {
        length_m: -1.0,
        ..BodyDimensions::AMBLER
    };
    assert!(bad.check().is_err());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_legged_ism_asks_for_the_body_pose() {
    let (_central, c) = tca_testkit::in_process_central().await;
    let p = pose(4.0, 1.0, 2.6, 0.03, -0.02, 0.7);
    let _controller = within(
        "controller",
        Module::builder("controller")
            .handle(move |_ctx, _q: tca_legged_messages::BodyPose| async move { Ok(p) })
            .connect(&c),
    )
    .await
    .unwrap();
    let config = IsmConfig::legged_simulated(flat(-10.0, 20.0, 0.1), &BodyDimensions::AMBLER, 3);
    assert_eq!(config.pose_source(), PoseSource::LeggedBody);
    assert_eq!(config.kinds(), vec![SensorKind::Perceptron]);
    let _ism = within("ism", tca_ism::connect(&c, config)).await.unwrap();
    let client = within("client", Module::builder("client").connect(&c))
        .await
        .unwrap();
    let image = within(
        "acquire",
        client.query(&AcquireImage {
            sensor: SensorKind::Perceptron,
        }),
    )
    .await
    .unwrap();
    let frames = ImageFrames::of(&image).unwrap();
    let expected = world_from_body(&p);
    let got = frames.body_from_global.inverse();
    assert!(
        (got.to_homogeneous() - expected.to_homogeneous())
            .abs()
            .max()
            < 1e-12
    );
    let scanner = frames.global_from_locus() * Point3::origin();
    assert!((scanner - expected * Point3::new(0.0, 0.0, 5.2)).norm() < 1e-9);

    let bad = BodyDimensions {
        standing_height_m: f64::NAN,
        ..BodyDimensions::AMBLER
    };
    let e = tca_ism::connect(
        &c,
        IsmConfig::legged_simulated(flat(-1.0, 1.0, 0.1), &bad, 0),
    )
    .await
    .unwrap_err()
    .to_string();
    assert!(e.contains("body dimensions"), "{e}");
}
