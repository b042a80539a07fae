//! A guard against a shared segment that shrinks under its reader (issue 37 item 4): the
//! world's, the orchestrator's and every agent's.
//!
//! iceoryx2's segments are files in /dev/shm that any process of the user can `ftruncate`; a
//! read or write of a mapping beyond the file's new end raises SIGBUS, which kills the
//! process. [`install`] sets a SIGBUS handler; while a thread touches segments it says so
//! ([`reading`], with a marker: the robot whose act service the world reads, or one of the
//! markers below); a SIGBUS on that thread then maps an anonymous zero page over the faulting
//! page (the access resumes and sees zeros) and records the fault, and [`reading`] reports it
//! (None): the caller makes the robot a fault, remakes the service, or gives it up. A SIGBUS
//! anywhere else is not absorbed: the handler puts back the action that was there before
//! [`install`] (the default, or a handler of the program's own, e.g. Python's faulthandler)
//! and the faulting access, run again, meets it.
//!
//! The handler is async-signal-safe: atomics, `syscall(SYS_gettid)`, `mmap` and `sigaction`.

use std::sync::atomic::{compiler_fence, AtomicU32, AtomicU64, AtomicUsize, Ordering};

/// [`READING`]'s value while the world reads no robot's segments.
const NOBODY: u32 = u32::MAX;
/// The marker of a read of the run's own segments, no robot's (`run/control` in the world
/// and the orchestrator, `world/state` in the orchestrator): a fault there is absorbed (the
/// read sees zeros, which these services' readers ignore) and reported to the caller.
pub const RUN_SEGMENTS: u32 = u32::MAX - 2;

/// The marker of an agent's reads of the world's data services (its Sense record, its list in
/// the air): a fault there is absorbed and reported; the agent holds its robot still for the
/// tick (the world remakes the services at its next write, docs/protocol.md section 4).
pub const AGENT_FRAMES: u32 = u32::MAX - 4;

/// The marker of the world's writes of its own data services (`world/sense`, `radio/air`):
/// a fault there is absorbed (the write goes to a private zero page) and reported to the
/// caller, which makes the services anew (`crate::data_plane`).
pub const WORLD_DATA: u32 = u32::MAX - 3;

/// [`READING`]'s value while the world closes every act service, after its outputs are
/// written: a segment that shrank is of no consequence any more.
pub const CLOSING: u32 = u32::MAX - 1;

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
#[error("install the SIGBUS handler (a shrunk shared segment ends in a fault, not a signal): {0}")]
pub struct GuardError(std::io::Error);

/// The calling thread's kernel id.
fn tid() -> u32 {
    // SAFETY: gettid has no arguments and cannot fail.
    unsafe { libc::syscall(libc::SYS_gettid) as u32 }
}

/// The SIGBUS action before [`install`] (its `sa_sigaction`, `sa_flags`; SIG_DFL until then).
static PREVIOUS_ACTION: AtomicUsize = AtomicUsize::new(libc::SIG_DFL);
static PREVIOUS_FLAGS: AtomicUsize = AtomicUsize::new(0);

/// Puts the SIGBUS action that was there before [`install`] back (the default kills the
/// process when the faulting access runs again).
fn fall_back() {
    // SAFETY: a sigaction rebuilt from the one saved by install (its handler and flags, an
    // empty mask); sigaction is async-signal-safe.
    unsafe {
        let mut prev: libc::sigaction = std::mem::zeroed();
        prev.sa_sigaction = PREVIOUS_ACTION.load(Ordering::Relaxed);
        prev.sa_flags = PREVIOUS_FLAGS.load(Ordering::Relaxed) as libc::c_int;
        libc::sigaction(libc::SIGBUS, &prev, std::ptr::null_mut());
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
    // SAFETY: a sigaction naming a handler that is async-signal-safe (above); the one it
    // replaces is saved (once: a second install must not save our own as the previous).
    let r = unsafe {
        let mut sa: libc::sigaction = std::mem::zeroed();
        sa.sa_sigaction = on_sigbus as *const () as usize;
        sa.sa_flags = libc::SA_SIGINFO;
        libc::sigemptyset(&mut sa.sa_mask);
        let mut old: libc::sigaction = std::mem::zeroed();
        let r = libc::sigaction(libc::SIGBUS, &sa, &mut old);
        if r == 0 && old.sa_sigaction != on_sigbus as *const () as usize {
            PREVIOUS_ACTION.store(old.sa_sigaction, Ordering::Relaxed);
            PREVIOUS_FLAGS.store(old.sa_flags as usize, Ordering::Relaxed);
        }
        r
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

/// Lets go of `t` (ports and services one of whose segments shrank) without closing them:
/// closing reads their segments, and iceoryx2 panics on the zeros it finds there, which
/// during an unwind aborts the process. Their files stay until the orchestrator removes the
/// run's files at its end (as it does for any run).
pub fn give_up<T>(t: T) {
    std::mem::forget(t);
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
