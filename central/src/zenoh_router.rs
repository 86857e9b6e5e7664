//! Central's side of the zenoh transport: a zenoh router whose subscriptions feed the driver.
//!
//! Frames a module publishes on its up key go to its link's bounded inbox; one arriving at a
//! full inbox is answered with an over-limit error instead of being routed. A module's
//! liveliness token opens its link (if its first frame has not already) and closes it when
//! withdrawn. Central's own token is declared last, so a module that sees it can say hello at
//! once. The key scheme and the router's configuration are `tca_link::zenoh`'s.

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex};

use bytes::Bytes;
use tca_link::Inbox;
use tca_link::zenoh::{
    ALIVE_KEY_PATTERN, CENTRAL_ALIVE_KEY, UP_KEY_PATTERN, down_key, router_config_with_users,
    zid_of,
};
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

use crate::core::{Event, LinkId};
use crate::runtime::{CentralHandle, Input};
use crate::{CentralError, Result};

/// Links known to the zenoh side, by session id.
struct LinkTable {
    by_zid: HashMap<String, (LinkId, Arc<Inbox>)>,
}

/// Central's zenoh router and the subscriptions that feed the driver.
pub(crate) struct ZenohCentral {
    session: zenoh::Session,
    endpoints: Vec<String>,
    _frames: zenoh::pubsub::Subscriber<()>,
    _alive: zenoh::pubsub::Subscriber<()>,
    _token: zenoh::liveliness::LivelinessToken,
}

impl ZenohCentral {
    pub(crate) async fn start(
        listen: &[String],
        users_file: Option<&Path>,
        handle: CentralHandle,
    ) -> Result<Self> {
        let session = zenoh::open(router_config_with_users(listen, users_file)?)
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
            move |zid: &str| -> Option<Arc<Inbox>> {
                let mut t = table.lock().unwrap_or_else(|p| p.into_inner());
                if let Some((_, inbox)) = t.by_zid.get(zid) {
                    return Some(inbox.clone());
                }
                let (link, inbox, mut rx) = handle.attach().ok()?;
                t.by_zid.insert(zid.to_owned(), (link, inbox.clone()));
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
                Some(inbox)
            }
        };

        let frames = {
            let open = open.clone();
            session
                .declare_subscriber(UP_KEY_PATTERN)
                .callback(move |sample| {
                    let Some(zid) = zid_of(sample.key_expr().as_str()) else {
                        return;
                    };
                    let Some(inbox) = open(zid) else {
                        return;
                    };
                    let frame = Bytes::from(sample.payload().to_bytes().into_owned());
                    inbox.push_or_refuse(frame);
                })
                .await
                .map_err(|e| CentralError::Zenoh(e.to_string()))?
        };

        let alive = {
            let handle = handle.clone();
            let table = table.clone();
            session
                .liveliness()
                .declare_subscriber(ALIVE_KEY_PATTERN)
                .history(true)
                .callback(move |sample| {
                    let Some(zid) = zid_of(sample.key_expr().as_str()) else {
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
                            if let Some((link, _)) = link {
                                let _ = handle.input().send(Input::Event(Event::Closed(link)));
                            }
                        }
                    }
                })
                .await
                .map_err(|e| CentralError::Zenoh(e.to_string()))?
        };
        // Declared last: a module that sees it can say hello at once.
        let token = session
            .liveliness()
            .declare_token(CENTRAL_ALIVE_KEY)
            .await
            .map_err(|e| CentralError::Zenoh(e.to_string()))?;
        tracing::info!(endpoints = ?listen, "central listening over zenoh");
        Ok(ZenohCentral {
            session,
            endpoints: listen.to_vec(),
            _frames: frames,
            _alive: alive,
            _token: token,
        })
    }

    pub(crate) fn endpoints(&self) -> &[String] {
        &self.endpoints
    }

    pub(crate) async fn close(self) {
        let _ = self.session.close().await;
    }
}
