//! `tca up FILE`: central and a set of modules as processes, stopped together on Ctrl-C.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use clap::Args;
use tca_launch::Launch;

#[derive(Debug, Args)]
pub(crate) struct UpArgs {
    /// The launch file.
    file: PathBuf,
}

pub(crate) async fn run(args: UpArgs) -> anyhow::Result<ExitCode> {
    let launch = Launch::load(&args.file, super::module::BUILTIN_MODULES)?;
    let exe = std::env::current_exe().context("cannot find the tca executable")?;
    let up = tca_launch::up(&launch, &exe).await?;
    if let (Some(log), Some(kept)) = (&launch.central.log, up.kept_log()) {
        eprintln!(
            "the previous log {} is kept as {}",
            log.display(),
            kept.display()
        );
    }
    eprintln!(
        "central listening on {}; modules connect at {}",
        up.endpoints().join(", "),
        up.module_endpoint()
    );
    eprintln!("started {} modules", up.modules());
    tokio::signal::ctrl_c()
        .await
        .context("cannot wait for Ctrl-C")?;
    eprintln!("stopping {} modules and central", up.modules());
    up.stop().await?;
    Ok(ExitCode::SUCCESS)
}
