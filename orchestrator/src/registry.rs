//! The registry of runs on this machine, so that another terminal (`orchestrator clean`,
//! `status`, `kill`) finds them: one JSON file per run, in a folder only this user can write.
//!
//! The folder is `$XDG_RUNTIME_DIR/swarm-runtime-<uid>` (or `/tmp/swarm-runtime-<uid>`): made
//! 0700, and used only while it is a real folder (no link) owned by this user with no access
//! for anyone else; otherwise every command that needs it refuses, touching nothing (another
//! user who made the folder first could plant entries naming processes to kill). Entries are
//! written without following links (`O_NOFOLLOW | O_EXCL` on the temporary name, then an
//! atomic rename), read without following links, and used only when their fields have the
//! project's own forms ([`RunEntry::check`]).

use crate::runid;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// The environment variable naming this user's private runtime folder (freedesktop.org).
pub const RUNTIME_DIR_ENV: &str = "XDG_RUNTIME_DIR";
/// Where the registry folder goes when `XDG_RUNTIME_DIR` is unset (or not absolute).
pub const FALLBACK_BASE: &str = "/tmp";
/// The registry folder's name under the base, followed by the user id.
pub const DIR_NAME: &str = "swarm-runtime-";
/// Mode of the registry folder: this user only.
const DIR_MODE: u32 = 0o700;
/// Mode of an entry: this user only.
const ENTRY_MODE: u32 = 0o600;
/// The sticky bit: in a folder others may write to, only a file's owner may rename or remove it.
const STICKY: u32 = 0o1000;

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunEntry {
    pub run_id: String,
    pub prefix: String,
    pub orchestrator_pid: u32,
    pub world_pid: u32,
    /// Current agent process of each robot (index = robot id).
    pub agent_pids: Vec<u32>,
    /// Start time of each process above (clock ticks after boot, /proc/PID/stat field 22):
    /// a pid counts as the run's only while the process with that pid started then (pids are
    /// reused). 0: not recorded, never the run's.
    #[serde(default)]
    pub orchestrator_start: u64,
    #[serde(default)]
    pub world_start: u64,
    #[serde(default)]
    pub agent_starts: Vec<u64>,
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

/// Why the registry cannot be used or an entry not written.
#[derive(Debug, thiserror::Error)]
pub enum RegistryError {
    #[error(
        "run registry {path}: {why}; it must be a folder of this user's (uid {uid}) that no one \
         else can read or write: remove it, or set {RUNTIME_DIR_ENV} to a private folder"
    )]
    Unsafe {
        path: PathBuf,
        why: String,
        uid: u32,
    },
    #[error("run registry {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "run id {run_id} is already in use by a running orchestrator (pid {pid}); give \
         another {} or none",
        runid::RUN_ID_ENV
    )]
    InUse { run_id: String, pid: u32 },
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> RegistryError + '_ {
    move |source| RegistryError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn euid() -> u32 {
    // SAFETY: geteuid cannot fail.
    unsafe { libc::geteuid() }
}

/// The registry folder's path (not checked).
pub fn dir_path() -> PathBuf {
    let base = std::env::var_os(RUNTIME_DIR_ENV)
        .map(PathBuf::from)
        .filter(|p| p.is_absolute())
        .unwrap_or_else(|| PathBuf::from(FALLBACK_BASE));
    base.join(format!("{DIR_NAME}{}", euid()))
}

/// The registry folder, made if missing, checked: a real folder of this user's, mode 0700,
/// in a base folder no other user can swap it out of.
pub fn dir() -> Result<PathBuf, RegistryError> {
    let path = dir_path();
    let uid = euid();
    let unsafe_dir = |why: String| RegistryError::Unsafe {
        path: path.clone(),
        why,
        uid,
    };
    let base = path.parent().unwrap_or(Path::new("/"));
    let bm = std::fs::metadata(base).map_err(io_err(base))?;
    let others_write = bm.mode() & 0o022 != 0;
    if (bm.uid() != uid && bm.uid() != 0) || (others_write && bm.mode() & STICKY == 0) {
        return Err(unsafe_dir(format!(
            "its folder {} can be changed by other users (owner uid {}, mode {:o})",
            base.display(),
            bm.uid(),
            bm.mode() & 0o7777
        )));
    }
    match std::fs::DirBuilder::new().mode(DIR_MODE).create(&path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(io_err(&path)(e)),
    }
    let m = std::fs::symlink_metadata(&path).map_err(io_err(&path))?;
    if m.file_type().is_symlink() {
        return Err(unsafe_dir("it is a symbolic link".into()));
    }
    if !m.is_dir() {
        return Err(unsafe_dir("it is not a folder".into()));
    }
    if m.uid() != uid {
        return Err(unsafe_dir(format!("it belongs to uid {}", m.uid())));
    }
    if m.mode() & 0o077 != 0 {
        return Err(unsafe_dir(format!(
            "other users have access to it (mode {:o})",
            m.mode() & 0o7777
        )));
    }
    Ok(path)
}

fn entry_name(run_id: &str) -> String {
    format!("{run_id}.json")
}

/// The temporary name an entry is written under before its rename.
fn temp_name(run_id: &str) -> String {
    format!(".{run_id}.json.tmp")
}

/// Writes `text` to `dir/name` as a new file of this user's, never through a link: a file or
/// link already at that name is removed first (unlink removes the link, not its target).
fn write_new(dir: &Path, name: &str, text: &str) -> Result<PathBuf, RegistryError> {
    let path = dir.join(name);
    let open = || {
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(ENTRY_MODE)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
    };
    let mut f = match open() {
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            std::fs::remove_file(&path).map_err(io_err(&path))?;
            open()
        }
        r => r,
    }
    .map_err(io_err(&path))?;
    f.write_all(text.as_bytes()).map_err(io_err(&path))?;
    Ok(path)
}

fn to_json(e: &RunEntry) -> String {
    serde_json::to_string_pretty(e).expect("a RunEntry serialises")
}

/// Registers a new run: fails with `InUse` when a live orchestrator holds the same run id (a
/// stale entry of a dead one is replaced).
pub fn create(e: &RunEntry) -> Result<(), RegistryError> {
    let dir = dir()?;
    let tmp = write_new(&dir, &temp_name(&e.run_id), &to_json(e))?;
    let path = dir.join(entry_name(&e.run_id));
    // link() fails if the name exists (a link there included) and never follows one.
    let linked = std::fs::hard_link(&tmp, &path);
    let result = match linked {
        Ok(()) => Ok(()),
        Err(err) if err.kind() == std::io::ErrorKind::AlreadyExists => {
            match read_entry(&path).filter(|old| old.orchestrator_is_live()) {
                Some(old) => Err(RegistryError::InUse {
                    run_id: e.run_id.clone(),
                    pid: old.orchestrator_pid,
                }),
                None => std::fs::rename(&tmp, &path).map_err(io_err(&path)),
            }
        }
        Err(err) => Err(io_err(&path)(err)),
    };
    let _ = std::fs::remove_file(&tmp);
    result
}

/// Rewrites a registered run's entry (its pids, its progress).
pub fn write(e: &RunEntry) -> Result<(), RegistryError> {
    let dir = dir()?;
    let tmp = write_new(&dir, &temp_name(&e.run_id), &to_json(e))?;
    let path = dir.join(entry_name(&e.run_id));
    std::fs::rename(&tmp, &path).map_err(io_err(&path))
}

/// Removes the entry of a run (only a run id of the project's form names a file).
pub fn remove(run_id: &str) {
    if let (true, Ok(dir)) = (runid::is_valid(run_id), dir()) {
        let _ = std::fs::remove_file(dir.join(entry_name(run_id)));
    }
}

/// Reads an entry: a regular file of this user's (never through a link) whose fields have
/// the project's forms.
fn read_entry(path: &Path) -> Option<RunEntry> {
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)
        .ok()?;
    let m = f.metadata().ok()?;
    if !m.is_file() || m.uid() != euid() {
        return None;
    }
    let e: RunEntry = serde_json::from_reader(std::io::BufReader::new(f)).ok()?;
    let name = path.file_name()?.to_str()?;
    (e.check().is_ok() && name == entry_name(&e.run_id)).then_some(e)
}

/// The registered runs (valid entries only) and a line for each file that was ignored.
pub fn scan() -> Result<(Vec<RunEntry>, Vec<String>), RegistryError> {
    let dir = dir()?;
    let mut runs = Vec::new();
    let mut ignored = Vec::new();
    for d in std::fs::read_dir(&dir).map_err(io_err(&dir))?.flatten() {
        let name = d.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') || !name.ends_with(".json") {
            continue;
        }
        match read_entry(&d.path()) {
            Some(e) => runs.push(e),
            None => ignored.push(format!(
                "ignored {}: not a valid entry of this user's",
                d.path().display()
            )),
        }
    }
    runs.sort_by(|a, b| a.run_id.cmp(&b.run_id));
    Ok((runs, ignored))
}

/// The registered runs; none when the registry cannot be used (`scan` says why).
pub fn list() -> Vec<RunEntry> {
    scan().map(|(runs, _)| runs).unwrap_or_default()
}

/// Whether `name` has the shape of a run's shared-memory prefix: `sw` + 10 hex digits + `_`.
pub fn is_prefix_shape(name: &str) -> bool {
    name.len() == 13
        && name.starts_with("sw")
        && name.ends_with('_')
        && name[2..12].bytes().all(|b| b.is_ascii_hexdigit())
}

impl RunEntry {
    /// Refuses fields not of the project's own forms: the run id's shape, the prefix that
    /// run id gives, one start time per agent pid.
    pub fn check(&self) -> Result<(), String> {
        if !runid::is_valid(&self.run_id) {
            return Err(format!("run_id {:?} is not a run id", self.run_id));
        }
        if self.prefix != swarm::transport::prefix_for(&self.run_id)
            || !is_prefix_shape(&self.prefix)
        {
            return Err(format!(
                "prefix {:?} is not run {}'s",
                self.prefix, self.run_id
            ));
        }
        if self.agent_starts.len() != self.agent_pids.len() {
            return Err("agent_starts and agent_pids differ in length".into());
        }
        Ok(())
    }

    /// Whether the run's orchestrator is still running: the recorded process (pid and start
    /// time) runs a binary named `orchestrator`, this build's or another's (a second checkout,
    /// an installed copy). A live run of another build is live: `clean` (which every `up`
    /// runs) once took it for dead and SIGKILLed its agents mid-run. Another program at that
    /// pid is not an orchestrator.
    pub fn orchestrator_is_live(&self) -> bool {
        runs_binary_named(self.orchestrator_pid, self.orchestrator_start, ORCHESTRATOR)
    }

    /// The run's world and agent processes still running (pid, binary), verified.
    pub fn live_children(&self) -> Vec<u32> {
        let world = is_ours(self.world_pid, self.world_start, WORLD).then_some(self.world_pid);
        world
            .into_iter()
            .chain(
                self.agent_pids
                    .iter()
                    .zip(&self.agent_starts)
                    .filter(|&(&p, &s)| self.is_agent(p, s))
                    .map(|(&p, _)| p),
            )
            .collect()
    }

    /// Whether `pid` is still the agent this run started at `start`: this build's agent
    /// binary, or (an `[[agents]]` program of the user's, issue 38) a process started at that
    /// time whose arguments hold this run's `--prefix`.
    pub fn is_agent(&self, pid: u32, start: u64) -> bool {
        is_ours(pid, start, AGENT)
            || (pid != 0 && start != 0 && start_time(pid) == Some(start) && {
                let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
                cmdline
                    .split(|&b| b == 0)
                    .any(|arg| arg == self.prefix.as_bytes())
            })
    }
}

/// The project's binaries, by file name (they live side by side).
pub const ORCHESTRATOR: &str = "orchestrator";
pub const WORLD: &str = "world";
pub const AGENT: &str = "agent";

/// When process `pid` started (clock ticks after boot), if it exists.
pub fn start_time(pid: u32) -> Option<u64> {
    if pid == 0 {
        return None;
    }
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name (which may hold spaces and parentheses): state is field
    // 3, starttime field 22.
    let rest = &stat[stat.rfind(')')? + 1..];
    rest.split_whitespace().nth(22 - 3)?.parse().ok()
}

/// This build's binary `name` (beside the running orchestrator).
pub fn binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("current exe");
    exe.parent().expect("exe dir").join(name)
}

/// The binary process `pid` runs, if it is the process that started at `start` (a reused
/// pid, another start time, is not). A binary rebuilt while its process runs reads as
/// "PATH (deleted)": the path is given without that suffix.
fn exe_of(pid: u32, start: u64) -> Option<PathBuf> {
    if pid == 0 || start == 0 || start_time(pid) != Some(start) {
        return None;
    }
    let exe = std::fs::read_link(format!("/proc/{pid}/exe")).ok()?;
    let exe = exe.to_string_lossy();
    Some(PathBuf::from(
        exe.strip_suffix(" (deleted)").unwrap_or(&exe),
    ))
}

/// Whether process `pid` started at `start` and runs a binary whose file name is `name`, of
/// whichever build.
pub fn runs_binary_named(pid: u32, start: u64, name: &str) -> bool {
    exe_of(pid, start).is_some_and(|exe| exe.file_name().is_some_and(|f| f == name))
}

/// Whether `pid` is a process of this project's: it started at `start` and runs this build's
/// binary `name`. A reused pid (another start time) or another program is not.
pub fn is_ours(pid: u32, start: u64, name: &str) -> bool {
    let Some(exe) = exe_of(pid, start) else {
        return false;
    };
    let want = binary(name);
    exe == want || std::fs::canonicalize(&want).is_ok_and(|w| exe == w)
}

pub fn pid_alive(pid: u32) -> bool {
    // SAFETY: signal 0 only checks for existence.
    pid != 0 && unsafe { libc::kill(pid as i32, 0) } == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefix_shapes() {
        assert!(is_prefix_shape("sw0123456789_"));
        assert!(!is_prefix_shape(""));
        assert!(!is_prefix_shape("sw0123456789_x"));
        assert!(!is_prefix_shape("sw../../etc_"));
    }

    #[test]
    fn entries_of_other_forms_are_refused() {
        let good = RunEntry {
            run_id: "20261122-183500-3fa2".into(),
            prefix: swarm::transport::prefix_for("20261122-183500-3fa2"),
            orchestrator_pid: 1,
            world_pid: 0,
            agent_pids: vec![],
            orchestrator_start: 0,
            world_start: 0,
            agent_starts: vec![],
            run_dir: String::new(),
            tick: 0,
            alive: 0,
            dead: 0,
            restarted: 0,
        };
        assert!(good.check().is_ok());
        for (run_id, prefix) in [
            ("../x", swarm::transport::prefix_for("../x")),
            ("", String::new()),
            ("20261122-183500-3fa2", String::new()),
            ("20261122-183500-3fa2", "sw../".into()),
            (
                "20261122-183500-3fa2",
                swarm::transport::prefix_for("other"),
            ),
        ] {
            let e = RunEntry {
                run_id: run_id.into(),
                prefix,
                ..good.clone()
            };
            assert!(e.check().is_err(), "{e:?}");
        }
        let e = RunEntry {
            agent_pids: vec![3],
            ..good.clone()
        };
        assert!(e.check().is_err(), "a pid without its start time");
    }

    #[test]
    fn a_process_is_ours_only_with_its_start_time_and_binary() {
        let me = std::process::id();
        let start = start_time(me).expect("own start time");
        // The unit test binary is not the orchestrator: never "ours"; under its own name, it is.
        assert!(!is_ours(me, start, ORCHESTRATOR));
        let exe = std::env::current_exe().unwrap();
        let own = exe.file_name().unwrap().to_str().unwrap();
        assert!(is_ours(me, start, own));
        assert!(
            !is_ours(me, start + 1, own),
            "another start time: a reused pid"
        );
        let mut sleep = std::process::Command::new("sleep")
            .arg("5")
            .spawn()
            .unwrap();
        let s = start_time(sleep.id()).unwrap();
        assert!(!is_ours(sleep.id(), s, AGENT), "sleep is no agent");
        assert!(!is_ours(sleep.id(), s + 1, AGENT));
        sleep.kill().unwrap();
        sleep.wait().unwrap();
    }
}
