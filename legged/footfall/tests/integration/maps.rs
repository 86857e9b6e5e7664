//! The maps of the rock field's rover: colours where they should be, agreement with the
//! brute-force check of the same rules, and the robot's polygons.

use nalgebra::Point2;
use tca_footfall::Scene;
use tca_footfall::maps::{Colour, MapParams, brute_force_verdict, leg_maps};

#[test]
fn rock_field_maps_have_every_colour_and_agree_with_brute_force() {
    let scene = Scene::rock_field(1).unwrap();
    let params = MapParams::default();
    let leg = scene.leg_index("left_front").unwrap();
    let t = std::time::Instant::now();
    let maps = leg_maps(&scene, leg, &params).unwrap();
    println!("maps in {:?}: {:?}", t.elapsed(), maps.counts);
    for row in maps.rows.iter().rev().step_by(2) {
        println!("{}", row.chars().step_by(2).collect::<String>());
    }
    let c = maps.counts;
    assert!(
        c.green > 200 && c.red > 200 && c.orange > 0 && c.blue > 0,
        "{c:?}"
    );
    // Every fourth cell, both ways.
    let (mut same, mut total) = (0, 0);
    for iy in (0..maps.ny).step_by(4) {
        for ix in (0..maps.nx).step_by(4) {
            let Some(colour) = maps.colour(ix, iy) else {
                continue;
            };
            let brute = brute_force_verdict(&scene, leg, &params, maps.centre(ix, iy));
            total += 1;
            if brute == colour {
                same += 1;
            } else {
                println!("cell ({ix}, {iy}): map {colour:?}, brute force {brute:?}");
            }
        }
    }
    println!("agreement {same}/{total}");
    assert!(same as f64 >= 0.99 * total as f64, "{same}/{total}");
    let _ = Point2::new(0.0, 0.0);
    let _ = Colour::Green;
}
