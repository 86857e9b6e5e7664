//! Auditing a log for lost and doubly handled messages (`tca log audit`, `tca chaos`).
//!
//! Central's log holds every frame in and out, every link event and every task-tree operation,
//! so it can prove what happened to each message a module sent:
//!
//! - **lost**: a query that never got an answer (reply, failure or error) back to its sender
//!   (unless the sender went down first);
//!   a goal or command that got neither a task node nor an error; an inform neither delivered
//!   nor refused; a task node that never ended (achieved, failed or killed) by the end of the
//!   log.
//! - **handled twice**: a goal or command delivered again although the module it was delivered
//!   to had not gone down in between (central delivers a task again only after its handler's
//!   link closed, marking it as redelivery 1, 2, ...), or a task with more than one end
//!   (success or failure) from its handlers.
//!
//! A log cut short by a crash of central ends with messages in flight; audit a log of a run
//! that ended cleanly. Exceptions are counted but not followed (their routing up the tree
//! ends in handlers, not answers).

use std::collections::{BTreeMap, HashMap, HashSet};

use serde::Serialize;
use tca_messages::{Class, Envelope, ModuleName};
use tca_task_tree::{NodeId, TaskTree, TreeEvent, TreeOp};

use crate::reader::LogFile;
use crate::record::{Direction, LinkEvent, RecordKind};

/// What the audit found.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Audit {
    /// Queries modules sent.
    pub queries: usize,
    /// Goals and commands modules sent.
    pub tasks: usize,
    /// Informs modules sent.
    pub informs: usize,
    /// Exceptions modules raised.
    pub exceptions: usize,
    /// Messages central refused with an error (unknown name, over a limit, module gone...).
    pub refused: usize,
    /// Goals and commands delivered again after their handler's module went down.
    pub redelivered: usize,
    /// Links that closed while their module was registered (module stopped or killed).
    pub links_closed: usize,
    /// Lost messages, one line each.
    pub lost: Vec<String>,
    /// Messages handled twice, one line each.
    pub handled_twice: Vec<String>,
}

impl Audit {
    /// A readable summary: what was counted, then every message lost or handled twice.
    pub fn text(&self) -> String {
        let mut s = format!(
            "{} queries, {} goals and commands, {} informs, {} exceptions; {} refused with an \
             error; {} tasks delivered again after their module went down ({} links closed)\n",
            self.queries,
            self.tasks,
            self.informs,
            self.exceptions,
            self.refused,
            self.redelivered,
            self.links_closed
        );
        if self.is_clean() {
            s.push_str("no message lost, none handled twice\n");
        }
        for l in &self.lost {
            s.push_str(&format!("LOST: {l}\n"));
        }
        for d in &self.handled_twice {
            s.push_str(&format!("HANDLED TWICE: {d}\n"));
        }
        s
    }
}

impl Audit {
    /// Nothing lost and nothing handled twice.
    pub fn is_clean(&self) -> bool {
        self.lost.is_empty() && self.handled_twice.is_empty()
    }
}

/// What the log shows of one message a module sent.
#[derive(Debug)]
struct Sent {
    class: Class,
    name: String,
    sender: ModuleName,
    /// Record index where it entered central.
    entered: usize,
    /// Deliveries to a handler: record index, handler, redelivery count.
    deliveries: Vec<(usize, Option<ModuleName>, u32)>,
    /// Answers to the sender (queries) or ends from handlers (tasks).
    answers: usize,
    /// Central refused it with an error.
    refused: bool,
    node: Option<NodeId>,
}

/// Audits a log. See the [module documentation](self).
pub fn audit(log: &LogFile) -> Audit {
    let mut sent: BTreeMap<u64, Sent> = BTreeMap::new();
    // When each module's links closed (record indices).
    let mut closed: HashMap<ModuleName, Vec<usize>> = HashMap::new();
    let mut ops: Vec<TreeOp> = Vec::new();
    let mut node_message: HashMap<NodeId, u64> = HashMap::new();
    let mut audit = Audit::default();
    for (index, record) in log.records.iter().enumerate() {
        match &record.kind {
            RecordKind::Frame(frame) => {
                let Ok(envelope) = LogFile::envelope(frame) else {
                    continue;
                };
                match frame.direction {
                    Direction::In => on_in(&mut sent, index, &envelope),
                    Direction::Out => on_out(&mut sent, index, frame.peer.clone(), &envelope),
                }
            }
            RecordKind::Link(link) if link.event == LinkEvent::Closed => {
                if let Some(module) = &link.module {
                    closed.entry(module.clone()).or_default().push(index);
                    audit.links_closed += 1;
                }
            }
            RecordKind::Tree(tree) => {
                if let (TreeOp::AddNode { id, .. }, Some(message)) = (&tree.op, tree.message) {
                    node_message.insert(*id, message);
                }
                ops.push(tree.op.clone());
            }
            _ => {}
        }
    }
    for (node, message) in &node_message {
        if let Some(s) = sent.get_mut(message) {
            s.node = Some(*node);
        }
    }
    let ended = ended_nodes(&ops);
    for (id, s) in &sent {
        let what = format!(
            "{} {} #{} from {}",
            s.class,
            s.name,
            tca_messages::MessageId(*id),
            s.sender
        );
        if s.refused {
            audit.refused += 1;
        }
        match s.class {
            Class::Query => {
                audit.queries += 1;
                // An asker that went down before the answer came has nobody to answer.
                let asker_died = closed
                    .get(&s.sender)
                    .is_some_and(|c| c.iter().any(|i| *i > s.entered));
                if s.answers == 0 && !asker_died {
                    audit.lost.push(format!("{what}: never answered"));
                }
            }
            Class::Inform => {
                audit.informs += 1;
                if s.deliveries.is_empty() && !s.refused {
                    audit
                        .lost
                        .push(format!("{what}: neither delivered nor refused"));
                }
            }
            Class::Goal | Class::Command => {
                audit.tasks += 1;
                check_task(&what, s, &ended, &closed, &mut audit);
            }
            Class::Exception => audit.exceptions += 1,
            _ => {}
        }
    }
    audit
}

fn on_in(sent: &mut BTreeMap<u64, Sent>, index: usize, envelope: &Envelope) {
    match envelope.class {
        Class::Query | Class::Goal | Class::Command | Class::Inform | Class::Exception => {
            sent.entry(envelope.id.0).or_insert_with(|| Sent {
                class: envelope.class,
                name: envelope.name.to_string(),
                sender: envelope.sender.clone(),
                entered: index,
                deliveries: Vec::new(),
                answers: 0,
                refused: false,
                node: None,
            });
        }
        // A handler's end of a goal or command.
        Class::Success | Class::Failure => {
            if let Some(s) = envelope.correlation.and_then(|c| sent.get_mut(&c.0))
                && matches!(s.class, Class::Goal | Class::Command)
            {
                s.answers += 1;
            }
        }
        _ => {}
    }
}

fn on_out(
    sent: &mut BTreeMap<u64, Sent>,
    index: usize,
    peer: Option<ModuleName>,
    envelope: &Envelope,
) {
    match envelope.class {
        Class::Query | Class::Goal | Class::Command | Class::Inform => {
            if let Some(s) = sent.get_mut(&envelope.id.0) {
                s.deliveries.push((index, peer, envelope.redelivery));
            }
        }
        Class::Reply | Class::Failure | Class::Error => {
            let Some(s) = envelope.correlation.and_then(|c| sent.get_mut(&c.0)) else {
                return;
            };
            // Only answers going back to the sender count (not a failure passed on).
            if peer.as_ref() != Some(&s.sender) {
                return;
            }
            if envelope.class == Class::Error {
                s.refused = true;
            }
            if s.class == Class::Query {
                s.answers += 1;
            }
        }
        _ => {}
    }
}

fn check_task(
    what: &str,
    s: &Sent,
    ended: &HashSet<NodeId>,
    closed: &HashMap<ModuleName, Vec<usize>>,
    audit: &mut Audit,
) {
    match s.node {
        None if !s.refused => {
            audit
                .lost
                .push(format!("{what}: neither a task node nor an error"));
        }
        None => {}
        Some(node) if !ended.contains(&node) => {
            audit
                .lost
                .push(format!("{what}: its task node {node} never ended"));
        }
        Some(_) => {}
    }
    if s.answers > 1 {
        audit
            .handled_twice
            .push(format!("{what}: {} ends from its handlers", s.answers));
    }
    for pair in s.deliveries.windows(2) {
        let ((before, handler, n), (after, _, m)) = (&pair[0], &pair[1]);
        audit.redelivered += 1;
        let went_down = handler.as_ref().is_some_and(|h| {
            closed
                .get(h)
                .is_some_and(|c| c.iter().any(|i| i > before && i < after))
        });
        if !went_down || *m != n + 1 {
            audit.handled_twice.push(format!(
                "{what}: delivered again (redelivery {m}) although {} had not gone down since delivery {n}",
                handler
                    .as_ref()
                    .map(ModuleName::to_string)
                    .unwrap_or_else(|| "its handler".into())
            ));
        }
    }
}

/// Nodes whose last word was achieved, failed or killed, from replaying the tree.
fn ended_nodes(ops: &[TreeOp]) -> HashSet<NodeId> {
    let mut tree = TaskTree::new();
    let mut ended = HashSet::new();
    for op in ops {
        let Ok(events) = tree.apply(op) else {
            break;
        };
        for event in events {
            match event {
                TreeEvent::Achieved(n) => {
                    ended.insert(n);
                }
                TreeEvent::Failed { node, .. } | TreeEvent::Killed { node, .. } => {
                    ended.insert(node);
                }
                // Retried (a task delivered again after its module went down): live again.
                TreeEvent::Ready(n) | TreeEvent::HandlingStarted(n) => {
                    ended.remove(&n);
                }
                _ => {}
            }
        }
    }
    ended
}

#[cfg(test)]
mod tests {
    use bytes::Bytes;
    use tca_messages::{MessageId, MessageName, SendOptions, encode};
    use tca_task_tree::{NodeKind, NodeSpec, Outcome};

    use super::*;
    use crate::record::{FrameRecord, LinkRecord, LogRecord, TreeRecord};

    /// Builds a log record by record.
    #[derive(Default)]
    struct Log(Vec<LogRecord>);

    fn module(name: &str) -> ModuleName {
        ModuleName::new(name).unwrap()
    }

    impl Log {
        fn push(&mut self, kind: RecordKind) -> &mut Self {
            self.0.push(LogRecord {
                at_ns: self.0.len() as u64,
                kind,
            });
            self
        }

        #[allow(clippy::too_many_arguments)]
        fn frame(
            &mut self,
            direction: Direction,
            peer: &str,
            class: Class,
            id: MessageId,
            sender: &str,
            correlation: Option<MessageId>,
            redelivery: u32,
        ) -> &mut Self {
            let envelope = Envelope {
                id,
                class,
                name: MessageName::new("work").unwrap(),
                sender: module(sender),
                context: None,
                node: None,
                correlation,
                cause: None,
                timestamp_ns: 0,
                options: SendOptions::default(),
                redelivery,
                data: Vec::new(),
            };
            self.push(RecordKind::Frame(FrameRecord {
                direction,
                link: 1,
                peer: Some(module(peer)),
                name: envelope.name.clone(),
                class,
                frame: Bytes::from(encode(&envelope).unwrap()),
            }))
        }

        fn closed(&mut self, who: &str) -> &mut Self {
            self.push(RecordKind::Link(LinkRecord {
                link: 1,
                event: LinkEvent::Closed,
                module: Some(module(who)),
                detail: String::new(),
            }))
        }

        fn tree(&mut self, op: TreeOp, message: Option<MessageId>) -> &mut Self {
            self.push(RecordKind::Tree(TreeRecord {
                op,
                message: message.map(|m| m.0),
            }))
        }

        fn audit(&self) -> Audit {
            audit(&LogFile {
                path: "test.mcap".into(),
                records: self.0.clone(),
                formats: HashMap::new(),
                truncated: None,
            })
        }
    }

    const Q: MessageId = MessageId(7);

    fn asked(log: &mut Log) {
        log.frame(Direction::In, "gait", Class::Query, Q, "gait", None, 0)
            .frame(Direction::Out, "ltm", Class::Query, Q, "gait", None, 0)
            .frame(
                Direction::In,
                "ltm",
                Class::Reply,
                MessageId(9),
                "ltm",
                Some(Q),
                0,
            );
    }

    #[test]
    fn an_answered_query_is_clean_and_an_unanswered_one_is_lost() {
        let mut log = Log::default();
        asked(&mut log);
        let unanswered = log.audit();
        assert_eq!(unanswered.queries, 1);
        assert_eq!(unanswered.lost.len(), 1, "{unanswered:?}");
        assert!(unanswered.lost[0].contains("never answered"));
        log.frame(
            Direction::Out,
            "gait",
            Class::Reply,
            MessageId(9),
            "ltm",
            Some(Q),
            0,
        );
        assert!(log.audit().is_clean(), "{:?}", log.audit());
    }

    #[test]
    fn a_query_whose_asker_died_is_not_lost() {
        let mut log = Log::default();
        asked(&mut log);
        log.closed("gait");
        assert!(log.audit().is_clean(), "{:?}", log.audit());
    }

    /// A goal that enters, gets node `node`, is delivered (maybe twice) and ends.
    fn goal(log: &mut Log, handler_dies_between: bool) -> Audit {
        let g = MessageId(11);
        let node = tca_task_tree::TaskTree::new().next_id();
        log.frame(Direction::In, "gait", Class::Goal, g, "gait", None, 0)
            .tree(
                TreeOp::AddNode {
                    id: node,
                    spec: NodeSpec::new(NodeKind::Goal, "work", "lrp"),
                    now: 1,
                },
                Some(g),
            )
            .tree(TreeOp::Start { node, now: 2 }, Some(g))
            .frame(Direction::Out, "lrp", Class::Goal, g, "gait", None, 0);
        if handler_dies_between {
            log.closed("lrp");
        }
        log.frame(Direction::Out, "lrp", Class::Goal, g, "gait", None, 1)
            .frame(
                Direction::In,
                "lrp",
                Class::Success,
                MessageId(12),
                "lrp",
                Some(g),
                0,
            )
            .tree(
                TreeOp::Finish {
                    node,
                    outcome: Outcome::Success,
                    now: 3,
                },
                Some(g),
            );
        log.audit()
    }

    #[test]
    fn a_goal_delivered_again_after_its_handler_died_is_clean() {
        let audit = goal(&mut Log::default(), true);
        assert!(audit.is_clean(), "{audit:?}");
        assert_eq!((audit.tasks, audit.redelivered), (1, 1));
    }

    #[test]
    fn a_goal_delivered_twice_to_a_live_handler_was_handled_twice() {
        let audit = goal(&mut Log::default(), false);
        assert_eq!(audit.handled_twice.len(), 1, "{audit:?}");
        assert!(audit.handled_twice[0].contains("had not gone down"));
    }

    #[test]
    fn a_goal_with_no_node_and_no_error_is_lost() {
        let mut log = Log::default();
        log.frame(
            Direction::In,
            "gait",
            Class::Goal,
            MessageId(5),
            "gait",
            None,
            0,
        );
        let audit = log.audit();
        assert_eq!(audit.lost.len(), 1, "{audit:?}");
        assert!(audit.lost[0].contains("neither a task node nor an error"));
    }

    #[test]
    fn two_ends_of_one_goal_were_handled_twice() {
        let mut log = Log::default();
        let g = MessageId(11);
        goal(&mut log, true);
        log.frame(
            Direction::In,
            "lrp",
            Class::Success,
            MessageId(13),
            "lrp",
            Some(g),
            0,
        );
        let audit = log.audit();
        assert!(
            audit.handled_twice.iter().any(|d| d.contains("2 ends")),
            "{audit:?}"
        );
    }
}
