//! The registry of runs on this machine, so that another terminal (`orchestrator clean`, and
//! later `status` / `kill`) finds them: one JSON file per run.

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

pub const REGISTRY_DIR: &str = "/tmp/swarm-runtime/runs";

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunEntry {
    pub run_id: String,
    pub prefix: String,
    pub orchestrator_pid: u32,
    pub world_pid: u32,
    /// Current agent process of each robot (index = robot id).
    pub agent_pids: Vec<u32>,
    pub run_dir: String,
    /// Progress, refreshed by the run's orchestrator a few times a second.
    #[serde(default)]
    pub tick: u64,
    #[serde(default)]
    pub alive: u32,
    #[serde(default)]
    pub dead: u32,
    #[serde(default)]
    pub restarted: u32,
}

fn path(run_id: &str) -> PathBuf {
    PathBuf::from(REGISTRY_DIR).join(format!("{run_id}.json"))
}

pub fn write(e: &RunEntry) -> std::io::Result<()> {
    std::fs::create_dir_all(REGISTRY_DIR)?;
    let tmp = path(&format!(".{}", e.run_id));
    std::fs::write(
        &tmp,
        serde_json::to_string_pretty(e).map_err(std::io::Error::other)?,
    )?;
    std::fs::rename(tmp, path(&e.run_id))
}

pub fn remove(run_id: &str) {
    let _ = std::fs::remove_file(path(run_id));
}

pub fn list() -> Vec<RunEntry> {
    let mut v: Vec<RunEntry> = std::fs::read_dir(REGISTRY_DIR)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().ends_with(".json"))
                .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
                .filter_map(|e| std::fs::read_to_string(e.path()).ok())
                .filter_map(|s| serde_json::from_str(&s).ok())
                .collect()
        })
        .unwrap_or_default();
    v.sort_by(|a, b| a.run_id.cmp(&b.run_id));
    v
}

pub fn pid_alive(pid: u32) -> bool {
    // SAFETY: signal 0 only checks for existence.
    pid != 0 && unsafe { libc::kill(pid as i32, 0) } == 0
}
