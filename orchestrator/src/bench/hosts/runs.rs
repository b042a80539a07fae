//! One run of the rows: the roam scenario as `orchestrator up` in the world's namespace, with
//! (across hosts) one `orchestrator host` proxy in each host's namespace, every process a child
//! of the bench that enters its namespace before it starts (setns in `pre_exec`). Its tick p50
//! comes from the run's summary.json.

use super::error::HostsBenchError;
use super::net::{enter_fd, Net, Netns};
use crate::bench::{BenchError, BenchResult};
use crate::signals;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use swarm::scenario::Scenario;
use swarm::sections::hosts::{HostSpec, RobotSet};

/// The port the world's host listens on, in its own namespace (nothing else is there).
const PORT: u16 = 7447;
/// Seconds the world waits for its hosts to join (`runtime.startup_timeout_s`), and a proxy
/// for the world's host (`host --wait`). [chosen] Far above the few seconds 200 robots take
/// to start here, loaded.
const JOIN_S: u64 = 120;
/// A run's time limit: this many seconds, plus RUN_LIMIT_PER_TICK_MS a tick.
const RUN_LIMIT_BASE_S: u64 = 180;
/// A run's time limit per tick (ms), 10x the slowest tick measured across hosts here.
const RUN_LIMIT_PER_TICK_MS: u64 = 50;
/// How long a stopped run's processes have to end after SIGINT before SIGKILL.
const STOP_GRACE: Duration = Duration::from_secs(15);
/// How often the bench looks at its run's processes.
const POLL: Duration = Duration::from_millis(20);
/// The end of a failed process's stderr quoted in the error (bytes).
const LOG_TAIL: usize = 600;

/// A finished run: its id, its tick p50 and its folder (recording.bin, summary.json).
pub struct Done {
    pub run_id: String,
    pub p50_ms: f64,
    pub dir: PathBuf,
}

/// The roam scenario at `robots` robots for `ticks` ticks; with `hosts` > 0 split evenly over
/// the world's host and hosts h1..=h<hosts> (the last one takes the rest).
fn scenario(robots: u32, ticks: u64, hosts: usize) -> Scenario {
    let mut sc = Scenario::roam();
    sc.run.robots = robots;
    sc.run.max_ticks = ticks;
    sc.runtime.startup_timeout_s = JOIN_S;
    if hosts > 0 {
        sc.hosts_listen = Some(format!("tcp/0.0.0.0:{PORT}"));
        let per = robots / (hosts as u32 + 1);
        sc.hosts = (1..=hosts as u32)
            .map(|h| {
                let end = if h == hosts as u32 {
                    robots
                } else {
                    (h + 1) * per
                };
                HostSpec {
                    name: format!("h{h}"),
                    robots: RobotSet::Range(format!("{}..{end}", h * per)),
                }
            })
            .collect();
    }
    sc
}

/// The scenario as a file `up --scenario` reads (`to_toml` leaves the hosts out: where a robot
/// runs is never part of a resolved scenario, so they are added here).
fn write_scenario(sc: &Scenario, path: &Path) -> Result<(), HostsBenchError> {
    let mut t: toml::Table = sc.to_toml().parse().expect("a resolved scenario is TOML");
    if let Some(l) = &sc.hosts_listen {
        t.insert("hosts_listen".into(), toml::Value::String(l.clone()));
    }
    if !sc.hosts.is_empty() {
        let hosts = toml::Value::try_from(&sc.hosts).expect("hosts serialise");
        t.insert("hosts".into(), hosts);
    }
    std::fs::write(path, toml::to_string(&t).expect("scenario serialises")).map_err(|source| {
        HostsBenchError::File {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// This program, as a child in namespace `ns`, its stderr into `log`; it dies with the bench
/// (PR_SET_PDEATHSIG: a killed bench leaves no run behind).
fn spawn_in(ns: &Netns, args: &[String], run_id: &str, log: &Path) -> BenchResult<Child> {
    let what = args[0].clone();
    let spawn_err = |source| HostsBenchError::Spawn {
        what: what.clone(),
        source,
    };
    let exe = std::env::current_exe().map_err(spawn_err)?;
    let stderr = std::fs::File::create(log).map_err(spawn_err)?;
    let fd = ns.fd();
    let mut cmd = Command::new(exe);
    cmd.args(args)
        .env(crate::runid::RUN_ID_ENV, run_id)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(stderr)
        .process_group(0);
    // SAFETY: between fork and exec only async-signal-safe calls: setns and prctl.
    unsafe {
        cmd.pre_exec(move || {
            enter_fd(fd)?;
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM);
            Ok(())
        });
    }
    Ok(cmd.spawn().map_err(spawn_err)?)
}

/// The end of a log file, for an error message.
fn tail(log: &Path) -> String {
    let s = std::fs::read_to_string(log).unwrap_or_default();
    let s = s.trim();
    let cut = s.len().saturating_sub(LOG_TAIL);
    let cut = (cut..=s.len())
        .find(|&i| s.is_char_boundary(i))
        .unwrap_or(0);
    s[cut..].to_string()
}

/// SIGINT to every live child (their clean stop), then SIGKILL to those still there after
/// STOP_GRACE; reaps them all.
fn stop(children: &mut [(String, Child, PathBuf)]) {
    for (_, c, _) in children.iter_mut() {
        if c.try_wait().ok().flatten().is_none() {
            // SAFETY: a signal to a child of the bench that has not been reaped.
            unsafe { libc::kill(c.id() as i32, libc::SIGINT) };
        }
    }
    let t = Instant::now();
    for (_, c, _) in children.iter_mut() {
        while c.try_wait().ok().flatten().is_none() && t.elapsed() < STOP_GRACE {
            std::thread::sleep(POLL);
        }
        let _ = c.kill();
        let _ = c.wait();
    }
}

/// Waits for every child to end by itself within `limit`; stops them all on Ctrl-C (or
/// SIGTERM) or when the limit passes. Each must exit 0.
fn wait_all(children: &mut [(String, Child, PathBuf)], limit: Duration) -> BenchResult<()> {
    let t = Instant::now();
    loop {
        if signals::interrupted() {
            stop(children);
            return Err(BenchError::Interrupted);
        }
        if t.elapsed() > limit {
            stop(children);
            return Err(HostsBenchError::Timeout {
                what: "a run".into(),
                seconds: limit.as_secs(),
            }
            .into());
        }
        let mut live = false;
        for (what, c, log) in children.iter_mut() {
            match c.try_wait() {
                Ok(None) => live = true,
                Ok(Some(s)) if s.success() => {}
                Ok(Some(s)) => {
                    let (what, log) = (what.clone(), log.clone());
                    stop(children);
                    return Err(HostsBenchError::Exited {
                        what,
                        status: s.to_string(),
                        log: tail(&log),
                    }
                    .into());
                }
                Err(e) => {
                    let what = what.clone();
                    stop(children);
                    return Err(HostsBenchError::Spawn { what, source: e }.into());
                }
            }
        }
        if !live {
            return Ok(());
        }
        std::thread::sleep(POLL);
    }
}

/// The /dev/shm files of a run (the world's prefix and each proxy's): removed when dropped,
/// whatever happened; `check` first says whether the run itself left any.
struct RunFiles(Vec<String>);

impl RunFiles {
    fn check(&self) -> BenchResult<()> {
        self.0
            .iter()
            .try_for_each(|p| super::super::check_no_leftovers(p))
    }
}

impl Drop for RunFiles {
    fn drop(&mut self) {
        for p in &self.0 {
            swarm::cleanup::remove_run(p);
        }
    }
}

/// One run of `robots` robots for `ticks` ticks in `net`: on the world's host alone
/// (`across` false) or split over every namespace. Its folder is `dir`.
pub fn run(net: &Net, robots: u32, ticks: u64, across: bool, dir: &Path) -> BenchResult<Done> {
    let hosts = if across { net.hosts() } else { 0 };
    let sc = scenario(robots, ticks, hosts);
    let file = dir.with_extension("toml");
    write_scenario(&sc, &file)?;
    let run_id = crate::runid::new_run_id();
    let files = RunFiles(
        std::iter::once(swarm::transport::prefix_for(&run_id))
            .chain((1..=hosts).map(|h| swarm::transport::prefix_for(&format!("{run_id}@h{h}"))))
            .collect(),
    );
    // The proxies' run folders (`swarm-host-NAME-RUN`) beside the run's folder.
    let proxy_out = dir.parent().unwrap_or(dir);
    let mut children: Vec<(String, Child, PathBuf)> = Vec::new();
    let started = (|| -> BenchResult<()> {
        for h in 1..=hosts {
            let args: Vec<String> = [
                "host",
                "--join",
                &format!("tcp/{}:{PORT}", Net::world_addr(h)),
                "--name",
                &format!("h{h}"),
                "--wait",
                &JOIN_S.to_string(),
                "--out",
            ]
            .iter()
            .map(|s| s.to_string())
            .chain(std::iter::once(proxy_out.display().to_string()))
            .collect();
            let log = dir.with_extension(format!("h{h}.log"));
            let ns = Netns::open(net.host(h))?;
            let c = spawn_in(&ns, &args, &run_id, &log)?;
            children.push((format!("host h{h}'s proxy"), c, log));
        }
        let args: Vec<String> = ["up", "--quiet", "--scenario"]
            .iter()
            .map(|s| s.to_string())
            .chain([
                file.display().to_string(),
                "--out".into(),
                dir.display().to_string(),
            ])
            .collect();
        let log = dir.with_extension("up.log");
        let ns = Netns::open(net.world())?;
        let c = spawn_in(&ns, &args, &run_id, &log)?;
        children.push(("`orchestrator up`".into(), c, log));
        Ok(())
    })();
    if let Err(e) = started {
        stop(&mut children);
        return Err(e);
    }
    let limit = Duration::from_secs(RUN_LIMIT_BASE_S + ticks * RUN_LIMIT_PER_TICK_MS / 1000);
    wait_all(&mut children, limit)?;
    files.check()?;
    let s = crate::bench::tick::read_summary(dir)?;
    Ok(Done {
        run_id,
        p50_ms: s["tick_time"]["p50_us"].as_f64().unwrap_or(f64::NAN) / 1e3,
        dir: dir.to_path_buf(),
    })
}
