//! Who may connect to central's local socket: decided by the peer's user id, which the kernel
//! reports for a Unix socket (`SO_PEERCRED`) and the peer cannot forge.

use crate::Result;
use crate::local::endpoint::current_uid;

/// The user ids admitted on central's local socket.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PeerPolicy {
    uids: Vec<u32>,
}

impl PeerPolicy {
    /// Only processes of the user central runs as.
    pub fn same_user() -> Result<Self> {
        Self::same_user_and([])
    }

    /// Processes of the user central runs as, and of the users `extra`.
    pub fn same_user_and(extra: impl IntoIterator<Item = u32>) -> Result<Self> {
        let mut uids = vec![current_uid()?];
        uids.extend(extra);
        uids.sort_unstable();
        uids.dedup();
        Ok(PeerPolicy { uids })
    }

    /// Exactly the users `uids` (not necessarily central's own).
    pub fn only(uids: impl IntoIterator<Item = u32>) -> Self {
        let mut uids: Vec<u32> = uids.into_iter().collect();
        uids.sort_unstable();
        uids.dedup();
        PeerPolicy { uids }
    }

    /// The admitted user ids.
    pub fn uids(&self) -> &[u32] {
        &self.uids
    }

    /// Whether a peer running as `uid` (and process `pid`, when known) may connect; the
    /// refusal says why and what to do.
    pub fn admit(&self, uid: u32, pid: Option<i32>) -> Result<(), String> {
        if self.uids.contains(&uid) {
            return Ok(());
        }
        let pid = pid.map(|p| format!(" (process {p})")).unwrap_or_default();
        Err(format!(
            "user {uid}{pid} may not connect to this central's local socket; it admits users \
             {:?}: run the module as one of them, or start central with --local-allow-uid {uid}",
            self.uids
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_listed_users_are_admitted() {
        let me = current_uid().unwrap();
        let p = PeerPolicy::same_user().unwrap();
        assert!(p.admit(me, None).is_ok());
        let other = me.wrapping_add(4242);
        let err = p.admit(other, Some(77)).unwrap_err();
        assert!(err.contains(&format!("user {other} (process 77)")), "{err}");
        assert!(err.contains("--local-allow-uid"), "{err}");
        let p = PeerPolicy::same_user_and([other, other]).unwrap();
        assert!(p.admit(other, None).is_ok() && p.uids().len() == 2);
        assert!(PeerPolicy::only([other]).admit(me, None).is_err());
    }
}
