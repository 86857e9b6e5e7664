//! Central's side of the zenoh transport: a zenoh router whose subscriptions feed the driver.
//!
//! Frames a module publishes on its up key go to its link's bounded inbox; one arriving at a
//! full inbox is answered with an over-limit error instead of being routed. A module's
//! liveliness token opens its link (if its first frame has not already) and closes it when
//! withdrawn. Central's own token is declared last, so a module that sees it can say hello at
//! once. The key scheme and the router's configuration are `tca_link::zenoh`'s.
//!
//! When the policy authenticates zenoh clients (a users file, TLS client certificates), the
//! router's access control confines each identity to its own keys, so the identity a key
//! carries is the one the router authenticated: the link is opened as that identity and the
//! module's hello is held to it. Central then subscribes per identity, and reads from the
//! router's statistics how many messages its access control refused
//! (`tca_link::zenoh::acl::refusals`).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bytes::Bytes;
use tca_link::Inbox;
use tca_link::zenoh::{
    ALIVE_KEY_PATTERN, CENTRAL_ALIVE_KEY, RouterSecurity, UP_KEY_PATTERN, down_key, link_of,
    router_config_secured, up_key_pattern,
};
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

use crate::core::{Event, LinkId};
use crate::runtime::{CentralHandle, Input};
use crate::{CentralError, Result};

/// Links known to the zenoh side, by identity and session id.
struct LinkTable {
    by_key: HashMap<(String, String), (LinkId, Arc<Inbox>)>,
}

/// Central's zenoh router and the subscriptions that feed the driver.
pub(crate) struct ZenohCentral {
    session: zenoh::Session,
    endpoints: Vec<String>,
    _frames: Vec<zenoh::pubsub::Subscriber<()>>,
    _alive: zenoh::pubsub::Subscriber<()>,
    _token: zenoh::liveliness::LivelinessToken,
}

impl ZenohCentral {
    pub(crate) async fn start(
        listen: &[String],
        security: &RouterSecurity,
        handle: CentralHandle,
    ) -> Result<Self> {
        let session = zenoh::open(router_config_secured(listen, security)?)
            .await
            .map_err(|e| CentralError::Zenoh(format!("cannot listen on {listen:?}: {e}")))?;
        // With access control, the identity in a key is the one the router authenticated.
        let isolating = security.authenticators().any();
        let table = Arc::new(Mutex::new(LinkTable {
            by_key: HashMap::new(),
        }));
        let runtime = tokio::runtime::Handle::current();

        let open = {
            let table = table.clone();
            let handle = handle.clone();
            let session = session.clone();
            let runtime = runtime.clone();
            move |who: &str, zid: &str| -> Option<Arc<Inbox>> {
                let mut t = table.lock().unwrap_or_else(|p| p.into_inner());
                let id = (who.to_owned(), zid.to_owned());
                if let Some((_, inbox)) = t.by_key.get(&id) {
                    return Some(inbox.clone());
                }
                let identity = isolating.then(|| who.to_owned());
                let (link, inbox, mut rx) = handle.attach_as(identity).ok()?;
                t.by_key.insert(id, (link, inbox.clone()));
                let key = down_key(who, zid);
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

        // One subscriber per identity, so that each session learns only of its own.
        let patterns = if isolating {
            security
                .identities
                .iter()
                .map(|n| up_key_pattern(n))
                .collect()
        } else {
            vec![UP_KEY_PATTERN.to_owned()]
        };
        let mut frames = Vec::with_capacity(patterns.len());
        for pattern in patterns {
            let open = open.clone();
            let subscriber = session
                .declare_subscriber(pattern)
                .callback(move |sample| {
                    let Some((who, zid)) = link_of(sample.key_expr().as_str()) else {
                        return;
                    };
                    let Some(inbox) = open(who, zid) else {
                        return;
                    };
                    let frame = Bytes::from(sample.payload().to_bytes().into_owned());
                    inbox.push_or_refuse(frame);
                })
                .await
                .map_err(|e| CentralError::Zenoh(e.to_string()))?;
            frames.push(subscriber);
        }

        let alive = {
            let handle = handle.clone();
            let table = table.clone();
            session
                .liveliness()
                .declare_subscriber(ALIVE_KEY_PATTERN)
                .history(true)
                .callback(move |sample| {
                    let Some((who, zid)) = link_of(sample.key_expr().as_str()) else {
                        return;
                    };
                    match sample.kind() {
                        SampleKind::Put => {
                            open(who, zid);
                        }
                        SampleKind::Delete => {
                            let link = table
                                .lock()
                                .unwrap_or_else(|p| p.into_inner())
                                .by_key
                                .remove(&(who.to_owned(), zid.to_owned()));
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

    /// The router's session (for its statistics).
    pub(crate) fn session(&self) -> &zenoh::Session {
        &self.session
    }

    pub(crate) async fn close(self) {
        let _ = self.session.close().await;
    }
}
