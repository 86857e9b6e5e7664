//! The `tca` command: central, modules, launch files, ping, registry and log tools.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
