//! Walks with the walking modules as separate processes over zenoh while modules are killed
//! (`SIGKILL`) at random moments and started again (`tca chaos`; §3.1: modules restart without
//! bringing down the rest).
//!
//! Central runs in this process, listening on loopback and logging all traffic. For each walk
//! the six walking modules start as `tca module NAME --state DIR` processes (a fresh state
//! directory per walk: the Controller's leg and the LTM Manager's map survive their restarts
//! in it); the walk is driven as by `tca walk --connect`. During the walk, after a randomly
//! chosen step and a random delay, a randomly chosen module is killed; once central has seen
//! its link close, it is started again. Every walk must reach its goal without a collision;
//! at the end the log is audited ([`tca_logs::audit`]): no message lost, none handled twice.
//!
//! With [`ChaosOptions::kill_central`] the victim is central itself: it runs as its own process
//! (`tca central --journal`), is killed with `SIGKILL` at random moments of the walks and started
//! again at once on the same journal; the walker waits through each restart and never sends
//! its walk again. The logs of every central, read in order, are audited as one history, and
//! each walk must have been sent once.
//!
//! # Layout
//!
//! - this file: [`ChaosOptions`], [`run`] (the walks, the kills, the audit), the
//!   [`ChaosReport`] and its text ([`summary`]).
//! - [`processes`]: the module processes, started, killed and started again.

pub mod processes;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use tca_central::StartOptions;
use tca_logs::Audit;
use tca_module::{Connector, Module};
use tokio::sync::mpsc;

use processes::{ModuleProcess, ProcessSetup};
use tca_walk::{ComputeModel, Progress, TerrainChoice, WALKING_MODULES, WalkOptions};

/// What to run.
#[derive(Clone, Debug)]
pub struct ChaosOptions {
    /// Walks to complete.
    pub walks: usize,
    /// Module kills to make across the walks (spread evenly; at least this many are made,
    /// more walks run if some kills found their walk already over).
    pub kills: usize,
    /// The terrain (course 3 by default).
    pub terrain: TerrainChoice,
    /// `--course N` or `--terrain FILE` as the module processes are given it.
    pub terrain_args: Vec<String>,
    /// Seed of the kills' choices and of the scanner noise.
    pub seed: u64,
    /// The Controller's speed factor (None: as fast as it computes).
    pub speed: Option<f64>,
    /// What the planners charge to simulated time.
    pub compute: ComputeModel,
    /// Where the log and the modules' state go.
    pub out: PathBuf,
    /// Central's zenoh endpoint (a free loopback port if `None`).
    pub listen: Option<String>,
    /// The `tca` executable to start modules with.
    pub exe: PathBuf,
    /// The modules that may be killed (all six walking modules if empty).
    pub victims: Vec<String>,
    /// Plan the next step while the current one executes.
    pub concurrent: bool,
    /// Kill central (a process on a journal) instead of the modules.
    pub kill_central: bool,
}

/// One kill.
#[derive(Clone, Debug, Serialize)]
pub struct KillRecord {
    /// Which walk (from 0).
    pub walk: usize,
    /// The module killed.
    pub module: String,
    /// Steps planned in that walk before the kill.
    pub after_step: usize,
    /// Milliseconds after that step's report.
    pub delay_ms: u64,
    /// Milliseconds from the kill until the new process was started.
    pub restarted_after_ms: u64,
}

/// One walk.
#[derive(Clone, Debug, Serialize)]
pub struct WalkRecord {
    /// Which walk (from 0).
    pub walk: usize,
    /// The carriage reached the goal.
    pub reached: bool,
    /// Times the leg struck terrain.
    pub collisions: u32,
    /// Steps the walk reported (a restarted Gait Planner numbers its steps afresh).
    pub steps: usize,
    /// Kills during this walk.
    pub kills: usize,
    /// Simulated seconds.
    pub sim_time_s: f64,
    /// Wall-clock seconds.
    pub wall_time_s: f64,
    /// Why not reached, if not.
    pub reason: Option<String>,
}

/// What happened.
#[derive(Clone, Debug, Serialize)]
pub struct ChaosReport {
    /// The walks.
    pub walks: Vec<WalkRecord>,
    /// The kills.
    pub kills: Vec<KillRecord>,
    /// The log's audit.
    pub audit: Audit,
    /// The log's time check.
    pub time: tca_logs::TimeCheck,
    /// The log (the last central's, when central was killed).
    pub log: PathBuf,
    /// Every central's log, in order (one, unless central was killed and restarted).
    pub logs: Vec<PathBuf>,
    /// `walk` goals the walker sent, in all the logs: one per walk (a walk is never sent
    /// again).
    pub walk_goals: usize,
    /// Every walk reached its goal with no collision and was sent once, the kills were made,
    /// the audit is clean and time was kept.
    pub passed: bool,
    /// Wall-clock seconds of the whole run.
    pub wall_time_s: f64,
}

/// Steps after which a kill may be made (a walk on course 3 plans 6 or more).
const KILL_WINDOW_STEPS: usize = 5;

/// Runs the chaos walks. `say` gets one line per event for a display.
pub async fn run(options: &ChaosOptions, say: impl Fn(String)) -> anyhow::Result<ChaosReport> {
    let started = Instant::now();
    if options.walks == 0 {
        anyhow::bail!("--walks must be at least 1");
    }
    if let Some(v) = options
        .victims
        .iter()
        .find(|v| !WALKING_MODULES.contains(&v.as_str()))
    {
        anyhow::bail!(
            "{v:?} is not a walking module; the modules that can be killed are {}",
            WALKING_MODULES.join(", ")
        );
    }
    if options.kill_central && !options.victims.is_empty() {
        anyhow::bail!(
            "--victims names modules to kill; with --kill-central central is the one killed"
        );
    }
    std::fs::create_dir_all(&options.out)
        .with_context(|| format!("cannot create {}", options.out.display()))?;
    let log = options.out.join("traffic.mcap");
    tca_logs::set_aside(&log).context("cannot keep the previous log")?;
    let earlier_logs = numbered_logs(&log);
    let endpoint = match &options.listen {
        Some(e) => e.clone(),
        None => tca_link::net::free_loopback_endpoint().context("no free loopback port")?,
    };
    let mut central = if options.kill_central {
        let journal = options.out.join("central.journal");
        let stderr = options.out.join("central.stderr");
        CentralRun::Process(ModuleProcess::central(
            &options.exe,
            &endpoint,
            &log,
            &journal,
            &stderr,
        )?)
    } else {
        CentralRun::InProcess(
            tca_central::start(StartOptions {
                log: Some(log.clone()),
                listen: vec![endpoint.clone()],
                config: tca_central::CentralConfig {
                    simulated_time: true,
                    ..tca_central::CentralConfig::default()
                },
                ..StartOptions::default()
            })
            .await
            .context("cannot start central")?,
        )
    };
    let watcher = watch_central(&central, &endpoint).await?;
    let setup = ProcessSetup {
        exe: options.exe.clone(),
        endpoint: endpoint.clone(),
        terrain_args: options.terrain_args.clone(),
        seed: options.seed,
        speed: options.speed,
        compute: match options.compute {
            ComputeModel::Paper => "paper",
            ComputeModel::Measured => "measured",
        },
    };
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let per_walk = options.kills.div_ceil(options.walks);
    let mut walks = Vec::new();
    let mut kills = Vec::new();
    let mut w = 0;
    // Extra walks (at most as many again) make up for kills that found their walk over.
    while w < options.walks || (kills.len() < options.kills && w < 2 * options.walks) {
        let wanted = per_walk.min(options.kills.saturating_sub(kills.len()));
        let (record, made) = one_walk(
            w,
            wanted,
            options,
            &setup,
            &watcher,
            &endpoint,
            &mut rng,
            &mut central,
            &say,
        )
        .await?;
        say(format!(
            "walk {w}: {} with {} collision(s), {} step(s), {} kill(s), {:.1} s simulated, {:.1} s wall{}",
            if record.reached {
                "reached"
            } else {
                "NOT reached"
            },
            record.collisions,
            record.steps,
            record.kills,
            record.sim_time_s,
            record.wall_time_s,
            record
                .reason
                .as_ref()
                .map(|r| format!(": {r}"))
                .unwrap_or_default()
        ));
        walks.push(record);
        kills.extend(made);
        w += 1;
    }
    watcher.close().await;
    match central {
        CentralRun::InProcess(c) => {
            c.shutdown().await.context("central did not stop")?;
        }
        CentralRun::Process(mut p) => p.stop().await,
    }
    // The crashed centrals' logs (set aside by each restart), then the last one's.
    let mut logs: Vec<PathBuf> = numbered_logs(&log)
        .into_iter()
        .filter(|l| !earlier_logs.contains(l))
        .collect();
    logs.push(log.clone());
    let mut read = Vec::new();
    for l in &logs {
        read.push(
            tca_logs::LogFile::open(l)
                .with_context(|| format!("cannot read the log {}", l.display()))?,
        );
    }
    let recorded = tca_logs::LogFile::chain(read);
    let audit = tca_logs::audit(&recorded);
    let time = tca_logs::time_check(&recorded);
    let walk_goals = walk_goals_sent(&recorded);
    let passed = walks.iter().all(|w| w.reached && w.collisions == 0)
        && kills.len() >= options.kills
        && walk_goals == walks.len()
        && audit.is_clean()
        && time.holds();
    Ok(ChaosReport {
        walks,
        kills,
        audit,
        time,
        log,
        logs,
        walk_goals,
        passed,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

/// Central, in this process or as its own (to be killed).
enum CentralRun {
    InProcess(tca_central::RunningCentral),
    Process(ModuleProcess),
}

/// A module of this process that asks central for its registry (over zenoh when central is a
/// process: it rejoins central's restarts by itself).
async fn watch_central(central: &CentralRun, endpoint: &str) -> anyhow::Result<Module> {
    let name = format!("chaos-{}", std::process::id());
    let connector = match central {
        CentralRun::InProcess(c) => Connector::from(c.in_process()),
        CentralRun::Process(_) => Connector::zenoh(endpoint.to_owned()),
    };
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        match Module::builder(name.clone()).connect(&connector).await {
            Ok(m) => return Ok(m),
            Err(e) if Instant::now() > deadline => {
                return Err(e).context("cannot watch central");
            }
            Err(_) => tokio::time::sleep(Duration::from_millis(100)).await,
        }
    }
}

/// The logs `STEM.N.EXT` next to `log`, by N.
fn numbered_logs(log: &std::path::Path) -> Vec<PathBuf> {
    let stem = log
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = log
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut found: Vec<(u32, PathBuf)> = (1..100_000u32)
        .map(|n| (n, log.with_file_name(format!("{stem}.{n}.{ext}"))))
        .take_while(|(_, p)| p.exists())
        .collect();
    found.sort();
    found.into_iter().map(|(_, p)| p).collect()
}

/// How many `walk` goals modules sent central.
fn walk_goals_sent(log: &tca_logs::LogFile) -> usize {
    log.records
        .iter()
        .filter(|r| {
            matches!(&r.kind, tca_logs::RecordKind::Frame(f)
                if f.direction == tca_logs::Direction::In
                    && f.class == tca_messages::Class::Goal
                    && f.name.as_str() == "walk")
        })
        .count()
}

/// Walks once with fresh module processes, making up to `wanted` kills (of modules, or of
/// `central` when it is a process).
#[allow(clippy::too_many_arguments)]
async fn one_walk(
    w: usize,
    wanted: usize,
    options: &ChaosOptions,
    setup: &ProcessSetup,
    watcher: &Module,
    endpoint: &str,
    rng: &mut ChaCha8Rng,
    central: &mut CentralRun,
    say: &impl Fn(String),
) -> anyhow::Result<(WalkRecord, Vec<KillRecord>)> {
    let started = Instant::now();
    let state = options.out.join("state").join(format!("walk-{w}"));
    if state.exists() {
        std::fs::remove_dir_all(&state)
            .with_context(|| format!("cannot clear {}", state.display()))?;
    }
    let mut modules = Vec::new();
    for name in WALKING_MODULES {
        modules.push(ModuleProcess::start(setup, name, &state)?);
    }
    wait_until(watcher, Duration::from_secs(30), |registry| {
        WALKING_MODULES.iter().all(|m| {
            registry.modules.iter().any(|c| c.as_str() == *m)
                && registry
                    .entries
                    .iter()
                    .any(|e| e.handler.as_str() == *m && e.connected)
        })
    })
    .await
    .context("the walking modules did not all register within 30 s")?;

    // When to kill: after which step, how long after it, which module.
    let victims: Vec<usize> = (0..WALKING_MODULES.len())
        .filter(|i| {
            options.victims.is_empty() || options.victims.iter().any(|v| v == WALKING_MODULES[*i])
        })
        .collect();
    // Central is killed at any moment of a step: while it is planned, or the leg moves.
    let most_delay = if options.kill_central { 400 } else { 40u64 };
    let mut plan: Vec<(usize, u64, usize)> = (0..wanted)
        .map(|_| {
            (
                rng.random_range(0..=KILL_WINDOW_STEPS),
                rng.random_range(0..=most_delay),
                victims[rng.random_range(0..victims.len())],
            )
        })
        .collect();
    plan.sort();
    let walk_options = WalkOptions {
        terrain: options.terrain.clone(),
        goal_y_m: None,
        backward: false,
        mode: if options.concurrent {
            tca_single_leg_messages::WalkMode::Concurrent
        } else {
            tca_single_leg_messages::WalkMode::Sequential
        },
        seed: options.seed,
        out: None,
        step_pictures: false,
        connect: Some(endpoint.to_owned()),
        compute: options.compute,
        fault: None,
        rigid: false,
        body_move_law: Default::default(),
        attach: None,
    };
    let (tx, mut rx) = mpsc::unbounded_channel();
    let mut walk = tokio::spawn(async move { tca_walk::walk(&walk_options, tx).await });
    let mut steps = 0usize;
    let mut made = Vec::new();
    let result = loop {
        tokio::select! {
            r = &mut walk => break r.context("the walk task failed")?,
            p = rx.recv() => {
                match p {
                    Some(Progress::Step(_)) => steps += 1,
                    Some(Progress::Leg { .. }) => {}
                    None => break walk.await.context("the walk task failed")?,
                }
                while let Some(&(after, delay, which)) = plan.first() {
                    if after > steps {
                        break;
                    }
                    plan.remove(0);
                    tokio::time::sleep(Duration::from_millis(delay)).await;
                    if walk.is_finished() {
                        break;
                    }
                    let (victim, kill) = match central {
                        CentralRun::Process(c) => (c.name.clone(), kill_central(c).await?),
                        CentralRun::InProcess(_) => (
                            modules[which].name.clone(),
                            kill_and_restart(&mut modules[which], watcher).await?,
                        ),
                    };
                    say(format!(
                        "walk {w}: killed {victim} after step {steps} (+{delay} ms), started again after {kill} ms",
                    ));
                    made.push(KillRecord {
                        walk: w,
                        module: victim,
                        after_step: steps,
                        delay_ms: delay,
                        restarted_after_ms: kill,
                    });
                }
            }
        }
    };
    for m in &mut modules {
        m.stop().await;
    }
    let record = match result {
        Ok(report) => WalkRecord {
            walk: w,
            reached: report.reached,
            collisions: report.collisions,
            steps: report.steps,
            kills: made.len(),
            sim_time_s: report.sim_time_s,
            wall_time_s: started.elapsed().as_secs_f64(),
            reason: report.reason,
        },
        Err(e) => WalkRecord {
            walk: w,
            reached: false,
            collisions: 0,
            steps,
            kills: made.len(),
            sim_time_s: 0.0,
            wall_time_s: started.elapsed().as_secs_f64(),
            reason: Some(format!("{e:#}")),
        },
    };
    Ok((record, made))
}

/// Kills a module, waits until central has seen its link close, and starts it again; returns
/// the milliseconds between kill and restart.
async fn kill_and_restart(module: &mut ModuleProcess, watcher: &Module) -> anyhow::Result<u64> {
    let killed = Instant::now();
    module.kill().await;
    let name = module.name.clone();
    wait_until(watcher, Duration::from_secs(10), |registry| {
        !registry.modules.iter().any(|c| c.as_str() == name)
    })
    .await
    .with_context(|| format!("central did not notice that {name} died"))?;
    module.restart()?;
    Ok(killed.elapsed().as_millis() as u64)
}

/// Kills central with SIGKILL and starts it again at once on its journal; returns the
/// milliseconds between kill and restart.
async fn kill_central(central: &mut ModuleProcess) -> anyhow::Result<u64> {
    let killed = Instant::now();
    central.kill().await;
    central.restart()?;
    Ok(killed.elapsed().as_millis() as u64)
}

/// Polls central's registry until `ok` holds for it.
async fn wait_until(
    watcher: &Module,
    limit: Duration,
    ok: impl Fn(&tca_messages::control::Registry) -> bool,
) -> anyhow::Result<()> {
    let deadline = Instant::now() + limit;
    loop {
        // A central being restarted does not answer: ask again once it is back.
        let registry = match watcher.registry().await {
            Ok(r) => Some(r),
            Err(tca_module::ModuleError::CentralLost) => None,
            Err(e) => return Err(e.into()),
        };
        if registry.as_ref().is_some_and(&ok) {
            return Ok(());
        }
        if Instant::now() > deadline {
            let connected: Vec<String> = registry
                .map(|r| r.modules.iter().map(|m| m.to_string()).collect())
                .unwrap_or_else(|| vec!["(central is away)".into()]);
            anyhow::bail!("timed out; connected now: {}", connected.join(", "));
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

/// A readable summary of a chaos run.
pub fn summary(report: &ChaosReport) -> String {
    let reached = report.walks.iter().filter(|w| w.reached).count();
    let collisions: u32 = report.walks.iter().map(|w| w.collisions).sum();
    let mut by_module = std::collections::BTreeMap::new();
    for k in &report.kills {
        *by_module.entry(k.module.as_str()).or_insert(0) += 1;
    }
    let mut s = format!(
        "{} walks, {reached} reached their goal, {collisions} collisions; {} kills ({}); {:.1} s\n",
        report.walks.len(),
        report.kills.len(),
        by_module
            .iter()
            .map(|(m, n)| format!("{m} {n}"))
            .collect::<Vec<_>>()
            .join(", "),
        report.wall_time_s
    );
    s.push_str(&format!(
        "{} walk goal(s) sent for {} walk(s)\n",
        report.walk_goals,
        report.walks.len()
    ));
    s.push_str(&report.audit.text());
    s.push_str(&report.time.text());
    s.push_str(&format!(
        "log: {}\n{}\n",
        report
            .logs
            .iter()
            .map(|l| l.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        if report.passed { "PASSED" } else { "FAILED" }
    ));
    s
}
