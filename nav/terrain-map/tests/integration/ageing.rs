//! Frames overwrite heights, and age windows hide old ones.

use nalgebra::{Point2, Point3};
use tca_nav_danger_map::{DangerMap, DangerParams, HeightView};
use tca_nav_terrain_map::{Ageing, TerrainMap};
use tca_robot::CellIndex;

fn map() -> TerrainMap {
    TerrainMap::new(Point2::new(0.0, 0.0), 0.02, 100, 100, Ageing::PAPER).unwrap()
}

fn patch(x0: f64, x1: f64, z: f64) -> Vec<Point3<f64>> {
    let mut pts = Vec::new();
    let mut x = x0;
    while x <= x1 {
        let mut y = 0.0;
        while y < 2.0 {
            pts.push(Point3::new(x, y, z));
            y += 0.01;
        }
        x += 0.01;
    }
    pts
}

#[test]
fn the_highest_point_of_a_frame_overwrites_the_cell_and_ages() {
    let mut m = map();
    let r = m
        .insert_frame([Point3::new(0.5, 0.5, 0.1), Point3::new(0.505, 0.505, 0.3)])
        .unwrap();
    assert_eq!((r.x0, r.y0, r.x1, r.y1), (25, 25, 25, 25));
    assert_eq!(m.cell(CellIndex::new(25, 25)), Some((0.3, 1)));
    for _ in 0..20 {
        m.insert_frame([Point3::new(1.5, 1.5, 0.0)]);
    }
    assert_eq!(m.frame(), 21);
    assert_eq!(
        m.recent().height(25, 25),
        Some(0.3),
        "20 frames old: still recent"
    );
    m.insert_frame([]);
    assert_eq!(
        m.recent().height(25, 25),
        None,
        "21 frames old: dropped from the recent window"
    );
    assert_eq!(m.older().height(25, 25), Some(0.3));
    // A new frame overwrites, even with a lower height.
    m.insert_frame([Point3::new(0.5, 0.5, 0.05)]);
    assert_eq!(m.cell(CellIndex::new(25, 25)), Some((0.05, 23)));
    assert_eq!(
        m.insert_frame([Point3::new(-5.0, 0.0, 0.0)]),
        None,
        "outside the grid"
    );
}

#[test]
fn an_old_misplaced_step_is_not_a_hazard_for_traversable_cells() {
    // Frame 1 saw a 60 mm ledge east of x = 1 m (an artifact of drift, say); the next 25
    // frames saw level ground west of it.
    let mut m = map();
    m.insert_frame(patch(1.0, 1.99, 0.06));
    for _ in 0..25 {
        m.insert_frame(patch(0.0, 0.99, 0.0));
    }
    let (origin, res, nx, ny) = m.geometry();
    let mut all = DangerMap::new(DangerParams::paper(0.5), origin, res, nx, ny).unwrap();
    let mut aged = all.clone();
    let rect = tca_nav_danger_map::CellRect {
        x0: 0,
        y0: 0,
        x1: 99,
        y1: 99,
    };
    all.update(rect, &m.all(), &m.all());
    aged.update(rect, &m.recent(), &m.older());
    let c = CellIndex::new(48, 50);
    assert!(
        !all.cell(c).is_traversable(),
        "every height: the ledge blocks"
    );
    assert!(
        aged.cell(c).is_traversable(),
        "aged: the ledge is too old for a traversable cell"
    );
}

#[test]
fn bad_age_windows_are_refused() {
    let e = TerrainMap::new(
        Point2::new(0.0, 0.0),
        0.02,
        10,
        10,
        Ageing {
            recent_frames: 30,
            older_frames: 20,
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("recent <= older"), "{e}");
}
