//! The TCA module library: what a module links to connect to central, register the messages
//! it handles and talk to the rest of the system (§3.2 of the report).
//!
//! ```no_run
//! use serde::{Deserialize, Serialize};
//! use tca_module::{Connector, Module};
//!
//! /// The carriage position on the rails, in metres.
//! #[derive(Serialize, Deserialize)]
//! pub struct BodyPosition;
//! #[derive(Serialize, Deserialize)]
//! pub struct Pose { pub y_m: f64 }
//! tca_messages::message!(BodyPosition: query "bodyPosition" -> Pose);
//!
//! # async fn run(connector: Connector) -> Result<(), tca_module::ModuleError> {
//! // A module that answers the query...
//! let _controller = Module::builder("controller")
//!     .handle(|_ctx, _q: BodyPosition| async { Ok(Pose { y_m: 1.5 }) })
//!     .connect(&connector)
//!     .await?;
//! // ...and one that asks it, through central.
//! let gait = Module::builder("gait").connect(&connector).await?;
//! let pose = gait.query(&BodyPosition).await?;
//! assert_eq!(pose.y_m, 1.5);
//! # Ok(()) }
//! ```
//!
//! # Layout
//!
//! - [`builder`]: [`ModuleBuilder`]: name, capacity, handlers, `connect`.
//! - [`module`]: [`Module`], the connected handle, by job: sending (`query`, `goal`,
//!   `command`, `inform`, `raise`, typed and raw), control requests (registry and tree
//!   inspection, kill, constraints, exception handlers, monitors) and the link's life cycle,
//!   receiving and dispatch to handlers, the simulated clock.
//! - [`context`]: [`Context`], what a handler gets: sends attach to the handler's task node.
//! - [`connector`]: [`Connector`]: any `tca-link` transport (in-process, local socket, zenoh),
//!   or one chosen by endpoint.
//! - [`credentials`]: the identity/secret of the hello and the zenoh login, in code or from
//!   `TCA_IDENTITY`/`TCA_SECRET` and `TCA_ZENOH_USER`/`TCA_ZENOH_PASSWORD`.
//! - [`compute_time`]: [`ComputeTime`], what a handler charges to simulated time.
//! - `handler`: type erasure of handlers.
//! - [`rejoin`]: joining a restarted central again (transports where central can die alone:
//!   zenoh and the local socket).
//! - [`error`]: [`ModuleError`] and [`HandlerError`].
//!
//! Message classes are checked when the code compiles: a goal is sent with `goal`, a query
//! with `query`, and not the other way round. This compiles:
//!
//! ```no_run
//! use serde::{Deserialize, Serialize};
//! #[derive(Serialize, Deserialize)]
//! pub struct BasePosition;
//! tca_messages::message!(BasePosition: query "basePosition" -> f64);
//!
//! fn plan(module: &tca_module::Module) {
//!     let _ = module.query(&BasePosition);
//! }
//! ```
//!
//! and this does not:
//!
//! ```compile_fail,E0271
//! use serde::{Deserialize, Serialize};
//! #[derive(Serialize, Deserialize)]
//! pub struct BasePosition;
//! tca_messages::message!(BasePosition: query "basePosition" -> f64);
//!
//! fn plan(module: &tca_module::Module) {
//!     // A query is not a goal: this does not compile.
//!     let _ = module.goal(&BasePosition);
//! }
//! ```

pub mod attachment;
pub mod builder;
pub mod compute_time;
pub mod connector;
pub mod context;
pub mod credentials;
pub mod error;
mod handler;
pub mod module;
pub mod rejoin;

pub use attachment::Attachment;
pub use builder::{ModuleBuilder, REQUERIES_AFTER_CRASH};
pub use compute_time::ComputeTime;
pub use connector::Connector;
pub use context::Context;
pub use credentials::{TlsFiles, ZenohLogin};
pub use error::{HandlerError, ModuleError, Result};
pub use module::{
    DEFAULT_QUERY_TIMEOUT, Module, Task, WatchedTask, WeakModule, raise_action, send_action,
};
pub use tca_messages::control::MonitorAction;
pub use tca_messages::{self as messages, ConstraintSpec, TaskRef, kind};
