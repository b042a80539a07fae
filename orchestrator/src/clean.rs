//! `orchestrator clean`: removes everything dead runs left behind, never touching a live run.

use crate::registry::{self, RegistryError};
use swarm::cleanup;

/// Shared-memory names that look like a run of ours: `sw` + 10 hex digits + `_`.
fn run_prefix_of(name: &str) -> Option<&str> {
    let p = name.get(..13)?;
    registry::is_prefix_shape(p).then_some(p)
}

pub struct CleanReport {
    pub runs: usize,
    pub shm_files: usize,
    pub processes: usize,
    /// Registry files that were not valid entries of this user's, left as they are.
    pub ignored: Vec<String>,
}

/// Cleans dead runs. A run is dead when its orchestrator process is gone (the recorded pid
/// no longer runs this build's orchestrator started at the recorded time). Only the run's
/// own processes are killed (recorded pid, this project's binary, recorded start time) and
/// only its own files removed (entries whose run id and prefix have the project's forms).
/// Refuses, touching nothing, when the registry folder is not this user's private folder.
pub fn clean_dead_runs() -> Result<CleanReport, RegistryError> {
    let (entries, ignored) = registry::scan()?;
    let mut report = CleanReport {
        runs: 0,
        shm_files: 0,
        processes: 0,
        ignored,
    };
    let mut live_prefixes = Vec::new();
    for e in &entries {
        if e.orchestrator_is_live() {
            live_prefixes.push(e.prefix.clone());
            continue;
        }
        for pid in e.live_children() {
            // SAFETY: plain kill of a verified process of the dead run.
            unsafe {
                libc::kill(pid as i32, libc::SIGKILL);
            }
            report.processes += 1;
        }
        report.shm_files += cleanup::remove_run(&e.prefix);
        registry::remove(&e.run_id);
        report.runs += 1;
    }
    // Orphans: files of runs whose registry entry is gone too. Benchmarks, tests and
    // in-process sweeps make iceoryx2 services without a registry entry, so a missing entry
    // alone does not make a prefix dead: it is an orphan only when no live process maps or
    // holds any of its files and none of them changed in the last ORPHAN_GRACE (a run that is
    // creating its first files has not mapped them yet). Files of another user's are never
    // ours to remove.
    let mut orphans: Vec<String> = cleanup::shm_files("sw")
        .iter()
        .filter_map(|n| run_prefix_of(n).map(str::to_string))
        .filter(|p| !live_prefixes.contains(p))
        .collect();
    orphans.dedup();
    orphans.retain(|p| all_mine(p));
    if !orphans.is_empty() {
        // Read /proc only when there is a candidate: `up` runs this on every start.
        let in_use = prefixes_in_use();
        orphans.retain(|p| !in_use.contains(p));
    }
    for p in orphans {
        if touched_recently(&p) {
            continue;
        }
        report.shm_files += cleanup::remove_run(&p);
        report.runs += 1;
    }
    Ok(report)
}

/// Whether every /dev/shm file of the prefix belongs to this user.
fn all_mine(prefix: &str) -> bool {
    use std::os::unix::fs::MetadataExt;
    // SAFETY: geteuid cannot fail.
    let me = unsafe { libc::geteuid() };
    cleanup::shm_files(prefix).iter().all(|f| {
        std::fs::symlink_metadata(std::path::Path::new("/dev/shm").join(f))
            .is_ok_and(|m| m.uid() == me)
    })
}

/// How recently a file of an unregistered prefix may have changed for the prefix still to
/// count as possibly being set up (and so left alone).
const ORPHAN_GRACE: std::time::Duration = std::time::Duration::from_secs(10);

/// Run prefixes of the /dev/shm files that some live process has mapped (/proc/PID/maps) or
/// open (/proc/PID/fd). Processes whose /proc entries cannot be read are skipped: their files
/// are not ours to remove either.
fn prefixes_in_use() -> std::collections::BTreeSet<String> {
    let mut used = std::collections::BTreeSet::new();
    let mut note = |path: &str| {
        if let Some(name) = path.strip_prefix("/dev/shm/") {
            if let Some(p) = run_prefix_of(name) {
                used.insert(p.to_string());
            }
        }
    };
    let Ok(procs) = std::fs::read_dir("/proc") else {
        return used;
    };
    for e in procs.flatten() {
        let name = e.file_name();
        if !name.to_string_lossy().bytes().all(|b| b.is_ascii_digit()) {
            continue;
        }
        let dir = e.path();
        if let Ok(maps) = std::fs::read_to_string(dir.join("maps")) {
            for line in maps.lines() {
                if let Some(i) = line.find("/dev/shm/") {
                    note(line[i..].trim_end_matches(" (deleted)"));
                }
            }
        }
        for fd in std::fs::read_dir(dir.join("fd"))
            .into_iter()
            .flatten()
            .flatten()
        {
            if let Ok(target) = std::fs::read_link(fd.path()) {
                note(&target.to_string_lossy());
            }
        }
    }
    used
}

/// Whether any /dev/shm file of the prefix changed within ORPHAN_GRACE.
fn touched_recently(prefix: &str) -> bool {
    cleanup::shm_files(prefix).iter().any(|f| {
        std::fs::metadata(std::path::Path::new("/dev/shm").join(f))
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_none_or(|age| age < ORPHAN_GRACE)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An unregistered prefix whose file a live process maps survives a clean; the same
    /// prefix, unmapped and older than the grace, is removed. Judges only its own files.
    #[test]
    fn clean_spares_unregistered_files_in_use_and_removes_old_unused_ones() {
        use std::os::unix::io::AsRawFd;
        let id = crate::runid::new_run_id();
        let prefix = swarm::transport::prefix_for(&format!("clean-test-{id}"));
        let path = std::path::Path::new("/dev/shm").join(format!("{prefix}probe"));
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)
            .unwrap();
        f.set_len(4096).unwrap();
        let old = std::time::SystemTime::now() - 2 * ORPHAN_GRACE;
        f.set_modified(old).unwrap();
        // SAFETY: a shared read mapping of a file this test owns, unmapped below.
        let map = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                4096,
                libc::PROT_READ,
                libc::MAP_SHARED,
                f.as_raw_fd(),
                0,
            )
        };
        assert_ne!(map, libc::MAP_FAILED);
        drop(f);
        assert!(prefixes_in_use().contains(&prefix));
        clean_dead_runs().unwrap();
        assert!(
            path.exists(),
            "clean removed a mapped file of an unregistered run"
        );
        // SAFETY: the mapping made above.
        unsafe {
            libc::munmap(map, 4096);
        }
        assert!(!prefixes_in_use().contains(&prefix));
        clean_dead_runs().unwrap();
        let gone = !path.exists();
        let _ = std::fs::remove_file(&path);
        assert!(
            gone,
            "clean left an old, unused file of an unregistered run"
        );
    }

    #[test]
    fn recognises_run_prefixes_only() {
        assert_eq!(run_prefix_of("sw0123456789_tick"), Some("sw0123456789_"));
        assert_eq!(run_prefix_of("swag_something_long"), None);
        assert_eq!(run_prefix_of("iox2_abc"), None);
    }
}
