//! `orchestrator clean`: removes everything dead runs left behind, never touching a live run.

use crate::registry;
use swarm::cleanup;

/// Shared-memory names that look like a run of ours: `sw` + 10 hex digits + `_`.
fn run_prefix_of(name: &str) -> Option<&str> {
    let p = name.get(..13)?;
    let ok =
        p.starts_with("sw") && p.ends_with('_') && p[2..12].bytes().all(|b| b.is_ascii_hexdigit());
    ok.then_some(p)
}

pub struct CleanReport {
    pub runs: usize,
    pub shm_files: usize,
    pub processes: usize,
}

/// Cleans dead runs. A run is dead when its orchestrator process is gone.
pub fn clean_dead_runs() -> CleanReport {
    let mut report = CleanReport {
        runs: 0,
        shm_files: 0,
        processes: 0,
    };
    let entries = registry::list();
    let mut live_prefixes = Vec::new();
    for e in &entries {
        if registry::pid_alive(e.orchestrator_pid) {
            live_prefixes.push(e.prefix.clone());
            continue;
        }
        for &pid in std::iter::once(&e.world_pid).chain(e.agent_pids.iter()) {
            if is_our_process(pid, &e.prefix) {
                // SAFETY: plain kill of a process of the dead run.
                unsafe {
                    libc::kill(pid as i32, libc::SIGKILL);
                }
                report.processes += 1;
            }
        }
        report.shm_files += cleanup::remove_run(&e.prefix);
        registry::remove(&e.run_id);
        report.runs += 1;
    }
    // Orphans: files of runs whose registry entry is gone too (never those of a live run).
    let mut orphans: Vec<String> = cleanup::shm_files("sw")
        .iter()
        .filter_map(|n| run_prefix_of(n).map(str::to_string))
        .filter(|p| !live_prefixes.contains(p))
        .collect();
    orphans.dedup();
    for p in orphans {
        // A run being set up registers before it creates files, so an unregistered prefix
        // belongs to no live run.
        report.shm_files += cleanup::remove_run(&p);
        report.runs += 1;
    }
    report
}

/// Whether pid is a process of the run with this prefix (its command line names the prefix).
fn is_our_process(pid: u32, prefix: &str) -> bool {
    std::fs::read(format!("/proc/{pid}/cmdline"))
        .map(|c| String::from_utf8_lossy(&c).contains(prefix))
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recognises_run_prefixes_only() {
        assert_eq!(run_prefix_of("sw0123456789_tick"), Some("sw0123456789_"));
        assert_eq!(run_prefix_of("swag_something_long"), None);
        assert_eq!(run_prefix_of("iox2_abc"), None);
    }
}
