//! The Sense frames in the world's ring (`runtime.sense = "ring"`, the default) with real
//! processes: agents SIGKILLed (and restarted) many times never leak the ring's slots or
//! stall the run, restarted agents read their frames again, and the ring and the iceoryx2
//! services hand out the same frames (the same recorded ticks).

use e2e::*;
use std::path::PathBuf;

/// configs/roam.toml with `runtime.sense = sense`.
fn roam_with_sense(tag: &str, sense: &str) -> PathBuf {
    let dir = tmp_dir(&format!("{tag}-sc"));
    std::fs::create_dir_all(&dir).unwrap();
    let roam_sc = std::fs::read_to_string(roam()).unwrap();
    let file = dir.join("roam.toml");
    std::fs::write(
        &file,
        roam_sc + &format!("\n[runtime]\nsense = {sense:?}\n"),
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

/// The Sense ring's data files of a run (`<prefix>sense.<slot>.<generation>`).
fn sense_files(run_id: &str) -> usize {
    shm_of_run(run_id)
        .iter()
        .filter(|f| f.contains("_sense."))
        .count()
}

#[test]
fn agents_killed_at_any_tick_leave_the_sense_ring_clean_and_come_back() {
    let _g = serial();
    const ROBOTS: u32 = 4;
    // The ring has 2 + robots slots (one hold cell a robot); more kills than that.
    let kills: Vec<(u64, u32)> = (0..12u64)
        .map(|j| (15 + 11 * j, (j % ROBOTS as u64) as u32))
        .collect();
    assert!(kills.len() as u32 > 2 + ROBOTS);
    let chaos_at = kills
        .iter()
        .map(|(t, r)| format!("{t}:{r}"))
        .collect::<Vec<_>>()
        .join(",");
    let sc = roam_with_sense("sense-kill", "ring");
    let out = tmp_dir("sense-kill");
    let id = own_run_id("sense-kill");
    let max_ticks = 180u64;
    let t0 = std::time::Instant::now();
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
    // published frames, the ones being written; a leaked hold would pin one more a kill).
    let most = most_while_running(&mut child, || sense_files(&id));
    let o = child.wait_with_output().unwrap();
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    assert!(most >= 1, "the sense ring was seen: {most} data files");
    assert!(most <= 3, "{most} data files: holds were leaked");
    let s = summary(&out);
    assert_eq!(s["ticks"].as_u64(), Some(max_ticks), "{s}");
    assert_eq!(s["end"], "completed", "{s}");
    assert_every_kill_restarted(&s, kills.len());
    // Restarted agents read their frames: no robot was declared dead for silence (a
    // replacement that never got a Sense frame would never act), and every robot is alive at
    // the end.
    let faults = s["faults"].as_array().unwrap();
    assert!(
        faults
            .iter()
            .all(|f| !f.to_string().contains("ack_deadline")),
        "{faults:?}"
    );
    let t = ticks(&out);
    assert_eq!(t.len() as u64, max_ticks);
    assert!(
        t.last().unwrap().alive.iter().all(|a| *a == 1),
        "{:?}",
        t.last().unwrap().alive
    );
    // 180 ticks at 200 Hz take ~1 s; a wedged tick would wait runtime.ack_deadline_ms (5 s).
    assert!(
        t0.elapsed() < std::time::Duration::from_secs(60),
        "{:?}",
        t0.elapsed()
    );
    assert!(shm_of_run(&id).is_empty(), "{:?}", shm_of_run(&id));
    assert_left_nothing(&out);
}

#[test]
fn the_sense_ring_and_the_iceoryx2_services_record_the_same_ticks() {
    let _g = serial();
    let mut dirs = Vec::new();
    for sense in ["ring", "iceoryx2"] {
        let sc = roam_with_sense(&format!("sense-same-{sense}"), sense);
        let out = tmp_dir(&format!("sense-same-{sense}"));
        let o = up(
            &[
                "--scenario",
                sc.to_str().unwrap(),
                "--robots",
                "8",
                "--max-ticks",
                "150",
                "--loss",
                "0.2",
            ],
            &out,
        );
        assert!(ended_by_itself(&o), "{sense}: {}", stderr(&o));
        dirs.push(out);
    }
    let (a, b) = (ticks(&dirs[0]), ticks(&dirs[1]));
    assert_eq!(a.len(), 150);
    assert!(a == b, "the Sense frames' transport changed the run");
    // The robots moved (their frames reached them: roam moves on what it senses and hears).
    let first = &a[0];
    let last = a.last().unwrap();
    assert!(first.poses != last.poses);
    for d in &dirs {
        assert_left_nothing(d);
    }
}
