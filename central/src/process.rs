//! Whether a module's process is known to be gone, from what its hello says.
//!
//! A module restarted right after its process was killed may say hello before central has
//! noticed the old connection drop (a zenoh liveliness token can take a moment to lapse).
//! When the old module ran on this machine and its process no longer exists, the new hello
//! takes its place instead of being refused as a duplicate.

pub use tca_messages::control::this_host;

/// True only when `host` is this machine and process `pid` certainly does not exist here
/// (Linux: no `/proc/<pid>`). Anything uncertain (another host, no `/proc`, pid 0) is false:
/// the module is then treated as alive.
pub fn is_gone(host: &str, pid: u32) -> bool {
    if pid == 0 || host != this_host() {
        return false;
    }
    let proc_dir = std::path::Path::new("/proc");
    if !proc_dir.join("self").exists() {
        return false;
    }
    !proc_dir.join(pid.to_string()).exists()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_is_alive_and_other_hosts_are_never_gone() {
        assert!(!is_gone(&this_host(), std::process::id()));
        assert!(!is_gone("some-other-host.invalid", u32::MAX - 1));
        assert!(!is_gone(&this_host(), 0));
    }

    #[test]
    fn a_finished_process_is_gone() {
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        assert!(is_gone(&this_host(), pid));
    }
}
