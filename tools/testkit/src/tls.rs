//! Certificates for tests of mutual TLS, made fresh by the test: a certificate authority,
//! central's certificate for `127.0.0.1` and `localhost`, and module certificates whose
//! common names are identities.

use std::path::{Path, PathBuf};

use rcgen::{
    BasicConstraints, CertificateParams, DnType, ExtendedKeyUsagePurpose, IsCa, Issuer, KeyPair,
    KeyUsagePurpose,
};
use tca_link::zenoh::TlsFiles;

/// A certificate authority that writes certificates and keys as PEM files into a folder.
pub struct TestCa {
    dir: PathBuf,
    issuer: Issuer<'static, KeyPair>,
    ca: PathBuf,
}

impl TestCa {
    /// A new authority named `name`, its certificate written to `dir/<name>-ca.pem`.
    pub fn new(dir: &Path, name: &str) -> Self {
        let mut params = CertificateParams::new(Vec::<String>::new()).expect("no names");
        params.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
        params
            .distinguished_name
            .push(DnType::CommonName, format!("{name} test CA"));
        params.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign];
        let key = KeyPair::generate().expect("a key pair");
        let cert = params.self_signed(&key).expect("a self-signed CA");
        let ca = dir.join(format!("{name}-ca.pem"));
        std::fs::write(&ca, cert.pem()).expect("write the CA certificate");
        TestCa {
            dir: dir.to_owned(),
            issuer: Issuer::new(params, key),
            ca,
        }
    }

    /// The authority's certificate file.
    pub fn ca(&self) -> &Path {
        &self.ca
    }

    /// Central's certificate and key, for `127.0.0.1` and `localhost` (common name
    /// `central`), with this authority's certificate to check modules against.
    pub fn central(&self) -> TlsFiles {
        self.issue(
            "central",
            vec!["127.0.0.1".into(), "localhost".into()],
            ExtendedKeyUsagePurpose::ServerAuth,
        )
    }

    /// A module's certificate and key with common name `identity`, with this authority's
    /// certificate to check central against.
    pub fn module(&self, identity: &str) -> TlsFiles {
        self.issue(identity, Vec::new(), ExtendedKeyUsagePurpose::ClientAuth)
    }

    fn issue(&self, cn: &str, names: Vec<String>, usage: ExtendedKeyUsagePurpose) -> TlsFiles {
        let mut params = CertificateParams::new(names).expect("valid names");
        params.distinguished_name.push(DnType::CommonName, cn);
        params.use_authority_key_identifier_extension = true;
        params.key_usages = vec![
            KeyUsagePurpose::DigitalSignature,
            KeyUsagePurpose::KeyEncipherment,
        ];
        params.extended_key_usages = vec![usage];
        let key = KeyPair::generate().expect("a key pair");
        let cert = params
            .signed_by(&key, &self.issuer)
            .expect("a signed certificate");
        let certificate = self.dir.join(format!("{cn}.pem"));
        let private_key = self.dir.join(format!("{cn}.key"));
        std::fs::write(&certificate, cert.pem()).expect("write a certificate");
        std::fs::write(&private_key, key.serialize_pem()).expect("write a key");
        TlsFiles::new(certificate, private_key, &self.ca)
    }
}
