//! The live view: a Foxglove WebSocket server (the SDK's) publishing the traffic channels and
//! the well-known channels of messages as they are tapped from central.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use foxglove::messages::{FrameTransforms, Grid, Log, RawImage, SceneUpdate};
use foxglove::{ChannelBuilder, Context, Encode, RawChannel, Schema, WebSocketServer};
use serde_json::json;
use tca_messages::Envelope;

use crate::error::{FoxgloveError, Result};
use crate::export::robot_description_schema;
use crate::traffic::{FormatTable, data_json, message_json, topic, topic_schema};
use crate::wellknown::{WellKnown, WellKnownState};

/// A running live view: feed it every tapped message with [`LiveView::publish`].
pub struct LiveView {
    context: Arc<Context>,
    server: Option<foxglove::WebSocketServerHandle>,
    channels: HashMap<String, Arc<RawChannel>>,
    formats: FormatTable,
    state: WellKnownState,
    latched: Latched,
}

/// The last message of each topic that is sent once and must reach clients that subscribe
/// later (the robot's description), with its channel.
type Latched = Arc<Mutex<HashMap<String, (Arc<RawChannel>, Vec<u8>)>>>;

/// Sends a latched topic's last message again when a client subscribes to it.
struct Latch(Latched);

impl foxglove::websocket::ServerListener for Latch {
    fn on_subscribe(
        &self,
        _client: foxglove::websocket::Client,
        channel: foxglove::websocket::ChannelView<'_>,
    ) {
        let last = self
            .0
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get(channel.topic())
            .cloned();
        if let Some((c, bytes)) = last {
            c.log(&bytes);
        }
    }
}

impl LiveView {
    /// Starts the server on `host:port` (port 0: any free port); must run inside a tokio
    /// runtime.
    pub async fn start(host: &str, port: u16) -> Result<Self> {
        let context = Context::new();
        let latched = Latched::default();
        let server = WebSocketServer::new()
            .name("tca")
            .bind(host, port)
            .context(&context)
            .listener(Arc::new(Latch(latched.clone())))
            .start()
            .await
            .map_err(|e| FoxgloveError::Server(e.to_string()))?;
        Ok(Self {
            context,
            server: Some(server),
            channels: HashMap::new(),
            formats: FormatTable::new(),
            state: WellKnownState::new(),
            latched,
        })
    }

    /// The port the server listens on.
    pub fn port(&self) -> u16 {
        self.server.as_ref().map(|s| s.port()).unwrap_or_default()
    }

    /// Sets the registered formats (from central's registry); channels already advertised
    /// keep their schema.
    pub fn set_formats(&mut self, formats: FormatTable) {
        self.formats = formats;
    }

    /// Whether `name` has formats known.
    pub fn knows(&self, name: &str) -> bool {
        self.formats.keys().any(|n| n.as_str() == name)
    }

    fn channel(
        &mut self,
        topic: &str,
        schema: impl FnOnce() -> Option<Schema>,
        encoding: &str,
    ) -> Result<Arc<RawChannel>> {
        if let Some(c) = self.channels.get(topic) {
            return Ok(c.clone());
        }
        let c = ChannelBuilder::new(topic)
            .context(&self.context)
            .message_encoding(encoding)
            .schema(schema())
            .build_raw()
            .map_err(|e| FoxgloveError::Server(e.to_string()))?;
        self.channels.insert(topic.to_owned(), c.clone());
        Ok(c)
    }

    fn encoded<T: Encode>(&mut self, topic: &str, msg: &T) -> Result<()> {
        let c = self.channel(topic, T::get_schema, &T::get_message_encoding())?;
        let mut buf = Vec::new();
        msg.encode(&mut buf)
            .map_err(|e| FoxgloveError::Write(e.to_string()))?;
        c.log(&buf);
        Ok(())
    }

    /// Publishes one message a module sent at `at_ns` (nanoseconds since the UNIX epoch): on
    /// its traffic channel when its data decodes, and as the well-known messages it makes.
    pub fn publish(&mut self, envelope: &Envelope, at_ns: u64) -> Result<()> {
        let Some(topic) = topic(envelope.name.as_str(), envelope.class) else {
            return Ok(());
        };
        if let Ok(data) = data_json(envelope, &self.formats) {
            let formats = &self.formats;
            let schema =
                topic_schema(&topic, envelope.name.as_str(), envelope.class, formats).map(|s| {
                    Schema::new(
                        format!("tca.{topic}"),
                        "jsonschema",
                        s.to_string().into_bytes(),
                    )
                });
            let c = self.channel(&topic, || schema, "json")?;
            let bytes = serde_json::to_vec(&message_json(envelope, data))
                .map_err(|e| FoxgloveError::Write(e.to_string()))?;
            c.log(&bytes);
        }
        for w in self.state.feed(envelope, at_ns) {
            let topic = w.topic().to_owned();
            match &w {
                WellKnown::Transforms(m) => self.encoded::<FrameTransforms>(&topic, m)?,
                WellKnown::Grid { grid, .. } => self.encoded::<Grid>(&topic, grid)?,
                WellKnown::Scene(m) => self.encoded::<SceneUpdate>(&topic, m)?,
                WellKnown::Image { image, .. } => self.encoded::<RawImage>(&topic, image)?,
                WellKnown::Log(m) => self.encoded::<Log>(&topic, m)?,
                WellKnown::RobotDescription(urdf) => {
                    let c = self.channel(
                        &topic,
                        || {
                            Some(Schema::new(
                                "tca.RobotDescription",
                                "jsonschema",
                                robot_description_schema().to_string().into_bytes(),
                            ))
                        },
                        "json",
                    )?;
                    let bytes = json!({ "data": urdf }).to_string().into_bytes();
                    c.log(&bytes);
                    // Sent once per walk: kept for clients that subscribe later.
                    self.latched
                        .lock()
                        .unwrap_or_else(|p| p.into_inner())
                        .insert(topic, (c, bytes));
                }
            }
        }
        Ok(())
    }

    /// Stops the server.
    pub async fn stop(mut self) {
        if let Some(s) = self.server.take() {
            s.stop().wait().await;
        }
    }
}
