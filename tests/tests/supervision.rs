//! Fault injection and supervision with real processes and real SIGKILLs: restart, kill the
//! world, kill the orchestrator, clean, reproducible chaos, live status / kill.

use e2e::*;
use std::path::Path;
use std::process::{Child, Command};
use std::time::{Duration, Instant};

fn wait_for(what: &str, limit: Duration, mut f: impl FnMut() -> bool) {
    let t = Instant::now();
    while !f() {
        assert!(t.elapsed() < limit, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn running(out: &Path, robots: usize) -> serde_json::Value {
    let mut v = None;
    wait_for("the run to tick", Duration::from_secs(30), || {
        v = registry_of(out).filter(|r| {
            r["agent_pids"].as_array().map(|a| a.len()) == Some(robots)
                && r["tick"].as_u64().unwrap_or(0) > 10
        });
        v.is_some()
    });
    v.unwrap()
}

fn finish(c: Child, limit: Duration) -> std::process::Output {
    let mut c = c;
    let t = Instant::now();
    while c.try_wait().unwrap().is_none() {
        if t.elapsed() > limit {
            let _ = c.kill();
            panic!("orchestrator did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    c.wait_with_output().unwrap()
}

#[test]
fn a_robot_restarts_100_times_in_a_row() {
    let _g = serial();
    let out = tmp_dir("restart100");
    let child = spawn_up(
        &[
            "--scenario",
            roam(),
            "--robots",
            "6",
            "--max-ticks",
            "100000000",
            "--on-fault",
            "restart",
            "--max-restarts",
            "1000",
        ],
        &out,
    );
    let entry = running(&out, 6);
    let run_id = entry["run_id"].as_str().unwrap().to_string();
    for i in 0..100u64 {
        let old = registry_of(&out).unwrap()["agent_pids"][2]
            .as_u64()
            .unwrap();
        let o = Command::new(orchestrator())
            .args(["kill", "--run", &run_id, "--robot", "2"])
            .output()
            .unwrap();
        assert!(o.status.success(), "kill #{i}: {}", stderr(&o));
        wait_for(
            &format!("restart #{}", i + 1),
            Duration::from_secs(20),
            || {
                registry_of(&out).is_some_and(|r| {
                    r["agent_pids"][2].as_u64() != Some(old)
                        && r["restarted"].as_u64().unwrap_or(0) > i
                        && r["alive"] == 6
                })
            },
        );
    }
    // SAFETY: Ctrl-C to our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = finish(child, Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    let s = summary(&out);
    let faults = s["faults"].as_array().unwrap();
    assert_eq!(faults.len(), 100, "{faults:?}");
    assert!(faults
        .iter()
        .all(|f| f["robot"] == 2 && f["restarted_tick"].is_u64()));
    assert!(faults
        .iter()
        .all(|f| f["detected_tick"].as_u64() >= f["tick"].as_u64()));
    assert_eq!(s["alive_at_end"], 6);
    assert_left_nothing(&out);
}

#[test]
fn killing_the_world_ends_the_run_with_an_error_and_agents_exit() {
    let _g = serial();
    let out = tmp_dir("killworld");
    let child = spawn_up(
        &[
            "--scenario",
            roam(),
            "--robots",
            "6",
            "--max-ticks",
            "100000000",
        ],
        &out,
    );
    let entry = running(&out, 6);
    let world = entry["world_pid"].as_i64().unwrap() as i32;
    let agents: Vec<i32> = entry["agent_pids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_i64().unwrap() as i32)
        .collect();
    // SAFETY: SIGKILL of this test run's world process.
    unsafe { libc::kill(world, libc::SIGKILL) };
    let t = Instant::now();
    wait_for("agents to exit", Duration::from_secs(5), || {
        agents.iter().all(|&p| !pid_alive(p))
    });
    let exit_time = t.elapsed();
    let o = finish(child, Duration::from_secs(30));
    assert!(
        !o.status.success(),
        "the orchestrator must report the failure"
    );
    assert!(stderr(&o).contains("world"), "{}", stderr(&o));
    assert!(
        exit_time < Duration::from_secs(1),
        "agents took {exit_time:?}"
    );
    let prefix = swarm::transport::prefix_for(entry["run_id"].as_str().unwrap());
    assert!(
        run_shm_entries().iter().all(|n| !n.starts_with(&prefix)),
        "shm left"
    );
    assert!(registry_of(&out).is_none(), "registry entry left");
}

#[test]
fn killing_the_orchestrator_takes_the_run_down_and_clean_removes_its_leftovers() {
    let _g = serial();
    let out = tmp_dir("killorch");
    let child = spawn_up(
        &[
            "--scenario",
            roam(),
            "--robots",
            "6",
            "--max-ticks",
            "100000000",
        ],
        &out,
    );
    let entry = running(&out, 6);
    let pids: Vec<i32> = std::iter::once(&entry["world_pid"])
        .chain(entry["agent_pids"].as_array().unwrap())
        .map(|p| p.as_i64().unwrap() as i32)
        .collect();
    // SAFETY: SIGKILL of our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGKILL) };
    let _ = finish(child, Duration::from_secs(5));
    let t = Instant::now();
    wait_for("world and agents to exit", Duration::from_secs(5), || {
        pids.iter().all(|&p| !pid_alive(p))
    });
    assert!(
        t.elapsed() < Duration::from_secs(1),
        "took {:?}",
        t.elapsed()
    );
    let prefix = swarm::transport::prefix_for(entry["run_id"].as_str().unwrap());
    assert!(
        run_shm_entries().iter().any(|n| n.starts_with(&prefix)),
        "a killed orchestrator leaves shm (else this test proves nothing)"
    );
    // A live run at the same time must survive the clean.
    let live_out = tmp_dir("killorch-live");
    let live = spawn_up(
        &[
            "--scenario",
            roam(),
            "--robots",
            "4",
            "--max-ticks",
            "100000000",
        ],
        &live_out,
    );
    let live_entry = running(&live_out, 4);
    let o = Command::new(orchestrator()).arg("clean").output().unwrap();
    assert!(o.status.success());
    assert!(
        run_shm_entries().iter().all(|n| !n.starts_with(&prefix)),
        "clean left shm"
    );
    assert!(registry_of(&out).is_none(), "clean left the registry entry");
    let live_prefix = swarm::transport::prefix_for(live_entry["run_id"].as_str().unwrap());
    assert!(
        run_shm_entries()
            .iter()
            .any(|n| n.starts_with(&live_prefix)),
        "clean touched a live run"
    );
    let tick = registry_of(&live_out).unwrap()["tick"].as_u64().unwrap();
    wait_for("the live run to go on", Duration::from_secs(10), || {
        registry_of(&live_out).is_some_and(|r| r["tick"].as_u64().unwrap() > tick + 10)
    });
    // SAFETY: Ctrl-C to our own child.
    unsafe { libc::kill(live.id() as i32, libc::SIGINT) };
    let o = finish(live, Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    assert_left_nothing(&live_out);
}

#[test]
fn chaos_under_drop_is_reproducible_byte_for_byte() {
    let _g = serial();
    let args = [
        "--scenario",
        roam(),
        "--robots",
        "10",
        "--max-ticks",
        "400",
        "--seed",
        "3",
        "--chaos",
        "0.5",
        "--chaos-at",
        "50:1,120:7",
    ];
    let dirs: Vec<_> = ["chaos-a", "chaos-b", "chaos-c"]
        .iter()
        .map(|n| tmp_dir(n))
        .collect();
    for (d, exec) in dirs.iter().zip(["processes", "processes", "inprocess"]) {
        let o = up(&[&args[..], &["--executor", exec]].concat(), d);
        assert!(o.status.success(), "{exec}: {}", stderr(&o));
    }
    let rec = |d: &Path| std::fs::read(d.join("recording.bin")).unwrap();
    assert!(rec(&dirs[0]) == rec(&dirs[1]), "two chaos runs differ");
    assert!(
        rec(&dirs[0]) == rec(&dirs[2]),
        "chaos run differs from the in-process executor"
    );
    let s = summary(&dirs[0]);
    let faults = s["faults"].as_array().unwrap();
    assert!(faults.len() >= 3, "random kills happened too: {faults:?}");
    assert!(faults
        .iter()
        .any(|f| f["robot"] == 1 && f["tick"] == 50 && f["detected_tick"] == 50));
    assert!(faults.iter().any(|f| f["robot"] == 7 && f["tick"] == 120));
    assert_eq!(
        s["alive_at_end"].as_u64().unwrap(),
        10 - faults.len() as u64
    );
    for d in &dirs[..2] {
        assert_left_nothing(d);
    }
}

#[test]
fn status_lists_the_run_and_kill_rejects_bad_input() {
    let _g = serial();
    let out = tmp_dir("status");
    let child = spawn_up(
        &[
            "--scenario",
            roam(),
            "--robots",
            "5",
            "--max-ticks",
            "100000000",
        ],
        &out,
    );
    let entry = running(&out, 5);
    let run_id = entry["run_id"].as_str().unwrap();
    let o = Command::new(orchestrator()).arg("status").output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains(run_id), "{text}");
    let o = Command::new(orchestrator())
        .args(["kill", "--run", run_id, "--robot", "9"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("0..=4"), "{}", stderr(&o));
    let o = Command::new(orchestrator())
        .args(["kill", "--run", "nope", "--robot", "1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = Command::new(orchestrator())
        .args(["kill", "--run", run_id, "--robots", "1,3"])
        .output()
        .unwrap();
    assert!(o.status.success());
    wait_for("two robots dead", Duration::from_secs(10), || {
        registry_of(&out).is_some_and(|r| r["dead"] == 2)
    });
    // SAFETY: Ctrl-C to our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = finish(child, Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    let s = summary(&out);
    let mut dead: Vec<u64> = s["faults"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["robot"].as_u64().unwrap())
        .collect();
    dead.sort();
    assert_eq!(dead, vec![1, 3]);
    assert!(s["faults"][0]["detection_ms"].as_f64().unwrap() < 1000.0);
    assert_left_nothing(&out);
}

/// A hung agent (SIGSTOP) is declared dead at the ack deadline, its process is killed, and
/// under `restart` a new agent takes the robot over (issue 14 item 2: the fault had
/// `restarted_tick: null` and the stopped process idled to the end of the run after SIGCONT).
#[test]
fn a_hung_agent_is_killed_and_restarted() {
    let _g = serial();
    let out = tmp_dir("sigstop");
    std::fs::create_dir_all(std::env::temp_dir()).unwrap();
    let file = std::env::temp_dir().join(format!("swarm-e2e-{}-sigstop.toml", std::process::id()));
    let roam_text = std::fs::read_to_string(roam()).unwrap();
    std::fs::write(
        &file,
        format!("{roam_text}\n[runtime]\nack_deadline_ms = 400\n"),
    )
    .unwrap();
    let child = spawn_up(
        &[
            "--scenario",
            file.to_str().unwrap(),
            "--robots",
            "6",
            "--max-ticks",
            "100000000",
            "--tick-hz",
            "200",
            "--on-fault",
            "restart",
        ],
        &out,
    );
    let entry = running(&out, 6);
    let hung = entry["agent_pids"][2].as_u64().unwrap() as i32;
    // SAFETY: a signal to an agent of the run this test started.
    unsafe { libc::kill(hung, libc::SIGSTOP) };
    wait_for(
        "the hung agent to be replaced",
        Duration::from_secs(20),
        || {
            registry_of(&out).is_some_and(|r| {
                r["agent_pids"][2].as_u64() != Some(hung as u64)
                    && r["restarted"] == 1
                    && r["alive"] == 6
            })
        },
    );
    assert!(!pid_alive(hung), "the hung agent's process was killed");
    // SAFETY: as above (no effect on a dead pid that was not reused within this test).
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = finish(child, Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    let s = summary(&out);
    let faults = s["faults"].as_array().unwrap();
    assert_eq!(faults.len(), 1, "{faults:?}");
    assert_eq!(faults[0]["robot"], 2);
    assert_eq!(
        faults[0]["cause"].as_str(),
        Some("no action within runtime.ack_deadline_ms")
    );
    assert!(faults[0]["restarted_tick"].is_u64(), "{faults:?}");
    assert_eq!(s["alive_at_end"], 6);
    assert_left_nothing(&out);
}

/// Under `--on-fault restart`, killing every robot at once (all four at tick 20, scheduled)
/// restarts them all: the run does not end "all robots dead" while restarts are left
/// (issue 37 item 9; before, it ended at tick 20), and a Ctrl-C then ends it with 130 and
/// every robot back.
#[test]
fn killing_every_robot_under_restart_restarts_them_all() {
    let _g = serial();
    let out = tmp_dir("kill-all-restart");
    let child = spawn_up(
        &[
            "--scenario",
            roam(),
            "--robots",
            "4",
            "--max-ticks",
            "100000000",
            "--tick-hz",
            "200",
            "--on-fault",
            "restart",
            "--chaos-at",
            "20:0,20:1,20:2,20:3",
        ],
        &out,
    );
    wait_for("every robot restarted", Duration::from_secs(30), || {
        registry_of(&out).is_some_and(|r| r["restarted"] == 4 && r["alive"] == 4)
    });
    // SAFETY: Ctrl-C to our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let o = finish(child, Duration::from_secs(30));
    assert_eq!(o.status.code(), Some(exit::SIGINT), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["end"], "interrupted");
    assert_every_kill_restarted(&s, 4);
    assert!(s["faults"]
        .as_array()
        .unwrap()
        .iter()
        .all(|f| f["tick"] == 20));
    assert_eq!(s["alive_at_end"], 4);
    assert_left_nothing(&out);
}
