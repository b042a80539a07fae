//! `orchestrator kill` (and the viewer's kill button) for a robot that runs on another host:
//! there is no local process to signal, so the order goes where the world's own kill orders
//! go, the robot's kill-order word in the run's barrier (docs/protocol.md sections 4, 9); the
//! gateway forwards it to the robot's host, whose proxy SIGKILLs that agent.

use swarm::barrier::TickBarrier;

/// Orders robot `robot`'s current agent on its host killed; the line to print.
pub fn kill_remote(prefix: &str, run_id: &str, robot: u32) -> String {
    let barrier = match TickBarrier::open(prefix) {
        Ok(b) => b,
        Err(e) => return format!("robot {robot}: the run's barrier: {e}"),
    };
    let attach = barrier.attach_count(robot);
    if attach == 0 || attach <= barrier.dead_upto(robot) {
        return format!("robot {robot}: no live agent on its host (already dead?)");
    }
    barrier.order_kill(robot, attach);
    // "killed ..." as for a local agent (stdout): its proxy SIGKILLs it within milliseconds.
    format!("killed robot {robot} of run {run_id} (on its host: ordered through the barrier)")
}
