//! The local link's two ends against a stand-in for central: admission by user id, frames
//! both ways, a module's end noticed, central's end noticed and a new central rejoined.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bytes::Bytes;
use tokio::sync::mpsc;

use crate::hub::testing::Recorder;
use crate::local::endpoint::current_uid;
use crate::local::{Attach, LocalEndpoint, LocalListener, LocalTransport, PeerPolicy};
use crate::outbox::{FrameReceiver, Gauge, OutboxLimits};
use crate::transport::{Presence, Transport};
use crate::{Inbox, LinkId, Taken};

/// A link the stand opened: its number, its inbox, where to send frames down it.
type StandLink = (LinkId, Arc<Inbox>, mpsc::UnboundedSender<Bytes>);

/// Central's part, reduced to the links it opened and the ones that closed.
#[derive(Default)]
struct Stand {
    hub: Arc<Recorder>,
    links: Mutex<Vec<StandLink>>,
    closed: Mutex<Vec<LinkId>>,
}

impl Attach for Stand {
    fn attach(&self) -> Option<(LinkId, Arc<Inbox>, FrameReceiver)> {
        let mut links = self.links.lock().unwrap();
        let link = links.len() as LinkId + 1;
        let inbox = Arc::new(Inbox::new(link, 100, 1 << 20, self.hub.clone()));
        let gauge = Arc::new(Gauge::new(
            link,
            OutboxLimits::new(100, 1 << 20),
            self.hub.clone(),
        ));
        let (tx, rx) = mpsc::unbounded_channel();
        links.push((link, inbox.clone(), tx));
        Some((link, inbox, FrameReceiver::metered(rx, gauge)))
    }

    fn closed(&self, link: LinkId) {
        self.closed.lock().unwrap().push(link);
    }
}

fn endpoint(test: &str) -> LocalEndpoint {
    LocalEndpoint::parse(&format!("local/unit-{}-{test}", std::process::id())).unwrap()
}

/// Waits (bounded) until `f` holds.
async fn until(what: &str, mut f: impl FnMut() -> bool) {
    tokio::time::timeout(Duration::from_secs(20), async {
        while !f() {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await
    .unwrap_or_else(|_| panic!("timed out: {what}"));
}

#[tokio::test]
async fn a_user_the_policy_does_not_name_is_refused_at_connection() {
    let e = endpoint("refuse");
    let stand = Arc::new(Stand::default());
    let other = current_uid().unwrap().wrapping_add(4242);
    let _listener =
        LocalListener::bind(&e, PeerPolicy::only([other]), 1 << 20, stand.clone()).unwrap();
    let err = LocalTransport::new(&e.to_string())
        .unwrap()
        .open()
        .await
        .unwrap_err()
        .to_string();
    assert!(err.contains("refused this connection"), "{err}");
    assert!(err.contains("may not connect"), "{err}");
    assert!(stand.links.lock().unwrap().is_empty(), "no link was opened");
}

#[tokio::test]
async fn frames_flow_both_ways_and_a_dropped_module_closes_its_link() {
    let e = endpoint("flow");
    let stand = Arc::new(Stand::default());
    let listener =
        LocalListener::bind(&e, PeerPolicy::same_user().unwrap(), 1 << 20, stand.clone()).unwrap();
    let mode = std::os::unix::fs::PermissionsExt::mode(
        &std::fs::metadata(listener.path()).unwrap().permissions(),
    );
    assert_eq!(mode & 0o777, 0o600, "the socket is the user's alone");
    let mut link = LocalTransport::new(&e.to_string())
        .unwrap()
        .open()
        .await
        .unwrap();
    link.sender.send(Bytes::from_static(b"up")).unwrap();
    until("the frame reaches the inbox", || {
        stand.links.lock().unwrap().first().is_some_and(
            |(_, inbox, _)| matches!(inbox.take().0, Some(Taken::Frame(f)) if f == "up"),
        )
    })
    .await;
    let down = stand.links.lock().unwrap()[0].2.clone();
    down.send(Bytes::from_static(b"down")).unwrap();
    assert_eq!(link.receiver.recv().await.unwrap(), "down");
    drop(link);
    until("the link is closed", || {
        stand.closed.lock().unwrap().as_slice() == [1]
    })
    .await;
}

#[tokio::test]
async fn a_module_hears_central_go_and_come_back() {
    let e = endpoint("rejoin");
    let stand = Arc::new(Stand::default());
    let listener =
        LocalListener::bind(&e, PeerPolicy::same_user().unwrap(), 1 << 20, stand.clone()).unwrap();
    let mut link = LocalTransport::new(&e.to_string())
        .unwrap()
        .open()
        .await
        .unwrap();
    let presence = link.presence.as_mut().unwrap();
    // A second central on a live socket is refused.
    let err = LocalListener::bind(&e, PeerPolicy::same_user().unwrap(), 1 << 20, stand.clone())
        .unwrap_err()
        .to_string();
    assert!(err.contains("already listening"), "{err}");
    until("the link opened", || stand.links.lock().unwrap().len() == 1).await;
    drop(listener);
    stand.links.lock().unwrap().clear();
    assert_eq!(presence.recv().await, Some(Presence::Down));
    let _again =
        LocalListener::bind(&e, PeerPolicy::same_user().unwrap(), 1 << 20, stand.clone()).unwrap();
    let up = tokio::time::timeout(Duration::from_secs(20), presence.recv()).await;
    assert_eq!(up.unwrap(), Some(Presence::Up));
    link.sender
        .send(Bytes::from_static(b"hello again"))
        .unwrap();
    until("the new central hears from the module", || {
        stand.links.lock().unwrap().first().is_some_and(
            |(_, inbox, _)| matches!(inbox.take().0, Some(Taken::Frame(f)) if f == "hello again"),
        )
    })
    .await;
}
