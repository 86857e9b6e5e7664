//! `tca ping`: query round trips from a pinger module to an echo module through central.

use std::time::{Duration, Instant};

use serde::Serialize;
use tca_module::{Connector, Module, ModuleError};

use crate::echo::{self, Ping};

/// Round-trip statistics, in microseconds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PingReport {
    /// Round trips timed.
    pub n: usize,
    /// Fastest.
    pub min_us: f64,
    /// Median.
    pub p50_us: f64,
    /// 99th percentile.
    pub p99_us: f64,
    /// Slowest.
    pub max_us: f64,
}

/// Connects an echo and a pinger through `connector`, warms up, then times `n` queries.
pub async fn run(
    connector: &Connector,
    n: usize,
    payload: usize,
) -> Result<PingReport, ModuleError> {
    let pid = std::process::id();
    let _echo = echo::connect(connector, &format!("echo-{pid}")).await?;
    let pinger = Module::builder(format!("pinger-{pid}"))
        .connect(connector)
        .await?;
    time(&pinger, n, payload).await
}

/// Connects a pinger through `connector` and times `n` queries to the echo module named
/// `target`, already connected (say, in another process: `tca module echo`).
pub async fn run_target(
    connector: &Connector,
    target: &str,
    n: usize,
    payload: usize,
) -> Result<PingReport, ModuleError> {
    let pinger = Module::builder(format!("pinger-{}", std::process::id()))
        .connect(connector)
        .await?;
    let registry = pinger.registry().await?;
    let handler = registry
        .entries
        .iter()
        .find(|e| e.name.as_str() == <Ping as tca_messages::Message>::NAME);
    match handler {
        Some(e) if e.handler.as_str() == target && e.connected => {}
        Some(e) => {
            return Err(ModuleError::Usage(format!(
                "the ping messages are handled by module {}{}, not by {target}; start \
                 `tca module echo` or give --target {}",
                e.handler,
                if e.connected { "" } else { " (down)" },
                e.handler
            )));
        }
        None => {
            return Err(ModuleError::Usage(format!(
                "no module handles the ping messages ({}); start one with `tca module echo \
                 --connect ENDPOINT` (looking for --target {target})",
                connector.describe()
            )));
        }
    }
    time(&pinger, n, payload).await
}

/// Warms up, then times `n` queries of `payload` bytes from `pinger`; closes it.
async fn time(pinger: &Module, n: usize, payload: usize) -> Result<PingReport, ModuleError> {
    let body = vec![0xa5; payload];
    let warmup = (n / 10).clamp(10, 1000);
    for seq in 0..warmup as u64 {
        pinger
            .query(&Ping {
                seq,
                payload: body.clone(),
            })
            .await?;
    }
    let mut samples = Vec::with_capacity(n);
    for seq in 0..n as u64 {
        let ping = Ping {
            seq,
            payload: body.clone(),
        };
        let start = Instant::now();
        let pong = pinger.query(&ping).await?;
        samples.push(start.elapsed());
        if pong != ping {
            return Err(ModuleError::Protocol(
                "the echo module answered with different data".into(),
            ));
        }
    }
    pinger.close().await;
    Ok(report(&mut samples))
}

/// Summarises samples.
pub fn report(samples: &mut [Duration]) -> PingReport {
    samples.sort();
    let us = |d: Duration| d.as_secs_f64() * 1e6;
    let at = |q: f64| {
        if samples.is_empty() {
            return 0.0;
        }
        let i = ((samples.len() - 1) as f64 * q).round() as usize;
        us(samples[i.min(samples.len() - 1)])
    };
    PingReport {
        n: samples.len(),
        min_us: at(0.0),
        p50_us: at(0.5),
        p99_us: at(0.99),
        max_us: at(1.0),
    }
}
