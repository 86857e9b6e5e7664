//! Authentication, authorisation and resource limits, end to end:
//! central with a policy file refuses strangers, wrong secrets and sends or registrations
//! outside an identity's rules (nothing of them is routed), refuses zenoh clients without the
//! right zenoh login, never logs a secret, and throttles a flooding module while others keep
//! talking. In-process, over zenoh and over the local link where it applies.

use crate::common;

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use common::{free_endpoint, unique_local_endpoint, within};
use serde::{Deserialize, Serialize};
use tca_central::policy::hash_secret;
use tca_central::{CentralConfig, Policy, RunningCentral, StartOptions};
use tca_messages::RouteError;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module, ModuleError};

/// Echo: a query answered with its argument.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Echo(u64);
tca_messages::message!(Echo: query "echo" -> u64);

/// A map update: an inform.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct MapUpdate(Vec<u8>);
tca_messages::message!(MapUpdate: inform "mapUpdate");

/// Work: a goal.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Work(u32);
tca_messages::message!(Work: goal "work");

/// A message nobody may send (outside every rule).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Secret(u32);
tca_messages::message!(Secret: query "adminSecret" -> u32);

const ECHO_SECRET: &str = "echo-secret-9f2";
const ASKER_SECRET: &str = "asker-secret-71c";

/// The policy of these tests: `echo` answers `echo` and gets `map*`; `asker` may send `echo`,
/// `map*` and `work`; `worker` handles `work`.
fn policy_text(zenoh_users: Option<&Path>) -> String {
    let mut text = String::new();
    if let Some(users) = zenoh_users {
        text.push_str(&format!(
            "[transport]\nzenoh_users_file = {:?}\n",
            users.display().to_string()
        ));
    }
    text.push_str(&format!(
        "[[identity]]\nname = \"echo\"\nsecret_sha3 = \"{}\"\nmodules = [\"echo*\"]\n\
         register = [\"echo\", \"map*\"]\nsend = []\n\
         [[identity]]\nname = \"asker\"\nsecret_sha3 = \"{}\"\nmodules = [\"asker*\", \"flood*\"]\n\
         register = []\nsend = [\"echo\", \"map*\", \"work\"]\n\
         [[identity]]\nname = \"worker\"\nsecret_sha3 = \"{}\"\nregister = [\"work\"]\n",
        hash_secret("echo", ECHO_SECRET),
        hash_secret("asker", ASKER_SECRET),
        hash_secret("worker", "w"),
    ));
    text
}

fn policy(zenoh_users: Option<&Path>) -> Arc<Policy> {
    Arc::new(Policy::parse(Path::new("test-policy.toml"), &policy_text(zenoh_users)).unwrap())
}

async fn start(config: CentralConfig, zenoh: bool, log: Option<&Path>) -> (RunningCentral, String) {
    let endpoint = free_endpoint();
    let central = tca_central::start(StartOptions {
        config,
        log: log.map(Path::to_owned),
        listen: if zenoh {
            vec![endpoint.clone()]
        } else {
            vec![]
        },
        insecure: false,
        ..StartOptions::default()
    })
    .await
    .unwrap();
    (central, endpoint)
}

/// The echo module, with a counter of the map updates it received.
async fn echo(connect: &Connect, secret: &str) -> Result<(Module, Arc<AtomicU64>), ModuleError> {
    let maps = Arc::new(AtomicU64::new(0));
    let seen = maps.clone();
    let module = Module::builder("echo")
        .identity("echo", secret)
        .handle(|_ctx, q: Echo| async move { Ok(q.0) })
        .handle(move |_ctx, _m: MapUpdate| {
            let seen = seen.clone();
            async move {
                seen.fetch_add(1, Ordering::Relaxed);
                Ok(())
            }
        })
        .connect(&connect("echo"))
        .await?;
    Ok((module, maps))
}

/// The connector a module of an identity uses (over zenoh, each identity logs in as itself).
type Connect = dyn Fn(&str) -> Connector;

/// The same connector for every identity.
fn same(connector: Connector) -> impl Fn(&str) -> Connector {
    move |_| connector.clone()
}

fn refused_reason(result: Result<Module, ModuleError>) -> String {
    match result {
        Err(ModuleError::Refused { reason, .. }) => reason,
        Err(other) => panic!("expected a refusal, got {other}"),
        Ok(_) => panic!("expected a refusal, the module was admitted"),
    }
}

async fn refusals_at_hello(connector: &Connector) {
    // Unknown identity.
    let r = Module::builder("echo2")
        .identity("stranger", "x")
        .connect(connector)
        .await;
    let reason = refused_reason(r);
    assert!(reason.contains("\"stranger\" is unknown"), "{reason}");
    // Wrong secret.
    let r = Module::builder("echo2")
        .identity("echo", "guess")
        .connect(connector)
        .await;
    let reason = refused_reason(r);
    assert!(reason.contains("secret is wrong"), "{reason}");
    // No credentials, and the policy has no [anonymous] section.
    let r = Module::builder("anon").connect(connector).await;
    let reason = refused_reason(r);
    assert!(reason.contains("requires credentials"), "{reason}");
    // A right identity connecting as a module name outside its `modules` rule.
    let r = Module::builder("controller")
        .identity("echo", ECHO_SECRET)
        .connect(connector)
        .await;
    let reason = refused_reason(r);
    assert!(
        reason.contains("may not connect as module \"controller\""),
        "{reason}"
    );
}

async fn permitted_and_refused_traffic(connect: &Connect, central: &RunningCentral) {
    let (_echo, maps) = within("echo connects", echo(connect, ECHO_SECRET))
        .await
        .unwrap();
    let asker = within(
        "asker connects",
        Module::builder("asker")
            .identity("asker", ASKER_SECRET)
            .connect(&connect("asker")),
    )
    .await
    .unwrap();
    // Permitted: a query and an inform.
    assert_eq!(within("echo", asker.query(&Echo(41))).await.unwrap(), 41);
    asker.inform(&MapUpdate(vec![1, 2])).unwrap();
    assert_eq!(
        within("echo again", asker.query(&Echo(42))).await.unwrap(),
        42
    );

    // Registering outside the policy: the asker may register nothing.
    let r = Module::builder("asker-2")
        .identity("asker", ASKER_SECRET)
        .handle(|_ctx, q: Secret| async move { Ok(q.0) })
        .connect(&connect("asker"))
        .await;
    match r {
        Err(ModuleError::Registration(reasons)) => {
            let all = reasons.join("; ");
            assert!(all.contains("may not register \"adminSecret\""), "{all}");
            assert!(all.contains("identity \"asker\" register = []"), "{all}");
        }
        Err(other) => panic!("expected a registration refusal, got {other}"),
        Ok(_) => panic!("registration outside the policy was accepted"),
    }

    // Sending outside the policy: echo may send nothing; its query is refused with the rule
    // and never reaches a handler.
    let echo_sender = within(
        "second echo",
        Module::builder("echo-sender")
            .identity("echo", ECHO_SECRET)
            .connect(&connect("echo")),
    )
    .await
    .unwrap();
    match within("refused query", echo_sender.query(&Echo(1))).await {
        Err(ModuleError::Route(RouteError::NotPermitted {
            action,
            name,
            rule,
            identity,
            ..
        })) => {
            assert_eq!(
                (action.as_str(), name.as_str(), identity.as_str()),
                ("send", "echo", "echo")
            );
            assert!(rule.contains("identity \"echo\" send = []"), "{rule}");
        }
        other => panic!("expected NotPermitted, got {other:?}"),
    }
    // An inform outside the policy: not routed (the handler's count does not move), and the
    // module is told asynchronously; the next permitted exchange proves it was handled first.
    let before = maps.load(Ordering::Relaxed);
    echo_sender.inform(&MapUpdate(vec![9])).unwrap();
    let goal = echo_sender.send_watched(&Work(1), []).unwrap();
    match within("refused goal", goal.outcome()).await {
        Err(ModuleError::Route(RouteError::NotPermitted { name, .. })) => assert_eq!(name, "work"),
        other => panic!("expected NotPermitted for the goal, got {other:?}"),
    }
    assert_eq!(within("after", asker.query(&Echo(7))).await.unwrap(), 7);
    assert_eq!(
        maps.load(Ordering::Relaxed),
        before,
        "a refused inform was routed"
    );
    assert_eq!(before, 1);
    let stats = central.handle().stats().await.unwrap();
    assert!(stats.counters.not_permitted >= 4, "{:?}", stats.counters);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn policy_in_process() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("traffic.mcap");
    let config = CentralConfig {
        policy: Some(policy(None)),
        ..CentralConfig::default()
    };
    let (central, _) = start(config, false, Some(&log)).await;
    let connector = Connector::from(central.in_process());
    refusals_at_hello(&connector).await;
    permitted_and_refused_traffic(&same(connector), &central).await;
    central.shutdown().await.unwrap();
    // The log tells the story, without a single secret in it.
    let bytes = std::fs::read(&log).unwrap();
    for secret in [ECHO_SECRET, ASKER_SECRET] {
        assert!(
            !bytes.windows(secret.len()).any(|w| w == secret.as_bytes()),
            "the log holds a secret"
        );
    }
    let parsed = tca_logs::LogFile::parse(&log, &bytes).unwrap();
    let problems: Vec<String> = parsed
        .records
        .iter()
        .filter_map(|r| match &r.kind {
            tca_logs::RecordKind::Problem(p) => Some(p.error.clone()),
            _ => None,
        })
        .collect();
    assert!(
        problems.iter().any(|p| p.contains("may not send \"echo\"")),
        "{problems:?}"
    );
    assert!(
        problems
            .iter()
            .any(|p| p.contains("may not register \"adminSecret\"")),
        "{problems:?}"
    );
}

/// A central with `config` listening on a local endpoint of its own, and that endpoint.
async fn start_local(config: CentralConfig) -> (RunningCentral, String) {
    let endpoint = unique_local_endpoint();
    let central = tca_central::start(StartOptions {
        config,
        log: None,
        listen: vec![endpoint.clone()],
        insecure: false,
        ..StartOptions::default()
    })
    .await
    .unwrap();
    (central, endpoint)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn policy_over_the_local_link() {
    let config = CentralConfig {
        policy: Some(policy(None)),
        ..CentralConfig::default()
    };
    let (central, endpoint) = start_local(config).await;
    let connector = Connector::endpoint(endpoint);
    refusals_at_hello(&connector).await;
    permitted_and_refused_traffic(&same(connector), &central).await;
    central.shutdown().await.unwrap();
}

/// Each identity's zenoh login: the user is the identity.
fn users_file(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("zenoh-users.txt");
    std::fs::write(&path, "echo:zp-echo\nasker:zp-asker\nworker:zp-worker\n").unwrap();
    path
}

/// Connects as `identity` logging in to zenoh as that identity.
fn login(endpoint: &str) -> impl Fn(&str) -> Connector + use<> {
    let endpoint = endpoint.to_owned();
    move |identity| Connector::zenoh_with_login(&endpoint, identity, format!("zp-{identity}"))
}

/// With a zenoh login the link's identity is the login's: a hello naming another identity, a
/// wrong secret or a module name outside the identity's rule is refused; no credentials at
/// all are fine (the login proves the identity).
async fn refusals_at_hello_with_login(endpoint: &str) {
    let as_echo = Connector::zenoh_with_login(endpoint, "echo", "zp-echo");
    let r = Module::builder("echo2")
        .identity("asker", ASKER_SECRET)
        .connect(&as_echo)
        .await;
    let reason = refused_reason(r);
    assert!(
        reason.contains("authenticated as identity \"echo\"") && reason.contains("\"asker\""),
        "{reason}"
    );
    let r = Module::builder("echo2")
        .identity("echo", "guess")
        .connect(&as_echo)
        .await;
    let reason = refused_reason(r);
    assert!(reason.contains("secret in the hello is wrong"), "{reason}");
    let r = Module::builder("controller").connect(&as_echo).await;
    let reason = refused_reason(r);
    assert!(
        reason.contains("may not connect as module \"controller\""),
        "{reason}"
    );
    let admitted = within(
        "a module proven by its login alone",
        Module::builder("echo-by-login").connect(&as_echo),
    )
    .await
    .unwrap();
    admitted.close().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn policy_over_zenoh_with_zenoh_login() {
    let dir = tempfile::tempdir().unwrap();
    let users = users_file(dir.path());
    let config = CentralConfig {
        policy: Some(policy(Some(&users))),
        ..CentralConfig::default()
    };
    let (central, endpoint) = start(config, true, None).await;

    // No zenoh login, or a wrong one: refused by zenoh when the session opens.
    for connector in [
        Connector::zenoh(endpoint.clone()),
        Connector::zenoh_with_login(&endpoint, "echo", "wrong"),
        Connector::zenoh_with_login(&endpoint, "nobody", "zp-echo"),
    ] {
        let r = within(
            "unauthenticated zenoh client",
            Module::builder("echo")
                .identity("echo", ECHO_SECRET)
                .connect(&connector),
        )
        .await;
        match r {
            Err(ModuleError::Connect(reason)) => {
                assert!(reason.contains("no central at"), "{reason}")
            }
            Err(other) => panic!("expected a refused zenoh session, got {other}"),
            Ok(_) => panic!("a zenoh client without the right login was admitted"),
        }
    }
    // The right zenoh login: the policy applies as in-process.
    refusals_at_hello_with_login(&endpoint).await;
    permitted_and_refused_traffic(&login(&endpoint), &central).await;
    central.shutdown().await.unwrap();
}

#[test]
fn policy_example_file_parses() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../policy.example.toml");
    let policy = Policy::load(&path).unwrap();
    assert!(policy.zenoh_users_file().is_some());
    // Its zenoh users are its identities, so the router takes it, with access control on.
    let security = policy.router_security();
    assert!(security.authenticators().users);
    let config =
        tca_link::zenoh::router_config_secured(&["tcp/127.0.0.1:7447".into()], &security).unwrap();
    assert!(
        config
            .get_json("access_control/enabled")
            .unwrap()
            .contains("true")
    );
}

// ---------------------------------------------------------------------------------------------
// Resource limits.

/// One module floods informs and goals; two others keep exchanging queries.
/// With `exact`, every inform the flooder's sends accepted must reach its handler (in-process,
/// where refusals are synchronous).
async fn flood(connect: &Connect, central: &RunningCentral, exact: bool) {
    let (_echo, maps) = within("echo", echo(connect, ECHO_SECRET)).await.unwrap();
    let handled = Arc::new(AtomicU64::new(0));
    let h = handled.clone();
    let _worker = within(
        "worker",
        Module::builder("worker")
            .identity("worker", "w")
            .handle(move |_ctx, _w: Work| {
                let h = h.clone();
                async move {
                    tokio::time::sleep(Duration::from_millis(1)).await;
                    h.fetch_add(1, Ordering::Relaxed);
                    Ok(())
                }
            })
            .connect(&connect("worker")),
    )
    .await
    .unwrap();
    let asker = within(
        "asker",
        Module::builder("asker")
            .identity("asker", ASKER_SECRET)
            .connect(&connect("asker")),
    )
    .await
    .unwrap();
    let flooder = within(
        "flooder",
        Module::builder("flooder")
            .identity("asker", ASKER_SECRET)
            .connect(&connect("asker")),
    )
    .await
    .unwrap();

    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flooding = {
        let stop = stop.clone();
        tokio::spawn(async move {
            let (mut refused_now, mut sent, mut informs, mut tasks) =
                (0u64, 0u64, 0u64, Vec::new());
            let payload = vec![7u8; 512];
            let mut i = 0u32;
            while !stop.load(Ordering::Relaxed) && i < 50_000 {
                i += 1;
                let r = if i.is_multiple_of(8) {
                    flooder.send_watched(&Work(i), []).map(|t| tasks.push(t))
                } else {
                    flooder
                        .inform(&MapUpdate(payload.clone()))
                        .map(|()| informs += 1)
                };
                match r {
                    Ok(()) => sent += 1,
                    Err(ModuleError::Route(RouteError::OverLimit { .. })) => refused_now += 1,
                    Err(e) => panic!("flooder: unexpected error {e}"),
                }
                if i.is_multiple_of(64) {
                    tokio::task::yield_now().await;
                }
            }
            (flooder, refused_now, sent, informs, tasks)
        })
    };

    // Meanwhile the two others exchange queries: all answered, none slow.
    let mut worst = Duration::ZERO;
    for n in 0..300u64 {
        let t = Instant::now();
        let answer = within("query during the flood", asker.query(&Echo(n)))
            .await
            .unwrap();
        assert_eq!(answer, n);
        worst = worst.max(t.elapsed());
    }
    stop.store(true, Ordering::Relaxed);
    let (_flooder, refused_now, sent, informs, tasks) =
        within("flooder stops", flooding).await.unwrap();

    // Goals that were accepted all complete; refused ones say why.
    let (mut achieved, mut over_limit) = (0u64, 0u64);
    for task in tasks {
        match within("goal outcome", task.outcome()).await {
            Ok(TaskOutcome::Achieved) => achieved += 1,
            Err(ModuleError::Route(RouteError::OverLimit { setting, .. })) => {
                assert!(setting.starts_with("max_"), "{setting}");
                over_limit += 1;
            }
            other => panic!("unexpected goal outcome {other:?}"),
        }
    }
    let stats = central.handle().stats().await.unwrap();
    eprintln!(
        "flood: sent {sent}, refused at once {refused_now}, goals achieved {achieved}, goals over \
         limit {over_limit}, central over-limit errors {}, worst query {worst:?}",
        stats.counters.over_limit
    );
    assert!(
        refused_now + stats.counters.over_limit > 0,
        "the flood never reached a limit"
    );
    assert_eq!(
        handled.load(Ordering::Relaxed),
        achieved,
        "an accepted goal was lost"
    );
    if exact {
        within("every accepted inform arrives", async {
            while maps.load(Ordering::Relaxed) < informs {
                tokio::time::sleep(Duration::from_millis(5)).await;
            }
        })
        .await;
        assert_eq!(maps.load(Ordering::Relaxed), informs);
    }
    // Bounded latency: far below what waiting behind the whole flood would take.
    assert!(
        worst < Duration::from_secs(2),
        "a query took {worst:?} during the flood"
    );
}

fn flood_config(zenoh_users: Option<&Path>) -> CentralConfig {
    CentralConfig {
        policy: Some(policy(zenoh_users)),
        max_inbox_frames: 32,
        max_inbox_bytes: 64 << 10,
        max_queued_messages: 16,
        max_queued_bytes: 16 << 10,
        ..CentralConfig::default()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn flooding_module_is_throttled_in_process() {
    let (central, _) = start(flood_config(None), false, None).await;
    flood(&same(Connector::from(central.in_process())), &central, true).await;
    central.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn flooding_module_is_throttled_over_zenoh() {
    let dir = tempfile::tempdir().unwrap();
    let users = users_file(dir.path());
    let (central, endpoint) = start(flood_config(Some(&users)), true, None).await;
    flood(&login(&endpoint), &central, false).await;
    central.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn flooding_module_is_throttled_over_the_local_link() {
    let (central, endpoint) = start_local(flood_config(None)).await;
    flood(&same(Connector::endpoint(endpoint)), &central, false).await;
    central.shutdown().await.unwrap();
}
