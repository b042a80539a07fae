//! The world's bound on one read of a robot's act service.
//!
//! A read of an iceoryx2 blackboard entry (`runtime.acts = "blackboard"`) copies the newest
//! value and retries while the entry's write counter moved during the copy; the counter lives
//! in shared memory that the robot's agent can write, so an agent that bumps it in a loop
//! keeps the world's read retrying without end (iceoryx2 0.10's `UnrestrictedAtomicMgmt::
//! load` has no bound). A well-behaved writer updates an entry once a tick, so a read retries
//! at most once or twice.
//!
//! This thread watches the world's guarded reads (`shrink_guard::reading` numbers them):
//! a read of robot r's service still found by [`STUCK_KILL_LOOKS`] looks in a row makes the world order r's
//! agent killed (the barrier's kill order, which the orchestrator carries out; a dead writer
//! lets the read finish, and the robot is then a fault like any dead one). A read still
//! found by [`STUCK_EXIT_LOOKS`] looks (the writer outlived the kill: another process of the user
//! writing the segment) ends the world with a message naming the robot, and the
//! orchestrator fails the run cleanly: never a hang.

use std::sync::Arc;
use std::time::Duration;
use swarm::barrier::TickBarrier;

/// How often the watchdog looks at the read in progress.
pub const WATCH_EVERY: Duration = Duration::from_millis(200);
/// Looks that find the same read before its robot's agent is ordered killed (2 s). A copy
/// of an act value takes well under a microsecond. Looks, not wall time: a world stopped
/// and continued (Ctrl-Z, a debugger) resumes its read and the watchdog together.
pub const STUCK_KILL_LOOKS: u32 = 10;
/// Looks that find the same read before the world ends (10 s).
pub const STUCK_EXIT_LOOKS: u32 = 50;
/// The world's exit code when a read stayed stuck past [`STUCK_EXIT_LOOKS`].
pub const EXIT_STUCK: i32 = 4;

/// Starts the watchdog for the run's `barrier` (it lives as long as the world process).
pub fn spawn(barrier: Arc<TickBarrier>) -> std::io::Result<()> {
    std::thread::Builder::new()
        .name("read-watchdog".into())
        .spawn(move || watch(&barrier))
        .map(drop)
}

fn watch(barrier: &TickBarrier) {
    // The read seen at the last look, and how many looks in a row found it.
    let mut seen: Option<(u32, u64)> = None;
    let mut looks = 0u32;
    loop {
        std::thread::sleep(WATCH_EVERY);
        let (robot, n) = crate::shrink_guard::read_in_progress();
        let Some(robot) = robot else {
            seen = None;
            continue;
        };
        if seen != Some((robot, n)) {
            seen = Some((robot, n));
            looks = 1;
            continue;
        }
        looks += 1;
        let secs = |looks: u32| looks as f64 * WATCH_EVERY.as_secs_f64();
        if looks == STUCK_KILL_LOOKS {
            eprintln!(
                "world: a read of robot {robot}'s act service has not ended for {:.0} s: its \
                 agent is ordered killed",
                secs(looks)
            );
            barrier.order_kill(robot, barrier.attach_count(robot).max(1));
        }
        if looks >= STUCK_EXIT_LOOKS {
            eprintln!(
                "world: a read of robot {robot}'s act service did not end within {:.0} s (a \
                 process keeps writing its segment, and killing robot {robot}'s agent did not \
                 stop it): the run ends here",
                secs(looks)
            );
            std::process::exit(EXIT_STUCK);
        }
    }
}
