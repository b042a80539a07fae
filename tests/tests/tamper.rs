//! A hostile agent against a live run (issue 37 items 4 and 5): this test process, of the
//! same user as the run's processes, does what an agent program could do with the files it
//! can reach, and the run must end in at most a fault of the tampered robot.
//!
//! - The tick barrier: nothing in /dev/shm to open by name; the sealed memfds an agent
//!   inherits, opened again read-write through /proc/<pid>/fd, cannot be written, resized or
//!   mapped writable.
//! - Robot r's act publisher data segment (or its connection to the world) truncated under
//!   the world: robot r becomes a fault, every other robot completes, `up` exits normally and
//!   /dev/shm is left as found.
//! - The same with the actions over blackboards (`runtime.acts = "blackboard"`): robot r's
//!   board truncated, or a program that never lets the world's read of its board end.
//! - The orchestrator's own `run/control` segment truncated: the run goes on.
//! - The world's own Sense, air and status segments truncated: the world makes its data
//!   services anew (agents follow the barrier's generation word), gives up the status, and the
//!   run completes with no robot hurt.
//! - The air's segment truncated under robots that keep zero-copy views of it (`Blob`s) and
//!   read them at their next tick: they read zeros, and no robot is hurt.

use e2e::*;
use std::os::fd::AsRawFd;
use std::path::Path;
use std::process::Child;
use std::time::{Duration, Instant};

/// Robots of every run here.
const ROBOTS: usize = 4;
/// Ticks of every run (at [`TICK_HZ`]: 10 s, time enough to tamper mid-run on a loaded
/// machine).
const MAX_TICKS: &str = "1000";
const TICK_HZ: &str = "100";
/// The robot whose files are tampered with.
const VICTIM: usize = 1;
/// A robot SIGSTOPped while robot [`VICTIM`]'s segment is truncated: the world then waits for
/// it while holding the victim's action of the tick, so its next read of that action is a
/// read of the truncated segment (and the victim, waiting for the next release, does not
/// touch its own segment first).
const STALLED: usize = 2;
/// How long the stalled robot is stopped before the truncation (the victim sends its action
/// in far less); well under the scenario's ack deadline.
const STALL: Duration = Duration::from_millis(300);

/// Starts a paced roam run of [`ROBOTS`] robots; returns it and the agent pids by robot.
fn start(tag: &str) -> (Child, std::path::PathBuf, String, Vec<i32>) {
    start_with(tag, roam())
}

/// configs/roam.toml with the actions over `acts` (`runtime.acts`) and `more` TOML after
/// it, written into `dir`; returns its path.
fn acts_scenario(dir: &Path, acts: &str, more: &str) -> String {
    std::fs::create_dir_all(dir).unwrap();
    let text = std::fs::read_to_string(roam()).unwrap();
    let path = dir.join("acts.toml");
    std::fs::write(
        &path,
        format!("{text}\n[runtime]\nacts = \"{acts}\"\n{more}"),
    )
    .unwrap();
    path.display().to_string()
}

/// configs/roam.toml with the actions over blackboards and `more` after it.
fn board_scenario(dir: &Path, more: &str) -> String {
    acts_scenario(dir, "blackboard", more)
}

/// [`start`] with the scenario file `scenario`.
fn start_with(tag: &str, scenario: &str) -> (Child, std::path::PathBuf, String, Vec<i32>) {
    let out = tmp_dir(tag);
    let id = own_run_id(tag);
    let up = spawn_up_as(
        &[
            "--scenario",
            scenario,
            "--robots",
            &ROBOTS.to_string(),
            "--max-ticks",
            MAX_TICKS,
            "--tick-hz",
            TICK_HZ,
        ],
        &out,
        Some(&id),
    );
    let mut up = up;
    let t = Instant::now();
    let entry = loop {
        if let Some(v) = registry_of(&out)
            .filter(|v| v["agent_pids"].as_array().map(|a| a.len()) == Some(ROBOTS))
        {
            break v;
        }
        if up.try_wait().unwrap().is_some() {
            let o = up.wait_with_output().unwrap();
            panic!("the run ended before the test began: {}", stderr(&o));
        }
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "no agents registered"
        );
        std::thread::sleep(Duration::from_millis(10));
    };
    let pids: Vec<i32> = entry["agent_pids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_i64().unwrap() as i32)
        .collect();
    let prefix = swarm::transport::prefix_for(&id);
    for (r, pid) in pids.iter().enumerate() {
        let cmd = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
        let args: Vec<String> = cmd
            .split(|&b| b == 0)
            .map(|a| String::from_utf8_lossy(a).into_owned())
            .collect();
        assert!(
            args.windows(2)
                .any(|w| w[0] == "--robot" && w[1] == r.to_string())
                && args.contains(&prefix),
            "pid {pid} is not robot {r}'s agent: {args:?}"
        );
    }
    // The run is ticking.
    let t = Instant::now();
    while registry_tick(&out) < 5 {
        assert!(
            t.elapsed() < Duration::from_secs(30),
            "the run never ticked"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    (up, out, id, pids)
}

/// The barrier descriptors `pid` inherited (`SWARM_BARRIER_FDS=<tick>,<acks>`).
fn barrier_fds(pid: i32) -> (i32, i32) {
    let env = std::fs::read(format!("/proc/{pid}/environ")).unwrap();
    let var = env
        .split(|&b| b == 0)
        .map(String::from_utf8_lossy)
        .find_map(|v| v.strip_prefix("SWARM_BARRIER_FDS=").map(str::to_string))
        .expect("agent has SWARM_BARRIER_FDS");
    let (t, a) = var.split_once(',').unwrap();
    (t.parse().unwrap(), a.parse().unwrap())
}

/// `pid`'s descriptor `fd`, opened again read-write through /proc.
fn reopen(pid: i32, fd: i32) -> std::fs::File {
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(format!("/proc/{pid}/fd/{fd}"))
        .unwrap_or_else(|e| panic!("open /proc/{pid}/fd/{fd} read-write: {e}"))
}

/// Whether a shared writable mapping of `f` is made (unmapped at once if so).
fn maps_writable(f: &std::fs::File) -> bool {
    let len = f.metadata().unwrap().len() as usize;
    // SAFETY: a new mapping of our own, unmapped below.
    let p = unsafe {
        libc::mmap(
            std::ptr::null_mut(),
            len,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_SHARED,
            f.as_raw_fd(),
            0,
        )
    };
    if p == libc::MAP_FAILED {
        return false;
    }
    // SAFETY: our mapping.
    unsafe { libc::munmap(p, len) };
    true
}

/// Robot `pid`'s own act publisher data segment: the one iceoryx2 `.data` file it maps
/// read-write.
fn own_data_segment(pid: i32) -> String {
    own_segment(pid, ".data")
}

/// The one iceoryx2 file ending in `suffix` that `pid` maps read-write.
fn own_segment(pid: i32, suffix: &str) -> String {
    let maps = std::fs::read_to_string(format!("/proc/{pid}/maps")).unwrap();
    let own: Vec<&str> = maps
        .lines()
        .filter(|l| l.split_whitespace().nth(1) == Some("rw-s") && l.ends_with(suffix))
        .filter_map(|l| l.split_whitespace().nth(5))
        .collect();
    assert_eq!(own.len(), 1, "{maps}");
    own[0].to_string()
}

fn truncate(path: &str) {
    std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .and_then(|f| f.set_len(0))
        .unwrap_or_else(|e| panic!("truncate {path}: {e}"));
}

fn signal(pid: i32, sig: i32) {
    // SAFETY: a signal to an agent of this test's own run.
    unsafe { libc::kill(pid, sig) };
}

/// The faults of the run in `out`: (robot, cause).
fn faults(out: &Path) -> Vec<(u64, String)> {
    summary(out)["faults"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["robot"].as_u64().unwrap(),
                f["cause"].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

/// The run ended by itself with every tick, robot [`VICTIM`] at most faulted, and left
/// nothing behind.
fn assert_only_the_victim_hurt(up: Child, out: &Path, id: &str) -> Vec<(u64, String)> {
    let o = up.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let s = summary(out);
    assert_eq!(s["end"], "completed", "{s}");
    assert_eq!(s["ticks"].as_u64(), MAX_TICKS.parse().ok(), "{s}");
    let f = faults(out);
    assert!(f.iter().all(|(r, _)| *r == VICTIM as u64), "{f:?}");
    assert!(
        s["alive_at_end"].as_u64().unwrap() >= ROBOTS as u64 - 1,
        "{s}"
    );
    assert!(shm_of_run(id).is_empty(), "{:?}", shm_of_run(id));
    assert_left_nothing(out);
    f
}

#[test]
fn the_barrier_is_out_of_an_agents_reach() {
    let _g = serial();
    let (up, out, id, pids) = start("barrier");
    let prefix = swarm::transport::prefix_for(&id);
    // Nothing of the barrier in /dev/shm to open by name.
    for name in ["tick", "acks"] {
        let p = format!("/dev/shm/{prefix}{name}");
        assert!(!Path::new(&p).exists(), "{p} exists");
    }
    let pid = pids[VICTIM];
    let (tick_fd, acks_fd) = barrier_fds(pid);
    // The world's segment (release, shutdown, kill orders): refused whatever the way in.
    let tick = reopen(pid, tick_fd);
    let len = tick.metadata().unwrap().len();
    assert!(len > 0);
    use std::os::unix::fs::FileExt;
    assert!(
        tick.write_at(&[0xff; 8], 16).is_err(),
        "write to the tick segment"
    );
    assert!(tick.set_len(0).is_err(), "shrink the tick segment");
    assert!(tick.set_len(len * 2).is_err(), "grow the tick segment");
    assert!(
        !maps_writable(&tick),
        "writable mapping of the tick segment"
    );
    // The agents' segment: written through the agents' mappings, but never resized nor
    // sealed further (a seal against writes would stop every agent).
    let acks = reopen(pid, acks_fd);
    let acks_len = acks.metadata().unwrap().len();
    assert!(acks.set_len(0).is_err(), "shrink the acks segment");
    assert!(acks.set_len(acks_len * 2).is_err(), "grow the acks segment");
    // SAFETY: fcntl on our own descriptor.
    let sealed = unsafe {
        libc::fcntl(
            acks.as_raw_fd(),
            libc::F_ADD_SEALS,
            libc::F_SEAL_FUTURE_WRITE,
        )
    };
    assert_eq!(sealed, -1, "seal the acks segment against writes");
    assert_eq!(tick.metadata().unwrap().len(), len);
    assert_eq!(acks.metadata().unwrap().len(), acks_len);
    drop((tick, acks));
    let f = assert_only_the_victim_hurt(up, &out, &id);
    assert!(f.is_empty(), "{f:?}");
}

#[test]
fn a_truncated_act_segment_makes_only_its_robot_a_fault() {
    let _g = serial();
    let dir = tmp_dir("act-data-sc");
    let (up, out, id, pids) = start_with("act-data", &acts_scenario(&dir, "pub-sub", ""));
    signal(pids[STALLED], libc::SIGSTOP);
    std::thread::sleep(STALL);
    truncate(&own_data_segment(pids[VICTIM]));
    signal(pids[STALLED], libc::SIGCONT);
    let f = assert_only_the_victim_hurt(up, &out, &id);
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(
        f[0].1
            .contains(&format!("robot {VICTIM}'s act segment shrank")),
        "{f:?}"
    );
}

#[test]
fn a_truncated_act_connection_hurts_only_its_robot() {
    let _g = serial();
    let dir = tmp_dir("act-conn-sc");
    let (up, out, id, pids) = start_with("act-conn", &acts_scenario(&dir, "pub-sub", ""));
    // The connection files of the victim's publisher (`<service>_<publisher>_<subscriber>`).
    let data = own_data_segment(pids[VICTIM]);
    let publisher = data
        .trim_end_matches(".data")
        .rsplit('_')
        .next()
        .unwrap()
        .to_string();
    let conns: Vec<String> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .map(|e| e.path().display().to_string())
        .filter(|p| p.contains(&format!("_{publisher}_")) && p.ends_with(".connection"))
        .collect();
    assert!(!conns.is_empty(), "no connection of {data}");
    for c in &conns {
        truncate(c);
    }
    let f = assert_only_the_victim_hurt(up, &out, &id);
    assert_eq!(f.len(), 1, "{f:?}");
}

/// The same over blackboards: robot r's board data (the world made it; r's agent maps it to
/// write its actions) truncated under the world: r is a fault, the run goes on.
#[test]
fn a_truncated_board_makes_only_its_robot_a_fault() {
    let _g = serial();
    let dir = tmp_dir("board-data-sc");
    let (up, out, id, pids) = start_with("board-data", &board_scenario(&dir, ""));
    signal(pids[STALLED], libc::SIGSTOP);
    std::thread::sleep(STALL);
    truncate(&own_segment(pids[VICTIM], ".blackboard_data"));
    signal(pids[STALLED], libc::SIGCONT);
    let f = assert_only_the_victim_hurt(up, &out, &id);
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(
        f[0].1
            .contains(&format!("robot {VICTIM}'s act segment shrank")),
        "{f:?}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// A robot's program that moves its board's write counters without end, writing nothing
/// (each read of such an entry by the world retries for as long as the counter moves during
/// its copy: iceoryx2's read has no bound). Only that robot is hurt: the world's reads get
/// through (on 2 cores the writer is off-CPU often enough), the robot gives no action of its
/// own and is declared dead; where a read does not get through, the read watchdog orders the
/// writer killed after 2 s (world/src/read_watchdog.rs, its unit test).
#[test]
fn a_board_writer_that_moves_its_counters_without_end_hurts_only_its_robot() {
    let _g = serial();
    let dir = tmp_dir("board-hostile-sc");
    let agents = format!(
        "\n[[agents]]\nrobots = [{VICTIM}]\ncommand = [{:?}]\n",
        env!("CARGO_BIN_EXE_hostile_board")
    );
    let (up, out, id, _pids) = start_with("board-hostile", &board_scenario(&dir, &agents));
    let f = assert_only_the_victim_hurt(up, &out, &id);
    assert_eq!(f.len(), 1, "{f:?}");
    let _ = std::fs::remove_dir_all(dir);
}

/// The orchestrator's own `run/control` publisher segment truncated, then an agent dies: the
/// orchestrator's report of the death (and the world's read of it) see zeros rather than
/// SIGBUS the orchestrator, which left the run's files behind; the world finds the dead robot
/// by its ack deadline and the run completes.
#[test]
fn a_truncated_control_segment_leaves_the_orchestrator_standing() {
    let _g = serial();
    let (up, out, id, pids) = start("control");
    let maps = std::fs::read_to_string(format!("/proc/{}/maps", up.id())).unwrap();
    let control: Vec<&str> = maps
        .lines()
        .filter(|l| l.split_whitespace().nth(1) == Some("rw-s") && l.ends_with(".data"))
        .filter_map(|l| l.split_whitespace().nth(5))
        .collect();
    assert_eq!(control.len(), 1, "{maps}");
    truncate(control[0]);
    signal(pids[VICTIM], libc::SIGKILL);
    let f = assert_only_the_victim_hurt(up, &out, &id);
    assert_eq!(f.len(), 1, "{f:?}");
}

/// The data segments of the world `world_pid` maps read-write (`.data` files), largest first
/// (the Sense one, every robot's record, is the largest here).
fn worlds_data_segments(world_pid: i32) -> Vec<String> {
    let maps = std::fs::read_to_string(format!("/proc/{world_pid}/maps")).unwrap();
    let mut segments: Vec<String> = maps
        .lines()
        .filter(|l| l.split_whitespace().nth(1) == Some("rw-s") && l.ends_with(".data"))
        .filter_map(|l| l.split_whitespace().nth(5))
        .map(str::to_string)
        .collect();
    segments.sort_by_key(|p| std::cmp::Reverse(std::fs::metadata(p).map(|m| m.len()).unwrap_or(0)));
    segments.dedup();
    segments
}

/// How long the world is stopped before a truncation of its data segments: every agent reads
/// its frames within it and then sleeps on the barrier (the world cannot release the next
/// tick), so no agent is reading them when they shrink (an agent that is, dies of SIGBUS: the
/// limit docs/protocol.md section 4 gives, not what these tests judge).
const AGENTS_SETTLE: Duration = Duration::from_millis(300);

/// Truncates `segments` while the world `world_pid` is stopped and its agents sleep.
fn truncate_with_world_stopped(world_pid: i32, segments: &[String]) {
    signal(world_pid, libc::SIGSTOP);
    std::thread::sleep(AGENTS_SETTLE);
    for s in segments {
        truncate(s);
    }
    signal(world_pid, libc::SIGCONT);
}

/// The run ended by itself with every tick, no robot hurt, and left nothing behind; its
/// stderr.
fn assert_nobody_hurt(up: Child, out: &Path, id: &str) -> String {
    let o = up.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let s = summary(out);
    assert_eq!(s["end"], "completed", "{s}");
    assert_eq!(s["ticks"].as_u64(), MAX_TICKS.parse().ok(), "{s}");
    assert_eq!(faults(out), vec![], "{}", stderr(&o));
    assert!(shm_of_run(id).is_empty(), "{:?}", shm_of_run(id));
    assert_left_nothing(out);
    stderr(&o)
}

/// The world's own Sense segment truncated (every agent maps it: any of them could): the
/// world's next write of it goes to a private page instead of a SIGBUS, the world makes
/// `world/sense` and `radio/air` anew (generation 1), every agent opens them, and the run
/// completes with no robot hurt.
#[test]
fn a_truncated_sense_segment_is_made_anew_and_no_robot_is_hurt() {
    let _g = serial();
    let (up, out, id, _pids) = start("sense");
    let world = world_pid_of(&id);
    let sense = worlds_data_segments(world)[0].clone();
    truncate_with_world_stopped(world, &[sense]);
    let err = assert_nobody_hurt(up, &out, &id);
    assert!(err.contains("made anew as generation 1"), "{err}");
}

/// Every data segment the world writes (Sense, air, status) truncated at once: the data
/// services are made anew, the status is given up (said on stderr), the run completes.
#[test]
fn every_worlds_data_segment_truncated_hurts_no_robot() {
    let _g = serial();
    let (up, out, id, _pids) = start("world-data");
    let world = world_pid_of(&id);
    let segments = worlds_data_segments(world);
    assert!(segments.len() >= 3, "{segments:?}");
    truncate_with_world_stopped(world, &segments);
    let err = assert_nobody_hurt(up, &out, &id);
    assert!(err.contains("made anew as generation"), "{err}");
}

/// The iceoryx2 files ending in `suffix` that process `pid` maps read-write.
fn mapped_rw(pid: i32, suffix: &str) -> std::collections::BTreeSet<String> {
    let maps = std::fs::read_to_string(format!("/proc/{pid}/maps")).unwrap_or_default();
    maps.lines()
        .filter(|l| l.split_whitespace().nth(1) == Some("rw-s") && l.ends_with(suffix))
        .filter_map(|l| l.split_whitespace().nth(5))
        .map(str::to_string)
        .collect()
}

/// The shared state (`.dynamic`: the ports, the nodes) of the world's data services: the
/// files the world and every agent map (each agent maps only those two and its own act
/// service's) truncated, as their data segments above: the services are made anew, no robot
/// is hurt, nobody aborts on the zeros iceoryx2 would read when closing their ports, and the
/// run's files go.
#[test]
fn the_shared_state_of_the_worlds_data_services_truncated_hurts_no_robot() {
    let _g = serial();
    let (up, out, id, pids) = start("world-dynamic");
    let world = world_pid_of(&id);
    let mut shared = mapped_rw(world, ".dynamic");
    for &p in &pids {
        let mine = mapped_rw(p, ".dynamic");
        shared.retain(|f| mine.contains(f));
    }
    assert_eq!(shared.len(), 2, "world/sense's and radio/air's: {shared:?}");
    let shared: Vec<String> = shared.into_iter().collect();
    truncate_with_world_stopped(world, &shared);
    let err = assert_nobody_hurt(up, &out, &id);
    assert!(err.contains("made anew as generation 1"), "{err}");
}

/// Bytes of each keeper robot's beacon payload (a `Blob`, kept as a view of the air).
const HELD_PAYLOAD: usize = 1000;

/// configs/roam.toml run by `keeper` robots (agent/src/behaviours/keeper.rs): beacons of
/// [`HELD_PAYLOAD`] bytes (robot i's are all i) received in place, every robot in range of
/// every other, each robot keeping the last tick's beacons (views of that tick's air) and
/// reading every byte of them again at its next step. Written into `dir`; its path.
fn keeper_scenario(dir: &Path) -> String {
    std::fs::create_dir_all(dir).unwrap();
    let text = std::fs::read_to_string(roam())
        .unwrap()
        .replace("behaviour = \"roam\"", "behaviour = \"keeper\"")
        .replace(
            "max_message_bytes = 256",
            "max_message_bytes = 2048\nzero_copy_held = 2\ncomm_radius = 2000.0",
        );
    let path = dir.join("keeper.toml");
    std::fs::write(
        &path,
        format!("{text}\n[roam]\npayload_bytes = {HELD_PAYLOAD}\n"),
    )
    .unwrap();
    path.display().to_string()
}

/// The air's data segment of the world `world_pid`: of the data segments it writes, the one
/// that holds the last robot's beacon payload.
fn air_data_segment(world_pid: i32) -> String {
    let payload = vec![ROBOTS as u8 - 1; HELD_PAYLOAD];
    let air: Vec<String> = worlds_data_segments(world_pid)
        .into_iter()
        .filter(|s| {
            std::fs::read(s)
                .unwrap_or_default()
                .windows(HELD_PAYLOAD)
                .any(|w| w == payload)
        })
        .collect();
    assert_eq!(air.len(), 1, "{air:?}");
    air[0].clone()
}

/// The air's data segment truncated while every robot keeps views of the last air in it (and
/// its agent sleeps on the barrier): the world makes its data services anew, and each robot's
/// next step reads its held views, beyond the end of the truncated file. The shrink guard
/// absorbs those faults, on the behaviour's own reads (outside the agent's guarded reads of its
/// frames): the views read zeros, each agent says so once, and no robot is hurt.
#[test]
fn a_truncated_air_segment_under_held_blob_views_hurts_no_robot() {
    let _g = serial();
    let dir = tmp_dir("air-held-sc");
    let (up, out, id, _pids) = start_with("air-held", &keeper_scenario(&dir));
    let world = world_pid_of(&id);
    let air = air_data_segment(world);
    truncate_with_world_stopped(world, &[air]);
    let err = assert_nobody_hurt(up, &out, &id);
    assert!(err.contains("made anew as generation 1"), "{err}");
    // Each robot's agent (its stderr is its log) read its held views beyond the file's end,
    // and said so once.
    for r in 0..ROBOTS {
        let log = std::fs::read_to_string(out.join(format!("logs/robot-{r}.log"))).unwrap();
        let said = log
            .matches(&format!(
                "agent {r}: messages it held were lost to a truncated segment"
            ))
            .count();
        assert_eq!(said, 1, "robot {r}'s log: {log}");
    }
    let _ = std::fs::remove_dir_all(dir);
}
