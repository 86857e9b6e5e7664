//! Mutual TLS on zenoh links: the certificate, key and certificate authority each end uses.
//!
//! Central listens on `tls/HOST:PORT` with its certificate (which must name the host modules
//! connect to) and requires every module to present a certificate signed by the CA it is
//! given; a module connects to `tls/HOST:PORT` with its own certificate and checks central's
//! against the same CA. The common name of a module's certificate is its identity.

use std::path::{Path, PathBuf};

use crate::{LinkError, Result};

/// Environment variable naming a module's certificate (PEM).
pub const ENV_CERTIFICATE: &str = "TCA_ZENOH_TLS_CERT";
/// Environment variable naming a module's private key (PEM).
pub const ENV_PRIVATE_KEY: &str = "TCA_ZENOH_TLS_KEY";
/// Environment variable naming the certificate authority that signed central's certificate
/// (PEM).
pub const ENV_CA: &str = "TCA_ZENOH_TLS_CA";

/// The files of one end of a mutual-TLS zenoh link, all PEM.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TlsFiles {
    /// This end's certificate (a chain, leaf first).
    pub certificate: PathBuf,
    /// Its private key.
    pub private_key: PathBuf,
    /// The certificate authority the other end's certificate must be signed by.
    pub ca: PathBuf,
}

impl TlsFiles {
    /// The three files.
    pub fn new(
        certificate: impl Into<PathBuf>,
        private_key: impl Into<PathBuf>,
        ca: impl Into<PathBuf>,
    ) -> Self {
        TlsFiles {
            certificate: certificate.into(),
            private_key: private_key.into(),
            ca: ca.into(),
        }
    }

    /// The files named by `TCA_ZENOH_TLS_CERT`, `TCA_ZENOH_TLS_KEY` and `TCA_ZENOH_TLS_CA`:
    /// none when none is set, an error naming the missing ones when only some are.
    pub fn from_env() -> Result<Option<Self>> {
        let vars = [ENV_CERTIFICATE, ENV_PRIVATE_KEY, ENV_CA].map(std::env::var_os);
        let missing: Vec<&str> = [ENV_CERTIFICATE, ENV_PRIVATE_KEY, ENV_CA]
            .iter()
            .zip(&vars)
            .filter(|(_, v)| v.is_none())
            .map(|(name, _)| *name)
            .collect();
        match missing.len() {
            3 => Ok(None),
            0 => {
                let [c, k, a] = vars.map(|v| PathBuf::from(v.unwrap_or_default()));
                Ok(Some(TlsFiles::new(c, k, a)))
            }
            _ => Err(LinkError::Config(format!(
                "TLS needs {ENV_CERTIFICATE}, {ENV_PRIVATE_KEY} and {ENV_CA}; {} not set",
                missing.join(" and ")
            ))),
        }
    }

    /// Checks that the three files can be read and hold PEM; the error names the file.
    pub fn check(&self) -> Result<()> {
        for (what, path) in [
            ("certificate", &self.certificate),
            ("private key", &self.private_key),
            ("CA certificate", &self.ca),
        ] {
            let text = read(what, path)?;
            if !text.contains("-----BEGIN ") {
                return Err(LinkError::Config(format!(
                    "TLS {what} {} is not PEM (no -----BEGIN line)",
                    path.display()
                )));
            }
        }
        Ok(())
    }

    /// The common name of the certificate (its first one, the leaf's): the identity it
    /// carries.
    pub fn common_name(&self) -> Result<String> {
        let text = read("certificate", &self.certificate)?;
        let bad = |why: String| {
            LinkError::Config(format!(
                "TLS certificate {}: {why}",
                self.certificate.display()
            ))
        };
        let (_, pem) = x509_parser::pem::parse_x509_pem(text.as_bytes())
            .map_err(|e| bad(format!("not a PEM certificate ({e})")))?;
        let cert = pem
            .parse_x509()
            .map_err(|e| bad(format!("not an X.509 certificate ({e})")))?;
        let cn = cert
            .subject()
            .iter_common_name()
            .next()
            .ok_or_else(|| bad("its subject has no common name (CN)".into()))?;
        cn.as_str()
            .map(str::to_owned)
            .map_err(|e| bad(format!("its common name is not text ({e})")))
    }
}

fn read(what: &str, path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| {
        LinkError::Config(format!(
            "cannot read the TLS {what} {}: {e}",
            path.display()
        ))
    })
}

/// Whether `endpoint` is a TLS one (`tls/HOST:PORT`).
pub fn is_tls(endpoint: &str) -> bool {
    endpoint.starts_with("tls/")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unreadable_or_non_pem_files_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let text = dir.path().join("x.txt");
        std::fs::write(&text, "hello").unwrap();
        let files = TlsFiles::new(&text, &text, dir.path().join("missing.pem"));
        let err = files.check().unwrap_err().to_string();
        assert!(err.contains("not PEM"), "{err}");
        let files = TlsFiles::new(dir.path().join("missing.pem"), &text, &text);
        let err = files.check().unwrap_err().to_string();
        assert!(err.contains("cannot read the TLS certificate"), "{err}");
        let err = TlsFiles::new(&text, &text, &text)
            .common_name()
            .unwrap_err()
            .to_string();
        assert!(err.contains("not a PEM certificate"), "{err}");
        assert!(is_tls("tls/127.0.0.1:7448"));
        assert!(!is_tls("tcp/127.0.0.1:7448"));
    }
}
