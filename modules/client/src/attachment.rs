//! Something started beside the modules of a run that starts its own central.

use std::fmt;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;

use crate::Connector;

type AttachFn =
    dyn Fn(Connector) -> Pin<Box<dyn Future<Output = Result<(), String>> + Send>> + Send + Sync;

/// A tool to join a run's in-process central once it is up and before the run's modules
/// connect (a live view that taps all the traffic, for example): it is given the central's
/// connector and returns once it has joined, spawning whatever it keeps doing. An error
/// stops the run before it starts, with that reason.
#[derive(Clone)]
pub struct Attachment {
    name: String,
    attach: Arc<AttachFn>,
}

impl Attachment {
    /// An attachment called `name` (for messages) that runs `attach`.
    pub fn new<F, Fut>(name: impl Into<String>, attach: F) -> Self
    where
        F: Fn(Connector) -> Fut + Send + Sync + 'static,
        Fut: Future<Output = Result<(), String>> + Send + 'static,
    {
        Attachment {
            name: name.into(),
            attach: Arc::new(move |c| Box::pin(attach(c))),
        }
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Joins `connector`'s central; the error says what failed, prefixed with the name.
    pub async fn attach(&self, connector: Connector) -> Result<(), String> {
        (self.attach)(connector)
            .await
            .map_err(|e| format!("{}: {e}", self.name))
    }
}

impl fmt::Debug for Attachment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Attachment")
            .field("name", &self.name)
            .finish()
    }
}
