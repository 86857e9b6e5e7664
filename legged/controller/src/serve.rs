//! The module and its handlers over one shared simulator.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tca_legged_messages::{
    BodyMove, BodyPose, FootContact, Halt, HardwareFault, LegMove, LegState, LeggedStatus,
    LeggedStatusReply, Resume, RobotDescription, RobotModel, SupportState,
};
use tca_legged_sim::{
    LeggedSim, MoveError, MoveException, MoveReport, isometry_to_pose, pose_to_isometry,
    world_point,
};
use tca_module::{Connector, Context, HandlerError, Module, ModuleError};

use crate::config::{InjectedFault, LeggedControllerConfig};

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
        })),
        turn: Arc::new(tokio::sync::Mutex::new(())),
    };
    Module::builder(config.module_name.clone())
        .replace(true)
        .simulated_time(true)
        .handle({
            let s = s.clone();
            move |ctx: Context, m: LegMove| {
                let s = s.clone();
                async move {
                    let legs = vec![m.leg.clone()];
                    s.command(&ctx, Moves::Legs(legs), |sim| {
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
                    s.command(&ctx, Moves::Standing, |sim| sim.body_move(&target))
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
        .handle(move |_ctx, _q: LeggedStatus| {
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
        })
        .connect(connector)
        .await
}

struct State {
    sim: LeggedSim,
    /// Whether a command came already (the first sends the state before it).
    commanded: bool,
    /// Hardware faults to inject.
    faults: Vec<InjectedFault>,
    /// When the emergency stop came (motion clock, seconds), until a resume.
    halted_at_s: Option<f64>,
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

    /// Runs a move on the simulator, sends its informs, spends its simulated time, then
    /// raises a failure's exception and ends.
    async fn command(
        &self,
        ctx: &Context,
        moves: Moves,
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
        let (outgoing, duration_s, result) = {
            let mut state = self.lock();
            let mut outgoing = Vec::new();
            if !state.commanded {
                state.commanded = true;
                outgoing.push(Outgoing::State(state.sim.support_state()));
            }
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
                    outgoing.push(Outgoing::Contact(FootContact {
                        leg: e.leg_name.clone(),
                        at: world_point(&e.at),
                        stance: e.stance,
                    }));
                    if !e.stance {
                        outgoing.push(Outgoing::State(e.state));
                    }
                }
                outgoing.push(Outgoing::State(state.sim.support_state()));
            }
            (outgoing, duration_s, result)
        };
        for o in &outgoing {
            let sent = match o {
                Outgoing::State(s) => ctx.inform(s),
                Outgoing::Contact(c) => ctx.inform(c),
            };
            if let Err(e) = sent {
                tracing::warn!(error = %e, "could not send a controller inform");
            }
        }
        if duration_s > 0.0 && duration_s.is_finite() {
            ctx.spend(Duration::from_secs_f64(duration_s));
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
