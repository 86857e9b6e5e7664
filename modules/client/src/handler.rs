//! Handlers, erased to one shape: postcard data in, postcard reply (or failure) out.

use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;

use tca_messages::control::Registration;
use tca_messages::{Message, MessageName, class_of, decode_data, encode_data};

use crate::context::Context;
use crate::error::{HandlerError, ModuleError, Result};

/// A boxed handler future.
pub(crate) type HandlerFuture = Pin<Box<dyn Future<Output = Result<Vec<u8>, HandlerError>> + Send>>;

/// A handler of one message name.
pub(crate) type ErasedHandler = Arc<dyn Fn(Context, Vec<u8>) -> HandlerFuture + Send + Sync>;

/// A registered handler with what central must know about it.
#[derive(Clone)]
pub(crate) struct HandlerEntry {
    pub(crate) registration: Registration,
    pub(crate) call: ErasedHandler,
}

/// Wraps a handler of encoded data, registered with a format given at run time.
pub(crate) fn erase_raw<F, Fut>(registration: Registration, f: F) -> Result<HandlerEntry>
where
    F: Fn(Context, Vec<u8>) -> Fut + Send + Sync + 'static,
    Fut: Future<Output = Result<Vec<u8>, HandlerError>> + Send + 'static,
{
    if !registration.class.is_handled() {
        return Err(ModuleError::Usage(format!(
            "{} is registered as a {}; only queries, goals, commands, informs and exceptions have handlers",
            registration.name, registration.class
        )));
    }
    if registration.class == tca_messages::Class::Query && registration.reply.is_none() {
        return Err(ModuleError::Usage(format!(
            "query {} needs a reply format; give Registration::reply",
            registration.name
        )));
    }
    let f = Arc::new(f);
    let call: ErasedHandler = Arc::new(move |ctx: Context, data: Vec<u8>| {
        let f = f.clone();
        Box::pin(async move { f(ctx, data).await }) as HandlerFuture
    });
    Ok(HandlerEntry { registration, call })
}

/// Wraps a typed handler. (Every message kind has handlers.)
pub(crate) fn erase<M, F, Fut>(f: F, replace: bool) -> Result<HandlerEntry>
where
    M: Message,
    F: Fn(Context, M) -> Fut + Send + Sync + 'static,
    Fut: Future<Output = Result<M::Reply, HandlerError>> + Send + 'static,
{
    let name = MessageName::new(M::NAME).map_err(|e| ModuleError::Usage(e.to_string()))?;
    let registration = Registration {
        name,
        class: class_of::<M>(),
        format: M::format()?,
        reply: M::reply_format()?,
        replace,
    };
    let f = Arc::new(f);
    let call: ErasedHandler = Arc::new(move |ctx: Context, data: Vec<u8>| {
        let f = f.clone();
        Box::pin(async move {
            let message: M = decode_data(&data).map_err(|e| {
                HandlerError::new(format!(
                    "data of {} does not decode as this module's type: {e}",
                    M::NAME
                ))
            })?;
            let reply = f(ctx, message).await?;
            encode_data(&reply).map_err(|e| HandlerError::new(e.to_string()))
        }) as HandlerFuture
    });
    Ok(HandlerEntry { registration, call })
}
