//! What map to draw: the kind, the area (a rectangle, a polygon, or everything mapped) and
//! the resolution, parsed from command-line text and checked before any work is done.

use anyhow::{Context as _, bail};
use tca_ltm::{LtmConfig, Region};
use tca_pdm::render::MAX_CELLS_PER_SIDE;
use tca_single_leg_messages::{MapKind, PlanePoint};

/// The default cell size, metres.
pub const DEFAULT_RESOLUTION_M: f64 = 0.05;

/// Which part of the terrain to draw.
#[derive(Clone, Debug, PartialEq)]
pub enum MapArea {
    /// Everything the map knows about (known or occluded cells).
    Mapped,
    /// A polygon, world frame (a rectangle is a four-corner polygon).
    Polygon(Vec<PlanePoint>),
}

/// A map to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct MapRequest {
    /// The map kind (elevation, elevation uncertainty, footfall evaluation or slope).
    pub kind: MapKind,
    /// The area.
    pub area: MapArea,
    /// Cell size, metres.
    pub resolution_m: f64,
}

impl MapRequest {
    /// A checked request: a finite resolution above zero and, for a polygon, a region the LTM
    /// Manager serves and the PDM can draw at that resolution.
    pub fn new(kind: MapKind, area: MapArea, resolution_m: f64) -> anyhow::Result<Self> {
        check_resolution(resolution_m)?;
        if let MapArea::Polygon(corners) = &area {
            check_region(corners, resolution_m)?;
        }
        Ok(Self {
            kind,
            area,
            resolution_m,
        })
    }
}

/// Refuses a resolution that is not a finite length above zero.
pub fn check_resolution(resolution_m: f64) -> anyhow::Result<()> {
    if !(resolution_m.is_finite() && resolution_m > 0.0) {
        bail!(
            "--resolution must be a cell size in metres greater than zero (e.g. 0.05), got \
             {resolution_m}"
        );
    }
    Ok(())
}

/// Checks that `corners` at `resolution_m` make a region the LTM Manager answers and the PDM
/// draws; returns its size in cells `(nx, ny)`.
pub fn check_region(corners: &[PlanePoint], resolution_m: f64) -> anyhow::Result<(usize, usize)> {
    let region = Region::new(corners, resolution_m, LtmConfig::default().max_query_cells)
        .context("the region cannot be mapped")?;
    let layout = region.layout();
    let limit = MAX_CELLS_PER_SIDE as usize;
    if layout.nx > limit || layout.ny > limit {
        let side_m = layout.nx.max(layout.ny) as f64 * resolution_m;
        bail!(
            "the region is {} x {} cells at {resolution_m} m, and a picture has at most {limit} \
             cells a side; give --resolution {:.3} or coarser, or a smaller region",
            layout.nx,
            layout.ny,
            side_m / limit as f64
        );
    }
    Ok((layout.nx, layout.ny))
}

/// Parses a map kind: `elevation`, `uncertainty`, `footfall` or `slope`.
pub fn parse_kind(text: &str) -> anyhow::Result<MapKind> {
    match text.trim().to_ascii_lowercase().as_str() {
        "elevation" => Ok(MapKind::Elevation),
        "uncertainty" | "elevation-uncertainty" => Ok(MapKind::ElevationUncertainty),
        "footfall" => Ok(MapKind::Footfall),
        "slope" => Ok(MapKind::Slope),
        other => {
            bail!("unknown map kind {other:?}; give elevation, uncertainty, footfall or slope")
        }
    }
}

/// The command-line name of a map kind.
pub fn kind_name(kind: MapKind) -> &'static str {
    match kind {
        MapKind::Elevation => "elevation",
        MapKind::ElevationUncertainty => "uncertainty",
        MapKind::Footfall => "footfall",
        MapKind::Slope => "slope",
        MapKind::Reachability => "reachability",
    }
}

fn number(text: &str, what: &str, usage: &str) -> anyhow::Result<f64> {
    let Ok(v) = text.trim().parse::<f64>() else {
        bail!("{what}: {text:?} is not a number; {usage}");
    };
    if !v.is_finite() {
        bail!("{what}: {text:?} is not a finite number of metres; {usage}");
    }
    Ok(v)
}

/// Parses `--region x0,y0,x1,y1` (metres, world frame: two opposite corners of a rectangle)
/// into the rectangle's four corners.
pub fn parse_rectangle(text: &str) -> anyhow::Result<Vec<PlanePoint>> {
    let usage = "give --region x0,y0,x1,y1 in metres, e.g. --region 0,0,6,11";
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 4 {
        bail!(
            "--region {text:?} has {} numbers, not 4; {usage}",
            parts.len()
        );
    }
    let mut v = [0.0; 4];
    for (slot, part) in v.iter_mut().zip(&parts) {
        *slot = number(part, "--region", usage)?;
    }
    let [x0, y0, x1, y1] = v;
    if x0 == x1 || y0 == y1 {
        bail!("--region {text:?} encloses no area (x0 = x1 or y0 = y1); {usage}");
    }
    let (xa, xb) = (x0.min(x1), x0.max(x1));
    let (ya, yb) = (y0.min(y1), y0.max(y1));
    Ok(rectangle(xa, ya, xb, yb))
}

/// The four corners of an axis-aligned rectangle, counter-clockwise.
pub fn rectangle(x_min_m: f64, y_min_m: f64, x_max_m: f64, y_max_m: f64) -> Vec<PlanePoint> {
    [
        (x_min_m, y_min_m),
        (x_max_m, y_min_m),
        (x_max_m, y_max_m),
        (x_min_m, y_max_m),
    ]
    .iter()
    .map(|&(x_m, y_m)| PlanePoint { x_m, y_m })
    .collect()
}

/// Parses `--polygon "x,y x,y x,y ..."` (metres, world frame; points separated by spaces or
/// semicolons, coordinates by a comma): at least three corners.
pub fn parse_polygon(text: &str) -> anyhow::Result<Vec<PlanePoint>> {
    let usage = "give --polygon \"x,y x,y x,y ...\" in metres, e.g. --polygon \"1,2 5,2 3,6\"";
    let mut corners = Vec::new();
    for (n, point) in text
        .split(|c: char| c.is_whitespace() || c == ';')
        .filter(|p| !p.is_empty())
        .enumerate()
    {
        let Some((x, y)) = point.split_once(',') else {
            bail!("--polygon point {} ({point:?}) is not x,y; {usage}", n + 1);
        };
        let what = format!("--polygon point {}", n + 1);
        let x_m = number(x, &what, usage)?;
        let y_m = number(y, &what, usage)?;
        corners.push(PlanePoint { x_m, y_m });
    }
    if corners.len() < 3 {
        bail!(
            "--polygon needs at least three points, got {}; {usage}",
            corners.len()
        );
    }
    Ok(corners)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err<T: std::fmt::Debug>(r: anyhow::Result<T>) -> String {
        format!("{:#}", r.unwrap_err())
    }

    #[test]
    fn rectangles_parse_in_either_corner_order() {
        let r = parse_rectangle("6,11,0,0").unwrap();
        assert_eq!(r, rectangle(0.0, 0.0, 6.0, 11.0));
        assert_eq!(parse_rectangle(" 1.5, 2 ,3,4").unwrap()[0].x_m, 1.5);
    }

    #[test]
    fn bad_rectangles_say_what_to_give() {
        assert!(err(parse_rectangle("0,0,6")).contains("3 numbers, not 4"));
        assert!(err(parse_rectangle("0,0,six,11")).contains("not a number"));
        assert!(err(parse_rectangle("0,0,NaN,11")).contains("not a finite"));
        assert!(err(parse_rectangle("1,0,1,11")).contains("no area"));
        assert!(err(parse_rectangle("")).contains("--region x0,y0,x1,y1"));
    }

    #[test]
    fn polygons_parse_with_spaces_or_semicolons() {
        let p = parse_polygon("1,2 5,2;3,6").unwrap();
        assert_eq!(p.len(), 3);
        assert_eq!((p[2].x_m, p[2].y_m), (3.0, 6.0));
        assert!(err(parse_polygon("1,2 5,2")).contains("at least three points, got 2"));
        assert!(err(parse_polygon("1,2 5 3,6")).contains("point 2"));
        assert!(err(parse_polygon("1,2 5,x 3,6")).contains("not a number"));
    }

    #[test]
    fn resolutions_and_regions_are_checked() {
        assert!(err(check_resolution(0.0)).contains("greater than zero"));
        assert!(check_resolution(f64::NAN).is_err());
        assert!(check_resolution(-0.1).is_err());
        assert_eq!(
            check_region(&rectangle(0.0, 0.0, 6.0, 11.0), 0.05).unwrap(),
            (121, 221)
        );
        let e = err(check_region(&rectangle(0.0, 0.0, 6.0, 11.0), 0.001));
        assert!(e.contains("coarser"), "{e}");
        let line = parse_polygon("0,0 1,1 2,2").unwrap();
        assert!(err(check_region(&line, 0.1)).contains("zero area"));
        assert!(MapRequest::new(MapKind::Slope, MapArea::Mapped, 0.0).is_err());
    }

    #[test]
    fn kinds_parse_by_their_command_line_names() {
        for kind in [
            MapKind::Elevation,
            MapKind::ElevationUncertainty,
            MapKind::Footfall,
            MapKind::Slope,
        ] {
            assert_eq!(parse_kind(kind_name(kind)).unwrap(), kind);
        }
        assert!(err(parse_kind("height")).contains("elevation, uncertainty"));
    }
}
