//! Runs that collide (issue 37 item 13): two runs on one `--out`, one `SWARM_RUN_ID` twice,
//! one robot named thrice in a kill order, a live run of another build of the project. The
//! second run is refused (exit 2) before it writes anything, and the first goes on unharmed.
//! Real processes.

use e2e::*;
use std::path::Path;
use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

fn wait_with_timeout(mut c: Child, limit: Duration) -> Output {
    let t = Instant::now();
    while c.try_wait().unwrap().is_none() {
        if t.elapsed() > limit {
            let _ = c.kill();
            panic!("orchestrator did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    c.wait_with_output().unwrap()
}

const LONG: [&str; 8] = [
    "--robots",
    "4",
    "--max-ticks",
    "100000000",
    "--tick-hz",
    "200",
    "--seed",
    "5",
];

/// The run writing to `out` ticks on: its tick moves past `from` + 20.
fn goes_on(out: &Path, from: u64) {
    let t = Instant::now();
    while registry_tick(out) < from + 20 {
        assert!(
            t.elapsed() < Duration::from_secs(30),
            "the first run stopped"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

fn running(out: &Path) -> u64 {
    registry_entry(out, 4);
    goes_on(out, 0);
    registry_tick(out)
}

#[test]
fn a_second_run_on_the_same_out_is_refused_and_the_first_goes_on() {
    let _g = serial();
    for exec in ["processes", "inprocess"] {
        let out = tmp_dir(&format!("same-out-{exec}"));
        let args = [&["--scenario", roam(), "--executor", exec][..], &LONG[..]].concat();
        let first = spawn_up(&args, &out);
        if exec == "processes" {
            running(&out);
        } else {
            let t = Instant::now();
            while !out.join("recording.bin").exists() {
                assert!(t.elapsed() < Duration::from_secs(30), "never started");
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        let before = std::fs::read(out.join("scenario.toml")).unwrap();
        // Another scenario (other seed), short: had it run, scenario.toml would differ.
        let second_args = [
            "--scenario",
            roam(),
            "--executor",
            exec,
            "--robots",
            "4",
            "--max-ticks",
            "50",
            "--seed",
            "6",
        ];
        let o = up(&second_args, &out);
        assert_eq!(
            o.status.code(),
            Some(exit::BAD_INPUT),
            "{exec}: {}",
            stderr(&o)
        );
        assert!(
            stderr(&o).contains("another run is writing into this folder"),
            "{exec}: {}",
            stderr(&o)
        );
        assert_eq!(std::fs::read(out.join("scenario.toml")).unwrap(), before);
        if exec == "processes" {
            goes_on(&out, registry_tick(&out));
        }
        // SAFETY: Ctrl-C to the orchestrator this test started.
        unsafe { libc::kill(first.id() as i32, libc::SIGINT) };
        let o = wait_with_timeout(first, Duration::from_secs(30));
        assert_eq!(
            o.status.code(),
            Some(exit::SIGINT),
            "{exec}: {}",
            stderr(&o)
        );
        assert_eq!(summary(&out)["seed"], 5, "{exec}: the first run's summary");
        assert_left_nothing(&out);
    }
}

/// The same `SWARM_RUN_ID` for a second run while the first runs: refused by name (exit 2),
/// the first run's files and registry entry untouched. Before: a cryptic "File exists", and
/// the failed run's cleanup could remove the first run's files.
#[test]
fn a_run_id_in_use_is_refused_and_the_first_run_goes_on() {
    let _g = serial();
    let id = own_run_id("same-id");
    let a = tmp_dir("same-id-a");
    let b = tmp_dir("same-id-b");
    let args = [&["--scenario", roam()][..], &LONG[..]].concat();
    let first = spawn_up_as(&args, &a, Some(&id));
    let tick = running(&a);
    let files = shm_of_run(&id);
    assert!(!files.is_empty());
    let o = up_as(&args, &b, Some(&id));
    assert_eq!(o.status.code(), Some(exit::BAD_INPUT), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(&format!("run id {id} is already in use")),
        "{}",
        stderr(&o)
    );
    assert!(!b.join("scenario.toml").exists(), "the refused run wrote");
    assert_eq!(shm_of_run(&id), files, "the first run's files were touched");
    goes_on(&a, tick);
    // SAFETY: Ctrl-C to the orchestrator this test started.
    unsafe { libc::kill(first.id() as i32, libc::SIGINT) };
    let o = wait_with_timeout(first, Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    assert_left_nothing(&a);
}

/// `kill --robots 3,3,3` kills robot 3 once and says so once (before: three kills reported).
#[test]
fn a_robot_named_thrice_is_killed_once() {
    let _g = serial();
    let out = tmp_dir("kill-thrice");
    let args = [&["--scenario", roam()][..], &LONG[..]].concat();
    let child = spawn_up(&args, &out);
    running(&out);
    let run_id = registry_of(&out).unwrap()["run_id"]
        .as_str()
        .unwrap()
        .to_string();
    let o = Command::new(orchestrator())
        .args(["kill", "--run", &run_id, "--robots", "3,3,3"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    // One line in all (before: a line for each time it was named: killed, or gone).
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(said.lines().count(), 1, "{said}");
    assert!(said.starts_with("killed robot 3 "), "{said}");
    let t = Instant::now();
    while registry_of(&out).is_none_or(|r| r["dead"] != 1) {
        assert!(t.elapsed() < Duration::from_secs(20), "robot 3 never died");
        std::thread::sleep(Duration::from_millis(10));
    }
    // SAFETY: Ctrl-C to the orchestrator this test started.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = wait_with_timeout(child, Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    let faults = summary(&out)["faults"].as_array().unwrap().clone();
    assert_eq!(faults.len(), 1, "{faults:?}");
    assert_eq!(faults[0]["robot"], 3);
    assert_left_nothing(&out);
}

/// Two builds of the project on one machine (a second checkout, an installed copy) share the
/// run registry: `clean` (and so every `up`) of one must leave the other's live runs alone.
/// Before, a run was live only if its orchestrator ran *this* build's binary: another build's
/// run counted as dead, and `clean` SIGKILLed its agents (their command lines hold the run's
/// prefix) mid-run, once in CI while a second checkout ran its tests.
#[test]
fn a_live_run_of_another_build_is_left_alone_by_clean() {
    let _g = serial();
    let other = tmp_dir("other-build");
    std::fs::create_dir_all(&other).unwrap();
    for b in ["orchestrator", "world", "agent"] {
        std::fs::copy(bin_dir().join(b), other.join(b)).unwrap();
    }
    let out = tmp_dir("other-build-run");
    let mut cmd = Command::new(other.join("orchestrator"));
    cmd.args(["up", "--quiet", "--out"])
        .arg(&out)
        .args(["--scenario", roam(), "--robots", "4", "--max-ticks", "600"])
        .args(["--tick-hz", "200", "--seed", "5"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    let child = cmd.spawn().unwrap();
    let entry = registry_entry(&out, 4);
    goes_on(&out, registry_tick(&out));
    // This build's clean, while the other build's run ticks.
    let o = Command::new(orchestrator()).arg("clean").output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    for pid in entry["agent_pids"].as_array().unwrap() {
        let pid = pid.as_u64().unwrap() as i32;
        assert!(pid_alive(pid), "clean killed agent {pid} of a live run");
    }
    let o = wait_with_timeout(child, Duration::from_secs(60));
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["ticks"], 600, "{s}");
    assert_eq!(s["faults"].as_array().unwrap().len(), 0, "{s}");
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&other);
    let _ = std::fs::remove_dir_all(&out);
}
