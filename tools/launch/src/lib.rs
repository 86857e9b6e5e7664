//! Launch files (`tca up FILE`): central and a set of modules, each its own process, started
//! together and stopped together; a module whose process dies is started again.
//!
//! # Layout
//!
//! - [`file`]: the launch file format ([`Launch`]) and its checks.
//! - [`supervise`]: starting central and the module processes ([`up`]), restarting those
//!   that die, stopping everything ([`Up::stop`]).
//! - [`error`](mod@error): [`LaunchError`].

pub mod error;
pub mod file;
pub mod supervise;

pub use error::LaunchError;
pub use file::{CentralSection, Launch, ModuleSection};
pub use supervise::{FIRST_PAUSE, HEALTHY_RUN, LAUNCHER_PID_ENV, LONGEST_PAUSE, Up, up};
