//! Opening a link to central: in-process channels or a zenoh client session.

use std::sync::Arc;

use bytes::Bytes;
use tca_central::CentralHandle;
use tca_central::inproc::InProcSender;
use tca_central::zenoh_transport::{
    CENTRAL_ALIVE_KEY, ZenohLogin, alive_key, client_config_with_login, down_key, up_key,
};
use tokio::sync::mpsc;
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

use crate::error::{ModuleError, Result};

/// How a module reaches central. The same module code runs on either.
#[derive(Clone, Debug)]
pub enum Connector {
    /// Central runs in this process (the embedded default).
    InProcess(CentralHandle),
    /// Central is reached over zenoh at these endpoints (e.g. `tcp/127.0.0.1:7447`), logging
    /// in with `TCA_ZENOH_USER`/`TCA_ZENOH_PASSWORD` when they are set.
    Zenoh(Vec<String>),
    /// Central is reached over zenoh at these endpoints, logging in with this zenoh
    /// user/password (central's router requires it when its policy names a zenoh users file).
    ZenohWithLogin(Vec<String>, ZenohLogin),
}

impl Connector {
    /// A zenoh connector for one endpoint.
    pub fn zenoh(endpoint: impl Into<String>) -> Self {
        Connector::Zenoh(vec![endpoint.into()])
    }

    /// A zenoh connector for one endpoint that logs in with a zenoh user and password.
    pub fn zenoh_with_login(
        endpoint: impl Into<String>,
        user: impl Into<String>,
        password: impl Into<String>,
    ) -> Self {
        Connector::ZenohWithLogin(
            vec![endpoint.into()],
            ZenohLogin {
                user: user.into(),
                password: password.into(),
            },
        )
    }

    /// Describes where it connects, for messages.
    pub fn describe(&self) -> String {
        match self {
            Connector::InProcess(_) => "in-process central".into(),
            Connector::Zenoh(e) | Connector::ZenohWithLogin(e, _) => {
                format!("central over zenoh at {}", e.join(", "))
            }
        }
    }

    pub(crate) async fn open(&self) -> Result<Link> {
        match self {
            Connector::InProcess(handle) => {
                let mut link = handle
                    .connect_in_process()
                    .map_err(|e| ModuleError::Connect(e.to_string()))?;
                let rx = link
                    .take_receiver()
                    .ok_or_else(|| ModuleError::Connect("link receiver already taken".into()))?;
                let tx = FrameTx::InProc(link.sender());
                Ok(Link {
                    tx,
                    rx,
                    presence: None,
                    keep: Keep::InProc(Arc::new(link)),
                })
            }
            Connector::Zenoh(endpoints) => {
                open_zenoh(endpoints, ZenohLogin::from_env().as_ref()).await
            }
            Connector::ZenohWithLogin(endpoints, login) => open_zenoh(endpoints, Some(login)).await,
        }
    }
}

/// Sends frames to central.
#[derive(Clone, Debug)]
pub(crate) enum FrameTx {
    InProc(InProcSender),
    Zenoh(mpsc::UnboundedSender<Bytes>),
}

impl FrameTx {
    pub(crate) fn send(&self, frame: Bytes) -> Result<()> {
        match self {
            FrameTx::InProc(s) => s.send(frame).map_err(|e| match e {
                // Over its inbox limit in central: the send is refused, the link stays.
                tca_central::CentralError::Refused(route) => ModuleError::Route(route),
                _ => ModuleError::Disconnected,
            }),
            FrameTx::Zenoh(s) => s.send(frame).map_err(|_| ModuleError::Disconnected),
        }
    }
}

/// What keeps a link open; dropping it closes the link.
#[allow(dead_code)]
pub(crate) enum Keep {
    InProc(Arc<tca_central::InProcLink>),
    Zenoh(ZenohLink),
}

/// A zenoh client link's resources.
#[allow(dead_code)]
pub(crate) struct ZenohLink {
    session: zenoh::Session,
    subscriber: zenoh::pubsub::Subscriber<()>,
    token: zenoh::liveliness::LivelinessToken,
    central: zenoh::pubsub::Subscriber<()>,
}

/// Whether central is there, as a zenoh link sees it (its liveliness token).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Presence {
    /// Central's token appeared: central is (back) up.
    Up,
    /// Central's token was withdrawn: central died or the network dropped.
    Down,
}

/// An open link.
pub(crate) struct Link {
    pub(crate) tx: FrameTx,
    pub(crate) rx: tca_central::FrameReceiver,
    /// Central's comings and goings (zenoh only: an in-process central cannot die alone).
    pub(crate) presence: Option<mpsc::UnboundedReceiver<Presence>>,
    pub(crate) keep: Keep,
}

async fn open_zenoh(endpoints: &[String], login: Option<&ZenohLogin>) -> Result<Link> {
    let config = client_config_with_login(endpoints, login)
        .map_err(|e| ModuleError::Connect(e.to_string()))?;
    let session = zenoh::open(config).await.map_err(|e| {
        let hint = match login {
            Some(l) => format!(
                "; central may have refused zenoh user {:?} (check TCA_ZENOH_USER/TCA_ZENOH_PASSWORD \
                 against its zenoh users file)",
                l.user
            ),
            None => "; if central requires a zenoh login, set TCA_ZENOH_USER and \
                     TCA_ZENOH_PASSWORD"
                .into(),
        };
        ModuleError::Connect(format!(
            "no central at {}: {e}; start one with `tca central --listen ENDPOINT`{hint}",
            endpoints.join(", ")
        ))
    })?;
    let zid = session.zid().to_string();
    let (in_tx, rx) = mpsc::unbounded_channel();
    let subscriber = session
        .declare_subscriber(down_key(&zid))
        .callback(move |sample| {
            let _ = in_tx.send(Bytes::from(sample.payload().to_bytes().into_owned()));
        })
        .await
        .map_err(|e| ModuleError::Connect(e.to_string()))?;
    let publisher = session
        .declare_publisher(up_key(&zid))
        .congestion_control(CongestionControl::Block)
        .express(true)
        .await
        .map_err(|e| ModuleError::Connect(e.to_string()))?;
    let token = session
        .liveliness()
        .declare_token(alive_key(&zid))
        .await
        .map_err(|e| ModuleError::Connect(e.to_string()))?;
    let (presence_tx, presence) = mpsc::unbounded_channel();
    let central = session
        .liveliness()
        .declare_subscriber(CENTRAL_ALIVE_KEY)
        .history(true)
        .callback(move |sample| {
            let _ = presence_tx.send(match sample.kind() {
                SampleKind::Put => Presence::Up,
                SampleKind::Delete => Presence::Down,
            });
        })
        .await
        .map_err(|e| ModuleError::Connect(e.to_string()))?;
    let (out_tx, mut out_rx) = mpsc::unbounded_channel::<Bytes>();
    tokio::spawn(async move {
        while let Some(frame) = out_rx.recv().await {
            if let Err(e) = publisher.put(frame).await {
                tracing::warn!(error = %e, "publishing to central failed");
            }
        }
    });
    Ok(Link {
        tx: FrameTx::Zenoh(out_tx),
        rx: rx.into(),
        presence: Some(presence),
        keep: Keep::Zenoh(ZenohLink {
            session,
            subscriber,
            token,
            central,
        }),
    })
}
