//! Prints the `secret_sha3` line of a policy file for an identity, reading the secret from
//! standard input (so it does not land in the shell history):
//!
//! ```text
//! printf '%s' "$SECRET" | cargo run -p tca-central --example hash_secret -- gait
//! ```

use std::io::Read;
use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(identity) = std::env::args().nth(1) else {
        eprintln!("usage: hash_secret IDENTITY < secret");
        return ExitCode::FAILURE;
    };
    let mut secret = String::new();
    if let Err(e) = std::io::stdin().read_to_string(&mut secret) {
        eprintln!("cannot read the secret from standard input: {e}");
        return ExitCode::FAILURE;
    }
    let secret = secret.trim_end_matches(['\n', '\r']);
    if secret.is_empty() {
        eprintln!("the secret on standard input is empty");
        return ExitCode::FAILURE;
    }
    println!(
        "secret_sha3 = \"{}\"",
        tca_central::policy::hash_secret(&identity, secret)
    );
    ExitCode::SUCCESS
}
