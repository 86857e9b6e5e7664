//! The module and its handlers over one shared simulator.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tca_legged_messages::{
    BodyMove, BodyPose, FootContact, Halt, HardwareFault, LegMove, LegState, LeggedStatus,
    LeggedStatusReply, Resume, RobotDescription, RobotModel, SupportState, Telemetry,
};
use tca_legged_model::RobotModel as Model;
use tca_legged_sim::{
    LeggedSim, MoveError, MoveException, MoveReport, isometry_to_pose, pose_to_isometry,
    world_point,
};
use tca_messages::Message;
use tca_module::{Connector, Context, HandlerError, Module, ModuleError};
use tokio::time::Instant;

use crate::config::{InjectedFault, LeggedControllerConfig};
use crate::telemetry::{Motion, Snapshot, timed_path};

/// Connects the simulated Controller to central under `config.module_name` and serves the
/// `legged.` Controller messages until the returned [`Module`] (and every clone) is dropped
/// or closed. A robot that cannot stand at the start is a [`ModuleError::Config`] saying
/// why.
pub async fn connect(
    connector: &Connector,
    config: LeggedControllerConfig,
) -> Result<Module, ModuleError> {
    let sim = LeggedSim::new(
        config.model.clone(),
        config.terrain.clone(),
        config.start,
        config.params.clone(),
    )
    .map_err(|e| ModuleError::Config(format!("legged controller: {e}")))?;
    config
        .check_wall_clock()
        .map_err(|e| ModuleError::Config(format!("legged controller: {e}")))?;
    for fault in &config.faults {
        fault
            .check(&config.model)
            .map_err(|e| ModuleError::Config(format!("legged controller: {e}")))?;
    }
    let description = RobotDescription {
        name: config.model.name().to_owned(),
        urdf: config.urdf.clone(),
        legs: config
            .model
            .legs()
            .iter()
            .map(|l| l.name().to_owned())
            .collect(),
    };
    tracing::info!(module = %config.module_name, robot = %description.name, "legged controller starting");
    let s = Shared {
        state: Arc::new(Mutex::new(State {
            sim,
            commanded: false,
            faults: config.faults.clone(),
            halted_at_s: None,
            motion: None,
        })),
        turn: Arc::new(tokio::sync::Mutex::new(())),
        model: config.model.clone(),
        speed: config.speed,
    };
    let module = Module::builder(config.module_name.clone())
        .replace(true)
        .simulated_time(config.speed.is_none())
        .handle({
            let s = s.clone();
            move |ctx: Context, m: LegMove| {
                let s = s.clone();
                async move {
                    let legs = vec![m.leg.clone()];
                    let path = Some((m.leg.as_str(), m.waypoints.as_slice()));
                    s.command(&ctx, Moves::Legs(legs), path, |sim| {
                        sim.leg_move(&m.leg, &m.waypoints, m.transition)
                    })
                    .await
                }
            }
        })
        .handle({
            let s = s.clone();
            move |ctx: Context, m: BodyMove| {
                let s = s.clone();
                async move {
                    let target = pose_to_isometry(&m.target);
                    s.command(&ctx, Moves::Standing, None, |sim| sim.body_move(&target))
                        .await
                }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _h: Halt| {
                let mut state = s.lock();
                if state.halted_at_s.is_none() {
                    let at = state.sim.clock_s();
                    state.halted_at_s = Some(at);
                    tracing::warn!(
                        at_s = at,
                        "emergency stop: every move refused until legged.resume"
                    );
                }
                async { Ok(()) }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _r: Resume| {
                if s.lock().halted_at_s.take().is_some() {
                    tracing::info!("emergency stop lifted: moves carried out again");
                }
                async { Ok(()) }
            }
        })
        .handle(move |_ctx, _q: RobotModel| {
            let d = description.clone();
            async move { Ok(d) }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _q: BodyPose| {
                let pose = isometry_to_pose(&s.lock().sim.body());
                async move { Ok(pose) }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, q: LegState| {
                let reply = s
                    .lock()
                    .sim
                    .leg_state(&q.leg)
                    .map_err(|e| HandlerError::new(e.to_string()));
                async move { reply }
            }
        })
        .handle({
            let s = s.clone();
            move |_ctx, _q: LeggedStatus| {
                let reply = {
                    let state = s.lock();
                    let c = state.sim.counters();
                    LeggedStatusReply {
                        clock_s: state.sim.clock_s(),
                        falls: c.falls,
                        collisions: c.collisions,
                        self_collisions: c.self_collisions,
                        fallen: state.sim.fallen(),
                        moves: c.moves,
                    }
                };
                async move { Ok(reply) }
            }
        })
        .connect(connector)
        .await?;
    if (config.telemetry_hz.is_some() || config.speed.is_some())
        && module.central_keeps_simulated_time()
    {
        module.close().await;
        return Err(ModuleError::Config(
            "legged controller: telemetry at a rate and moves in wall-clock time (--telemetry, \
             --speed) need a central on wall-clock time; this central keeps a simulated clock: \
             start it without --simulated-time, or leave both out"
                .into(),
        ));
    }
    if let Some(hz) = config.telemetry_hz {
        tokio::spawn(publish_telemetry(module.downgrade(), s, hz));
    }
    Ok(module)
}

/// How often the telemetry loop looks again whether anyone handles `legged.telemetry`.
const LOOK_AGAIN: Duration = Duration::from_secs(1);

/// Publishes `legged.telemetry` `hz` times a second until the module closes; while no module
/// handles it, says so once and waits.
async fn publish_telemetry(module: tca_module::WeakModule, s: Shared, hz: f64) {
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / hz));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut seq = 0u64;
    let mut handled = false;
    let mut looked: Option<Instant> = None;
    let mut said = false;
    loop {
        tick.tick().await;
        let Some(m) = module.upgrade() else { return };
        if m.is_closed() {
            return;
        }
        if !m.is_online() {
            handled = false;
            continue;
        }
        if !handled {
            if looked.is_some_and(|t| t.elapsed() < LOOK_AGAIN) {
                continue;
            }
            looked = Some(Instant::now());
            handled = match m.registry().await {
                Ok(r) => r.entries.iter().any(|e| e.name.as_str() == Telemetry::NAME),
                Err(_) => false,
            };
            if !handled {
                if !said {
                    tracing::info!(
                        "no module handles {} yet; the Controller publishes telemetry once one does",
                        Telemetry::NAME
                    );
                    said = true;
                }
                continue;
            }
        }
        let sample = s.sample(seq);
        match m.inform(&sample) {
            Ok(()) => seq += 1,
            Err(e) => tracing::warn!(error = %e, "telemetry not sent"),
        }
    }
}

struct State {
    sim: LeggedSim,
    /// Whether a command came already (the first sends the state before it).
    commanded: bool,
    /// Hardware faults to inject.
    faults: Vec<InjectedFault>,
    /// When the emergency stop came (motion clock, seconds), until a resume.
    halted_at_s: Option<f64>,
    /// The move under way in wall-clock time, if any.
    motion: Option<Motion>,
}

impl State {
    /// The fault that refuses a command now: the emergency stop, or the first injected
    /// fault active on one of the legs it moves.
    fn fault_for(&self, moves: &Moves) -> Option<HardwareFault> {
        if let Some(at) = self.halted_at_s {
            return Some(HardwareFault {
                leg: None,
                detail: format!(
                    "the Controller is halted by an emergency stop (legged.halt at {at:.1} s of \
                     motion); nothing was moved: send legged.resume to move again"
                ),
            });
        }
        self.injected_fault(moves)
    }

    /// The first injected fault active now on one of the legs a command moves.
    fn injected_fault(&self, moves: &Moves) -> Option<HardwareFault> {
        let legs = match moves {
            Moves::Legs(legs) => legs.clone(),
            Moves::Standing => self.sim.standing_legs(),
        };
        let clock_s = self.sim.clock_s();
        let fault = self
            .faults
            .iter()
            .find(|f| f.active_at(clock_s) && legs.contains(&f.leg))?;
        Some(HardwareFault {
            leg: Some(fault.leg.clone()),
            detail: format!(
                "the drives of leg {} stopped responding at {:.1} s of motion (an injected fault); nothing was moved",
                fault.leg, fault.at_s
            ),
        })
    }
}

/// Which legs a command moves.
enum Moves {
    /// These legs.
    Legs(Vec<String>),
    /// Every standing leg (a body move).
    Standing,
}

#[derive(Clone)]
struct Shared {
    state: Arc<Mutex<State>>,
    /// Held by a command for its whole run.
    turn: Arc<tokio::sync::Mutex<()>>,
    /// The robot.
    model: Arc<Model>,
    /// Moves take their duration divided by this on the wall clock (`None`: simulated time).
    speed: Option<f64>,
}

/// What a command sends, in order.
enum Outgoing {
    State(SupportState),
    Contact(FootContact),
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A telemetry sample of the robot now (part-way through a move under way).
    fn sample(&self, seq: u64) -> Telemetry {
        let snapshot = {
            let state = self.lock();
            match &state.motion {
                Some(m) if m.started.elapsed() < m.wall => m.at(m.started.elapsed()),
                _ => Snapshot::of(&state.sim),
            }
        };
        snapshot.sample(&self.model, seq)
    }

    /// Runs a move on the simulator, sends its informs, spends its time (simulated, or on the
    /// wall clock with a speed, the informs then going out as their events happen), then
    /// raises a failure's exception and ends. `path` is a leg move's leg and way-points.
    async fn command(
        &self,
        ctx: &Context,
        moves: Moves,
        path: Option<(&str, &[Vec<f64>])>,
        run: impl FnOnce(&mut LeggedSim) -> Result<MoveReport, MoveError>,
    ) -> Result<(), HandlerError> {
        let _turn = self.turn.lock().await;
        let fault = self.lock().fault_for(&moves);
        if let Some(fault) = fault {
            tracing::warn!(leg = ?fault.leg, detail = %fault.detail, "a command refused");
            if let Err(r) = ctx.raise(&fault) {
                tracing::warn!(error = %r, "could not raise the hardware fault");
            }
            return Err(HandlerError::new(fault.detail));
        }
        let (outgoing, duration_s, result, motion) = {
            let mut state = self.lock();
            let mut outgoing = Vec::new();
            if !state.commanded {
                state.commanded = true;
                outgoing.push((0.0, Outgoing::State(state.sim.support_state())));
            }
            let before = self.speed.map(|_| Snapshot::of(&state.sim));
            let result = run(&mut state.sim);
            let report = match &result {
                Ok(r) => Some(r.clone()),
                Err(e) if e.moved() => state.sim.last_move().cloned(),
                Err(_) => None,
            };
            let mut duration_s = 0.0;
            if let Some(r) = report {
                duration_s = r.duration_s;
                for e in r.events {
                    let at = (e.t_s - r.start_s).max(0.0);
                    outgoing.push((
                        at,
                        Outgoing::Contact(FootContact {
                            leg: e.leg_name.clone(),
                            at: world_point(&e.at),
                            stance: e.stance,
                        }),
                    ));
                    if !e.stance {
                        outgoing.push((at, Outgoing::State(e.state)));
                    }
                }
                outgoing.push((duration_s, Outgoing::State(state.sim.support_state())));
            }
            let motion = match (self.speed, before) {
                (Some(speed), Some(before)) if duration_s > 0.0 && duration_s.is_finite() => {
                    let leg_path = path.and_then(|(leg, waypoints)| {
                        let i = self.model.leg_index(leg)?;
                        let start = before.posture.get(i)?;
                        Some((i, timed_path(&self.model, i, start, waypoints)?))
                    });
                    Some(Motion {
                        started: Instant::now(),
                        wall: Duration::from_secs_f64(duration_s / speed),
                        after: Snapshot::of(&state.sim),
                        before,
                        leg_path,
                    })
                }
                _ => None,
            };
            state.motion = motion.clone();
            (outgoing, duration_s, result, motion)
        };
        for (at_s, o) in &outgoing {
            if let (Some(m), Some(speed)) = (&motion, self.speed) {
                tokio::time::sleep_until(m.started + Duration::from_secs_f64(at_s / speed)).await;
            }
            let sent = match o {
                Outgoing::State(s) => ctx.inform(s),
                Outgoing::Contact(c) => ctx.inform(c),
            };
            if let Err(e) = sent {
                tracing::warn!(error = %e, "could not send a controller inform");
            }
        }
        match &motion {
            Some(m) => {
                tokio::time::sleep_until(m.started + m.wall).await;
                self.lock().motion = None;
            }
            None if self.speed.is_none() && duration_s > 0.0 && duration_s.is_finite() => {
                ctx.spend(Duration::from_secs_f64(duration_s));
            }
            None => {}
        }
        match result {
            Ok(_) => Ok(()),
            Err(e) => {
                let raised = match e.to_exception() {
                    MoveException::MoveFailed(m) => ctx.raise(&m),
                    MoveException::TipOver(t) => ctx.raise(&t),
                };
                if let Err(r) = raised {
                    tracing::warn!(error = %r, reason = %e, "could not raise the controller's exception");
                }
                Err(HandlerError::new(e.to_string()))
            }
        }
    }
}
