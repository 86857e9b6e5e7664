//! Links and modules: hello, welcome, refusal, bye, and what happens when a link closes.

use std::collections::VecDeque;

use tca_logs::{LinkEvent, LinkRecord, LogRecord, RecordKind};
use tca_messages::control::{ControlKind, ControlNotice, ControlRequest, Welcome};
use tca_messages::{Class, Envelope, MessageName, ModuleName, RouteError};

use super::{Action, Central, Link, LinkId, ModuleState};

impl Central {
    pub(super) fn link_opened(&mut self, link: LinkId, out: &mut Vec<Action>) {
        if self.links.contains_key(&link) {
            return;
        }
        self.max_link = self.max_link.max(link);
        self.links.insert(
            link,
            Link {
                module: None,
                identity: None,
                congested: false,
                unread: Default::default(),
            },
        );
        self.log_link(link, LinkEvent::Opened, None, String::new(), out);
    }

    /// The transport authenticated the link's peer as `identity`.
    pub(super) fn link_identified(&mut self, link: LinkId, identity: String) {
        if let Some(l) = self.links.get_mut(&link) {
            l.identity = Some(identity);
        }
    }

    /// The first frame on a link must be a hello.
    pub(super) fn before_hello(&mut self, link: LinkId, envelope: Envelope, out: &mut Vec<Action>) {
        let is_hello = envelope.class == Class::Control
            && ControlKind::from_name(envelope.name.as_str()).is_some_and(ControlKind::is_hello);
        if !is_hello {
            let reason = format!(
                "the first frame on a link must be {} or {} (got {} {}); connect with the module \
                 library",
                ControlKind::Hello,
                ControlKind::HelloAuth,
                envelope.class,
                envelope.name
            );
            return self.refuse(link, &envelope, reason, out);
        }
        let (hello, credentials) =
            match ControlRequest::decode(envelope.name.as_str(), &envelope.data) {
                Ok(ControlRequest::Hello(h)) => (h, None),
                Ok(ControlRequest::HelloAuth(a)) => (a.hello, Some(a.credentials)),
                Ok(other) => unreachable!("{} is a hello", other.kind()),
                Err(err) => return self.refuse(link, &envelope, format!("bad hello: {err}"), out),
            };
        if hello.module != envelope.sender {
            let reason = format!(
                "hello names module {} but the envelope's sender is {}",
                hello.module, envelope.sender
            );
            return self.refuse(link, &envelope, reason, out);
        }
        if hello.module.as_str() == self.central_name.as_str() {
            let reason = "the module name \"central\" is reserved; choose another".to_owned();
            return self.refuse(link, &envelope, reason, out);
        }
        let old = self
            .modules
            .get(&hello.module)
            .and_then(|m| m.link.map(|link| (link, m.hello.host.clone(), m.hello.pid)));
        if let Some((other, host, pid)) = old
            && self.process_gone(&host, pid)
        {
            // Its process is gone but its link has not dropped yet: the new one takes over.
            tracing::warn!(
                module = %hello.module,
                old_link = other,
                old_pid = pid,
                "module's old process is gone; its link is replaced by the new hello"
            );
            self.link_closed(other, out);
            out.push(Action::Close(other));
        }
        if let Some(existing) = self.modules.get(&hello.module)
            && let Some(other) = existing.link
        {
            let reason = format!(
                "a module named {} is already connected (link {other}, pid {} on {}); \
                     choose another name or stop that one first",
                hello.module, existing.hello.pid, existing.hello.host
            );
            return self.refuse(link, &envelope, reason, out);
        }
        let transport_identity = self.links.get(&link).and_then(|l| l.identity.clone());
        let grant = match self.admission(
            hello.module.as_str(),
            credentials.as_ref(),
            transport_identity.as_deref(),
        ) {
            Ok(grant) => grant,
            Err(reason) => return self.refuse(link, &envelope, reason, out),
        };
        let capacity = if hello.capacity == 0 {
            self.config.default_capacity.max(1)
        } else {
            hello.capacity
        } as usize;
        let name = hello.module.clone();
        let detail = match &grant {
            Some(g) => format!(
                "pid {} on {}, capacity {capacity}, identity {}",
                hello.pid, hello.host, g.identity
            ),
            None => format!("pid {} on {}, capacity {capacity}", hello.pid, hello.host),
        };
        match self.modules.get_mut(&name) {
            Some(state) => {
                // A module coming back: keep what waits for it; it is delivered once the module
                // registers its handlers again.
                state.link = Some(link);
                state.hello = hello;
                state.capacity = capacity;
                state.running = 0;
                state.down_since = None;
                state.grant = grant;
            }
            None => {
                self.modules.insert(
                    name.clone(),
                    ModuleState {
                        link: Some(link),
                        hello,
                        capacity,
                        running: 0,
                        ready: VecDeque::new(),
                        waiting: VecDeque::new(),
                        down_since: None,
                        grant,
                    },
                );
            }
        }
        if let Some(l) = self.links.get_mut(&link) {
            l.module = Some(name.clone());
        }
        tracing::info!(module = %name, link, "module connected");
        self.log_link(link, LinkEvent::Connected, Some(name.clone()), detail, out);
        let welcome = ControlNotice::Welcome(Welcome {
            link,
            central_version: env!("CARGO_PKG_VERSION").to_owned(),
            simulated_clock: self.config.simulated_time,
            journal: self.journal.id,
        });
        let reply = self.notice_envelope(&welcome, Some(envelope.id));
        self.send(link, &reply, out);
    }

    fn refuse(&mut self, link: LinkId, envelope: &Envelope, reason: String, out: &mut Vec<Action>) {
        tracing::warn!(link, %reason, "connection refused");
        self.log_link(
            link,
            LinkEvent::Refused,
            Some(envelope.sender.clone()),
            reason.clone(),
            out,
        );
        self.send_error(link, envelope, RouteError::Refused { reason }, out);
        out.push(Action::Close(link));
        self.links.remove(&link);
    }

    /// A module said goodbye: same as its link closing, but announced.
    pub(super) fn bye(&mut self, link: LinkId, out: &mut Vec<Action>) {
        self.link_closed(link, out);
        out.push(Action::Close(link));
    }

    pub(super) fn link_closed(&mut self, link: LinkId, out: &mut Vec<Action>) {
        let Some(state) = self.links.remove(&link) else {
            return;
        };
        let Some(module) = state.module else {
            self.log_link(link, LinkEvent::Closed, None, String::new(), out);
            return;
        };
        tracing::info!(%module, link, "module disconnected");
        self.log_link(
            link,
            LinkEvent::Closed,
            Some(module.clone()),
            String::new(),
            out,
        );
        let now = self.now;
        if let Some(m) = self.modules.get_mut(&module) {
            m.link = None;
            m.running = 0;
            m.down_since = Some(now);
            for w in m.waiting.iter_mut() {
                w.since_ns = now;
            }
        }
        // On the simulated clock, its handlers end and what was queued for it is handed back.
        for envelope in self.clock.module_gone(&module) {
            self.hand_back(&module, envelope);
        }
        self.drop_tap(&module);
        self.fail_queries_of(&module, out);
        self.requeue_tasks_of(&module, out);
        self.requeue_exceptions_of(&module);
    }

    pub(super) fn log_link(
        &mut self,
        link: LinkId,
        event: LinkEvent,
        module: Option<ModuleName>,
        detail: String,
        out: &mut Vec<Action>,
    ) {
        out.push(Action::Log(LogRecord {
            at_ns: self.now,
            kind: RecordKind::Link(LinkRecord {
                link,
                event,
                module,
                detail,
            }),
        }));
    }
}

/// A control message name (the constants are valid names).
pub(super) fn control_name(name: &'static str) -> MessageName {
    MessageName::new(name).unwrap_or_else(|_| unreachable!("control names are valid"))
}

impl Central {
    /// A control notice from central, answering `correlation`.
    pub(super) fn notice_envelope(
        &mut self,
        notice: &ControlNotice,
        correlation: Option<tca_messages::MessageId>,
    ) -> Envelope {
        let data = notice.encode_data().unwrap_or_default();
        self.central_envelope(
            Class::Control,
            control_name(notice.name()),
            correlation,
            data,
        )
    }
}
