//! Typed messages: a Rust type that declares its name and class.
//!
//! A message's class is also a type ([`kind`]), so that sending a message as the wrong class
//! does not compile: a module's `goal` takes only messages whose kind is [`kind::Goal`].

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::class::Class;
use crate::error::FormatError;
use crate::format::DataFormat;

/// The classes of §3.2 as types: a [`Message`]'s `Kind` says how it may be sent.
pub mod kind {
    use crate::class::Class;

    mod sealed {
        pub trait Sealed {}
    }

    /// A message class as a type. Implemented by the five uninhabited types of this module
    /// only.
    pub trait Kind: sealed::Sealed + Send + Sync + 'static {
        /// The class.
        const CLASS: Class;
    }

    /// Goals and commands: the classes that become task-tree nodes.
    pub trait TaskClass: Kind {}

    /// Goals, commands and informs: what a monitor may send when its condition holds.
    pub trait MonitorSend: Kind {}

    macro_rules! kinds {
        ($($(#[$doc:meta])* $name:ident),*) => {$(
            $(#[$doc])*
            #[derive(Debug)]
            pub enum $name {}
            impl sealed::Sealed for $name {}
            impl Kind for $name {
                const CLASS: Class = Class::$name;
            }
        )*};
    }

    kinds!(
        /// A query: blocks the sender until its reply.
        Query,
        /// A goal: a task to plan, a node of the task tree.
        Goal,
        /// A command: a task to execute, a node of the task tree.
        Command,
        /// An inform: one-way.
        Inform,
        /// An exception: raised by a handler, routed up the task tree.
        Exception
    );

    impl TaskClass for Goal {}
    impl TaskClass for Command {}
    impl MonitorSend for Goal {}
    impl MonitorSend for Command {}
    impl MonitorSend for Inform {}
}

/// A message type. Implement it with the [`message!`](crate::message) macro:
///
/// ```
/// use serde::{Deserialize, Serialize};
/// /// Move the arm's base to a position on its rail, metres.
/// #[derive(Serialize, Deserialize)]
/// pub struct MoveBase { pub target_m: f64 }
/// tca_messages::message!(MoveBase: command "moveBase");
///
/// #[derive(Serialize, Deserialize)]
/// pub struct BasePosition;
/// #[derive(Serialize, Deserialize)]
/// pub struct Position { pub at_m: f64 }
/// tca_messages::message!(BasePosition: query "basePosition" -> Position);
///
/// use tca_messages::{Class, Message, class_of};
/// assert_eq!(MoveBase::NAME, "moveBase");
/// assert_eq!(class_of::<BasePosition>(), Class::Query);
/// ```
pub trait Message: Serialize + DeserializeOwned + Send + Sync + 'static {
    /// The name central routes by.
    const NAME: &'static str;
    /// The class as a type: [`kind::Query`], [`kind::Goal`], [`kind::Command`],
    /// [`kind::Inform`] or [`kind::Exception`]. The class on the wire is always this one's
    /// ([`class_of`]).
    type Kind: kind::Kind;
    /// What a query's handler answers with; `()` for the other classes.
    type Reply: Serialize + DeserializeOwned + Send + 'static;

    /// The data format registered with central for this message.
    fn format() -> Result<DataFormat, FormatError> {
        DataFormat::of::<Self>()
    }

    /// The data format of the reply (queries only).
    fn reply_format() -> Result<Option<DataFormat>, FormatError> {
        if class_of::<Self>() == Class::Query {
            DataFormat::of::<Self::Reply>().map(Some)
        } else {
            Ok(None)
        }
    }
}

/// The class of message type `M`: the one its [`Message::Kind`] names.
pub fn class_of<M: Message>() -> Class {
    <M::Kind as kind::Kind>::CLASS
}

/// Declares a type as a [`Message`]: `message!(Type: class "name")`, and for queries
/// `message!(Type: query "name" -> ReplyType)`. Classes: `query`, `goal`, `command`, `inform`,
/// `exception`.
#[macro_export]
macro_rules! message {
    ($ty:ty: query $name:literal -> $reply:ty) => {
        impl $crate::Message for $ty {
            const NAME: &'static str = $name;
            type Kind = $crate::kind::Query;
            type Reply = $reply;
        }
    };
    ($ty:ty: goal $name:literal) => {
        $crate::message!(@task $ty, Goal, $name);
    };
    ($ty:ty: command $name:literal) => {
        $crate::message!(@task $ty, Command, $name);
    };
    ($ty:ty: inform $name:literal) => {
        $crate::message!(@task $ty, Inform, $name);
    };
    ($ty:ty: exception $name:literal) => {
        $crate::message!(@task $ty, Exception, $name);
    };
    (@task $ty:ty, $class:ident, $name:literal) => {
        impl $crate::Message for $ty {
            const NAME: &'static str = $name;
            type Kind = $crate::kind::$class;
            type Reply = ();
        }
    };
}
