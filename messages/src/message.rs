//! Typed messages: a Rust type that declares its name and class.

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::class::Class;
use crate::error::FormatError;
use crate::format::DataFormat;

/// A message type. Implement it with the [`message!`](crate::message) macro:
///
/// ```
/// use serde::{Deserialize, Serialize};
/// /// Move the carriage along the rails to a world Y position.
/// #[derive(Serialize, Deserialize)]
/// pub struct BodyMove { pub target_y_m: f64 }
/// tca_messages::message!(BodyMove: command "bodyMove");
///
/// #[derive(Serialize, Deserialize)]
/// pub struct BodyPosition;
/// #[derive(Serialize, Deserialize)]
/// pub struct Pose { pub y_m: f64 }
/// tca_messages::message!(BodyPosition: query "bodyPosition" -> Pose);
///
/// use tca_messages::{Class, Message};
/// assert_eq!(BodyMove::NAME, "bodyMove");
/// assert_eq!(<BodyPosition as Message>::CLASS, Class::Query);
/// ```
pub trait Message: Serialize + DeserializeOwned + Send + Sync + 'static {
    /// The name central routes by.
    const NAME: &'static str;
    /// The class: query, goal, command, inform or exception.
    const CLASS: Class;
    /// What a query's handler answers with; `()` for the other classes.
    type Reply: Serialize + DeserializeOwned + Send + 'static;

    /// The data format registered with central for this message.
    fn format() -> Result<DataFormat, FormatError> {
        DataFormat::of::<Self>()
    }

    /// The data format of the reply (queries only).
    fn reply_format() -> Result<Option<DataFormat>, FormatError> {
        if Self::CLASS == Class::Query {
            DataFormat::of::<Self::Reply>().map(Some)
        } else {
            Ok(None)
        }
    }
}

/// Declares a type as a [`Message`]: `message!(Type: class "name")`, and for queries
/// `message!(Type: query "name" -> ReplyType)`. Classes: `query`, `goal`, `command`, `inform`,
/// `exception`.
#[macro_export]
macro_rules! message {
    ($ty:ty: query $name:literal -> $reply:ty) => {
        impl $crate::Message for $ty {
            const NAME: &'static str = $name;
            const CLASS: $crate::Class = $crate::Class::Query;
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
            const CLASS: $crate::Class = $crate::Class::$class;
            type Reply = ();
        }
    };
}
