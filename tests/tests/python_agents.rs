//! Python robots (issue 38): agent programs written with the `swarm` Python package, run by
//! a real interpreter (the repository's `.venv`, made by scripts/test.sh's `need_python`) as
//! real processes of a run: reproducible, restarted after a SIGKILL, and a `step` that raises
//! is a fault with its traceback in the robot's log.

use e2e::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The repository.
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The venv's interpreter, with the package installed (`need_python` of scripts/test.sh).
fn python() -> String {
    let p = repo().join(".venv/bin/python");
    assert!(
        p.exists(),
        "no {}: make it with scripts/test.sh (need_python), which installs ./python into it",
        p.display()
    );
    p.display().to_string()
}

/// A scenario in `dir`: configs/roam.toml's arena and radio, `robots` robots, `ticks` ticks,
/// and the given `[[agents]]` entries (TOML text).
fn scenario(dir: &Path, robots: u32, ticks: u64, agents: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let base = std::fs::read_to_string(roam()).unwrap().replacen(
        "[run]\n",
        &format!("[run]\nrobots = {robots}\n"),
        1,
    );
    let base = base.replace("max_ticks = 500", &format!("max_ticks = {ticks}"));
    let path = dir.join("scenario.toml");
    std::fs::write(&path, format!("{base}\n{agents}")).unwrap();
    path
}

/// An `[[agents]]` entry running `script` with the venv's Python for `robots`.
fn python_agents(robots: &str, script: &Path) -> String {
    format!(
        "[[agents]]\nrobots = \"{robots}\"\ncommand = [{:?}, {:?}]\n",
        python(),
        script.display().to_string()
    )
}

/// The Rust example's binary (scripts/test.sh builds examples/rust-boids into target/).
fn rust_boids() -> String {
    let p = bin_dir().join("rust-boids");
    assert!(
        p.exists(),
        "no {}: build examples/rust-boids (scripts/test.sh does)",
        p.display()
    );
    p.display().to_string()
}

/// rust-boids' weights (examples/rust-boids/boids.toml's).
const RUST_BOIDS_PARAMS: &str = "[agents.params]\ncohesion = 0.01\nalignment = 0.125\n\
    separation = 20.0\nseparation_radius = 25.0\navoid = 40.0\ncruise = 0.6\n";

fn boids() -> PathBuf {
    repo().join("examples/python-boids/boids.py")
}

#[test]
fn a_python_swarm_equals_itself_across_runs() {
    let _g = serial();
    let dir = tmp_dir("py-same");
    let sc = scenario(&dir, 8, 150, &python_agents("0..8", &boids()));
    let runs = [dir.join("a"), dir.join("b")];
    for out in &runs {
        let o = up(
            &[
                "--scenario",
                sc.to_str().unwrap(),
                "--executor",
                "processes",
            ],
            out,
        );
        assert!(ended_by_itself(&o), "{}", stderr(&o));
        let s = summary(out);
        assert_eq!(s["ticks"], 150);
        assert_eq!(s["faults"].as_array().unwrap().len(), 0, "{s}");
        // The robots talked: the boids heard each other.
        assert!(s["messages"]["delivered"].as_u64().unwrap() > 1000, "{s}");
        assert_left_nothing(out);
    }
    assert!(same_recording(&runs[0], &runs[1]));
    let (_, ticks) = swarm::recording::read_recording(
        std::fs::File::open(runs[0].join("recording.bin")).unwrap(),
    )
    .unwrap();
    // The Python robots moved (their commands reached the world).
    assert_ne!(ticks[0].poses, ticks[149].poses);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_sigkilled_python_agent_comes_back_under_restart() {
    let _g = serial();
    let dir = tmp_dir("py-kill");
    let sc = scenario(&dir, 6, 3000, &python_agents("0..6", &boids()));
    let out = dir.join("run");
    let child = spawn_up(
        &[
            "--scenario",
            sc.to_str().unwrap(),
            "--on-fault",
            "restart",
            // Paced, so the kill lands mid-run: 3,000 ticks take at least 3 s.
            "--tick-hz",
            "1000",
        ],
        &out,
    );
    let entry = registry_entry(&out, 6);
    let pid = entry["agent_pids"][3].as_u64().unwrap() as i32;
    let cmdline = String::from_utf8_lossy(&std::fs::read(format!("/proc/{pid}/cmdline")).unwrap())
        .into_owned();
    assert!(cmdline.contains("boids.py"), "{cmdline:?}");
    let t = Instant::now();
    while registry_tick(&out) < 200 {
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "the run never ticked"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // SAFETY: SIGKILL to an agent process of this test's run.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGKILL) }, 0);
    let o = child.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["ticks"], 3000);
    assert_every_kill_restarted(&s, 1);
    assert_eq!(s["faults"][0]["robot"], 3);
    assert_eq!(s["alive_at_end"], 6, "{s}");
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_step_that_raises_is_a_fault_with_its_traceback_in_the_log() {
    let _g = serial();
    let dir = tmp_dir("py-raise");
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("raises.py");
    std::fs::write(
        &script,
        "import swarm\n\
         class Raises:\n\
         \x20   def __init__(self, agent):\n\
         \x20       self.robot = agent.robot\n\
         \x20   def step(self, sense, inbox, out):\n\
         \x20       if self.robot == 2 and sense.tick == 30:\n\
         \x20           raise ValueError('robot 2 gives up')\n\
         \x20       return (1.0, 0.0)\n\
         swarm.run(Raises)\n",
    )
    .unwrap();
    let sc = scenario(&dir, 4, 100, &python_agents("0..4", &script));
    let out = dir.join("run");
    let o = up(&["--scenario", sc.to_str().unwrap()], &out);
    // The run goes on without robot 2.
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["ticks"], 100);
    assert_eq!(s["alive_at_end"], 3);
    let faults = s["faults"].as_array().unwrap();
    assert_eq!(faults.len(), 1, "{faults:?}");
    assert_eq!(faults[0]["robot"], 2);
    assert_eq!(faults[0]["tick"], 30);
    let cause = faults[0]["cause"].as_str().unwrap();
    assert!(
        cause.contains("exit code 5") && cause.contains("raised"),
        "{cause}"
    );
    let log = std::fs::read_to_string(out.join("logs/robot-2.log")).expect("robot 2's log");
    assert!(log.contains("Traceback (most recent call last)"), "{log}");
    assert!(log.contains("ValueError: robot 2 gives up"), "{log}");
    assert!(log.contains("raises.py\", line 7, in step"), "{log}");
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_mixed_swarm_of_built_in_rust_and_python_robots_repeats_byte_for_byte() {
    let _g = serial();
    let dir = tmp_dir("py-mixed");
    let agents = format!(
        "[[agents]]\nrobots = \"10..20\"\ncommand = [{:?}]\n{RUST_BOIDS_PARAMS}\n{}",
        rust_boids(),
        python_agents("20..30", &boids())
    );
    let sc = scenario(&dir, 30, 120, &agents);
    let runs = [dir.join("a"), dir.join("b")];
    for out in &runs {
        let o = up(&["--scenario", sc.to_str().unwrap()], out);
        assert!(ended_by_itself(&o), "{}", stderr(&o));
        let s = summary(out);
        assert_eq!(s["ticks"], 120);
        assert_eq!(s["faults"].as_array().unwrap().len(), 0, "{s}");
        assert_left_nothing(out);
    }
    assert!(same_recording(&runs[0], &runs[1]));
    let (_, ticks) = swarm::recording::read_recording(
        std::fs::File::open(runs[0].join("recording.bin")).unwrap(),
    )
    .unwrap();
    // Every third of the swarm moved (each program's commands reached the world).
    for third in [0..10, 10..20, 20..30] {
        assert!(
            third
                .clone()
                .any(|i| ticks[0].poses[i] != ticks[119].poses[i]),
            "robots {third:?} never moved"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Rust boids (examples/rust-boids) and Python boids (examples/python-boids) speak one message
/// (four little-endian f64): in a swarm of only the two, every message delivered decodes, none
/// is malformed, and both halves hear enough to flock.
#[test]
fn rust_and_python_boids_understand_each_other() {
    let _g = serial();
    let dir = tmp_dir("py-interop");
    let agents = format!(
        "[[agents]]\nrobots = \"0..6\"\ncommand = [{:?}]\n{RUST_BOIDS_PARAMS}\n{}",
        rust_boids(),
        python_agents("6..12", &boids())
    );
    let sc = scenario(&dir, 12, 100, &agents);
    let out = dir.join("run");
    let o = up(&["--scenario", sc.to_str().unwrap()], &out);
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["faults"].as_array().unwrap().len(), 0, "{s}");
    assert!(s["messages"]["delivered"].as_u64().unwrap() > 500, "{s}");
    assert_eq!(s["messages"]["malformed"], 0, "{s}");
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Python robots follow the world when it remakes its data services (issue 37: a process of
/// the user truncated the Sense segment, here while the world was stopped and its agents
/// slept): every Python agent opens `world/sense/g1` and `radio/air/g1` through the same loop
/// as a Rust one, and the run completes with no robot hurt.
#[test]
fn python_agents_follow_the_worlds_remade_data_services() {
    let _g = serial();
    let dir = tmp_dir("py-remade");
    let sc = scenario(&dir, 4, 3000, &python_agents("0..4", &boids()));
    let out = dir.join("run");
    let id = own_run_id("py-remade");
    let child = spawn_up_as(
        &["--scenario", sc.to_str().unwrap(), "--tick-hz", "1000"],
        &out,
        Some(&id),
    );
    let t = Instant::now();
    while registry_tick(&out) < 200 {
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "the run never ticked"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let world = world_pid_of(&id);
    let maps = std::fs::read_to_string(format!("/proc/{world}/maps")).unwrap();
    // The world's largest segment it writes: every robot's Sense record.
    let sense = maps
        .lines()
        .filter(|l| l.split_whitespace().nth(1) == Some("rw-s") && l.ends_with(".data"))
        .filter_map(|l| l.split_whitespace().nth(5))
        .max_by_key(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0))
        .expect("the world's Sense segment")
        .to_string();
    // SAFETY: signals to this test's own world process.
    unsafe { libc::kill(world, libc::SIGSTOP) };
    std::thread::sleep(Duration::from_millis(300));
    std::fs::OpenOptions::new()
        .write(true)
        .open(&sense)
        .and_then(|f| f.set_len(0))
        .unwrap();
    // SAFETY: as above.
    unsafe { libc::kill(world, libc::SIGCONT) };
    let o = child.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("made anew as generation 1"),
        "{}",
        stderr(&o)
    );
    let s = summary(&out);
    assert_eq!(s["end"], "completed", "{s}");
    assert_eq!(s["ticks"], 3000);
    assert_eq!(s["faults"], serde_json::json!([]), "{s}");
    assert!(shm_of_run(&id).is_empty(), "{:?}", shm_of_run(&id));
    assert_left_nothing(&out);
    let _ = std::fs::remove_dir_all(&dir);
}
