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
//! Bytes an agent keeps in shared memory past its guarded reads (a zero-copy [`crate::Blob`]
//! view into an air sample, which behaviour code reads whenever it likes, on any thread) are
//! guarded by address instead: [`absorb_mapping_of`] registers the whole mapping that holds
//! them (a subscriber's view of the world's data segment), and a SIGBUS at an address inside
//! a registered range, on any thread at any time, maps a zero page there too; the access
//! resumes and reads zeros, and [`absorbed`] counts it (the caller says so once). Only faults
//! of an access beyond a file's end (`BUS_ADRERR`) are absorbed there.
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

/// How many address ranges [`absorb_range`] keeps: an agent registers two a generation of the
/// world's data services (the Sense and the air data segments), and the world makes at most
/// 9 generations in a run (`world::data_plane::MAX_REMAKES` + 1).
pub const RANGES: usize = 32;
/// The registered ranges `[start, end)`: a slot is in use once its start is not 0 (its end is
/// stored first); slots are never cleared (a registered mapping is one the process keeps
/// mapped: the services of an old generation are let go unclosed, [`give_up`]).
static RANGE_START: [AtomicUsize; RANGES] = [const { AtomicUsize::new(0) }; RANGES];
static RANGE_END: [AtomicUsize; RANGES] = [const { AtomicUsize::new(0) }; RANGES];
/// Serialises [`absorb_range`]s (the handler only reads the slots).
static RANGES_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
/// How many faults in registered ranges the handler absorbed.
static ABSORBED: AtomicU64 = AtomicU64::new(0);

/// Whether `addr` lies in a registered range (async-signal-safe: atomic loads only).
fn in_ranges(addr: usize) -> bool {
    RANGE_START.iter().zip(&RANGE_END).any(|(s, e)| {
        let s = s.load(Ordering::Acquire);
        s != 0 && addr >= s && addr < e.load(Ordering::Acquire)
    })
}

/// Registers `[start, start + len)`: a SIGBUS at an address inside it, beyond the end of the
/// file mapped there, is absorbed on any thread at any time (a zero page is mapped over the
/// faulting page and [`absorbed`] counts it). False when the table is full (the range is not
/// guarded). A range inside one registered already is not registered again.
pub fn absorb_range(start: usize, len: usize) -> bool {
    let end = start.saturating_add(len);
    if start == 0 || len == 0 {
        return false;
    }
    let _lock = RANGES_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let covered = RANGE_START.iter().zip(&RANGE_END).any(|(s, e)| {
        let s = s.load(Ordering::Acquire);
        s != 0 && s <= start && end <= e.load(Ordering::Acquire)
    });
    if covered {
        return true;
    }
    let Some(i) = RANGE_START
        .iter()
        .position(|s| s.load(Ordering::Acquire) == 0)
    else {
        return false;
    };
    RANGE_END[i].store(end, Ordering::Release);
    RANGE_START[i].store(start, Ordering::Release);
    true
}

/// The file mapping of this process that holds address `p`: `[start, end)` of its line in
/// /proc/self/maps, joined with the lines next to it of the same file (one `mmap` that the
/// handler split already). None when `p` is in no mapping, or in one of no file.
pub fn mapping_of(p: usize) -> Option<(usize, usize)> {
    let maps = std::fs::read_to_string("/proc/self/maps").ok()?;
    mapping_in(&maps, p)
}

/// [`mapping_of`] in the text `maps` of /proc/<pid>/maps.
fn mapping_in(maps: &str, p: usize) -> Option<(usize, usize)> {
    // Each line: `start-end perms offset dev inode [path]`; kept: start, end, (dev, inode).
    let lines: Vec<(usize, usize, (&str, &str))> = maps
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let (s, e) = f.first()?.split_once('-')?;
            let s = usize::from_str_radix(s, 16).ok()?;
            let e = usize::from_str_radix(e, 16).ok()?;
            Some((s, e, (*f.get(3)?, *f.get(4)?)))
        })
        .collect();
    let at = lines.iter().position(|&(s, e, _)| s <= p && p < e)?;
    let (mut start, mut end, file) = lines[at];
    if file.1 == "0" {
        return None;
    }
    for &(s, e, f) in lines[..at].iter().rev() {
        if e != start || f != file {
            break;
        }
        start = s;
    }
    for &(s, e, f) in &lines[at + 1..] {
        if s != end || f != file {
            break;
        }
        end = e;
    }
    Some((start, end))
}

/// Registers the mapping that holds address `p` ([`mapping_of`], [`absorb_range`]); the
/// range registered, or None (no such mapping, or the table is full).
pub fn absorb_mapping_of(p: usize) -> Option<(usize, usize)> {
    let (start, end) = mapping_of(p)?;
    absorb_range(start, end - start).then_some((start, end))
}

/// How many faults in registered ranges were absorbed so far (each read zeros instead of the
/// bytes that were there).
pub fn absorbed() -> u64 {
    ABSORBED.load(Ordering::Acquire)
}

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
    let page = PAGE.load(Ordering::Relaxed);
    if info.is_null() || page == 0 {
        fall_back();
        return;
    }
    // SAFETY: the kernel passes a valid siginfo_t for a SA_SIGINFO handler; for SIGBUS,
    // si_addr is the faulting address.
    let (addr, code) = unsafe { ((*info).si_addr() as usize, (*info).si_code) };
    let robot = READING.load(Ordering::Acquire);
    let guarded = robot != NOBODY && READER.load(Ordering::Acquire) == tid();
    // Outside a guarded read: absorbed only beyond the end of a registered mapping's file.
    let registered = code == libc::BUS_ADRERR && in_ranges(addr);
    if !guarded && !registered {
        fall_back();
        return;
    }
    if !zero_page(addr & !(page - 1), page) {
        fall_back();
        return;
    }
    if guarded {
        SHRANK.store(robot, Ordering::Release);
    } else {
        ABSORBED.fetch_add(1, Ordering::AcqRel);
    }
}

/// Maps a private zero page at `start` (page-aligned) over what was there; false if it could
/// not. Async-signal-safe (mmap).
fn zero_page(start: usize, page: usize) -> bool {
    // SAFETY: replaces one page of a shared mapping being read (the part of a segment beyond
    // the file's new end: a robot's act segment under the world's read, or a registered range
    // of the world's data segment under an agent's) with private zeros; nothing else is
    // touched.
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
    p != libc::MAP_FAILED
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

    /// A file mapped shared and registered ([`absorb_mapping_of`]), then truncated to
    /// nothing: read on another thread, outside any [`reading`], it gives zeros and the fault
    /// is counted; the test process lives on. A mapping not registered still faults (in a
    /// child process, which dies of SIGBUS).
    #[test]
    fn a_registered_mapping_read_anywhere_after_truncation_gives_zeros() {
        install().unwrap();
        let page = PAGE.load(Ordering::Relaxed);
        let map = |f: &std::fs::File| {
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
            };
            assert_ne!(p, libc::MAP_FAILED);
            p as usize
        };
        let mut f = tempfile_in_shm();
        f.write_all(&vec![7u8; 3 * page]).unwrap();
        let p = map(&f);
        // (p is in a file's mapping; an address in no file's is not registered.)
        assert_eq!(mapping_of(&page as *const usize as usize), None);
        let mut g = tempfile_in_shm();
        g.write_all(&vec![7u8; 3 * page]).unwrap();
        let q = map(&g);
        // SAFETY: within a mapping of 3 pages, which stays mapped (q's until the end).
        let read =
            |base: usize, at: usize| unsafe { std::ptr::read_volatile((base + at) as *const u8) };
        // The whole mapping is found from an address inside it, and registered once.
        assert_eq!(absorb_mapping_of(p + page + 5), Some((p, p + 3 * page)));
        assert_eq!(absorb_mapping_of(p), Some((p, p + 3 * page)));
        assert_eq!(read(p, 2 * page), 7);
        f.set_len(0).unwrap();
        g.set_len(0).unwrap();
        let before = absorbed();
        let sum =
            std::thread::spawn(move || (0..3).map(|i| read(p, i * page + 1) as u32).sum::<u32>())
                .join()
                .unwrap();
        assert_eq!(sum, 0);
        assert_eq!(absorbed() - before, 3, "one fault a page");
        // The mapping not registered: a read of it still dies of SIGBUS.
        // SAFETY: the child only reads memory and exits.
        let child = unsafe { libc::fork() };
        if child == 0 {
            read(q, 1);
            // SAFETY: leaves the child at once.
            unsafe { libc::_exit(0) };
        }
        let mut status = 0;
        // SAFETY: waits for our own child.
        assert_eq!(unsafe { libc::waitpid(child, &mut status, 0) }, child);
        assert!(
            libc::WIFSIGNALED(status) && libc::WTERMSIG(status) == libc::SIGBUS,
            "status {status:#x}"
        );
        // SAFETY: our mapping (p's stays: its range stays registered, as an agent's do).
        unsafe { libc::munmap(q as *mut libc::c_void, 3 * page) };
    }

    #[test]
    fn mapping_in_joins_the_lines_of_one_file_and_skips_anonymous_memory() {
        let maps = "\
1000-2000 r--p 00000000 08:01 11 /usr/bin/x
2000-3000 r--s 00000000 00:19 42 /dev/shm/iox2_a.data
3000-4000 rw-p 00000000 00:00 0
4000-6000 r--s 00002000 00:19 42 /dev/shm/iox2_a.data
6000-7000 r--s 00000000 00:19 43 /dev/shm/iox2_b.data
7000-8000 rw-p 00000000 00:00 0
";
        assert_eq!(mapping_in(maps, 0x2fff), Some((0x2000, 0x3000)));
        assert_eq!(mapping_in(maps, 0x3000), None, "anonymous");
        // A zero page mapped over the middle of a file's mapping (the handler's) splits it:
        // only the lines next to each other are joined.
        assert_eq!(mapping_in(maps, 0x4000), Some((0x4000, 0x6000)));
        assert_eq!(mapping_in(maps, 0x6100), Some((0x6000, 0x7000)));
        assert_eq!(mapping_in(maps, 0x9000), None);
        let adjacent = "\
2000-3000 r--s 00000000 00:19 42 /dev/shm/iox2_a.data
3000-4000 r--s 00001000 00:19 42 /dev/shm/iox2_a.data
4000-6000 r--s 00002000 00:19 42 /dev/shm/iox2_a.data
";
        assert_eq!(mapping_in(adjacent, 0x3800), Some((0x2000, 0x6000)));
    }

    /// A file under /dev/shm (tmpfs, as iceoryx2's), removed at once (named `sw…` so a leak
    /// would be this project's).
    fn tempfile_in_shm() -> std::fs::File {
        static N: AtomicU32 = AtomicU32::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let path = format!("/dev/shm/swguard{}-{n}", std::process::id());
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
