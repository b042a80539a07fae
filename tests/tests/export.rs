//! `orchestrator export` of real runs: the MCAP's every message validates against Foxglove's
//! published JSON schemas (the npm package `@foxglove/schemas`, installed by this test into
//! tests/foxglove/node_modules with `npm ci`), its chunks are compressed, its log times are the
//! scenario's simulated time; the CSV holds the recording's numbers, simulated time and state
//! names; the events export holds every event of the recording.

use e2e::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use swarm::recording::TickRecord;

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

/// The test's npm folder (package.json and package-lock.json pin the schemas' version).
fn npm_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("foxglove")
}

/// Foxglove's JSON schemas by name (`foxglove.SceneUpdate`: schema), from the npm package.
fn foxglove_schemas() -> &'static BTreeMap<String, serde_json::Value> {
    static S: OnceLock<BTreeMap<String, serde_json::Value>> = OnceLock::new();
    S.get_or_init(|| {
        let dir = npm_dir();
        if !dir.join("node_modules/@foxglove/schemas").exists() {
            let o = Command::new("npm")
                .args(["ci", "--no-audit", "--no-fund"])
                .current_dir(&dir)
                .output()
                .expect("npm (Debian package npm; scripts/test.sh installs it)");
            assert!(o.status.success(), "npm ci: {}", stderr(&o));
        }
        let o = Command::new("node")
            .args([
                "-e",
                "process.stdout.write(JSON.stringify(require('@foxglove/schemas/jsonschema')))",
            ])
            .current_dir(&dir)
            .output()
            .expect("node (Debian package nodejs; scripts/test.sh installs it)");
        assert!(o.status.success(), "node: {}", stderr(&o));
        let all: BTreeMap<String, serde_json::Value> =
            serde_json::from_slice(&o.stdout).expect("the schemas as JSON");
        all.into_values()
            .map(|s| (s["title"].as_str().expect("a title").to_string(), s))
            .collect()
    })
}

fn export(run: &Path, format: &str) {
    let o = Command::new(orchestrator())
        .args(["export", run.to_str().unwrap(), "--format", format])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}

fn ticks_of(run: &Path) -> Vec<TickRecord> {
    swarm::recording::read_recording(std::fs::File::open(run.join("recording.bin")).unwrap())
        .unwrap()
        .1
}

/// A search run of 12 robots on processes, robot 4 SIGKILLed at tick 30.
fn search_run(tag: &str) -> PathBuf {
    let out = tmp_dir(tag);
    let sc = configs().join("search.toml");
    let o = up(
        &[
            "--scenario",
            sc.to_str().unwrap(),
            "--robots",
            "12",
            "--seed",
            "3",
            "--max-ticks",
            "160",
            "--chaos-at",
            "30:4",
        ],
        &out,
    );
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    out
}

#[test]
fn every_mcap_message_validates_against_foxglove_schemas_in_compressed_chunks() {
    let _g = serial();
    let out = search_run("export-mcap");
    let ticks = ticks_of(&out);
    export(&out, "mcap");
    let bytes = std::fs::read(out.join("recording.mcap")).unwrap();
    let schemas = foxglove_schemas();
    let mut validators = BTreeMap::new();
    let mut per_topic: BTreeMap<String, usize> = BTreeMap::new();
    let mut first_scene: Option<serde_json::Value> = None;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m.channel.schema.as_ref().expect("a schema");
        assert_eq!(schema.encoding, "jsonschema");
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        if schema.name.starts_with("foxglove.") {
            let published = &schemas[&schema.name];
            // The schema record is Foxglove's own, as published.
            let recorded: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
            assert_eq!(&recorded, published, "{}", schema.name);
            let val = validators.entry(schema.name.clone()).or_insert_with(|| {
                jsonschema::validator_for(published).expect("a valid JSON schema")
            });
            let errors: Vec<String> = val.iter_errors(&v).map(|e| e.to_string()).collect();
            assert!(
                errors.is_empty(),
                "{} message on {} at tick {}: {errors:?}",
                schema.name,
                m.channel.topic,
                m.sequence
            );
        }
        if m.channel.topic == "/scene" && first_scene.is_none() {
            first_scene = Some(v);
        }
        *per_topic.entry(m.channel.topic.clone()).or_default() += 1;
    }
    let n = ticks.len();
    let events: usize = ticks.iter().map(|t| t.events.len()).sum();
    assert!(events >= 1, "the kill at tick 30 is an event");
    assert_eq!(
        per_topic.into_iter().collect::<Vec<_>>(),
        vec![
            ("/events".to_string(), events),
            ("/scene".to_string(), n),
            ("/swarm/radio".to_string(), n),
            ("/tf".to_string(), n),
        ]
    );
    // Robot 7 of the first tick where the recording puts it, named by its state.
    let scene = first_scene.unwrap();
    let robot = scene["entities"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["id"] == "robot/7")
        .expect("entity robot/7");
    let at = &robot["cylinders"][0]["pose"]["position"];
    assert_eq!(at["x"].as_f64(), Some(ticks[0].poses[7][0]));
    assert_eq!(at["y"].as_f64(), Some(ticks[0].poses[7][1]));
    let meta: BTreeMap<&str, &str> = robot["metadata"]
        .as_array()
        .unwrap()
        .iter()
        .map(|kv| (kv["key"].as_str().unwrap(), kv["value"].as_str().unwrap()))
        .collect();
    assert_eq!(meta["state"], ticks[0].states[7].to_string());
    assert!(!meta["state_name"].is_empty(), "{meta:?}");
    // The mission's targets are in the scene, labelled.
    assert!(
        scene["entities"].as_array().unwrap().iter().any(|e| e["id"]
            .as_str()
            .unwrap()
            .starts_with("mark/")
            && e["metadata"].to_string().contains("target")),
        "no target among the entities"
    );
    // Every chunk is compressed.
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    assert!(!summary.chunk_indexes.is_empty());
    for c in &summary.chunk_indexes {
        assert_eq!(c.compression, "zstd");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// (log time in ns, tick) of every `/tf` message, and the file's `swarm run` metadata.
fn times_and_metadata(mcap_file: &Path) -> (Vec<(u64, u32)>, BTreeMap<String, String>) {
    let bytes = std::fs::read(mcap_file).unwrap();
    let times = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/tf")
        .map(|m| (m.log_time, m.sequence))
        .collect();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let index = summary
        .metadata_indexes
        .iter()
        .find(|i| i.name == "swarm run")
        .expect("a swarm run metadata record");
    let meta = mcap::read::metadata(&bytes, index).unwrap().metadata;
    (times, meta)
}

#[test]
fn log_times_are_the_scenarios_simulated_time() {
    let _g = serial();
    // The hunt: 0.05 minutes a tick, 3 s.
    let out = tmp_dir("export-hunt-time");
    let sc = configs().join("hunt-auction.toml");
    let o = up(
        &[
            "--executor",
            "inprocess",
            "--scenario",
            sc.to_str().unwrap(),
            "--max-ticks",
            "20",
        ],
        &out,
    );
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    export(&out, "mcap");
    export(&out, "csv");
    let (times, meta) = times_and_metadata(&out.join("recording.mcap"));
    assert_eq!(times.len(), ticks_of(&out).len());
    for (ns, tick) in &times {
        assert_eq!(*ns, u64::from(*tick) * 3_000_000_000, "tick {tick}");
    }
    assert_eq!(meta["seconds_per_tick"], "3");
    assert!(meta["time"].contains("minutes_per_tick"), "{meta:?}");
    let csv = std::fs::read_to_string(out.join("recording.csv")).unwrap();
    for row in csv.lines().skip(1) {
        let c: Vec<&str> = row.split(',').collect();
        let tick: f64 = c[0].parse().unwrap();
        assert_eq!(c[1].parse::<f64>().unwrap(), tick * 3.0, "{row}");
    }
    let _ = std::fs::remove_dir_all(&out);
    // A scenario with no unit of time: a tick is a second, and the file says so.
    let out = tmp_dir("export-roam-time");
    let o = up(&["--scenario", roam(), "--max-ticks", "10"], &out);
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    export(&out, "mcap");
    let (times, meta) = times_and_metadata(&out.join("recording.mcap"));
    assert_eq!(times.len(), 10);
    for (ns, tick) in &times {
        assert_eq!(*ns, u64::from(*tick) * 1_000_000_000);
    }
    assert_eq!(meta["seconds_per_tick"], "1");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn the_csv_holds_the_recordings_numbers_and_state_names_and_events_every_event() {
    let _g = serial();
    let out = search_run("export-csv");
    let ticks = ticks_of(&out);
    export(&out, "csv");
    export(&out, "events");
    let csv = std::fs::read_to_string(out.join("recording.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("tick,time_s,robot,x,y,heading,state,state_name,alive")
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), ticks.len() * 12);
    // The search mission's display states (papers/search/src/mission.rs).
    let names = ["roaming", "cooperative", "declared"];
    let mut named = 0;
    for (row, (t, i)) in rows
        .iter()
        .zip(ticks.iter().flat_map(|t| (0..12).map(move |i| (t, i))))
    {
        let c: Vec<&str> = row.split(',').collect();
        assert_eq!(c[0].parse::<u64>().unwrap(), t.tick);
        assert_eq!(c[1].parse::<f64>().unwrap(), t.tick as f64);
        assert_eq!(c[2].parse::<usize>().unwrap(), i);
        let xyh: Vec<f64> = c[3..6].iter().map(|v| v.parse().unwrap()).collect();
        assert_eq!(xyh, t.poses[i].to_vec(), "tick {} robot {i}", t.tick);
        assert_eq!(c[6].parse::<u8>().unwrap(), t.states[i]);
        named += names.contains(&c[7]) as usize;
        assert_eq!(c[8].parse::<u8>().unwrap(), t.alive[i]);
    }
    assert_eq!(named, rows.len(), "every row's state has its name");
    let mut r = csv_reader(&out.join("events.csv"));
    assert_eq!(
        r.headers().unwrap(),
        vec!["tick", "time_s", "event", "robot", "entity", "detail"]
    );
    let rows: Vec<Vec<String>> = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    let want: Vec<(u64, &swarm::recording::Event)> = ticks
        .iter()
        .flat_map(|t| t.events.iter().map(move |e| (t.tick, e)))
        .collect();
    assert_eq!(rows.len(), want.len());
    for (row, (tick, _)) in rows.iter().zip(&want) {
        assert_eq!(row[0], tick.to_string());
    }
    // A target is found by a live robot, and names the target (search.toml has 10).
    let targets = summary(&out)["mission"]["search"]["targets"]
        .as_u64()
        .unwrap();
    let found: Vec<&Vec<String>> = rows.iter().filter(|r| r[2] == "entity_done").collect();
    assert!(!found.is_empty(), "{rows:?}");
    for r in found {
        let tick: usize = r[0].parse().unwrap();
        let robot: usize = r[3].parse().unwrap();
        assert!(r[4].parse::<u64>().unwrap() < targets, "{r:?}");
        let t = ticks.iter().find(|t| t.tick as usize == tick).unwrap();
        assert_eq!(t.alive[robot], 1, "found by a dead robot: {r:?}");
    }
    let died: Vec<&Vec<String>> = rows.iter().filter(|r| r[2] == "robot_died").collect();
    assert_eq!(died.len(), 1, "{rows:?}");
    assert_eq!(died[0][3], "4");
    assert!(!died[0][5].is_empty(), "the cause of death: {:?}", died[0]);
    let _ = std::fs::remove_dir_all(&out);
}

fn csv_reader(p: &Path) -> csv::Reader<std::fs::File> {
    csv::Reader::from_path(p).unwrap()
}
