//! How the orchestrator starts one robot's agent: the built-in `agent` binary, or the program
//! of the robot's `[[agents]]` entry (issue 38), with the same arguments and environment,
//! its stdout and stderr appended to `<run dir>/logs/robot-<i>.log` after a line that marks
//! each start.

use crate::registry;
use std::io::Write;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;
use swarm::scenario::{AgentEntry, Scenario};

/// The folder of the per-robot logs inside a run folder.
pub const LOGS_DIR: &str = "logs";
/// How many last lines of a robot's log a failure report quotes.
pub const LOG_TAIL_LINES: usize = 8;
/// What starts each agent's section of its log (`orchestrator logs` shows it as written).
pub const START_MARK: &str = "--- swarm: agent start";

/// `<run dir>/logs/robot-<i>.log`.
pub fn log_path(run_dir: &Path, robot: u32) -> PathBuf {
    run_dir.join(LOGS_DIR).join(format!("robot-{robot}.log"))
}

/// Starts the agents of one run.
pub struct Launcher<'a> {
    pub sc: &'a Scenario,
    pub prefix: &'a str,
    pub run_id: &'a str,
    /// The run folder's resolved scenario.toml (what every agent reads).
    pub scenario_path: &'a Path,
    pub run_dir: &'a Path,
}

impl Launcher<'_> {
    /// The `[[agents]]` entry of `robot`, if it has one.
    pub fn entry(&self, robot: u32) -> Option<&AgentEntry> {
        swarm::sections::agents::entry_of(&self.sc.agents, robot).map(|i| &self.sc.agents[i])
    }

    /// The command that runs `robot`'s agent (no stdio set).
    pub fn command(&self, robot: u32) -> Command {
        let mut c = match self.entry(robot) {
            Some(e) => {
                let mut c = Command::new(&e.command[0]);
                c.args(&e.command[1..]);
                if let Some(cwd) = &e.cwd {
                    c.current_dir(cwd);
                }
                c
            }
            None => Command::new(registry::binary("agent")),
        };
        c.args([
            "--robot",
            &robot.to_string(),
            "--prefix",
            self.prefix,
            "--run-id",
            self.run_id,
            "--scenario",
        ])
        // Absolute: an `[[agents]]` program runs in its own working directory.
        .arg(std::path::absolute(self.scenario_path).unwrap_or_else(|_| self.scenario_path.into()));
        c
    }

    /// The command line of `robot`'s agent, as reports show it.
    pub fn describe(&self, robot: u32) -> String {
        let cmd = self.command(robot);
        std::iter::once(cmd.get_program())
            .chain(cmd.get_args())
            .map(|a| a.to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// How long an agent of `robot` may take to attach before it is killed and the robot
    /// fails; None for the built-in agent (the world's runtime.startup_timeout_s covers it).
    pub fn attach_timeout(&self, robot: u32) -> Option<Duration> {
        self.entry(robot).map(AgentEntry::attach_timeout)
    }

    /// Starts an agent of `robot` (its `start`-th, from 1), its output appended to its log;
    /// returns (pid, start time).
    pub fn spawn(&self, robot: u32, start: u32, tick: u64) -> Result<(u32, u64), String> {
        let path = log_path(self.run_dir, robot);
        let log = open_log(
            &path,
            &format!(
                "{START_MARK} {start} of robot {robot} at run tick {tick}: {}\n",
                self.describe(robot)
            ),
        )
        .map_err(|e| format!("robot {robot}'s log {}: {e}", path.display()))?;
        let err = log
            .try_clone()
            .map_err(|e| format!("robot {robot}'s log {}: {e}", path.display()))?;
        self.command(robot)
            .stdin(Stdio::null())
            .stdout(log)
            .stderr(err)
            .process_group(0)
            .spawn()
            .map(|c| (c.id(), registry::start_time(c.id()).unwrap_or(0)))
            .map_err(|e| {
                format!(
                    "cannot start robot {robot}'s agent: {e}; command: {}",
                    self.describe(robot)
                )
            })
    }

    /// The last [`LOG_TAIL_LINES`] lines of `robot`'s log after its last start mark.
    pub fn log_tail(&self, robot: u32) -> String {
        let text = std::fs::read_to_string(log_path(self.run_dir, robot)).unwrap_or_default();
        let last = text.rfind(START_MARK).unwrap_or(0);
        let lines: Vec<&str> = text[last..].lines().skip(1).collect();
        let from = lines.len().saturating_sub(LOG_TAIL_LINES);
        lines[from..].join("\n")
    }
}

/// Opens `path` for appending (making its folder) and writes `mark`.
fn open_log(path: &Path, mark: &str) -> std::io::Result<std::fs::File> {
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d)?;
    }
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)?;
    f.write_all(mark.as_bytes())?;
    Ok(f)
}
