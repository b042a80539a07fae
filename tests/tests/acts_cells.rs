//! The agents' actions through the world's act cells (`runtime.acts = "cells"`, the default)
//! with real processes: the same run as through one iceoryx2 act service per robot and as the
//! in-process executor, and an agent SIGKILLed mid-run is survived with counters that add up.

use e2e::*;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// configs/roam.toml with `runtime.acts = acts`.
fn roam_with_acts(tag: &str, acts: &str) -> PathBuf {
    let dir = tmp_dir(&format!("{tag}-sc"));
    std::fs::create_dir_all(&dir).unwrap();
    let roam_sc = std::fs::read_to_string(roam()).unwrap();
    let file = dir.join("roam.toml");
    std::fs::write(&file, roam_sc + &format!("\n[runtime]\nacts = {acts:?}\n")).unwrap();
    file
}

fn read(
    dir: &Path,
) -> (
    swarm::recording::RecordingHeader,
    Vec<swarm::recording::TickRecord>,
) {
    let f = std::fs::File::open(dir.join("recording.bin")).unwrap();
    swarm::recording::read_recording(std::io::BufReader::new(f)).unwrap()
}

/// Per tick: the (message, receiver) pairs offered so far equal their outcomes plus those in
/// flight.
fn assert_counters_add_up(dir: &Path) -> swarm::radio::RadioCounters {
    let mut sum = swarm::radio::RadioCounters::default();
    for t in &read(dir).1 {
        sum.add(&t.radio);
        assert_eq!(sum.offered, sum.accounted(), "tick {}: {sum:?}", t.tick);
    }
    sum
}

#[test]
fn acts_cells_iceoryx2_and_inprocess_record_the_same_run() {
    let _g = serial();
    let base = [
        "--robots",
        "12",
        "--max-ticks",
        "300",
        "--seed",
        "7",
        "--loss",
        "0.2",
        "--delay",
        "2",
    ];
    let ice_sc = roam_with_acts("acts-same-ice", "iceoryx2");
    let runs = [
        (
            "cells",
            vec!["--scenario", roam(), "--executor", "processes"],
        ),
        (
            "iceoryx2",
            vec![
                "--scenario",
                ice_sc.to_str().unwrap(),
                "--executor",
                "processes",
            ],
        ),
        (
            "inprocess",
            vec!["--scenario", roam(), "--executor", "inprocess"],
        ),
    ];
    let mut dirs = Vec::new();
    for (tag, args) in runs {
        let out = tmp_dir(&format!("acts-same-{tag}"));
        let o = up(&[&base[..], &args[..]].concat(), &out);
        assert!(ended_by_itself(&o), "{tag}: {}", stderr(&o));
        dirs.push(out);
    }
    let bytes = |d: &Path| std::fs::read(d.join("recording.bin")).unwrap();
    // Cells (the default: the resolved scenario does not name it) and the in-process
    // executor: byte for byte.
    assert!(
        bytes(&dirs[0]) == bytes(&dirs[2]),
        "acts = cells and the in-process executor differ"
    );
    // Through iceoryx2 the header names `acts = "iceoryx2"` (and only that); every tick is
    // the same.
    let (hc, tc) = read(&dirs[0]);
    let (hi, ti) = read(&dirs[1]);
    assert_eq!(tc.len(), 300);
    assert!(tc == ti, "the acts' transport changed the run");
    let named: Vec<&str> = hi
        .scenario
        .lines()
        .filter(|l| l.contains("acts ="))
        .collect();
    assert_eq!(named, ["acts = \"iceoryx2\""]);
    let rest: Vec<&str> = hi
        .scenario
        .lines()
        .filter(|l| !l.contains("acts ="))
        .collect();
    assert_eq!(rest, hc.scenario.lines().collect::<Vec<_>>());
    assert_eq!(
        (hi.seed, hi.robots, hi.version),
        (hc.seed, hc.robots, hc.version)
    );
    // The radio carried the messages, with loss and delay.
    let sum = assert_counters_add_up(&dirs[0]);
    assert!(sum.delivered > 1000 && sum.dropped_loss > 300, "{sum:?}");
    assert!(tc[0].poses != tc.last().unwrap().poses, "the robots moved");
    for d in &dirs[..2] {
        assert_left_nothing(d);
    }
}

#[test]
fn an_agent_sigkilled_under_acts_cells_is_survived_and_the_counters_add_up() {
    let _g = serial();
    let out = tmp_dir("acts-kill9");
    let id = own_run_id("acts-kill9");
    const ROBOTS: usize = 8;
    const TICKS: u64 = 2000;
    let mut child = spawn_up_as(
        &[
            "--scenario",
            roam(),
            "--robots",
            &ROBOTS.to_string(),
            "--max-ticks",
            &TICKS.to_string(),
            "--loss",
            "0.2",
            // Paced (lock-step all the same), so the kill lands mid-run: at least 2 s.
            "--tick-hz",
            "1000",
        ],
        &out,
        Some(&id),
    );
    let entry = registry_entry(&out, ROBOTS);
    let acts_file = format!("{}acts", swarm::transport::prefix_for(&id));
    assert!(
        shm_of_run(&id).contains(&acts_file),
        "the acts segment /dev/shm/{acts_file}: {:?}",
        shm_of_run(&id)
    );
    let pid = entry["agent_pids"][5].as_u64().unwrap() as i32;
    let cmdline = String::from_utf8_lossy(&std::fs::read(format!("/proc/{pid}/cmdline")).unwrap())
        .into_owned();
    assert!(cmdline.contains("--robot\u{0}5\u{0}"), "{cmdline:?}");
    std::thread::sleep(Duration::from_millis(500));
    // SAFETY: SIGKILL to an agent process of this test's run (wherever it is in its tick,
    // possibly between the start and the stamp of its cell's write).
    assert_eq!(unsafe { libc::kill(pid, libc::SIGKILL) }, 0);
    let most = most_while_running(&mut child, || shm_of_run(&id).len());
    let o = child.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "exit {:?}: {}", o.status, stderr(&o));
    assert!(most > 0);
    let s = summary(&out);
    assert_eq!(s["ticks"], TICKS, "the run finished: {s}");
    assert_eq!(s["end"], "completed");
    assert_eq!(s["alive_at_end"], ROBOTS as u64 - 1);
    let faults = s["faults"].as_array().unwrap();
    assert_eq!(faults.len(), 1, "{faults:?}");
    assert_eq!(faults[0]["robot"], 5);
    let tick = faults[0]["detected_tick"].as_u64().unwrap();
    assert!(tick > 0 && tick < TICKS, "fault tick {tick}");
    let (_, ticks) = read(&out);
    assert_eq!(ticks.len() as u64, TICKS);
    // Robot 5 stands still from its death on; the others keep moving and talking.
    let at = ticks[tick as usize].poses[5];
    for t in &ticks[tick as usize..] {
        assert_eq!((t.alive[5], t.poses[5]), (0, at));
    }
    assert_eq!(ticks[tick as usize - 1].alive[5], 1);
    let last = ticks.last().unwrap();
    assert!(
        ticks[tick as usize].poses[0] != last.poses[0],
        "robot 0 moved on"
    );
    let sum = assert_counters_add_up(&out);
    assert!(sum.delivered > 10_000, "{sum:?}");
    let m = &s["messages"];
    assert_eq!(m["offered"].as_u64(), Some(sum.offered), "{m}");
    assert_eq!(m["delivered"].as_u64(), Some(sum.delivered), "{m}");
    assert!(shm_of_run(&id).is_empty(), "{:?}", shm_of_run(&id));
    assert_left_nothing(&out);
}
