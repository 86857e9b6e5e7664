//! Isolation per identity, enforced by central's zenoh router, seen from outside: a plain
//! zenoh session (not the module library) logged in as one identity of the policy receives
//! nothing of the other modules' traffic, its frames on their keys never reach central, and
//! its liveliness tokens as central or as another module are refused; the router counts what
//! it refused in central's statistics. The same with identities proven by TLS certificates,
//! where a session without a certificate signed by central's CA cannot open at all.

use crate::common;

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use common::{free_endpoint, within};
use serde::{Deserialize, Serialize};
use tca_central::{CentralConfig, Policy, RunningCentral, StartOptions};
use tca_link::zenoh::{
    CENTRAL_ALIVE_KEY, TlsFiles, ZenohLogin, alive_key, client_config_secured, down_key, up_key,
};
use tca_logs::{LinkEvent, RecordKind};
use tca_module::{Connector, Module, ModuleError};
use tca_testkit::TestCa;

/// Echo: a query answered with its argument.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Echo(u64);
tca_messages::message!(Echo: query "echo" -> u64);

/// `echo` answers `echo`, `asker` asks it; `spy` is a legitimate identity that tries to
/// overhear and speak for the others. No secrets: the transport proves who is who.
const POLICY: &str = "[[identity]]\nname = \"echo\"\nregister = [\"echo\"]\n\
    [[identity]]\nname = \"asker\"\nsend = [\"echo\"]\n\
    [[identity]]\nname = \"spy\"\nsend = [\"*\"]\n";

async fn start(policy: String, listen: String, log: &Path) -> RunningCentral {
    let policy = Policy::parse(Path::new("isolation-policy.toml"), &policy).unwrap();
    tca_central::start(StartOptions {
        config: CentralConfig {
            policy: Some(Arc::new(policy)),
            ..CentralConfig::default()
        },
        log: Some(log.to_owned()),
        listen: vec![listen],
        insecure: false,
        journal: None,
        keep_previous_log: false,
    })
    .await
    .unwrap()
}

/// A plain zenoh client of one identity: one session speaks, another listens to everything
/// under `tca` (a session would hear its own publications and tokens locally).
struct Spy {
    session: zenoh::Session,
    ears: zenoh::Session,
    seen: Arc<std::sync::Mutex<Vec<String>>>,
    _keep: (zenoh::pubsub::Subscriber<()>, zenoh::pubsub::Subscriber<()>),
}

impl Spy {
    /// Opens the two sessions with `config`.
    async fn open(config: zenoh::Config) -> Spy {
        let session = zenoh::open(config.clone()).await.unwrap();
        let ears = zenoh::open(config).await.unwrap();
        let seen = Arc::new(std::sync::Mutex::new(Vec::new()));
        let s = seen.clone();
        let all = ears
            .declare_subscriber("tca/**")
            .callback(move |sample| s.lock().unwrap().push(sample.key_expr().to_string()))
            .await
            .unwrap();
        let s = seen.clone();
        let tokens = ears
            .liveliness()
            .declare_subscriber("tca/**")
            .history(true)
            .callback(move |sample| {
                s.lock()
                    .unwrap()
                    .push(format!("token {}", sample.key_expr()))
            })
            .await
            .unwrap();
        Spy {
            session,
            ears,
            seen,
            _keep: (all, tokens),
        }
    }

    /// Publishes `n` frames on each of the other modules' keys and central's, and declares
    /// central's token and another module's; returns how many messages that was.
    async fn speak_for_others(&self, n: u64) -> (u64, Vec<zenoh::liveliness::LivelinessToken>) {
        let zid = self.session.zid().to_string();
        let keys = [
            up_key("echo", &zid),
            up_key("asker", "anything"),
            down_key("asker", "anything"),
        ];
        for i in 0..n {
            for key in &keys {
                self.session
                    .put(key, vec![0xff, i as u8, 0x13])
                    .await
                    .unwrap();
            }
        }
        let mut tokens = Vec::new();
        for key in [CENTRAL_ALIVE_KEY.to_owned(), alive_key("echo", &zid)] {
            tokens.push(self.session.liveliness().declare_token(key).await.unwrap());
        }
        (n * keys.len() as u64 + 2, tokens)
    }

    fn seen(&self) -> Vec<String> {
        self.seen.lock().unwrap().clone()
    }
}

/// `echo` and `asker` connected by `connector_for`, the spy meddling, and what must hold;
/// `earlier` link records (opened, refused) are in the log from before.
async fn check_isolation(
    central: RunningCentral,
    log: &Path,
    connector_for: impl Fn(&str) -> Connector,
    spy: Spy,
    earlier: usize,
) {
    let echo = within(
        "echo connects with no hello credentials",
        Module::builder("echo")
            .handle(|_ctx, q: Echo| async move { Ok(q.0) })
            .connect(&connector_for("echo")),
    )
    .await
    .unwrap();
    let asker = within(
        "asker connects",
        Module::builder("asker").connect(&connector_for("asker")),
    )
    .await
    .unwrap();
    for n in 0..50 {
        assert_eq!(within("echo", asker.query(&Echo(n))).await.unwrap(), n);
    }
    let before = central.handle().stats().await.unwrap();
    let (tried, _tokens) = spy.speak_for_others(20).await;
    // The modules go on undisturbed.
    for n in 0..5 {
        assert_eq!(
            within("echo after", asker.query(&Echo(n))).await.unwrap(),
            n
        );
    }
    tokio::time::sleep(Duration::from_millis(300)).await;
    let after = central.handle().stats().await.unwrap();
    let seen = spy.seen();
    assert!(
        seen.is_empty(),
        "the spy saw {} samples: {:?}",
        seen.len(),
        &seen[..seen.len().min(5)]
    );
    assert_eq!(after.counters.bad_frames, before.counters.bad_frames);
    let refused = after.refused_by_router - before.refused_by_router;
    eprintln!("the spy tried {tried} messages; the router refused {refused}");
    assert!(refused >= tried, "the router refused {refused} of {tried}");
    spy.session.close().await.unwrap();
    spy.ears.close().await.unwrap();
    asker.close().await;
    echo.close().await;
    let last = central.shutdown().await.unwrap();
    assert!(last.refused_by_router >= after.refused_by_router);
    // Nothing of the spy's reached central: the only links opened since are the two modules'.
    let bytes = std::fs::read(log).unwrap();
    let parsed = tca_logs::LogFile::parse(log, &bytes).unwrap();
    let links: Vec<_> = parsed
        .records
        .iter()
        .filter_map(|r| match &r.kind {
            RecordKind::Link(l) if matches!(l.event, LinkEvent::Opened | LinkEvent::Refused) => {
                Some(format!("{:?} {:?}", l.event, l.module))
            }
            _ => None,
        })
        .collect();
    assert_eq!(links.len(), earlier + 2, "{links:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_logged_in_session_reads_and_speaks_only_for_itself() {
    let dir = tempfile::tempdir().unwrap();
    let users = dir.path().join("users.txt");
    std::fs::write(&users, "echo:zp-echo\nasker:zp-asker\nspy:zp-spy\n").unwrap();
    let policy = format!(
        "[transport]\nzenoh_users_file = {:?}\n{POLICY}",
        users.display().to_string()
    );
    let endpoint = free_endpoint();
    let log = dir.path().join("traffic.mcap");
    let central = start(policy, endpoint.clone(), &log).await;
    let spy_login = ZenohLogin::new("spy", "zp-spy");
    let spy = Spy::open(
        client_config_secured(std::slice::from_ref(&endpoint), Some(&spy_login), None).unwrap(),
    )
    .await;
    let connector_for =
        |identity: &str| Connector::zenoh_with_login(&endpoint, identity, format!("zp-{identity}"));
    check_isolation(central, &log, connector_for, spy, 0).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn identities_from_certificates_over_mutual_tls() {
    let dir = tempfile::tempdir().unwrap();
    let ca = TestCa::new(dir.path(), "tca");
    let central_files = ca.central();
    let policy = format!(
        "[transport.tls]\ncertificate = {:?}\nprivate_key = {:?}\nca = {:?}\n{POLICY}",
        central_files.certificate.display().to_string(),
        central_files.private_key.display().to_string(),
        central_files.ca.display().to_string(),
    );
    let port = tca_testkit::free_port();
    let endpoint = format!("tls/127.0.0.1:{port}");
    let log = dir.path().join("traffic.mcap");
    let central = start(policy, endpoint.clone(), &log).await;

    // Without a certificate signed by central's CA, no session opens.
    let rogue_dir = dir.path().join("rogue");
    std::fs::create_dir(&rogue_dir).unwrap();
    let rogue = TestCa::new(&rogue_dir, "rogue").module("echo");
    let forged = TlsFiles::new(&rogue.certificate, &rogue.private_key, ca.ca());
    let config =
        client_config_secured(std::slice::from_ref(&endpoint), None, Some(&forged)).unwrap();
    assert!(
        zenoh::open(config).await.is_err(),
        "a certificate of another CA opened a session"
    );
    let mut no_certificate =
        tca_link::zenoh::client_config(std::slice::from_ref(&endpoint)).unwrap();
    no_certificate
        .insert_json5(
            "transport/link/tls/root_ca_certificate",
            &format!("{:?}", ca.ca().display().to_string()),
        )
        .unwrap();
    assert!(
        zenoh::open(no_certificate).await.is_err(),
        "a session without a certificate opened"
    );
    // The module library says what is missing before it tries.
    match Module::builder("echo")
        .connect(&Connector::zenoh(endpoint.clone()))
        .await
    {
        Err(e) => assert!(e.to_string().contains("TCA_ZENOH_TLS_CERT"), "{e}"),
        Ok(_) => panic!("a module without a certificate was admitted"),
    }
    // A certificate's common name is the identity: asker's may not connect as echo.
    let as_asker = Connector::zenoh_with_tls(&endpoint, ca.module("asker"));
    match within("asker as echo", Module::builder("echo").connect(&as_asker)).await {
        Err(ModuleError::Refused { reason, .. }) => assert!(
            reason.contains("identity \"asker\" may not connect as module \"echo\""),
            "{reason}"
        ),
        Err(other) => panic!("expected a refusal, got {other}"),
        Ok(_) => panic!("asker's certificate connected as echo"),
    }

    let spy_files = ca.module("spy");
    let spy = Spy::open(
        client_config_secured(std::slice::from_ref(&endpoint), None, Some(&spy_files)).unwrap(),
    )
    .await;
    let identities: std::collections::HashMap<&str, TlsFiles> =
        [("echo", ca.module("echo")), ("asker", ca.module("asker"))].into();
    let connector_for =
        |identity: &str| Connector::zenoh_with_tls(&endpoint, identities[identity].clone());
    // The refused module above opened one link of its own, and was refused on it.
    check_isolation(central, &log, connector_for, spy, 2).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn one_identitys_login_with_anothers_certificate_gets_neither() {
    let dir = tempfile::tempdir().unwrap();
    let ca = TestCa::new(dir.path(), "tca");
    let central_files = ca.central();
    let users = dir.path().join("users.txt");
    std::fs::write(&users, "echo:zp-echo\nasker:zp-asker\nspy:zp-spy\n").unwrap();
    let policy = format!(
        "[transport]\nzenoh_users_file = {:?}\n\
         [transport.tls]\ncertificate = {:?}\nprivate_key = {:?}\nca = {:?}\n{POLICY}",
        users.display().to_string(),
        central_files.certificate.display().to_string(),
        central_files.private_key.display().to_string(),
        central_files.ca.display().to_string(),
    );
    let port = tca_testkit::free_port();
    let endpoint = format!("tls/127.0.0.1:{port}");
    let log = dir.path().join("traffic.mcap");
    let central = start(policy, endpoint.clone(), &log).await;
    // The spy holds its own password and asker's certificate: as user "spy" and as common
    // name "asker" it would match both identities' subjects.
    let spy_login = ZenohLogin::new("spy", "zp-spy");
    let asker_files = ca.module("asker");
    let spy = Spy::open(
        client_config_secured(
            std::slice::from_ref(&endpoint),
            Some(&spy_login),
            Some(&asker_files),
        )
        .unwrap(),
    )
    .await;
    let identities: std::collections::HashMap<&str, TlsFiles> =
        [("echo", ca.module("echo")), ("asker", asker_files.clone())].into();
    let connector_for = |identity: &str| {
        Connector::new(
            tca_link::zenoh::ZenohTransport::with_login(
                vec![endpoint.clone()],
                ZenohLogin::new(identity, format!("zp-{identity}")),
            )
            .tls(identities[identity].clone()),
        )
    };
    check_isolation(central, &log, connector_for, spy, 0).await;
}
