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
//! The handler is async-signal-safe: atomics, `syscall(SYS_gettid)`, `mmap` and `sigaction`.

use std::sync::atomic::{compiler_fence, AtomicU32, AtomicU64, AtomicUsize, Ordering};
use swarm::frames::Action;
use swarm::mailbox::Air;
use swarm::transport::ActSource;

/// [`READING`]'s value while the world reads no robot's segments.
const NOBODY: u32 = u32::MAX;
/// The marker of a read of the run's own segments, no robot's (`run/control` in the world
/// and the orchestrator, `world/state` in the orchestrator): a fault there is absorbed (the
/// read sees zeros, which these services' readers ignore) and reported to the caller.
pub const RUN_SEGMENTS: u32 = u32::MAX - 2;

/// The marker of the world's writes of its own data services (`world/sense`, `radio/air`):
/// a fault there is absorbed (the write goes to a private zero page) and reported to the
/// caller, which makes the services anew (`crate::data_plane`).
pub const WORLD_DATA: u32 = u32::MAX - 3;

/// [`READING`]'s value while the world closes every act service, after its outputs are
/// written: a segment that shrank is of no consequence any more.
const CLOSING: u32 = u32::MAX - 1;

/// The robot whose act service the world is reading, or [`NOBODY`].
static READING: AtomicU32 = AtomicU32::new(NOBODY);
/// The thread that reads it (a SIGBUS of another thread is not that robot's).
static READER: AtomicU32 = AtomicU32::new(0);
/// The robot whose read faulted (and was given zeros), or [`NOBODY`].
static SHRANK: AtomicU32 = AtomicU32::new(NOBODY);
/// How many guarded reads began: the read watchdog (`read_watchdog`) tells one long read
/// from many short ones by it.
static READS: AtomicU64 = AtomicU64::new(0);
/// The page size, read once by [`install`] (sysconf is not async-signal-safe).
static PAGE: AtomicUsize = AtomicUsize::new(0);

/// The SIGBUS handler could not be installed.
#[derive(Debug, thiserror::Error)]
#[error("install the SIGBUS handler (a shrunk act segment ends in a fault of its robot): {0}")]
pub struct GuardError(std::io::Error);

/// The calling thread's kernel id.
fn tid() -> u32 {
    // SAFETY: gettid has no arguments and cannot fail.
    unsafe { libc::syscall(libc::SYS_gettid) as u32 }
}

/// Puts the default SIGBUS action back: the faulting access, run again, kills the process.
fn fall_back() {
    // SAFETY: a zeroed sigaction with SIG_DFL; sigaction is async-signal-safe.
    unsafe {
        let mut dfl: libc::sigaction = std::mem::zeroed();
        dfl.sa_sigaction = libc::SIG_DFL;
        libc::sigaction(libc::SIGBUS, &dfl, std::ptr::null_mut());
    }
}

extern "C" fn on_sigbus(_sig: libc::c_int, info: *mut libc::siginfo_t, _ctx: *mut libc::c_void) {
    let robot = READING.load(Ordering::Acquire);
    let page = PAGE.load(Ordering::Relaxed);
    if robot == NOBODY || READER.load(Ordering::Acquire) != tid() || info.is_null() || page == 0 {
        fall_back();
        return;
    }
    // SAFETY: the kernel passes a valid siginfo_t for a SA_SIGINFO handler; for SIGBUS,
    // si_addr is the faulting address.
    let addr = unsafe { (*info).si_addr() } as usize;
    let start = addr & !(page - 1);
    // SAFETY: replaces one page of a shared mapping the world is reading (the part of robot
    // r's segment beyond the file's new end) with private zeros; nothing else is touched.
    let p = unsafe {
        libc::mmap(
            start as *mut libc::c_void,
            page,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_FIXED | libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
            -1,
            0,
        )
    };
    if p == libc::MAP_FAILED {
        fall_back();
        return;
    }
    SHRANK.store(robot, Ordering::Release);
}

/// Installs the handler (once, before the world reads any act service).
pub fn install() -> Result<(), GuardError> {
    // SAFETY: sysconf with a constant argument.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    PAGE.store(page.max(1) as usize, Ordering::Relaxed);
    // SAFETY: a sigaction naming a handler that is async-signal-safe (above).
    let r = unsafe {
        let mut sa: libc::sigaction = std::mem::zeroed();
        sa.sa_sigaction = on_sigbus as *const () as usize;
        sa.sa_flags = libc::SA_SIGINFO;
        libc::sigemptyset(&mut sa.sa_mask);
        libc::sigaction(libc::SIGBUS, &sa, std::ptr::null_mut())
    };
    if r != 0 {
        return Err(GuardError(std::io::Error::last_os_error()));
    }
    // iceoryx2 panics on some zeros it reads from a shrunk segment (a publisher's zeroed
    // allocator: "the system seems to be corrupted"): [`reading`] catches that panic, and this
    // hook keeps it off stderr; every other panic is reported as before.
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if SHRANK.load(Ordering::Acquire) == NOBODY {
                previous(info);
            }
        }));
    });
    Ok(())
}

/// Runs `f`, which reads robot `robot`'s act service (or [`RUN_SEGMENTS`]): None when one of
/// the segments it touched shrank under it (`f` then read zeros there, or panicked on them;
/// either way its result is not to be believed: the caller makes the robot a fault, or gives
/// up the run's segment, [`control_lost`]). A panic without a shrink is passed on.
pub fn reading<T>(robot: u32, f: impl FnOnce() -> T) -> Option<T> {
    thread_local! {
        /// This thread's kernel id (one syscall per thread, not one per read: the world
        /// guards every poll of every robot's act service).
        static TID: u32 = tid();
    }
    READER.store(TID.with(|t| *t), Ordering::Release);
    READS.store(READS.load(Ordering::Relaxed) + 1, Ordering::Relaxed);
    READING.store(robot, Ordering::Release);
    // The handler runs on this thread: the marker is set before any of f's reads and cleared
    // after them, as the compiler emits them.
    compiler_fence(Ordering::SeqCst);
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    compiler_fence(Ordering::SeqCst);
    READING.store(NOBODY, Ordering::Release);
    let shrank = SHRANK.swap(NOBODY, Ordering::AcqRel) == robot;
    match out {
        Ok(v) if !shrank => Some(v),
        Err(panic) if !shrank => std::panic::resume_unwind(panic),
        _ => None,
    }
}

/// The read in progress: the robot whose act service is being read (None: no robot's) and
/// the number of the read (`READS`), for the read watchdog.
pub fn read_in_progress() -> (Option<u32>, u64) {
    let robot = READING.load(Ordering::Acquire);
    let n = READS.load(Ordering::Relaxed);
    let robot = (robot < WORLD_DATA).then_some(robot);
    (robot, n)
}

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

/// Lets go of `t` (ports and services one of whose segments shrank) without closing them:
/// closing reads their segments, and iceoryx2 panics on the zeros it finds there, which
/// during an unwind aborts the process. Their files stay until the orchestrator removes the
/// run's files at its end (as it does for any run).
pub fn give_up<T>(t: T) {
    std::mem::forget(t);
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use std::os::fd::AsRawFd;

    /// A file mapped shared, then truncated to nothing: reading it under [`reading`] gives
    /// zeros and reports the robot; the test process lives on.
    #[test]
    fn a_read_of_a_truncated_mapping_gives_zeros_and_names_the_robot() {
        install().unwrap();
        let page = PAGE.load(Ordering::Relaxed);
        let mut f = tempfile_in_shm();
        f.write_all(&vec![7u8; 3 * page]).unwrap();
        // SAFETY: a fresh shared read-only mapping of the file, unmapped below.
        let p = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                3 * page,
                libc::PROT_READ,
                libc::MAP_SHARED,
                f.as_raw_fd(),
                0,
            )
        } as *const u8;
        assert_ne!(p as *mut libc::c_void, libc::MAP_FAILED);
        // SAFETY: within the mapping.
        let read = |at: usize| unsafe { std::ptr::read_volatile(p.add(at)) };
        assert_eq!(reading(3, || read(page + 1)), Some(7));
        f.set_len(0).unwrap();
        assert_eq!(reading(3, || read(1) as u32 + read(page + 1) as u32), None);
        // The fault was reported once; the page is zeros from now on.
        assert_eq!(reading(3, || read(1)), Some(0));
        // A panic on the zeros (iceoryx2's on a zeroed allocator) is the shrink's.
        let panics = || {
            if read(2 * page) == 0 {
                panic!("zeros");
            }
        };
        assert_eq!(reading(3, panics), None);
        // A panic without a shrink is not absorbed.
        let other = std::panic::catch_unwind(|| reading(3, || panic!("a bug")));
        assert!(other.is_err());
        // SAFETY: our mapping.
        unsafe { libc::munmap(p as *mut libc::c_void, 3 * page) };
    }

    /// A file under /dev/shm (tmpfs, as iceoryx2's), removed at once (named `sw…` so a leak
    /// would be this project's).
    fn tempfile_in_shm() -> std::fs::File {
        let path = format!("/dev/shm/swguard{}", std::process::id());
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)
            .unwrap();
        std::fs::remove_file(&path).unwrap();
        f
    }
}
