//! TCA module library: connect to central, register handlers, send messages.
