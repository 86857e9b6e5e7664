//! Replaying a recorded run: some modules played back from its traffic log, the others run
//! live, and everything the live modules send compared with the record (§3.3: the log as a
//! tool for finding interface and timing errors; here, a regression test of modules).
//!
//! Central runs in-process with the live modules (those a [`LiveSide`] says run live, set up
//! by it) and one [stand-in](stand_in) for each module named in [`ReplayPlan::stand_ins`]. A
//! stand-in registers the recorded module's messages with their recorded formats and answers
//! each message with what the recorded module did for the same (asker, message name), in
//! recorded order: its reply, or the success or failure of a goal or command, the exceptions it
//! raised there and whatever else it sent while handling, each after the recorded simulated
//! time. A driver named like the recorded *originator* (the module that sent the first root
//! goal named [`ReplayPlan::root_goal`]) then sends the originator's recorded root goals of
//! that name one after another, each when the previous has ended.
//!
//! Afterwards every message the live modules sent during the replayed goals (queries, goals,
//! commands, informs, exceptions, replies, successes and failures) is compared with the record,
//! per (sender, message name) in order, field by field through the registered data formats
//! (see [`tca_logs::compare`](mod@tca_logs::compare) for what is and is not compared, and
//! [`ReplayPlan::rules`] for the fields the vocabulary treats specially). The report names the
//! first divergence (message, field, recorded and live values) and how many more there are.
//!
//! Modules are connected in the recorded order, so link numbers and message ids come out the
//! same. A replay that has drifted from the record can wait for answers that never come, so
//! each replayed goal is bounded in wall time ([`ReplayPlan::goal_timeout`]).
//!
//! # Layout
//!
//! - this file: [`ReplayPlan`], the [`LiveSide`] a vocabulary provides, [`replay`] and the
//!   [`ReplayReport`].
//! - [`stand_in`]: a module played back from its script in the log.

pub mod stand_in;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context as _, bail};
use futures::future::BoxFuture;
use serde::Serialize;
use tca_central::StartOptions;
use tca_logs::compare::{Rules, Side};
use tca_logs::{LogFile, RootTask};
use tca_messages::Class;
use tca_messages::control::TaskOutcome;
use tca_module::{Connector, Module};

/// Least wall-clock limit of one replayed goal, unless given.
pub const MIN_GOAL_TIMEOUT: Duration = Duration::from_secs(30);

/// Unless given, a replayed goal may take this many times its recorded wall-clock time (a
/// replay that has drifted from the record can wait on answers that never come).
pub const GOAL_TIMEOUT_FACTOR: u32 = 20;

/// How many divergences a report lists.
pub const LISTED_DIVERGENCES: usize = 20;

/// What to replay.
#[derive(Clone, Debug)]
pub struct ReplayPlan {
    /// The recorded traffic log.
    pub log: PathBuf,
    /// Modules played from the log.
    pub stand_ins: Vec<String>,
    /// The name of the root goals the driver sends again (their sender in the record is the
    /// originator the driver stands in for).
    pub root_goal: String,
    /// Data fields the comparison treats specially (the vocabulary's rules).
    pub rules: Rules,
    /// What to tell a user whose log holds no complete run to replay (how to record one).
    pub how_to_record: String,
    /// Keep the replay's traffic log in this directory.
    pub out: Option<PathBuf>,
    /// Wall-clock limit of each replayed goal; `None`: [`GOAL_TIMEOUT_FACTOR`] times its
    /// recorded duration, at least [`MIN_GOAL_TIMEOUT`].
    pub goal_timeout: Option<Duration>,
}

/// The live half of a replay: which recorded modules run live, and how they are set up.
pub trait LiveSide: Send + Sync {
    /// Whether recorded `module` (neither played from the log nor the originator) runs live;
    /// others are left out of the replay, with a warning.
    fn runs_live(&self, module: &str) -> bool;

    /// Gets ready to connect the `live` modules; whatever they write goes in `dir` (next to
    /// the replay's log, never over the record's). An error says why the replay cannot run.
    fn prepare(&mut self, live: &[String], dir: &Path) -> anyhow::Result<()>;

    /// Connects live module `name`.
    fn connect<'a>(
        &'a self,
        name: &'a str,
        connector: &'a Connector,
    ) -> BoxFuture<'a, anyhow::Result<Module>>;
}

/// One replayed root goal.
#[derive(Clone, Debug, Serialize)]
pub struct GoalReplay {
    /// Message name.
    pub name: String,
    /// How it ended in the record.
    pub recorded: String,
    /// How it ended in the replay.
    pub live: String,
    /// When it ended in the record, simulated seconds (if the run was on simulated time).
    pub recorded_sim_s: Option<f64>,
    /// When it ended in the replay, simulated seconds.
    pub live_sim_s: Option<f64>,
}

/// What the replay found.
#[derive(Clone, Debug, Serialize)]
pub struct ReplayReport {
    /// The recorded log.
    pub log: PathBuf,
    /// Modules played from the log.
    pub played: Vec<String>,
    /// Modules run live.
    pub live: Vec<String>,
    /// Messages compared.
    pub compared: usize,
    /// Every message matched and every goal ended as recorded.
    pub all_match: bool,
    /// Messages that differ.
    pub divergences: usize,
    /// The first divergence, as printed.
    pub first_divergence: Option<String>,
    /// The first [`LISTED_DIVERGENCES`] divergences.
    pub listed: Vec<tca_logs::Divergence>,
    /// The replayed root goals.
    pub goals: Vec<GoalReplay>,
    /// Per stand-in: deliveries the record had no answer left for.
    pub unscripted: BTreeMap<String, usize>,
    /// Per stand-in: recorded deliveries (from live modules or stand-ins, during the replayed
    /// goals) never asked for.
    pub unplayed: BTreeMap<String, usize>,
    /// Wall-clock time of the replay, seconds.
    pub wall_time_s: f64,
    /// The replay's own traffic log, if kept (`--out`).
    pub replay_log: Option<PathBuf>,
}

impl ReplayReport {
    /// The report as text lines.
    pub fn text(&self) -> String {
        let mut s = format!(
            "replayed {}: {} played from the log; {} live\n",
            self.log.display(),
            list(&self.played),
            list(&self.live)
        );
        for g in &self.goals {
            let at = |t: Option<f64>| t.map(|t| format!(" at {t:.1} s")).unwrap_or_default();
            s += &format!(
                "{} goal: recorded {}{}, replay {}{} (simulated time)\n",
                g.name,
                g.recorded,
                at(g.recorded_sim_s),
                g.live,
                at(g.live_sim_s)
            );
        }
        for (m, n) in self.unscripted.iter().filter(|(_, n)| **n > 0) {
            s += &format!("{m}: {n} deliveries had no recorded answer left\n");
        }
        for (m, n) in self.unplayed.iter().filter(|(_, n)| **n > 0) {
            s += &format!("{m}: {n} recorded deliveries were never asked for\n");
        }
        match &self.first_divergence {
            None if self.all_match => {
                s += &format!(
                    "{} messages compared, all match ({:.1} s)\n",
                    self.compared, self.wall_time_s
                )
            }
            None => {
                s += &format!(
                    "{} messages compared, all match, but the goals did not end as recorded\n",
                    self.compared
                )
            }
            Some(first) => {
                s += &format!("first divergence: {first}\n");
                let further = self.divergences.saturating_sub(1);
                s += &format!(
                    "{further} further divergences; {} messages compared ({:.1} s)\n",
                    self.compared, self.wall_time_s
                );
                for d in self.listed.iter().skip(1) {
                    s += &format!("  {d}\n");
                }
                if self.divergences > self.listed.len() {
                    s += &format!("  ... and {} more\n", self.divergences - self.listed.len());
                }
            }
        }
        if let Some(p) = &self.replay_log {
            s += &format!("replay log: {}\n", p.display());
        }
        s
    }
}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

fn describe(outcome: Option<&TaskOutcome>) -> String {
    match outcome {
        Some(TaskOutcome::Achieved) => "achieved".into(),
        Some(TaskOutcome::Failed(r)) => format!("failed ({r})"),
        Some(TaskOutcome::Killed) => "killed".into(),
        None => "did not end".into(),
    }
}

/// What of the record is replayed: the originator and its root goals.
#[derive(Debug)]
struct Recorded {
    log: LogFile,
    originator: String,
    roots: Vec<RootTask>,
    modules: Vec<String>,
}

fn read_record(path: &Path, root_goal: &str, how_to_record: &str) -> anyhow::Result<Recorded> {
    let log = LogFile::open(path).with_context(|| format!("cannot read log {}", path.display()))?;
    let originator = log.records.iter().find_map(|r| {
        let tca_logs::RecordKind::Frame(f) = &r.kind else {
            return None;
        };
        let env = LogFile::envelope(f).ok()?;
        (f.direction == tca_logs::Direction::In
            && env.class == Class::Goal
            && env.name.as_str() == root_goal
            && env.context.is_none())
        .then(|| env.sender.to_string())
    });
    let cut = log
        .truncated
        .as_ref()
        .map(|t| format!(" ({t})"))
        .unwrap_or_default();
    let Some(originator) = originator else {
        bail!(
            "{} holds no `{root_goal}` goal sent by a user{cut}, so there is nothing to \
             replay; {how_to_record}",
            path.display()
        );
    };
    let roots = replayed_roots(&log, &originator, root_goal);
    if let Some(open) = roots.iter().find(|r| r.outcome.is_none()) {
        bail!(
            "the recorded {} goal never ends in {}{cut}: the record is incomplete, so there is \
             nothing complete to compare with; {how_to_record}",
            open.envelope.name,
            path.display()
        );
    }
    let modules = tca_logs::connection_order(&log)
        .into_iter()
        .map(|m| m.to_string())
        .collect();
    Ok(Recorded {
        log,
        originator,
        roots,
        modules,
    })
}

/// Whether the recorded central kept the simulated clock: its welcomes say so.
fn kept_simulated_clock(log: &LogFile) -> bool {
    log.records.iter().any(|r| {
        let tca_logs::RecordKind::Frame(f) = &r.kind else {
            return false;
        };
        f.direction == tca_logs::Direction::Out
            && f.class == Class::Control
            && LogFile::envelope(f).is_ok_and(|env| {
                matches!(
                    tca_messages::control::ControlNotice::decode(env.name.as_str(), &env.data),
                    Some(tca_messages::control::ControlNotice::Welcome(w)) if w.simulated_clock
                )
            })
    })
}

/// The originator's root goals named `root_goal` (its other root tasks, such as drawing a map
/// afterwards, are not replayed).
fn replayed_roots(log: &LogFile, originator: &str, root_goal: &str) -> Vec<RootTask> {
    let mut roots = tca_logs::root_tasks(log, originator);
    roots.retain(|r| r.envelope.name.as_str() == root_goal);
    roots
}

/// When a root task ended, simulated seconds: the stamp of central's notice, if it is
/// simulated time.
fn ended_at_s(log: &LogFile, root: &RootTask) -> Option<f64> {
    let (_, position) = root.outcome.as_ref()?;
    let tca_logs::RecordKind::Frame(f) = &log.records.get(*position)?.kind else {
        return None;
    };
    let t = LogFile::envelope(f).ok()?.timestamp_ns;
    tca_messages::is_simulated_stamp(t).then(|| t as f64 / 1e9)
}

/// The window of a log the replay covers: from the first root goal to the end of the last.
fn window(roots: &[RootTask], len: usize) -> std::ops::Range<usize> {
    let start = roots.first().map_or(len, |r| r.position);
    let end = match roots.last().and_then(|r| r.outcome.as_ref()) {
        Some((_, end)) => end + 1,
        None => len,
    };
    start..end.max(start)
}

/// A directory for the replay's log: `out`, or a fresh one under the system's temp dir
/// (removed afterwards).
fn log_dir(out: Option<&Path>) -> anyhow::Result<(PathBuf, bool)> {
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        return Ok((dir.to_owned(), true));
    }
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let dir = std::env::temp_dir().join(format!("tca-replay-{}-{stamp}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    Ok((dir, false))
}

/// Replays a recorded run (see the crate documentation) with `live` running the modules that
/// are neither played from the log nor the originator. An `Err` means the log cannot be
/// replayed; divergences are in the report.
pub async fn replay(plan: &ReplayPlan, live: &mut dyn LiveSide) -> anyhow::Result<ReplayReport> {
    let started = Instant::now();
    let recorded = read_record(&plan.log, &plan.root_goal, &plan.how_to_record)?;
    let mut played: Vec<String> = Vec::new();
    for name in &plan.stand_ins {
        if name == &recorded.originator {
            bail!(
                "{name} sent the goals the replay sends again; name the modules to play from \
                 the log (recorded: {})",
                recorded.modules.join(", ")
            );
        }
        if !recorded.modules.contains(name) {
            bail!(
                "--as {name}: no module {name} in {}; the recorded modules are {}",
                plan.log.display(),
                recorded.modules.join(", ")
            );
        }
        if !played.contains(name) {
            played.push(name.clone());
        }
    }
    let live_names: Vec<String> = recorded
        .modules
        .iter()
        .filter(|m| !played.contains(m) && **m != recorded.originator && live.runs_live(m))
        .cloned()
        .collect();
    for other in recorded
        .modules
        .iter()
        .filter(|m| !played.contains(m) && !live_names.contains(m) && **m != recorded.originator)
    {
        tracing::warn!(module = %other, "not a module this replay can run: left out");
    }
    let mut scripts = BTreeMap::new();
    for name in &played {
        let script = tca_logs::module_script(&recorded.log, name)
            .with_context(|| format!("{name} is not in the log"))?;
        scripts.insert(name.clone(), script);
    }
    let originator_script = tca_logs::module_script(&recorded.log, &recorded.originator)
        .with_context(|| format!("the originator {} is not in the log", recorded.originator))?;

    let (dir, keep) = log_dir(plan.out.as_deref())?;
    let log_path = dir.join("traffic.mcap");
    live.prepare(&live_names, &dir)?;
    // Central keeps the simulated clock if the recorded one did (its welcomes said so).
    let central = tca_central::start(StartOptions {
        log: Some(log_path.clone()),
        config: tca_central::CentralConfig {
            simulated_time: kept_simulated_clock(&recorded.log),
            ..tca_central::CentralConfig::default()
        },
        ..StartOptions::default()
    })
    .await
    .context("cannot start central")?;
    let connector = Connector::from(central.in_process());
    // Connect in the recorded order, so link numbers (and message ids) come out the same.
    let mut stand_ins = Vec::new();
    let mut modules = Vec::new();
    for name in &recorded.modules {
        if let Some(script) = scripts.remove(name) {
            let s = stand_in::connect(&connector, script)
                .await
                .with_context(|| format!("cannot start the stand-in for {name}"))?;
            stand_ins.push((name.clone(), s));
        } else if live_names.contains(name) {
            let module = live
                .connect(name, &connector)
                .await
                .with_context(|| format!("cannot start the live {name} module"))?;
            modules.push(module);
        }
    }
    // The driver plays the originator's handlers (the informs it listens to, say) and sends
    // its root goals.
    let driver = stand_in::connect(&connector, originator_script)
        .await
        .context("the replay's driver cannot join central")?;
    let driver_module = driver.module.clone();
    let mut goals = Vec::new();
    for root in &recorded.roots {
        let env = &root.envelope;
        let now = driver_module.time_ns();
        if env.timestamp_ns > now {
            driver_module.spend(Duration::from_nanos(env.timestamp_ns - now));
        }
        let recorded_outcome = root.outcome.as_ref().map(|(o, _)| o);
        let task =
            driver_module.send_watched_raw(env.class, env.name.as_str(), env.data.clone(), [])?;
        let limit = plan.goal_timeout.unwrap_or_else(|| {
            let recorded_ns = root.outcome.as_ref().map_or(0, |(_, end)| {
                let at = |i: usize| recorded.log.records.get(i).map_or(0, |r| r.at_ns);
                at(*end).saturating_sub(at(root.position))
            });
            (Duration::from_nanos(recorded_ns) * GOAL_TIMEOUT_FACTOR).max(MIN_GOAL_TIMEOUT)
        });
        let live = match tokio::time::timeout(limit, task.outcome()).await {
            Ok(Ok(o)) => describe(Some(&o)),
            Ok(Err(e)) => format!("lost ({e})"),
            Err(_) => format!("did not end within {limit:?}"),
        };
        let ended = !live.starts_with("did not end") && !live.starts_with("lost");
        goals.push(GoalReplay {
            name: env.name.to_string(),
            recorded: describe(recorded_outcome),
            live,
            recorded_sim_s: ended_at_s(&recorded.log, root),
            live_sim_s: None,
        });
        if !ended {
            break;
        }
    }
    let unscripted: BTreeMap<String, usize> = stand_ins
        .iter()
        .map(|(n, s)| (n.clone(), s.unscripted()))
        .collect();
    let rec_window = window(&recorded.roots, recorded.log.records.len());
    let unplayed: BTreeMap<String, usize> = stand_ins
        .iter()
        .map(|(n, s)| {
            let counted = |position: usize, asker: &str| {
                rec_window.contains(&position) && asker != recorded.originator
            };
            (n.clone(), s.unplayed(counted))
        })
        .collect();
    driver_module.close().await;
    for (_, s) in &stand_ins {
        s.module.close().await;
    }
    for m in &modules {
        m.close().await;
    }
    central
        .shutdown()
        .await
        .context("central did not stop cleanly")?;
    let live_log = LogFile::open(&log_path)
        .with_context(|| format!("cannot read the replay's log {}", log_path.display()))?;
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    let live_roots = replayed_roots(&live_log, &recorded.originator, &plan.root_goal);
    let live_window = window(&live_roots, live_log.records.len());
    for (goal, root) in goals.iter_mut().zip(&live_roots) {
        goal.live_sim_s = ended_at_s(&live_log, root);
    }
    let comparison = tca_logs::compare(
        Side {
            log: &recorded.log,
            window: &rec_window,
        },
        Side {
            log: &live_log,
            window: &live_window,
        },
        &live_names,
        &plan.rules,
    );
    let goals_match =
        goals.len() == recorded.roots.len() && goals.iter().all(|g| g.recorded == g.live);
    Ok(ReplayReport {
        log: plan.log.clone(),
        played,
        live: live_names,
        compared: comparison.compared,
        all_match: comparison.all_match() && goals_match,
        divergences: comparison.divergences.len(),
        first_divergence: comparison.divergences.first().map(|d| d.to_string()),
        listed: comparison
            .divergences
            .into_iter()
            .take(LISTED_DIVERGENCES)
            .collect(),
        goals,
        unscripted,
        unplayed,
        wall_time_s: started.elapsed().as_secs_f64(),
        replay_log: keep.then_some(log_path),
    })
}
