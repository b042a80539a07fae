//! The world's air ring (`radio.air = "ring"`, the default) with real processes: agents that
//! keep zero-copy views of the air between ticks are SIGKILLed (and restarted) more times than
//! the ring has slots, and the run goes on (their holds are cleared by the world, never
//! leaked); and the ring and the iceoryx2 air record the same ticks.

use e2e::*;
use std::path::PathBuf;

/// The roam scenario run by `keeper` robots: 1,000-byte bulk beacons received in place, each
/// robot keeping its last tick's beacons (views of that tick's air) until its next tick.
fn keeper_scenario(tag: &str, air: &str) -> PathBuf {
    let dir = tmp_dir(&format!("{tag}-sc"));
    std::fs::create_dir_all(&dir).unwrap();
    let roam_sc = std::fs::read_to_string(roam()).unwrap();
    let file = dir.join("keeper.toml");
    std::fs::write(
        &file,
        roam_sc
            .replace("behaviour = \"roam\"", "behaviour = \"keeper\"")
            .replace(
                "max_message_bytes = 256",
                // Every robot in range of every other wherever they roam (the arena's
                // diagonal is below 2,000), so the radio's end-of-run check does not depend
                // on where restarts leave the robots.
                &format!(
                    "max_message_bytes = 2048\nzero_copy_held = 2\nair = {air:?}\ncomm_radius = 2000.0"
                ),
            )
            + "\n[roam]\npayload_bytes = 1000\n",
    )
    .unwrap();
    file
}

fn ticks(dir: &std::path::Path) -> Vec<swarm::recording::TickRecord> {
    let f = std::fs::File::open(dir.join("recording.bin")).unwrap();
    swarm::recording::read_recording(std::io::BufReader::new(f))
        .unwrap()
        .1
}

/// The air ring's data files of a run (`<prefix>air.<slot>.<generation>`).
fn ring_files(run_id: &str) -> usize {
    shm_of_run(run_id)
        .iter()
        .filter(|f| f.contains("_air."))
        .count()
}

#[test]
fn agents_killed_while_holding_the_air_never_exhaust_the_ring() {
    let _g = serial();
    const ROBOTS: u32 = 4;
    const HELD: u32 = 2;
    // The ring has 2 + robots x (held + 1) slots; more kills than that, each of an agent
    // keeping views of the last tick's air (so its hold cells are in use when it dies).
    let slots = 2 + ROBOTS * (HELD + 1);
    let kills: Vec<(u64, u32)> = (0..20u64)
        .map(|j| (20 + 12 * j, 1 + (j % 3) as u32))
        .collect();
    assert!(kills.len() as u32 > slots);
    let chaos_at = kills
        .iter()
        .map(|(t, r)| format!("{t}:{r}"))
        .collect::<Vec<_>>()
        .join(",");
    let sc = keeper_scenario("ring-kill", "ring");
    let out = tmp_dir("ring-kill");
    let id = own_run_id("ring-kill");
    let max_ticks = 300u64;
    let mut child = spawn_up_as(
        &[
            "--scenario",
            sc.to_str().unwrap(),
            "--robots",
            &ROBOTS.to_string(),
            "--max-ticks",
            &max_ticks.to_string(),
            // Paced (lock-step all the same), so restarts land mid-run.
            "--tick-hz",
            "200",
            "--loss",
            "0",
            "--chaos-at",
            &chaos_at,
            "--on-fault",
            "restart",
            "--max-restarts",
            "100",
        ],
        &out,
        Some(&id),
    );
    // While it runs: the ring never has more data files than the slots in use at once (the
    // published air, the one being written, the air the agents keep; a leaked hold would pin
    // one more slot per kill).
    let most = most_while_running(&mut child, || ring_files(&id));
    let o = child.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    assert!(most >= 2, "the ring was seen: {most} data files");
    assert!(most <= 4, "{most} data files: holds were leaked");
    let s = summary(&out);
    assert_eq!(s["ticks"].as_u64(), Some(max_ticks), "{s}");
    assert_eq!(s["end"], "completed", "{s}");
    // Every kill took effect and every killed robot came back.
    assert_every_kill_restarted(&s, kills.len());
    // The counters add up at every tick, and the radio still works at the end: with no loss
    // every robot hears the others, in the last ticks as in the first.
    let t = ticks(&out);
    assert_eq!(t.len() as u64, max_ticks);
    let mut sum = swarm::radio::RadioCounters::default();
    for r in &t {
        sum.add(&r.radio);
        assert_eq!(sum.offered, sum.accounted(), "tick {}: {sum:?}", r.tick);
    }
    assert_eq!(sum.malformed, 0, "{sum:?}");
    let late = &t[t.len() - 5..];
    assert!(
        late.iter().all(|r| r.radio.delivered > 0),
        "the radio works after {} kills: {:?}",
        kills.len(),
        late.iter()
            .map(|r| (r.tick, r.alive.clone(), r.radio))
            .collect::<Vec<_>>()
    );
    let m = &s["messages"];
    assert_eq!(m["offered"].as_u64().unwrap(), sum.offered, "{m}");
    assert_eq!(m["delivered"].as_u64().unwrap(), sum.delivered, "{m}");
    // Nothing of this run is left in /dev/shm (only this run's files are judged).
    assert!(shm_of_run(&id).is_empty(), "{:?}", shm_of_run(&id));
    assert_left_nothing(&out);
}

#[test]
fn the_ring_and_the_iceoryx2_air_record_the_same_ticks() {
    let _g = serial();
    // Bulk beacons kept as views, a radio delay (airs held past the hold limit arrive as
    // copies) and loss: what the robots hear, and so the whole run, must not depend on the
    // air's transport.
    let mut dirs = Vec::new();
    for air in ["ring", "iceoryx2"] {
        let sc = keeper_scenario(&format!("ring-same-{air}"), air);
        let out = tmp_dir(&format!("ring-same-{air}"));
        let o = up(
            &[
                "--scenario",
                sc.to_str().unwrap(),
                "--robots",
                "8",
                "--max-ticks",
                "200",
                "--loss",
                "0.2",
                "--delay",
                "1",
            ],
            &out,
        );
        assert!(ended_by_itself(&o), "{air}: {}", stderr(&o));
        dirs.push(out);
    }
    let (a, b) = (ticks(&dirs[0]), ticks(&dirs[1]));
    assert_eq!(a.len(), 200);
    assert!(a == b, "the air's transport changed the run");
    assert!(a.iter().map(|r| r.radio.delivered).sum::<u64>() > 2000);
    for d in &dirs {
        assert_left_nothing(d);
    }
}
