//! Modules that `tca up` started end when `tca up` itself is killed before it can stop them,
//! instead of waiting for ever for a central that will not come back.

use std::time::Duration;

use crate::common::*;

/// Process ids whose command line holds `needle`.
fn processes_with(needle: &str) -> Vec<u32> {
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    dir.filter_map(|e| {
        let e = e.ok()?;
        let pid: u32 = e.file_name().to_str()?.parse().ok()?;
        let cmdline = std::fs::read(e.path().join("cmdline")).ok()?;
        let cmdline = String::from_utf8_lossy(&cmdline).replace('\0', " ");
        cmdline.contains(needle).then_some(pid)
    })
    .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn modules_end_when_their_launcher_is_killed() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let endpoint = free_endpoint();
    let file = dir.path().join("up.toml");
    std::fs::write(
        &file,
        format!("[central]\nlisten = [\"{endpoint}\"]\n\n[[module]]\nname = \"echo\"\nargs = []\n"),
    )
    .expect("the launch file written");
    let mut up = spawn_tca(&["up", file.to_str().expect("a UTF-8 path")]);
    wait_for_modules(&endpoint, &["echo"]).await;
    // The module connects at the launcher's own local endpoint, named after its process.
    let needle = format!("module echo --connect local/up-{} ", up.0.id());
    let modules = processes_with(&needle);
    assert_eq!(modules.len(), 1, "one echo module started by tca up");

    up.kill();
    within("the module ends with its launcher", async {
        while !processes_with(&needle).is_empty() {
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    })
    .await;
}
