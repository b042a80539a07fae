//! `orchestrator bench tick`: the runtime's lock-step tick next to a raw iceoryx2 round and the
//! futex floor, all measured in the same run on the same machine.
//!
//! - runtime: `up` with the roam scenario (configs/roam.toml: every robot broadcasts its position
//!   every tick, all within range at the start), processes executor, N robots, T ticks;
//! - iox2 round: N child processes; per round 1 notify to N listeners, N notifications back,
//!   no work (the spec's Appendix A harness);
//! - futex floor: N child processes released by one futex word (one FUTEX_WAKE for all) and
//!   counting themselves back through the same `TickBarrier` the runtime uses, no work.

use super::{BenchError, BenchResult, ChildArgs};
use crate::processes;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use serde::Serialize;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use swarm::barrier::{BarrierFds, TickBarrier, Wake};
use swarm::cleanup;
use swarm::scenario::{ActsKind, BarrierKind, Scenario};
use swarm::transport::{self, EventCapacity, Reach, ServiceId, TransportError};
use world::output::percentile;

#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub robots: u32,
    /// Ticks (rounds) measured for this size.
    pub ticks: u64,
    pub runtime_ticks_per_s: f64,
    pub runtime_p50_us: f64,
    pub runtime_p99_us: f64,
    /// The runtime with `runtime.barrier = "iox2-event"`.
    pub runtime_ev_ticks_per_s: f64,
    pub runtime_ev_p50_us: f64,
    /// The runtime with `runtime.acts = "pub-sub"` (the same run but the act path: one
    /// iceoryx2 publish-subscribe service a robot instead of the default blackboard).
    pub runtime_ps_ticks_per_s: f64,
    pub runtime_ps_p50_us: f64,
    /// The runtime on the embedded default scenario (search, mode BT) run until every target
    /// is found (or `ticks`): how many ticks that took, ticks per second, p50. None above
    /// SEARCH_MAX_ROBOTS.
    pub search_ticks: Option<u64>,
    pub search_ticks_per_s: Option<f64>,
    pub search_p50_us: Option<f64>,
    pub iox2_rounds_per_s: f64,
    pub iox2_p50_us: f64,
    pub iox2_p99_us: f64,
    pub futex_rounds_per_s: f64,
    pub futex_p50_us: f64,
    pub futex_p99_us: f64,
}

pub(super) struct Stats {
    pub per_s: f64,
    pub p50_us: f64,
    pub p99_us: f64,
    /// Spawn to every agent attached (a run's summary.json; 0 where not measured).
    pub startup_s: f64,
}

fn stats(mut ns: Vec<u64>) -> Stats {
    let total: u64 = ns.iter().sum();
    ns.sort_unstable();
    Stats {
        per_s: ns.len() as f64 / (total as f64 / 1e9),
        p50_us: percentile(&ns, 0.5) / 1e3,
        p99_us: percentile(&ns, 0.99) / 1e3,
        startup_s: 0.0,
    }
}

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.0}")).unwrap_or_else(|| "-".into())
}

pub fn print_table(rows: &[Row]) {
    println!("lock-step tick (roam scenario, configs/roam.toml, for the runtime; no work for the others)");
    println!(
        "{:>6} {:>6} | {:>10} {:>8} {:>8} | {:>10} {:>8} | {:>10} {:>8} {:>7} | {:>6} {:>9} {:>8} | {:>10} {:>8} {:>8} | {:>10} {:>8} {:>8} | {:>9} {:>9}",
        "robots",
        "ticks",
        "runtime/s",
        "p50 us",
        "p99 us",
        "rt-ev/s",
        "p50 us",
        "rt-ps/s",
        "p50 us",
        "rt/ps",
        "ticks",
        "search/s",
        "p50 us",
        "iox2 rd/s",
        "p50 us",
        "p99 us",
        "futex rd/s",
        "p50 us",
        "p99 us",
        "rt/iox2",
        "rt/futex"
    );
    for r in rows {
        println!(
            "{:>6} {:>6} | {:>10.0} {:>8.0} {:>8.0} | {:>10.0} {:>8.0} | {:>10.0} {:>8.0} {:>6.2}x | {:>6} {:>9} {:>8} | {:>10.0} {:>8.0} {:>8.0} | {:>10.0} {:>8.0} {:>8.0} | {:>8.2}x {:>8.2}x",
            r.robots,
            r.ticks,
            r.runtime_ticks_per_s,
            r.runtime_p50_us,
            r.runtime_p99_us,
            r.runtime_ev_ticks_per_s,
            r.runtime_ev_p50_us,
            r.runtime_ps_ticks_per_s,
            r.runtime_ps_p50_us,
            r.runtime_ticks_per_s / r.runtime_ps_ticks_per_s,
            opt(r.search_ticks.map(|t| t as f64)),
            opt(r.search_ticks_per_s),
            opt(r.search_p50_us),
            r.iox2_rounds_per_s,
            r.iox2_p50_us,
            r.iox2_p99_us,
            r.futex_rounds_per_s,
            r.futex_p50_us,
            r.futex_p99_us,
            r.iox2_rounds_per_s / r.runtime_ticks_per_s,
            r.futex_rounds_per_s / r.runtime_ticks_per_s,
        );
    }
    println!("runtime = the runtime with its default futex barrier, the Sense frames, the air and the actions through their iceoryx2 services (world/sense, radio/air, and runtime.acts = \"blackboard\": robot/<i>/board); rt-ev = the same with runtime.barrier = \"iox2-event\"; rt-ps = with runtime.acts = \"pub-sub\" (robot/<i>/act services, the default), rt/ps = runtime's ticks/s over rt-ps's.");
    println!("search = the runtime on the default scenario (search BT, futex barrier) until every target is found: ticks run, ticks/s, p50.");
    println!("rt/iox2 = runtime tick time / raw iceoryx2 round time (mean); below 1 means faster than the raw round.");
}

/// Ticks measured at size `n`: `ticks` up to 100 robots, then fewer in proportion (at least
/// 100), so that 200 and 500 robots, whose runtime ticks take tens or hundreds of
/// milliseconds, finish in a minute or two.
pub fn ticks_for(n: u32, ticks: u64) -> u64 {
    if n <= 100 {
        ticks
    } else {
        (ticks * 100 / n as u64).max(100).min(ticks)
    }
}

pub fn bench_tick(sizes: &[u32], ticks: u64) -> BenchResult<Vec<Row>> {
    let mut rows = Vec::new();
    for &n in sizes {
        let ticks = ticks_for(n, ticks);
        let rt = runtime(n, ticks, BarrierKind::Futex, ActsKind::Blackboard)?;
        let rt_ev = runtime(n, ticks, BarrierKind::Iox2Event, ActsKind::Blackboard)?;
        let rt_ps = runtime(n, ticks, BarrierKind::Futex, ActsKind::PubSub)?;
        let search = if n <= SEARCH_MAX_ROBOTS {
            let mut sc = Scenario::default();
            sc.run.robots = n;
            sc.run.max_ticks = ticks;
            crate::prepare::prepare_from(&mut sc, "bench tick")?;
            Some(run_stats(&sc)?)
        } else {
            None
        };
        let iox = raw_iox2(n, ticks)?;
        let fx = futex_floor(n, ticks)?;
        rows.push(Row {
            robots: n,
            ticks,
            runtime_ticks_per_s: rt.per_s,
            runtime_p50_us: rt.p50_us,
            runtime_p99_us: rt.p99_us,
            runtime_ev_ticks_per_s: rt_ev.per_s,
            runtime_ev_p50_us: rt_ev.p50_us,
            runtime_ps_ticks_per_s: rt_ps.per_s,
            runtime_ps_p50_us: rt_ps.p50_us,
            search_ticks: search.as_ref().map(|s| s.0),
            search_ticks_per_s: search.as_ref().map(|s| s.1.per_s),
            search_p50_us: search.as_ref().map(|s| s.1.p50_us),
            iox2_rounds_per_s: iox.per_s,
            iox2_p50_us: iox.p50_us,
            iox2_p99_us: iox.p99_us,
            futex_rounds_per_s: fx.per_s,
            futex_p50_us: fx.p50_us,
            futex_p99_us: fx.p99_us,
        });
    }
    Ok(rows)
}

/// The search run of the table stops at this swarm size (its behaviour's per-robot work grows
/// with the robots in range, and 500 would take many minutes here).
const SEARCH_MAX_ROBOTS: u32 = 200;

/// The runtime itself: the roam scenario with N robots for `ticks` ticks (+ warm-up).
fn runtime(n: u32, ticks: u64, barrier: BarrierKind, acts: ActsKind) -> BenchResult<Stats> {
    let mut sc = Scenario::roam();
    sc.run.robots = n;
    sc.runtime.barrier = barrier;
    sc.runtime.acts = acts;
    let warmup = (ticks / 20).max(10);
    sc.run.max_ticks = ticks + warmup;
    run_stats(&sc).map(|(_, s)| s)
}

/// Runs `sc` with the processes executor: the ticks it ran and its steady tick statistics.
pub(super) fn run_stats(sc: &Scenario) -> BenchResult<(u64, Stats)> {
    let (s, dir) = run_processes(sc)?;
    let _ = std::fs::remove_dir_all(&dir);
    Ok((
        s["ticks"].as_u64().unwrap_or(0),
        Stats {
            per_s: s["steady_ticks_per_second"].as_f64().unwrap_or(0.0),
            p50_us: s["tick_time"]["p50_us"].as_f64().unwrap_or(0.0),
            p99_us: s["tick_time"]["p99_us"].as_f64().unwrap_or(0.0),
            startup_s: s["startup_seconds"].as_f64().unwrap_or(0.0),
        },
    ))
}

/// Runs `sc` with the processes executor into a temporary run folder: its summary.json, and
/// the folder (the caller removes it).
pub(super) fn run_processes(sc: &Scenario) -> BenchResult<(serde_json::Value, std::path::PathBuf)> {
    sc.validate(&|_| "bench".into())?;
    let run_id = crate::runid::new_run_id();
    let dir = std::env::temp_dir().join(format!("swarm-bench-{run_id}"));
    let out = processes::run(processes::ProcessRun {
        sc,
        run_id: &run_id,
        run_dir: &dir,
        live: false,
        on_status: &mut |_| {},
    })
    .map_err(BenchError::Run)?;
    if out.world_exit != Ok(0) {
        return Err(BenchError::WorldExit(out.world_exit));
    }
    Ok((read_summary(&dir)?, dir))
}

/// The summary.json of the run folder `dir`.
pub(super) fn read_summary(dir: &std::path::Path) -> BenchResult<serde_json::Value> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|source| BenchError::File {
        path: path.clone(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|source| BenchError::Json { path, source })
}

fn spawn_children(
    kind: &str,
    prefix: &str,
    n: u32,
    barrier: Option<&BarrierFds>,
) -> BenchResult<Vec<Child>> {
    let spawn_error = |source| BenchError::Spawn {
        kind: kind.to_string(),
        source,
    };
    let exe = std::env::current_exe().map_err(spawn_error)?;
    (0..n)
        .map(|i| {
            let mut cmd = Command::new(&exe);
            if let Some(b) = barrier {
                b.pass_to(&mut cmd);
            }
            cmd.args([
                "__bench-child",
                kind,
                "--prefix",
                prefix,
                "--index",
                &i.to_string(),
            ])
            .stdin(Stdio::null())
            .process_group(0)
            .spawn()
            .map_err(spawn_error)
        })
        .collect()
}

use std::os::unix::process::CommandExt;

pub(super) fn reap_children(children: Vec<Child>) {
    for mut c in children {
        let t = Instant::now();
        while c.try_wait().ok().flatten().is_none() {
            if t.elapsed() > Duration::from_secs(2) {
                let _ = c.kill();
                let _ = c.wait();
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

pub(super) fn bench_prefix(kind: &str) -> String {
    transport::prefix_for(&format!("bench-{kind}-{}", crate::runid::new_run_id()))
}

/// The raw round's two event services: the parent rings `bench/down` for all children, each
/// child rings `bench/up` back.
const DOWN: &str = "bench/down";
const UP: &str = "bench/up";

fn iox2_services(
    node: &Node<ipc::Service>,
    n: usize,
) -> BenchResult<(transport::EventService, transport::EventService)> {
    let down = transport::event(
        node,
        ServiceId::from(DOWN),
        Reach::Create(EventCapacity {
            listeners: n + 2,
            notifiers: 2,
            nodes: n + 4,
        }),
    )?;
    let up = transport::event(
        node,
        ServiceId::from(UP),
        Reach::Create(EventCapacity {
            listeners: 2,
            notifiers: n + 2,
            nodes: n + 4,
        }),
    )?;
    Ok((down, up))
}

fn notifier(svc: &transport::EventService) -> Result<Notifier<ipc::Service>, TransportError> {
    svc.notifier_builder()
        .create()
        .map_err(|source| TransportError::Notifier {
            service: ServiceId::of(svc),
            source,
        })
}

fn listener(svc: &transport::EventService) -> Result<Listener<ipc::Service>, TransportError> {
    svc.listener_builder()
        .create()
        .map_err(|source| TransportError::Listener {
            service: ServiceId::of(svc),
            source,
        })
}

/// Waits for events on `listener` (of `svc`) up to `timeout`, calling `each` per activation.
fn wait(
    svc: &transport::EventService,
    listener: &Listener<ipc::Service>,
    each: impl FnMut(iceoryx2::port::EventActivation),
    timeout: Duration,
) -> Result<u64, TransportError> {
    listener
        .timed_wait(each, timeout)
        .map_err(|source| TransportError::Wait {
            service: ServiceId::of(svc),
            source,
        })
}

fn notify(svc: &transport::EventService, n: &Notifier<ipc::Service>) -> Result<(), TransportError> {
    n.notify()
        .map(|_| ())
        .map_err(|source| TransportError::Notify {
            service: ServiceId::of(svc),
            source,
        })
}

/// Seconds the bench children of the raw round and the futex floor have to attach.
const ATTACH_S: u64 = 60;

/// 1 notify to N listeners, N notifications back.
fn raw_iox2(n: u32, rounds: u64) -> BenchResult<Stats> {
    let prefix = bench_prefix("iox2");
    let result = (|| {
        let config = transport::run_config(&prefix)?;
        let node = transport::node(&config, "bench-parent")?;
        let (down, up) = iox2_services(&node, n as usize)?;
        let notifier = notifier(&down)?;
        let listener = listener(&up)?;
        let children = spawn_children("iox2", &prefix, n, None)?;
        let t = Instant::now();
        while up.dynamic_config().number_of_notifiers() < n as usize {
            if t.elapsed() > Duration::from_secs(ATTACH_S) {
                return Err(BenchError::ChildNotReady {
                    kind: "iox2".into(),
                    seconds: ATTACH_S,
                });
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let mut ns = Vec::with_capacity(rounds as usize);
        let warm = (rounds / 20).max(10);
        for r in 0..rounds + warm {
            let t = Instant::now();
            notify(&down, &notifier)?;
            let mut got = 0u64;
            while got < n as u64 {
                wait(&up, &listener, |ev| got += ev.count, Duration::from_secs(5))?;
            }
            if r >= warm {
                ns.push(t.elapsed().as_nanos() as u64);
            }
        }
        drop(notifier);
        reap_children(children);
        Ok(stats(ns))
    })();
    cleanup::remove_run(&prefix);
    result
}

/// N processes released by one futex word and counting themselves back.
fn futex_floor(n: u32, rounds: u64) -> BenchResult<Stats> {
    let prefix = bench_prefix("futex");
    let result = (|| {
        let (b, fds) = TickBarrier::create(&prefix, n)?;
        let children = spawn_children("futex", &prefix, n, Some(&fds))?;
        let t = Instant::now();
        while b.ready_count() < n {
            if t.elapsed() > Duration::from_secs(ATTACH_S) {
                return Err(BenchError::ChildNotReady {
                    kind: "futex".into(),
                    seconds: ATTACH_S,
                });
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let mut ns = Vec::with_capacity(rounds as usize);
        let warm = (rounds / 20).max(10);
        for k in 0..rounds + warm {
            let t = Instant::now();
            b.release(k, n);
            while !(0..n).all(|i| b.acked(i, k)) {
                b.wait_acks(Duration::from_secs(5));
            }
            if k >= warm {
                ns.push(t.elapsed().as_nanos() as u64);
            }
        }
        b.shutdown();
        reap_children(children);
        Ok(stats(ns))
    })();
    cleanup::remove_run(&prefix);
    result
}

/// A benchmark child of `bench tick`: does no work, only takes part in the rounds.
pub fn child(a: &ChildArgs) -> i32 {
    match a.kind.as_str() {
        "futex" => {
            let Ok(b) = TickBarrier::open_inherited() else {
                return 1;
            };
            b.mark_ready(a.index);
            let mut done = 0;
            loop {
                match b.wait_release(done, Duration::from_millis(500)) {
                    Wake::Tick(k) => {
                        b.ack(a.index, k);
                        done = k + 1;
                    }
                    Wake::Shutdown => return 0,
                    Wake::Timeout => {}
                }
            }
        }
        "iox2" => {
            let run = || -> BenchResult<()> {
                let config = transport::run_config(&a.prefix)?;
                let node = transport::node(&config, &format!("bench-{}", a.index))?;
                let down = transport::event(&node, ServiceId::from(DOWN), Reach::Open)?;
                let up = transport::event(&node, ServiceId::from(UP), Reach::Open)?;
                let listener = listener(&down)?;
                // The reply notifier last: the parent counts notifiers to know we are ready.
                let notifier = notifier(&up)?;
                loop {
                    let mut k = 0u64;
                    wait(
                        &down,
                        &listener,
                        |ev| k += ev.count,
                        Duration::from_millis(500),
                    )?;
                    if k == 0 {
                        // No round for a while: is the service still there (parent alive)?
                        if down.dynamic_config().number_of_notifiers() == 0 {
                            return Ok(());
                        }
                    }
                    for _ in 0..k {
                        notify(&up, &notifier)?;
                    }
                }
            };
            match run() {
                Ok(()) => 0,
                Err(e) => {
                    eprintln!("bench child {}: {e}", a.index);
                    1
                }
            }
        }
        other => {
            eprintln!("unknown bench child kind {other:?}: allowed iox2, futex");
            2
        }
    }
}
