//! zenoh configuration of central's router and of module clients, and the zenoh login.

use std::path::Path;

use super::keys::{RETRY_PERIOD_INIT_MS, RETRY_PERIOD_MAX_MS};
use crate::{LinkError, Result};

fn config_error(key: &str, e: impl std::fmt::Display) -> LinkError {
    LinkError::Config(format!("zenoh configuration {key}: {e}"))
}

fn set(config: &mut zenoh::Config, key: &str, json5: &str) -> Result<()> {
    config
        .insert_json5(key, json5)
        .map_err(|e| config_error(key, e))
}

fn set_string(config: &mut zenoh::Config, key: &str, value: &str) -> Result<()> {
    let json = serde_json::to_string(value).map_err(|e| config_error(key, e))?;
    set(config, key, &json)
}

fn endpoints_json(endpoints: &[String]) -> Result<String> {
    for e in endpoints {
        if !e.contains('/') {
            return Err(LinkError::Config(format!(
                "endpoint {e:?} has no protocol; write it like tcp/127.0.0.1:7447"
            )));
        }
    }
    serde_json::to_string(endpoints).map_err(|e| config_error("endpoints", e))
}

fn base_config(mode: &str) -> Result<zenoh::Config> {
    let mut config = zenoh::Config::default();
    set(&mut config, "mode", &format!("{mode:?}"))?;
    set(&mut config, "scouting/multicast/enabled", "false")?;
    set(&mut config, "scouting/gossip/enabled", "false")?;
    Ok(config)
}

/// zenoh configuration of central: a router listening on `listen`.
pub fn router_config(listen: &[String]) -> Result<zenoh::Config> {
    router_config_with_users(listen, None)
}

/// zenoh configuration of central: a router listening on `listen`. With `users_file` (a zenoh
/// user/password dictionary, `user:password` per line) the router refuses every client that
/// does not log in with one of its pairs (zenoh's `transport/auth/usrpwd`).
pub fn router_config_with_users(
    listen: &[String],
    users_file: Option<&Path>,
) -> Result<zenoh::Config> {
    let mut config = base_config("router")?;
    set(&mut config, "listen/endpoints", &endpoints_json(listen)?)?;
    if let Some(file) = users_file {
        check_users_file(file)?;
        set_string(
            &mut config,
            "transport/auth/usrpwd/dictionary_file",
            &file.to_string_lossy(),
        )?;
    }
    Ok(config)
}

/// Checks a zenoh user/password dictionary before zenoh reads it, for a clearer error.
fn check_users_file(file: &Path) -> Result<()> {
    let text = std::fs::read_to_string(file).map_err(|e| {
        LinkError::Config(format!(
            "cannot read the zenoh users file {}: {e}",
            file.display()
        ))
    })?;
    let mut users = 0;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        match line.split_once(':') {
            Some((u, p)) if !u.trim().is_empty() && !p.trim().is_empty() => users += 1,
            _ => {
                return Err(LinkError::Config(format!(
                    "zenoh users file {} line {}: write one user:password per line",
                    file.display(),
                    i + 1
                )));
            }
        }
    }
    if users == 0 {
        return Err(LinkError::Config(format!(
            "zenoh users file {} has no user:password line; add one per module login",
            file.display()
        )));
    }
    Ok(())
}

/// A zenoh login (user/password authentication of the zenoh transport).
#[derive(Clone, PartialEq, Eq)]
pub struct ZenohLogin {
    /// The zenoh user.
    pub user: String,
    /// Its password.
    pub password: String,
}

impl std::fmt::Debug for ZenohLogin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ZenohLogin {{ user: {:?}, password: *** }}", self.user)
    }
}

impl ZenohLogin {
    /// A login as `user` with `password`.
    pub fn new(user: impl Into<String>, password: impl Into<String>) -> Self {
        ZenohLogin {
            user: user.into(),
            password: password.into(),
        }
    }

    /// The login named by the environment variables `TCA_ZENOH_USER` and
    /// `TCA_ZENOH_PASSWORD`, when both are set.
    pub fn from_env() -> Option<Self> {
        let user = std::env::var("TCA_ZENOH_USER").ok()?;
        let password = std::env::var("TCA_ZENOH_PASSWORD").ok()?;
        Some(ZenohLogin { user, password })
    }
}

/// zenoh configuration of a module: a client connecting to `connect`, logging in with `login`
/// when central requires it.
pub fn client_config_with_login(
    connect: &[String],
    login: Option<&ZenohLogin>,
) -> Result<zenoh::Config> {
    let mut config = client_config(connect)?;
    if let Some(login) = login {
        set_string(&mut config, "transport/auth/usrpwd/user", &login.user)?;
        set_string(
            &mut config,
            "transport/auth/usrpwd/password",
            &login.password,
        )?;
    }
    Ok(config)
}

/// zenoh configuration of a module: a client connecting to `connect`.
pub fn client_config(connect: &[String]) -> Result<zenoh::Config> {
    let mut config = base_config("client")?;
    set(&mut config, "connect/endpoints", &endpoints_json(connect)?)?;
    // Do not listen for peers: a module only talks to central.
    set(&mut config, "listen/endpoints", "[]")?;
    // When central goes away, keep trying to reach it, backing off.
    let retry = format!(
        "{{ period_init_ms: {RETRY_PERIOD_INIT_MS}, period_max_ms: {RETRY_PERIOD_MAX_MS}, \
         period_increase_factor: 2.0 }}"
    );
    set(&mut config, "connect/retry", &retry)?;
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endpoint_without_a_protocol_is_refused_with_an_example() {
        let err = client_config(&["127.0.0.1:7447".into()]).unwrap_err();
        assert!(err.to_string().contains("tcp/127.0.0.1:7447"), "{err}");
        assert!(router_config(&["tcp/127.0.0.1:0".into()]).is_ok());
    }

    #[test]
    fn users_files_are_checked_line_by_line() {
        let dir = tempfile::tempdir().unwrap();
        let bad = dir.path().join("bad.txt");
        std::fs::write(&bad, "gait:secret\njust-a-name\n").unwrap();
        let err = router_config_with_users(&["tcp/127.0.0.1:0".into()], Some(&bad)).unwrap_err();
        assert!(err.to_string().contains("line 2"), "{err}");
        let empty = dir.path().join("empty.txt");
        std::fs::write(&empty, "\n").unwrap();
        let err = router_config_with_users(&[], Some(&empty)).unwrap_err();
        assert!(err.to_string().contains("no user:password"), "{err}");
        let missing = dir.path().join("missing.txt");
        let err = router_config_with_users(&[], Some(&missing)).unwrap_err();
        assert!(err.to_string().contains("cannot read"), "{err}");
    }

    #[test]
    fn a_login_never_shows_its_password() {
        let login = ZenohLogin::new("gait", "hunter2");
        assert!(!format!("{login:?}").contains("hunter2"));
    }
}
