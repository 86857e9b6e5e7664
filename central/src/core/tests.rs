//! Tests of the core without any transport: events in, actions out.

use std::time::Duration;

use bytes::Bytes;
use serde::{Deserialize, Serialize};
use tca_messages::control::{
    self, Hello, Register, RegisterOutcome, Registration, TaskEnded, TaskOutcome, Welcome, names,
};
use tca_messages::*;

use super::*;

// Tests of slow links, with this file's harness.
#[path = "congestion_tests.rs"]
mod congestion;

// Taps and the command line's task controls, with this file's harness.
#[path = "taps_tests.rs"]
mod taps;

const MS: u64 = 1_000_000;

#[derive(Serialize, Deserialize)]
struct Target {
    y_m: f64,
}

#[derive(Serialize, Deserialize)]
struct TargetDeg {
    y_deg: f64,
}

struct Harness {
    central: Central,
    now: u64,
    seq: u32,
}

impl Harness {
    fn new() -> Self {
        Self::with(CentralConfig {
            max_waiting: 3,
            max_wait: Duration::from_millis(500),
            ..CentralConfig::default()
        })
    }

    fn with(config: CentralConfig) -> Self {
        Harness {
            central: Central::new(config),
            now: 1_000 * MS,
            seq: 0,
        }
    }

    fn step(&mut self, event: Event) -> Vec<(LinkId, Envelope)> {
        let mut out = Vec::new();
        self.central.handle(self.now, event, &mut out);
        out.into_iter()
            .filter_map(|a| match a {
                Action::Send(link, frame) => Some((link, decode(&frame, usize::MAX).unwrap())),
                _ => None,
            })
            .collect()
    }

    fn envelope(
        &mut self,
        link: LinkId,
        module: &str,
        class: Class,
        name: &str,
        data: Vec<u8>,
    ) -> Envelope {
        self.seq += 1;
        Envelope {
            id: MessageId::new(link, self.seq),
            class,
            name: MessageName::new(name).unwrap(),
            sender: ModuleName::new(module).unwrap(),
            context: None,
            node: None,
            correlation: None,
            cause: None,
            timestamp_ns: self.now,
            options: SendOptions::default(),
            redelivery: 0,
            data,
        }
    }

    fn send(&mut self, link: LinkId, env: &Envelope) -> Vec<(LinkId, Envelope)> {
        self.step(Event::Frame(link, Bytes::from(encode(env).unwrap())))
    }

    fn connect(&mut self, link: LinkId, module: &str, capacity: u32) -> Vec<(LinkId, Envelope)> {
        self.connect_from(link, module, capacity, "test", 1)
    }

    fn connect_from(
        &mut self,
        link: LinkId,
        module: &str,
        capacity: u32,
        host: &str,
        pid: u32,
    ) -> Vec<(LinkId, Envelope)> {
        self.step(Event::Opened(link));
        let hello = Hello {
            module: ModuleName::new(module).unwrap(),
            capacity,
            pid,
            host: host.into(),
            simulated_time: false,
        };
        let mut env = self.envelope(
            link,
            module,
            Class::Control,
            names::HELLO,
            encode_data(&hello).unwrap(),
        );
        env.id = MessageId::new(0, 0);
        self.send(link, &env)
    }

    fn register<T: serde::de::DeserializeOwned>(
        &mut self,
        link: LinkId,
        module: &str,
        name: &str,
        class: Class,
        replace: bool,
    ) -> RegisterOutcome {
        let reg = Registration {
            name: MessageName::new(name).unwrap(),
            class,
            format: DataFormat::of::<T>().unwrap(),
            reply: (class == Class::Query).then(|| DataFormat::of::<f64>().unwrap()),
            replace,
        };
        let data = encode_data(&Register { entries: vec![reg] }).unwrap();
        let env = self.envelope(link, module, Class::Control, names::REGISTER, data);
        let sent = self.send(link, &env);
        let reply = sent
            .iter()
            .find(|(l, e)| *l == link && e.class == Class::Reply && e.correlation == Some(env.id))
            .expect("registration answered");
        decode_data(&reply.1.data).unwrap()
    }

    fn register_sent<T: serde::de::DeserializeOwned>(
        &mut self,
        link: LinkId,
        module: &str,
        name: &str,
        class: Class,
    ) -> Vec<(LinkId, Envelope)> {
        let reg = Registration {
            name: MessageName::new(name).unwrap(),
            class,
            format: DataFormat::of::<T>().unwrap(),
            reply: (class == Class::Query).then(|| DataFormat::of::<f64>().unwrap()),
            replace: false,
        };
        let data = encode_data(&Register { entries: vec![reg] }).unwrap();
        let env = self.envelope(link, module, Class::Control, names::REGISTER, data);
        self.send(link, &env)
    }

    fn done(
        &mut self,
        link: LinkId,
        module: &str,
        task: &Envelope,
        ok: bool,
    ) -> Vec<(LinkId, Envelope)> {
        let (class, data) = if ok {
            (Class::Success, encode_data(&()).unwrap())
        } else {
            (
                Class::Failure,
                encode_data(&Failure {
                    reason: "no".into(),
                })
                .unwrap(),
            )
        };
        let mut env = self.envelope(link, module, class, task.name.as_str(), data);
        env.correlation = Some(task.id);
        self.send(link, &env)
    }
}

fn error_of(env: &Envelope) -> RouteError {
    assert_eq!(env.class, Class::Error, "{env:?}");
    decode_data(&env.data).unwrap()
}

fn target(y: f64) -> Vec<u8> {
    encode_data(&Target { y_m: y }).unwrap()
}

#[test]
fn hello_is_welcomed_and_a_second_module_of_the_same_name_refused() {
    let mut h = Harness::new();
    let sent = h.connect(1, "ctl", 1);
    assert_eq!(sent.len(), 1);
    let welcome: Welcome = decode_data(&sent[0].1.data).unwrap();
    assert_eq!(welcome.link, 1);
    let sent = h.connect(2, "ctl", 1);
    let err = error_of(&sent[0].1);
    assert!(err.to_string().contains("already connected"), "{err}");
    assert_eq!(h.central.connected_modules().len(), 1);
}

#[test]
fn a_module_whose_process_is_gone_is_replaced_by_its_restart() {
    let mut h = Harness::new();
    let host = tca_messages::control::this_host();
    let mut old = std::process::Command::new("sleep")
        .arg("30")
        .spawn()
        .unwrap();
    h.connect_from(1, "ctl", 1, &host, old.id());
    // Same name while the old process lives: refused.
    let sent = h.connect_from(2, "ctl", 1, &host, std::process::id());
    assert!(
        error_of(&sent[0].1)
            .to_string()
            .contains("already connected")
    );
    // The old process gone, its link not yet dropped: the new hello takes over.
    old.kill().unwrap();
    old.wait().unwrap();
    let sent = h.connect_from(3, "ctl", 1, &host, std::process::id());
    let welcome = sent
        .iter()
        .find(|(link, _)| *link == 3)
        .map(|(_, env)| decode_data::<Welcome>(&env.data).unwrap())
        .expect("a welcome on link 3");
    assert_eq!(welcome.link, 3);
    assert_eq!(h.central.connected_modules().len(), 1);
}

#[test]
fn the_first_frame_must_be_a_hello() {
    let mut h = Harness::new();
    h.step(Event::Opened(4));
    let env = h.envelope(4, "x", Class::Query, "q", vec![]);
    let mut out = Vec::new();
    h.central.handle(
        h.now,
        Event::Frame(4, Bytes::from(encode(&env).unwrap())),
        &mut out,
    );
    assert!(out.iter().any(|a| matches!(a, Action::Close(4))));
}

#[test]
fn queries_are_routed_and_answered() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.connect(2, "gait", 1);
    assert!(
        h.register::<Target>(1, "ctl", "bodyPosition", Class::Query, false)
            .refused
            .is_empty()
    );
    let q = h.envelope(2, "gait", Class::Query, "bodyPosition", target(1.0));
    let sent = h.send(2, &q);
    assert_eq!(sent.len(), 1);
    assert_eq!(sent[0].0, 1, "delivered to the handler");
    assert_eq!(sent[0].1.id, q.id);
    let mut reply = h.envelope(
        1,
        "ctl",
        Class::Reply,
        "bodyPosition",
        encode_data(&2.5f64).unwrap(),
    );
    reply.correlation = Some(q.id);
    let sent = h.send(1, &reply);
    assert_eq!(sent.len(), 1);
    assert_eq!(sent[0].0, 2, "reply goes back to the asker");
    assert_eq!(decode_data::<f64>(&sent[0].1.data).unwrap(), 2.5);
}

#[test]
fn unknown_names_get_an_error_with_a_suggestion() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.register::<Target>(1, "ctl", "moveBase", Class::Command, false);
    let c = h.envelope(1, "ctl", Class::Command, "move_base", target(1.0));
    let sent = h.send(1, &c);
    let err = error_of(&sent[0].1);
    assert!(matches!(err, RouteError::UnknownMessage { .. }));
    assert!(
        err.to_string().contains("did you mean \"moveBase\""),
        "{err}"
    );
    assert_eq!(sent[0].1.correlation, Some(c.id));
}

#[test]
fn a_differing_format_is_refused_naming_the_field() {
    let mut h = Harness::new();
    h.connect(1, "a", 1);
    h.connect(2, "b", 1);
    h.register::<Target>(1, "a", "moveBase", Class::Command, false);
    let outcome = h.register::<TargetDeg>(2, "b", "moveBase", Class::Command, true);
    assert_eq!(outcome.refused.len(), 1);
    let reason = &outcome.refused[0].1;
    assert!(reason.contains("$.y_m"), "{reason}");
    assert!(reason.contains("y_deg"), "{reason}");
}

#[test]
fn a_second_handler_needs_replace_and_then_takes_over() {
    let mut h = Harness::new();
    h.connect(1, "sim", 1);
    h.connect(2, "real", 1);
    h.connect(3, "gait", 1);
    h.register::<Target>(1, "sim", "moveBase", Class::Command, false);
    let refused = h.register::<Target>(2, "real", "moveBase", Class::Command, false);
    assert!(
        refused.refused[0]
            .1
            .contains("already handled by module sim")
    );
    let ok = h.register::<Target>(2, "real", "moveBase", Class::Command, true);
    assert!(ok.refused.is_empty());
    let c = h.envelope(3, "gait", Class::Command, "moveBase", target(1.0));
    let sent = h.send(3, &c);
    assert_eq!(sent[0].0, 2, "the replacement handles it");
}

#[test]
fn commands_wait_for_capacity_and_run_in_order() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.connect(2, "gait", 1);
    h.register::<Target>(1, "ctl", "moveBase", Class::Command, false);
    let a = h.envelope(2, "gait", Class::Command, "moveBase", target(1.0));
    let b = h.envelope(2, "gait", Class::Command, "moveBase", target(2.0));
    let sent = h.send(2, &a);
    assert_eq!(sent.len(), 1);
    assert!(sent[0].1.node.is_some(), "delivered with its node");
    let sent = h.send(2, &b);
    assert!(sent.is_empty(), "b waits: capacity 1");
    let sent = h.done(1, "ctl", &a, true);
    assert_eq!(sent.len(), 1);
    assert_eq!(sent[0].1.id, b.id, "b goes once a is done");
}

#[test]
fn messages_wait_for_a_module_that_is_down_and_are_delivered_when_it_returns() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.connect(2, "gait", 1);
    h.register::<Target>(1, "ctl", "bodyPosition", Class::Query, false);
    h.step(Event::Closed(1));
    let q = h.envelope(2, "gait", Class::Query, "bodyPosition", target(0.0));
    assert!(h.send(2, &q).is_empty(), "held");
    h.now += 100 * MS;
    h.connect(3, "ctl", 1);
    let sent = h.register_sent::<Target>(3, "ctl", "bodyPosition", Class::Query);
    let delivered = sent
        .iter()
        .find(|(_, e)| e.id == q.id)
        .expect("held query delivered");
    assert_eq!(delivered.0, 3);
    assert!(
        h.central.next_deadline().is_none(),
        "nothing is held any more"
    );
}

#[test]
fn held_messages_are_bounded_by_count_and_age() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.connect(2, "gait", 1);
    h.register::<Target>(1, "ctl", "bodyPosition", Class::Query, false);
    h.step(Event::Closed(1));
    for _ in 0..3 {
        let q = h.envelope(2, "gait", Class::Query, "bodyPosition", target(0.0));
        assert!(h.send(2, &q).is_empty());
    }
    let q = h.envelope(2, "gait", Class::Query, "bodyPosition", target(0.0));
    let err = error_of(&h.send(2, &q)[0].1);
    assert!(
        matches!(err, RouteError::QueueFull { limit: 3, .. }),
        "{err}"
    );
    let deadline = h.central.next_deadline().unwrap();
    assert_eq!(deadline, h.now + 500 * MS);
    h.now = deadline;
    let sent = h.step(Event::Tick);
    assert_eq!(sent.len(), 3);
    for (link, env) in sent {
        assert_eq!(link, 2);
        assert!(matches!(error_of(&env), RouteError::Expired { .. }));
    }
}

#[test]
fn a_query_in_flight_fails_at_once_when_its_handler_dies() {
    let mut h = Harness::new();
    h.connect(1, "ltm", 1);
    h.connect(2, "gait", 1);
    h.register::<Target>(1, "ltm", "map", Class::Query, false);
    let q = h.envelope(2, "gait", Class::Query, "map", target(0.0));
    h.send(2, &q);
    let sent = h.step(Event::Closed(1));
    let err = error_of(&sent[0].1);
    assert!(matches!(err, RouteError::HandlerDied { .. }), "{err}");
    assert_eq!(sent[0].1.correlation, Some(q.id));
}

#[test]
fn a_running_command_is_redelivered_after_its_handler_restarts() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.connect(2, "gait", 1);
    h.register::<Target>(1, "ctl", "moveBase", Class::Command, false);
    let mut c = h.envelope(2, "gait", Class::Command, "moveBase", target(3.0));
    c.options.notify = true;
    assert_eq!(h.send(2, &c).len(), 1);
    h.step(Event::Closed(1));
    h.connect(3, "ctl", 1);
    let sent = h.register_sent::<Target>(3, "ctl", "moveBase", Class::Command);
    let again = sent
        .iter()
        .find(|(_, e)| e.id == c.id)
        .expect("redelivered");
    assert_eq!(again.0, 3);
    assert_eq!(again.1.redelivery, 1);
    let sent = h.done(3, "ctl", &c, true);
    let ended = sent
        .iter()
        .find(|(_, e)| e.name.as_str() == names::TASK_ENDED)
        .unwrap();
    assert_eq!(ended.0, 2);
    let ended: TaskEnded = decode_data(&ended.1.data).unwrap();
    assert_eq!(ended.outcome, TaskOutcome::Achieved);
}

#[test]
fn malformed_frames_get_an_error_and_central_keeps_serving() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.connect(2, "gait", 1);
    h.register::<Target>(1, "ctl", "bodyPosition", Class::Query, false);
    for junk in [&b""[..], &[9, 9, 9][..], &[1, 0xff, 0xff][..]] {
        let sent = h.step(Event::Frame(2, Bytes::copy_from_slice(junk)));
        assert!(matches!(error_of(&sent[0].1), RouteError::BadFrame { .. }));
    }
    let q = h.envelope(2, "gait", Class::Query, "bodyPosition", target(0.0));
    assert_eq!(h.send(2, &q)[0].0, 1, "still routing");
    assert_eq!(h.central.counters().bad_frames, 3);
}

#[test]
fn frames_over_the_size_limit_are_refused() {
    let mut h = Harness::with(CentralConfig {
        max_frame_bytes: 64,
        ..CentralConfig::default()
    });
    h.connect(1, "ctl", 1);
    let big = h.envelope(1, "ctl", Class::Inform, "x", vec![0; 200]);
    let sent = h.send(1, &big);
    let err = error_of(&sent[0].1);
    assert!(err.to_string().contains("exceeds the limit"), "{err}");
}

#[test]
fn forged_sender_and_ids_are_refused() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.connect(2, "gait", 1);
    let forged = h.envelope(2, "ctl", Class::Inform, "x", vec![]);
    let err = error_of(&h.send(2, &forged)[0].1);
    assert!(err.to_string().contains("belongs to module gait"), "{err}");
    let mut wrong_id = h.envelope(2, "gait", Class::Inform, "x", vec![]);
    wrong_id.id = MessageId::new(1, 99);
    let err = error_of(&h.send(2, &wrong_id)[0].1);
    assert!(err.to_string().contains("link's number"), "{err}");
}

#[derive(Serialize, Deserialize)]
struct Failed {
    why: String,
}

/// Sends a task in the context of `context` and returns what central sent.
fn task(
    h: &mut Harness,
    link: LinkId,
    module: &str,
    class: Class,
    name: &str,
    context: Option<NodeId>,
    notify: bool,
) -> (Envelope, Vec<(LinkId, Envelope)>) {
    let mut e = h.envelope(link, module, class, name, target(1.0));
    e.context = context;
    e.options.notify = notify;
    let sent = h.send(link, &e);
    (e, sent)
}

fn control_msg<T: Serialize>(
    h: &mut Harness,
    link: LinkId,
    module: &str,
    name: &str,
    body: &T,
) -> Vec<(LinkId, Envelope)> {
    let e = h.envelope(
        link,
        module,
        Class::Control,
        name,
        encode_data(body).unwrap(),
    );
    h.send(link, &e)
}

#[test]
fn an_exception_handled_two_levels_up_patches_the_plan_and_the_tree_completes() {
    let mut h = Harness::new();
    h.connect(1, "user", 1);
    h.connect(2, "gait", 4);
    h.connect(3, "lrp", 4);
    h.connect(4, "ctl", 1);
    h.register::<Target>(2, "gait", "walk", Class::Goal, false);
    h.register::<Failed>(2, "gait", "moveFailed", Class::Exception, false);
    h.register::<Target>(3, "lrp", "step", Class::Goal, false);
    h.register::<Target>(4, "ctl", "moveArm", Class::Command, false);

    // user -> walk (W); gait attaches its exception handler at W and sends step S.
    let (walk, sent) = task(&mut h, 1, "user", Class::Goal, "walk", None, true);
    let w = sent[0].1.node.unwrap();
    let sent = control_msg(
        &mut h,
        2,
        "gait",
        names::ON_EXCEPTION,
        &control::OnException {
            node: w,
            name: MessageName::new("moveFailed").unwrap(),
        },
    );
    assert_eq!(sent[0].1.class, Class::Reply, "{:?}", sent[0].1);
    let (_step, sent) = task(&mut h, 2, "gait", Class::Goal, "step", Some(w), false);
    let s = sent[0].1.node.unwrap();
    h.done(2, "gait", &walk, true); // the walk handler is done planning
    // lrp -> moveArm (C) under S; the controller fails it with an exception.
    let (leg, sent) = task(&mut h, 3, "lrp", Class::Command, "moveArm", Some(s), false);
    let c = sent[0].1.node.unwrap();
    let mut exc = h.envelope(
        4,
        "ctl",
        Class::Exception,
        "moveFailed",
        encode_data(&Failed {
            why: "hit a box".into(),
        })
        .unwrap(),
    );
    exc.context = Some(c);
    let sent = h.send(4, &exc);
    let delivered = &sent
        .iter()
        .find(|(l, _)| *l == 2)
        .expect("delivered to gait")
        .1;
    assert_eq!(
        delivered.node,
        Some(w),
        "delivered at the node it was attached to"
    );
    assert_eq!(delivered.context, Some(c), "context names the raising node");
    // The command then fails; its failure is held while the exception is handled.
    let sent = h.done(4, "ctl", &leg, false);
    assert!(
        sent.iter()
            .all(|(_, e)| e.name.as_str() != names::TASK_ENDED),
        "nothing fails yet: {sent:?}"
    );
    // gait patches the plan: a new step under W, then kill the old one, end the exception.
    let (step2, sent) = task(&mut h, 2, "gait", Class::Goal, "step", Some(w), false);
    let s2 = sent[0].1.node.unwrap();
    control_msg(&mut h, 2, "gait", names::KILL, &control::Kill { node: s });
    let mut ok = h.envelope(
        2,
        "gait",
        Class::Success,
        "moveFailed",
        encode_data(&()).unwrap(),
    );
    ok.correlation = Some(exc.id);
    h.send(2, &ok);
    // The new step runs to the end and the walk is achieved.
    let (leg2, _) = task(&mut h, 3, "lrp", Class::Command, "moveArm", Some(s2), false);
    h.done(3, "lrp", &step2, true);
    let sent = h.done(4, "ctl", &leg2, true);
    let ended = sent
        .iter()
        .find(|(_, e)| e.name.as_str() == names::TASK_ENDED)
        .expect("walk ended");
    assert_eq!(ended.0, 1, "the user is told");
    let ended: TaskEnded = decode_data(&ended.1.data).unwrap();
    assert_eq!(ended.node, w);
    assert_eq!(ended.outcome, TaskOutcome::Achieved);
}

#[test]
fn an_unhandled_exception_fails_the_tree_and_its_originator_is_told() {
    let mut h = Harness::new();
    h.connect(1, "user", 1);
    h.connect(2, "ctl", 1);
    h.register::<Target>(2, "ctl", "moveArm", Class::Command, false);
    let (_cmd, sent) = task(&mut h, 1, "user", Class::Command, "moveArm", None, false);
    let c = sent[0].1.node.unwrap();
    let mut exc = h.envelope(
        2,
        "ctl",
        Class::Exception,
        "hardwareFault",
        encode_data(&Failed {
            why: "limit switch".into(),
        })
        .unwrap(),
    );
    exc.context = Some(c);
    let sent = h.send(2, &exc);
    let cancel = sent
        .iter()
        .find(|(_, e)| e.name.as_str() == names::CANCEL)
        .expect("running handler cancelled");
    assert_eq!(cancel.0, 2);
    let ended = sent
        .iter()
        .find(|(_, e)| e.name.as_str() == names::TASK_ENDED)
        .expect("originator told");
    assert_eq!(ended.0, 1);
    let ended: TaskEnded = decode_data(&ended.1.data).unwrap();
    match ended.outcome {
        TaskOutcome::Failed(reason) => assert!(
            reason.contains("unhandled exception hardwareFault"),
            "{reason}"
        ),
        other => panic!("{other:?}"),
    }
    assert_eq!(h.central.live_nodes(), 0);
}

#[test]
fn an_exception_outside_a_task_is_refused() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    let exc = h.envelope(1, "ctl", Class::Exception, "moveFailed", vec![]);
    let err = error_of(&h.send(1, &exc)[0].1);
    assert!(
        err.to_string().contains("outside a live task node"),
        "{err}"
    );
}

#[test]
fn a_sender_over_its_queue_limit_is_refused_while_others_are_served() {
    let mut h = Harness::with(CentralConfig {
        max_queued_messages: 2,
        max_queued_bytes: 1 << 20,
        ..CentralConfig::default()
    });
    h.connect(1, "ctl", 1);
    h.register::<Target>(1, "ctl", "move", Class::Command, false);
    h.connect(2, "flood", 1);
    h.connect(3, "calm", 1);
    // The first command runs at once; the next two wait for capacity (queued, charged to the
    // flooder); the fourth is over the limit.
    let mut cmds = Vec::new();
    for i in 0..4 {
        let c = h.envelope(2, "flood", Class::Command, "move", target(f64::from(i)));
        let sent = h.send(2, &c);
        cmds.push((c, sent));
    }
    assert_eq!(cmds[0].1.len(), 1, "delivered to the handler");
    assert!(cmds[1].1.is_empty() && cmds[2].1.is_empty(), "queued");
    let err = error_of(&cmds[3].1[0].1);
    match &err {
        RouteError::OverLimit {
            module, setting, ..
        } => assert_eq!(
            (module.as_str(), setting.as_str()),
            ("flood", "max_queued_messages")
        ),
        other => panic!("expected OverLimit, got {other}"),
    }
    assert!(err.to_string().contains("over its limit of 2"), "{err}");
    assert_eq!(
        h.central
            .queued_by(&ModuleName::new("flood").unwrap())
            .messages,
        2
    );
    // Another sender is not affected by the flooder's limit.
    let calm = h.envelope(3, "calm", Class::Command, "move", target(9.0));
    assert!(h.send(3, &calm).is_empty(), "queued, not refused");
    // As the handler finishes, queued commands are delivered and the flooder's count falls.
    let first = cmds[0].1[0].1.clone();
    let sent = h.done(1, "ctl", &first, true);
    assert!(
        sent.iter()
            .any(|(l, e)| *l == 1 && e.class == Class::Command)
    );
    assert_eq!(
        h.central
            .queued_by(&ModuleName::new("flood").unwrap())
            .messages,
        1
    );
    assert_eq!(h.central.recount_queued(), h.central.queued_totals());
    let again = h.envelope(2, "flood", Class::Command, "move", target(5.0));
    assert!(h.send(2, &again).is_empty(), "room again");
}

#[test]
fn a_full_inbox_is_answered_with_an_error_naming_the_limit() {
    let mut h = Harness::with(CentralConfig {
        max_inbox_frames: 8,
        ..CentralConfig::default()
    });
    h.connect(1, "ctl", 1);
    h.register::<Target>(1, "ctl", "move", Class::Command, false);
    h.connect(2, "flood", 1);
    let c = h.envelope(2, "flood", Class::Command, "move", target(1.0));
    let used = InboxUse {
        frames: 8,
        bytes: 400,
    };
    let sent = h.step(Event::InboxFull(2, Bytes::from(encode(&c).unwrap()), used));
    assert_eq!(sent.len(), 1, "only the error, nothing routed");
    assert_eq!(sent[0].0, 2);
    assert_eq!(sent[0].1.correlation, Some(c.id));
    let err = error_of(&sent[0].1);
    assert!(err.to_string().contains("max_inbox_frames"), "{err}");
    assert_eq!(h.central.counters().over_limit, 1);
}

#[test]
fn the_policy_refuses_strangers_and_sends_outside_the_rules_without_routing_them() {
    let text = format!(
        "[[identity]]\nname = \"gait\"\nsecret_sha3 = \"{}\"\nregister = []\n\
         send = [\"moveBase\", \"tca.monitor\"]\n\
         [[identity]]\nname = \"ctl\"\nsecret_sha3 = \"{}\"\nregister = [\"moveBase\", \"status\"]\n",
        crate::policy::hash_secret("gait", "g"),
        crate::policy::hash_secret("ctl", "c"),
    );
    let policy = crate::Policy::parse(std::path::Path::new("p.toml"), &text).unwrap();
    let mut h = Harness::with(CentralConfig {
        policy: Some(std::sync::Arc::new(policy)),
        ..CentralConfig::default()
    });
    let auth_hello = |h: &mut Harness, link: LinkId, module: &str, id: &str, secret: &str| {
        h.step(Event::Opened(link));
        let hello = control::AuthHello {
            hello: Hello {
                module: ModuleName::new(module).unwrap(),
                capacity: 1,
                pid: 1,
                host: "test".into(),
                simulated_time: false,
            },
            credentials: control::Credentials {
                identity: id.into(),
                secret: secret.into(),
            },
        };
        let data = encode_data(&hello).unwrap();
        let mut env = h.envelope(link, module, Class::Control, names::HELLO_AUTH, data);
        env.id = MessageId::new(0, 0);
        h.send(link, &env)
    };
    // A plain hello, and a wrong secret, are refused.
    let sent = h.connect(9, "gait", 1);
    assert!(
        error_of(&sent[0].1)
            .to_string()
            .contains("requires credentials")
    );
    let sent = auth_hello(&mut h, 8, "gait", "gait", "nope");
    assert!(error_of(&sent[0].1).to_string().contains("secret is wrong"));
    assert!(h.central.connected_modules().is_empty());
    // The right ones are welcomed.
    let sent = auth_hello(&mut h, 1, "ctl", "ctl", "c");
    assert_eq!(sent[0].1.class, Class::Control, "welcome");
    auth_hello(&mut h, 2, "gait", "gait", "g");
    let outcome = h.register::<Target>(1, "ctl", "moveBase", Class::Command, false);
    assert_eq!(outcome.accepted.len(), 1);
    let outcome = h.register::<Target>(1, "ctl", "walk", Class::Goal, false);
    assert!(
        outcome.refused[0].1.contains("may not register \"walk\""),
        "{outcome:?}"
    );
    h.register::<Target>(1, "ctl", "status", Class::Query, false);
    // gait may send moveBase...
    let ok = h.envelope(2, "gait", Class::Command, "moveBase", target(1.0));
    let sent = h.send(2, &ok);
    assert_eq!(sent[0].0, 1, "delivered to the controller");
    // ...but not the query `status`, directly or as a monitor's condition.
    let q = h.envelope(2, "gait", Class::Query, "status", target(1.0));
    let sent = h.send(2, &q);
    assert_eq!(sent.len(), 1, "only the error; nothing routed");
    match error_of(&sent[0].1) {
        RouteError::NotPermitted { name, rule, .. } => {
            assert_eq!(name, "status");
            assert!(rule.contains("identity \"gait\" send"), "{rule}");
        }
        other => panic!("expected NotPermitted, got {other}"),
    }
    let monitor = control::Monitor {
        node: NodeId(1),
        query: MessageName::new("status").unwrap(),
        query_data: target(1.0),
        period_ms: None,
        action: control::MonitorAction::Raise {
            name: MessageName::new("moveFailed").unwrap(),
            data: Vec::new(),
        },
    };
    let m = h.envelope(
        2,
        "gait",
        Class::Control,
        names::MONITOR,
        encode_data(&monitor).unwrap(),
    );
    let sent = h.send(2, &m);
    assert_eq!(sent.len(), 1);
    assert!(matches!(
        error_of(&sent[0].1),
        RouteError::NotPermitted { .. }
    ));
    assert_eq!(h.central.counters().not_permitted, 3);
}

#[test]
fn a_task_sent_from_a_killed_task_is_not_started() {
    let mut h = Harness::new();
    h.connect(1, "user", 1);
    h.connect(2, "lrp", 4);
    h.connect(3, "ctl", 1);
    h.register::<Target>(2, "lrp", "step", Class::Goal, false);
    h.register::<Target>(3, "ctl", "moveArm", Class::Command, false);
    let (_step, sent) = task(&mut h, 1, "user", Class::Goal, "step", None, false);
    let s = sent[0].1.node.unwrap();
    control_msg(&mut h, 1, "user", names::KILL, &control::Kill { node: s });
    // The step's handler, not yet told it was killed, still sends its leg move.
    let (_leg, sent) = task(&mut h, 2, "lrp", Class::Command, "moveArm", Some(s), false);
    assert!(
        sent.iter().all(|(link, _)| *link != 3),
        "the controller got {sent:?}"
    );
    let err = error_of(&sent.iter().find(|(l, _)| *l == 2).expect("lrp told").1);
    assert!(err.to_string().contains("no longer live"), "{err}");
    assert_eq!(h.central.live_nodes(), 0);
}

#[test]
fn a_sender_that_was_away_learns_how_its_watched_tasks_stand() {
    let mut h = Harness::new();
    h.connect(1, "ctl", 1);
    h.register::<Target>(1, "ctl", "moveBase", Class::Command, false);
    h.connect(2, "gait", 1);
    let mut watched = h.envelope(2, "gait", Class::Command, "moveBase", target(1.0));
    watched.options.notify = true;
    let sent = h.send(2, &watched);
    assert!(sent.iter().any(|(l, e)| *l == 1 && e.id == watched.id));
    let mut live = h.envelope(2, "gait", Class::Command, "moveBase", target(2.0));
    live.options.notify = true;
    h.send(2, &live);
    // The sender goes away; its first task ends meanwhile (its end cannot be told).
    h.step(Event::Closed(2));
    let sent = h.done(1, "ctl", &watched, true);
    assert!(
        !sent
            .iter()
            .any(|(_, e)| e.name.as_str() == names::TASK_ENDED),
        "{sent:?}"
    );
    // It comes back on another link and asks.
    h.connect(3, "gait", 1);
    let never = MessageId::new(2, 999);
    let ask = control::TaskStatusRequest {
        tasks: vec![watched.id, live.id, never],
    };
    let request = h.envelope(
        3,
        "gait",
        Class::Control,
        names::TASK_STATUS,
        encode_data(&ask).unwrap(),
    );
    let sent = h.send(3, &request);
    let reply = sent
        .iter()
        .find(|(l, e)| *l == 3 && e.correlation == Some(request.id))
        .expect("answered");
    let status: Vec<control::TaskStatus> = decode_data(&reply.1.data).unwrap();
    let states: Vec<control::TaskState> = status.into_iter().map(|s| s.state).collect();
    assert_eq!(
        states,
        vec![
            control::TaskState::Ended(TaskOutcome::Achieved),
            control::TaskState::Live,
            control::TaskState::Unknown
        ]
    );
    // Another module cannot learn of them.
    let request = h.envelope(
        1,
        "ctl",
        Class::Control,
        names::TASK_STATUS,
        encode_data(&ask).unwrap(),
    );
    let sent = h.send(1, &request);
    let status: Vec<control::TaskStatus> = decode_data(&sent[0].1.data).unwrap();
    assert!(
        status
            .iter()
            .all(|s| s.state == control::TaskState::Unknown)
    );
}
