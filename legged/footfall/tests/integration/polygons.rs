//! The rover's polygons wherever the chosen foot is placed: the conservative polygon lies
//! inside the support polygon.

use std::sync::{Arc, OnceLock};

use nalgebra::Point2;
use proptest::prelude::*;
use tca_footfall::Scene;
use tca_footfall::maps::{Evaluator, MapParams};
use tca_stability::{conservative_support_polygon, support_polygon};

fn scene() -> &'static Arc<Scene> {
    static SCENE: OnceLock<Arc<Scene>> = OnceLock::new();
    SCENE.get_or_init(|| Arc::new(Scene::rock_field(1).unwrap()))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn the_conservative_polygon_lies_inside_the_support_polygon(
        leg in 0usize..6,
        dx in -2.5..2.5f64,
        dy in -2.5..2.5f64,
    ) {
        let scene = scene();
        let eval = Evaluator::new(scene, leg, &MapParams::default()).unwrap();
        let here = scene.touch_points()[leg];
        let mut feet: Vec<Point2<f64>> = eval.other_feet().to_vec();
        feet.push(Point2::new(here.x + dx, here.y + dy));
        let support = support_polygon(&feet);
        let conservative = conservative_support_polygon(&feet);
        for v in conservative.vertices() {
            prop_assert!(support.signed_distance(*v) >= -1e-9, "{v:?} outside {support:?}");
        }
        prop_assert!(conservative.area() <= support.area() + 1e-9);
        // And the margins the maps report keep that order.
        let com = scene.centre_of_mass_with(leg, &scene.posture[leg]);
        let ms = tca_stability::stability_margin(&support, com);
        let mc = tca_stability::stability_margin(&conservative, com);
        prop_assert!(mc <= ms + 1e-9, "{mc} > {ms}");
    }
}
