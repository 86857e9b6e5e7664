//! The danger map's behaviour on steps, slopes, unknown ground and aged heights.

use nalgebra::Point2;
use tca_nav_danger_map::{CellDanger, CellRect, DangerMap, DangerParams, HeightView, assess_cell};
use tca_robot::{CellIndex, Grid, HeightField};

const RES: f64 = 0.02;
const N: usize = 80;

fn params() -> DangerParams {
    DangerParams::paper(0.5)
}

fn field(f: impl Fn(f64, f64) -> f64) -> HeightField {
    let g = Grid::from_fn(Point2::new(0.0, 0.0), RES, N, N, |_, p| f(p.x, p.y)).unwrap();
    HeightField::from_grid(g).unwrap()
}

fn map_of(view: &impl HeightView) -> DangerMap {
    DangerMap::from_view(params(), Point2::new(0.0, 0.0), RES, N, N, view).unwrap()
}

#[test]
fn a_60_mm_step_across_more_than_50_cells_is_untraversable_and_a_gentle_slope_is_not() {
    // A straight 60 mm step at x = 0.8 m: every cell within the robot's radius of it sees
    // far more than 50 step cells in its circle.
    let step = field(|x, _| if x >= 0.8 { 0.06 } else { 0.0 });
    let map = map_of(&step);
    let at_edge = map.cell(CellIndex::new(40, 40));
    assert!(at_edge.danger.is_infinite(), "{at_edge:?}");
    assert!((at_edge.step_m - 0.06).abs() < 1e-9, "{at_edge:?}");
    let far = map.cell(CellIndex::new(8, 40));
    assert!(far.danger < 0.01, "flat ground far from the step: {far:?}");

    // A 5 degree slope: finite, slope term 0.5 * 5 / 20.
    let tilt = 5f64.to_radians().tan();
    let slope = field(|x, _| x * tilt);
    let map = map_of(&slope);
    let c = map.cell(CellIndex::new(40, 40));
    assert!(c.is_traversable(), "{c:?}");
    assert!((c.slope_rad - 5f64.to_radians()).abs() < 1e-6, "{c:?}");
    assert!((c.danger - 0.125).abs() < 1e-3, "{c:?}");
    assert_eq!(c.step_m, 0.0);

    // A 25 degree slope passes s_crit.
    let steep = field(|x, _| x * 25f64.to_radians().tan());
    assert!(
        map_of(&steep)
            .cell(CellIndex::new(40, 40))
            .danger
            .is_infinite()
    );
}

#[test]
fn a_step_lower_than_critical_is_only_dangerous() {
    let step = field(|x, _| if x >= 0.8 { 0.04 } else { 0.0 });
    let c = map_of(&step).cell(CellIndex::new(40, 40));
    assert!(c.is_traversable() && c.danger > 0.1, "{c:?}");
}

#[test]
fn the_step_height_counts_in_full_only_over_n_crit_cells() {
    let flat = field(|_, _| 0.0);
    let p = params();
    // 30 cells of the circle carry a 60 mm temporary step: h = 0.06 * 30 / 50 = 36 mm.
    let few = |x: isize, y: isize| {
        ((x - 40).abs() <= 2 && (y - 40).abs() <= 2 || x == 40 && (y - 40).abs() <= 2 + 2)
            .then_some(0.06)
    };
    let n_few = (0..N as isize)
        .flat_map(|y| (0..N as isize).map(move |x| (x, y)))
        .filter(|&(x, y)| few(x, y).is_some())
        .count();
    let c = assess_cell(&p, RES, &flat, few, 40, 40);
    let expected = 0.06 * n_few as f64 / 50.0;
    assert!(n_few < 50);
    assert!((c.step_m - expected).abs() < 1e-12, "{c:?} vs {expected}");
    assert!(c.is_traversable());
    // 70 such cells: h = min(0.06, 0.06 * 70 / 50) = 0.06 > h_crit.
    let many = |x: isize, y: isize| ((x - 40).abs() <= 3 && (y - 40).abs() <= 4).then_some(0.06);
    let c = assess_cell(&p, RES, &flat, many, 40, 40);
    assert_eq!(c.step_m, 0.06);
    assert!(c.danger.is_infinite());
}

#[test]
fn unknown_ground_is_danger_one_with_its_certainty() {
    let unknown: Grid<Option<f64>> = Grid::filled(Point2::new(0.0, 0.0), RES, N, N, None).unwrap();
    let map = map_of(&unknown);
    assert_eq!(map.cell(CellIndex::new(40, 40)), CellDanger::UNKNOWN);
    // Half the plane known (x < 0.8 m): the cell on the border is computed with
    // certainty about one half.
    let half = Grid::from_fn(Point2::new(0.0, 0.0), RES, N, N, |_, p| {
        (p.x < 0.79).then_some(0.0)
    })
    .unwrap();
    let c = map_of(&half).cell(CellIndex::new(40, 40));
    assert!((c.certainty - 0.5).abs() < 0.05, "{c:?}");
    assert!(c.danger < 0.01);
    // A cell with under 30 % of its circle known stays unknown, danger 1.
    let c = map_of(&half).cell(CellIndex::new(48, 40));
    assert!(c.certainty < 0.3 && c.danger == 1.0, "{c:?}");
}

#[test]
fn untraversable_cells_are_reassessed_with_the_older_heights() {
    let step = field(|x, _| if x >= 0.8 { 0.06 } else { 0.0 });
    let mut map = map_of(&step);
    let edge = CellIndex::new(40, 40);
    assert!(!map.cell(edge).is_traversable());
    // The recent frames saw only flat ground west of the step; the step side is too old
    // for traversable cells but not for untraversable ones.
    let recent = Grid::from_fn(Point2::new(0.0, 0.0), RES, N, N, |_, p| {
        (p.x < 0.8).then_some(0.0)
    })
    .unwrap();
    let patch = CellRect {
        x0: 30,
        y0: 30,
        x1: 50,
        y1: 50,
    };
    let changed = map.update(patch, &recent, &step);
    assert!(
        !map.cell(edge).is_traversable(),
        "kept untraversable by the older heights"
    );
    // A traversable cell west of the step whose circle just reaches the step cells is
    // judged on the recent heights alone: the step it saw is gone.
    let west = CellIndex::new(24, 40);
    let before = map_of(&step).cell(west);
    assert!(before.is_traversable() && before.step_m > 0.0, "{before:?}");
    let after = map.cell(west);
    assert!(
        after.step_m == 0.0 && after.danger < before.danger,
        "{after:?}"
    );
    assert!(!changed.contains(&edge));
    // Reassessing the edge with the recent heights as the older ones too frees it.
    let changed = map.update(patch, &recent, &recent);
    assert!(map.cell(edge).is_traversable());
    assert!(changed.contains(&edge));
}

#[test]
fn the_robot_files_hold_the_papers_values_and_bad_files_are_explained() {
    for robot in ["hexapod", "wheeled"] {
        let path = format!("{}/robots/{robot}.toml", env!("CARGO_MANIFEST_DIR"));
        let p = DangerParams::read(&path).unwrap();
        assert_eq!(p.s_crit_deg, 20.0);
        assert_eq!(p.alpha, [0.5, 0.25, 0.25]);
        assert_eq!(p.n_crit, 50);
    }
    let e = DangerParams::from_toml("robot_diameter_m = 0.5\n", "x.toml").unwrap_err();
    assert!(e.to_string().contains("x.toml"), "{e}");
    let mut bad = params();
    bad.alpha = [0.5, 0.5, 0.5];
    assert!(bad.validate().unwrap_err().to_string().contains("sum to 1"));
    bad = params();
    bad.step_window_cells = 10;
    assert!(bad.validate().unwrap_err().to_string().contains("odd"));
}
