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
    // The closure is called at once (in the order messages arrive, see `run_handler`); only
    // its future runs later.
    let call: ErasedHandler =
        Arc::new(move |ctx: Context, data: Vec<u8>| Box::pin(f(ctx, data)) as HandlerFuture);
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
    // Decoded and called at once (in the order messages arrive, see `run_handler`); only the
    // handler's future runs later.
    let call: ErasedHandler = Arc::new(move |ctx: Context, data: Vec<u8>| {
        let message: M = match decode_data(&data) {
            Ok(m) => m,
            Err(e) => {
                let e = HandlerError::new(format!(
                    "data of {} does not decode as this module's type: {e}",
                    M::NAME
                ));
                return Box::pin(std::future::ready(Err(e))) as HandlerFuture;
            }
        };
        let running = f(ctx, message);
        Box::pin(async move {
            let reply = running.await?;
            encode_data(&reply).map_err(|e| HandlerError::new(e.to_string()))
        }) as HandlerFuture
    });
    Ok(HandlerEntry { registration, call })
}
