//! The search scenario end to end: real processes over real iceoryx2, and the experiment grid.

use e2e::*;
use std::path::PathBuf;
use std::process::Command;

fn configs() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

#[test]
fn twenty_robots_in_processes_find_all_targets() {
    let _g = serial();
    let out = tmp_dir("search20");
    let sc = configs().join("search.toml");
    let o = up(
        &[
            "--scenario",
            sc.to_str().unwrap(),
            "--robots",
            "20",
            "--seed",
            "1",
        ],
        &out,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    let m = &s["mission"]["search"];
    assert_eq!(m["targets"], 10, "{s}");
    assert_eq!(m["found"], 10, "all targets found: {m}");
    assert_eq!(s["end"], "all targets found");
    let steps = m["steps"].as_u64().unwrap();
    assert_eq!(steps, s["ticks"].as_u64().unwrap());
    // Energy is path length: at most v_max per robot-step.
    assert!(m["energy"].as_f64().unwrap() <= 10.0 * 20.0 * steps as f64 + 1e-6);
    assert!(s["blocked_moves"].as_u64().is_some());
    let svg = std::fs::read_to_string(out.join("run.svg")).unwrap();
    assert!(svg.contains("<svg"));
    assert_left_nothing(&out);
}

/// A small experiment file in `dir` (created): the search map, seeds from 1, the step cap of
/// Table 5's grid, then `rest` (modes, robots, seeds, paper rows).
fn grid_file(dir: &std::path::Path, rest: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join("grid.toml");
    let head = format!(
        "scenario = {:?}\nfirst_seed = 1\nmax_ticks = 3000\n",
        configs().join("search.toml").display().to_string()
    );
    std::fs::write(&file, head + rest).unwrap();
    file
}

#[test]
fn the_experiment_grid_writes_the_paper_style_table() {
    let _g = serial();
    let dir = tmp_dir("experiment");
    let file = grid_file(
        &dir,
        "modes = [\"BT\", \"BE\"]\nrobots = [20]\nseeds = 2\n\
         paper = [{ robots = 20, mode = \"BT\", steps = [272, 463, 935], energy = [3.979, 5.982, 10.72] }]\n",
    );
    let out = dir.join("results");
    let o = Command::new(orchestrator())
        .args([
            "experiment",
            file.to_str().unwrap(),
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let md = std::fs::read_to_string(out.join("results.md")).unwrap();
    assert!(
        md.contains("| 20 | BT | 2 |") && md.contains("| 20 | BE | 2 |"),
        "{md}"
    );
    assert!(
        md.contains("272 / 463 / 935"),
        "paper values beside ours: {md}"
    );
    // The table as charts beside it: a line per mode, the paper's mean as a cross.
    for chart in ["steps.svg", "energy.svg"] {
        let svg = std::fs::read_to_string(out.join(chart)).unwrap();
        for label in ["BT", "BE", "BT (paper)", "20"] {
            // plotters writes each text on a line of its own.
            assert!(
                svg.contains(&format!("\n{label}\n</text>")),
                "{chart}: no {label}"
            );
        }
    }
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let runs = j["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    // Same seeds for every mode.
    let seeds = |m: &str| -> Vec<u64> {
        runs.iter()
            .filter(|r| r["mode"] == m)
            .map(|r| r["seed"].as_u64().unwrap())
            .collect()
    };
    assert_eq!(seeds("BT"), seeds("BE"));
    for c in j["cells"].as_array().unwrap() {
        if let Some(e) = c["energy_per_robot_step"].as_f64() {
            assert!(e <= 10.0, "energy per robot-step above v_max: {c}");
        }
    }
}

/// The grid with real processes reports exactly what the in-process executor reports (the
/// processes' figures are read back from each run's summary.json: SA at N = 40, seed 1 came
/// back 1 ulp off in its energy before serde_json parsed floats exactly).
#[test]
fn the_experiment_grid_gives_the_same_runs_with_either_executor() {
    let _g = serial();
    let dir = tmp_dir("experiment-executors");
    let file = grid_file(&dir, "modes = [\"BT\", \"SA\"]\nrobots = [40]\nseeds = 1\n");
    // Both files as text: parsed, two floats 1 ulp apart can read back as one.
    let results = |executor: &str| -> (String, String) {
        let out = dir.join(executor);
        let o = Command::new(orchestrator())
            .args([
                "experiment",
                file.to_str().unwrap(),
                "--executor",
                executor,
                "--quiet",
            ])
            .args(["--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{executor}: {}", stderr(&o));
        let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
        (read("results.json"), read("results.md"))
    };
    let (p, i) = (results("processes"), results("inprocess"));
    assert!(p.0.contains("\"mode\": \"SA\""), "{}", p.0);
    assert_eq!(p.0, i.0, "results.json, processes vs in-process");
    assert_eq!(p.1, i.1, "results.md, processes vs in-process");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 4 item 6: with 20 % of the agents SIGKILLed (real processes, real signals), under drop
/// and under restart, the swarm still finds every target in at least 19 of 20 seeds.
#[test]
fn the_mission_survives_twenty_percent_of_agents_killed() {
    let _g = serial();
    let out = tmp_dir("search-faults");
    // The experiment's id is fixed, so the test knows every run's shared-memory prefix
    // (`<id>-<mode>-<robots>-<seed>-<job>`) and judges only its own runs' files.
    let id = own_run_id("faults");
    let o = Command::new(orchestrator())
        .env("SWARM_RUN_ID", &id)
        .args([
            "experiment",
            configs().join("search-faults.toml").to_str().unwrap(),
            "--executor",
            "processes",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let runs = j["runs"].as_array().unwrap();
    for variant in ["no faults", "drop 20 %", "restart 20 %"] {
        let rs: Vec<&serde_json::Value> = runs.iter().filter(|r| r["variant"] == variant).collect();
        assert_eq!(rs.len(), 20, "{variant}");
        let found_all = rs.iter().filter(|r| r["steps"].is_u64()).count();
        assert!(
            found_all >= 19,
            "{variant}: all targets found in only {found_all} of 20 seeds"
        );
        let killed: u64 = rs.iter().map(|r| r["faults"].as_u64().unwrap()).sum();
        let restarted: u64 = rs.iter().map(|r| r["restarted"].as_u64().unwrap()).sum();
        match variant {
            "no faults" => assert_eq!(killed, 0),
            "drop 20 %" => assert_eq!((killed, restarted), (80, 0), "4 of 20 robots, 20 seeds"),
            _ => {
                assert_eq!(killed, 80);
                // A restart counts only if the new agent attaches (~0.2 s here, under two runs
                // of 21 processes on 2 cores) before the last target is found, so the count
                // falls as ticks get faster: 67-72 of 80 on this VM before the search kernels
                // were sped up, 53-67 after. "Most" is the claim.
                assert!(
                    restarted > 40,
                    "most killed robots come back: {restarted} of 80"
                );
            }
        }
    }
    let prefixes: std::collections::BTreeSet<String> = runs
        .iter()
        .flat_map(|r| {
            let (mode, n, seed) = (
                r["mode"].as_str().unwrap().to_string(),
                r["robots"].as_u64().unwrap(),
                r["seed"].as_u64().unwrap(),
            );
            let id = id.clone();
            (0..runs.len()).map(move |job| {
                swarm::transport::prefix_for(&format!("{id}-{mode}-{n}-{seed}-{job}"))
            })
        })
        .collect();
    let left: Vec<String> = run_shm_entries()
        .into_iter()
        .filter(|e| prefixes.iter().any(|p| e.starts_with(p)))
        .collect();
    assert!(left.is_empty(), "this experiment's runs left {left:?}");
}
