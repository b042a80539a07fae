//! The air through iceoryx2 (`radio/air`, static slots) with real processes: agents that keep
//! zero-copy `Blob` views of the air between ticks are SIGKILLed (and restarted) twenty
//! times; the run goes on, what each killed agent held is reclaimed with its dead node (the
//! run's files in /dev/shm do not grow with the kills), and nothing is left at the end.

use e2e::*;
use std::path::PathBuf;

/// The roam scenario run by `keeper` robots: 1,000-byte bulk beacons received in place, each
/// robot keeping its last tick's beacons (views of that tick's air) until its next tick.
fn keeper_scenario(tag: &str) -> PathBuf {
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
                "max_message_bytes = 2048\nzero_copy_held = 2\ncomm_radius = 2000.0",
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

/// Every sample of `count` taken every 5 ms while `child` runs.
fn samples_while_running(child: &mut std::process::Child, count: impl Fn() -> usize) -> Vec<usize> {
    let mut v = Vec::new();
    while child.try_wait().unwrap().is_none() {
        v.push(count());
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    v
}

#[test]
fn agents_killed_while_holding_air_samples_leak_nothing() {
    let _g = serial();
    const ROBOTS: u32 = 4;
    const HELD: u32 = 2;
    // More kills than the air service has samples for the robots' holds (robots x (held +
    // 1)), each of an agent keeping views of the last tick's air (so it holds samples when it
    // dies).
    let slots = ROBOTS * (HELD + 1);
    let kills: Vec<(u64, u32)> = (0..20u64)
        .map(|j| (20 + 12 * j, 1 + (j % 3) as u32))
        .collect();
    assert!(kills.len() as u32 > slots);
    let chaos_at = kills
        .iter()
        .map(|(t, r)| format!("{t}:{r}"))
        .collect::<Vec<_>>()
        .join(",");
    let sc = keeper_scenario("held-kill");
    let out = tmp_dir("held-kill");
    let id = own_run_id("held-kill");
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
    // While it runs: the run's files in /dev/shm (iceoryx2's segments and node files) do not
    // grow with the kills: each dead agent's node, its connections and what it held are
    // cleaned before its replacement attaches (a leak would add files with every one of
    // the 20 kills).
    let counts = samples_while_running(&mut child, || shm_of_run(&id).len());
    let o = child.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let running: Vec<usize> = counts.into_iter().filter(|&c| c > 0).collect();
    let mut sorted = running.clone();
    sorted.sort_unstable();
    let (median, most) = (sorted[sorted.len() / 2], sorted[sorted.len() - 1]);
    eprintln!("files of the run while it ran: median {median}, most {most}");
    assert!(
        most <= median + 2 * ROBOTS as usize,
        "{most} files at most against a median of {median}: the kills leaked"
    );
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
