//! zenoh configuration of central's router and of module clients, and the zenoh login.

use std::path::{Path, PathBuf};

use super::acl::{Authenticators, access_control};
use super::keys::{RETRY_PERIOD_INIT_MS, RETRY_PERIOD_MAX_MS};
use super::tls::{TlsFiles, is_tls};
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

/// Mutual TLS with `tls`'s files, as the `side` (`listen` or `connect`) of links.
fn set_tls(config: &mut zenoh::Config, tls: &TlsFiles, side: &str) -> Result<()> {
    tls.check()?;
    let path = |p: &Path| p.to_string_lossy().into_owned();
    for (key, value) in [
        (format!("{side}_certificate"), path(&tls.certificate)),
        (format!("{side}_private_key"), path(&tls.private_key)),
        ("root_ca_certificate".to_owned(), path(&tls.ca)),
    ] {
        set_string(config, &format!("transport/link/tls/{key}"), &value)?;
    }
    set(config, "transport/link/tls/enable_mtls", "true")
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

/// How central's router authenticates zenoh clients and confines them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RouterSecurity {
    /// zenoh user/password dictionary (`user:password` per line): every client must log in
    /// with one of its pairs (zenoh's `transport/auth/usrpwd`), and its user is its identity.
    pub users_file: Option<PathBuf>,
    /// Mutual TLS on the `tls/` endpoints: central's certificate and key, and the authority
    /// every client's certificate must be signed by; a certificate's common name is its
    /// identity.
    pub tls: Option<TlsFiles>,
    /// The identities (zenoh users, certificate common names) the router lets in. With an
    /// authenticator above, its access control confines each to its own keys (see
    /// [`super::acl`]) and denies everything else.
    pub identities: Vec<String>,
}

impl RouterSecurity {
    /// How the router tells sessions apart; with any, it enforces access control.
    pub fn authenticators(&self) -> Authenticators {
        Authenticators {
            users: self.users_file.is_some(),
            certificates: self.tls.is_some(),
        }
    }
}

/// zenoh configuration of central: a router listening on `listen`, open to every client.
pub fn router_config(listen: &[String]) -> Result<zenoh::Config> {
    router_config_secured(listen, &RouterSecurity::default())
}

/// zenoh configuration of central: a router listening on `listen`, authenticating and
/// confining clients as `security` says. With a users file or TLS the router's access
/// control keeps each identity to its own keys, and its admin space is on (for central's own
/// session only: the access control denies every client's query) so that central can read
/// how many messages the access control refused.
pub fn router_config_secured(
    listen: &[String],
    security: &RouterSecurity,
) -> Result<zenoh::Config> {
    let mut config = base_config("router")?;
    set(&mut config, "listen/endpoints", &endpoints_json(listen)?)?;
    if let Some(file) = &security.users_file {
        check_users_file(file, &security.identities)?;
        set_string(
            &mut config,
            "transport/auth/usrpwd/dictionary_file",
            &file.to_string_lossy(),
        )?;
    }
    match &security.tls {
        Some(tls) => set_tls(&mut config, tls, "listen")?,
        None => {
            if let Some(e) = listen.iter().find(|e| is_tls(e)) {
                return Err(LinkError::Config(format!(
                    "listening on {e} needs TLS files: give central a policy whose [transport.tls] \
                     names its certificate, private_key and the ca that signed the modules' \
                     certificates (see policy.example.toml)"
                )));
            }
        }
    }
    if security.authenticators().any() {
        let acl = access_control(&security.identities, security.authenticators())?;
        set(&mut config, "access_control", &acl.to_string())?;
        set(&mut config, "adminspace/enabled", "true")?;
    }
    Ok(config)
}

/// Checks a zenoh user/password dictionary before zenoh reads it, for a clearer error, and
/// that each of its users is one of `identities`.
fn check_users_file(file: &Path, identities: &[String]) -> Result<()> {
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
            Some((u, p)) if !u.trim().is_empty() && !p.trim().is_empty() => {
                users += 1;
                if !identities.iter().any(|n| n == u) {
                    return Err(LinkError::Config(format!(
                        "zenoh users file {} line {}: user {u:?} is no identity of the policy; \
                         a zenoh user is the identity its module connects as, so add an \
                         [[identity]] named {u:?} or remove the line",
                        file.display(),
                        i + 1
                    )));
                }
            }
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
    client_config_secured(connect, login, None)
}

/// zenoh configuration of a module: a client connecting to `connect`, logging in with `login`
/// and presenting the certificate of `tls` (checking central's against its CA) when given.
/// A `tls/` endpoint without `tls` is refused with an error that says what to set.
pub fn client_config_secured(
    connect: &[String],
    login: Option<&ZenohLogin>,
    tls: Option<&TlsFiles>,
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
    match tls {
        Some(tls) => set_tls(&mut config, tls, "connect")?,
        None => {
            if let Some(e) = connect.iter().find(|e| is_tls(e)) {
                return Err(LinkError::Config(format!(
                    "connecting to {e} needs a certificate: set {}, {} and {} (the module's \
                     certificate, its key, and the CA that signed central's)",
                    super::tls::ENV_CERTIFICATE,
                    super::tls::ENV_PRIVATE_KEY,
                    super::tls::ENV_CA
                )));
            }
        }
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
        let with = |file: &Path| RouterSecurity {
            users_file: Some(file.to_owned()),
            tls: None,
            identities: vec!["gait".into()],
        };
        let err = router_config_secured(&["tcp/127.0.0.1:0".into()], &with(&bad)).unwrap_err();
        assert!(err.to_string().contains("line 2"), "{err}");
        let empty = dir.path().join("empty.txt");
        std::fs::write(&empty, "\n").unwrap();
        let err = router_config_secured(&[], &with(&empty)).unwrap_err();
        assert!(err.to_string().contains("no user:password"), "{err}");
        let missing = dir.path().join("missing.txt");
        let err = router_config_secured(&[], &with(&missing)).unwrap_err();
        assert!(err.to_string().contains("cannot read"), "{err}");
        let stranger = dir.path().join("stranger.txt");
        std::fs::write(&stranger, "gait:a\nltm:b\n").unwrap();
        let err = router_config_secured(&[], &with(&stranger)).unwrap_err();
        assert!(err.to_string().contains("\"ltm\" is no identity"), "{err}");
        let good = dir.path().join("good.txt");
        std::fs::write(&good, "gait:a\n").unwrap();
        assert!(router_config_secured(&["tcp/127.0.0.1:0".into()], &with(&good)).is_ok());
    }

    #[test]
    fn tls_endpoints_need_tls_files() {
        let err = router_config(&["tls/127.0.0.1:0".into()]).unwrap_err();
        assert!(err.to_string().contains("[transport.tls]"), "{err}");
        let err = client_config_secured(&["tls/127.0.0.1:7447".into()], None, None).unwrap_err();
        assert!(err.to_string().contains("TCA_ZENOH_TLS_CERT"), "{err}");
    }

    #[test]
    fn a_login_never_shows_its_password() {
        let login = ZenohLogin::new("gait", "hunter2");
        assert!(!format!("{login:?}").contains("hunter2"));
    }
}
