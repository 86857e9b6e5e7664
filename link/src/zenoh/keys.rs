//! The zenoh key scheme. A module's link is named by the identity its zenoh session was
//! authenticated as, `<who>`, and its zenoh session id, `<zid>`:
//!
//! - the module publishes frames on `tca/up/<who>/<zid>` ([`up_key`]); central subscribes to
//!   `tca/up/<who>/*` for each identity of its policy ([`up_key_pattern`]), or to
//!   `tca/up/*/*` ([`UP_KEY_PATTERN`]) when its router checks no identities;
//! - central publishes frames for it on `tca/down/<who>/<zid>` ([`down_key`]); the module
//!   subscribes there;
//! - the module holds the liveliness token `tca/alive/<who>/<zid>` ([`alive_key`]); when its
//!   session ends (it leaves, crashes or the network drops) zenoh withdraws the token and
//!   central closes the link;
//! - central holds the liveliness token `tca/central` ([`CENTRAL_ALIVE_KEY`]); a module that
//!   sees it withdrawn knows central is gone (killed, or the network dropped). Its zenoh
//!   session keeps trying to reach the router with exponential backoff
//!   ([`RETRY_PERIOD_INIT_MS`] up to [`RETRY_PERIOD_MAX_MS`]); when the token is back, the
//!   module says hello and registers again on the new central.
//!
//! `<who>` is the module's zenoh user when it logs in, else the common name of its TLS
//! certificate, else [`NO_IDENTITY`]. When central's policy authenticates zenoh clients, the
//! router's access control (see [`super::acl`]) lets a session of identity `gait` publish
//! only under `tca/up/gait/`, subscribe only under `tca/down/gait/` and declare tokens only
//! under `tca/alive/gait/`, so the `<who>` of a key central receives is the identity the
//! router authenticated.

/// Central's default zenoh endpoint.
pub const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// Key expression of every module's frames (central subscribes to it when its router checks
/// no identities).
pub const UP_KEY_PATTERN: &str = "tca/up/*/*";

/// Key expression of every module's liveliness token.
pub const ALIVE_KEY_PATTERN: &str = "tca/alive/*/*";

/// Central's liveliness token: modules watch it to notice that central went away (its token is
/// withdrawn when its process dies or the network drops) and came back (they then say hello and
/// register again).
pub const CENTRAL_ALIVE_KEY: &str = "tca/central";

/// The `<who>` of a module whose zenoh session has no identity (no zenoh login, no
/// certificate). It is not a valid identity name, so no policy identity can own its keys.
pub const NO_IDENTITY: &str = "_";

/// How a module's zenoh session retries a lost or refused connection to central: the first
/// retry after this many milliseconds, each next one after twice as long, up to
/// [`RETRY_PERIOD_MAX_MS`].
pub const RETRY_PERIOD_INIT_MS: u64 = 250;

/// The longest wait between two attempts to reach central again, milliseconds.
pub const RETRY_PERIOD_MAX_MS: u64 = 4000;

/// Key on which the module `who`/`zid` publishes its frames.
pub fn up_key(who: &str, zid: &str) -> String {
    format!("tca/up/{who}/{zid}")
}

/// Key expression of every frame the sessions of identity `who` publish.
pub fn up_key_pattern(who: &str) -> String {
    format!("tca/up/{who}/*")
}

/// Key on which central publishes the frames of module `who`/`zid`.
pub fn down_key(who: &str, zid: &str) -> String {
    format!("tca/down/{who}/{zid}")
}

/// Key expression of every frame central publishes for the sessions of identity `who`.
pub fn down_key_pattern(who: &str) -> String {
    format!("tca/down/{who}/*")
}

/// The liveliness token of module `who`/`zid`.
pub fn alive_key(who: &str, zid: &str) -> String {
    format!("tca/alive/{who}/{zid}")
}

/// Key expression of every liveliness token the sessions of identity `who` may hold.
pub fn alive_key_pattern(who: &str) -> String {
    format!("tca/alive/{who}/*")
}

/// The identity and session id an up key or liveliness key names (its last two chunks).
pub fn link_of(key: &str) -> Option<(&str, &str)> {
    let mut chunks = key.rsplit('/');
    let zid = chunks.next().filter(|z| !z.is_empty())?;
    let who = chunks.next().filter(|w| !w.is_empty())?;
    Some((who, zid))
}

/// Checks that `name` can be an identity in zenoh keys: one key chunk of ASCII letters,
/// digits, `-`, `_` and `.`, not [`NO_IDENTITY`]. The error says what is wrong.
pub fn check_identity_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("an identity name must not be empty".into());
    }
    if name == NO_IDENTITY {
        return Err(format!(
            "{NO_IDENTITY:?} is reserved for modules without identity; choose another name"
        ));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.')))
    {
        return Err(format!(
            "identity name {name:?} has {c:?}; use ASCII letters, digits, '-', '_' and '.' \
             (it names the module's zenoh keys, its zenoh user and its certificate's common name)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_name_the_identity_and_session_and_give_them_back() {
        assert_eq!(up_key("gait", "a1"), "tca/up/gait/a1");
        assert_eq!(down_key("gait", "a1"), "tca/down/gait/a1");
        assert_eq!(alive_key("gait", "a1"), "tca/alive/gait/a1");
        assert_eq!(up_key_pattern("gait"), "tca/up/gait/*");
        assert_eq!(link_of(&up_key("gait", "a1")), Some(("gait", "a1")));
        assert_eq!(link_of(&alive_key("_", "b2")), Some(("_", "b2")));
        assert_eq!(link_of("tca/up/"), None);
        assert_eq!(link_of("a1"), None);
    }

    #[test]
    fn identity_names_are_single_plain_chunks() {
        for good in ["gait", "ltm-2", "nav.ism", "Tools_1"] {
            assert!(check_identity_name(good).is_ok(), "{good}");
        }
        for bad in ["", "_", "a/b", "a*", "**", "$x", "a b", "é"] {
            assert!(check_identity_name(bad).is_err(), "{bad}");
        }
    }
}
