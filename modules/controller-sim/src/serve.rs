//! The Controller module on the bus: one handler per message of §4.2 over a shared
//! [`Controller`].
//!
//! Queries lock the state only to read a snapshot, so they answer at once even while a
//! move plays out. Commands take turns (central gives the module one at a time anyway;
//! the turn lock keeps that true under any capacity), run the simulator, wait the move's
//! wall-clock time, then raise the failure's exception in their own context and end.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tca_module::{Connector, Context, HandlerError, Module, ModuleError};
use tca_single_leg_messages::{
    BodyMove, BodyPosition, CartLegPosition, ControllerState, ControllerStatus, GlobalLegPosition,
    Halt, HardwareFault, JointLegPosition, LegMove, ReadForce, Resume, SetTransForce,
};
use tokio::time::Instant;

use crate::config::{ControllerConfig, SpeedFactor};
use crate::controller::{CommandFailure, CommandRun, Controller, Snapshot};
use crate::convert::{
    Raised, body_pose_to_message, carriage_point_to_message, force_to_message, joints_from_message,
    joints_to_message, world_point_to_message,
};
use crate::persist::{Persistence, StateError};

/// Connects the simulated Controller to central under `config.module_name` and serves the
/// Controller's messages (§4.2) until the returned [`Module`] (and every clone) is dropped
/// or closed.
///
/// Commands: [`LegMove`], [`BodyMove`], [`SetTransForce`], and the emergency stop [`Halt`]
/// (every later command refused, raising `HardwareFault`) and [`Resume`]. Queries: [`BodyPosition`],
/// [`JointLegPosition`], [`CartLegPosition`], [`GlobalLegPosition`], [`ReadForce`],
/// [`ControllerStatus`]. A failed `legMove`/`bodyMove` raises
/// [`MoveFailed`](tca_single_leg_messages::MoveFailed) (or
/// [`HardwareFault`](tca_single_leg_messages::HardwareFault)) in the command's context and ends
/// the command with failure. A bad configuration is a [`ModuleError::Config`] saying what to
/// fix; a state file that cannot be read or written, a [`ModuleError::Io`] or
/// [`ModuleError::Config`].
pub async fn connect(
    connector: &Connector,
    config: ControllerConfig,
) -> Result<Module, ModuleError> {
    // On central's simulated clock the Controller's own clock is the bus's: a message's
    // simulated stamp maps onto an instant after `epoch`, and moves play out in it at the
    // rate of one simulated second a second, whatever the wall-clock pace (`config.speed`).
    // Otherwise moves play out in wall-clock time at that pace (see `Shared::now`).
    let epoch = Instant::now();
    let mut controller = Controller::new(&config, epoch)
        .map_err(|e| ModuleError::Config(format!("controller configuration: {e}")))?;
    let persistence = match &config.state_file {
        Some(path) => {
            let (persistence, saved) = Persistence::open(path).map_err(state_error)?;
            if let Some(saved) = saved {
                controller.restore(&saved, epoch);
                tracing::info!(file = %path.display(), carriage_y_m = saved.sim.carriage.y_m, "controller state restored: the leg is where the last controller left it");
            } else {
                persistence.write(controller.saved()).map_err(state_error)?;
            }
            Some(Arc::new(Mutex::new(persistence)))
        }
        None => None,
    };
    tracing::info!(
        module = %config.module_name,
        speed = %config.speed,
        "simulated controller starting"
    );
    let s = Shared {
        state: Arc::new(Mutex::new(controller)),
        turn: Arc::new(tokio::sync::Mutex::new(())),
        persistence,
        epoch,
        pace: config.speed,
        halted: Arc::new(AtomicBool::new(false)),
    };
    let builder = Module::builder(config.module_name.clone())
        .replace(config.replace)
        .simulated_time(config.bus_simulated_time)
        // Commands.
        .handle({
            let s = s.clone();
            move |ctx: Context, m: LegMove| {
                let s = s.clone();
                async move {
                    let waypoints: Vec<_> = m.waypoints.iter().map(joints_from_message).collect();
                    s.command(&ctx, |c, now| c.leg_move(&waypoints, m.transition, now))
                        .await
                }
            }
        })
        .handle({
            let s = s.clone();
            move |ctx: Context, m: BodyMove| {
                let s = s.clone();
                async move {
                    s.command(&ctx, |c, now| c.body_move(m.target_y_m, now))
                        .await
                }
            }
        })
        .handle({
            let s = s.clone();
            move |ctx: Context, m: SetTransForce| {
                let s = s.clone();
                async move {
                    s.command(&ctx, |c, now| c.set_trans_force(m.force_n, now))
                        .await
                }
            }
        })
        // The emergency stop: it takes no turn, so it is taken while a move plays out.
        .handle({
            let s = s.clone();
            move |_ctx, _h: Halt| {
                if !s.halted.swap(true, Ordering::SeqCst) {
                    tracing::warn!("emergency stop: every command refused until resume");
                }
                async { Ok(()) }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _r: Resume| {
                if s.halted.swap(false, Ordering::SeqCst) {
                    tracing::info!("emergency stop lifted: commands carried out again");
                }
                async { Ok(()) }
            }
        })
        // Queries.
        .handle({
            let s = s.clone();
            move |_ctx, _q: BodyPosition| {
                let snap = s.snapshot(&_ctx);
                async move { Ok(body_pose_to_message(&snap.carriage)) }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _q: JointLegPosition| {
                let snap = s.snapshot(&_ctx);
                async move { Ok(joints_to_message(&snap.joints)) }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _q: CartLegPosition| {
                let snap = s.snapshot(&_ctx);
                async move { Ok(carriage_point_to_message(&snap.cart_leg)) }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _q: GlobalLegPosition| {
                let snap = s.snapshot(&_ctx);
                async move { Ok(world_point_to_message(&snap.global_leg)) }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _q: ReadForce| {
                let snap = s.snapshot(&_ctx);
                async move { Ok(force_to_message(&snap.force)) }
            }
        })
        .handle(move |_ctx, _q: ControllerStatus| {
            let snap = s.snapshot(&_ctx);
            async move {
                Ok(ControllerState {
                    clock_s: snap.clock.as_secs_f64(),
                    foot_planted: snap.foot_planted,
                    collisions: snap.collisions,
                })
            }
        });
    builder.connect(connector).await
}

/// A state file that cannot be used, as the module library's error.
fn state_error(e: StateError) -> ModuleError {
    match e {
        StateError::Io { path, source } => ModuleError::Io {
            what: format!("controller state file {}", path.display()),
            source,
        },
        other => ModuleError::Config(other.to_string()),
    }
}

/// Connects the built-in Controller ([`ControllerConfig::builtin`]: obstacle course 1, the
/// foot planted at the start of the rails, real time) for `tca module controller`. Choosing
/// another course or speed is the caller's job: build a [`ControllerConfig`] and call
/// [`connect`].
pub async fn run_builtin(connector: &Connector) -> Result<Module, ModuleError> {
    let config = ControllerConfig::builtin()
        .map_err(|e| ModuleError::Config(format!("built-in controller configuration: {e}")))?;
    connect(connector, config).await
}

/// What every handler shares.
#[derive(Clone)]
struct Shared {
    state: Arc<Mutex<Controller>>,
    /// Held by a command for its whole run, wall-clock wait included.
    turn: Arc<tokio::sync::Mutex<()>>,
    /// The state file, when the Controller keeps one.
    persistence: Option<Arc<Mutex<Persistence>>>,
    /// On central's simulated clock: the instant simulated time 0 maps onto.
    epoch: Instant,
    /// How fast moves play out against the wall clock.
    pace: SpeedFactor,
    /// Whether an emergency stop holds (from `halt` until `resume`).
    halted: Arc<AtomicBool>,
}

/// Settles the move in progress when its command's handler ends before the move has played
/// out (its task killed, or central gone and the handler with it). The simulator already
/// stands at the move's end: from then on the queries answer that, and the next command
/// starts from it, instead of the queries showing a move part-way that nothing waits for.
struct SettleIfAbandoned<'a> {
    shared: &'a Shared,
    /// On central's simulated clock: the move's end. Otherwise the move ends when abandoned.
    end_on_clock: Option<Instant>,
    armed: bool,
}

impl SettleIfAbandoned<'_> {
    /// The move played out: nothing to do.
    fn disarm(mut self) {
        self.armed = false;
    }
}

impl Drop for SettleIfAbandoned<'_> {
    fn drop(&mut self) {
        if self.armed {
            let at = self.end_on_clock.unwrap_or_else(Instant::now);
            tracing::debug!("a move's command ended before the move played out; settling it");
            self.shared.lock().settle(at);
        }
    }
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Controller> {
        // A panic while holding the lock cannot leave the simulator half-updated in a way
        // that matters more than stopping; keep serving.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The instant a handler acts at, and the pace moves play out at. On central's simulated
    /// clock: the handler's simulated time, one simulated second a second (so a query is
    /// answered with the leg as it is then, part-way through a move). Otherwise: now, at the
    /// configured pace.
    fn now(&self, ctx: &Context) -> (Instant, SpeedFactor) {
        if ctx.on_central_clock() {
            (
                self.epoch + Duration::from_nanos(ctx.time_ns()),
                SpeedFactor::Times(1.0),
            )
        } else {
            (Instant::now(), self.pace)
        }
    }

    /// The state as of the handler's time (the Controller put on that handler's time base).
    fn at(&self, ctx: &Context) -> (MutexGuard<'_, Controller>, Instant) {
        let (now, timeline) = self.now(ctx);
        let mut state = self.lock();
        state.set_timeline(timeline, now);
        (state, now)
    }

    fn snapshot(&self, ctx: &Context) -> Snapshot {
        let (state, now) = self.at(ctx);
        state.snapshot(now)
    }

    /// Runs a command: simulate, wait its wall-clock time, then raise and end.
    async fn command(
        &self,
        ctx: &Context,
        start: impl FnOnce(&mut Controller, Instant) -> CommandRun,
    ) -> Result<(), HandlerError> {
        let _turn = self.turn.lock().await;
        if let Some(outcome) = self.already_done(ctx) {
            // Delivered again after a Controller died before answering, but carried out
            // already: answer as then, without moving the leg a second time.
            tracing::info!(id = %ctx.message_id(), "redelivered command was carried out before; answering with its outcome");
            return self.end(ctx, outcome);
        }
        if self.halted.load(Ordering::SeqCst) {
            let reason = "the Controller is halted by an emergency stop (halt); nothing was \
                          moved: send resume to move again"
                .to_owned();
            tracing::warn!("a command refused: the emergency stop holds");
            return self.end(
                ctx,
                Err(CommandFailure {
                    exception: Some(Raised::HardwareFault(HardwareFault {
                        detail: reason.clone(),
                    })),
                    reason,
                }),
            );
        }
        let on_clock = ctx.on_central_clock();
        let run = {
            let (mut state, started) = self.at(ctx);
            let run = start(&mut state, started);
            if let Some(p) = &self.persistence {
                let mut p = p.lock().unwrap_or_else(|e| e.into_inner());
                if let Err(e) = p.record(ctx.message_id(), &run.outcome, state.saved()) {
                    tracing::error!(error = %e, "cannot save the controller's state; a restart would lose this move");
                }
            }
            run
        };
        tracing::debug!(
            simulated_s = run.simulated.as_secs_f64(),
            wall_s = run.wall.as_secs_f64(),
            ok = run.outcome.is_ok(),
            "controller command"
        );
        let abandoned = SettleIfAbandoned {
            shared: self,
            end_on_clock: on_clock.then_some(run.started + run.simulated),
            armed: true,
        };
        // The move plays out: in wall-clock time, or (on central's simulated clock) at its
        // pace while its end is stamped its simulated duration later.
        let wait = if on_clock {
            self.pace.wall_time(run.simulated)
        } else {
            run.wall
        };
        if !wait.is_zero() {
            tokio::time::sleep(wait).await;
        }
        let ended = if on_clock {
            run.started + run.simulated
        } else {
            Instant::now()
        };
        abandoned.disarm();
        self.lock().settle(ended);
        // On the bus's simulated time (if the module uses it) the move took this long.
        ctx.spend(run.simulated);
        self.end(ctx, run.outcome)
    }

    /// The outcome of this command if a Controller carried it out already.
    fn already_done(&self, ctx: &Context) -> Option<Result<(), CommandFailure>> {
        if ctx.redelivery() == 0 {
            return None;
        }
        let p = self.persistence.as_ref()?;
        let p = p.lock().unwrap_or_else(|e| e.into_inner());
        p.outcome_of(ctx.message_id()).cloned()
    }

    /// Ends a command: raises a failure's exception in its context, then fails.
    fn end(&self, ctx: &Context, outcome: Result<(), CommandFailure>) -> Result<(), HandlerError> {
        let Err(failure) = outcome else {
            return Ok(());
        };
        let raised = match &failure.exception {
            Some(Raised::MoveFailed(e)) => Some(ctx.raise(e)),
            Some(Raised::HardwareFault(e)) => Some(ctx.raise(e)),
            None => None,
        };
        if let Some(Err(e)) = raised {
            tracing::warn!(error = %e, reason = %failure.reason, "could not raise the controller's exception");
        }
        Err(HandlerError::new(failure.reason))
    }
}
