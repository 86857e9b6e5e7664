//! A module's side of the zenoh transport: a client session connected to central's router.

use bytes::Bytes;
use futures::future::BoxFuture;
use tokio::sync::mpsc;
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

use super::config::{ZenohLogin, client_config_secured};
use super::keys::{
    CENTRAL_ALIVE_KEY, NO_IDENTITY, alive_key, check_identity_name, down_key, up_key,
};
use super::tls::TlsFiles;
use crate::outbox::FrameReceiver;
use crate::transport::{FrameSender, Link, Presence, SendFrame, Transport};
use crate::{LinkError, Result};

/// Opens links to central over zenoh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ZenohTransport {
    endpoints: Vec<String>,
    login: Option<ZenohLogin>,
    tls: Option<TlsFiles>,
}

impl ZenohTransport {
    /// Connects to central at `endpoints` (e.g. `tcp/127.0.0.1:7447`), logging in with
    /// `TCA_ZENOH_USER`/`TCA_ZENOH_PASSWORD` when they are set and presenting the certificate
    /// of `TCA_ZENOH_TLS_CERT`/`TCA_ZENOH_TLS_KEY`/`TCA_ZENOH_TLS_CA` when they are.
    pub fn new(endpoints: Vec<String>) -> Self {
        ZenohTransport {
            endpoints,
            login: None,
            tls: None,
        }
    }

    /// Connects to central at `endpoints`, logging in with `login` (central's router requires
    /// it when its policy names a zenoh users file).
    pub fn with_login(endpoints: Vec<String>, login: ZenohLogin) -> Self {
        ZenohTransport {
            endpoints,
            login: Some(login),
            tls: None,
        }
    }

    /// The same, presenting `tls`'s certificate on `tls/` endpoints and checking central's
    /// against its CA (central's router requires it when its policy has `[transport.tls]`).
    pub fn tls(mut self, tls: TlsFiles) -> Self {
        self.tls = Some(tls);
        self
    }

    /// The endpoints it connects to.
    pub fn endpoints(&self) -> &[String] {
        &self.endpoints
    }

    async fn open_link(&self) -> Result<Link> {
        let login = match &self.login {
            Some(l) => Some(l.clone()),
            None => ZenohLogin::from_env(),
        };
        let tls = match &self.tls {
            Some(t) => Some(t.clone()),
            None => TlsFiles::from_env()?,
        };
        open(&self.endpoints, login.as_ref(), tls.as_ref()).await
    }
}

/// The identity the module's keys carry: its zenoh user, else its certificate's common name,
/// else [`NO_IDENTITY`]. A user and a certificate naming two identities are refused.
pub fn session_identity(login: Option<&ZenohLogin>, tls: Option<&TlsFiles>) -> Result<String> {
    let cn = tls.map(TlsFiles::common_name).transpose()?;
    let who = match (login, cn) {
        (Some(l), Some(cn)) if l.user != cn => {
            return Err(LinkError::Config(format!(
                "zenoh user {:?} and certificate common name {cn:?} name two identities; \
                 log in as the identity the certificate names",
                l.user
            )));
        }
        (Some(l), _) => l.user.clone(),
        (None, Some(cn)) => cn,
        (None, None) => return Ok(NO_IDENTITY.to_owned()),
    };
    check_identity_name(&who).map_err(LinkError::Config)?;
    Ok(who)
}

impl Transport for ZenohTransport {
    fn open(&self) -> BoxFuture<'_, Result<Link>> {
        Box::pin(self.open_link())
    }

    fn describe(&self) -> String {
        format!("central over zenoh at {}", self.endpoints.join(", "))
    }
}

/// Frames to central, handed to the publishing task.
#[derive(Debug)]
struct ZenohSender(mpsc::UnboundedSender<Bytes>);

impl SendFrame for ZenohSender {
    fn send(&self, frame: Bytes) -> Result<()> {
        self.0.send(frame).map_err(|_| LinkError::Stopped)
    }
}

/// A zenoh client link's resources; dropping them ends the session (and withdraws the
/// module's liveliness token).
#[allow(dead_code)]
struct Resources {
    session: zenoh::Session,
    subscriber: zenoh::pubsub::Subscriber<()>,
    token: zenoh::liveliness::LivelinessToken,
    central: zenoh::pubsub::Subscriber<()>,
}

fn open_error(e: impl std::fmt::Display) -> LinkError {
    LinkError::Open(e.to_string())
}

async fn open(
    endpoints: &[String],
    login: Option<&ZenohLogin>,
    tls: Option<&TlsFiles>,
) -> Result<Link> {
    let config = client_config_secured(endpoints, login, tls)?;
    let who = session_identity(login, tls)?;
    let session = zenoh::open(config).await.map_err(|e| {
        let mut hint = match login {
            Some(l) => format!(
                "; central may have refused zenoh user {:?} (check TCA_ZENOH_USER/TCA_ZENOH_PASSWORD \
                 against its zenoh users file)",
                l.user
            ),
            None => "; if central requires a zenoh login, set TCA_ZENOH_USER and \
                     TCA_ZENOH_PASSWORD"
                .into(),
        };
        if tls.is_some() {
            hint.push_str(
                "; central may have refused the certificate (is it signed by the CA central \
                 trusts, and is central's signed by TCA_ZENOH_TLS_CA?)",
            );
        }
        LinkError::Open(format!(
            "no central at {}: {e}; start one with `tca central --listen ENDPOINT`{hint}",
            endpoints.join(", ")
        ))
    })?;
    let zid = session.zid().to_string();
    let (in_tx, rx) = mpsc::unbounded_channel();
    let subscriber = session
        .declare_subscriber(down_key(&who, &zid))
        .callback(move |sample| {
            let _ = in_tx.send(Bytes::from(sample.payload().to_bytes().into_owned()));
        })
        .await
        .map_err(open_error)?;
    let publisher = session
        .declare_publisher(up_key(&who, &zid))
        .congestion_control(CongestionControl::Block)
        .express(true)
        .await
        .map_err(open_error)?;
    let token = session
        .liveliness()
        .declare_token(alive_key(&who, &zid))
        .await
        .map_err(open_error)?;
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
        .map_err(open_error)?;
    let (out_tx, mut out_rx) = mpsc::unbounded_channel::<Bytes>();
    tokio::spawn(async move {
        while let Some(frame) = out_rx.recv().await {
            if let Err(e) = publisher.put(frame).await {
                tracing::warn!(error = %e, "publishing to central failed");
            }
        }
    });
    Ok(Link {
        sender: FrameSender::new(ZenohSender(out_tx)),
        receiver: FrameReceiver::from(rx),
        presence: Some(presence),
        keep: Box::new(Resources {
            session,
            subscriber,
            token,
            central,
        }),
    })
}
