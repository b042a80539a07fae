//! Lock-step runs with the same scenario and seed give byte-identical recordings: across two
//! multi-process runs (real processes, real iceoryx2) and against the in-process executor.

use e2e::*;

fn recording(out: &std::path::Path) -> Vec<u8> {
    std::fs::read(out.join("recording.bin")).expect("recording.bin")
}

/// Runs `up ARGS` with the processes and the in-process executor (folders `NAME-p`, `NAME-i`),
/// checks that both succeed with the same recording and returns the processes run's folder.
fn same_run_in_both_executors(name: &str, args: &[&str]) -> std::path::PathBuf {
    let a = tmp_dir(&format!("{name}-p"));
    let b = tmp_dir(&format!("{name}-i"));
    for (dir, exec) in [(&a, "processes"), (&b, "inprocess")] {
        let o = up(&[args, &["--executor", exec]].concat(), dir);
        assert!(ended_by_itself(&o), "{exec}: {}", stderr(&o));
    }
    assert!(recording(&a) == recording(&b), "the executors differ");
    a
}

#[test]
fn processes_and_inprocess_give_identical_recordings() {
    let _g = serial();
    let args = [
        "--robots",
        "12",
        "--max-ticks",
        "150",
        "--seed",
        "7",
        "--loss",
        "0.3",
    ];
    let a = tmp_dir("det-a");
    let b = tmp_dir("det-b");
    let c = tmp_dir("det-c");
    for (dir, exec) in [(&a, "processes"), (&b, "processes"), (&c, "inprocess")] {
        let o = up(&[&args[..], &["--executor", exec]].concat(), dir);
        assert!(ended_by_itself(&o), "{exec}: {}", stderr(&o));
    }
    let ra = recording(&a);
    assert!(
        ra.len() > 150 * 12 * 24,
        "recording too small: {} bytes",
        ra.len()
    );
    assert!(ra == recording(&b), "two multi-process runs differ");
    assert!(
        ra == recording(&c),
        "multi-process and in-process runs differ"
    );
    // The radio really worked and the loss model really dropped messages.
    let s = summary(&a);
    assert!(s["messages"]["delivered"].as_u64().unwrap() > 1000, "{s}");
    assert!(s["messages"]["dropped_loss"].as_u64().unwrap() > 300, "{s}");
    assert_eq!(s["robots"], 12);
    assert_left_nothing(&a);
    assert_left_nothing(&b);
}

#[test]
fn a_different_seed_or_loss_gives_a_different_recording() {
    let _g = serial();
    let base = [
        "--robots",
        "10",
        "--max-ticks",
        "120",
        "--executor",
        "inprocess",
    ];
    let dirs: Vec<_> = ["s1", "s2", "l9"].iter().map(|n| tmp_dir(n)).collect();
    up(&[&base[..], &["--seed", "1"]].concat(), &dirs[0]);
    up(&[&base[..], &["--seed", "2"]].concat(), &dirs[1]);
    up(
        &[&base[..], &["--seed", "1", "--loss", "0.9"]].concat(),
        &dirs[2],
    );
    let r: Vec<Vec<u8>> = dirs.iter().map(|d| recording(d)).collect();
    assert_ne!(r[0], r[1]);
    assert_ne!(r[0], r[2], "trajectories must depend on the radio");
}

#[test]
fn run_folder_holds_every_output() {
    let _g = serial();
    let out = tmp_dir("outputs");
    let o = up(&["--robots", "8", "--max-ticks", "60"], &out);
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    for f in ["scenario.toml", "summary.json", "recording.bin", "run.svg"] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    let sc = swarm::scenario::Scenario::load(&out.join("scenario.toml"))
        .expect("resolved scenario parses");
    assert_eq!(sc.run.robots, 8);
    let s = summary(&out);
    for k in [
        "robots",
        "ticks",
        "wall_seconds",
        "ticks_per_second",
        "messages",
        "faults",
        "mission",
    ] {
        assert!(!s[k].is_null(), "summary lacks {k}: {s}");
    }
    let m = &s["messages"];
    let total: u64 = [
        "delivered",
        "dropped_range",
        "dropped_occluded",
        "dropped_bandwidth",
        "dropped_loss",
        "malformed",
        "receiver_dead",
        "in_flight",
    ]
    .iter()
    .map(|k| m[k].as_u64().unwrap())
    .sum();
    assert_eq!(
        total,
        m["offered"].as_u64().unwrap(),
        "message counters must add up: {m}"
    );
    let svg = std::fs::read_to_string(out.join("run.svg")).unwrap();
    assert!(
        svg.contains("<svg") && svg.matches("<polyline").count() >= 8,
        "trajectories drawn"
    );
    let (_, ticks) =
        swarm::recording::read_recording(std::fs::File::open(out.join("recording.bin")).unwrap())
            .unwrap();
    assert_eq!(ticks.len(), 60);
    assert_left_nothing(&out);
}

/// The iceoryx2-event tick barrier (kept for comparison) runs the same ticks as the default
/// futex barrier: same trajectories, same radio, also across a restart.
#[test]
fn the_iox2_event_barrier_gives_the_same_run_as_the_futex_one() {
    let _g = serial();
    let dir = tmp_dir("barriers");
    std::fs::create_dir_all(&dir).unwrap();
    let mut runs = Vec::new();
    for kind in ["futex", "iox2-event"] {
        let sc = dir.join(format!("{kind}.toml"));
        std::fs::write(
            &sc,
            format!("[run]\nbehaviour = \"roam\"\n[runtime]\nbarrier = \"{kind}\"\n"),
        )
        .unwrap();
        let out = dir.join(kind);
        let o = up(
            &[
                "--scenario",
                sc.to_str().unwrap(),
                "--robots",
                "10",
                "--max-ticks",
                "300",
                "--loss",
                "0.2",
                "--chaos-at",
                "100:3",
            ],
            &out,
        );
        assert!(ended_by_itself(&o), "{kind}: {}", stderr(&o));
        assert_left_nothing(&out);
        runs.push(out);
    }
    let svg = |d: &std::path::Path| std::fs::read(d.join("run.svg")).unwrap();
    assert!(svg(&runs[0]) == svg(&runs[1]), "trajectories differ");
    let (a, b) = (summary(&runs[0]), summary(&runs[1]));
    assert_eq!(a["messages"], b["messages"]);
    assert_eq!(a["distance_travelled"], b["distance_travelled"]);
    assert_eq!(a["faults"].as_array().unwrap().len(), 1);
}

/// The actions over one blackboard a robot (`runtime.acts = "blackboard"`): a search run
/// with loss and a kill gives the in-process executor's recording byte for byte, and the same
/// tick records as the pub-sub services (the recordings' headers differ by the resolved
/// scenario's `acts` line).
#[test]
fn acts_over_blackboards_give_the_same_run_in_both_executors_and_as_pub_sub() {
    let _g = serial();
    let dir = tmp_dir("boards");
    std::fs::create_dir_all(&dir).unwrap();
    let sc = dir.join("board.toml");
    std::fs::write(&sc, "[runtime]\nacts = \"blackboard\"\n").unwrap();
    let args = [
        "--robots",
        "12",
        "--max-ticks",
        "200",
        "--seed",
        "5",
        "--loss",
        "0.2",
        "--chaos-at",
        "60:4",
    ];
    let board = same_run_in_both_executors(
        "boards-bb",
        &[&args[..], &["--scenario", sc.to_str().unwrap()]].concat(),
    );
    assert_left_nothing(&board);
    let pubsub = tmp_dir("boards-ps");
    let o = up(&args, &pubsub);
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let (a, b) = (summary(&board), summary(&pubsub));
    assert_eq!(a["ticks"], b["ticks"]);
    assert_eq!(a["messages"], b["messages"]);
    assert_eq!(a["faults"].as_array().unwrap().len(), 1);
    // The tick records: the recordings' tails after the longer header.
    let (ra, rb) = (recording(&board), recording(&pubsub));
    let n = ra.len().min(rb.len()) - 4096;
    assert!(
        ra[ra.len() - n..] == rb[rb.len() - n..],
        "the tick records differ"
    );
}

#[test]
fn a_paced_run_ticks_no_faster_than_asked_and_records_the_same_ticks() {
    let _g = serial();
    let base = ["--robots", "6", "--max-ticks", "200", "--seed", "3"];
    let fast = tmp_dir("pace-free");
    let paced = tmp_dir("pace-400");
    assert!(ended_by_itself(&up(&base, &fast)));
    let o = up(&[&base[..], &["--tick-hz", "400"]].concat(), &paced);
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    // Tick 199 starts no earlier than 199 / 400 s into the loop: at most 200 / 0.4975 ticks/s.
    let rate = summary(&paced)["ticks_per_second"].as_f64().unwrap();
    assert!(
        rate <= 200.0 / (199.0 / 400.0),
        "paced run ticked at {rate}/s"
    );
    let ticks = |d: &std::path::Path| {
        swarm::recording::read_recording(std::fs::File::open(d.join("recording.bin")).unwrap())
            .unwrap()
            .1
    };
    // Pacing changes only when ticks start, never what happens in them (the header's resolved
    // scenario differs by runtime.tick_hz alone).
    assert!(ticks(&fast) == ticks(&paced), "pacing changed the run");
    assert_left_nothing(&fast);
    assert_left_nothing(&paced);
}

/// Per tick of a recording: the offers up to the tick equal the outcomes up to it plus what
/// is in flight after it; in (message, receiver) pairs and in payload bytes alike.
fn assert_books_balance_per_tick(dir: &std::path::Path) -> swarm::radio::RadioCounters {
    let f = std::fs::File::open(dir.join("recording.bin")).unwrap();
    let (_, ticks) = swarm::recording::read_recording(std::io::BufReader::new(f)).unwrap();
    let mut sum = swarm::radio::RadioCounters::default();
    let mut bytes = swarm::radio::RadioCounters::default();
    for t in &ticks {
        sum.add(&t.radio);
        bytes.add(&t.radio_bytes);
        assert_eq!(
            sum.offered,
            sum.accounted(),
            "tick {}: the counters do not add up: {sum:?}",
            t.tick
        );
        assert_eq!(
            bytes.offered,
            bytes.accounted(),
            "tick {}: the byte counters do not add up: {bytes:?}",
            t.tick
        );
        // A message has a payload of one byte at least: bytes follow pairs.
        assert!(bytes.delivered >= sum.delivered && bytes.offered >= sum.offered);
    }
    let b = &summary(dir)["message_bytes"];
    assert_eq!(b["offered"].as_u64().unwrap(), bytes.offered, "{b}");
    assert_eq!(b["delivered"].as_u64().unwrap(), bytes.delivered, "{b}");
    sum
}

#[test]
fn the_medium_with_occlusion_bursts_and_a_death_gives_the_same_run_in_both_executors() {
    let _g = serial();
    // Roaming robots among the roam scenario's obstacles, walls blocking the line of sight,
    // bursty loss per link, and four robots killed on the way: every counter of the medium is
    // exercised, the books balance at every tick (read back from recording.bin of the
    // processes run: real processes, real iceoryx2), and both executors record the same bytes.
    let args = [
        "--scenario",
        roam(),
        "--robots",
        "16",
        "--max-ticks",
        "300",
        "--occlusion",
        "--burst",
        "0.05,0.25,0.05,0.9",
        "--chaos-at",
        "100:3,150:5,200:8,250:11",
    ];
    let a = same_run_in_both_executors("det-medium", &args);
    let sum = assert_books_balance_per_tick(&a);
    assert!(sum.delivered > 5000, "{sum:?}");
    assert!(sum.dropped_occluded > 0, "{sum:?}");
    assert!(sum.dropped_loss > 500, "{sum:?}");
    assert!(
        sum.receiver_dead > 0,
        "the dead robot's due messages: {sum:?}"
    );
    let m = &summary(&a)["messages"];
    assert_eq!(m["in_flight"].as_u64().unwrap(), sum.in_flight, "{m}");
    assert_eq!(m["offered"].as_u64().unwrap(), sum.offered, "{m}");
    assert_left_nothing(&a);
}

#[test]
fn messages_of_tick_0_are_delivered_and_a_bandwidth_cap_drops_what_exceeds_it() {
    let _g = serial();
    // Roam's beacon is one ~60-byte message (header included) a tick: a 50-byte cap drops all
    // of them, the default (no cap) none; without a cap tick 1 already delivers tick 0's.
    let base = ["--scenario", roam(), "--robots", "8", "--max-ticks", "40"];
    let free = tmp_dir("bw-free");
    let capped = tmp_dir("bw-50");
    assert!(ended_by_itself(&up(&base, &free)));
    let o = up(&[&base[..], &["--bandwidth", "50"]].concat(), &capped);
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let f = std::fs::File::open(free.join("recording.bin")).unwrap();
    let (_, ticks) = swarm::recording::read_recording(std::io::BufReader::new(f)).unwrap();
    assert_eq!(ticks[0].radio.offered, 8 * 7);
    assert_eq!(
        ticks[1].radio.delivered,
        8 * 7,
        "tick 0's messages, all in range"
    );
    let c = assert_books_balance_per_tick(&capped);
    assert_eq!(
        (c.delivered, c.dropped_bandwidth),
        (0, c.offered - c.dropped_range)
    );
    assert_left_nothing(&free);
    assert_left_nothing(&capped);
}

#[test]
fn robots_leaving_and_reentering_radio_reach_give_the_same_run_in_both_executors() {
    let _g = serial();
    // A short radio and roaming robots: pairs go out of reach and come back.
    let args = [
        "--scenario",
        roam(),
        "--robots",
        "16",
        "--max-ticks",
        "800",
        "--comm-radius",
        "120",
        "--loss",
        "0.2",
    ];
    let a = same_run_in_both_executors("det-reach", &args);
    let m = &summary(&a)["messages"];
    assert!(
        m["dropped_range"].as_u64().unwrap() > m["delivered"].as_u64().unwrap(),
        "{m}"
    );
    assert!(m["delivered"].as_u64().unwrap() > 5000, "{m}");
    assert_left_nothing(&a);
}

#[test]
fn beacons_with_a_bulk_payload_received_in_place_give_the_same_run() {
    let _g = serial();
    // Roam beacons carrying 3,000 bytes each (a Blob: received zero-copy, as views into the
    // iceoryx2 samples or the in-process tick's bytes). The payload does not steer the robots:
    // the run must be the one without it, in both executors.
    let dir = tmp_dir("det-blob-sc");
    std::fs::create_dir_all(&dir).unwrap();
    let roam_sc = std::fs::read_to_string(roam()).unwrap();
    let with = dir.join("blob.toml");
    std::fs::write(
        &with,
        roam_sc.replace(
            "max_message_bytes = 256",
            "max_message_bytes = 4096\nzero_copy_held = 1",
        ) + "\n[roam]\npayload_bytes = 3000\n",
    )
    .unwrap();
    // With a radio delay the air samples are held past the hold limit: later messages
    // arrive as copies, with the same run.
    for delay in ["0", "2"] {
        let args = |sc| {
            vec![
                "--scenario",
                sc,
                "--robots",
                "16",
                "--max-ticks",
                "300",
                "--loss",
                "0.2",
                "--delay",
                delay,
            ]
        };
        let p =
            same_run_in_both_executors(&format!("det-blob-{delay}"), &args(with.to_str().unwrap()));
        let plain = tmp_dir(&format!("det-blob-plain-{delay}"));
        let b = args(roam());
        let o = up(&b, &plain);
        assert!(ended_by_itself(&o), "{}", stderr(&o));
        // The header holds the resolved scenario (it differs); every tick record must not,
        // but for the byte counters (the payload's bytes are counted).
        let ticks = |dir: &std::path::Path| {
            let f = std::fs::File::open(dir.join("recording.bin")).unwrap();
            let mut t = swarm::recording::read_recording(std::io::BufReader::new(f))
                .unwrap()
                .1;
            for r in &mut t {
                r.radio_bytes = Default::default();
            }
            t
        };
        let (tp, tq) = (ticks(&p), ticks(&plain));
        assert_eq!(tp.len(), 300);
        assert!(tp == tq, "delay {delay}: the payload changed the run");
        let m = &summary(&p)["messages"];
        assert!(
            m["delivered"].as_u64().unwrap() > 5000,
            "delay {delay}: {m}"
        );
        assert_eq!(m["malformed"].as_u64().unwrap(), 0, "{m}");
        assert_left_nothing(&p);
        assert_left_nothing(&plain);
    }
}
