//! Local endpoints (`local`, `local/NAME`) and where their sockets live.
//!
//! A local endpoint names a Unix-domain socket in a per-user runtime directory:
//! `$TCA_LOCAL_DIR` if set, else `$XDG_RUNTIME_DIR/tca`, else `/tmp/tca-<uid>`. The directory is
//! created with mode 0700 and must belong to this user and be closed to everyone else; the
//! socket is `<dir>/<NAME>.sock` (`default.sock` for plain `local`), mode 0600.

use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};

use crate::{LinkError, Result};

/// The protocol word of local endpoints.
pub const LOCAL_PROTOCOL: &str = "local";

/// The name of plain `local`.
pub const DEFAULT_LOCAL_NAME: &str = "default";

/// Longest NAME: the socket path must fit a Unix socket address (108 bytes on Linux).
const MAX_NAME: usize = 48;

/// A parsed local endpoint.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct LocalEndpoint {
    name: String,
}

impl LocalEndpoint {
    /// Parses `local` or `local/NAME` (NAME: letters, digits, `.`, `_`, `-`; at most 48).
    pub fn parse(endpoint: &str) -> Result<Self> {
        let rest = endpoint
            .strip_prefix(LOCAL_PROTOCOL)
            .filter(|r| r.is_empty() || r.starts_with('/'))
            .ok_or_else(|| {
                LinkError::Config(format!(
                    "endpoint {endpoint:?} is not a local endpoint; write local or local/NAME"
                ))
            })?;
        let name = rest.strip_prefix('/').unwrap_or(DEFAULT_LOCAL_NAME);
        let valid = !name.is_empty()
            && name.len() <= MAX_NAME
            && !name.starts_with('.')
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'));
        if !valid {
            return Err(LinkError::Config(format!(
                "local endpoint {endpoint:?}: NAME must be 1 to {MAX_NAME} letters, digits, \
                 '.', '_' or '-' (not starting with '.'), e.g. local/robot1"
            )));
        }
        Ok(LocalEndpoint {
            name: name.to_owned(),
        })
    }

    /// Whether `endpoint` is meant as a local one (`local` or `local/...`).
    pub fn is_local(endpoint: &str) -> bool {
        endpoint == LOCAL_PROTOCOL || endpoint.starts_with("local/")
    }

    /// The NAME (`default` for plain `local`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The socket's path in the runtime directory (the directory is not created).
    pub fn socket_path(&self) -> Result<PathBuf> {
        Ok(runtime_dir()?.join(format!("{}.sock", self.name)))
    }

    /// The socket's path, creating the runtime directory (0700) if needed and checking that it
    /// belongs to this user and is closed to others.
    pub fn prepare(&self) -> Result<PathBuf> {
        let dir = runtime_dir()?;
        ensure_private_dir(&dir)?;
        Ok(dir.join(format!("{}.sock", self.name)))
    }
}

impl std::fmt::Display for LocalEndpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.name == DEFAULT_LOCAL_NAME {
            f.write_str(LOCAL_PROTOCOL)
        } else {
            write!(f, "{LOCAL_PROTOCOL}/{}", self.name)
        }
    }
}

/// The user id this process runs as.
pub fn current_uid() -> Result<u32> {
    if let Ok(m) = std::fs::metadata("/proc/self") {
        return Ok(m.uid());
    }
    // Elsewhere: a file this process creates belongs to it.
    let probe = std::env::temp_dir().join(format!("tca-uid-probe-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .map_err(|e| LinkError::Config(format!("cannot find this process's user id: {e}")))?;
    let uid = std::fs::metadata(&probe).map(|m| m.uid());
    let _ = std::fs::remove_file(&probe);
    uid.map_err(|e| LinkError::Config(format!("cannot find this process's user id: {e}")))
}

/// The per-user directory of local sockets.
pub fn runtime_dir() -> Result<PathBuf> {
    if let Some(dir) = std::env::var_os("TCA_LOCAL_DIR").filter(|d| !d.is_empty()) {
        return Ok(PathBuf::from(dir));
    }
    if let Some(dir) = std::env::var_os("XDG_RUNTIME_DIR").filter(|d| !d.is_empty()) {
        let dir = PathBuf::from(dir);
        if dir.is_dir() {
            return Ok(dir.join("tca"));
        }
    }
    Ok(std::env::temp_dir().join(format!("tca-{}", current_uid()?)))
}

/// Creates `dir` with mode 0700 if missing; refuses one that another user owns or that others
/// may enter.
fn ensure_private_dir(dir: &Path) -> Result<()> {
    if !dir.exists() {
        std::fs::DirBuilder::new()
            .recursive(true)
            .mode(0o700)
            .create(dir)
            .map_err(|e| {
                LinkError::Config(format!(
                    "cannot create the local socket directory {}: {e}; set TCA_LOCAL_DIR to a \
                     directory of yours",
                    dir.display()
                ))
            })?;
        // The mode asked for is masked by the umask: set it exactly.
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o700)).map_err(|e| {
            LinkError::Config(format!("cannot make {} private: {e}", dir.display()))
        })?;
    }
    check_private_dir(dir)
}

/// Checks that `dir` is a directory of this user that nobody else may enter.
pub fn check_private_dir(dir: &Path) -> Result<()> {
    let meta = std::fs::symlink_metadata(dir).map_err(|e| {
        LinkError::Config(format!(
            "cannot read the local socket directory {}: {e}",
            dir.display()
        ))
    })?;
    let uid = current_uid()?;
    if !meta.is_dir() {
        return Err(LinkError::Config(format!(
            "the local socket directory {} is not a directory; remove it or set TCA_LOCAL_DIR",
            dir.display()
        )));
    }
    if meta.uid() != uid {
        return Err(LinkError::Config(format!(
            "the local socket directory {} belongs to user {}, not to this user ({uid}); \
             someone else may be posing as central: remove it or set TCA_LOCAL_DIR",
            dir.display(),
            meta.uid()
        )));
    }
    if meta.mode() & 0o077 != 0 {
        return Err(LinkError::Config(format!(
            "the local socket directory {} is open to other users (mode {:o}); \
             run `chmod 700 {}` or set TCA_LOCAL_DIR",
            dir.display(),
            meta.mode() & 0o777,
            dir.display()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_parse_with_a_default_name() {
        assert_eq!(LocalEndpoint::parse("local").unwrap().name(), "default");
        let e = LocalEndpoint::parse("local/robot-1.a").unwrap();
        assert_eq!(e.name(), "robot-1.a");
        assert_eq!(e.to_string(), "local/robot-1.a");
        assert_eq!(LocalEndpoint::parse("local").unwrap().to_string(), "local");
        assert!(LocalEndpoint::is_local("local") && LocalEndpoint::is_local("local/x"));
        assert!(!LocalEndpoint::is_local("localhost/x") && !LocalEndpoint::is_local("tcp/x"));
    }

    #[test]
    fn bad_names_are_refused_with_an_example() {
        for bad in [
            "local/",
            "local/a/b",
            "local/../x",
            "local/.x",
            "localx",
            "tcp/1:2",
        ] {
            let err = LocalEndpoint::parse(bad).unwrap_err().to_string();
            assert!(err.contains("local/"), "{bad}: {err}");
        }
        let long = format!("local/{}", "a".repeat(49));
        assert!(LocalEndpoint::parse(&long).is_err());
    }

    #[test]
    fn a_directory_open_to_others_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let open = dir.path().join("open");
        std::fs::create_dir(&open).unwrap();
        std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o755)).unwrap();
        let err = check_private_dir(&open).unwrap_err().to_string();
        assert!(
            err.contains("open to other users") && err.contains("chmod 700"),
            "{err}"
        );
        let fresh = dir.path().join("fresh/tca");
        ensure_private_dir(&fresh).unwrap();
        let mode = std::fs::metadata(&fresh).unwrap().mode() & 0o777;
        assert_eq!(mode, 0o700);
    }
}
