//! A stand-in: a module played back from its script ([`tca_logs::script`](mod@tca_logs::script)). It registers the
//! recorded module's messages with their recorded formats and answers each delivery with what
//! the recorded module did for the same (asker, message name), in recorded order (preferring,
//! among the next few, one whose recorded data is the same as the delivery's): the
//! messages it sent while handling (queries, goals, commands, informs, exceptions, task-tree
//! control), then its reply, success or failure, each after the recorded own (simulated)
//! time.
//!
//! Recorded task-node and message ids are mapped to the live ones as they become known: a
//! node when it is delivered to the stand-in, a message id when the stand-in sends the
//! message. A constraint naming something not known live is dropped (with a warning).

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex, MutexGuard};

use tca_logs::script::{AnswerOutcome, ModuleScript, ScriptAction};
use tca_messages::control::ControlRequest;
use tca_messages::{Class, ConstraintSpec, MessageId, NodeId, PointRef, TaskRef};
use tca_module::{Connector, Context, HandlerError, Module, ModuleError};

/// Live counterparts of recorded ids, and what is left to play.
#[derive(Debug, Default)]
struct State {
    /// (asker, message name) -> handlings still to play, in order.
    queues: HashMap<(String, String), VecDeque<usize>>,
    /// Recorded node -> live node.
    nodes: HashMap<NodeId, NodeId>,
    /// Recorded message id (sent by this module) -> live id.
    ids: HashMap<MessageId, MessageId>,
    /// Deliveries the record had no handling left for.
    unscripted: usize,
}

/// A connected stand-in.
#[derive(Clone, Debug)]
pub struct StandIn {
    /// The module.
    pub module: Module,
    script: Arc<ModuleScript>,
    state: Arc<Mutex<State>>,
}

fn lock(state: &Mutex<State>) -> MutexGuard<'_, State> {
    state.lock().unwrap_or_else(|p| p.into_inner())
}

impl StandIn {
    /// Deliveries that had no recorded handling left (the live run asked for more).
    pub fn unscripted(&self) -> usize {
        lock(&self.state).unscripted
    }

    /// Recorded handlings never asked for, counting only those `counts` accepts (by the
    /// handling's position in the log and its asker).
    pub fn unplayed(&self, counts: impl Fn(usize, &str) -> bool) -> usize {
        let state = lock(&self.state);
        state
            .queues
            .values()
            .flatten()
            .filter(|&&i| {
                self.script
                    .handlings
                    .get(i)
                    .is_some_and(|h| counts(h.position, h.delivery.sender.as_str()))
            })
            .count()
    }
}

/// Connects a stand-in playing `script`.
pub async fn connect(connector: &Connector, script: ModuleScript) -> Result<StandIn, ModuleError> {
    let mut state = State::default();
    for (i, h) in script.handlings.iter().enumerate() {
        state
            .queues
            .entry((h.delivery.sender.to_string(), h.delivery.name.to_string()))
            .or_default()
            .push_back(i);
    }
    let script = Arc::new(script);
    let state = Arc::new(Mutex::new(state));
    let mut builder = Module::builder(script.module.to_string())
        .capacity(script.capacity)
        .simulated_time(script.simulated_time);
    for registration in &script.registrations {
        let (script, state) = (script.clone(), state.clone());
        let name = registration.name.to_string();
        builder = builder.handle_raw(registration.clone(), move |ctx, data| {
            let (script, state, name) = (script.clone(), state.clone(), name.clone());
            async move { play(ctx, &name, &data, &script, &state).await }
        });
    }
    let module = builder.connect(connector).await?;
    Ok(StandIn {
        module,
        script,
        state,
    })
}

/// How far down its queue a delivery looks for a recorded one with the same data.
pub const LOOKAHEAD: usize = 16;

/// The handling to play for a delivery with `data`: the first of the next [`LOOKAHEAD`] queued
/// whose recorded data is the same (deliveries may come in another order than recorded, e.g.
/// steps planned concurrently), else the next in recorded order.
fn take_next(queue: &mut VecDeque<usize>, script: &ModuleScript, data: &[u8]) -> Option<usize> {
    let same = queue.iter().take(LOOKAHEAD).position(|&i| {
        script
            .handlings
            .get(i)
            .is_some_and(|h| h.delivery.data == data)
    });
    queue.remove(same.unwrap_or(0))
}

/// Plays the next recorded handling of (asker, `name`).
async fn play(
    ctx: Context,
    name: &str,
    data: &[u8],
    script: &ModuleScript,
    state: &Mutex<State>,
) -> Result<Vec<u8>, HandlerError> {
    let asker = ctx.sender().to_string();
    let next = {
        let mut s = lock(state);
        let next = s
            .queues
            .get_mut(&(asker.clone(), name.to_owned()))
            .and_then(|queue| take_next(queue, script, data));
        if next.is_none() {
            s.unscripted += 1;
        }
        next
    };
    let Some(handling) = next.and_then(|i| script.handlings.get(i)) else {
        let recorded = script
            .handlings
            .iter()
            .filter(|h| h.delivery.sender.as_str() == asker && h.delivery.name.as_str() == name)
            .count();
        tracing::warn!(module = %script.module, %asker, name, recorded, "no recorded handling left");
        return Err(HandlerError::new(format!(
            "replay: the record holds only {recorded} {name} from {asker} to {}; the live run \
             sent more",
            script.module
        )));
    };
    {
        let mut s = lock(state);
        if let (Some(r), Some(l)) = (handling.delivery.node, ctx.node()) {
            s.nodes.insert(r, l);
        }
        if let (Some(r), Some(l)) = (handling.delivery.context, ctx.origin()) {
            s.nodes.insert(r, l);
        }
    }
    for action in &handling.actions {
        // Where a real handler could be cancelled (its node killed), so can this one.
        tokio::task::yield_now().await;
        ctx.spend(action.spend);
        perform(&ctx, action, script, state).await;
    }
    if handling.delivery.class == Class::Inform {
        return Ok(Vec::new()); // nothing answers an inform
    }
    let Some(answer) = &handling.answer else {
        // The recorded handler never ended (its node was killed, or the log ends): wait to be
        // cancelled the same way.
        std::future::pending::<()>().await;
        return Err(HandlerError::new("unreachable"));
    };
    ctx.spend(answer.spend);
    match &answer.outcome {
        AnswerOutcome::Reply(data) => Ok(data.clone()),
        AnswerOutcome::Success => Ok(Vec::new()),
        AnswerOutcome::Failure(reason) => Err(HandlerError::new(reason.clone())),
    }
}

/// Sends one recorded message again, its ids mapped to live ones.
async fn perform(
    ctx: &Context,
    action: &ScriptAction,
    script: &ModuleScript,
    state: &Mutex<State>,
) {
    let env = &action.envelope;
    let name = env.name.as_str();
    let live_context = match env.context {
        None => None,
        Some(c) => lock(state).nodes.get(&c).copied().or(ctx.node()),
    };
    let handle = ctx.in_context(live_context);
    let module = &script.module;
    let node = |n: NodeId| lock(state).nodes.get(&n).copied();
    let outcome: Result<(), ModuleError> = match env.class {
        Class::Query => match handle.query_raw(name, env.data.clone(), None).await {
            // The answer was the live module's business; only sending matters here.
            Ok(_) | Err(ModuleError::HandlerFailed { .. }) => Ok(()),
            Err(e) => Err(e),
        },
        Class::Goal | Class::Command | Class::Inform | Class::Exception => {
            let constraints = if env.class.is_task() {
                remap_constraints(&env.options.constraints, state)
            } else {
                Vec::new()
            };
            // A task sent with notification is sent so again; its end is not awaited here.
            let sent = if env.class.is_task() && env.options.notify {
                handle
                    .send_watched_raw(env.class, name, env.data.clone(), constraints)
                    .map(|t| t.id())
            } else {
                handle.send_raw(env.class, name, env.data.clone(), constraints)
            };
            sent.map(|id| {
                lock(state).ids.insert(env.id, id);
            })
        }
        Class::Control => match ControlRequest::decode(name, &env.data) {
            Ok(ControlRequest::OnException(o)) => match node(o.node) {
                Some(n) => handle.on_exception_raw(n, o.name.as_str()).await,
                None => Err(unknown_node(o.node)),
            },
            // The node may have ended already, as it may have in the record.
            Ok(ControlRequest::Kill(k)) => match node(k.node) {
                Some(n) => handle.kill(n).await.or(Ok(())),
                None => Err(unknown_node(k.node)),
            },
            Ok(ControlRequest::Retry(r)) => match node(r.node) {
                Some(n) => handle.retry(n).await,
                None => Err(unknown_node(r.node)),
            },
            Ok(ControlRequest::Constrain(c)) => match remap_constraint(&c.constraint, state) {
                Some(c) => handle.constrain(c).await,
                None => Err(ModuleError::Protocol(
                    "the recorded constraint names a task not known in the replay".into(),
                )),
            },
            Ok(_) => Ok(()),
            Err(e) => Err(ModuleError::Protocol(e.to_string())),
        },
        _ => Ok(()),
    };
    if let Err(e) = outcome {
        tracing::warn!(%module, message = name, class = %env.class, error = %e, "a recorded message could not be played");
    }
}

fn unknown_node(n: NodeId) -> ModuleError {
    ModuleError::Protocol(format!(
        "recorded node {n} was never delivered to this stand-in in the replay"
    ))
}

fn remap_constraints(constraints: &[ConstraintSpec], state: &Mutex<State>) -> Vec<ConstraintSpec> {
    constraints
        .iter()
        .filter_map(|c| {
            let mapped = remap_constraint(c, state);
            if mapped.is_none() {
                tracing::warn!(constraint = ?c, "constraint dropped: it names a task not known in the replay");
            }
            mapped
        })
        .collect()
}

fn remap_constraint(c: &ConstraintSpec, state: &Mutex<State>) -> Option<ConstraintSpec> {
    let s = lock(state);
    let task = |t: TaskRef| -> Option<TaskRef> {
        Some(match t {
            TaskRef::This => TaskRef::This,
            TaskRef::Message(id) => TaskRef::Message(*s.ids.get(&id)?),
            TaskRef::Node(n) => TaskRef::Node(*s.nodes.get(&n)?),
        })
    };
    Some(ConstraintSpec {
        before: PointRef {
            task: task(c.before.task)?,
            point: c.before.point,
        },
        after: PointRef {
            task: task(c.after.task)?,
            point: c.after.point,
        },
    })
}
