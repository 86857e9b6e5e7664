//! Central goes away and comes back, over zenoh and over the local link: the modules notice at
//! once
//! (queries in flight and task watchers fail with `CentralLost`, new sends are refused with the
//! same error instead of hanging), keep retrying, and register again with the new central on
//! the same endpoint, after which messages flow as before.

use crate::common;

use std::time::Duration;

use common::{STEP, free_endpoint, unique_local_endpoint, within};
use serde::{Deserialize, Serialize};
use tca_central::{RunningCentral, StartOptions};
use tca_module::{Connector, Module, ModuleError};

/// Echo: a query answered with its argument.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Echo(u64);
tca_messages::message!(Echo: query "echo" -> u64);

/// Slow: a query answered after a long time (to be in flight when central goes).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Slow;
tca_messages::message!(Slow: query "slow" -> u64);

/// Park: a goal whose handler never ends by itself.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Park;
tca_messages::message!(Park: goal "park");

async fn central_at(endpoint: &str) -> RunningCentral {
    tca_central::start(StartOptions {
        listen: vec![endpoint.to_owned()],
        ..StartOptions::default()
    })
    .await
    .unwrap()
}

async fn server(connector: &Connector) -> Module {
    Module::builder("server")
        .handle(|_ctx, e: Echo| async move { Ok(e.0) })
        .handle(|_ctx, _s: Slow| async move {
            tokio::time::sleep(Duration::from_secs(60)).await;
            Ok(0)
        })
        .handle(|_ctx, _p: Park| async move {
            std::future::pending::<()>().await;
            Ok(())
        })
        .connect(connector)
        .await
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn modules_rejoin_a_central_that_came_back() {
    rejoin(&free_endpoint()).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn modules_rejoin_a_central_that_came_back_over_the_local_link() {
    rejoin(&unique_local_endpoint()).await;
}

/// Central at `endpoint` stops with work in flight and starts again on the same endpoint.
async fn rejoin(endpoint: &str) {
    let central = central_at(endpoint).await;
    let connector = Connector::endpoint(endpoint);
    let server = within("server connects", server(&connector)).await;
    let client = within(
        "client connects",
        Module::builder("client").connect(&connector),
    )
    .await
    .unwrap();
    assert_eq!(within("echo", client.query(&Echo(7))).await.unwrap(), 7);

    // Work in flight when central goes: a slow query and a watched goal.
    let slow = {
        let client = client.clone();
        tokio::spawn(async move { client.query(&Slow).await })
    };
    let parked = client.send_watched(&Park, []).unwrap();
    tokio::time::sleep(Duration::from_millis(200)).await;

    central.shutdown().await.unwrap();

    // Both fail at once with CentralLost, not after the 30 s query timeout.
    let lost = within("the slow query fails", slow).await.unwrap();
    assert!(
        matches!(lost, Err(ModuleError::CentralLost)),
        "slow query: {lost:?}"
    );
    let outcome = within("the parked goal's watcher fails", parked.outcome()).await;
    assert!(
        matches!(outcome, Err(ModuleError::CentralLost)),
        "parked goal: {outcome:?}"
    );
    // The client noticed (its calls failed); the server, which had nothing in flight,
    // notices as soon as the liveliness of central's session goes (over zenoh) or its socket
    // ends (over the local link), a moment later.
    tokio::time::timeout(Duration::from_secs(2), async {
        while client.is_online() || server.is_online() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("both modules see central gone within 2 s");
    // Sends while central is gone are refused, with the reason.
    let refused = client.goal(&Park).unwrap_err();
    assert!(matches!(refused, ModuleError::CentralLost), "{refused:?}");
    assert!(
        refused.to_string().contains("registers again by itself"),
        "{refused}"
    );
    assert!(matches!(
        within("query while central is gone", client.query(&Echo(1))).await,
        Err(ModuleError::CentralLost)
    ));

    // Central comes back on the same endpoint: both modules register again by themselves.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let central = central_at(endpoint).await;
    assert!(
        client.wait_online(STEP).await,
        "the client did not rejoin central"
    );
    assert!(
        server.wait_online(STEP).await,
        "the server did not rejoin central"
    );
    assert_eq!(
        within("echo after rejoining", client.query(&Echo(42)))
            .await
            .unwrap(),
        42
    );
    let registry = within("registry", client.registry()).await.unwrap();
    assert!(
        registry.entries.iter().any(|e| e.name.as_str() == "echo"),
        "the server's handlers are registered again: {registry:?}"
    );
    assert_eq!(registry.modules.len(), 2, "{registry:?}");
    // Goals flow again too: the new central keeps the new goal's node while it runs.
    let parked = client.send_watched(&Park, []).unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    let tree = within("tree", client.tree()).await.unwrap();
    assert!(tree.text.contains("park"), "{}", tree.text);
    drop(parked);
    central.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn in_process_modules_never_go_offline() {
    let (central, connector) = tca_testkit::in_process_central().await;
    let server = within("server connects", server(&connector)).await;
    assert!(server.is_online());
    assert!(server.wait_online(Duration::from_millis(10)).await);
    central.shutdown().await.unwrap();
    within("link closes", server.closed()).await;
    let err = server.goal(&Park).unwrap_err();
    assert!(matches!(err, ModuleError::Disconnected), "{err:?}");
}

/// Resume: a goal whose first delivery never ends and whose redelivery ends at once.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Resume;
tca_messages::message!(Resume: goal "resume");

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_watched_goal_survives_a_crash_of_a_central_that_keeps_a_journal() {
    journaled_crash(&unique_local_endpoint()).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_watched_goal_survives_a_crash_of_a_central_that_keeps_a_journal_over_zenoh() {
    journaled_crash(&free_endpoint()).await;
}

/// Central on a journal crashes while a goal runs; a central started on the same journal
/// delivers the goal again, marked, and the sender's watcher, which waited, gets its end.
async fn journaled_crash(endpoint: &str) {
    let dir = tempfile::tempdir().unwrap();
    let options = StartOptions {
        listen: vec![endpoint.to_owned()],
        journal: Some(dir.path().join("central.journal")),
        ..StartOptions::default()
    };
    let central = tca_central::start(options.clone()).await.unwrap();
    assert!(central.restored().is_none(), "a fresh journal");
    let connector = Connector::endpoint(endpoint);
    let (tx, mut deliveries) = tokio::sync::mpsc::unbounded_channel();
    let server = within(
        "server connects",
        Module::builder("server")
            .handle(move |ctx, _r: Resume| {
                let _ = tx.send(ctx.redelivery());
                async move {
                    if ctx.redelivery() == 0 {
                        std::future::pending::<()>().await;
                    }
                    Ok(())
                }
            })
            .connect(&connector),
    )
    .await
    .unwrap();
    let client = within(
        "client connects",
        Module::builder("client").connect(&connector),
    )
    .await
    .unwrap();
    let resumed = client.send_watched(&Resume, []).unwrap();
    let first = within("first delivery", deliveries.recv()).await;
    assert_eq!(first, Some(0));

    central.crash().await;
    tokio::time::timeout(Duration::from_secs(2), async {
        while client.is_online() || server.is_online() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("both modules see central gone within 2 s");

    let central = tca_central::start(options).await.unwrap();
    let restored = central.restored().expect("restored from the journal");
    assert!(
        restored.summary.contains("1 live task node"),
        "{}",
        restored.summary
    );
    assert!(server.wait_online(STEP).await && client.wait_online(STEP).await);
    let again = within("delivered again", deliveries.recv()).await;
    assert_eq!(again, Some(1), "the redelivery is marked");
    let outcome = within("the watcher gets the end", resumed.outcome()).await;
    assert_eq!(
        outcome.unwrap(),
        tca_messages::control::TaskOutcome::Achieved
    );
    // A clean stop ends the journal: the next central starts afresh.
    central.shutdown().await.unwrap();
    assert!(!dir.path().join("central.journal").exists());
}
