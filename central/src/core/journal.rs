//! What the core gives its journal and takes back from it (the file is `crate::journal`'s).
//!
//! The core is deterministic: the same events at the same times give the same state and the
//! same actions. So the journal keeps what the core was given, not what it did: every event
//! with its time ([`JournalEntry`]), plus the few answers the core looked up outside itself while
//! handling it ([`Fact`]: whether a module's old process was gone, what the policy said of a
//! hello), and, now and then, the core's whole state ([`Central::save`]). A central restarted on
//! the journal restores the latest state ([`Central::restore`]) and hands the entries after it
//! to the core again ([`Central::replay`]): the facts are then taken from the entries, not
//! looked up again, so the core comes to the very state it had. What the replay sends goes
//! nowhere (those links are gone); what it logs is what the crashed central logged, which lets
//! the restarted one write what its log lost.
//!
//! A hello's secret never reaches the journal: the frame is kept with the secret blanked, as in
//! the traffic log, and what the policy made of it is kept as a fact.

use std::collections::VecDeque;

use bytes::Bytes;
use serde::{Deserialize, Serialize};

use super::{Action, Central, Event, InboxUse, LinkId, OutboxUse};
use crate::config::CentralConfig;
use crate::journal::format;
use crate::policy::{Grant, Permissions};

/// One event the core handled, with its time and the facts it looked up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JournalEntry {
    /// The time the driver handed the event with (nanoseconds since the UNIX epoch).
    pub at_ns: u64,
    /// The event.
    pub event: JournaledEvent,
    /// What the core looked up outside itself while handling it, in order.
    pub facts: Vec<Fact>,
}

/// An [`Event`] as the journal keeps it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum JournaledEvent {
    /// [`Event::Opened`].
    Opened(LinkId),
    /// [`Event::Frame`] (a hello's secret blanked).
    Frame(
        LinkId,
        #[serde(with = "tca_logs::record::bytes_serde")] Bytes,
    ),
    /// [`Event::Closed`].
    Closed(LinkId),
    /// [`Event::Tick`].
    Tick,
    /// [`Event::InboxFull`]: the frame and the inbox's frames and bytes.
    InboxFull(
        LinkId,
        #[serde(with = "tca_logs::record::bytes_serde")] Bytes,
        (u64, u64),
    ),
    /// [`Event::InboxDropped`].
    InboxDropped(LinkId, u64),
    /// [`Event::OutboxLevel`]: the outbox's frames and bytes.
    OutboxLevel(LinkId, (u64, u64)),
    /// [`Event::OutboxFull`]: the outbox's frames and bytes.
    OutboxFull(LinkId, (u64, u64)),
    /// [`Event::Identified`]: the identity the transport authenticated.
    Identified(LinkId, String),
}

/// An [`Event`] borrowed, serialized exactly as the [`JournaledEvent`] it journals as (the
/// same variants, in the same order, with the same fields), so that an entry is written
/// straight from the event: its frame is neither copied into a new buffer nor shared (a shared
/// frame's count is an atomic the sending thread touches too).
#[derive(Serialize)]
enum JournaledEventRef<'a> {
    Opened(LinkId),
    Frame(LinkId, RawBytes<'a>),
    Closed(LinkId),
    Tick,
    InboxFull(LinkId, RawBytes<'a>, (u64, u64)),
    InboxDropped(LinkId, u64),
    OutboxLevel(LinkId, (u64, u64)),
    OutboxFull(LinkId, (u64, u64)),
    Identified(LinkId, &'a str),
}

/// Bytes serialized as a byte string, as `tca_logs::record::bytes_serde` serializes [`Bytes`].
struct RawBytes<'a>(&'a [u8]);

impl Serialize for RawBytes<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(self.0)
    }
}

impl<'a> From<&'a Event> for JournaledEventRef<'a> {
    fn from(event: &'a Event) -> Self {
        match event {
            Event::Opened(l) => Self::Opened(*l),
            Event::Frame(l, f) => Self::Frame(*l, RawBytes(f)),
            Event::Closed(l) => Self::Closed(*l),
            Event::Tick => Self::Tick,
            Event::InboxFull(l, f, u) => Self::InboxFull(*l, RawBytes(f), (u.frames, u.bytes)),
            Event::InboxDropped(l, n) => Self::InboxDropped(*l, *n),
            Event::OutboxLevel(l, u) => Self::OutboxLevel(*l, (u.frames, u.bytes)),
            Event::OutboxFull(l, u) => Self::OutboxFull(*l, (u.frames, u.bytes)),
            Event::Identified(l, id) => Self::Identified(*l, id),
        }
    }
}

/// An entry being written while its event is handled: where its record starts in the
/// recorder's buffer, and the link of its frame (a hello's is rewritten with its secret
/// blanked).
pub(super) struct OpenEntry {
    start: usize,
    frame_link: Option<LinkId>,
}

impl From<JournaledEvent> for Event {
    fn from(event: JournaledEvent) -> Self {
        let outbox = |(frames, bytes)| OutboxUse { frames, bytes };
        match event {
            JournaledEvent::Opened(l) => Event::Opened(l),
            JournaledEvent::Frame(l, f) => Event::Frame(l, f),
            JournaledEvent::Closed(l) => Event::Closed(l),
            JournaledEvent::Tick => Event::Tick,
            JournaledEvent::InboxFull(l, f, (frames, bytes)) => {
                Event::InboxFull(l, f, InboxUse { frames, bytes })
            }
            JournaledEvent::InboxDropped(l, n) => Event::InboxDropped(l, n),
            JournaledEvent::OutboxLevel(l, u) => Event::OutboxLevel(l, outbox(u)),
            JournaledEvent::OutboxFull(l, u) => Event::OutboxFull(l, outbox(u)),
            JournaledEvent::Identified(l, id) => Event::Identified(l, id),
        }
    }
}

/// Something the core looked up outside itself while handling an event.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Fact {
    /// Whether the process of a module saying hello again was gone (its old link is then
    /// replaced instead of the hello being refused).
    ProcessGone(bool),
    /// What the policy made of a hello: the module's grant (None without a policy), or why it
    /// was refused.
    Admission(Result<Option<SavedGrant>, String>),
}

/// A module's grant as saved: its identity and permissions.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SavedGrant {
    identity: String,
    who: String,
    modules: Vec<String>,
    register: Vec<String>,
    send: Vec<String>,
}

impl From<&Grant> for SavedGrant {
    fn from(grant: &Grant) -> Self {
        let p = grant.permissions();
        SavedGrant {
            identity: grant.identity.clone(),
            who: p.who.clone(),
            modules: p.modules.clone(),
            register: p.register.clone(),
            send: p.send.clone(),
        }
    }
}

impl From<SavedGrant> for Grant {
    fn from(saved: SavedGrant) -> Self {
        Grant::restored(
            saved.identity,
            Permissions {
                who: saved.who,
                modules: saved.modules,
                register: saved.register,
                send: saved.send,
            },
        )
    }
}

/// Why the core could not go back to a saved state or replay an entry.
#[derive(Debug, thiserror::Error)]
pub enum RestoreError {
    /// The saved state does not decode.
    #[error("the saved state does not decode: {0}")]
    State(String),
    /// The saved state was kept on the other kind of clock.
    #[error(
        "the saved state was kept on {saved}, but this central runs on {now}; start it with the \
         same clock (--simulated-time or not)"
    )]
    Clock {
        /// The saved state's clock.
        saved: &'static str,
        /// This central's.
        now: &'static str,
    },
    /// An entry asked for a fact the journal did not hold, or held another.
    #[error("the entry of {at_ns} ns does not fit this central: {reason}")]
    JournalEntry {
        /// The entry's time.
        at_ns: u64,
        /// What did not fit.
        reason: String,
    },
}

/// The core's side of journaling: the entries it writes and, while replaying, the facts it
/// reads back. Not part of the saved state.
#[derive(Debug, Default)]
pub(super) struct Recorder {
    /// Entries are written to `entries`.
    on: bool,
    /// Framed entries not yet taken by the driver (see `crate::journal::format`).
    entries: Vec<u8>,
    /// Facts of the event being handled.
    facts: Vec<Fact>,
    /// While replaying: the facts of the entry being replayed, in order.
    replay: Option<VecDeque<Fact>>,
    /// The first fact a replay lacked, or that did not fit.
    mismatch: Option<String>,
    /// The frame to keep in place of the one being handled (a hello with its secret blanked).
    redacted: Option<Bytes>,
    /// The journal's id, told to modules in their welcome.
    pub(super) id: Option<u64>,
}

fn clock_name(on: bool) -> &'static str {
    if on {
        "the simulated clock"
    } else {
        "the wall clock"
    }
}

impl Central {
    /// Starts writing an entry for every event handled (taken with
    /// [`Central::take_journal`]); `id` is the journal's, told to modules in their welcome.
    pub fn record_journal(&mut self, id: u64) {
        self.journal.on = true;
        self.journal.id = Some(id);
    }

    /// Tells modules in their welcome that central keeps journal `id` (without writing entries:
    /// a restored central replaying its journal welcomes as the crashed one did).
    pub fn set_journal_id(&mut self, id: u64) {
        self.journal.id = Some(id);
    }

    /// Moves the framed entries written since the last call to the end of `into`.
    pub fn take_journal(&mut self, into: &mut Vec<u8>) {
        if into.is_empty() {
            std::mem::swap(into, &mut self.journal.entries);
        } else {
            into.append(&mut self.journal.entries);
        }
    }

    /// The whole state of central (not its configuration), for its journal. The form is
    /// central's own: the journal that keeps it names the version that wrote it.
    pub fn save(&self) -> Result<Vec<u8>, postcard::Error> {
        postcard::to_allocvec(self)
    }

    /// A central in the state [`Central::save`] saved, with `config`.
    pub fn restore(state: &[u8], config: CentralConfig) -> Result<Central, RestoreError> {
        let mut central: Central =
            postcard::from_bytes(state).map_err(|e| RestoreError::State(e.to_string()))?;
        if central.clock.on != config.simulated_time {
            return Err(RestoreError::Clock {
                saved: clock_name(central.clock.on),
                now: clock_name(config.simulated_time),
            });
        }
        central.set_config(config);
        Ok(central)
    }

    /// Changes the configuration (limits, policy) from now on. The clock cannot change: a
    /// simulated clock stays on, a wall clock stays off.
    pub fn set_config(&mut self, config: CentralConfig) {
        self.outbox_limits =
            tca_link::OutboxLimits::new(config.max_outbox_frames, config.max_outbox_bytes);
        self.config = CentralConfig {
            simulated_time: self.clock.on,
            ..config
        };
    }

    /// Handles a journaled event again, with the facts it holds, appending the actions to
    /// `out`.
    pub fn replay(
        &mut self,
        entry: JournalEntry,
        out: &mut Vec<Action>,
    ) -> Result<(), RestoreError> {
        let recording = std::mem::replace(&mut self.journal.on, false);
        self.journal.replay = Some(entry.facts.into());
        self.journal.mismatch = None;
        self.handle(entry.at_ns, entry.event.into(), out);
        let left = self.journal.replay.take().map_or(0, |f| f.len());
        self.journal.on = recording;
        let reason = match (self.journal.mismatch.take(), left) {
            (Some(reason), _) => reason,
            (None, 0) => return Ok(()),
            (None, n) => format!("{n} fact(s) it holds were not asked for"),
        };
        Err(RestoreError::JournalEntry {
            at_ns: entry.at_ns,
            reason,
        })
    }

    /// After a restart: every link the saved central had is gone with its process. Each
    /// closes as a module that went down: the goals and commands it was running wait to be
    /// delivered again (marked as redeliveries), the queries it asked or was answering fail,
    /// what waits for it waits on.
    pub fn links_lost(&mut self, now_ns: u64, out: &mut Vec<Action>) {
        let mut links: Vec<LinkId> = self.links.keys().copied().collect();
        links.sort_unstable();
        for link in links {
            self.handle(now_ns, Event::Closed(link), out);
        }
    }

    /// The highest link number central has seen: a restarted central numbers new links after
    /// it, so that message ids (which carry their link's number) are never used twice.
    pub fn highest_link(&self) -> LinkId {
        self.max_link
    }

    /// Whether the module process named in a hello is gone; a fact, journaled or replayed.
    pub(super) fn process_gone(&mut self, host: &str, pid: u32) -> bool {
        match self.replayed_fact() {
            Some(Some(Fact::ProcessGone(gone))) => gone,
            Some(other) => {
                self.misfit(other, "whether a process was gone");
                false
            }
            None => {
                let gone = crate::process::is_gone(host, pid);
                self.note_fact(Fact::ProcessGone(gone));
                gone
            }
        }
    }

    /// What the policy makes of a hello; a fact, journaled or replayed.
    pub(super) fn admission(
        &mut self,
        module: &str,
        credentials: Option<&tca_messages::control::Credentials>,
        transport_identity: Option<&str>,
    ) -> Result<Option<Grant>, String> {
        match self.replayed_fact() {
            Some(Some(Fact::Admission(result))) => result.map(|g| g.map(Grant::from)),
            Some(other) => {
                self.misfit(other, "what the policy made of a hello");
                Err("the journal does not say what the policy made of this hello".into())
            }
            None => {
                let result = match &self.config.policy {
                    Some(policy) => policy
                        .authenticate(module, credentials, transport_identity)
                        .map(Some),
                    None => Ok(None),
                };
                if self.journal.on {
                    let saved = result
                        .as_ref()
                        .map(|g| g.as_ref().map(SavedGrant::from))
                        .map_err(Clone::clone);
                    self.note_fact(Fact::Admission(saved));
                }
                result
            }
        }
    }

    /// The frame to journal in place of the one being handled.
    pub(super) fn journal_redacted(&mut self, frame: &Bytes) {
        if self.journal.on {
            self.journal.redacted = Some(frame.clone());
        }
    }

    /// While replaying, the next fact of the entry (None inside when it has no more); None
    /// when not replaying.
    fn replayed_fact(&mut self) -> Option<Option<Fact>> {
        self.journal.replay.as_mut().map(VecDeque::pop_front)
    }

    fn misfit(&mut self, fact: Option<Fact>, wanted: &str) {
        let reason = match fact {
            Some(f) => format!("it holds {f:?} where {wanted} was asked for"),
            None => format!("it holds no fact where {wanted} was asked for"),
        };
        self.journal.mismatch.get_or_insert(reason);
    }

    fn note_fact(&mut self, fact: Fact) {
        if self.journal.on {
            self.journal.facts.push(fact);
        }
    }

    /// Called before an event is handled: starts its entry (the time and the event; the facts
    /// looked up while handling it follow in [`Central::journal_end`]).
    pub(super) fn journal_begin(&mut self, at_ns: u64, event: &Event) -> Option<OpenEntry> {
        if !self.journal.on {
            return None;
        }
        let buf = &mut self.journal.entries;
        let start = format::begin_record(buf);
        if let Err(e) = postcard::to_io(&(at_ns, JournaledEventRef::from(event)), &mut *buf) {
            buf.truncate(start);
            tracing::error!(error = %e, "an event could not be journaled");
            return None;
        }
        let frame_link = match event {
            Event::Frame(l, _) => Some(*l),
            _ => None,
        };
        Some(OpenEntry { start, frame_link })
    }

    /// Called after an event was handled: ends its entry with the facts looked up (the same
    /// bytes as a [`JournalEntry`] of the time, the event and the facts).
    pub(super) fn journal_end(&mut self, at_ns: u64, open: Option<OpenEntry>) {
        let redacted = self.journal.redacted.take();
        let Some(OpenEntry { start, frame_link }) = open else {
            return;
        };
        let buf = &mut self.journal.entries;
        let mut written: postcard::Result<()> = Ok(());
        if let (Some(frame), Some(link)) = (redacted, frame_link) {
            buf.truncate(start + format::RECORD_HEADER);
            let event = JournaledEventRef::Frame(link, RawBytes(&frame));
            written = postcard::to_io(&(at_ns, event), &mut *buf).map(drop);
        }
        let written = written
            .and_then(|()| postcard::to_io(self.journal.facts.as_slice(), &mut *buf).map(drop));
        self.journal.facts.clear();
        match written {
            Ok(()) => format::end_record(buf, start),
            Err(e) => {
                buf.truncate(start);
                tracing::error!(error = %e, "an event could not be journaled");
            }
        }
    }
}

/// A grant as saved (identity and permissions), for `#[serde(with)]`.
pub(super) mod grant_serde {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use super::SavedGrant;
    use crate::policy::Grant;

    pub(in crate::core) fn serialize<S: Serializer>(
        v: &Option<Grant>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        v.as_ref().map(SavedGrant::from).serialize(s)
    }

    pub(in crate::core) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<Grant>, D::Error> {
        Ok(Option::<SavedGrant>::deserialize(d)?.map(Grant::from))
    }
}

/// An outbox level as (frames, bytes), for `#[serde(with)]`.
pub(super) mod outbox_serde {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    use tca_link::OutboxUse;

    pub(in crate::core) fn serialize<S: Serializer>(
        v: &OutboxUse,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        (v.frames, v.bytes).serialize(s)
    }

    pub(in crate::core) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<OutboxUse, D::Error> {
        let (frames, bytes) = <(u64, u64)>::deserialize(d)?;
        Ok(OutboxUse { frames, bytes })
    }
}
