//! The Foxglove export of a log: its traffic channels carry JSON schemas from the registered
//! formats and JSON that matches them, and the walking traffic becomes Foxglove's well-known
//! messages with their protobuf schemas; read back with the `mcap` crate.

use std::collections::HashMap;

use bytes::Bytes;
use foxglove::Decode;
use foxglove::messages::{FrameTransforms, Grid, Log, RawImage, SceneUpdate};
use tca_legged_messages as legged;
use tca_logs::*;
use tca_messages::control::Registration;
use tca_messages::*;
use tca_single_leg_messages as leg;

struct Builder {
    records: Vec<LogRecord>,
    seq: u32,
    at: u64,
}

impl Builder {
    fn register<M: Message>(&mut self, module: &str) {
        self.at += 1_000;
        self.records.push(LogRecord {
            at_ns: self.at,
            kind: RecordKind::Registered(RegisteredRecord {
                module: ModuleName::new(module).unwrap(),
                registration: Registration {
                    name: MessageName::new(M::NAME).unwrap(),
                    class: class_of::<M>(),
                    format: M::format().unwrap(),
                    reply: M::reply_format().unwrap(),
                    replace: false,
                },
            }),
        });
    }

    /// A frame a module sent (`In`), and central's copy to its receiver (`Out`).
    fn send<T: serde::Serialize>(
        &mut self,
        sender: &str,
        name: &str,
        class: Class,
        data: &T,
        correlation: Option<MessageId>,
    ) -> MessageId {
        self.seq += 1;
        self.at += 1_000_000;
        let id = MessageId::new(3, self.seq);
        let envelope = Envelope {
            id,
            class,
            name: MessageName::new(name).unwrap(),
            sender: ModuleName::new(sender).unwrap(),
            context: None,
            node: None,
            correlation,
            cause: None,
            timestamp_ns: self.at,
            options: SendOptions::default(),
            redelivery: 0,
            data: encode_data(data).unwrap(),
        };
        for direction in [Direction::In, Direction::Out] {
            self.records.push(LogRecord {
                at_ns: self.at,
                kind: RecordKind::Frame(FrameRecord {
                    direction,
                    link: 1,
                    peer: Some(ModuleName::new("controller").unwrap()),
                    name: envelope.name.clone(),
                    class,
                    frame: Bytes::from(encode(&envelope).unwrap()),
                }),
            });
        }
        id
    }
}

fn map() -> leg::MapGrid {
    leg::MapGrid {
        kind: leg::MapKind::Elevation,
        origin_x_m: 1.0,
        origin_y_m: 2.0,
        resolution_m: 0.5,
        nx: 3,
        ny: 2,
        cells: vec![
            leg::MapCell::Known {
                value: 0.25,
                sigma_m: 0.01,
            },
            leg::MapCell::Unknown,
            leg::MapCell::Occluded {
                max_elevation_m: 0.7,
            },
            leg::MapCell::Known {
                value: -0.5,
                sigma_m: 0.02,
            },
            leg::MapCell::Unknown,
            leg::MapCell::Unknown,
        ],
    }
}

fn write_log(path: &std::path::Path) {
    let mut b = Builder {
        records: Vec::new(),
        seq: 0,
        at: 1_700_000_000_000_000_000,
    };
    b.register::<leg::MapRegion>("ltm");
    b.register::<leg::AcquireImage>("ism");
    b.register::<legged::RobotModel>("controller");
    b.register::<legged::SupportState>("controller");
    b.register::<legged::LegMove>("controller");
    b.register::<legged::TipOver>("walker");
    let q = b.send(
        "walker",
        "mapRegion",
        Class::Query,
        &leg::MapRegion {
            kind: leg::MapKind::Elevation,
            polygon: vec![
                leg::PlanePoint { x_m: 0.0, y_m: 0.0 },
                leg::PlanePoint { x_m: 1.0, y_m: 0.0 },
                leg::PlanePoint { x_m: 1.0, y_m: 1.0 },
            ],
            resolution_m: 0.5,
            refresh: false,
        },
        None,
    );
    b.send("ltm", "mapRegion", Class::Reply, &map(), Some(q));
    let q = b.send(
        "walker",
        "acquireImage",
        Class::Query,
        &leg::AcquireImage {
            sensor: leg::SensorKind::Erim,
        },
        None,
    );
    let identity = leg::Transform {
        m: [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ],
    };
    let mut body_from_global = identity;
    body_from_global.m[3] = -4.0; // the body 4 m east of the world origin
    b.send(
        "ism",
        "acquireImage",
        Class::Reply,
        &leg::RangeImage {
            sensor: leg::SensorKind::Erim,
            width: 2,
            height: 2,
            range_counts: vec![1, 2, 3, 65535],
            reflectance: vec![9, 9, 9, 9],
            range_resolution_m: 0.08,
            ambiguity_m: 20.0,
            azimuth_fov_rad: 1.0,
            elevation_fov_rad: 0.5,
            locus_from_scanner: identity,
            scanner_from_body: identity,
            body_from_global,
            sequence: 1,
        },
        Some(q),
    );
    let robot = tca_legged_model::builtin::BUILTIN_ROBOTS
        .iter()
        .find(|r| r.name == "hexapod")
        .unwrap();
    let model = tca_legged_model::RobotModel::from_urdf_str(robot.urdf).unwrap();
    let q = b.send(
        "walker",
        "legged.robotModel",
        Class::Query,
        &legged::RobotModel,
        None,
    );
    b.send(
        "controller",
        "legged.robotModel",
        Class::Reply,
        &legged::RobotDescription {
            name: "hexapod".into(),
            urdf: robot.urdf.into(),
            legs: model.legs().iter().map(|l| l.name().to_owned()).collect(),
        },
        Some(q),
    );
    let feet: Vec<legged::FootState> = [(0.2, 0.2), (0.2, -0.2), (-0.2, -0.2), (-0.2, 0.2)]
        .iter()
        .enumerate()
        .map(|(i, (x, y))| legged::FootState {
            leg: format!("leg{i}"),
            at: legged::WorldPoint {
                x_m: *x,
                y_m: *y,
                z_m: 0.0,
            },
            stance: i < 3,
        })
        .collect();
    b.send(
        "controller",
        "legged.supportState",
        Class::Inform,
        &legged::SupportState {
            t_s: 1.0,
            body: legged::Pose {
                x_m: 1.0,
                y_m: 2.0,
                z_m: 0.1,
                roll_rad: 0.0,
                pitch_rad: 0.0,
                yaw_rad: 0.5,
            },
            com: legged::WorldPoint {
                x_m: 0.05,
                y_m: 0.0,
                z_m: 0.1,
            },
            feet,
            margin_m: 0.04,
        },
        None,
    );
    let first = &model.legs()[0];
    let mut target = first.neutral();
    target[0] += 0.2;
    let m = b.send(
        "walker",
        "legged.legMove",
        Class::Command,
        &legged::LegMove {
            leg: first.name().to_owned(),
            waypoints: vec![first.neutral(), target.clone()],
            transition: false,
        },
        None,
    );
    b.send("controller", "legged.legMove", Class::Success, &(), Some(m));
    b.send(
        "controller",
        "legged.tipOver",
        Class::Exception,
        &legged::TipOver {
            com: legged::WorldPoint {
                x_m: 0.0,
                y_m: 0.0,
                z_m: 0.0,
            },
            margin_m: -0.01,
            standing: vec![],
            detail: "the centre of mass left the polygon".into(),
        },
        None,
    );
    let mut w = LogWriter::create(path).unwrap();
    for r in &b.records {
        w.append(r).unwrap();
    }
    w.finish().unwrap();
}

struct Read {
    /// topic -> (schema name, schema encoding, schema data, message encoding)
    channels: HashMap<String, (String, String, Vec<u8>, String)>,
    messages: HashMap<String, Vec<Vec<u8>>>,
}

fn read(path: &std::path::Path) -> Read {
    let bytes = std::fs::read(path).unwrap();
    let mut out = Read {
        channels: HashMap::new(),
        messages: HashMap::new(),
    };
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let topic = m.channel.topic.clone();
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        out.channels.insert(
            topic.clone(),
            (
                schema.name.clone(),
                schema.encoding.clone(),
                schema.data.to_vec(),
                m.channel.message_encoding.clone(),
            ),
        );
        out.messages.entry(topic).or_default().push(m.data.to_vec());
    }
    out
}

fn export() -> (ExportSummaryHolder, Read) {
    let dir = tempfile::tempdir().unwrap();
    let log_path = dir.path().join("traffic.mcap");
    write_log(&log_path);
    let log = LogFile::open(&log_path).unwrap();
    let out = dir.path().join("foxglove.mcap");
    let summary = tca_foxglove::export_foxglove(&log, &out).unwrap();
    (ExportSummaryHolder(summary), read(&out))
}

struct ExportSummaryHolder(tca_foxglove::ExportSummary);

#[test]
fn traffic_channels_carry_schemas_from_the_registered_formats() {
    let (summary, r) = export();
    assert_eq!(summary.0.undecoded, 0);
    let (name, enc, data, msg_enc) = &r.channels["mapRegion/reply"];
    assert_eq!(
        (name.as_str(), enc.as_str(), msg_enc.as_str()),
        ("tca.mapRegion/reply", "jsonschema", "json")
    );
    let schema: serde_json::Value = serde_json::from_slice(data).unwrap();
    let data_schema = &schema["properties"]["data"];
    assert_eq!(data_schema["title"], "MapGrid");
    assert_eq!(
        data_schema["properties"]["nx"]["type"], "integer",
        "{data_schema}"
    );
    // Cells are an enum: unit variants as strings, others as one-key objects.
    let cell = &data_schema["properties"]["cells"]["items"]["oneOf"];
    assert_eq!(cell[0]["const"], "Unknown");
    assert_eq!(cell[2]["required"][0], "Known");
    // The message is the decoded reply, one per frame sent (central's copies left out).
    let msgs = &r.messages["mapRegion/reply"];
    assert_eq!(msgs.len(), 1);
    let m: serde_json::Value = serde_json::from_slice(&msgs[0]).unwrap();
    assert_eq!(m["class"], "reply");
    assert_eq!(m["sender"], "ltm");
    assert_eq!(m["data"]["cells"][1], "Unknown");
    assert_eq!(m["data"]["cells"][0]["Known"]["value"], 0.25);
    // The query on its own channel, the success on the outcome channel.
    assert_eq!(r.messages["mapRegion"].len(), 1);
    assert_eq!(r.messages["legged.legMove/outcome"].len(), 1);
    assert_eq!(r.channels["legged.legMove"].0, "tca.legged.legMove");
}

#[test]
fn terrain_maps_become_foxglove_grids() {
    let (_, r) = export();
    let (name, enc, _, msg_enc) = &r.channels["/map/elevation"];
    assert_eq!(
        (name.as_str(), enc.as_str(), msg_enc.as_str()),
        ("foxglove.Grid", "protobuf", "protobuf")
    );
    let g = Grid::decode(&r.messages["/map/elevation"][0][..]).unwrap();
    assert_eq!(g.column_count, 3);
    assert_eq!(g.cell_stride, 12);
    assert_eq!(g.data.len(), 6 * 12);
    let p = g.pose.unwrap().position.unwrap();
    // Cell (0, 0) is centred at the map's origin: the grid's corner is half a cell off.
    assert_eq!((p.x, p.y), (0.75, 1.75));
    let f32_at = |i: usize| f32::from_le_bytes(g.data[i..i + 4].try_into().unwrap());
    assert_eq!(f32_at(0), 0.25);
    assert!(f32_at(12).is_nan(), "an unknown cell has no value");
    assert_eq!(f32_at(2 * 12 + 8), 0.7, "an occluded cell's bound");
    assert_eq!(f32_at(3 * 12), -0.5, "row 1 starts at cell 3");
}

#[test]
fn frames_urdf_scene_images_and_log_are_well_known_messages() {
    let (_, r) = export();
    // The URDF on its topic for the 3D panel.
    let d: serde_json::Value =
        serde_json::from_slice(&r.messages["/robot_description"][0]).unwrap();
    assert!(d["data"].as_str().unwrap().contains("<robot"));
    // Transforms: the scanner, the hexapod's links (at the robot model, and again when the
    // leg move succeeded), the body.
    assert_eq!(r.channels["/tf"].0, "foxglove.FrameTransforms");
    let tfs: Vec<FrameTransforms> = r.messages["/tf"]
        .iter()
        .map(|m| FrameTransforms::decode(&m[..]).unwrap())
        .collect();
    let all: Vec<_> = tfs.iter().flat_map(|t| t.transforms.iter()).collect();
    let scanner = all.iter().find(|t| t.child_frame_id == "scanner").unwrap();
    assert_eq!(scanner.translation.as_ref().unwrap().x, 4.0);
    let body = all
        .iter()
        .find(|t| t.parent_frame_id == "world" && t.child_frame_id != "scanner")
        .unwrap();
    assert_eq!(body.translation.as_ref().unwrap().y, 2.0);
    let links: Vec<_> = all
        .iter()
        .filter(|t| t.parent_frame_id == body.child_frame_id)
        .collect();
    assert!(
        links.len() >= 18,
        "six legs of three links: {}",
        links.len()
    );
    // The leg move's success moved its leg's links: some link's transform changed.
    let first_links = &tfs[1].transforms;
    let last_links = &tfs.last().unwrap().transforms;
    assert_eq!(first_links.len(), last_links.len());
    assert!(
        first_links
            .iter()
            .zip(last_links)
            .any(|(a, b)| a.rotation != b.rotation)
    );
    // Scene: feet, the support polygon of the three standing feet, centre of mass, leg path.
    let scenes: Vec<SceneUpdate> = r.messages["/plan"]
        .iter()
        .map(|m| SceneUpdate::decode(&m[..]).unwrap())
        .collect();
    let entities: Vec<_> = scenes.iter().flat_map(|s| s.entities.iter()).collect();
    let polygon = entities.iter().find(|e| e.id == "support_polygon").unwrap();
    assert_eq!(polygon.lines[0].points.len(), 3);
    assert_eq!(
        entities
            .iter()
            .find(|e| e.id == "feet")
            .unwrap()
            .spheres
            .len(),
        4
    );
    let path = entities
        .iter()
        .find(|e| e.id.starts_with("leg_path/"))
        .unwrap();
    assert_eq!(path.lines[0].points.len(), 2);
    // Range and reflectance images.
    let img = RawImage::decode(&r.messages["/scanner/range"][0][..]).unwrap();
    assert_eq!(
        (img.width, img.height, img.step, img.encoding.as_str()),
        (2, 2, 4, "mono16")
    );
    assert_eq!(&img.data[6..8], &[0xff, 0xff]);
    assert_eq!(r.messages["/scanner/reflectance"].len(), 1);
    // The tip-over as an error line.
    let logs: Vec<Log> = r.messages["/log"]
        .iter()
        .map(|m| Log::decode(&m[..]).unwrap())
        .collect();
    let tip = logs
        .iter()
        .find(|l| l.message.contains("tipped over"))
        .unwrap();
    assert_eq!(tip.level, foxglove::messages::log::Level::Error as i32);
    assert_eq!(tip.name, "controller");
}
