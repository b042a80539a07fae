//! Robots run by programs of the user's (issue 38): `[[agents]]` entries naming the
//! rust-boids example (examples/rust-boids, built against swarm's public API) or small shell
//! programs, beside built-in roaming robots. Real processes, real SIGKILLs.

use e2e::programs::*;
use e2e::*;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn up_file(scenario: &Path, extra: &[&str], out: &Path) -> Output {
    let mut args = vec!["--scenario", scenario.to_str().unwrap()];
    args.extend_from_slice(extra);
    up(&args, out)
}

fn logs(args: &[&str]) -> Output {
    Command::new(orchestrator())
        .arg("logs")
        .args(args)
        .output()
        .unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// 10 built-in roaming robots and 10 rust-boids ones in one swarm, twice: the same recording
/// byte for byte, every robot alive and every tick run (lock-step: the world waits for all
/// 20 acks each tick), and not the recording of 20 built-in robots (the boids ran).
#[test]
fn a_mixed_swarm_of_built_in_and_rust_boids_robots_runs_lock_step_and_repeats_exactly() {
    let _g = serial();
    let dir = tmp_dir("own-mixed");
    let sc = scenario_with_agents(&dir, "robots = 20", &[boids_entry("\"10..20\"")]);
    let runs: Vec<_> = ["a", "b"]
        .iter()
        .map(|t| {
            let out = dir.join(t);
            let o = up_file(&sc, &["--max-ticks", "200"], &out);
            assert_eq!(o.status.code(), Some(exit::COMPLETE), "{}", stderr(&o));
            let s = summary(&out);
            assert_eq!(s["ticks"].as_u64(), Some(200), "{s}");
            assert_eq!(s["alive_at_end"].as_u64(), Some(20), "{s}");
            assert_left_nothing(&out);
            out
        })
        .collect();
    assert!(same_recording(&runs[0], &runs[1]), "two runs differ");
    let log = std::fs::read_to_string(runs[0].join("logs/robot-15.log")).unwrap();
    assert!(log.contains("rust-boids --robot 15"), "{log}");
    let builtin = dir.join("builtin");
    let o = up(
        &["--scenario", roam(), "--robots", "20", "--max-ticks", "200"],
        &builtin,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!same_recording(&runs[0], &builtin), "the boids did not run");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A rust-boids agent SIGKILLed (a scheduled kill at tick 60) under `--on-fault restart`
/// comes back: the fault is restarted, its log holds two starts, all robots end alive.
#[test]
fn a_sigkilled_rust_boids_agent_is_restarted() {
    let _g = serial();
    let dir = tmp_dir("own-restart");
    let sc = scenario_with_agents(&dir, "robots = 6", &[boids_entry("[3, 4, 5]")]);
    let out = dir.join("run");
    let o = up_file(
        &sc,
        &[
            "--max-ticks",
            "300",
            "--tick-hz",
            "200",
            "--on-fault",
            "restart",
            "--chaos-at",
            "60:4",
        ],
        &out,
    );
    assert_eq!(o.status.code(), Some(exit::COMPLETE), "{}", stderr(&o));
    let s = summary(&out);
    assert_every_kill_restarted(&s, 1);
    assert_eq!(s["faults"][0]["robot"].as_u64(), Some(4), "{s}");
    assert_eq!(s["alive_at_end"].as_u64(), Some(6), "{s}");
    let log = std::fs::read_to_string(out.join("logs/robot-4.log")).unwrap();
    assert_eq!(log.matches("--- swarm: agent start").count(), 2, "{log}");
    assert!(log.contains("agent start 2 of robot 4"), "{log}");
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A program that exits at once and one that stays alive without attaching: each run fails
/// within seconds (not runtime.startup_timeout_s = 120 s) with exit 1, naming the robot, the
/// command and how it ended, and quoting the program's last output; nothing is left behind.
#[test]
fn a_program_that_exits_at_once_or_never_attaches_is_reported_fast() {
    let _g = serial();
    let dir = tmp_dir("own-broken");
    let sh = |script: &str| {
        vec![
            "/bin/sh".to_string(),
            "-c".into(),
            script.into(),
            "sh".into(),
        ]
    };
    let cases = [
        (
            "exits",
            sh("echo 'cannot open the camera' >&2; exit 7"),
            "",
            "exit code 7",
        ),
        (
            "hangs",
            sh("echo 'waiting for a licence server'; exec sleep 600.123"),
            "attach_timeout_s = 1\n",
            "did not attach within 1 s",
        ),
    ];
    for (tag, command, extra, how) in cases {
        let sc = scenario_with_agents(
            &dir.join(tag),
            "robots = 4",
            &[Entry {
                robots: "[2]",
                command,
                params: "",
                extra,
            }],
        );
        let id = own_run_id(&format!("own-{tag}"));
        let t = Instant::now();
        let o = up_as(
            &["--scenario", sc.to_str().unwrap(), "--max-ticks", "100000"],
            &dir.join(tag).join("run"),
            Some(&id),
        );
        let took = t.elapsed();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(exit::FAILED), "{tag}: {err}");
        assert!(err.contains("robot 2 failed"), "{tag}: {err}");
        assert!(err.contains("/bin/sh -c"), "{tag}: the command: {err}");
        assert!(err.contains(how), "{tag}: {err}");
        let said = if tag == "exits" {
            "cannot open the camera"
        } else {
            "waiting for a licence server"
        };
        assert!(err.contains(said), "{tag}: its output: {err}");
        // Generous for a loaded machine: the run fails in about 1 s here.
        assert!(took < Duration::from_secs(20), "{tag}: took {took:?}");
        assert!(shm_of_run(&id).is_empty(), "{tag}: {:?}", shm_of_run(&id));
        assert!(
            processes_mentioning("600.123").is_empty(),
            "{tag}: the program lives on"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `orchestrator logs`: a robot's output (a wrapper that prints a line, then runs the boid),
/// by run folder and --robot, by run id while the run goes on with --follow (which ends with
/// the run), and every robot's log under a header each.
#[test]
fn orchestrator_logs_shows_what_a_robot_printed() {
    let _g = serial();
    let dir = tmp_dir("own-logs");
    let boids = rust_boids().display().to_string();
    let sc = scenario_with_agents(
        &dir,
        "robots = 3",
        &[Entry {
            robots: "[1]",
            command: vec![
                "/bin/sh".into(),
                "-c".into(),
                "echo \"boid $2 says hello\"; exec \"$0\" \"$@\"".into(),
                boids,
            ],
            params: BOIDS_PARAMS,
            extra: "",
        }],
    );
    let out = dir.join("run");
    let id = own_run_id("own-logs");
    let mut child = spawn_up_as(
        &[
            "--scenario",
            sc.to_str().unwrap(),
            "--max-ticks",
            "150",
            "--tick-hz",
            "50",
        ],
        &out,
        Some(&id),
    );
    // Follow the live run by its id (once it is registered), until it ends.
    let t = Instant::now();
    while registry_of(&out).is_none() && t.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let follow = logs(&[&id, "--follow"]);
    assert!(follow.status.success(), "{}", stderr(&follow));
    let o = child.wait().unwrap();
    assert!(o.success());
    let text = stdout(&follow);
    assert!(text.contains("robot-1| boid 1 says hello"), "{text}");
    assert!(
        text.contains("robot-0| --- swarm: agent start 1 of robot 0"),
        "{text}"
    );
    let one = logs(&[out.to_str().unwrap(), "--robot", "1"]);
    assert!(one.status.success(), "{}", stderr(&one));
    let text = stdout(&one);
    assert!(
        text.starts_with("--- swarm: agent start 1 of robot 1"),
        "{text}"
    );
    assert!(text.contains("\nboid 1 says hello\n"), "{text}");
    let all = stdout(&logs(&[out.to_str().unwrap()]));
    for r in 0..3 {
        assert!(all.contains(&format!("robot-{r}.log <==")), "{all}");
    }
    let o = logs(&[out.to_str().unwrap(), "--robot", "7"]);
    assert_eq!(o.status.code(), Some(exit::BAD_INPUT));
    assert!(stderr(&o).contains("--robot 7"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad `[[agents]]` input exits 2 naming the file, its line and the key path: robots in two
/// entries, a robot out of range, an empty command, a program that is not there, a
/// parameter of the wrong type (found by the program: the SDK's error, passed on), and the
/// in-process executor, which cannot run programs.
#[test]
fn bad_agents_input_exits_2_naming_file_key_and_line() {
    let _g = serial();
    let dir = tmp_dir("own-bad");
    let boids = vec![rust_boids().display().to_string()];
    let entry = |robots, command: &Vec<String>, params| Entry {
        robots,
        command: command.clone(),
        params,
        extra: "",
    };
    let bad_params = BOIDS_PARAMS.replace("alignment = 0.125", "alignment = \"strong\"");
    // (tag, entries, more flags, the key named, the start of the line named)
    type Case<'a> = (&'a str, Vec<Entry<'a>>, &'a [&'a str], &'a str, &'a str);
    let cases: Vec<Case> = vec![
        (
            "overlap",
            vec![entry("\"0..3\"", &boids, ""), entry("[5, 2]", &boids, "")],
            &[],
            "agents[1].robots",
            "robots = [5, 2]",
        ),
        (
            "range",
            vec![entry("\"2..9\"", &boids, "")],
            &[],
            "agents[0].robots",
            "robots = \"2..9\"",
        ),
        (
            "empty",
            vec![entry("[1]", &vec![], "")],
            &[],
            "agents[0].command",
            "command = []",
        ),
        (
            "missing",
            vec![entry("[1]", &vec!["./no-such-program".into()], "")],
            &[],
            "agents[0].command",
            "command = [\"./no-such-program\"]",
        ),
        (
            "params",
            vec![entry("[1]", &boids, &bad_params)],
            &[],
            "agents[0].params.alignment",
            "alignment = ",
        ),
        (
            "inprocess",
            vec![entry("[1]", &boids, BOIDS_PARAMS)],
            &["--executor", "inprocess"],
            "agents",
            "[[agents]]",
        ),
    ];
    for (tag, entries, flags, key, line_of) in cases {
        let sc = scenario_with_agents(&dir.join(tag), "robots = 5", &entries);
        let mut args = vec!["--scenario", sc.to_str().unwrap(), "--max-ticks", "50"];
        args.extend_from_slice(flags);
        let o = up(&args, &dir.join(tag).join("run"));
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(exit::BAD_INPUT), "{tag}: {err}");
        let line = line_starting(&sc, line_of);
        let at = format!("{}:{line}", sc.display());
        assert!(err.contains(&at), "{tag}: wants {at}: {err}");
        assert!(err.contains(key), "{tag}: wants {key}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
