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
//!   link;
//! - central holds the liveliness token `tca/central` ([`CENTRAL_ALIVE_KEY`]); a module that
//!   sees it withdrawn knows central is gone (killed, or the network dropped). Its zenoh session
//!   keeps trying to reach the router with exponential backoff ([`RETRY_PERIOD_INIT_MS`] up to
//!   [`RETRY_PERIOD_MAX_MS`]); when the token is back, the module says hello and registers
//!   again on the new central.
//!
//! Publications are reliable with blocking congestion control (no frame is silently dropped)
//! and express (sent at once, not batched), and multicast scouting is off: modules find central
//! by its endpoint only.
//!
//! Frames from a module go to its link's bounded inbox; one arriving at a full inbox is answered
//! with an over-limit error instead of being routed.
//!
//! With a zenoh users file ([`router_config_with_users`], from the policy's
//! `[transport] zenoh_users_file`) the router requires zenoh user/password authentication
//! (`transport/auth/usrpwd`): a client without a valid login cannot open a session at all.
//! Modules log in with a [`ZenohLogin`] ([`client_config_with_login`]).

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex};

use bytes::Bytes;
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

use crate::core::{Event, LinkId};
use crate::inbox::Inbox;
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

/// Central's liveliness token: modules watch it to notice that central went away (its token is
/// withdrawn when its process dies or the network drops) and came back (they then say hello and
/// register again).
pub const CENTRAL_ALIVE_KEY: &str = "tca/central";

/// How a module's zenoh session retries a lost or refused connection to central: the first
/// retry after this many milliseconds, each next one after twice as long, up to
/// [`RETRY_PERIOD_MAX_MS`].
pub const RETRY_PERIOD_INIT_MS: u64 = 250;

/// The longest wait between two attempts to reach central again, milliseconds.
pub const RETRY_PERIOD_MAX_MS: u64 = 4000;

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
    router_config_with_users(listen, None)
}

/// zenoh configuration of central: a router listening on `listen`. With `users_file` (a zenoh
/// user/password dictionary, `user:password` per line) the router refuses every client that
/// does not log in with one of its pairs (zenoh's `transport/auth/usrpwd`).
pub fn router_config_with_users(
    listen: &[String],
    users_file: Option<&Path>,
) -> Result<zenoh::Config> {
    let mut config = base_config("router")?;
    config
        .insert_json5("listen/endpoints", &endpoints_json(listen)?)
        .map_err(|e| CentralError::Zenoh(format!("listen endpoints: {e}")))?;
    if let Some(file) = users_file {
        check_users_file(file)?;
        let path = serde_json::to_string(&file.to_string_lossy())
            .map_err(|e| CentralError::Zenoh(e.to_string()))?;
        config
            .insert_json5("transport/auth/usrpwd/dictionary_file", &path)
            .map_err(|e| CentralError::Zenoh(format!("zenoh users file: {e}")))?;
    }
    Ok(config)
}

/// Checks a zenoh user/password dictionary before zenoh reads it, for a clearer error.
fn check_users_file(file: &Path) -> Result<()> {
    let text = std::fs::read_to_string(file).map_err(|e| {
        CentralError::Zenoh(format!(
            "cannot read the zenoh users file {}: {e}",
            file.display()
        ))
    })?;
    let mut users = 0;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        match line.split_once(':') {
            Some((u, p)) if !u.trim().is_empty() && !p.trim().is_empty() => users += 1,
            _ => {
                return Err(CentralError::Zenoh(format!(
                    "zenoh users file {} line {}: write one user:password per line",
                    file.display(),
                    i + 1
                )));
            }
        }
    }
    if users == 0 {
        return Err(CentralError::Zenoh(format!(
            "zenoh users file {} has no user:password line; add one per module login",
            file.display()
        )));
    }
    Ok(())
}

/// A zenoh login (user/password authentication of the zenoh transport).
#[derive(Clone, PartialEq, Eq)]
pub struct ZenohLogin {
    /// The zenoh user.
    pub user: String,
    /// Its password.
    pub password: String,
}

impl std::fmt::Debug for ZenohLogin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ZenohLogin {{ user: {:?}, password: *** }}", self.user)
    }
}

impl ZenohLogin {
    /// The login named by the environment variables `TCA_ZENOH_USER` and
    /// `TCA_ZENOH_PASSWORD`, when both are set.
    pub fn from_env() -> Option<Self> {
        let user = std::env::var("TCA_ZENOH_USER").ok()?;
        let password = std::env::var("TCA_ZENOH_PASSWORD").ok()?;
        Some(ZenohLogin { user, password })
    }
}

/// zenoh configuration of a module: a client connecting to `connect`, logging in with `login`
/// when central requires it.
pub fn client_config_with_login(
    connect: &[String],
    login: Option<&ZenohLogin>,
) -> Result<zenoh::Config> {
    let mut config = client_config(connect)?;
    if let Some(login) = login {
        let set = |c: &mut zenoh::Config, key: &str, value: &str| -> Result<()> {
            let json =
                serde_json::to_string(value).map_err(|e| CentralError::Zenoh(e.to_string()))?;
            c.insert_json5(key, &json)
                .map_err(|e| CentralError::Zenoh(format!("{key}: {e}")))
        };
        set(&mut config, "transport/auth/usrpwd/user", &login.user)?;
        set(
            &mut config,
            "transport/auth/usrpwd/password",
            &login.password,
        )?;
    }
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
    // When central goes away, keep trying to reach it, backing off.
    let retry = format!(
        "{{ period_init_ms: {RETRY_PERIOD_INIT_MS}, period_max_ms: {RETRY_PERIOD_MAX_MS}, \
         period_increase_factor: 2.0 }}"
    );
    config
        .insert_json5("connect/retry", &retry)
        .map_err(|e| CentralError::Zenoh(format!("connect/retry: {e}")))?;
    Ok(config)
}

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
                .declare_subscriber("tca/up/*")
                .callback(move |sample| {
                    let Some(zid) = sample.key_expr().as_str().rsplit('/').next() else {
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
