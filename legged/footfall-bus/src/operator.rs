//! The operator's side of sending a plan: the `footfall.execute` command, and the robot's
//! telemetry (`legged.supportState`, `legged.footContact`) as it comes back while the plan
//! is carried out.

use std::time::Duration;

use tca_footfall::plan::FootfallPlan;
use tca_legged_messages::{FootContact, SupportState};
use tca_messages::control::TaskOutcome;
use tca_messages::{Message, decode_data};
use tca_module::{Module, ModuleError};

use crate::messages::FootfallExecute;

/// A piece of telemetry seen while a plan runs.
#[derive(Clone, Debug, PartialEq)]
pub enum Telemetry {
    /// The robot's support state (body, centre of mass, feet, margin).
    Support(SupportState),
    /// A foot lifted off or touched down.
    Contact(FootContact),
}

/// Sends `plan` to the executor from `operator` and waits for its end, passing the
/// telemetry seen meanwhile to `seen`; the outcome. Telemetry still on its way when the
/// plan ends is waited for up to `linger`.
pub async fn send_plan(
    operator: &Module,
    plan: &FootfallPlan,
    linger: Duration,
    mut seen: impl FnMut(Telemetry),
) -> Result<TaskOutcome, ModuleError> {
    let mut tap = operator
        .tap(&[SupportState::NAME, FootContact::NAME])
        .await?;
    let task = operator.send_watched(&FootfallExecute { plan: plan.clone() }, [])?;
    let outcome = task.outcome();
    tokio::pin!(outcome);
    let mut pass = |env: tca_messages::Envelope| {
        if env.name.as_str() == SupportState::NAME {
            if let Ok(s) = decode_data::<SupportState>(&env.data) {
                seen(Telemetry::Support(s));
            }
        } else if env.name.as_str() == FootContact::NAME
            && let Ok(c) = decode_data::<FootContact>(&env.data)
        {
            seen(Telemetry::Contact(c));
        }
    };
    let result = loop {
        tokio::select! {
            r = &mut outcome => break r,
            env = tap.next() => match env {
                Some(env) => pass(env),
                None => break Err(ModuleError::Disconnected),
            },
        }
    };
    // What was sent before the end and is still in flight.
    while let Ok(Some(env)) = tokio::time::timeout(linger, tap.next()).await {
        pass(env);
    }
    result
}
