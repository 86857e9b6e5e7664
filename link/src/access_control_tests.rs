//! The router's access control, with plain zenoh sessions on both sides: a router configured
//! as central's is (users file, the policy's identities), and clients logged in as one
//! identity each. Each identity publishes, subscribes and declares tokens only under its own
//! keys; whatever else it tries never reaches the router's own session or another client, and
//! the router counts it.

use std::sync::Arc;
use std::time::Duration;

use crate::zenoh::{
    CENTRAL_ALIVE_KEY, RouterSecurity, ZenohLogin, acl, alive_key, client_config_with_login,
    down_key, router_config_secured, up_key, up_key_pattern,
};
use zenoh::sample::SampleKind;

fn free_endpoint() -> String {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    format!("tcp/127.0.0.1:{port}")
}

/// Counts what a callback sees, by key.
#[derive(Clone, Default)]
struct Seen(Arc<std::sync::Mutex<Vec<(String, SampleKind)>>>);

impl Seen {
    fn note(&self, sample: &zenoh::sample::Sample) {
        self.0
            .lock()
            .unwrap()
            .push((sample.key_expr().to_string(), sample.kind()));
    }
    fn keys(&self) -> Vec<String> {
        self.0
            .lock()
            .unwrap()
            .iter()
            .map(|(k, _)| k.clone())
            .collect()
    }
    fn count(&self, key: &str) -> usize {
        self.keys().iter().filter(|k| *k == key).count()
    }
}

async fn client(endpoint: &str, user: &str, password: &str) -> zenoh::Session {
    let login = ZenohLogin::new(user, password);
    let config = client_config_with_login(&[endpoint.to_owned()], Some(&login)).unwrap();
    zenoh::open(config).await.unwrap()
}

/// A router configured as central's, with these logins (each user an identity), and its
/// endpoint.
async fn router(dir: &std::path::Path, logins: &[(&str, &str)]) -> (zenoh::Session, String) {
    let users = dir.join("users.txt");
    let text: String = logins.iter().map(|(u, p)| format!("{u}:{p}\n")).collect();
    std::fs::write(&users, text).unwrap();
    let endpoint = free_endpoint();
    let security = RouterSecurity {
        users_file: Some(users),
        tls: None,
        identities: logins.iter().map(|(u, _)| u.to_string()).collect(),
    };
    let config = router_config_secured(std::slice::from_ref(&endpoint), &security).unwrap();
    (zenoh::open(config).await.unwrap(), endpoint)
}

async fn settle() {
    tokio::time::sleep(Duration::from_millis(300)).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn each_identity_is_confined_to_its_own_keys() {
    let dir = tempfile::tempdir().unwrap();
    let (router, endpoint) = router(dir.path(), &[("gait", "pg"), ("spy", "ps")]).await;
    // The router's session listens as central does: per identity, and to every token.
    let at_router = Seen::default();
    let mut subscribers = Vec::new();
    for who in ["gait", "spy"] {
        let seen = at_router.clone();
        subscribers.push(
            router
                .declare_subscriber(up_key_pattern(who))
                .callback(move |s| seen.note(&s))
                .await
                .unwrap(),
        );
    }
    let tokens_at_router = Seen::default();
    let seen = tokens_at_router.clone();
    let _tokens = router
        .liveliness()
        .declare_subscriber("tca/**")
        .callback(move |s| seen.note(&s))
        .await
        .unwrap();

    let gait = client(&endpoint, "gait", "pg").await;
    // The spy speaks with one session and listens with another (a session hears its own
    // publications and tokens locally, without the router).
    let spy = client(&endpoint, "spy", "ps").await;
    let ears = client(&endpoint, "spy", "ps").await;
    let refused_at_start = acl::refusals(&router).await.unwrap();

    // gait: its own keys work both ways.
    let from_router = Seen::default();
    let seen = from_router.clone();
    let _gait_down = gait
        .declare_subscriber(down_key("gait", "g1"))
        .callback(move |s| seen.note(&s))
        .await
        .unwrap();
    let central_seen = Seen::default();
    let seen = central_seen.clone();
    let _gait_watch = gait
        .liveliness()
        .declare_subscriber(CENTRAL_ALIVE_KEY)
        .history(true)
        .callback(move |s| seen.note(&s))
        .await
        .unwrap();
    let _gait_token = gait
        .liveliness()
        .declare_token(alive_key("gait", "g1"))
        .await
        .unwrap();

    // The spy listens to everything and tries to speak for gait and for central.
    let spied = Seen::default();
    let seen = spied.clone();
    let _spy_all = ears
        .declare_subscriber("tca/**")
        .callback(move |s| seen.note(&s))
        .await
        .unwrap();
    let seen = spied.clone();
    let _spy_tokens = ears
        .liveliness()
        .declare_subscriber("tca/**")
        .history(true)
        .callback(move |s| seen.note(&s))
        .await
        .unwrap();
    let _fake_central = spy
        .liveliness()
        .declare_token(CENTRAL_ALIVE_KEY)
        .await
        .unwrap();
    let _fake_gait = spy
        .liveliness()
        .declare_token(alive_key("gait", "s1"))
        .await
        .unwrap();
    let _own_token = spy
        .liveliness()
        .declare_token(alive_key("spy", "s1"))
        .await
        .unwrap();
    settle().await;
    // The tokens the router's session has seen before it declares its own.
    let tokens = tokens_at_router.keys();
    // Central's token is declared after the spy's attempt: the watcher sees only this one.
    let _central = router
        .liveliness()
        .declare_token(CENTRAL_ALIVE_KEY)
        .await
        .unwrap();
    settle().await;

    for i in 0..10u8 {
        gait.put(up_key("gait", "g1"), vec![i]).await.unwrap();
        router.put(down_key("gait", "g1"), vec![i]).await.unwrap();
        spy.put(up_key("gait", "g1"), vec![i]).await.unwrap();
        spy.put(up_key("gait", "s1"), vec![i]).await.unwrap();
        spy.put(down_key("gait", "g1"), vec![i]).await.unwrap();
        spy.put(up_key("spy", "s1"), vec![i]).await.unwrap();
    }
    settle().await;

    // gait's frames reach the router, and only gait's own 10 on its key; the router's reach
    // gait, and only the router's.
    assert_eq!(
        at_router.count(&up_key("gait", "g1")),
        10,
        "{:?}",
        at_router.keys()
    );
    assert_eq!(at_router.count(&up_key("gait", "s1")), 0);
    assert_eq!(from_router.count(&down_key("gait", "g1")), 10);
    // The spy's own key works (so its session is up and publishing).
    assert_eq!(at_router.count(&up_key("spy", "s1")), 10);
    // It heard nothing of anyone: neither frames nor tokens (not even its own other
    // session's).
    assert!(spied.keys().is_empty(), "the spy saw {:?}", spied.keys());
    // Its tokens as central or gait never reached the router; its own did.
    assert!(tokens.contains(&alive_key("gait", "g1")), "{tokens:?}");
    assert!(tokens.contains(&alive_key("spy", "s1")), "{tokens:?}");
    assert!(!tokens.contains(&alive_key("gait", "s1")), "{tokens:?}");
    assert!(
        !tokens.contains(&CENTRAL_ALIVE_KEY.to_owned()),
        "{tokens:?}"
    );
    // gait sees central's token come once: the spy's never existed at the router.
    assert_eq!(
        central_seen.count(CENTRAL_ALIVE_KEY),
        1,
        "{:?}",
        central_seen.keys()
    );

    // The router counted the refusals: 30 frames, 2 subscriptions and 2 tokens at least.
    let refused = acl::refusals(&router).await.unwrap() - refused_at_start;
    assert!(refused >= 34, "the router counted {refused} refusals");
    eprintln!("refused by the router's access control: {refused}");

    for s in [gait, spy, ears, router] {
        s.close().await.unwrap();
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_user_outside_the_dictionary_cannot_open_a_session() {
    let dir = tempfile::tempdir().unwrap();
    let (router, endpoint) = router(dir.path(), &[("gait", "pg")]).await;
    let config = crate::zenoh::client_config(std::slice::from_ref(&endpoint)).unwrap();
    assert!(zenoh::open(config).await.is_err(), "no login was admitted");
    let wrong = ZenohLogin::new("gait", "guess");
    let config = client_config_with_login(&[endpoint], Some(&wrong)).unwrap();
    assert!(
        zenoh::open(config).await.is_err(),
        "a wrong password was admitted"
    );
    router.close().await.unwrap();
}
