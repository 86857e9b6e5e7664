//! Maps from a traffic log: the range images the ISM returned (`acquireImage` replies) are fed,
//! in order, to a fresh LTM Manager map ([`LocalTerrainMap`]), which rebuilds the map the running
//! LTM Manager had (same builder, merger and scroller); the footfalls are those the Gait
//! Planner announced (`stepPlanned`), or else those it sent the Leg Recovery Planner
//! (`recoverLeg`).

use std::path::Path;

use anyhow::{Context as _, bail};
use tca_logs::{Direction, LogFile, RecordKind, TimeBase};
use tca_ltm::{LocalTerrainMap, LtmConfig};
use tca_messages::{Class, decode_data};
use tca_single_leg_messages::{
    MapRegion, Overlay, RangeImage, RecoverLeg, StepPlanned, WorldPoint,
};

use super::picture::{MapPicture, draw};
use super::request::{MapArea, MapRequest, check_region, rectangle};

/// Something recorded, with its time in seconds from the start of the log.
#[derive(Clone, Debug, PartialEq)]
pub struct Timed<T> {
    /// Seconds from the log's first message on the chosen clock.
    pub at_s: f64,
    /// What was recorded.
    pub value: T,
}

/// What a traffic log holds for maps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordedWalk {
    /// The range images, in the order the ISM returned them.
    pub images: Vec<Timed<RangeImage>>,
    /// The chosen footfalls, in order.
    pub footfalls: Vec<Timed<WorldPoint>>,
}

/// How to make a map from a log.
#[derive(Clone, Debug, PartialEq)]
pub struct LogMapOptions {
    /// The map as it stood this many seconds after the log's first message (`None`: the end).
    pub at_s: Option<f64>,
    /// The clock `at_s` is counted on: the messages' own timestamps (simulated time when the
    /// modules ran on it, as `tca walk` does) or central's clock.
    pub time_base: TimeBase,
    /// Draw the footfalls chosen up to then.
    pub overlay_footfalls: bool,
}

impl Default for LogMapOptions {
    fn default() -> Self {
        Self {
            at_s: None,
            time_base: TimeBase::Envelope,
            overlay_footfalls: false,
        }
    }
}

/// Reads the range images and footfalls of a log. Frames are taken as they reached central
/// from their senders (so each message counts once).
pub fn read_walk(log: &LogFile, time_base: TimeBase) -> RecordedWalk {
    let mut start = u64::MAX;
    let mut images = Vec::new();
    let mut planned = Vec::new();
    let mut recover = Vec::new();
    for record in &log.records {
        let RecordKind::Frame(f) = &record.kind else {
            continue;
        };
        let Ok(env) = LogFile::envelope(f) else {
            continue;
        };
        if env.class == Class::Control || env.name.is_control() {
            continue;
        }
        let t = match time_base {
            TimeBase::Envelope => env.timestamp_ns,
            TimeBase::Central => record.at_ns,
        };
        start = start.min(t);
        if f.direction != Direction::In {
            continue;
        }
        match (env.class, env.name.as_str()) {
            (Class::Reply, "acquireImage") => match decode_data::<RangeImage>(&env.data) {
                Ok(image) => images.push((t, image)),
                Err(e) => tracing::warn!(error = %e, "an acquireImage reply does not decode"),
            },
            (Class::Inform, "stepPlanned") => {
                if let Ok(s) = decode_data::<StepPlanned>(&env.data) {
                    planned.push((t, s.footfall));
                }
            }
            (Class::Goal, "recoverLeg") => {
                if let Ok(r) = decode_data::<RecoverLeg>(&env.data) {
                    recover.push((t, r.footfall));
                }
            }
            _ => {}
        }
    }
    RecordedWalk {
        images: timed(images, start),
        footfalls: timed(if planned.is_empty() { recover } else { planned }, start),
    }
}

fn timed<T>(values: Vec<(u64, T)>, start_ns: u64) -> Vec<Timed<T>> {
    values
        .into_iter()
        .map(|(t, value)| Timed {
            at_s: t.saturating_sub(start_ns) as f64 / 1e9,
            value,
        })
        .collect()
}

/// Rebuilds the LTM Manager's map from `images` (each merged as the LTM Manager merges it).
/// Images that do not build (refused by the builder) are skipped with a warning; returns the
/// map and the number of images merged.
pub fn rebuild(images: &[RangeImage]) -> anyhow::Result<(LocalTerrainMap, usize)> {
    let sensor = images
        .first()
        .map_or(LtmConfig::default().sensor, |i| i.sensor);
    let mut map = LocalTerrainMap::new(LtmConfig {
        sensor,
        ..LtmConfig::default()
    })
    .context("cannot start a terrain map")?;
    let mut merged = 0;
    for image in images {
        match map.add_image(image) {
            Ok(_) => merged += 1,
            Err(e) => {
                tracing::warn!(sequence = image.sequence, error = %e, "image skipped");
            }
        }
    }
    Ok((map, merged))
}

/// Draws the map of `request` from the log at `log_path` to `out`.
pub fn map_from_log(
    log_path: &Path,
    request: &MapRequest,
    options: &LogMapOptions,
    out: &Path,
) -> anyhow::Result<MapPicture> {
    if let Some(t) = options.at_s
        && !(t.is_finite() && t >= 0.0)
    {
        bail!("--at must be a number of seconds from the start of the log, at least 0; got {t}");
    }
    let log =
        LogFile::open(log_path).map_err(|e| anyhow::anyhow!("cannot read the traffic log {e}"))?;
    if let Some(t) = &log.truncated {
        tracing::warn!("{t}");
    }
    let walk = read_walk(&log, options.time_base);
    let (Some(first), Some(last)) = (walk.images.first(), walk.images.last()) else {
        bail!(
            "the log {} holds no range images (no acquireImage replies from the ISM); give the \
             traffic log of a walk, e.g. DIR/traffic.mcap after `tca walk --out DIR`",
            log_path.display()
        );
    };
    let limit = options.at_s.unwrap_or(f64::INFINITY);
    let images: Vec<RangeImage> = walk
        .images
        .iter()
        .filter(|i| i.at_s <= limit)
        .map(|i| i.value.clone())
        .collect();
    if images.is_empty() {
        bail!(
            "no range image was taken in the first {limit} s of the log; its {} images were \
             taken from {:.3} s to {:.3} s: give a later --at",
            walk.images.len(),
            first.at_s,
            last.at_s
        );
    }
    let (mut map, merged) = rebuild(&images)?;
    if merged == 0 {
        bail!(
            "none of the {} range images in the log could be made into a map (see the warnings \
             with TCA_LOG=warn)",
            images.len()
        );
    }
    let polygon = match &request.area {
        MapArea::Polygon(p) => p.clone(),
        MapArea::Mapped => {
            let Some((lo, hi)) = map.mapped_extent()? else {
                bail!(
                    "the {merged} range images in the log show no terrain, so there is no \
                     mapped area to draw"
                );
            };
            // Through the outermost cells' centres; a single row or column is widened a
            // little so that it still encloses an area.
            let pad = |a: f64, b: f64| {
                if a < b {
                    0.0
                } else {
                    0.25 * request.resolution_m
                }
            };
            let (px, py) = (pad(lo.x, hi.x), pad(lo.y, hi.y));
            let corners = rectangle(lo.x - px, lo.y - py, hi.x + px, hi.y + py);
            check_region(&corners, request.resolution_m)
                .context("the whole mapped area cannot be drawn at this resolution")?;
            corners
        }
    };
    let grid = map
        .query(&MapRegion {
            kind: request.kind,
            polygon,
            resolution_m: request.resolution_m,
            refresh: false,
        })
        .context("the map of the region cannot be made")?;
    let overlays: Vec<Overlay> = if options.overlay_footfalls {
        walk.footfalls
            .iter()
            .filter(|f| f.at_s <= limit)
            .enumerate()
            .map(|(n, f)| Overlay::Point {
                at: f.value,
                label: format!("{}", n + 1),
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut picture = draw(&grid, &overlays, out)?;
    picture.images = Some(merged);
    picture.at_s = options.at_s;
    Ok(picture)
}
