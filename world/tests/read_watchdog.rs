//! The read watchdog (world/src/read_watchdog.rs) in a test binary of its own: the guarded
//! read it watches is process-wide state (one reading thread in the world), which the world
//! crate's other unit tests, run in parallel threads, would change under it.

use std::sync::Arc;
use std::time::{Duration, Instant};
use swarm::barrier::TickBarrier;
use world::read_watchdog::{spawn, STUCK_KILL_LOOKS, WATCH_EVERY};

/// A read of robot 2's act service that does not end: the watchdog writes robot 2's kill
/// order (the orchestrator's cue to SIGKILL its agent) after its bound, not before.
#[test]
fn a_stuck_read_orders_its_robots_agent_killed() {
    let prefix = format!("swwd{}_", std::process::id());
    let (barrier, _fds) = TickBarrier::create(&prefix, 4).unwrap();
    let barrier = Arc::new(barrier);
    spawn(barrier.clone()).unwrap();
    let t = Instant::now();
    let waited = world::shrink_guard::reading(2, || {
        while barrier.kill_order(2) == 0 && t.elapsed() < Duration::from_secs(20) {
            std::thread::sleep(Duration::from_millis(10));
        }
        t.elapsed()
    })
    .unwrap();
    assert!(barrier.kill_order(2) >= 1, "no kill order after {waited:?}");
    assert_eq!(barrier.kill_order(1), 0);
    // STUCK_KILL_LOOKS looks, the first one starting the count.
    assert!(waited >= WATCH_EVERY * (STUCK_KILL_LOOKS - 1), "{waited:?}");
}
