//! `orchestrator bench restart`: restart latency under `--on-fault restart` (issue 14 item 3),
//! from the SIGKILL of one agent to its replacement's first acknowledged tick.
//!
//! A real run (processes executor, configs/roam.toml's scenario, unpaced): after a warm-up this
//! process SIGKILLs one agent (pid from the run registry); a watcher thread polls the tick
//! barrier (every 0.1 ms) until the robot has a new agent (attach count up) that acknowledged
//! a tick (its ack word moved): that instant is the latency. The orchestrator's supervision
//! loop (which calls this bench back) is busy in the port cleanup meanwhile, so the watcher
//! does not depend on it. Then the run settles and the next agent is killed. Also timed: the
//! cleanup of the dead agent's iceoryx2 ports (`processes::last_cleanup_us`).

use crate::{processes, registry, signals};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use swarm::frames::WorldStatus;
use swarm::scenario::{FaultPolicy, Scenario};
use swarm::{cleanup, transport};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Robots.
    #[arg(long, default_value_t = 50)]
    robots: u32,
    /// Agents killed, one at a time.
    #[arg(long, default_value_t = 10)]
    kills: u32,
    /// Also write the figures as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Ticks before the first kill (every radio link made) and between a restart and the next kill.
const SETTLE_TICKS: u64 = 200;
/// A restart slower than this is reported as a failure.
const RESTART_LIMIT: Duration = Duration::from_secs(20);

#[derive(Debug, Clone, Serialize, Default)]
pub struct Report {
    pub robots: u32,
    /// SIGKILL -> the replacement's first acknowledged tick, ms, one per kill.
    pub latency_ms: Vec<f64>,
    /// The orchestrator's port cleanup of each restart, ms.
    pub cleanup_ms: Vec<f64>,
    /// Ticks the swarm ran from the kill until the supervision loop saw the restart (it is
    /// busy cleaning meanwhile, so this is an upper bound), one per kill.
    pub ticks_away: Vec<u64>,
}

enum Phase {
    Settle {
        until: u64,
    },
    Away {
        since: Instant,
        tick: u64,
        restarted: u32,
    },
}

/// What the watcher waits for: robot, its ack word and attach count at the kill, the kill's
/// instant; it answers with the latency.
type Watch = Arc<Mutex<(Option<(u32, u64, u64, Instant)>, Option<Duration>)>>;

/// Polls the barrier until the watched robot's replacement acknowledged a tick.
fn watcher(watch: Watch, done: Arc<AtomicBool>) {
    let mut barrier = None;
    while !done.load(Ordering::Acquire) {
        std::thread::sleep(Duration::from_micros(100));
        let mut w = watch.lock().expect("lock");
        let Some((robot, ack0, attach0, since)) = w.0 else {
            continue;
        };
        if barrier.is_none() {
            barrier = processes::supervised_barrier();
        }
        let Some(b) = &barrier else {
            continue;
        };
        if b.attach_count(robot) > attach0 && b.acked_up_to(robot) > ack0 {
            *w = (None, Some(since.elapsed()));
        }
    }
}

pub fn bench(a: Args) -> i32 {
    match run(&a) {
        Ok(r) => {
            print(&r);
            if let Some(p) = &a.json {
                if let Err(e) = std::fs::write(p, serde_json::to_string_pretty(&r).expect("json")) {
                    eprintln!("error: {}: {e}", p.display());
                    return 1;
                }
            }
            0
        }
        Err(e) => {
            eprintln!("error: bench restart: {e}");
            1
        }
    }
}

fn run(a: &Args) -> Result<Report, String> {
    let mut sc = Scenario::roam();
    sc.run.robots = a.robots;
    sc.run.max_ticks = 100_000_000;
    sc.faults.on_fault = FaultPolicy::Restart;
    sc.faults.max_restarts = a.kills + 1;
    sc.validate(&|_| "bench".into())
        .map_err(|e| e.to_string())?;
    let run_id = crate::runid::new_run_id();
    let prefix = transport::prefix_for(&run_id);
    let dir = std::env::temp_dir().join(format!("swarm-bench-restart-{run_id}"));
    let mut report = Report {
        robots: a.robots,
        ..Default::default()
    };
    let mut phase = Phase::Settle {
        until: SETTLE_TICKS,
    };
    let mut error: Option<String> = None;
    let mut kills = 0;
    let watch: Watch = Arc::default();
    let done = Arc::new(AtomicBool::new(false));
    let w = {
        let (w, d) = (watch.clone(), done.clone());
        std::thread::spawn(move || watcher(w, d))
    };
    let mut barrier: Option<std::sync::Arc<swarm::barrier::TickBarrier>> = None;
    let out = processes::run(processes::ProcessRun {
        sc: &sc,
        run_id: &run_id,
        run_dir: &dir,
        live: false,
        on_status: &mut |st: &WorldStatus| match phase {
            Phase::Settle { until } if st.tick >= until && !signals::interrupted() => {
                if kills == a.kills {
                    signals::request_stop();
                    return;
                }
                let robot = (kills * 7 + 3) % a.robots;
                let pid = registry::list()
                    .into_iter()
                    .find(|e| e.run_id == run_id)
                    .and_then(|e| e.agent_pids.get(robot as usize).copied());
                let Some(pid) = pid else {
                    error = Some("the run is not in the registry".into());
                    signals::request_stop();
                    return;
                };
                if barrier.is_none() {
                    barrier = processes::supervised_barrier();
                }
                let Some(b) = &barrier else {
                    return;
                };
                *watch.lock().expect("lock") = (
                    Some((
                        robot,
                        b.acked_up_to(robot),
                        b.attach_count(robot),
                        Instant::now(),
                    )),
                    None,
                );
                // SAFETY: SIGKILL of an agent of the run this process supervises.
                unsafe { libc::kill(pid as i32, libc::SIGKILL) };
                kills += 1;
                phase = Phase::Away {
                    since: Instant::now(),
                    tick: st.tick,
                    restarted: st.restarted,
                };
            }
            Phase::Away {
                since,
                tick,
                restarted,
            } => {
                if st.restarted > restarted {
                    let lat = watch.lock().expect("lock").1.unwrap_or(since.elapsed());
                    report.latency_ms.push(lat.as_secs_f64() * 1e3);
                    report
                        .cleanup_ms
                        .push(processes::last_cleanup_us() as f64 / 1e3);
                    report.ticks_away.push(st.tick - tick);
                    phase = Phase::Settle {
                        until: st.tick + SETTLE_TICKS,
                    };
                } else if since.elapsed() > RESTART_LIMIT && error.is_none() {
                    error = Some(format!("no restart within {RESTART_LIMIT:?}"));
                    signals::request_stop();
                }
            }
            _ => {}
        },
    });
    done.store(true, Ordering::Release);
    let _ = w.join();
    drop(barrier);
    signals::clear();
    let _ = std::fs::remove_dir_all(&dir);
    cleanup::remove_run(&prefix);
    super::check_no_leftovers(&prefix)?;
    out?;
    match error {
        Some(e) => Err(e),
        None => Ok(report),
    }
}

fn print(r: &Report) {
    let stats = |v: &[f64]| {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        let q = |p: f64| s[((s.len() - 1) as f64 * p).round() as usize];
        (q(0.0), q(0.5), q(1.0))
    };
    println!(
        "restart latency at N = {} (unpaced roam, SIGKILL -> the replacement's first tick), {} kills",
        r.robots,
        r.latency_ms.len()
    );
    if r.latency_ms.is_empty() {
        return;
    }
    let (a, b, c) = stats(&r.latency_ms);
    println!("  latency  min {a:.1} ms  median {b:.1} ms  max {c:.1} ms");
    let (a, b, c) = stats(&r.cleanup_ms);
    println!("  port cleanup (after the spawn, off the critical path)  min {a:.1} ms  median {b:.1} ms  max {c:.1} ms");
    let t: Vec<f64> = r.ticks_away.iter().map(|&t| t as f64).collect();
    let (a, b, c) = stats(&t);
    println!(
        "  ticks until the supervisor saw it (upper bound)  min {a:.0}  median {b:.0}  max {c:.0}"
    );
}
