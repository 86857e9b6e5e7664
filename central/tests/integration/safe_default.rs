//! Central is safe by default: it listens where other machines can reach it only with a
//! policy, or when told it is insecure on purpose. Loopback and local sockets need neither.

use std::sync::Arc;

use tca_central::{CentralConfig, CentralError, Policy, StartOptions};

fn all_interfaces() -> String {
    format!(
        "tcp/0.0.0.0:{}",
        tca_link::net::free_loopback_port().unwrap()
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_network_endpoint_without_a_policy_is_refused_with_what_to_do() {
    let err = tca_central::start(StartOptions {
        listen: vec![all_interfaces()],
        ..StartOptions::default()
    })
    .await
    .err()
    .expect("an open central on every interface must be refused");
    assert!(matches!(err, CentralError::Insecure(_)), "{err}");
    let text = err.to_string();
    for hint in ["0.0.0.0", "--policy", "--insecure", "127.0.0.1"] {
        assert!(text.contains(hint), "{hint} missing from: {text}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn loopback_needs_no_policy_and_insecure_or_a_policy_opens_the_network() {
    let loopback = tca_link::net::free_loopback_endpoint().unwrap();
    let central = tca_central::start(StartOptions {
        listen: vec![loopback],
        ..StartOptions::default()
    })
    .await
    .unwrap();
    central.shutdown().await.unwrap();

    let central = tca_central::start(StartOptions {
        listen: vec![all_interfaces()],
        insecure: true,
        ..StartOptions::default()
    })
    .await
    .unwrap();
    central.shutdown().await.unwrap();

    // A policy whose router authenticates its clients (here a zenoh users file) opens it.
    let dir = tempfile::tempdir().unwrap();
    let users = dir.path().join("users.txt");
    std::fs::write(&users, "controller:zenoh-pw\n").unwrap();
    let identity = "[[identity]]\nname = \"controller\"\nsecret_sha3 = \
         \"deaa4421d5fe4c6f5045983a365c51f610280cb96b23a7721c78f32a011c823b\"\n\
         modules = [\"controller\"]\nregister = [\"*\"]\nsend = []\n";
    let with_users = format!(
        "[transport]\nzenoh_users_file = {:?}\n{identity}",
        users.display().to_string()
    );
    let central = tca_central::start(with_policy(&with_users, dir.path(), false))
        .await
        .unwrap();
    central.shutdown().await.unwrap();
}

/// Options listening on every interface with the policy `text`.
fn with_policy(text: &str, dir: &std::path::Path, insecure: bool) -> StartOptions {
    let path = dir.join("policy.toml");
    std::fs::write(&path, text).unwrap();
    StartOptions {
        listen: vec![all_interfaces()],
        config: CentralConfig {
            policy: Some(Arc::new(Policy::load(&path).unwrap())),
            ..CentralConfig::default()
        },
        insecure,
        ..StartOptions::default()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_network_endpoint_with_a_policy_that_cannot_isolate_needs_insecure() {
    // Hello secrets only: the router could not tell zenoh clients apart.
    let dir = tempfile::tempdir().unwrap();
    let text = "[[identity]]\nname = \"controller\"\nsecret_sha3 = \
         \"deaa4421d5fe4c6f5045983a365c51f610280cb96b23a7721c78f32a011c823b\"\n";
    let err = tca_central::start(with_policy(text, dir.path(), false))
        .await
        .err()
        .expect("a policy without zenoh authentication on every interface must be refused");
    assert!(matches!(err, CentralError::Unisolated(_)), "{err}");
    let text_of = err.to_string();
    for hint in [
        "0.0.0.0",
        "zenoh_users_file",
        "[transport.tls]",
        "--insecure",
        "127.0.0.1",
    ] {
        assert!(text_of.contains(hint), "{hint} missing from: {text_of}");
    }
    let central = tca_central::start(with_policy(text, dir.path(), true))
        .await
        .unwrap();
    central.shutdown().await.unwrap();
}
