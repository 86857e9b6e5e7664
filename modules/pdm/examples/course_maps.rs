//! Draws the maps the LTM Manager builds of an obstacle course from a few Erim images taken
//! along the rails, one picture per map kind, with the carriage stations drawn as a path.
//!
//! `cargo run -p tca-pdm --example course_maps -- [course 1-4] [output directory]`

use std::sync::Arc;

use tca_ism::{SensorSpec, VirtualScanner};
use tca_ltm::{LocalTerrainMap, LtmConfig};
use tca_pdm::{RenderOptions, write_png};
use tca_robot::{CarriagePose, Course, LegParams};
use tca_single_leg_messages::{MapKind, MapRegion, Overlay, PlanePoint, WorldPoint};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let course: u32 = args.next().map_or(Ok(3), |a| a.parse())?;
    let out = std::path::PathBuf::from(args.next().unwrap_or_else(|| "maps".into()));
    std::fs::create_dir_all(&out)?;
    let terrain = Arc::new(Course::builtin(course)?.height_field()?);
    let params = LegParams::default();
    let scanner = VirtualScanner::new(SensorSpec::erim(), terrain, &params).with_seed(1);
    let mut map = LocalTerrainMap::new(LtmConfig::default())?;
    let stations = [0.5, 1.5, 2.5, 3.5, 4.5];
    for (k, &y) in stations.iter().enumerate() {
        map.add_image(&scanner.cast(&CarriagePose::level(y), k as u64)?)?;
    }
    let pit = [(0.0, 0.0), (6.0, 0.0), (6.0, 11.0), (0.0, 11.0)]
        .iter()
        .map(|&(x_m, y_m)| PlanePoint { x_m, y_m })
        .collect::<Vec<_>>();
    let path = Overlay::Path {
        points: stations
            .iter()
            .map(|&y_m| WorldPoint {
                x_m: params.carriage.x_m,
                y_m,
                z_m: params.carriage.link_plane_height_m,
            })
            .collect(),
        label: "carriage".into(),
    };
    for kind in [
        MapKind::Elevation,
        MapKind::ElevationUncertainty,
        MapKind::Footfall,
        MapKind::Slope,
    ] {
        let grid = map.query(&MapRegion {
            kind,
            polygon: pit.clone(),
            resolution_m: 0.05,
            refresh: false,
        })?;
        let file = out.join(format!("course{course}-{kind:?}.png").to_lowercase());
        let options = RenderOptions {
            title: Some(format!("COURSE {course} {kind:?}")),
            ..RenderOptions::default()
        };
        write_png(&file, &grid, std::slice::from_ref(&path), &options)?;
        println!("{}", file.display());
    }
    Ok(())
}
