//! The world's guard against a shared segment that shrinks under it (issue 37 item 4).
//!
//! The world reads robot r's actions from r's act publisher's data segment, a file in
//! /dev/shm that r's agent (a program of the same user) created and can `ftruncate`: a read
//! beyond the file's new end raises SIGBUS, which would kill the world and end the run for
//! every robot. iceoryx2's segments are named files, so they cannot be sealed as the barrier's
//! memfds are (`swarm::sealed`).
//!
//! [`install`] sets a SIGBUS handler. While the world reads robot r's act service it says so
//! ([`reading`]); a SIGBUS then maps an anonymous zero page over the faulting page (the read
//! resumes and sees zeros) and records the fault, and [`reading`] reports it: the world makes
//! robot r a fault ("robot r's act segment shrank") and the run goes on. A SIGBUS anywhere
//! else (nothing to blame it on: the world's own Sense, air and status segments, a service's
//! shared configuration) is not absorbed: the handler restores the default action and the
//! faulting access, run again, kills the world by SIGBUS as before (docs/protocol.md
//! section 4 says what an agent can still do).
//!
//! The orchestrator uses the same guard for its own reads and writes of `run/control` and
//! `world/state` ([`RUN_SEGMENTS`]): a truncated `run/control` segment SIGBUSed it at the next
//! agent death and left the run's files in /dev/shm.
//!
//! The guard itself is `swarm::shrink_guard` (agents use it too); this module holds what is
//! the world's: its act services under the guard, and the control channel's loss.

use std::sync::atomic::Ordering;
use swarm::frames::Action;
use swarm::mailbox::Air;
pub use swarm::shrink_guard::{
    give_up, install, read_in_progress, reading, GuardError, CLOSING, RUN_SEGMENTS, WORLD_DATA,
};
use swarm::transport::ActSource;

/// Whether `run/control` shrank under this process ([`control_lost`]): it is not touched again.
static CONTROL_LOST: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether [`control_lost`] was called in this process.
pub fn control_is_lost() -> bool {
    CONTROL_LOST.load(Ordering::Acquire)
}

/// Says once, on stderr, that `run/control` shrank under this process: the orchestrator's
/// death and stop reports are lost from then on (the world still finds a dead robot by its
/// ack deadline; a stop ends in the orchestrator's SIGKILL of the world after its grace).
pub fn control_lost() {
    CONTROL_LOST.store(true, Ordering::Release);
    static SAID: std::sync::Once = std::sync::Once::new();
    SAID.call_once(|| {
        eprintln!(
            "the run/control segment shrank (truncated by a process of the user): its \
             messages are lost from now on (docs/protocol.md section 4)"
        )
    });
}

/// The fault's cause in the summary and the recording.
pub fn cause(robot: u32) -> String {
    format!("robot {robot}'s act segment shrank under the world (truncated while mapped)")
}

/// The world's act services, every read of robot r's under [`reading`]: the same calls as
/// [`ActSource`]'s, and the robots whose segments shrank, for [`GuardedActs::fault_shrunk`].
pub struct GuardedActs {
    /// Always Some but in Drop.
    acts: Option<ActSource>,
    shrunk: Vec<u32>,
    /// A segment of some robot's act service shrank during the run.
    tainted: bool,
}

impl Drop for GuardedActs {
    /// Closing the subscribers writes to every connection (a shrunk one too, which faulted
    /// the world at its very end before this guard).
    fn drop(&mut self) {
        let acts = self.acts.take();
        if self.tainted {
            // A segment shrank: closing would read its zeros (give_up).
            give_up(acts);
        } else {
            let _ = reading(CLOSING, || drop(acts));
        }
    }
}

impl GuardedActs {
    pub fn new(acts: ActSource) -> Self {
        GuardedActs {
            acts: Some(acts),
            shrunk: Vec::new(),
            tainted: false,
        }
    }

    /// Runs `f` on the act services, reading robot `robot`'s: None when the robot's segment
    /// shrank under it (what `f` read is zeros then; the robot is kept for
    /// [`GuardedActs::fault_shrunk`]).
    fn guard<T>(&mut self, robot: u32, f: impl FnOnce(&mut ActSource) -> T) -> Option<T> {
        let acts = self.acts.as_mut().expect("taken only in drop");
        let out = reading(robot, || f(acts));
        if out.is_none() {
            self.shrunk.push(robot);
            self.tainted = true;
        }
        out
    }

    /// [`ActSource::arrived`].
    pub fn arrived(&mut self, robot: u32, k: u64) -> bool {
        self.guard(robot, |a| a.arrived(robot, k)).unwrap_or(false)
    }

    /// [`ActSource::take`]; the messages of a robot whose segment shrank are left out.
    pub fn take(&mut self, robot: u32, k: u64, sent: &mut Air) -> Option<Action> {
        let before = sent.len();
        let out = self.guard(robot, |a| a.take(robot, k, &mut *sent));
        if out.is_none() {
            sent.truncate(before);
        }
        out.flatten()
    }

    /// [`ActSource::take_realtime`]; as [`GuardedActs::take`].
    pub fn take_realtime(
        &mut self,
        robot: u32,
        k: u64,
        since: u64,
        sent: &mut Air,
    ) -> (Option<Action>, Option<Action>) {
        let before = sent.len();
        let out = self.guard(robot, |a| a.take_realtime(robot, k, since, &mut *sent));
        if out.is_none() {
            sent.truncate(before);
        }
        out.unwrap_or((None, None))
    }

    /// [`ActSource::attached`]; 0 (not attached) when the robot's segment shrank.
    pub fn attached(
        &mut self,
        node: &iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
        robot: u32,
    ) -> u64 {
        self.guard(robot, |a| a.attached(node, robot)).unwrap_or(0)
    }

    /// [`ActSource::retire`] (dropping a blackboard writes to its segments).
    pub fn retire(&mut self, robot: u32) {
        self.guard(robot, |a| a.retire(robot));
    }

    /// [`ActSource::poll_realtime`]; no progress when the robot's segment shrank.
    pub fn poll_realtime(&mut self, robot: u32, k: u64, since: u64) -> bool {
        self.guard(robot, |a| a.poll_realtime(robot, k, since))
            .unwrap_or(false)
    }

    /// [`ActSource::holds`].
    pub fn holds(&mut self, robot: u32, k: u64) -> bool {
        self.guard(robot, |a| a.holds(robot, k)).unwrap_or(false)
    }

    /// [`ActSource::discard`].
    pub fn discard(&mut self, robot: u32) {
        self.guard(robot, |a| a.discard(robot));
    }

    /// Makes every robot whose act segment shrank since the last call a fault (a dead robot
    /// stays as it is); whether there was one (its agent is then to be killed).
    pub fn fault_shrunk(&mut self, world: &mut crate::World) -> bool {
        let any = !self.shrunk.is_empty();
        for r in self.shrunk.drain(..) {
            world.mark_dead(r, &cause(r), None, None);
        }
        any
    }
}
