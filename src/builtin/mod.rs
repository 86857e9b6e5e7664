//! Modules built into the `tca` command, runnable as their own process with
//! `tca module NAME [--connect ENDPOINT]`.

pub mod echo;

use tca_module::{Connector, Module, ModuleError};

/// Names of the built-in modules.
pub const BUILTIN_MODULES: &[&str] = &["echo"];

/// Connects the built-in module `name`.
pub async fn connect(name: &str, connector: &Connector) -> Result<Module, ModuleError> {
    match name {
        "echo" => echo::connect(connector, "echo").await,
        other => Err(ModuleError::Usage(format!(
            "no built-in module named {other:?}; built-in modules: {}",
            BUILTIN_MODULES.join(", ")
        ))),
    }
}
