//! What a handler gets: a [`Module`] handle that sends in the context of the handler's task
//! node, so the goals and commands it sends become children of that node (§3.2).

use std::ops::Deref;

use tca_messages::{Class, MessageId, ModuleName, NodeId};

use crate::module::Module;

/// The context of a running handler. Derefs to [`Module`]: `ctx.query(..)`, `ctx.goal(..)`
/// send in the context of the node being handled.
#[derive(Clone, Debug)]
pub struct Context {
    module: Module,
    redelivery: u32,
    origin: Option<NodeId>,
    message: Incoming,
}

/// What identifies the message being handled.
#[derive(Clone, Debug)]
pub(crate) struct Incoming {
    pub(crate) sender: ModuleName,
    pub(crate) id: MessageId,
    pub(crate) class: Class,
}

impl Context {
    pub(crate) fn new(
        module: Module,
        redelivery: u32,
        origin: Option<NodeId>,
        message: Incoming,
    ) -> Self {
        Context {
            module,
            redelivery,
            origin,
            message,
        }
    }

    /// The module that sent the message being handled (for an exception, the module that
    /// raised it; `central` for what central originates, such as monitor actions).
    pub fn sender(&self) -> &ModuleName {
        &self.message.sender
    }

    /// The id of the message being handled.
    pub fn message_id(&self) -> MessageId {
        self.message.id
    }

    /// The class of the message being handled.
    pub fn class(&self) -> Class {
        self.message.class
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
