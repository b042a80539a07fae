//! Real-time mode (`orchestrator up --realtime HZ`) with real processes: the world ticks on
//! its clock while an agent is stopped (SIGSTOP), counts that robot's misses, keeps its last
//! command, and still applies the ack deadline to a robot silent for too long. Judged by
//! counts from summary.json and recording.bin, never by timings.

use e2e::*;
use std::path::Path;
use std::time::{Duration, Instant};
use swarm::recording::{read_recording, Event, TickRecord};

/// Ticks the world must make while the agent is stopped.
const STOPPED_TICKS: u64 = 25;

fn signal(pid: i32, sig: i32) {
    // SAFETY: a signal to an agent process of this test's own run (its pid from the run's
    // registry entry).
    assert_eq!(unsafe { libc::kill(pid, sig) }, 0);
}

/// Waits until the run writing to `out` is at tick `tick` or beyond.
fn wait_for_tick(out: &Path, tick: u64) -> u64 {
    let t = Instant::now();
    loop {
        let now = registry_tick(out);
        if now >= tick {
            return now;
        }
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "the run stayed at tick {now}, below {tick}"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// configs/roam.toml with the tables of `more` added, as a file in `dir` (created).
fn roam_with(dir: &Path, more: &str) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join("roam.toml");
    let roam_text = std::fs::read_to_string(roam()).unwrap();
    std::fs::write(&file, format!("{roam_text}\n{more}")).unwrap();
    file
}

fn recording(out: &Path) -> (String, Vec<TickRecord>) {
    let (h, ticks) = read_recording(std::fs::File::open(out.join("recording.bin")).unwrap())
        .expect("recording.bin");
    (h.scenario, ticks)
}

/// The ticks at which robot `r` missed its deadline, from the recording's events.
fn missed_ticks(ticks: &[TickRecord], r: u32) -> Vec<u64> {
    ticks
        .iter()
        .filter(|t| t.events.contains(&Event::DeadlineMissed { robot: r }))
        .map(|t| t.tick)
        .collect()
}

/// The longest run of consecutive ticks in `ticks` (sorted): (first tick, length).
fn longest_streak(ticks: &[u64]) -> (u64, u64) {
    let mut best = (0, 0);
    let mut i = 0;
    while i < ticks.len() {
        let mut j = i;
        while j + 1 < ticks.len() && ticks[j + 1] == ticks[j] + 1 {
            j += 1;
        }
        let len = (j - i + 1) as u64;
        if len > best.1 {
            best = (ticks[i], len);
        }
        i = j + 1;
    }
    best
}

#[test]
fn a_stopped_agent_misses_ticks_alone_while_the_world_keeps_its_clock() {
    let _g = serial();
    let dir = tmp_dir("rt-sigstop");
    // Roam, slowly (1 unit a tick), so that no wall stops robot 2 while it misses.
    let file = roam_with(&dir, "[robot]\nv_max = 1.0\n");
    let out = dir.join("run");
    let child = spawn_up(
        &[
            "--scenario",
            file.to_str().unwrap(),
            "--robots",
            "4",
            "--max-ticks",
            "400",
            "--realtime",
            "100",
        ],
        &out,
    );
    let pid = registry_entry(&out, 4)["agent_pids"][2].as_u64().unwrap() as i32;
    let at = wait_for_tick(&out, 100);
    signal(pid, libc::SIGSTOP);
    // The world goes on ticking without robot 2: counted, not timed.
    wait_for_tick(&out, at + STOPPED_TICKS + 5);
    signal(pid, libc::SIGCONT);
    let o = child.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["ticks"], 400, "{s}");
    assert_eq!(s["alive_at_end"], 4, "no one was declared dead: {s}");
    let rt = &s["realtime"];
    assert_eq!(rt["hz"], 100.0);
    let per: Vec<u64> = rt["misses_per_robot"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    assert_eq!(per.len(), 4);
    assert_eq!(
        rt["deadline_misses"].as_u64().unwrap(),
        per.iter().sum::<u64>()
    );
    assert!(per[2] >= STOPPED_TICKS, "robot 2 missed {per:?}");

    let (scenario, ticks) = recording(&out);
    assert!(
        scenario.contains("realtime_hz = 100"),
        "the recording names the mode"
    );
    assert_eq!(ticks.len(), 400);
    let mut streaks = Vec::new();
    for r in 0..4 {
        let missed = missed_ticks(&ticks, r);
        assert_eq!(
            missed.len() as u64,
            per[r as usize],
            "robot {r}: events = summary"
        );
        streaks.push(longest_streak(&missed));
    }
    // Robot 2 missed every tick while it was stopped, in a row. The others, running, may
    // miss too when the whole machine stalls (2 cores shared with other work: all robots
    // then miss the same few ticks), but no run of ticks like robot 2's, and robot 2 alone
    // missed most of its streak.
    let (first, len) = streaks[2];
    assert!(len >= STOPPED_TICKS, "robot 2's streak {streaks:?}");
    for (r, s) in streaks.iter().enumerate() {
        if r != 2 {
            assert!(s.1 < len / 2, "robot {r}: {streaks:?} {per:?}");
        }
    }
    let others: std::collections::BTreeSet<u64> = [0, 1, 3]
        .iter()
        .flat_map(|&r| missed_ticks(&ticks, r))
        .collect();
    let alone = (first..first + len).filter(|t| !others.contains(t)).count() as u64;
    assert!(
        alone >= STOPPED_TICKS / 2,
        "robot 2 alone at {alone} of {len}"
    );
    // While it missed, robot 2 kept its last command: the same step every tick (roam is
    // holonomic: a step is the command), unless a wall or obstacle blocked it.
    let step = |t: u64| {
        let (a, b) = (ticks[t as usize - 1].poses[2], ticks[t as usize].poses[2]);
        [b[0] - a[0], b[1] - a[1]]
    };
    let before = step(first - 1);
    let blocked = |t: u64| {
        ticks[t as usize]
            .events
            .contains(&Event::MoveBlocked { robot: 2 })
    };
    let kept = (first..first + len)
        .filter(|&t| !blocked(t))
        .collect::<Vec<_>>();
    assert!(kept.len() as u64 > len / 2, "mostly unblocked");
    // (Steps are differences of positions: equal up to rounding.)
    for t in kept {
        let d = step(t);
        assert!(
            (d[0] - before[0]).abs() < 1e-9 && (d[1] - before[1]).abs() < 1e-9,
            "tick {t}: step {d:?}, the last command's {before:?}"
        );
    }
    assert!(before != [0.0, 0.0], "roam robots move");
    // The radio's books balance at every tick, misses included.
    let mut total = swarm::radio::RadioCounters::default();
    for t in &ticks {
        total.add(&t.radio);
        assert_eq!(total.offered, total.accounted(), "tick {}", t.tick);
    }
    assert_left_nothing(&out);
}

#[test]
fn an_agent_stopped_past_the_ack_deadline_is_declared_dead_while_the_clock_runs() {
    let _g = serial();
    let dir = tmp_dir("rt-deadline");
    // The roam scenario with a short ack deadline (ms).
    let file = roam_with(&dir, "[runtime]\nack_deadline_ms = 300\n");
    let out = dir.join("run");
    let child = spawn_up(
        &[
            "--scenario",
            file.to_str().unwrap(),
            "--robots",
            "3",
            "--max-ticks",
            "100000",
            "--realtime",
            "100",
        ],
        &out,
    );
    let pid = registry_entry(&out, 3)["agent_pids"][1].as_u64().unwrap() as i32;
    wait_for_tick(&out, 20);
    signal(pid, libc::SIGSTOP);
    // Declared dead (the world orders its SIGKILL, which ends a stopped process too): the
    // registry's dead count says so.
    let t = Instant::now();
    loop {
        let e = registry_entry(&out, 3);
        if e["dead"].as_u64() == Some(1) {
            break;
        }
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "never declared dead: {e}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // SAFETY: SIGINT to this test's own orchestrator: the clean stop.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    let s = summary(&out);
    let faults = s["faults"].as_array().unwrap();
    assert_eq!(faults.len(), 1, "{faults:?}");
    assert_eq!(faults[0]["robot"], 1);
    assert_eq!(
        faults[0]["cause"],
        "no action within runtime.ack_deadline_ms"
    );
    // It missed every tick from its stop to its death (the world ticked on without it), and
    // the world ticked on after.
    let detected = faults[0]["detected_tick"].as_u64().unwrap();
    let (_, ticks) = recording(&out);
    let (first, len) = longest_streak(&missed_ticks(&ticks, 1));
    assert_eq!(first + len, detected, "missed up to its death");
    assert!(len >= 2, "a run of misses before the deadline: {len}");
    assert_eq!(ticks[detected as usize].alive[1], 0);
    assert!(s["ticks"].as_u64().unwrap() > detected);
    assert_left_nothing(&out);
}

#[test]
fn real_time_mode_is_refused_with_a_clear_error_where_it_cannot_run() {
    let out = tmp_dir("rt-refused");
    for (args, wanted) in [
        (
            &["--realtime", "0.001"][..],
            &["--realtime", "runtime.realtime_hz", "[0.01, 10000]"][..],
        ),
        (
            &["--realtime", "100", "--tick-hz", "50"][..],
            &["runtime.realtime_hz", "runtime.tick_hz"][..],
        ),
        (
            &["--realtime", "100", "--executor", "inprocess"][..],
            &["--executor inprocess", "processes executor", "--tick-hz"][..],
        ),
    ] {
        let mut a = vec!["--scenario", roam(), "--robots", "2"];
        a.extend_from_slice(args);
        let o = up(&a, &out);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        for w in wanted {
            assert!(e.contains(w), "{args:?}: {w:?} not in {e}");
        }
    }
}
