//! The `tca` command: central, modules, launch files, the walking system, and the tools that
//! read traffic logs. It parses arguments and calls the library crates (see the README's
//! architecture table).

mod cli;

/// The allocator of the `tca` command. Central and the modules allocate small buffers for
/// every envelope and log record; mimalloc's thread-local free lists cut that cost by about a
/// third against glibc's malloc on the goal-throughput path (see BENCHMARKS.md).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    cli::main()
}
