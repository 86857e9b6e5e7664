//! The zenoh transport: what runs across processes and machines.
//!
//! Central opens a zenoh session in *router* mode listening on its endpoints
//! (`tcp/127.0.0.1:7447` by default); each module opens a *client* session connected to it.
//! A module's link is named by its zenoh session id `<zid>`:
//!
//! - the module publishes frames on `tca/up/<zid>`; central subscribes to `tca/up/*`;
//! - central publishes frames for it on `tca/down/<zid>`; the module subscribes there;
//! - the module holds the liveliness token `tca/alive/<zid>`; when its session ends (it
//!   leaves, crashes or the network drops) zenoh withdraws the token and central closes the
//!   link.
//!
//! Publications are reliable with blocking congestion control (no frame is silently dropped)
//! and express (sent at once, not batched), and multicast scouting is off: modules find central
//! by its endpoint only.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bytes::Bytes;
use tokio::sync::mpsc;
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

use crate::core::{Event, LinkId};
use crate::runtime::{CentralHandle, Input};
use crate::{CentralError, Result};

/// Central's default zenoh endpoint.
pub const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// Key on which a module publishes its frames.
pub fn up_key(zid: &str) -> String {
    format!("tca/up/{zid}")
}

/// Key on which central publishes a module's frames.
pub fn down_key(zid: &str) -> String {
    format!("tca/down/{zid}")
}

/// A module's liveliness token.
pub fn alive_key(zid: &str) -> String {
    format!("tca/alive/{zid}")
}

fn endpoints_json(endpoints: &[String]) -> Result<String> {
    for e in endpoints {
        if !e.contains('/') {
            return Err(CentralError::Zenoh(format!(
                "endpoint {e:?} has no protocol; write it like tcp/127.0.0.1:7447"
            )));
        }
    }
    serde_json::to_string(endpoints).map_err(|e| CentralError::Zenoh(e.to_string()))
}

fn base_config(mode: &str) -> Result<zenoh::Config> {
    let mut config = zenoh::Config::default();
    let set = |c: &mut zenoh::Config, k: &str, v: &str| {
        c.insert_json5(k, v)
            .map_err(|e| CentralError::Zenoh(format!("config {k}: {e}")))
    };
    set(&mut config, "mode", &format!("{mode:?}"))?;
    set(&mut config, "scouting/multicast/enabled", "false")?;
    set(&mut config, "scouting/gossip/enabled", "false")?;
    Ok(config)
}

/// zenoh configuration of central: a router listening on `listen`.
pub fn router_config(listen: &[String]) -> Result<zenoh::Config> {
    let mut config = base_config("router")?;
    config
        .insert_json5("listen/endpoints", &endpoints_json(listen)?)
        .map_err(|e| CentralError::Zenoh(format!("listen endpoints: {e}")))?;
    Ok(config)
}

/// zenoh configuration of a module: a client connecting to `connect`.
pub fn client_config(connect: &[String]) -> Result<zenoh::Config> {
    let mut config = base_config("client")?;
    config
        .insert_json5("connect/endpoints", &endpoints_json(connect)?)
        .map_err(|e| CentralError::Zenoh(format!("connect endpoints: {e}")))?;
    // Do not listen for peers: a module only talks to central.
    config
        .insert_json5("listen/endpoints", "[]")
        .map_err(|e| CentralError::Zenoh(format!("listen endpoints: {e}")))?;
    Ok(config)
}

/// Links known to the zenoh side, by session id.
struct LinkTable {
    by_zid: HashMap<String, LinkId>,
}

/// Central's zenoh router and the subscriptions that feed the driver.
pub(crate) struct ZenohCentral {
    session: zenoh::Session,
    endpoints: Vec<String>,
    _frames: zenoh::pubsub::Subscriber<()>,
    _alive: zenoh::pubsub::Subscriber<()>,
}

impl ZenohCentral {
    pub(crate) async fn start(listen: &[String], handle: CentralHandle) -> Result<Self> {
        let session = zenoh::open(router_config(listen)?)
            .await
            .map_err(|e| CentralError::Zenoh(format!("cannot listen on {listen:?}: {e}")))?;
        let table = Arc::new(Mutex::new(LinkTable {
            by_zid: HashMap::new(),
        }));
        let runtime = tokio::runtime::Handle::current();

        let open = {
            let table = table.clone();
            let handle = handle.clone();
            let session = session.clone();
            let runtime = runtime.clone();
            move |zid: &str| -> LinkId {
                let mut t = table.lock().unwrap_or_else(|p| p.into_inner());
                if let Some(&link) = t.by_zid.get(zid) {
                    return link;
                }
                let link = handle.allocate_link();
                t.by_zid.insert(zid.to_owned(), link);
                let (sink, mut rx) = mpsc::unbounded_channel::<Bytes>();
                let _ = handle.input().send(Input::Attach(link, sink));
                let _ = handle.input().send(Input::Event(Event::Opened(link)));
                let key = down_key(zid);
                let session = session.clone();
                runtime.spawn(async move {
                    let publisher = match session
                        .declare_publisher(key.clone())
                        .congestion_control(CongestionControl::Block)
                        .express(true)
                        .await
                    {
                        Ok(p) => p,
                        Err(e) => {
                            tracing::error!(%key, error = %e, "cannot publish to module");
                            return;
                        }
                    };
                    while let Some(frame) = rx.recv().await {
                        if let Err(e) = publisher.put(frame).await {
                            tracing::warn!(%key, error = %e, "publish to module failed");
                        }
                    }
                });
                link
            }
        };

        let frames = {
            let open = open.clone();
            let handle = handle.clone();
            session
                .declare_subscriber("tca/up/*")
                .callback(move |sample| {
                    let Some(zid) = sample.key_expr().as_str().rsplit('/').next() else {
                        return;
                    };
                    let link = open(zid);
                    let frame = Bytes::from(sample.payload().to_bytes().into_owned());
                    let _ = handle.input().send(Input::Event(Event::Frame(link, frame)));
                })
                .await
                .map_err(|e| CentralError::Zenoh(e.to_string()))?
        };

        let alive = {
            let handle = handle.clone();
            let table = table.clone();
            session
                .liveliness()
                .declare_subscriber("tca/alive/*")
                .history(true)
                .callback(move |sample| {
                    let Some(zid) = sample.key_expr().as_str().rsplit('/').next() else {
                        return;
                    };
                    match sample.kind() {
                        SampleKind::Put => {
                            open(zid);
                        }
                        SampleKind::Delete => {
                            let link = table
                                .lock()
                                .unwrap_or_else(|p| p.into_inner())
                                .by_zid
                                .remove(zid);
                            if let Some(link) = link {
                                let _ = handle.input().send(Input::Event(Event::Closed(link)));
                            }
                        }
                    }
                })
                .await
                .map_err(|e| CentralError::Zenoh(e.to_string()))?
        };
        tracing::info!(endpoints = ?listen, "central listening over zenoh");
        Ok(ZenohCentral {
            session,
            endpoints: listen.to_vec(),
            _frames: frames,
            _alive: alive,
        })
    }

    pub(crate) fn endpoints(&self) -> &[String] {
        &self.endpoints
    }

    pub(crate) async fn close(self) {
        let _ = self.session.close().await;
    }
}
