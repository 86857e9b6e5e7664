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

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("policy.toml");
    std::fs::write(
        &path,
        "[[identity]]\nname = \"controller\"\nsecret_sha3 = \
         \"deaa4421d5fe4c6f5045983a365c51f610280cb96b23a7721c78f32a011c823b\"\n\
         modules = [\"controller\"]\nregister = [\"*\"]\nsend = []\n",
    )
    .unwrap();
    let central = tca_central::start(StartOptions {
        listen: vec![all_interfaces()],
        config: CentralConfig {
            policy: Some(Arc::new(Policy::load(&path).unwrap())),
            ..CentralConfig::default()
        },
        ..StartOptions::default()
    })
    .await
    .unwrap();
    central.shutdown().await.unwrap();
}
