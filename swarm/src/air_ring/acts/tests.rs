use super::*;
use crate::air_ring::tests::{ours, prefix};

/// Tick t's message area byte j.
fn byte(t: u64, j: usize) -> u8 {
    (t as u8).wrapping_mul(31).wrapping_add(j as u8)
}

/// Tick t's used area bytes (0..area, varying from tick to tick).
fn used(t: u64, area: usize) -> usize {
    (t as usize * 37) % (area + 1)
}

/// Writes tick t's action of `robot`: the area byte by byte (slowly, to widen the window a
/// reader can overlap), the Action naming the tick in every field it has.
fn fill(t: u64, robot: u32) -> impl FnOnce(&mut [u8]) -> Action {
    move |out: &mut [u8]| {
        let n = used(t, out.len());
        for (j, b) in out[..n].iter_mut().enumerate() {
            // SAFETY: a plain byte of our own buffer; volatile so the loop is not merged.
            unsafe { std::ptr::write_volatile(b, byte(t, j)) };
        }
        let mut a = Action::idle(t, robot);
        a.cmd = [t as f64, -(t as f64)];
        a.report = [t as f64; 4];
        a.radio_bytes = n as u32;
        a
    }
}

/// Whether a read of tick t is tick t's whole write.
fn whole(t: u64, a: &Action, area: &[u8], robot: u32, len: usize) -> bool {
    a.tick == t
        && a.robot == robot
        && a.cmd == [t as f64, -(t as f64)]
        && a.report == [t as f64; 4]
        && a.radio_bytes as usize == used(t, len)
        && area.len() == used(t, len)
        && area.iter().enumerate().all(|(j, b)| *b == byte(t, j))
}

#[test]
fn written_actions_are_read_by_tick_parity_and_only_for_the_tick_asked() {
    let p = prefix("acts-rw");
    let mut cells = ActCells::create(&p, 3, 200).unwrap();
    let mut w = ActCellWriter::open(&p, 2).unwrap();
    let mut area = Vec::new();
    assert!(
        cells.read(2, 0, |_| true, &mut area).is_none(),
        "no action yet"
    );
    w.write(4, fill(4, 2));
    w.write(5, fill(5, 2));
    let (t, a) = cells.read(2, 4, |t| t == 4, &mut area).expect("tick 4");
    assert!(whole(t, &a, &area, 2, 200));
    let (t, a) = cells.read(2, 5, |t| t == 5, &mut area).expect("tick 5");
    assert!(whole(t, &a, &area, 2, 200));
    // The other robots' cells are untouched; a tick not asked for is not read.
    assert!(cells.read(1, 4, |_| true, &mut area).is_none());
    assert!(cells.read(2, 4, |t| t == 6, &mut area).is_none());
    assert!(
        cells.read(3, 4, |_| true, &mut area).is_none(),
        "no robot 3"
    );
    // Tick 6 replaces tick 4 (the same parity).
    w.write(6, fill(6, 2));
    assert!(cells.read(2, 4, |t| t == 4, &mut area).is_none());
    assert_eq!(cells.read(2, 4, |_| true, &mut area).map(|r| r.0), Some(6));
    // The world forgets a dead robot's actions.
    cells.clear(2);
    assert!(cells.read(2, 4, |_| true, &mut area).is_none());
    assert!(cells.read(2, 5, |_| true, &mut area).is_none());
    // A restarted agent opens the segment again and writes its cell.
    drop(w);
    let mut again = ActCellWriter::open(&p, 2).unwrap();
    again.write(9, fill(9, 2));
    let (t, a) = cells.read(2, 9, |t| t == 9, &mut area).expect("tick 9");
    assert!(whole(t, &a, &area, 2, 200));
    assert_eq!(cells.torn(), 0);
    drop(again);
    drop(cells);
    assert_eq!(ours(&p), 0, "the segment is removed with the world's side");
}

/// An agent SIGKILLed mid-write (its write begun, never stamped) leaves no action; a write
/// that overtakes a read (between its copy and its check) makes the read refused.
#[test]
fn a_torn_write_is_refused() {
    let p = prefix("acts-torn");
    let mut cells = ActCells::create(&p, 1, 64).unwrap();
    let mut w = ActCellWriter::open(&p, 0).unwrap();
    let mut area = Vec::new();
    w.write(3, fill(3, 0));
    assert!(cells.read(0, 3, |t| t == 3, &mut area).is_some());
    // Killed while writing tick 5 (same buffer as 3): half the area written, no stamp.
    {
        // Never finished: the process dies here (the begun write is all a kill leaves).
        let mut half = w.begin(5);
        half.area_mut()[..10].fill(0xee);
    }
    assert!(
        cells.read(0, 5, |_| true, &mut area).is_none(),
        "nothing stamped"
    );
    // A whole write of tick 7 lands between the copy of tick 5's and the stamp's check.
    w.write(5, fill(5, 0));
    let got = cells.read_with(0, 5, |t| t == 5, &mut area, || w.write(7, fill(7, 0)));
    assert!(got.is_none(), "overtaken read refused");
    assert!(area.is_empty());
    assert_eq!(cells.torn(), 1);
    let (t, a) = cells.read(0, 7, |_| true, &mut area).expect("tick 7");
    assert!(whole(t, &a, &area, 0, 64));
}

/// A misbehaving agent's lengths never make the world read outside the cell.
#[test]
fn lengths_from_a_cell_are_bounded_and_bad_segments_refused() {
    let p = prefix("acts-bounds");
    let mut cells = ActCells::create(&p, 2, 48).unwrap();
    let mut w = ActCellWriter::open(&p, 1).unwrap();
    let mut area = Vec::new();
    w.write(0, |out| {
        out.fill(0xff);
        let mut a = Action::idle(0, 1);
        a.radio_bytes = u32::MAX;
        a
    });
    let (_, a) = cells.read(1, 0, |_| true, &mut area).unwrap();
    assert_eq!(area.len(), 48, "cut to the area");
    assert_eq!(a.radio_bytes, 48);
    // A malformed area is no messages (the world counts it as today).
    assert!(crate::air::act_messages(&area).is_none());
    assert!(matches!(
        ActCellWriter::open(&p, 2),
        Err(ActCellsError::NoRobot {
            robot: 2,
            robots: 2
        })
    ));
    assert!(matches!(
        ActCellWriter::open(&prefix("acts-none"), 0),
        Err(ActCellsError::Io { .. })
    ));
    // A segment shorter than its head says, and one without the magic, are refused.
    let file = format!("/dev/shm/{p}{ACTS_SEGMENT}");
    let f = std::fs::OpenOptions::new().write(true).open(&file).unwrap();
    f.set_len(segment_bytes(2, 48) as u64 - 1).unwrap();
    assert!(matches!(
        ActCellWriter::open(&p, 0),
        Err(ActCellsError::Invalid { .. })
    ));
    drop(cells);
    let q = prefix("acts-zeros");
    std::fs::write(format!("/dev/shm/{q}{ACTS_SEGMENT}"), vec![0u8; 4096]).unwrap();
    assert!(matches!(
        ActCellWriter::open(&q, 0),
        Err(ActCellsError::Invalid { .. })
    ));
    std::fs::remove_file(format!("/dev/shm/{q}{ACTS_SEGMENT}")).unwrap();
    drop(w);
    assert_eq!(ours(&p) + ours(&q), 0);
}

/// A writer racing a reader from another thread: every read accepted is one tick's whole
/// write (every byte of the area and every field of the Action), whatever the interleaving.
#[test]
fn a_writer_racing_a_reader_never_hands_out_a_torn_action() {
    const TICKS: u64 = 100_000;
    const AREA: usize = 512;
    let p = prefix("acts-race");
    let mut cells = ActCells::create(&p, 1, AREA).unwrap();
    let mut w = ActCellWriter::open(&p, 0).unwrap();
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let d = done.clone();
    let writer = std::thread::spawn(move || {
        for t in 0..TICKS {
            w.write(t, fill(t, 0));
            // A pause, so the reader finds stamped buffers as well as ones being written.
            for _ in 0..200 {
                std::hint::spin_loop();
            }
        }
        d.store(true, Ordering::Release);
    });
    let mut area = Vec::new();
    let (mut accepted, mut last) = (0u64, [None::<u64>; 2]);
    loop {
        let finished = done.load(Ordering::Acquire);
        for parity in 0..2u64 {
            if let Some((t, a)) = cells.read(0, parity, |_| true, &mut area) {
                assert_eq!(t & 1, parity);
                assert!(whole(t, &a, &area, 0, AREA), "tick {t} read torn");
                // Stamps only move forward in a buffer.
                assert!(last[parity as usize] <= Some(t));
                last[parity as usize] = Some(t);
                accepted += 1;
            }
        }
        if finished {
            break;
        }
    }
    writer.join().unwrap();
    assert_eq!(
        last,
        [Some(TICKS - 2), Some(TICKS - 1)],
        "the last writes read"
    );
    assert!(accepted >= 2);
    eprintln!(
        "{accepted} reads accepted, {} refused as torn",
        cells.torn()
    );
}
