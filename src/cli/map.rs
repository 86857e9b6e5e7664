//! `tca map`: a picture of a terrain map, from a running system or a traffic log.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use tca_logs::TimeBase;
use tca_map_view::{
    DEFAULT_RESOLUTION_M, LiveMapOptions, LogMapOptions, MapArea, MapRequest, parse_kind,
    parse_polygon, parse_rectangle,
};
use tca_module::Connector;

use super::ConnectArgs;

#[derive(Debug, Args)]
#[command(
    after_help = "Without --log the map comes from the running system behind central at \
--connect (default tcp/127.0.0.1:7447, as `tca up walk.toml` starts it). Without --region or \
--polygon the picture shows the whole mapped area.

Examples:
  tca map --log out/walk/traffic.mcap -o map.png
  tca map --log out/walk/traffic.mcap --kind footfall --region 2,1,6,5 --overlay-footfalls -o f.png
  tca map --log out/walk/traffic.mcap --at 120 -o two-minutes-in.png
  tca map --connect tcp/127.0.0.1:7447 --kind slope --polygon \"2,2 5,2 5,6\" -o slope.png"
)]
pub(crate) struct MapArgs {
    #[command(flatten)]
    connect: ConnectArgs,
    /// Build the map from the range images in this traffic log (e.g. DIR/traffic.mcap of
    /// `tca walk --out DIR`) instead of asking a running system.
    #[arg(long, value_name = "FILE.mcap", conflicts_with = "connect")]
    log: Option<PathBuf>,
    /// The map kind: elevation, uncertainty (elevation standard deviation), footfall
    /// (footfall evaluation) or slope.
    #[arg(long, default_value = "elevation", value_name = "KIND")]
    kind: String,
    /// A rectangle by two opposite corners, metres (world frame).
    #[arg(
        long,
        value_name = "x0,y0,x1,y1",
        conflicts_with = "polygon",
        allow_hyphen_values = true
    )]
    region: Option<String>,
    /// A polygon of at least three corners, metres (world frame); the picture is its
    /// enclosing rectangle with the cells outside it unknown.
    #[arg(long, value_name = "\"x,y x,y x,y ...\"", allow_hyphen_values = true)]
    polygon: Option<String>,
    /// Cell size, metres.
    #[arg(long, value_name = "M", default_value_t = DEFAULT_RESOLUTION_M, allow_negative_numbers = true)]
    resolution: f64,
    /// With --log: the map as it stood this many seconds after the log's start (simulated
    /// seconds of the walk; central's clock with --central-clock).
    #[arg(
        long,
        value_name = "SECONDS",
        requires = "log",
        allow_negative_numbers = true
    )]
    at: Option<f64>,
    /// With --log: count --at on central's clock instead of the messages' timestamps.
    #[arg(long, requires = "log")]
    central_clock: bool,
    /// With --log: draw the footfalls the Gait Planner chose (up to --at), numbered.
    #[arg(long, requires = "log")]
    overlay_footfalls: bool,
    /// With a running system: have the LTM Manager take a fresh image first.
    #[arg(long, conflicts_with = "log")]
    refresh: bool,
    /// With a running system: have its PDM draw the picture (renderMap; it writes the file
    /// itself, so OUT must be a path that process can write).
    #[arg(long, conflicts_with = "log")]
    pdm: bool,
    /// With a running system: longest wait for each answer, seconds.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 30.0,
        conflicts_with = "log"
    )]
    timeout: f64,
    /// The PNG file to write.
    #[arg(short = 'o', long = "out", value_name = "OUT.png")]
    out: PathBuf,
    /// Print what was drawn as one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

pub(crate) async fn run(args: MapArgs) -> anyhow::Result<ExitCode> {
    let kind = parse_kind(&args.kind)?;
    let area = match (&args.region, &args.polygon) {
        (Some(r), _) => MapArea::Polygon(parse_rectangle(r)?),
        (None, Some(p)) => MapArea::Polygon(parse_polygon(p)?),
        (None, None) => MapArea::Mapped,
    };
    let request = MapRequest::new(kind, area, args.resolution)?;
    let picture = match &args.log {
        Some(log) => {
            let options = LogMapOptions {
                at_s: args.at,
                time_base: if args.central_clock {
                    TimeBase::Central
                } else {
                    TimeBase::Envelope
                },
                overlay_footfalls: args.overlay_footfalls,
            };
            let (log, out) = (log.clone(), args.out.clone());
            tokio::task::spawn_blocking(move || {
                tca_map_view::map_from_log(&log, &request, &options, &out)
            })
            .await??
        }
        None => {
            if !(args.timeout.is_finite() && args.timeout > 0.0) {
                anyhow::bail!(
                    "--timeout must be a number of seconds above zero, got {}",
                    args.timeout
                );
            }
            let options = LiveMapOptions {
                refresh: args.refresh,
                via_pdm: args.pdm,
                timeout: Duration::from_secs_f64(args.timeout.min(86_400.0)),
            };
            let connector = Connector::zenoh(args.connect.endpoint_or_default());
            tca_map_view::map_from_system(&connector, &request, &options, &args.out).await?
        }
    };
    eprintln!("{}", picture.summary());
    if args.json {
        println!("{}", serde_json::to_string(&picture)?);
    }
    Ok(ExitCode::SUCCESS)
}
