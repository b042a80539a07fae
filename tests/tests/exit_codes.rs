//! `orchestrator up`'s exit codes tell a script what happened (issue 37 items 8, 10, 11):
//! complete, mission not complete, interrupted (SIGINT / SIGTERM, both executors, mid-run),
//! failed (an agent program that exits at once), bad input. Real processes, real signals.

use e2e::*;
use std::path::{Path, PathBuf};
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

#[test]
fn a_run_that_accomplishes_its_mission_exits_0_and_one_that_does_not_exits_3() {
    let _g = serial();
    // Roam has no goal: running its max_ticks with robots alive is complete.
    let out = tmp_dir("exit-complete");
    let o = up(
        &["--scenario", roam(), "--robots", "3", "--max-ticks", "40"],
        &out,
    );
    assert_eq!(o.status.code(), Some(exit::COMPLETE), "{}", stderr(&o));
    assert_left_nothing(&out);
    // Search, 5 ticks: no target can be found that soon.
    let out = tmp_dir("exit-not-complete");
    let o = up(&["--robots", "3", "--max-ticks", "5"], &out);
    assert_eq!(
        o.status.code(),
        Some(exit::MISSION_NOT_COMPLETE),
        "{}",
        stderr(&o)
    );
    let s = summary(&out);
    assert!(s["mission"]["search"]["found"].as_u64() < s["mission"]["search"]["targets"].as_u64());
    assert_left_nothing(&out);
    // Every robot killed (drop): the run ends "all robots dead", its mission not complete.
    for exec in ["processes", "inprocess"] {
        let out = tmp_dir(&format!("exit-all-dead-{exec}"));
        let o = up(
            &[
                "--scenario",
                roam(),
                "--robots",
                "2",
                "--max-ticks",
                "1000",
                "--chaos-at",
                "5:0,5:1",
                "--executor",
                exec,
            ],
            &out,
        );
        assert_eq!(
            o.status.code(),
            Some(exit::MISSION_NOT_COMPLETE),
            "{exec}: {}",
            stderr(&o)
        );
        assert_eq!(summary(&out)["end"], "all robots dead");
        if exec == "processes" {
            assert_left_nothing(&out);
        }
    }
}

/// SIGINT and SIGTERM mid-run, in both executors: the run stops within seconds (a paced run
/// of 10^8 ticks), exits 128 + the signal, writes every output (end "interrupted") and
/// leaves nothing in /dev/shm. Before, the in-process executor ignored both signals and a
/// Ctrl-C mid-run exited 0.
#[test]
fn sigint_and_sigterm_mid_run_exit_128_plus_the_signal_with_outputs_written() {
    let _g = serial();
    for exec in ["processes", "inprocess"] {
        for (sig, code) in [(libc::SIGINT, exit::SIGINT), (libc::SIGTERM, exit::SIGTERM)] {
            let tag = format!("sig-{exec}-{sig}");
            let out = tmp_dir(&tag);
            let id = own_run_id(&tag);
            let child = spawn_up_as(
                &[
                    "--scenario",
                    roam(),
                    "--robots",
                    "4",
                    "--max-ticks",
                    "100000000",
                    "--tick-hz",
                    "200",
                    "--executor",
                    exec,
                ],
                &out,
                Some(&id),
            );
            if exec == "processes" {
                let t = Instant::now();
                while registry_tick(&out) < 20 {
                    assert!(t.elapsed() < Duration::from_secs(30), "{tag}: never ticked");
                    std::thread::sleep(Duration::from_millis(10));
                }
            } else {
                // No registry entry in-process: at 200 ticks/s, ticks are under way by then.
                std::thread::sleep(Duration::from_millis(800));
            }
            // SAFETY: a signal to the orchestrator this test started.
            unsafe { libc::kill(child.id() as i32, sig) };
            let o = wait_with_timeout(child, Duration::from_secs(30));
            assert_eq!(o.status.code(), Some(code), "{tag}: {}", stderr(&o));
            let s = summary(&out);
            assert_eq!(s["end"], "interrupted", "{tag}");
            let ticks = s["ticks"].as_u64().unwrap();
            assert!(ticks > 0 && ticks < 100_000_000, "{tag}: {ticks} ticks");
            for f in ["scenario.toml", "recording.bin", "run.svg"] {
                assert!(out.join(f).is_file(), "{tag}: no {f}");
            }
            let (_, recorded) = swarm::recording::read_recording(
                std::fs::File::open(out.join("recording.bin")).unwrap(),
            )
            .unwrap();
            assert_eq!(
                recorded.len() as u64,
                ticks,
                "{tag}: the recording is whole"
            );
            assert!(shm_of_run(&id).is_empty(), "{tag}: {:?}", shm_of_run(&id));
            assert_left_nothing(&out);
        }
    }
}

/// A folder with this build's orchestrator and world and, as `agent`, a program that exits
/// at once with `code`: a broken or hostile agent program.
fn broken_agent_install(tag: &str, code: i32) -> PathBuf {
    let dir = tmp_dir(tag);
    std::fs::create_dir_all(&dir).unwrap();
    for b in ["orchestrator", "world"] {
        std::fs::copy(bin_dir().join(b), dir.join(b)).unwrap();
    }
    let agent = dir.join("agent");
    std::fs::write(&agent, format!("#!/bin/sh\nexit {code}\n")).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&agent, std::fs::Permissions::from_mode(0o755)).unwrap();
    dir
}

fn up_with(install: &Path, args: &[&str], out: &Path, id: &str) -> Output {
    Command::new(install.join("orchestrator"))
        .args(["up", "--quiet", "--out"])
        .arg(out)
        .args(args)
        .env("SWARM_RUN_ID", id)
        .output()
        .unwrap()
}

/// An agent program that exits at once, under drop (once) and under restart (again and
/// again, exit code 0 or not): the run fails within seconds (exit 1) naming the robot and
/// the command, never waits for runtime.startup_timeout_s (120 s), and leaves nothing in
/// /dev/shm. Before: "all robots dead" and exit 0, or a wait of 120 s for an exit-0 agent.
#[test]
fn an_agent_program_that_exits_at_once_fails_the_run_naming_robot_and_command() {
    let _g = serial();
    for (code, policy) in [(0, "drop"), (7, "drop"), (0, "restart"), (7, "restart")] {
        let tag = format!("broken-agent-{code}-{policy}");
        let install = broken_agent_install(&tag, code);
        let out = install.join("run");
        let id = own_run_id(&tag);
        let t = Instant::now();
        let o = up_with(
            &install,
            &[
                "--scenario",
                roam(),
                "--robots",
                "3",
                "--max-ticks",
                "100000",
                "--tick-hz",
                "100",
                "--on-fault",
                policy,
                "--max-restarts",
                "50",
            ],
            &out,
            &id,
        );
        let took = t.elapsed();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(exit::FAILED), "{tag}: {err}");
        // Every robot's agent is the broken program: whichever is reaped first is named.
        let failed = (0..3)
            .find(|r| err.contains(&format!("robot {r} failed")))
            .unwrap_or_else(|| panic!("{tag}: no robot named: {err}"));
        assert!(
            err.contains(&format!(
                "{} --robot {failed}",
                install.join("agent").display()
            )),
            "{tag}: the command: {err}"
        );
        assert!(
            err.contains(&format!("exit code {code}")),
            "{tag}: how it ended: {err}"
        );
        let times = if policy == "drop" { "1 time" } else { "3 time" };
        assert!(err.contains(times), "{tag}: {err}");
        // Generous for a loaded machine; the run fails in well under a second here.
        assert!(took < Duration::from_secs(20), "{tag}: took {took:?}");
        assert!(shm_of_run(&id).is_empty(), "{tag}: {:?}", shm_of_run(&id));
        let _ = std::fs::remove_dir_all(&install);
    }
}

#[test]
fn bad_input_exits_2_before_anything_starts() {
    let _g = serial();
    let out = tmp_dir("exit-bad");
    let o = up(&["--robots", "0"], &out);
    assert_eq!(o.status.code(), Some(exit::BAD_INPUT), "{}", stderr(&o));
    let o = up_as(&["--robots", "2"], &out, Some("../escape"));
    assert_eq!(o.status.code(), Some(exit::BAD_INPUT), "{}", stderr(&o));
    assert!(stderr(&o).contains("SWARM_RUN_ID"), "{}", stderr(&o));
    // Restart in one process: refused, naming the key and the flag that set it (before, it
    // did nothing and said nothing).
    let o = up(
        &[
            "--executor",
            "inprocess",
            "--on-fault",
            "restart",
            "--robots",
            "2",
        ],
        &out,
    );
    assert_eq!(o.status.code(), Some(exit::BAD_INPUT), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--on-fault: `faults.on_fault`"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists(), "nothing started, no run folder");
}
