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
//! - [`module`]: [`Module`], the connected handle: `query`, `goal`, `command`, `inform`,
//!   registry and tree inspection, kill and constraints; the receive loop that runs handlers.
//! - [`context`]: [`Context`], what a handler gets: sends attach to the handler's task node.
//! - [`connector`]: [`Connector`]: in-process or zenoh.
//! - [`credentials`]: the identity/secret of the hello and the zenoh login, in code or from
//!   `TCA_IDENTITY`/`TCA_SECRET` and `TCA_ZENOH_USER`/`TCA_ZENOH_PASSWORD`.
//! - [`compute_time`]: [`ComputeTime`], what a handler charges to simulated time.
//! - `handler`: type erasure of handlers.
//! - [`error`]: [`ModuleError`] and [`HandlerError`].

pub mod builder;
pub mod compute_time;
pub mod connector;
pub mod context;
pub mod credentials;
pub mod error;
mod handler;
pub mod module;
pub mod rejoin;

pub use builder::{ModuleBuilder, REQUERIES_AFTER_CRASH};
pub use compute_time::ComputeTime;
pub use connector::Connector;
pub use context::Context;
pub use credentials::ZenohLogin;
pub use error::{HandlerError, ModuleError, Result};
pub use module::{DEFAULT_QUERY_TIMEOUT, Module, Task, raise_action, send_action};
pub use tca_messages::control::MonitorAction;
pub use tca_messages::{self as messages, ConstraintSpec, SendOptions, TaskRef};
