//! `orchestrator logs RUN [--robot N] [--follow]`: the agents' stdout and stderr, kept per
//! robot in `<run dir>/logs/robot-<i>.log` (agent_spawn.rs writes them).

use crate::agent_spawn::{self, LOGS_DIR};
use crate::{exit, registry};
use clap::Args;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How often `--follow` looks for new output and for the run's end.
const FOLLOW_PERIOD: Duration = Duration::from_millis(100);
/// The folder `up` puts runs in when --out is not given.
const RUNS_DIR: &str = "runs";

#[derive(Args, Debug)]
pub struct LogsArgs {
    /// The run: its id (a live run's, or a folder under runs/) or its run folder.
    pub run: String,
    /// One robot's log only [default: every robot's, one after the other].
    #[arg(long)]
    pub robot: Option<u32>,
    /// Go on printing what the agents write until the run ends (a live run).
    #[arg(short, long)]
    pub follow: bool,
}

/// A live run's folder, as an absolute path (its orchestrator's working directory joined
/// with the folder it was given).
fn live_dir(e: &registry::RunEntry) -> PathBuf {
    let cwd = std::fs::read_link(format!("/proc/{}/cwd", e.orchestrator_pid)).unwrap_or_default();
    cwd.join(&e.run_dir)
}

/// The live run whose id is `run`, or whose folder is `dir`.
fn live_run(run: &str, dir: Option<&Path>) -> Option<registry::RunEntry> {
    let dir = dir.and_then(|d| d.canonicalize().ok());
    registry::list().into_iter().find(|e| {
        e.orchestrator_is_live()
            && (e.run_id == run || dir.is_some() && live_dir(e).canonicalize().ok() == dir)
    })
}

/// The run folder RUN names, or why none.
fn run_dir(run: &str) -> Result<PathBuf, String> {
    if let Some(e) = live_run(run, None) {
        return Ok(live_dir(&e));
    }
    for d in [PathBuf::from(run), Path::new(RUNS_DIR).join(run)] {
        if d.join("scenario.toml").is_file() {
            return Ok(d);
        }
    }
    Err(format!(
        "RUN {run:?}: no live run has that id, and neither {run} nor {RUNS_DIR}/{run} is a run \
         folder (one holding scenario.toml)"
    ))
}

/// The robots that have a log in `dir`, in order.
fn robots_with_logs(dir: &Path) -> Vec<u32> {
    let mut v: Vec<u32> = std::fs::read_dir(dir.join(LOGS_DIR))
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            name.strip_prefix("robot-")?
                .strip_suffix(".log")?
                .parse()
                .ok()
        })
        .collect();
    v.sort_unstable();
    v
}

/// One log being printed: where it is and how much of it was printed.
struct Followed {
    robot: u32,
    path: PathBuf,
    at: u64,
    /// The start of a line not yet ended (printed once its newline comes).
    partial: Vec<u8>,
}

impl Followed {
    /// Prints what was added since the last call (whole lines; `prefix` before each when
    /// several robots' lines interleave); `flush` prints an unended last line too.
    fn pump(&mut self, out: &mut impl Write, prefix: bool, flush: bool) -> std::io::Result<()> {
        if let Ok(mut f) = std::fs::File::open(&self.path) {
            f.seek(SeekFrom::Start(self.at))?;
            let n = f.read_to_end(&mut self.partial)?;
            self.at += n as u64;
        }
        let end = if flush {
            self.partial.len()
        } else {
            self.partial
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |i| i + 1)
        };
        for line in self.partial[..end].split_inclusive(|&b| b == b'\n') {
            if prefix {
                write!(out, "robot-{}| ", self.robot)?;
            }
            out.write_all(line)?;
            if !line.ends_with(b"\n") {
                out.write_all(b"\n")?;
            }
        }
        self.partial.drain(..end);
        Ok(())
    }
}

pub fn logs(a: LogsArgs) -> i32 {
    let dir = match run_dir(&a.run) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::BAD_INPUT;
        }
    };
    let robots = match a.robot {
        Some(r) => vec![r],
        None => robots_with_logs(&dir),
    };
    if let Some(r) = a.robot {
        let path = agent_spawn::log_path(&dir, r);
        // Following a live run, a robot's log may not exist yet (its agent is starting).
        let coming = a.follow && live_run(&a.run, Some(&dir)).is_some();
        if !path.is_file() && !coming {
            eprintln!(
                "error: --robot {r}: {} does not exist (robots with a log: {:?})",
                path.display(),
                robots_with_logs(&dir)
            );
            return exit::BAD_INPUT;
        }
    }
    let mut logs: Vec<Followed> = robots
        .iter()
        .map(|&robot| Followed {
            robot,
            path: agent_spawn::log_path(&dir, robot),
            at: 0,
            partial: Vec::new(),
        })
        .collect();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    if !a.follow {
        // One robot after the other, each under a header when there are several.
        for l in &mut logs {
            if robots.len() > 1 {
                let _ = writeln!(out, "==> {} <==", l.path.display());
            }
            if l.pump(&mut out, false, true).is_err() {
                return exit::FAILED;
            }
        }
        return 0;
    }
    // Following: the lines of every robot as they come, each prefixed with its robot when
    // several are followed; until the run ends, then what is left.
    let prefix = a.robot.is_none();
    loop {
        let live = live_run(&a.run, Some(&dir)).is_some();
        if a.robot.is_none() {
            for r in robots_with_logs(&dir) {
                if !logs.iter().any(|l| l.robot == r) {
                    logs.push(Followed {
                        robot: r,
                        path: agent_spawn::log_path(&dir, r),
                        at: 0,
                        partial: Vec::new(),
                    });
                }
            }
        }
        for l in &mut logs {
            if l.pump(&mut out, prefix, !live).is_err() {
                return exit::FAILED;
            }
        }
        let _ = out.flush();
        if !live {
            return 0;
        }
        std::thread::sleep(FOLLOW_PERIOD);
    }
}
