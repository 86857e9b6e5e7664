//! Slow links: congestion holds new work (counted against its senders), a drained outbox gets
//! it in order and only as much as fits, and a link past its bound is disconnected.

use super::*;

/// Central with outboxes of 8 frames: congested at 4, disconnected past 8.
fn harness(max_queued_messages: u32) -> Harness {
    Harness::with(CentralConfig {
        max_outbox_frames: 8,
        max_queued_messages,
        ..CentralConfig::default()
    })
}

fn level(frames: u64) -> OutboxUse {
    OutboxUse {
        frames,
        bytes: frames * 100,
    }
}

/// Everything the core wants done for `event`, not only the sends.
fn actions(h: &mut Harness, event: Event) -> Vec<Action> {
    let mut out = Vec::new();
    h.central.handle(h.now, event, &mut out);
    out
}

fn frame(env: &Envelope, link: LinkId) -> Event {
    Event::Frame(link, Bytes::from(encode(env).unwrap()))
}

fn sent_to(actions: &[Action], link: LinkId) -> Vec<Envelope> {
    actions
        .iter()
        .filter_map(|a| match a {
            Action::Send(l, f) if *l == link => Some(decode(f, usize::MAX).unwrap()),
            _ => None,
        })
        .collect()
}

fn measured(actions: &[Action], link: LinkId) -> bool {
    actions
        .iter()
        .any(|a| matches!(a, Action::Measure(l) if *l == link))
}

fn queued(h: &Harness, module: &str) -> u64 {
    h.central
        .queued_by(&ModuleName::new(module).unwrap())
        .messages
}

/// "slow" on link 1 handles the query `ask`, the inform `note` and the goal `job`; "fast" on
/// link 2 handles the query `pose`. Both outboxes measured empty.
fn two_modules(h: &mut Harness) {
    h.connect(1, "slow", 1);
    h.register::<Target>(1, "slow", "ask", Class::Query, false);
    h.register::<Target>(1, "slow", "note", Class::Inform, false);
    h.register::<Target>(1, "slow", "job", Class::Goal, false);
    h.connect(2, "fast", 1);
    h.register::<Target>(2, "fast", "pose", Class::Query, false);
    for link in [1, 2] {
        h.step(Event::OutboxLevel(link, OutboxUse::default()));
    }
}

#[test]
fn a_congested_link_gets_no_new_work_until_it_drains_then_only_what_fits() {
    let mut h = harness(1024);
    two_modules(&mut h);
    // Three informs go out; the fourth reaches half the bound: the core asks for a measurement.
    for i in 0..4 {
        let note = h.envelope(2, "fast", Class::Inform, "note", target(f64::from(i)));
        let done = actions(&mut h, frame(&note, 2));
        assert_eq!(sent_to(&done, 1).len(), 1, "inform {i} delivered");
        assert_eq!(measured(&done, 1), i == 3, "measured at the fourth only");
    }
    // Until the measurement says otherwise, new work for slow is held, charged to fast.
    let note = h.envelope(2, "fast", Class::Inform, "note", target(4.0));
    let ask = h.envelope(2, "fast", Class::Query, "ask", target(5.0));
    let mut job = h.envelope(2, "fast", Class::Goal, "job", target(6.0));
    job.options.notify = true;
    for env in [&note, &ask, &job] {
        assert!(h.send(2, env).is_empty(), "{} held", env.name);
    }
    assert_eq!(queued(&h, "fast"), 3);
    // Answers to slow's own requests still reach it.
    let pose = h.envelope(1, "slow", Class::Query, "pose", target(0.0));
    let sent = h.send(1, &pose);
    assert_eq!((sent.len(), sent[0].0), (1, 2), "slow's query reaches fast");
    let mut reply = h.envelope(
        2,
        "fast",
        Class::Reply,
        "pose",
        encode_data(&1.0f64).unwrap(),
    );
    reply.correlation = Some(pose.id);
    let sent = h.send(2, &reply);
    assert_eq!((sent.len(), sent[0].0), (1, 1), "the reply reaches slow");
    // Measured congested: it stays so; the driver reports again once drained.
    let done = actions(&mut h, Event::OutboxLevel(1, level(5)));
    assert!(sent_to(&done, 1).is_empty() && !measured(&done, 1));
    assert_eq!(h.central.counters().congestions, 1);
    // Drained to 2 frames: held work goes out in order, up to half the bound again.
    let done = actions(&mut h, Event::OutboxLevel(1, level(2)));
    let names: Vec<_> = sent_to(&done, 1).iter().map(|e| e.id).collect();
    assert_eq!(names, vec![note.id, ask.id], "two fit before the mark");
    assert!(measured(&done, 1));
    assert_eq!(queued(&h, "fast"), 1, "the goal still waits");
    // Drained again: the goal is dispatched.
    let done = actions(&mut h, Event::OutboxLevel(1, level(0)));
    let sent = sent_to(&done, 1);
    assert_eq!(sent.len(), 1);
    assert_eq!((sent[0].id, sent[0].class), (job.id, Class::Goal));
    assert_eq!(queued(&h, "fast"), 0);
    assert_eq!(h.central.recount_queued(), h.central.queued_totals());
    // And it ends like any goal.
    let sent = h.done(1, "slow", &sent[0], true);
    assert!(
        sent.iter()
            .any(|(l, e)| *l == 2 && e.name.as_str() == names::TASK_ENDED)
    );
}

#[test]
fn senders_to_a_congested_link_meet_their_queue_limit() {
    let mut h = harness(2);
    two_modules(&mut h);
    h.step(Event::OutboxLevel(1, level(6)));
    let mut refused = Vec::new();
    for i in 0..3 {
        let note = h.envelope(2, "fast", Class::Inform, "note", target(f64::from(i)));
        refused.push(h.send(2, &note));
    }
    assert!(refused[0].is_empty() && refused[1].is_empty(), "held");
    let err = error_of(&refused[2][0].1);
    assert!(
        matches!(&err, RouteError::OverLimit { setting, .. } if setting == "max_queued_messages"),
        "{err}"
    );
    // Once slow has read its outbox, the two held informs arrive and fast may send again.
    let sent = h.step(Event::OutboxLevel(1, level(0)));
    assert_eq!(sent.iter().filter(|(l, _)| *l == 1).count(), 2);
    let note = h.envelope(2, "fast", Class::Inform, "note", target(9.0));
    assert_eq!(h.send(2, &note)[0].0, 1, "delivered at once");
}

#[test]
fn a_link_past_its_bound_is_disconnected_and_its_work_waits_for_it() {
    let mut h = harness(1024);
    two_modules(&mut h);
    let job = h.envelope(2, "fast", Class::Goal, "job", target(1.0));
    assert_eq!(h.send(2, &job)[0].0, 1, "running on slow");
    let ask = h.envelope(2, "fast", Class::Query, "ask", target(2.0));
    assert_eq!(h.send(2, &ask)[0].0, 1, "open at slow");
    let done = actions(&mut h, Event::OutboxFull(1, level(9)));
    // The last frame to slow says why; then the link closes.
    let last = sent_to(&done, 1);
    assert_eq!(last.len(), 1);
    let why = error_of(&last[0]).to_string();
    assert!(
        why.contains("too slow") && why.contains("max_outbox_frames = 8"),
        "{why}"
    );
    assert!(done.iter().any(|a| matches!(a, Action::Close(1))));
    // As for any module that goes down: the query fails at its asker...
    let to_fast = sent_to(&done, 2);
    assert_eq!(to_fast[0].correlation, Some(ask.id));
    assert!(matches!(
        error_of(&to_fast[0]),
        RouteError::HandlerDied { .. }
    ));
    assert_eq!(h.central.counters().too_slow, 1);
    assert_eq!(
        h.central.connected_modules(),
        vec![ModuleName::new("fast").unwrap()]
    );
    // ...and the goal runs again when slow is back.
    h.connect(3, "slow", 1);
    let sent = h.register_sent::<Target>(3, "slow", "job", Class::Goal);
    let again = sent
        .iter()
        .find(|(_, e)| e.id == job.id)
        .expect("redelivered");
    assert_eq!((again.0, again.1.redelivery), (3, 1));
    // A late report about the closed link changes nothing.
    assert!(actions(&mut h, Event::OutboxFull(1, level(10))).is_empty());
}
