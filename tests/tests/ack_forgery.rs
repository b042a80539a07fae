//! Forged barrier words (issue 37 item 5): "whatever an agent can write may at most hurt that
//! robot". Every agent maps the barrier's agents' segment (`<prefix>acks`) read-write, so any
//! of them can write every robot's ack and attach words, the ack counter and the ready
//! counter. Here a process of the same user (this test, as a hostile agent would) writes all
//! of them, over and over, for a whole live run: every robot still completes every tick and
//! the recording is byte for byte the untouched run's, because the world takes whether a
//! robot is done with a tick, and whether it attached, only from what arrives through the
//! robot's own act service (docs/protocol.md sections 4-6).

use e2e::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Robots of the runs: small enough for a quick test, enough that the world waits for many.
const ROBOTS: usize = 12;
/// Ticks of the runs.
const TICKS: &str = "200";
/// How long the hostile writer waits for the run's segment to appear.
const FIND_TIMEOUT: Duration = Duration::from_secs(30);

/// The roam scenario with a short `runtime.poll_ms`: a world whose wake-ups are forged away
/// looks again after at most this long, so the forged run is not slow (the recording does
/// not depend on it).
fn scenario(dir: &Path) -> PathBuf {
    let roam = std::fs::read_to_string(roam()).unwrap();
    let p = dir.join("roam-poll.toml");
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(&p, format!("{roam}\n[runtime]\npoll_ms = 5\n")).unwrap();
    p
}

fn args(sc: &Path) -> Vec<String> {
    [
        "--scenario",
        sc.to_str().unwrap(),
        "--robots",
        &ROBOTS.to_string(),
        "--max-ticks",
        TICKS,
        "--seed",
        "7",
        "--loss",
        "0.1",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// The run's agents' segment, as a hostile agent finds it: by name in /dev/shm, or through
/// an open descriptor of one of the run's processes.
fn find_acks(prefix: &str) -> Option<std::fs::File> {
    let rw = |p: &Path| {
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(p)
            .ok()
    };
    if let Some(f) = rw(&Path::new("/dev/shm").join(format!("{prefix}acks"))) {
        return Some(f);
    }
    for pid in processes_mentioning(prefix) {
        for fd in std::fs::read_dir(format!("/proc/{pid}/fd"))
            .into_iter()
            .flatten()
        {
            let Ok(fd) = fd else { continue };
            let target = std::fs::read_link(fd.path()).unwrap_or_default();
            if target.to_string_lossy().contains("acks") {
                if let Some(f) = rw(&fd.path()) {
                    return Some(f);
                }
            }
        }
    }
    None
}

/// Writes garbage into every word of the run's agents' segment until `stop`: the ack
/// counter and the ready counter (header, 8 bytes), then each robot's ack word and attach
/// word (16 bytes a robot). Returns the passes made.
fn forge(prefix: String, stop: Arc<AtomicBool>) -> u64 {
    let t = Instant::now();
    let file = loop {
        if let Some(f) = find_acks(&prefix) {
            break f;
        }
        assert!(
            t.elapsed() < FIND_TIMEOUT,
            "the run's acks segment never appeared"
        );
        if stop.load(Ordering::Acquire) {
            return 0;
        }
        std::thread::sleep(Duration::from_micros(200));
    };
    let len = file.metadata().unwrap().len() as usize;
    let words = 8 + 16 * ROBOTS;
    assert!(len >= words, "acks segment of {len} bytes");
    use std::os::fd::AsRawFd;
    // SAFETY: a shared read-write mapping of the run's segment, as an agent maps it; only
    // atomics are used on it, and it is unmapped below.
    let base = unsafe {
        libc::mmap(
            std::ptr::null_mut(),
            len,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_SHARED,
            file.as_raw_fd(),
            0,
        )
    };
    assert_ne!(base, libc::MAP_FAILED, "mmap the acks segment");
    // SAFETY: in the mapping, 4- and 8-aligned (the mapping is page-aligned).
    let counter = |off: usize| unsafe { &*(base.cast::<u8>().add(off) as *const AtomicU32) };
    let word = |off: usize| unsafe { &*(base.cast::<u8>().add(off) as *const AtomicU64) };
    let mut pass = 0u64;
    while !stop.load(Ordering::Acquire) {
        // The ack counter: cleared (the world's wake-ups lost), or far past any expected
        // count (the world woken for nothing); the ready counter likewise.
        let c = if pass.is_multiple_of(2) { 0 } else { 1 << 30 };
        counter(0).store(c, Ordering::Release);
        counter(4).store(c, Ordering::Release);
        for r in 0..ROBOTS {
            // Each robot's ack word: cleared, or a tick far ahead; its attach word: cleared,
            // or an attach number that never was.
            let (ack, attach) = match pass % 3 {
                0 => (0, 0),
                1 => (u64::MAX / 2, 1_000 + pass),
                _ => (pass, 1),
            };
            word(8 + 16 * r).store(ack, Ordering::Release);
            word(16 + 16 * r).store(attach, Ordering::Release);
        }
        pass += 1;
        std::thread::sleep(Duration::from_micros(50));
    }
    // SAFETY: unmapping the mapping made above.
    unsafe { libc::munmap(base, len) };
    pass
}

#[test]
fn forged_ack_and_attach_words_hurt_no_robot() {
    let _s = serial();
    let dir = tmp_dir("ack-forgery");
    let sc = scenario(&dir);
    let args = args(&sc);
    let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();

    let clean = dir.join("clean");
    let o = up(&args, &clean);
    assert!(ended_by_itself(&o), "untouched run: {}", stderr(&o));

    let forged = dir.join("forged");
    let run_id = own_run_id("ack-forgery");
    let prefix = swarm::transport::prefix_for(&run_id);
    let stop = Arc::new(AtomicBool::new(false));
    let writer = {
        let (prefix, stop) = (prefix.clone(), stop.clone());
        std::thread::spawn(move || forge(prefix, stop))
    };
    let child = spawn_up_as(&args, &forged, Some(&run_id));
    let o = child.wait_with_output().unwrap();
    stop.store(true, Ordering::Release);
    let passes = writer.join().unwrap();
    assert!(ended_by_itself(&o), "forged run: {}", stderr(&o));
    assert!(passes > 10, "the forger wrote only {passes} times");

    let s = summary(&forged);
    assert_eq!(s["ticks"].as_u64(), Some(TICKS.parse().unwrap()), "{s}");
    assert_eq!(s["faults"].as_array().map(|f| f.len()), Some(0), "{s}");
    assert!(
        same_recording(&clean, &forged),
        "the forged run's recording differs from the untouched run's ({passes} forging passes)"
    );
    assert_left_nothing(&forged);
    let _ = std::fs::remove_dir_all(&dir);
}
