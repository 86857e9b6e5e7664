//! Taps and the command line's task controls: copies of a name's traffic go to the module
//! that taps it (and stop when it leaves), a task is killed by its message's id, and every
//! tree at once without a waiting task starting in between.

use super::*;
use tca_messages::control::{KillTask, Tap, Tapped};

fn tapped(sent: &[(LinkId, Envelope)], link: LinkId) -> Vec<Envelope> {
    sent.iter()
        .filter(|(l, e)| *l == link && e.name.as_str() == names::TAPPED)
        .map(|(_, e)| decode_data::<Tapped>(&e.data).unwrap().envelope)
        .collect()
}

fn tap(h: &mut Harness, link: LinkId, module: &str, names: &[&str]) -> Vec<(LinkId, Envelope)> {
    let tap = Tap {
        names: names
            .iter()
            .map(|n| MessageName::new(*n).unwrap())
            .collect(),
    };
    control_msg(h, link, module, names::TAP, &tap)
}

#[test]
fn a_tap_copies_a_names_traffic_and_its_answers_until_the_module_leaves() {
    let mut h = Harness::new();
    h.connect(1, "user", 1);
    h.connect(2, "ctl", 1);
    h.connect(3, "echo", 1);
    h.register::<Target>(2, "ctl", "bodyMove", Class::Command, false);
    h.register::<Target>(2, "ctl", "pose", Class::Query, false);
    let sent = tap(&mut h, 3, "echo", &["bodyMove"]);
    assert!(
        sent.iter().any(|(l, e)| *l == 3 && e.class == Class::Reply),
        "the tap is acknowledged: {sent:?}"
    );
    let (cmd, sent) = task(&mut h, 1, "user", Class::Command, "bodyMove", None, false);
    let copies = tapped(&sent, 3);
    assert_eq!(copies.len(), 1, "{sent:?}");
    assert_eq!(copies[0].id, cmd.id);
    assert_eq!(copies[0].data, cmd.data);
    let sent = h.done(2, "ctl", &cmd, true);
    let copies = tapped(&sent, 3);
    assert_eq!(copies.len(), 1, "the answer is copied too: {sent:?}");
    assert_eq!(copies[0].class, Class::Success);
    // Other names are not copied; nor is anything once the tapping module has gone.
    let q = h.envelope(1, "user", Class::Query, "pose", target(1.0));
    assert!(tapped(&h.send(1, &q), 3).is_empty());
    h.step(Event::Closed(3));
    let (_, sent) = task(&mut h, 1, "user", Class::Command, "bodyMove", None, false);
    assert!(sent.iter().all(|(l, _)| *l != 3), "{sent:?}");
}

#[test]
fn an_error_central_sends_about_a_tapped_name_is_copied() {
    let mut h = Harness::new();
    h.connect(1, "user", 1);
    h.connect(3, "echo", 1);
    tap(&mut h, 3, "echo", &[]);
    let q = h.envelope(1, "user", Class::Query, "nobody", target(1.0));
    let copies = tapped(&h.send(1, &q), 3);
    let classes: Vec<Class> = copies.iter().map(|e| e.class).collect();
    assert_eq!(classes, [Class::Query, Class::Error], "{copies:?}");
}

#[test]
fn a_task_is_killed_by_the_id_of_its_message() {
    let mut h = Harness::new();
    h.connect(1, "user", 1);
    h.connect(2, "ctl", 1);
    h.register::<Target>(2, "ctl", "bodyMove", Class::Command, false);
    let (cmd, _) = task(&mut h, 1, "user", Class::Command, "bodyMove", None, true);
    let sent = control_msg(
        &mut h,
        1,
        "user",
        names::KILL_TASK,
        &KillTask { task: cmd.id },
    );
    assert!(
        sent.iter()
            .any(|(l, e)| *l == 2 && e.name.as_str() == names::CANCEL),
        "the running handler is told to stop: {sent:?}"
    );
    let ended = sent
        .iter()
        .find(|(_, e)| e.name.as_str() == names::TASK_ENDED)
        .expect("the sender is told");
    let ended: TaskEnded = decode_data(&ended.1.data).unwrap();
    assert_eq!(ended.outcome, TaskOutcome::Killed);
    // Again: it is gone, and the error says so.
    let sent = control_msg(
        &mut h,
        1,
        "user",
        names::KILL_TASK,
        &KillTask { task: cmd.id },
    );
    let error = sent
        .iter()
        .find(|(_, e)| e.class == Class::Error)
        .expect("refused");
    let error: RouteError = decode_data(&error.1.data).unwrap();
    assert!(error.to_string().contains("no live task"), "{error}");
}

#[test]
fn killing_every_tree_starts_none_of_the_waiting_tasks() {
    let mut h = Harness::new();
    h.connect(1, "user", 1);
    h.connect(2, "ctl", 1);
    h.register::<Target>(2, "ctl", "bodyMove", Class::Command, false);
    let (first, sent) = task(&mut h, 1, "user", Class::Command, "bodyMove", None, true);
    assert!(sent.iter().any(|(l, e)| *l == 2 && e.id == first.id));
    let (second, sent) = task(&mut h, 1, "user", Class::Command, "bodyMove", None, true);
    assert!(
        sent.iter().all(|(l, _)| *l != 2),
        "the second waits: {sent:?}"
    );
    let sent = control_msg(&mut h, 1, "user", names::KILL_ALL, &());
    assert!(
        sent.iter().all(|(_, e)| e.id != second.id),
        "the waiting command never starts: {sent:?}"
    );
    let reply = sent
        .iter()
        .find(|(l, e)| *l == 1 && e.class == Class::Reply)
        .expect("answered");
    assert_eq!(decode_data::<u64>(&reply.1.data).unwrap(), 2);
    let ends = sent
        .iter()
        .filter(|(_, e)| e.name.as_str() == names::TASK_ENDED)
        .count();
    assert_eq!(ends, 2);
    assert_eq!(h.central.live_nodes(), 0);
}
