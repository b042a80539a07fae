//! `orchestrator up`: resolve the scenario, run it, print the summary.

use crate::{clean, exit, inprocess, outcome, outdir, processes, registry, runid, signals};
use clap::{Args, ValueEnum};
use search::SearchScenario;
use std::path::{Path, PathBuf};
use swarm::scenario::{ConfigError, Scenario};

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Executor {
    /// One OS process per robot over iceoryx2 (the product).
    Processes,
    /// Everything in this process (unit tests, sweeps); same results.
    Inprocess,
}

#[derive(Args, Debug, Clone)]
pub struct UpArgs {
    /// Number of robots (one agent process each) [scenario: run.robots].
    #[arg(short = 'n', long)]
    pub robots: Option<u32>,
    /// Scenario file (TOML); keys it leaves out take the embedded default's values
    /// [default: the embedded scenario].
    #[arg(short, long)]
    pub scenario: Option<PathBuf>,
    /// Seed of every random stream [scenario: run.seed].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Ticks to run [scenario: run.max_ticks].
    #[arg(long)]
    pub max_ticks: Option<u64>,
    /// Communication radius [scenario: radio.comm_radius].
    #[arg(long)]
    pub comm_radius: Option<f64>,
    /// Message loss probability, 0..=1 [scenario: radio.loss].
    #[arg(long)]
    pub loss: Option<f64>,
    /// Search mode (Table 3): obstacle layer B = BSOA / S = SVF, search layer T = TPEPSO /
    /// E = EPSO / A = ARBA [scenario: search.mode].
    #[arg(long, value_enum)]
    pub mode: Option<SearchMode>,
    /// Radio delay in ticks [scenario: radio.delay_ticks].
    #[arg(long)]
    pub delay: Option<u32>,
    /// Bytes a robot may put on the air per tick, headers of 40 bytes included; 0 = no cap
    /// [scenario: radio.bandwidth_bytes_per_tick].
    #[arg(long)]
    pub bandwidth: Option<u32>,
    /// Bursty loss (Gilbert-Elliott per link): P_GOOD_BAD,P_BAD_GOOD,LOSS_GOOD,LOSS_BAD, each
    /// 0..=1, e.g. 0.05,0.25,0,0.8 [scenario: radio.burst].
    #[arg(long, value_parser = parse_burst)]
    pub burst: Option<swarm::radio::BurstParams>,
    /// Obstacles block the radio's line of sight [scenario: radio.occlusion].
    #[arg(long)]
    pub occlusion: bool,
    /// Pacing: at most this many ticks per second, 0 = unpaced; results are the same
    /// [scenario: runtime.tick_hz].
    #[arg(long)]
    pub tick_hz: Option<f64>,
    /// Real-time mode: tick on a clock at HZ ticks per second; an action late for its
    /// tick's deadline is not waited for (the robot keeps its last command) and counts as a
    /// deadline miss. Processes executor only [scenario: runtime.realtime_hz].
    #[arg(long, value_name = "HZ")]
    pub realtime: Option<f64>,
    /// Run folder [default: runs/<run-id>].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// Where the robots run.
    #[arg(long, value_enum, default_value_t = Executor::Processes)]
    pub executor: Executor,
    /// Random SIGKILLs of agents per 100 ticks, from the run's seed [scenario: faults.chaos_rate].
    #[arg(long)]
    pub chaos: Option<f64>,
    /// SIGKILLs at given ticks: TICK:ROBOT,... e.g. 120:7,300:12 [scenario: faults.kill_at].
    #[arg(long, value_parser = parse_kills)]
    pub chaos_at: Option<KillList>,
    /// Kill this fraction of the robots once each, at seeded random ticks in
    /// faults.kill_window [scenario: faults.kill_fraction].
    #[arg(long)]
    pub kill_fraction: Option<f64>,
    /// What happens to a robot whose agent dies [scenario: faults.on_fault].
    #[arg(long, value_enum)]
    pub on_fault: Option<OnFault>,
    /// Restarts allowed per robot under --on-fault restart [scenario: faults.max_restarts].
    #[arg(long)]
    pub max_restarts: Option<u32>,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
    /// Watch the run in the browser: serves the viewer on 127.0.0.1 (the URL is printed)
    /// fed from the run's recording as the world writes it, with a button that kills a
    /// robot's agent as `orchestrator kill` does.
    #[arg(long)]
    pub view: bool,
    /// Port of --view (0: any free port).
    #[arg(long, default_value_t = 0, requires = "view")]
    pub view_port: u16,
    /// A run across hosts (`[[hosts]]`): the Zenoh endpoint this host listens on for the
    /// hosts' proxies, tcp/ADDRESS:PORT [scenario: hosts_listen].
    #[arg(long, value_name = "ENDPOINT")]
    pub listen: Option<String>,
    /// Record which messages each robot was handed every tick (sender, seq, size), for the
    /// viewer's "heard this tick" [scenario: runtime.record_deliveries].
    #[arg(long)]
    pub record_deliveries: bool,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum OnFault {
    /// The robot stands still as an obstacle; the swarm carries on.
    Drop,
    /// A new agent process takes the robot over, fresh from its Sense frame.
    Restart,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
#[value(rename_all = "UPPER")]
pub enum SearchMode {
    Bt,
    Be,
    Ba,
    St,
    Se,
    Sa,
}

#[derive(Clone, Debug, PartialEq)]
pub struct KillList(pub Vec<[u64; 2]>);

fn parse_kills(s: &str) -> Result<KillList, String> {
    s.split(',')
        .filter(|x| !x.trim().is_empty())
        .map(|item| {
            let (t, r) = item
                .split_once(':')
                .ok_or_else(|| format!("{item:?} is not TICK:ROBOT (e.g. 120:7)"))?;
            let t: u64 = t
                .trim()
                .parse()
                .map_err(|_| format!("{item:?}: tick {t:?} is not a whole number"))?;
            let r: u64 = r
                .trim()
                .parse()
                .map_err(|_| format!("{item:?}: robot {r:?} is not a whole number"))?;
            Ok([t, r])
        })
        .collect::<Result<Vec<_>, _>>()
        .map(KillList)
}

/// `--burst P_GOOD_BAD,P_BAD_GOOD,LOSS_GOOD,LOSS_BAD` (ranges are checked with the scenario).
fn parse_burst(s: &str) -> Result<swarm::radio::BurstParams, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| {
            x.trim()
                .parse::<f64>()
                .map_err(|_| format!("{x:?} is not a number"))
        })
        .collect::<Result<_, _>>()?;
    match v[..] {
        [p_good_bad, p_bad_good, loss_good, loss_bad] => Ok(swarm::radio::BurstParams {
            p_good_bad,
            p_bad_good,
            loss_good,
            loss_bad,
        }),
        _ => Err(format!(
            "{s:?}: four numbers wanted, P_GOOD_BAD,P_BAD_GOOD,LOSS_GOOD,LOSS_BAD (e.g. 0.05,0.25,0,0.8)"
        )),
    }
}

/// Which flag set a scenario key, for error messages.
pub(crate) const FLAG_KEYS: &[(&str, &str)] = &[
    ("run.robots", "--robots"),
    ("run.seed", "--seed"),
    ("run.max_ticks", "--max-ticks"),
    ("radio.comm_radius", "--comm-radius"),
    ("radio.loss", "--loss"),
    ("radio.delay_ticks", "--delay"),
    ("radio.bandwidth_bytes_per_tick", "--bandwidth"),
    ("radio.burst.p_good_bad", "--burst"),
    ("radio.burst.p_bad_good", "--burst"),
    ("radio.burst.loss_good", "--burst"),
    ("radio.burst.loss_bad", "--burst"),
    ("radio.occlusion", "--occlusion"),
    ("search.mode", "--mode"),
    ("faults.chaos_rate", "--chaos"),
    ("faults.kill_at", "--chaos-at"),
    ("faults.kill_fraction", "--kill-fraction"),
    ("faults.max_restarts", "--max-restarts"),
    ("faults.on_fault", "--on-fault"),
    ("runtime.tick_hz", "--tick-hz"),
    ("runtime.realtime_hz", "--realtime"),
    ("runtime.record_deliveries", "--record-deliveries"),
    ("hosts_listen", "--listen"),
];

/// The scenario with the flags applied and validated.
pub fn resolve(a: &UpArgs) -> Result<Scenario, ConfigError> {
    let (mut sc, file) = match &a.scenario {
        Some(p) => (Scenario::load(p)?, p.display().to_string()),
        None => (Scenario::default(), "embedded default scenario".to_string()),
    };
    let mut from_flag: Vec<&str> = Vec::new();
    let mut set = |key: &'static str, apply: &mut dyn FnMut()| {
        apply();
        from_flag.push(key);
    };
    if let Some(v) = a.robots {
        set("run.robots", &mut || sc.run.robots = v);
    }
    if let Some(v) = a.seed {
        set("run.seed", &mut || sc.run.seed = v);
    }
    if let Some(v) = a.max_ticks {
        set("run.max_ticks", &mut || sc.run.max_ticks = v);
    }
    if let Some(v) = a.comm_radius {
        set("radio.comm_radius", &mut || sc.radio.comm_radius = v);
    }
    if let Some(v) = a.loss {
        set("radio.loss", &mut || sc.radio.loss = v);
    }
    if let Some(m) = a.mode {
        if sc.run.behaviour != "search" {
            return Err(ConfigError {
                source: "--mode".into(),
                key: "search.mode".into(),
                message: format!(
                    "applies to run.behaviour = \"search\" only; {file} sets run.behaviour = {:?}",
                    sc.run.behaviour
                ),
            });
        }
        let name = format!("{m:?}").to_uppercase();
        set("search.mode", &mut || sc.search_mut().mode = name.clone());
    }
    if let Some(v) = a.delay {
        set("radio.delay_ticks", &mut || sc.radio.delay_ticks = v);
    }
    if let Some(v) = a.bandwidth {
        set("radio.bandwidth_bytes_per_tick", &mut || {
            sc.radio.bandwidth_bytes_per_tick = v
        });
    }
    if let Some(v) = a.burst {
        // One flag sets the four keys; whichever is out of range names it.
        set("radio.burst.p_good_bad", &mut || sc.radio.burst = Some(v));
        for key in [
            "radio.burst.p_bad_good",
            "radio.burst.loss_good",
            "radio.burst.loss_bad",
        ] {
            set(key, &mut || {});
        }
    }
    if a.occlusion {
        set("radio.occlusion", &mut || sc.radio.occlusion = true);
    }
    if let Some(v) = a.chaos {
        set("faults.chaos_rate", &mut || sc.faults.chaos_rate = v);
    }
    if let Some(v) = &a.chaos_at {
        set("faults.kill_at", &mut || sc.faults.kill_at = v.0.clone());
    }
    if let Some(v) = a.kill_fraction {
        set("faults.kill_fraction", &mut || sc.faults.kill_fraction = v);
    }
    if let Some(v) = a.tick_hz {
        set("runtime.tick_hz", &mut || sc.runtime.tick_hz = v);
    }
    if let Some(v) = a.realtime {
        set("runtime.realtime_hz", &mut || sc.runtime.realtime_hz = v);
    }
    if let Some(v) = &a.listen {
        set("hosts_listen", &mut || sc.hosts_listen = Some(v.clone()));
    }
    if a.record_deliveries {
        set("runtime.record_deliveries", &mut || {
            sc.runtime.record_deliveries = true
        });
    }
    if let Some(v) = a.max_restarts {
        set("faults.max_restarts", &mut || sc.faults.max_restarts = v);
    }
    if let Some(v) = a.on_fault {
        set("faults.on_fault", &mut || {
            sc.faults.on_fault = match v {
                OnFault::Drop => swarm::scenario::FaultPolicy::Drop,
                OnFault::Restart => swarm::scenario::FaultPolicy::Restart,
            }
        });
    }
    let key_source = |key: &str| {
        // A flag's key, or an entry of it (`faults.kill_at[3]` came from --chaos-at).
        let of = |k: &str| key == k || key.strip_prefix(k).is_some_and(|r| r.starts_with('['));
        FLAG_KEYS
            .iter()
            .find(|(k, _)| of(k) && from_flag.contains(k))
            .map(|(_, f)| f.to_string())
            .unwrap_or_else(|| file.clone())
    };
    crate::prepare::prepare(&mut sc, &key_source)?;
    if a.executor == Executor::Inprocess
        && sc.faults.on_fault == swarm::scenario::FaultPolicy::Restart
    {
        // Restart means a new agent process taking a robot over, fresh from its Sense frame;
        // in one process there is no agent process to die or replace, and rebuilding a
        // behaviour from its constructor inside the world's threads would be another fault
        // model than the one the processes executor runs. Refused rather than ignored.
        let key = "faults.on_fault";
        return Err(ConfigError {
            source: swarm::key_lines::locate(&key_source(key), key),
            key: key.into(),
            message: "= \"restart\" needs the processes executor (--executor inprocess was \
                      given): in one process there is no agent process to die and be \
                      replaced, a scheduled kill drops the robot; use --executor processes, \
                      or on_fault = \"drop\" (--on-fault drop)"
                .into(),
        });
    }
    if a.executor == Executor::Inprocess && !sc.agents.is_empty() {
        // The in-process executor runs the built-in behaviours on the world's threads; a
        // program of the user's is a process of its own.
        let key = "agents";
        return Err(ConfigError {
            source: swarm::key_lines::locate(&key_source(key), key),
            key: key.into(),
            message: format!(
                "lists {} program(s) of your own: they run as processes, which --executor \
                 inprocess does not start; use --executor processes (the default)",
                sc.agents.len()
            ),
        });
    }
    crate::agent_programs::check_found(&sc, &key_source)?;
    if a.executor == Executor::Inprocess && !sc.hosts.is_empty() {
        let key = "hosts";
        return Err(ConfigError {
            source: swarm::key_lines::locate(&key_source(key), key),
            key: key.into(),
            message: "places robots on other hosts, which needs the processes executor \
                      (--executor inprocess was given)"
                .into(),
        });
    }
    expand_kills(&mut sc);
    Ok(sc)
}

/// Writes every kill of the run into `faults.kill_at`, the random ones of `chaos_rate` and
/// `kill_fraction` included, and zeroes those two: the resolved scenario.toml then lists each
/// SIGKILL the run schedules (its comment says so) and gives the same schedule when read back
/// (`chaos::schedule` of the expanded file is the list itself).
pub fn expand_kills(sc: &mut Scenario) {
    sc.faults.kill_at = swarm::chaos::schedule(sc);
    sc.faults.chaos_rate = 0.0;
    sc.faults.kill_fraction = 0.0;
}

/// How long `up --view` goes on serving after the run, for the pages to get its last frames.
const VIEW_LAST_FRAMES: std::time::Duration = std::time::Duration::from_millis(300);

pub fn up(a: UpArgs) -> i32 {
    // First of all: a Ctrl-C at any moment is a clean stop, never the default death.
    signals::install();
    let sc = match resolve(&a) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::BAD_INPUT;
        }
    };
    if a.executor == Executor::Inprocess {
        if let Err(e) = inprocess::check(&sc) {
            eprintln!("error: --executor inprocess: {e}");
            return exit::BAD_INPUT;
        }
    }
    let fixed_id = match runid::from_env() {
        Ok(id) => id,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::BAD_INPUT;
        }
    };
    if a.executor == Executor::Processes {
        // Refused before anything starts, rather than EMFILE in the world after seconds.
        let (soft, _) = swarm::limits::raise_nofile();
        if let Err(e) = swarm::limits::check_fits(sc.run.robots, soft) {
            eprintln!("error: {e}");
            return exit::BAD_INPUT;
        }
    }
    if signals::interrupted() {
        eprintln!("error: {}", processes::INTERRUPTED_AT_START);
        return signals::exit_code();
    }
    // The registry must be this user's private folder (else nothing starts: another user
    // could have planted entries naming processes to kill).
    let cleaned = match clean::clean_dead_runs() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::FAILED;
        }
    };
    if cleaned.runs > 0 {
        eprintln!(
            "cleaned {} dead run(s) left by earlier orchestrators",
            cleaned.runs
        );
    }
    let run_id = fixed_id.unwrap_or_else(runid::new_run_id);
    if a.executor == Executor::Processes {
        if let Some(other) = registry::list()
            .into_iter()
            .find(|e| e.run_id == run_id && e.orchestrator_is_live())
        {
            eprintln!(
                "error: {}",
                registry::RegistryError::InUse {
                    run_id,
                    pid: other.orchestrator_pid
                }
            );
            return exit::BAD_INPUT;
        }
    }
    let run_dir = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs").join(&run_id));
    // The run folder is bad input like any other (exit 2), found before anything starts; a
    // full disk fails the run (exit 1). Held by this run alone until it ends.
    let what = if a.out.is_some() {
        "--out "
    } else {
        "run folder "
    };
    let _held = match outdir::open(&run_dir, what, &sc.to_toml()) {
        Ok(h) => h,
        Err(e) => {
            eprintln!("error: {e}");
            return e.exit_code();
        }
    };
    let live = if a.view {
        let kill: Option<std::sync::Arc<crate::view::server::KillFn>> =
            (a.executor == Executor::Processes).then(|| {
                let id = run_id.clone();
                std::sync::Arc::new(move |robot: u32| {
                    crate::control::kill_robots(&id, &[robot])
                        .map(|lines| lines.join("; "))
                        .map_err(|e| e.to_string())
                }) as std::sync::Arc<crate::view::server::KillFn>
            });
        match crate::view::live(&run_dir, a.view_port, kill) {
            Ok(l) => {
                println!("viewer: {}", l.viewer.url);
                use std::io::Write;
                let _ = std::io::stdout().flush();
                Some(l)
            }
            Err(e) => {
                eprintln!("error: --view-port: {e}");
                return exit::BAD_INPUT;
            }
        }
    } else {
        None
    };
    let bar = crate::progress::Bar::new(&sc, a.quiet);
    let realtime = sc.runtime.is_realtime();
    let result: Result<(), (i32, String)> = match a.executor {
        Executor::Inprocess => inprocess::run_live(
            &sc,
            Some(&run_dir),
            &run_id,
            cores(),
            &mut |w| {
                if w.tick % 16 == 0 {
                    let r = &w.radio;
                    bar.update(&crate::progress::BarStatus {
                        tick: w.tick,
                        progress: w.mission.progress(),
                        alive: w.alive_count(),
                        delivered: r.delivered,
                        dropped: r.dropped_range
                            + r.dropped_loss
                            + r.dropped_occluded
                            + r.dropped_bandwidth
                            + r.receiver_dead
                            + r.malformed,
                        misses: None,
                    });
                }
            },
            a.view,
            &signals::interrupted,
        )
        .map(|_| ())
        .map_err(|e| (exit::FAILED, e.to_string())),
        Executor::Processes => processes::run_typed(processes::ProcessRun {
            sc: &sc,
            run_id: &run_id,
            run_dir: &run_dir,
            on_status: &mut |s| {
                bar.update(&crate::progress::BarStatus {
                    tick: s.tick,
                    progress: (s.progress_done, s.progress_total),
                    alive: s.alive,
                    delivered: s.delivered,
                    dropped: s.dropped_range + s.dropped_loss + s.dropped_other,
                    misses: realtime.then_some(s.deadline_misses),
                });
            },
            live: a.view,
        })
        .map_err(|e| match e {
            processes::RunError::InterruptedAtStart => (signals::exit_code(), e.to_string()),
            processes::RunError::Registry(registry::RegistryError::InUse { .. }) => {
                (exit::BAD_INPUT, e.to_string())
            }
            e => (exit::FAILED, e.to_string()),
        })
        .and_then(|o| match (o.failed_robot, o.world_exit) {
            // A program that refused its input (its params: exit 2, the agent SDK's bad
            // input) is bad input of this run too.
            (Some(f), _) if f.exit_code == Some(swarm::agent::EXIT_BAD_INPUT) => {
                Err((exit::BAD_INPUT, f.to_string()))
            }
            (Some(f), _) => Err((exit::FAILED, f.to_string())),
            (None, Ok(0)) => Ok(()),
            (None, Ok(c)) => Err((
                exit::FAILED,
                format!("the world process failed with exit code {c}"),
            )),
            (None, Err(sig)) if sig == libc::SIGBUS => Err((
                exit::FAILED,
                format!(
                    "the world process was killed by signal {sig} (SIGBUS: a shared segment of \
                     the run was truncated under it; docs/protocol.md section 4)"
                ),
            )),
            (None, Err(sig)) => Err((
                exit::FAILED,
                format!("the world process was killed by signal {sig}"),
            )),
        }),
    };
    bar.clear();
    if let Some(l) = &live {
        // The follower reads the last bytes, the open pages get them and the stream's end;
        // a page keeps every frame it got, to scrub after the run.
        l.feed.end();
        std::thread::sleep(VIEW_LAST_FRAMES);
        l.viewer.stop();
    }
    if let Err((code, e)) = result {
        // Ctrl-C before the first tick: the shell's code for an interrupted command.
        eprintln!("error: run {run_id}: {e}");
        return code;
    }
    match std::fs::read_to_string(run_dir.join("summary.json")) {
        Ok(s) => {
            let v: serde_json::Value = serde_json::from_str(&s).unwrap_or_default();
            let program = std::env::args()
                .next()
                .unwrap_or_else(|| "orchestrator".into());
            crate::summary::print(&v, &run_dir, &program);
            outcome::exit_code(&v)
        }
        Err(e) => {
            eprintln!("error: run {run_id}: no summary.json: {e}");
            exit::FAILED
        }
    }
}

/// Worker threads of a single in-process run: the machine's cores.
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expanded_kills_list_every_kill_and_schedule_the_same() {
        let mut sc = Scenario::default();
        sc.run.robots = 20;
        sc.faults.kill_at = vec![[7, 3]];
        sc.faults.chaos_rate = 2.0;
        sc.faults.kill_fraction = 0.25;
        // Under restart a robot can be killed again (under drop at most once each).
        sc.faults.on_fault = swarm::scenario::FaultPolicy::Restart;
        let all = swarm::chaos::schedule(&sc);
        // 1 explicit + ~60 random (2 per 100 ticks over 3,000) + 5 of the fraction.
        assert!(all.len() > 30, "{all:?}");
        expand_kills(&mut sc);
        assert_eq!(sc.faults.kill_at, all);
        assert_eq!(swarm::chaos::schedule(&sc), all);
        let back = Scenario::parse(&sc.to_toml(), "resolved").unwrap();
        assert_eq!(swarm::chaos::schedule(&back), all);
    }
}
