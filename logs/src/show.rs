//! Printing a log readably: one line per message delivery, data decoded through the registered
//! format (so it works for messages the viewer was not compiled with).

use std::fmt::Write as _;

use tca_messages::{Class, ModuleName};

use crate::reader::LogFile;
use crate::record::{Direction, LinkEvent, RecordKind};

/// Which records to print.
#[derive(Clone, Debug, Default)]
pub struct ShowFilter {
    /// Only traffic from or to this module.
    pub module: Option<String>,
    /// Only this message name.
    pub name: Option<String>,
    /// Only this class.
    pub class: Option<Class>,
    /// Print both directions of every frame (by default a routed message is printed once, as
    /// delivered, and module-to-central frames only when central is their destination).
    pub all_frames: bool,
}

/// Renders the log as text lines.
pub fn render(log: &LogFile, filter: &ShowFilter) -> Vec<String> {
    let start = log.records.first().map_or(0, |r| r.at_ns);
    let mut lines = Vec::new();
    for record in &log.records {
        let t = (record.at_ns.saturating_sub(start)) as f64 / 1e9;
        match &record.kind {
            RecordKind::Frame(f) => {
                let envelope = match LogFile::envelope(f) {
                    Ok(e) => e,
                    Err(err) => {
                        lines.push(format!("{t:>12.6}  <undecodable frame: {err}>"));
                        continue;
                    }
                };
                let central = matches!(
                    envelope.class,
                    Class::Success | Class::Failure | Class::Control
                );
                if !filter.all_frames && f.direction == Direction::In && !central {
                    continue;
                }
                let peer = f.peer.as_ref().map_or("?", ModuleName::as_str).to_owned();
                let (from, to) = match f.direction {
                    Direction::In => (peer, "central".to_owned()),
                    Direction::Out => (envelope.sender.to_string(), peer),
                };
                if let Some(m) = &filter.module
                    && &from != m
                    && &to != m
                {
                    continue;
                }
                if filter
                    .name
                    .as_ref()
                    .is_some_and(|n| n != envelope.name.as_str())
                {
                    continue;
                }
                if filter.class.is_some_and(|c| c != envelope.class) {
                    continue;
                }
                let node = envelope
                    .node
                    .or(envelope.context)
                    .map(|n| n.to_string())
                    .unwrap_or_else(|| "-".into());
                let data = match log.data_value(&envelope) {
                    Ok(v) => v.to_string(),
                    Err(e) => format!("<{} bytes: {e}>", envelope.data.len()),
                };
                let mut line = format!(
                    "{t:>12.6}  {:<9} {from} -> {to}  {}  {node}  {}",
                    envelope.class.as_str(),
                    envelope.name,
                    envelope.id
                );
                if let Some(c) = envelope.correlation {
                    let _ = write!(line, " re {c}");
                }
                if envelope.redelivery > 0 {
                    let _ = write!(line, " (redelivery {})", envelope.redelivery);
                }
                let _ = write!(line, "  {data}");
                lines.push(line);
            }
            RecordKind::Link(l) if filter.name.is_none() && filter.class.is_none() => {
                let module = l.module.as_ref().map_or("?", ModuleName::as_str);
                if filter.module.as_ref().is_some_and(|m| m != module) {
                    continue;
                }
                let what = match l.event {
                    LinkEvent::Opened => "link opened",
                    LinkEvent::Connected => "connected",
                    LinkEvent::Refused => "refused",
                    LinkEvent::Closed => "disconnected",
                };
                let detail = if l.detail.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", l.detail)
                };
                lines.push(format!(
                    "{t:>12.6}  link {}: {module} {what}{detail}",
                    l.link
                ));
            }
            RecordKind::Registered(r) if filter.class.is_none() => {
                if filter
                    .module
                    .as_ref()
                    .is_some_and(|m| m != r.module.as_str())
                {
                    continue;
                }
                if filter
                    .name
                    .as_ref()
                    .is_some_and(|n| n != r.registration.name.as_str())
                {
                    continue;
                }
                lines.push(format!(
                    "{t:>12.6}  registered {} {} by {}: {}",
                    r.registration.class, r.registration.name, r.module, r.registration.format
                ));
            }
            RecordKind::Problem(p) if filter.name.is_none() && filter.class.is_none() => {
                let module = p.module.as_ref().map_or("?", ModuleName::as_str);
                if filter.module.as_ref().is_some_and(|m| m != module) {
                    continue;
                }
                lines.push(format!("{t:>12.6}  PROBLEM from {module}: {}", p.error));
            }
            _ => {}
        }
    }
    if let Some(t) = &log.truncated {
        lines.push(format!("(note: {t})"));
    }
    lines
}

/// Rebuilds the task trees as they stood `at_s` seconds after the log's first record (the end
/// of the log if `None`) by replaying the logged tree operations, and renders them.
pub fn tree_at(log: &LogFile, at_s: Option<f64>) -> Result<String, String> {
    let start = log.records.first().map_or(0, |r| r.at_ns);
    let limit = at_s.map(|s| start.saturating_add((s.max(0.0) * 1e9) as u64));
    let ops = log.records.iter().filter_map(|r| match &r.kind {
        RecordKind::Tree(t) if limit.is_none_or(|l| r.at_ns <= l) => Some(&t.op),
        _ => None,
    });
    let mut tree = tca_task_tree::TaskTree::new();
    let mut applied = 0usize;
    for op in ops {
        tree.apply(op)
            .map_err(|e| format!("the log's tree operations do not replay (op {applied}): {e}"))?;
        applied += 1;
    }
    let text = tree.render_text();
    Ok(if text.trim().is_empty() {
        format!("(no live task nodes; {applied} tree operations replayed)")
    } else {
        text
    })
}
