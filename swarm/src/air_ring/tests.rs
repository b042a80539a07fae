use super::*;

pub(super) fn prefix(tag: &str) -> String {
    format!("swtest{}_{tag}_", std::process::id())
}

/// An air of `len` bytes, every one `tick as u8`, its header naming the tick and length.
fn fill_with(tick: u64, len: usize) -> impl FnOnce(&mut [u8]) -> AirHeader {
    move |out: &mut [u8]| {
        out.fill(tick as u8);
        AirHeader {
            tick,
            payload_bytes: len as u32,
            ..Default::default()
        }
    }
}

fn intact(a: &AirRead) -> bool {
    let len = a.header.payload_bytes as usize;
    a.header.tick == a.tick && a.bytes()[..len].iter().all(|&b| b == a.tick as u8)
}

pub(super) fn ours(p: &str) -> usize {
    std::fs::read_dir("/dev/shm")
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(p))
        .count()
}

#[test]
fn readers_see_the_published_air_and_held_slots_are_never_rewritten() {
    let p = prefix("ring");
    let mut w = AirWriter::create(&p, 2, 1).unwrap();
    assert_eq!(w.slots(), 2 + 2 * 2, "two cells a robot, plus two");
    let mut r = AirReader::open(&p, 1).unwrap();
    assert!(r.read().unwrap().is_none(), "nothing published yet");
    w.publish(0, 100, fill_with(0, 100)).unwrap();
    let a0 = r.read().unwrap().expect("tick 0's air");
    assert_eq!((a0.tick, a0.header.payload_bytes), (0, 100));
    assert!(intact(&a0));
    assert_eq!(w.holds(), 1);
    // Held (a zero-copy view) while 20 more ticks go by, some larger than a slot's file: its
    // bytes never change, and each later read sees its own tick.
    for k in 1..20u64 {
        let len = if k % 3 == 0 { 300_000 } else { 1000 };
        w.publish(k, len, fill_with(k, len)).unwrap();
        let a = r.read().unwrap().expect("latest air");
        assert_eq!(a.tick, k);
        assert!(intact(&a), "tick {k}");
    }
    assert!(intact(&a0));
    // Slot 0 held by a0 all along; the other ticks alternate between slots 1 and 2.
    assert_eq!(w.files(), 3);
    // Both of robot 1's cells in use: a third hold is refused (the agent never asks for one:
    // it keeps at most radio.zero_copy_held views).
    let a1 = r.read().unwrap().unwrap();
    assert!(matches!(
        r.read(),
        Err(AirRingError::NoCell { robot: 1, cells: 2 })
    ));
    drop((a0, a1));
    assert_eq!(w.holds(), 0, "dropping the reads empties the cells");
    assert!(matches!(
        AirReader::open(&p, 2),
        Err(AirRingError::NoRobot {
            robot: 2,
            robots: 2
        })
    ));
}

#[test]
fn a_killed_readers_holds_are_cleared_by_the_world_and_never_exhaust_the_ring() {
    // An agent SIGKILLed while holding airs never drops its holds: here, mem::forget. Kill
    // robot 0's agent (and restart it) 50 times, more than the ring has slots, each time while
    // it holds both of its cells; robot 1 reads normally all along.
    let p = prefix("kill");
    let mut w = AirWriter::create(&p, 2, 1).unwrap();
    let slots = w.slots();
    let mut r1 = AirReader::open(&p, 1).unwrap();
    let mut tick = 0;
    for kill in 0..50u64 {
        let mut r0 = AirReader::open(&p, 0).unwrap();
        for _ in 0..2 {
            w.publish(tick, 64, fill_with(tick, 64)).unwrap();
            std::mem::forget(r0.read().unwrap().expect("air"));
            assert!(intact(&r1.read().unwrap().unwrap()));
            tick += 1;
        }
        assert!(matches!(r0.read(), Err(AirRingError::NoCell { .. })));
        std::mem::forget(r0);
        // The leaked holds keep their slots from being rewritten until the world learns of
        // the death...
        assert_eq!(w.holds(), 2, "kill {kill}");
        w.publish(tick, 64, fill_with(tick, 64)).unwrap();
        tick += 1;
        // ... and clears them.
        w.release_robot(0);
        assert_eq!(w.holds(), 0);
    }
    assert!(tick as u32 > slots);
    // Only the slots ever needed at once have files: two held, the published one, one free.
    assert!(w.files() <= 4, "{} files", w.files());
    drop(w);
    assert_eq!(ours(&p), 0);
}

#[test]
fn the_writer_removes_its_files() {
    let p = prefix("files");
    let mut w = AirWriter::create(&p, 1, 0).unwrap();
    w.publish(0, 10, fill_with(0, 10)).unwrap();
    w.publish(1, 200_000, fill_with(1, 10)).unwrap();
    assert_eq!(ours(&p), 3, "the control segment and two data files");
    drop(w);
    assert_eq!(ours(&p), 0);
}

#[test]
fn readers_on_threads_never_see_an_air_being_rewritten() {
    // The race of the module's argument, hammered: one writer publishes as fast as it can
    // (sizes varying, so files regrow), four readers read whatever is published, check every
    // byte, keep some reads for a while (zero-copy holds) and check them again when they let
    // go. No reader waits for the writer, so readers are often late: the case where the
    // writer reuses a slot a reader has just found.
    let p = prefix("race");
    const READERS: u32 = 4;
    const TICKS: u64 = 20_000;
    let mut w = AirWriter::create(&p, READERS, 2).unwrap();
    let done = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let readers: Vec<_> = (0..READERS)
        .map(|robot| {
            let mut r = AirReader::open(&p, robot).unwrap();
            let done = done.clone();
            std::thread::spawn(move || {
                let (mut reads, mut kept) = (0u64, Vec::new());
                let mut last = 0;
                while !done.load(Ordering::Acquire) {
                    let Some(a) = r.read().unwrap() else {
                        continue;
                    };
                    assert!(intact(&a), "robot {robot}: torn air of tick {}", a.tick);
                    assert!(a.tick >= last, "ticks go forward");
                    last = a.tick;
                    reads += 1;
                    // Keep every 7th read across a few more (at most two at once: the
                    // cells are three, one for the read in hand).
                    if reads % 7 == robot as u64 {
                        kept.push(a);
                    } else {
                        std::hint::black_box(&a);
                    }
                    if kept.len() == 2 || (reads % 11 == 0 && !kept.is_empty()) {
                        let k = kept.remove(0);
                        assert!(intact(&k), "robot {robot}: held air rewritten");
                    }
                }
                assert!(kept.iter().all(intact));
                reads
            })
        })
        .collect();
    for k in 0..TICKS {
        let len = 8 + (k as usize * 7919) % 150_000;
        w.publish(k, len, fill_with(k, len)).unwrap();
    }
    done.store(true, Ordering::Release);
    for r in readers {
        assert!(r.join().unwrap() > 0);
    }
    assert_eq!(w.holds(), 0);
    drop(w);
    assert_eq!(ours(&p), 0);
}
