//! The zenoh key scheme. A module's link is named by its zenoh session id `<zid>`:
//!
//! - the module publishes frames on `tca/up/<zid>` ([`up_key`]); central subscribes to
//!   `tca/up/*` ([`UP_KEY_PATTERN`]);
//! - central publishes frames for it on `tca/down/<zid>` ([`down_key`]); the module subscribes
//!   there;
//! - the module holds the liveliness token `tca/alive/<zid>` ([`alive_key`]); when its session
//!   ends (it leaves, crashes or the network drops) zenoh withdraws the token and central
//!   closes the link;
//! - central holds the liveliness token `tca/central` ([`CENTRAL_ALIVE_KEY`]); a module that
//!   sees it withdrawn knows central is gone (killed, or the network dropped). Its zenoh
//!   session keeps trying to reach the router with exponential backoff
//!   ([`RETRY_PERIOD_INIT_MS`] up to [`RETRY_PERIOD_MAX_MS`]); when the token is back, the
//!   module says hello and registers again on the new central.

/// Central's default zenoh endpoint.
pub const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// Key expression central subscribes to for every module's frames.
pub const UP_KEY_PATTERN: &str = "tca/up/*";

/// Key expression of every module's liveliness token.
pub const ALIVE_KEY_PATTERN: &str = "tca/alive/*";

/// Central's liveliness token: modules watch it to notice that central went away (its token is
/// withdrawn when its process dies or the network drops) and came back (they then say hello and
/// register again).
pub const CENTRAL_ALIVE_KEY: &str = "tca/central";

/// How a module's zenoh session retries a lost or refused connection to central: the first
/// retry after this many milliseconds, each next one after twice as long, up to
/// [`RETRY_PERIOD_MAX_MS`].
pub const RETRY_PERIOD_INIT_MS: u64 = 250;

/// The longest wait between two attempts to reach central again, milliseconds.
pub const RETRY_PERIOD_MAX_MS: u64 = 4000;

/// Key on which a module publishes its frames.
pub fn up_key(zid: &str) -> String {
    format!("tca/up/{zid}")
}

/// Key on which central publishes a module's frames.
pub fn down_key(zid: &str) -> String {
    format!("tca/down/{zid}")
}

/// A module's liveliness token.
pub fn alive_key(zid: &str) -> String {
    format!("tca/alive/{zid}")
}

/// The session id a module's up key or liveliness key names (its last chunk).
pub fn zid_of(key: &str) -> Option<&str> {
    key.rsplit('/').next().filter(|z| !z.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_name_the_session_and_give_it_back() {
        assert_eq!(up_key("a1"), "tca/up/a1");
        assert_eq!(down_key("a1"), "tca/down/a1");
        assert_eq!(alive_key("a1"), "tca/alive/a1");
        assert_eq!(zid_of(&up_key("a1")), Some("a1"));
        assert_eq!(zid_of(&alive_key("b2")), Some("b2"));
        assert_eq!(zid_of("tca/up/"), None);
    }
}
