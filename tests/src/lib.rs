//! Helpers for the end-to-end tests: find the built binaries, run them, check that a run left
//! nothing behind (no process, nothing in /dev/shm).

pub mod fuzz;
pub mod fuzz_mutations;
pub mod programs;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

static SERIAL: Mutex<()> = Mutex::new(());

/// Orchestrators started in the background by the test that holds [`Serial`].
static SPAWNED: Mutex<Vec<u32>> = Mutex::new(Vec::new());

/// Held by a test for its whole length: tests of one binary run one at a time (they share
/// /dev/shm and 2 cores). If the test fails, dropping it stops every orchestrator the test
/// started in the background with Ctrl-C (SIGINT, the orchestrator's clean shutdown), so a
/// failed test leaves no run behind to disturb the next one.
pub struct Serial {
    _guard: MutexGuard<'static, ()>,
}

pub fn serial() -> Serial {
    let guard = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    SPAWNED.lock().unwrap_or_else(|e| e.into_inner()).clear();
    Serial { _guard: guard }
}

impl Drop for Serial {
    fn drop(&mut self) {
        let pids = std::mem::take(&mut *SPAWNED.lock().unwrap_or_else(|e| e.into_inner()));
        for pid in pids {
            if !pid_alive(pid as i32) {
                continue;
            }
            // SAFETY: signals to an orchestrator this test spawned and has not reaped.
            unsafe { libc::kill(pid as i32, libc::SIGINT) };
            let t = Instant::now();
            while pid_alive(pid as i32) && t.elapsed() < Duration::from_secs(15) {
                std::thread::sleep(Duration::from_millis(20));
            }
            if pid_alive(pid as i32) {
                // SAFETY: as above.
                unsafe { libc::kill(pid as i32, libc::SIGKILL) };
            }
        }
    }
}

/// Whether `pid` is a live process (a zombie still answers kill(0): look at its state).
pub fn pid_alive(pid: i32) -> bool {
    let st = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    !st.is_empty() && !st.contains(") Z ")
}

/// Starts `orchestrator up --quiet --out OUT ARGS` in the background; stopped with Ctrl-C if
/// the test fails before it ends.
pub fn spawn_up(args: &[&str], out: &Path) -> Child {
    spawn_up_as(args, out, None)
}

/// [`spawn_up`] with the run id fixed (`SWARM_RUN_ID`).
pub fn spawn_up_as(args: &[&str], out: &Path, run_id: Option<&str>) -> Child {
    let mut cmd = Command::new(orchestrator());
    cmd.arg("up")
        .arg("--quiet")
        .arg("--out")
        .arg(out)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    if let Some(id) = run_id {
        cmd.env("SWARM_RUN_ID", id);
    }
    let c = cmd.spawn().expect("spawn orchestrator");
    SPAWNED
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(c.id());
    c
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

/// configs/roam.toml: roaming only, no targets, so a run lasts its --max-ticks (the search
/// scenario, the default, ends when every target is found).
pub fn roam() -> &'static str {
    static P: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    P.get_or_init(|| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../configs/roam.toml")
            .display()
            .to_string()
    })
}

/// Runs `orchestrator up` with the given flags (quiet) and waits.
pub fn up(args: &[&str], out: &Path) -> Output {
    up_as(args, out, None)
}

/// [`up`] with the run id fixed (`SWARM_RUN_ID`), so the test knows the run's shared-memory
/// prefix (`swarm::transport::prefix_for(id)`) even when the run never starts.
pub fn up_as(args: &[&str], out: &Path, run_id: Option<&str>) -> Output {
    let mut c = Command::new(orchestrator());
    c.arg("up").arg("--quiet").arg("--out").arg(out).args(args);
    if let Some(id) = run_id {
        c.env("SWARM_RUN_ID", id);
    }
    c.output().expect("run orchestrator")
}

/// A run id of this test process's own, for [`up_as`].
pub fn own_run_id(tag: &str) -> String {
    format!("e2e-{}-{tag}", std::process::id())
}

/// This run's entries in /dev/shm (those under its prefix).
pub fn shm_of_run(run_id: &str) -> Vec<String> {
    let prefix = swarm::transport::prefix_for(run_id);
    run_shm_entries()
        .into_iter()
        .filter(|n| n.starts_with(&prefix))
        .collect()
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

/// The pid of run `id`'s world process (its `world` binary among the processes that name
/// the run's prefix).
pub fn world_pid_of(id: &str) -> i32 {
    processes_mentioning(&swarm::transport::prefix_for(id))
        .into_iter()
        .find(|p| {
            std::fs::read_link(format!("/proc/{p}/exe"))
                .is_ok_and(|e| e.file_name().is_some_and(|n| n == "world"))
        })
        .expect("world process") as i32
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

/// The run registry's folder as the orchestrator finds it in this environment:
/// `$XDG_RUNTIME_DIR/swarm-runtime-<uid>`, or `/tmp/swarm-runtime-<uid>`.
pub fn registry_dir() -> PathBuf {
    let base = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|p| p.is_absolute())
        .unwrap_or_else(|| PathBuf::from("/tmp"));
    // SAFETY: geteuid cannot fail.
    base.join(format!("swarm-runtime-{}", unsafe { libc::geteuid() }))
}

/// `orchestrator up`'s exit codes (README, "Exit codes").
pub mod exit {
    /// The run ended by itself, its mission accomplished (roam: ran its max_ticks).
    pub const COMPLETE: i32 = 0;
    pub const FAILED: i32 = 1;
    pub const BAD_INPUT: i32 = 2;
    /// The run ended by itself (max_ticks, every robot dead), its mission not accomplished.
    pub const MISSION_NOT_COMPLETE: i32 = 3;
    /// Stopped by SIGINT (Ctrl-C) / SIGTERM: 128 + the signal.
    pub const SIGINT: i32 = 130;
    pub const SIGTERM: i32 = 143;
}

/// Whether `up` ended a run by itself, its mission accomplished or not (exit 0 or 3): for
/// tests that judge a run's outputs rather than its mission.
pub fn ended_by_itself(o: &Output) -> bool {
    matches!(
        o.status.code(),
        Some(exit::COMPLETE) | Some(exit::MISSION_NOT_COMPLETE)
    )
}

/// The registry entry of the run writing to `out`, if it has one.
pub fn registry_of(out: &Path) -> Option<serde_json::Value> {
    let dir = out.display().to_string();
    std::fs::read_dir(registry_dir())
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| std::fs::read_to_string(e.path()).ok())
        .filter_map(|s| serde_json::from_str::<serde_json::Value>(&s).ok())
        .find(|v| v["run_dir"].as_str() == Some(dir.as_str()))
}

/// The registry entry of the run writing to `out`, once all its agents are started.
pub fn registry_entry(out: &Path, robots: usize) -> serde_json::Value {
    let t = Instant::now();
    loop {
        assert!(
            t.elapsed() < Duration::from_secs(30),
            "run never registered its agents"
        );
        if let Some(v) =
            registry_of(out).filter(|v| v["agent_pids"].as_array().map(|a| a.len()) == Some(robots))
        {
            return v;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The tick the run writing to `out` is at, as its registry entry says (refreshed every
/// 50 ms by the orchestrator); 0 before the entry exists.
pub fn registry_tick(out: &Path) -> u64 {
    registry_of(out).map_or(0, |v| v["tick"].as_u64().unwrap_or(0))
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs the repository's scenario file `config` (relative to configs/) once with real
/// processes and once in-process, each into its own fresh folder (`<tag>-p`, `<tag>-i`),
/// asserting that both succeed. Returns (processes' folder, in-process folder).
pub fn up_in_both_executors(config: &str, tag: &str) -> (PathBuf, PathBuf) {
    let sc = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../configs")
        .join(config);
    let a = tmp_dir(&format!("{tag}-p"));
    let b = tmp_dir(&format!("{tag}-i"));
    for (dir, exec) in [(&a, "processes"), (&b, "inprocess")] {
        let o = up(
            &["--scenario", sc.to_str().unwrap(), "--executor", exec],
            dir,
        );
        assert!(o.status.success(), "{exec}: {}", stderr(&o));
    }
    (a, b)
}

/// Whether two run folders hold byte-identical recording.bin files.
pub fn same_recording(a: &Path, b: &Path) -> bool {
    let rec = |d: &Path| std::fs::read(d.join("recording.bin")).expect("recording.bin");
    rec(a) == rec(b)
}

/// While `child` runs, the most `count()` gave, sampled every 5 ms (e.g. a ring's data files:
/// a leaked hold would pin one more a kill).
pub fn most_while_running(child: &mut Child, count: impl Fn() -> usize) -> usize {
    let mut most = 0;
    while child.try_wait().unwrap().is_none() {
        most = most.max(count());
        std::thread::sleep(Duration::from_millis(5));
    }
    most
}

/// Every one of `kills` kills took effect and every killed robot came back (summary `faults`).
pub fn assert_every_kill_restarted(s: &serde_json::Value, kills: usize) {
    let faults = s["faults"].as_array().unwrap();
    assert_eq!(faults.len(), kills, "{faults:?}");
    assert!(
        faults
            .iter()
            .all(|f| f["restarted_tick"].as_u64().is_some()),
        "{faults:?}"
    );
}
