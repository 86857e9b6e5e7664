//! The registration policy: who may connect, and which messages each identity may register and
//! send. Loaded from a TOML file (`tca central --policy FILE`; see `policy.example.toml` at the
//! repository root):
//!
//! ```toml
//! [transport]
//! # Optional: zenoh user/password dictionary (`user:password` per line). With it, central's
//! # zenoh router refuses every zenoh client that does not log in with one of these pairs.
//! # Each user is an identity below.
//! zenoh_users_file = "zenoh-users.txt"
//!
//! # Optional: mutual TLS on `tls/` endpoints. A module's certificate must be signed by `ca`;
//! # its common name is its identity.
//! [transport.tls]
//! certificate = "central.pem"
//! private_key = "central.key"
//! ca = "ca.pem"
//!
//! # Optional: what modules that present no credentials may do. Without this section they are
//! # refused at hello.
//! [anonymous]
//! register = []
//! send = []
//!
//! [[identity]]
//! name = "gait"
//! # hex SHA3-256 of "tca-identity:<name>:<secret>"; print it with
//! # `cargo run -p tca-central --example hash_secret -- gait` (reads the secret on stdin).
//! # Optional: without it the identity connects only as proven by its zenoh user or
//! # certificate.
//! secret_sha3 = "…64 hex digits…"
//! modules = ["gait"]            # module names it may connect as (globs); default [name]
//! register = ["planStep"]       # message names it may register (globs)
//! send = ["ltm*", "moveArm"]    # message names it may send (globs)
//! ```
//!
//! Identity names are ASCII letters, digits, `-`, `_` and `.`: they name the identity's zenoh
//! keys, its zenoh user and its certificate's common name. When the policy authenticates zenoh
//! clients (a users file, TLS), central's router confines each identity to its own keys
//! ([`tca_link::zenoh::acl`]), and a link's identity is the one its login or certificate
//! proved: its hello may omit credentials, and may not name another identity.
//!
//! Globs: `*` matches any run of characters (also none), `?` exactly one. Control messages:
//! `tca.hello`, `tca.helloAuth`, `tca.register` (each entry is checked against `register`),
//! `tca.bye`, `tca.registry` and `tca.tree` are always allowed; the other control requests
//! (`tca.kill`, `tca.constrain`, `tca.onException`, `tca.retry`, `tca.monitor`) must match `send`,
//! and a monitor's condition query and action must match it too. Answers (reply, success,
//! failure) to what central delivered to a module are always allowed.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Deserialize;
use sha3::{Digest, Sha3_256};
use tca_link::zenoh::{RouterSecurity, TlsFiles, check_identity_name};
use tca_messages::control::{ControlKind, Credentials};

/// Errors loading a policy file.
#[derive(Debug, thiserror::Error)]
pub enum PolicyError {
    /// The file could not be read.
    #[error("cannot read policy file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not valid TOML of the expected shape.
    #[error("policy file {path}: {reason}; see policy.example.toml for the format")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
    /// The file parsed but says something impossible.
    #[error("policy file {path}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
}

/// Result alias of the policy module.
pub type Result<T, E = PolicyError> = std::result::Result<T, E>;

/// The file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PolicyFile {
    #[serde(default)]
    transport: TransportSection,
    anonymous: Option<PermissionsFile>,
    #[serde(default)]
    identity: Vec<IdentityFile>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct TransportSection {
    zenoh_users_file: Option<PathBuf>,
    tls: Option<TlsSection>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TlsSection {
    certificate: PathBuf,
    private_key: PathBuf,
    ca: PathBuf,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PermissionsFile {
    #[serde(default)]
    register: Vec<String>,
    #[serde(default)]
    send: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct IdentityFile {
    name: String,
    secret_sha3: Option<String>,
    modules: Option<Vec<String>>,
    #[serde(default)]
    register: Vec<String>,
    #[serde(default)]
    send: Vec<String>,
}

/// What one identity (or the anonymous modules) may do.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Permissions {
    /// Who this is, as rules name it: `identity "gait"` or `[anonymous]`.
    pub who: String,
    /// Module names it may connect as (globs).
    pub modules: Vec<String>,
    /// Message names it may register (globs).
    pub register: Vec<String>,
    /// Message names it may send (globs).
    pub send: Vec<String>,
}

/// One identity of the policy.
#[derive(Clone, PartialEq, Eq)]
struct Identity {
    name: String,
    /// None: it can only be admitted on a link whose transport authenticated it.
    secret_hash: Option<[u8; 32]>,
    permissions: Arc<Permissions>,
}

/// A loaded policy. See the module documentation for the file format.
#[derive(Clone, PartialEq, Eq)]
pub struct Policy {
    identities: Vec<Identity>,
    anonymous: Option<Arc<Permissions>>,
    zenoh_users_file: Option<PathBuf>,
    tls: Option<TlsFiles>,
}

impl fmt::Debug for Policy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.identities.iter().map(|i| i.name.as_str()).collect();
        f.debug_struct("Policy")
            .field("identities", &names)
            .field("anonymous", &self.anonymous)
            .field("zenoh_users_file", &self.zenoh_users_file)
            .field("tls", &self.tls)
            .finish()
    }
}

/// What an authenticated (or admitted anonymous) module may do; kept by central per module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Grant {
    /// The identity it authenticated as (`anonymous` when it gave none).
    pub identity: String,
    permissions: Arc<Permissions>,
}

impl Grant {
    /// Checks that the module may send `name`; the error names the rule that refused it.
    pub fn may_send(&self, name: &str) -> std::result::Result<(), String> {
        if always_allowed(name) || matches_any(&self.permissions.send, name) {
            return Ok(());
        }
        Err(format!(
            "no pattern of {} send = {:?} matches it",
            self.permissions.who, self.permissions.send
        ))
    }

    /// Checks that the module may register `name`; the error names the rule that refused it.
    pub fn may_register(&self, name: &str) -> std::result::Result<(), String> {
        if matches_any(&self.permissions.register, name) {
            return Ok(());
        }
        Err(format!(
            "no pattern of {} register = {:?} matches it",
            self.permissions.who, self.permissions.register
        ))
    }

    /// The permissions behind the grant.
    pub fn permissions(&self) -> &Permissions {
        &self.permissions
    }
}

impl Grant {
    /// A grant as central's journal saved it (identity and permissions).
    pub(crate) fn restored(identity: String, permissions: Permissions) -> Grant {
        Grant {
            identity,
            permissions: Arc::new(permissions),
        }
    }
}

/// Control messages every connected module may send: the link's bookkeeping, not the task
/// trees.
fn always_allowed(name: &str) -> bool {
    ControlKind::from_name(name).is_some_and(|k| !k.acts_on_tasks())
}

fn matches_any(patterns: &[String], name: &str) -> bool {
    patterns.iter().any(|p| glob_match(p, name))
}

/// Glob match: `*` any run of characters (also none), `?` exactly one character.
pub fn glob_match(pattern: &str, text: &str) -> bool {
    let p: Vec<char> = pattern.chars().collect();
    let t: Vec<char> = text.chars().collect();
    let (mut pi, mut ti) = (0usize, 0usize);
    // Where the last `*` was and which text position it is trying to cover up to.
    let mut star: Option<(usize, usize)> = None;
    while ti < t.len() {
        match p.get(pi) {
            Some('*') => {
                star = Some((pi, ti));
                pi += 1;
            }
            Some(&c) if c == '?' || Some(&c) == t.get(ti) => {
                pi += 1;
                ti += 1;
            }
            _ => match star {
                Some((sp, st)) => {
                    pi = sp + 1;
                    ti = st + 1;
                    star = Some((sp, st + 1));
                }
                None => return false,
            },
        }
    }
    p[pi.min(p.len())..].iter().all(|&c| c == '*')
}

/// The hash a policy file stores for an identity's secret: hex SHA3-256 of
/// `tca-identity:<identity>:<secret>` (the identity salts it).
pub fn hash_secret(identity: &str, secret: &str) -> String {
    hex(&digest(identity, secret))
}

fn digest(identity: &str, secret: &str) -> [u8; 32] {
    let mut h = Sha3_256::new();
    h.update(b"tca-identity:");
    h.update(identity.as_bytes());
    h.update(b":");
    h.update(secret.as_bytes());
    h.finalize().into()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(text: &str) -> Option<[u8; 32]> {
    let text = text.trim();
    if text.len() != 64 || !text.is_ascii() {
        return None;
    }
    let mut out = [0u8; 32];
    for (i, o) in out.iter_mut().enumerate() {
        *o = u8::from_str_radix(text.get(2 * i..2 * i + 2)?, 16).ok()?;
    }
    Some(out)
}

/// Compares without stopping at the first difference.
fn same(a: &[u8; 32], b: &[u8; 32]) -> bool {
    a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

impl Policy {
    /// Reads a policy file. A relative `zenoh_users_file` is taken relative to the policy
    /// file's folder.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| PolicyError::Io {
            path: path.to_owned(),
            source,
        })?;
        let mut policy = Self::parse(path, &text)?;
        if let Some(dir) = path.parent() {
            let beside = |p: &mut PathBuf| {
                if p.is_relative() {
                    *p = dir.join(&*p);
                }
            };
            if let Some(users) = policy.zenoh_users_file.as_mut() {
                beside(users);
            }
            if let Some(tls) = policy.tls.as_mut() {
                beside(&mut tls.certificate);
                beside(&mut tls.private_key);
                beside(&mut tls.ca);
            }
        }
        Ok(policy)
    }

    /// Parses policy text; `path` only names it in errors.
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        let file: PolicyFile = toml::from_str(text).map_err(|e| PolicyError::Parse {
            path: path.to_owned(),
            reason: e.to_string(),
        })?;
        let invalid = |reason: String| PolicyError::Invalid {
            path: path.to_owned(),
            reason,
        };
        let check_patterns =
            |who: &str, key: &str, list: &[String]| match list.iter().find(|p| p.trim().is_empty())
            {
                Some(_) => Err(invalid(format!(
                    "{who} {key} has an empty pattern; remove it (use \"*\" to allow every name)"
                ))),
                None => Ok(()),
            };
        let mut identities: Vec<Identity> = Vec::new();
        for id in file.identity {
            if id.name.trim().is_empty() {
                return Err(invalid("an [[identity]] has an empty name".into()));
            }
            check_identity_name(&id.name)
                .map_err(|e| invalid(format!("[[identity]] name: {e}")))?;
            if identities.iter().any(|i| i.name == id.name) {
                return Err(invalid(format!(
                    "identity {:?} is given twice; merge the two entries",
                    id.name
                )));
            }
            let who = format!("identity {:?}", id.name);
            let secret_hash = match &id.secret_sha3 {
                Some(text) => match unhex(text) {
                    Some(hash) => Some(hash),
                    None => {
                        return Err(invalid(format!(
                            "{who}: secret_sha3 must be 64 hex digits (the output of \
                             `cargo run -p tca-central --example hash_secret -- {}`)",
                            id.name
                        )));
                    }
                },
                None => None,
            };
            let modules = id.modules.unwrap_or_else(|| vec![id.name.clone()]);
            check_patterns(&who, "modules", &modules)?;
            check_patterns(&who, "register", &id.register)?;
            check_patterns(&who, "send", &id.send)?;
            identities.push(Identity {
                name: id.name,
                secret_hash,
                permissions: Arc::new(Permissions {
                    who,
                    modules,
                    register: id.register,
                    send: id.send,
                }),
            });
        }
        let anonymous = match file.anonymous {
            Some(a) => {
                check_patterns("[anonymous]", "register", &a.register)?;
                check_patterns("[anonymous]", "send", &a.send)?;
                Some(Arc::new(Permissions {
                    who: "[anonymous]".into(),
                    modules: vec!["*".into()],
                    register: a.register,
                    send: a.send,
                }))
            }
            None => None,
        };
        let tls = file
            .transport
            .tls
            .map(|t| TlsFiles::new(t.certificate, t.private_key, t.ca));
        Ok(Policy {
            identities,
            anonymous,
            zenoh_users_file: file.transport.zenoh_users_file,
            tls,
        })
    }

    /// The zenoh user/password dictionary central's router requires, if any.
    pub fn zenoh_users_file(&self) -> Option<&Path> {
        self.zenoh_users_file.as_deref()
    }

    /// Central's TLS files (`[transport.tls]`), if any.
    pub fn tls(&self) -> Option<&TlsFiles> {
        self.tls.as_ref()
    }

    /// What central's zenoh router must do: the users file, TLS, and the policy's identities,
    /// each of which its access control confines to its own keys when the router can
    /// authenticate clients.
    pub fn router_security(&self) -> RouterSecurity {
        RouterSecurity {
            users_file: self.zenoh_users_file.clone(),
            tls: self.tls.clone(),
            identities: self.identities.iter().map(|i| i.name.clone()).collect(),
        }
    }

    /// Admits a module named `module` presenting `credentials`, or says why not. With
    /// `transport_identity` (the identity its zenoh user or certificate proved to the router)
    /// the module is that identity: credentials are then optional, and must name it when given.
    pub fn authenticate(
        &self,
        module: &str,
        credentials: Option<&Credentials>,
        transport_identity: Option<&str>,
    ) -> std::result::Result<Grant, String> {
        let identity = match (transport_identity, credentials) {
            (Some(t), Some(c)) if c.identity != t => {
                return Err(format!(
                    "this link was authenticated as identity {t:?} (its zenoh user or \
                     certificate) but its hello names identity {:?}; give the module the \
                     identity of its login or certificate, or no TCA_IDENTITY at all",
                    c.identity
                ));
            }
            (Some(t), c) => {
                let found = self.identities.iter().find(|i| i.name == t);
                let Some(identity) = found else {
                    return Err(format!(
                        "this link was authenticated as {t:?}, which is no identity of the \
                         policy; add an [[identity]] named {t:?}"
                    ));
                };
                if let (Some(c), Some(hash)) = (c, &identity.secret_hash)
                    && !same(hash, &digest(&c.identity, &c.secret))
                {
                    return Err(format!(
                        "identity {t:?}: the secret in the hello is wrong; check TCA_SECRET \
                         against central's policy file, or leave it out (the link's login or \
                         certificate already proves the identity)"
                    ));
                }
                identity
            }
            (None, None) => {
                return match &self.anonymous {
                    Some(p) => Ok(Grant {
                        identity: "anonymous".into(),
                        permissions: p.clone(),
                    }),
                    None => Err(
                        "central requires credentials (its policy has no [anonymous] \
                         section): give the module an identity and secret \
                         (ModuleBuilder::identity, or the TCA_IDENTITY and TCA_SECRET \
                         environment variables)"
                            .into(),
                    ),
                };
            }
            (None, Some(c)) => {
                let presented = digest(&c.identity, &c.secret);
                let found = self.identities.iter().find(|i| {
                    i.name == c.identity && i.secret_hash.is_some_and(|h| same(&h, &presented))
                });
                // One answer for every case, so a stranger cannot probe which identities
                // exist.
                found.ok_or_else(|| {
                    format!(
                        "identity {:?} is unknown or its secret is wrong; check \
                         TCA_IDENTITY/TCA_SECRET against central's policy file",
                        c.identity
                    )
                })?
            }
        };
        if !matches_any(&identity.permissions.modules, module) {
            return Err(format!(
                "identity {:?} may not connect as module {module:?}: no pattern of {} modules = \
                 {:?} matches it",
                identity.name, identity.permissions.who, identity.permissions.modules
            ));
        }
        Ok(Grant {
            identity: identity.name.clone(),
            permissions: identity.permissions.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn creds(identity: &str, secret: &str) -> Credentials {
        Credentials {
            identity: identity.into(),
            secret: secret.into(),
        }
    }

    fn policy() -> Policy {
        let text = format!(
            "[[identity]]\nname = \"gait\"\nsecret_sha3 = \"{}\"\nregister = [\"planStep\"]\n\
             send = [\"ltm*\", \"moveArm\", \"tca.kill\"]\n\
             [[identity]]\nname = \"tools\"\nsecret_sha3 = \"{}\"\nmodules = [\"ping-*\"]\n",
            hash_secret("gait", "s3cret"),
            hash_secret("tools", "t00ls")
        );
        Policy::parse(Path::new("p.toml"), &text).unwrap()
    }

    #[test]
    fn globs() {
        assert!(glob_match("map*", "map"));
        assert!(glob_match("map*", "mapRegion"));
        assert!(!glob_match("map*", "amap"));
        assert!(glob_match("move*", "moveArm"));
        assert!(glob_match("m?veArm", "moveArm"));
        assert!(glob_match("*", ""));
        assert!(glob_match("a*b*c", "axxbyyc"));
        assert!(!glob_match("a*b*c", "axxbyy"));
        assert!(glob_match("a**", "a"));
        assert!(!glob_match("", "a"));
        assert!(glob_match("tca.*", "tca.kill"));
    }

    #[test]
    fn right_secret_admits_and_rules_apply() {
        let p = policy();
        let g = p
            .authenticate("gait", Some(&creds("gait", "s3cret")), None)
            .unwrap();
        assert_eq!(g.identity, "gait");
        assert!(g.may_send("ltmFootfall").is_ok());
        assert!(g.may_send("moveArm").is_ok());
        assert!(g.may_send("tca.registry").is_ok());
        assert!(g.may_send("tca.kill").is_ok());
        let err = g.may_send("moveBase").unwrap_err();
        assert!(err.contains("identity \"gait\" send"), "{err}");
        assert!(g.may_send("tca.constrain").is_err());
        assert!(g.may_register("planStep").is_ok());
        let err = g.may_register("moveArm").unwrap_err();
        assert!(err.contains("register = [\"planStep\"]"), "{err}");
    }

    #[test]
    fn refusals() {
        let p = policy();
        let wrong = p
            .authenticate("gait", Some(&creds("gait", "guess")), None)
            .unwrap_err();
        assert!(wrong.contains("unknown or its secret is wrong"), "{wrong}");
        let unknown = p
            .authenticate("x", Some(&creds("x", "y")), None)
            .unwrap_err();
        assert!(unknown.contains("unknown"), "{unknown}");
        let none = p.authenticate("gait", None, None).unwrap_err();
        assert!(none.contains("requires credentials"), "{none}");
        let other = p
            .authenticate("ltm", Some(&creds("gait", "s3cret")), None)
            .unwrap_err();
        assert!(
            other.contains("may not connect as module \"ltm\""),
            "{other}"
        );
        assert!(
            p.authenticate("ping-1", Some(&creds("tools", "t00ls")), None)
                .is_ok()
        );
    }

    #[test]
    fn anonymous_section_admits_without_credentials() {
        let p = Policy::parse(
            Path::new("p.toml"),
            "[anonymous]\nsend = [\"q*\"]\n[transport]\nzenoh_users_file = \"u.txt\"\n",
        )
        .unwrap();
        let g = p.authenticate("anyone", None, None).unwrap();
        assert_eq!(g.identity, "anonymous");
        assert!(g.may_send("query1").is_ok());
        assert!(g.may_register("x").is_err());
        assert_eq!(p.zenoh_users_file(), Some(Path::new("u.txt")));
    }

    #[test]
    fn bad_files_are_explained() {
        let e = Policy::parse(
            Path::new("p.toml"),
            "[[identity]]\nname=\"a\"\nsecret_sha3=\"12\"\n",
        )
        .unwrap_err();
        assert!(e.to_string().contains("64 hex digits"), "{e}");
        let e = Policy::parse(Path::new("p.toml"), "[[identiti]]\n").unwrap_err();
        assert!(e.to_string().contains("policy.example.toml"), "{e}");
        let h = hash_secret("a", "b");
        let twice = format!(
            "[[identity]]\nname=\"a\"\nsecret_sha3=\"{h}\"\n[[identity]]\nname=\"a\"\nsecret_sha3=\"{h}\"\n"
        );
        let e = Policy::parse(Path::new("p.toml"), &twice).unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
        let empty = format!("[[identity]]\nname=\"a\"\nsecret_sha3=\"{h}\"\nsend=[\"\"]\n");
        assert!(Policy::parse(Path::new("p.toml"), &empty).is_err());
    }

    #[test]
    fn a_transport_identity_is_the_identity() {
        let mut p = policy();
        let text = "[[identity]]\nname = \"nav\"\nsend = [\"go\"]\n";
        let nav = Policy::parse(Path::new("p.toml"), text).unwrap();
        p.identities.extend(nav.identities);
        // No credentials: the login or certificate is the identity, also one without secret.
        let g = p.authenticate("gait", None, Some("gait")).unwrap();
        assert_eq!(g.identity, "gait");
        assert_eq!(
            p.authenticate("nav", None, Some("nav")).unwrap().identity,
            "nav"
        );
        // Credentials must name it, and a secret given must be right.
        assert!(
            p.authenticate("gait", Some(&creds("gait", "s3cret")), Some("gait"))
                .is_ok()
        );
        let e = p
            .authenticate("gait", Some(&creds("gait", "guess")), Some("gait"))
            .unwrap_err();
        assert!(e.contains("secret in the hello is wrong"), "{e}");
        let e = p
            .authenticate("gait", Some(&creds("tools", "t00ls")), Some("gait"))
            .unwrap_err();
        assert!(e.contains("authenticated as identity \"gait\""), "{e}");
        // Its module rule still applies; an identity without secret cannot log in by hello.
        assert!(p.authenticate("ltm", None, Some("gait")).is_err());
        let e = p
            .authenticate("nav", Some(&creds("nav", "")), None)
            .unwrap_err();
        assert!(e.contains("unknown or its secret is wrong"), "{e}");
        assert!(p.authenticate("x", None, Some("stranger")).is_err());
    }

    #[test]
    fn identity_names_must_fit_in_keys_and_tls_paths_are_beside_the_file() {
        let e = Policy::parse(Path::new("p.toml"), "[[identity]]\nname = \"a/b\"\n").unwrap_err();
        assert!(e.to_string().contains("ASCII letters"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("p.toml");
        std::fs::write(
            &file,
            "[transport.tls]\ncertificate = \"c.pem\"\nprivate_key = \"c.key\"\nca = \"/etc/ca.pem\"\n\
             [[identity]]\nname = \"gait\"\n",
        )
        .unwrap();
        let p = Policy::load(&file).unwrap();
        let tls = p.tls().unwrap();
        assert_eq!(tls.certificate, dir.path().join("c.pem"));
        assert_eq!(tls.ca, Path::new("/etc/ca.pem"));
        let security = p.router_security();
        assert!(security.authenticators().certificates);
        assert_eq!(security.identities, vec!["gait".to_owned()]);
    }

    #[test]
    fn hash_is_salted_by_identity() {
        assert_ne!(hash_secret("a", "x"), hash_secret("b", "x"));
        assert_eq!(hash_secret("a", "x").len(), 64);
        assert_eq!(unhex(&hash_secret("a", "x")), Some(digest("a", "x")));
    }
}
