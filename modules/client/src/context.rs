//! What a handler gets: a [`Module`] handle that sends in the context of the handler's task
//! node, so the goals and commands it sends become children of that node (§3.2).

use std::ops::Deref;

use tca_messages::NodeId;

use crate::module::Module;

/// The context of a running handler. Derefs to [`Module`]: `ctx.query(..)`, `ctx.goal(..)`
/// send in the context of the node being handled.
#[derive(Clone, Debug)]
pub struct Context {
    module: Module,
    redelivery: u32,
    origin: Option<NodeId>,
}

impl Context {
    pub(crate) fn new(module: Module, redelivery: u32, origin: Option<NodeId>) -> Self {
        Context {
            module,
            redelivery,
            origin,
        }
    }

    /// The sender's task node when the message was sent; for an exception, the node that
    /// raised it.
    pub fn origin(&self) -> Option<NodeId> {
        self.origin
    }

    /// The task node being handled (goals and commands), if any.
    pub fn node(&self) -> Option<NodeId> {
        self.module.context()
    }

    /// How many times central delivered this message before (its handler's module crashed).
    pub fn redelivery(&self) -> u32 {
        self.redelivery
    }

    /// The module handle in this context.
    pub fn module(&self) -> &Module {
        &self.module
    }
}

impl Deref for Context {
    type Target = Module;
    fn deref(&self) -> &Module {
        &self.module
    }
}
