//! Helpers for the end-to-end tests: find the built binaries, run them, check that a run left
//! nothing behind (no process, nothing in /dev/shm).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Mutex, MutexGuard};

static SERIAL: Mutex<()> = Mutex::new(());

/// Tests of one binary run one at a time: they share /dev/shm and 2 cores.
pub fn serial() -> MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// target/<profile>/ of the binaries (the test executable lives in target/<profile>/deps/).
pub fn bin_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test exe");
    exe.parent()
        .and_then(Path::parent)
        .expect("target dir")
        .to_path_buf()
}

pub fn orchestrator() -> PathBuf {
    let p = bin_dir().join("orchestrator");
    assert!(
        p.exists() && bin_dir().join("world").exists() && bin_dir().join("agent").exists(),
        "build the binaries first: cargo build --release (looked in {})",
        bin_dir().display()
    );
    p
}

pub fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("swarm-e2e-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Runs `orchestrator up` with the given flags (quiet) and waits.
pub fn up(args: &[&str], out: &Path) -> Output {
    Command::new(orchestrator())
        .arg("up")
        .arg("--quiet")
        .arg("--out")
        .arg(out)
        .args(args)
        .output()
        .expect("run orchestrator")
}

/// Every entry of /dev/shm that belongs to a run of this runtime (prefix `sw`).
pub fn run_shm_entries() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir("/dev/shm")
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.retain(|n| n.starts_with("sw"));
    v.sort();
    v
}

/// Whether any process's command line mentions `needle`.
pub fn processes_mentioning(needle: &str) -> Vec<u32> {
    let mut v = Vec::new();
    for e in std::fs::read_dir("/proc").into_iter().flatten().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        if let Ok(c) = std::fs::read(format!("/proc/{pid}/cmdline")) {
            // Zombies have an empty command line; they are not running.
            if String::from_utf8_lossy(&c).contains(needle) {
                v.push(pid);
            }
        }
    }
    v
}

pub fn summary(out: &Path) -> serde_json::Value {
    let s = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&s).expect("summary is JSON")
}

/// Asserts the run with this run id left no process and nothing in /dev/shm.
pub fn assert_left_nothing(out: &Path) {
    let run_id = summary(out)["run_id"].as_str().expect("run_id").to_string();
    let prefix = swarm::transport::prefix_for(&run_id);
    let shm: Vec<String> = run_shm_entries()
        .into_iter()
        .filter(|n| n.starts_with(&prefix))
        .collect();
    assert!(shm.is_empty(), "run {run_id} left in /dev/shm: {shm:?}");
    let procs = processes_mentioning(&prefix);
    assert!(procs.is_empty(), "run {run_id} left processes: {procs:?}");
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
