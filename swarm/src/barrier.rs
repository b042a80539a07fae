//! The lock-step tick barrier in shared memory.
//!
//! One futex word wakes every agent at once (one FUTEX_WAKE for all); each agent writes the tick
//! it finished into its own slot and bumps a counter that wakes the world when it reaches the
//! number of live robots. This replaces one iceoryx2 event per agent (~37 us a wake-up on this
//! VM); the data (Sense, Action, the air) stays on iceoryx2. The same slots tell the world exactly
//! which robots acknowledged a tick, which the fault handling needs.
//!
//! Two segments, removed with the rest of the run (docs/protocol.md section 4):
//!
//! - `/dev/shm/<prefix>tick`, the world's: the release and shutdown words, the world's pid, and
//!   per robot the kill order (world) and dead-up-to mark (orchestrator). An agent maps it
//!   read-only ([`TickBarrier::open_agent`]): nothing an agent program writes through its
//!   mappings can release a tick, stop the run or steer the orchestrator's SIGKILLs.
//! - `/dev/shm/<prefix>acks`, the agents': the ack counter the world sleeps on, the ready
//!   counter, and per robot the acknowledged tick and the attach counter.

use crate::bell::EventBell;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::time::{Duration, Instant};

const MAGIC: u64 = 0x5357_4152_4d54_4b34; // "SWARMTK4"

/// Bytes of one robot's slot in the world's segment: kill order, dead-up-to mark.
const CTL_SLOT_BYTES: usize = 16;
/// Bytes of one robot's slot in the agents' segment: acknowledged tick + 1, attach counter.
const ACK_SLOT_BYTES: usize = 16;

/// The head of the world's segment (`<prefix>tick`).
#[repr(C)]
struct Header {
    magic: AtomicU64,
    robots: u32,
    world_pid: AtomicU32,
    /// Futex word the agents sleep on: low 32 bits of (released tick + 1).
    release: AtomicU32,
    shutdown: AtomicU32,
    released_tick: AtomicU64,
    /// How many acknowledgements wake the world.
    expected: AtomicU32,
    _pad: u32,
}

/// The head of the agents' segment (`<prefix>acks`).
#[repr(C)]
struct AckHeader {
    /// Futex word the world sleeps on: acknowledgements since the last release.
    acks: AtomicU32,
    /// Agents that attached and are ready for the first tick.
    ready: AtomicU32,
}

/// One shared-memory segment of the barrier, mapped.
struct Segment {
    base: *mut u8,
    len: usize,
}

impl Drop for Segment {
    fn drop(&mut self) {
        // SAFETY: unmapping our own mapping.
        unsafe {
            libc::munmap(self.base as *mut libc::c_void, self.len);
        }
    }
}

impl Segment {
    /// Creates `/dev/shm/<name>` of `len` zero bytes, mapped read-write. Fails if it exists.
    fn create(name: &str, len: usize) -> std::io::Result<Segment> {
        let c = std::ffi::CString::new(format!("/{name}")).expect("prefix has no NUL");
        // SAFETY: plain POSIX calls with checked results.
        unsafe {
            let fd = libc::shm_open(
                c.as_ptr(),
                libc::O_CREAT | libc::O_EXCL | libc::O_RDWR,
                0o600,
            );
            if fd < 0 {
                return Err(std::io::Error::last_os_error());
            }
            if libc::ftruncate(fd, len as libc::off_t) != 0 {
                let e = std::io::Error::last_os_error();
                libc::close(fd);
                return Err(e);
            }
            Self::map(fd, len, true)
        }
    }

    /// Opens `/dev/shm/<name>` (read-only unless `writable`): its mapping and its length as
    /// `fstat` gives it.
    fn open(name: &str, writable: bool) -> std::io::Result<Segment> {
        let c = std::ffi::CString::new(format!("/{name}")).expect("prefix has no NUL");
        let flags = if writable {
            libc::O_RDWR
        } else {
            libc::O_RDONLY
        };
        // SAFETY: plain POSIX calls with checked results.
        unsafe {
            let fd = libc::shm_open(c.as_ptr(), flags, 0);
            if fd < 0 {
                return Err(std::io::Error::last_os_error());
            }
            let mut st: libc::stat = std::mem::zeroed();
            if libc::fstat(fd, &mut st) != 0 {
                let e = std::io::Error::last_os_error();
                libc::close(fd);
                return Err(e);
            }
            Self::map(fd, st.st_size as usize, writable)
        }
    }

    /// Maps `fd` (closed here) shared.
    unsafe fn map(fd: i32, len: usize, writable: bool) -> std::io::Result<Segment> {
        if len == 0 {
            libc::close(fd);
            return Ok(Segment {
                base: std::ptr::NonNull::<u64>::dangling().as_ptr() as *mut u8,
                len: 0,
            });
        }
        let prot = if writable {
            libc::PROT_READ | libc::PROT_WRITE
        } else {
            libc::PROT_READ
        };
        let p = libc::mmap(std::ptr::null_mut(), len, prot, libc::MAP_SHARED, fd, 0);
        libc::close(fd);
        if p == libc::MAP_FAILED {
            return Err(std::io::Error::last_os_error());
        }
        Ok(Segment {
            base: p as *mut u8,
            len,
        })
    }
}

/// A mapping of the run's barrier segments.
pub struct TickBarrier {
    /// The world's segment (read-only in an agent).
    ctl: Segment,
    /// The agents' segment.
    ack: Segment,
    robots: u32,
}

// SAFETY: the mapping is shared memory accessed only through atomics.
unsafe impl Send for TickBarrier {}
unsafe impl Sync for TickBarrier {}

/// Why the barrier segment could not be created or opened.
#[derive(Debug, thiserror::Error)]
pub enum BarrierError {
    #[error("create the tick barrier /dev/shm/{segment}: {source}")]
    Create {
        segment: String,
        source: std::io::Error,
    },
    #[error("open the tick barrier /dev/shm/{segment}: {source}")]
    Open {
        segment: String,
        source: std::io::Error,
    },
    /// The segment is smaller than its header: not a barrier of this runtime.
    #[error("the tick barrier /dev/shm/{segment} is too small: {bytes} bytes")]
    TooSmall { segment: String, bytes: usize },
    /// The world has not finished writing the segment (or it is not a barrier at all).
    #[error("the tick barrier /dev/shm/{segment} is not initialised")]
    Uninitialised { segment: String },
}

/// The world's segment's name in /dev/shm.
fn segment(prefix: &str) -> String {
    format!("{prefix}tick")
}

/// The agents' segment's name in /dev/shm.
fn ack_segment(prefix: &str) -> String {
    format!("{prefix}acks")
}

pub enum Wake {
    Tick(u64),
    Timeout,
    Shutdown,
}

/// Sleeps while `word` holds `expected` (at most `timeout`; spurious returns are possible).
pub fn futex_wait(word: &AtomicU32, expected: u32, timeout: Duration) {
    let ts = libc::timespec {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: word lives in a shared mapping for the lifetime of self; FUTEX_WAIT (not PRIVATE)
    // because the word is shared between processes.
    unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT,
            expected,
            &ts as *const libc::timespec,
            std::ptr::null::<u32>(),
            0,
        );
    }
}

/// Wakes up to `n` sleepers of `word`.
pub fn futex_wake(word: &AtomicU32, n: i32) {
    // SAFETY: see futex_wait.
    unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAKE,
            n,
            std::ptr::null::<libc::timespec>(),
            std::ptr::null::<u32>(),
            0,
        );
    }
}

impl TickBarrier {
    fn ctl_len(robots: u32) -> usize {
        std::mem::size_of::<Header>() + CTL_SLOT_BYTES * robots as usize
    }

    fn ack_len(robots: u32) -> usize {
        std::mem::size_of::<AckHeader>() + ACK_SLOT_BYTES * robots as usize
    }

    /// Creates both segments (world side). Fails if either exists.
    pub fn create(prefix: &str, robots: u32) -> Result<TickBarrier, BarrierError> {
        let create = |name: String, len: usize| {
            Segment::create(&name, len).map_err(|source| BarrierError::Create {
                segment: name,
                source,
            })
        };
        let ctl = create(segment(prefix), Self::ctl_len(robots))?;
        let ack = create(ack_segment(prefix), Self::ack_len(robots))?;
        let b = TickBarrier { ctl, ack, robots };
        let h = b.header();
        // SAFETY: the segment is ours alone until the magic word is written below.
        unsafe { std::ptr::addr_of!(h.robots).cast_mut().write(robots) };
        h.world_pid.store(std::process::id(), Ordering::Relaxed);
        h.magic.store(MAGIC, Ordering::Release);
        Ok(b)
    }

    /// Opens both segments read-write (the orchestrator, the benchmarks' children).
    pub fn open(prefix: &str) -> Result<TickBarrier, BarrierError> {
        Self::open_as(prefix, true)
    }

    /// Opens the segments as an agent: the world's read-only, the agents' read-write.
    pub fn open_agent(prefix: &str) -> Result<TickBarrier, BarrierError> {
        Self::open_as(prefix, false)
    }

    fn open_as(prefix: &str, world_writable: bool) -> Result<TickBarrier, BarrierError> {
        let open = |name: String, writable: bool| {
            Segment::open(&name, writable).map_err(|source| BarrierError::Open {
                segment: name,
                source,
            })
        };
        let ctl = open(segment(prefix), world_writable)?;
        if ctl.len < std::mem::size_of::<Header>() {
            return Err(BarrierError::TooSmall {
                segment: segment(prefix),
                bytes: ctl.len,
            });
        }
        let ack = open(ack_segment(prefix), true)?;
        let robots = ((ctl.len - std::mem::size_of::<Header>()) / CTL_SLOT_BYTES) as u32;
        if ack.len < Self::ack_len(robots) {
            return Err(BarrierError::TooSmall {
                segment: ack_segment(prefix),
                bytes: ack.len,
            });
        }
        let b = TickBarrier { ctl, ack, robots };
        if b.header().magic.load(Ordering::Acquire) != MAGIC || b.header().robots != robots {
            return Err(BarrierError::Uninitialised {
                segment: segment(prefix),
            });
        }
        Ok(b)
    }

    fn header(&self) -> &Header {
        // SAFETY: the mapping is at least size_of::<Header>() (checked when opened) and page
        // aligned.
        unsafe { &*(self.ctl.base as *const Header) }
    }

    fn ack_header(&self) -> &AckHeader {
        // SAFETY: as above, for the agents' segment.
        unsafe { &*(self.ack.base as *const AckHeader) }
    }

    /// Robot `robot`'s words in the world's segment: 0 = the attach number (the value of
    /// its attach counter after that agent's attach) of the agent the world wants killed;
    /// 1 = the highest attach number the orchestrator knows to be dead. Both name an agent
    /// *incarnation*, so a death report, a kill or an attach is never applied to the wrong
    /// process of a robot (issue 14 item 1).
    fn ctl_word(&self, robot: u32, w: usize) -> &AtomicU64 {
        assert!(robot < self.robots, "robot {robot} out of range");
        let at = std::mem::size_of::<Header>() + CTL_SLOT_BYTES * robot as usize + 8 * w;
        // SAFETY: slots follow the header, 8-byte aligned, within the length checked at open.
        unsafe { &*(self.ctl.base.add(at) as *const AtomicU64) }
    }

    /// Robot `robot`'s words in the agents' segment: 0 = acknowledged tick + 1; 1 = agent
    /// processes that attached.
    fn ack_word(&self, robot: u32, w: usize) -> &AtomicU64 {
        assert!(robot < self.robots, "robot {robot} out of range");
        let at = std::mem::size_of::<AckHeader>() + ACK_SLOT_BYTES * robot as usize + 8 * w;
        // SAFETY: as above, for the agents' segment.
        unsafe { &*(self.ack.base.add(at) as *const AtomicU64) }
    }

    fn slot(&self, robot: u32) -> &AtomicU64 {
        self.ack_word(robot, 0)
    }

    pub fn robots(&self) -> u32 {
        self.robots
    }

    /// The tick the world released last (the tick the swarm is in).
    pub fn current_tick(&self) -> u64 {
        self.header().released_tick.load(Ordering::Acquire)
    }

    pub fn world_pid(&self) -> u32 {
        self.header().world_pid.load(Ordering::Relaxed)
    }

    // ---- world side ----

    pub fn ready_count(&self) -> u32 {
        self.ack_header().ready.load(Ordering::Acquire)
    }

    /// Releases tick k to the agents; `expected` acknowledgements will wake the world.
    pub fn release(&self, tick: u64, expected: u32) {
        self.release_with(tick, expected, None);
    }

    /// `release`, waking the agents through `bell` instead of the futex if given
    /// (`runtime.barrier = "iox2-event"`).
    pub fn release_with(&self, tick: u64, expected: u32, bell: Option<&EventBell>) {
        let h = self.header();
        self.ack_header().acks.store(0, Ordering::Relaxed);
        h.expected.store(expected, Ordering::Relaxed);
        h.released_tick.store(tick, Ordering::Relaxed);
        h.release.store((tick + 1) as u32, Ordering::Release);
        match bell {
            Some(b) => b.ring(),
            None => {
                futex_wake(&h.release, i32::MAX);
            }
        }
    }

    /// Whether robot `robot` acknowledged tick k.
    pub fn acked(&self, robot: u32, tick: u64) -> bool {
        self.slot(robot).load(Ordering::Acquire) == tick + 1
    }

    /// Sleeps until the ack counter moves or `timeout` passes (spurious wake-ups allowed).
    pub fn wait_acks(&self, timeout: Duration) {
        self.wait_acks_with(timeout, None);
    }

    /// `wait_acks`, sleeping on `bell` instead of the futex if given.
    pub fn wait_acks_with(&self, timeout: Duration, bell: Option<&EventBell>) {
        let a = self.ack_header();
        let seen = a.acks.load(Ordering::Acquire);
        if seen >= self.header().expected.load(Ordering::Relaxed) {
            return;
        }
        match bell {
            Some(b) => b.wait(timeout),
            None => futex_wait(&a.acks, seen, timeout),
        }
    }

    /// The ack counter (acknowledgements since the last release, late ones of earlier ticks
    /// included, plus the orchestrator's nudges): read it before checking who acknowledged,
    /// then sleep with [`TickBarrier::wait_ack_change`] on the value read, and no wake-up is
    /// lost in between.
    pub fn ack_count(&self) -> u32 {
        self.ack_header().acks.load(Ordering::Acquire)
    }

    /// Sleeps while the ack counter holds `seen`, at most `timeout` (real-time mode). Unlike
    /// [`TickBarrier::wait_acks`] it does not return at once when the counter reached the
    /// expected number: in real-time mode late acknowledgements of an earlier tick count
    /// too, so the counter can reach it while robots of this tick are still missing.
    pub fn wait_ack_change_with(&self, seen: u32, timeout: Duration, bell: Option<&EventBell>) {
        match bell {
            Some(b) => b.wait(timeout),
            None => futex_wait(&self.ack_header().acks, seen, timeout),
        }
    }

    /// Wakes the world from `wait_acks` (the orchestrator does this after reporting a fault).
    pub fn nudge_world(&self) {
        let a = self.ack_header();
        a.acks.fetch_add(1, Ordering::AcqRel);
        futex_wake(&a.acks, 1);
    }

    /// Tells every agent to exit.
    pub fn shutdown(&self) {
        self.shutdown_with(None);
    }

    /// `shutdown`, also ringing `bell` if given.
    pub fn shutdown_with(&self, bell: Option<&EventBell>) {
        let h = self.header();
        h.shutdown.store(1, Ordering::Release);
        h.release.fetch_add(1, Ordering::AcqRel);
        futex_wake(&h.release, i32::MAX);
        if let Some(b) = bell {
            b.ring();
        }
    }

    pub fn is_shutdown(&self) -> bool {
        self.header().shutdown.load(Ordering::Acquire) != 0
    }

    // ---- agent side ----

    /// An agent process for `robot` is attached and ready for its next tick: its attach
    /// number (the robot's attach counter after this increment), which an agent sends in its
    /// attach notice through its act service. The world believes only the notice.
    pub fn mark_ready(&self, robot: u32) -> u64 {
        let attach = self.ack_word(robot, 1).fetch_add(1, Ordering::AcqRel) + 1;
        self.ack_header().ready.fetch_add(1, Ordering::AcqRel);
        attach
    }

    /// How many agent processes have attached for `robot` (a restart makes it grow).
    pub fn attach_count(&self, robot: u32) -> u64 {
        self.ack_word(robot, 1).load(Ordering::Acquire)
    }

    /// World side: the robot's agent with attach number `attach` is declared dead (a scheduled
    /// kill, an ack deadline): the orchestrator must SIGKILL it if it still runs.
    pub fn order_kill(&self, robot: u32, attach: u64) {
        self.ctl_word(robot, 0).fetch_max(attach, Ordering::AcqRel);
    }

    /// The attach number of the robot's latest agent the world ordered killed (0 = none).
    pub fn kill_order(&self, robot: u32) -> u64 {
        self.ctl_word(robot, 0).load(Ordering::Acquire)
    }

    /// Orchestrator side: every agent of `robot` with an attach number up to `attach` is dead
    /// (reaped). Written before the death is reported on the control channel.
    pub fn set_dead_upto(&self, robot: u32, attach: u64) {
        self.ctl_word(robot, 1).fetch_max(attach, Ordering::AcqRel);
    }

    /// The highest attach number of `robot` known dead (0 = none).
    pub fn dead_upto(&self, robot: u32) -> u64 {
        self.ctl_word(robot, 1).load(Ordering::Acquire)
    }

    /// The last tick this robot acknowledged plus one (0 if none): where a (re)started agent
    /// picks up.
    pub fn acked_up_to(&self, robot: u32) -> u64 {
        self.slot(robot).load(Ordering::Acquire)
    }

    /// Waits for a tick after `done` (ticks < done are finished), for at most `timeout`.
    pub fn wait_release(&self, done: u64, timeout: Duration) -> Wake {
        self.wait_release_with(done, timeout, None)
    }

    /// `wait_release`, sleeping on `bell` instead of the futex if given.
    pub fn wait_release_with(
        &self,
        done: u64,
        timeout: Duration,
        bell: Option<&EventBell>,
    ) -> Wake {
        let h = self.header();
        // The clock is read only when the agent has to sleep: a tick already released (and
        // every wake-up that finds its tick) costs no clock_gettime.
        let mut deadline = None;
        loop {
            if h.shutdown.load(Ordering::Acquire) != 0 {
                return Wake::Shutdown;
            }
            let word = h.release.load(Ordering::Acquire);
            let tick = h.released_tick.load(Ordering::Acquire);
            if word == (tick + 1) as u32 && tick + 1 > done {
                return Wake::Tick(tick);
            }
            let now = Instant::now();
            let deadline = *deadline.get_or_insert(now + timeout);
            if now >= deadline {
                return Wake::Timeout;
            }
            match bell {
                Some(b) => b.wait(deadline - now),
                None => futex_wait(&h.release, word, deadline - now),
            }
        }
    }

    /// Acknowledges tick k for `robot` (after its Action frame is published).
    pub fn ack(&self, robot: u32, tick: u64) {
        self.ack_with(robot, tick, None);
    }

    /// `ack`, ringing `bell` instead of the futex if given.
    pub fn ack_with(&self, robot: u32, tick: u64, bell: Option<&EventBell>) {
        let a = self.ack_header();
        self.slot(robot).store(tick + 1, Ordering::Release);
        let n = a.acks.fetch_add(1, Ordering::AcqRel) + 1;
        if n >= self.header().expected.load(Ordering::Acquire) {
            match bell {
                Some(b) => b.ring(),
                None => {
                    futex_wake(&a.acks, 1);
                }
            }
        }
    }
}

/// Removes the segments' names (the mappings stay valid until dropped).
pub fn unlink(prefix: &str) {
    for name in [segment(prefix), ack_segment(prefix)] {
        let c = std::ffi::CString::new(format!("/{name}")).expect("prefix has no NUL");
        // SAFETY: plain POSIX call.
        unsafe {
            libc::shm_unlink(c.as_ptr());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A segment of `len` zero bytes under the name `name`.
    fn raw_segment(name: &str, len: usize) {
        let name = std::ffi::CString::new(format!("/{name}")).unwrap();
        // SAFETY: plain POSIX calls; the fd is closed at once.
        unsafe {
            let fd = libc::shm_open(name.as_ptr(), libc::O_CREAT | libc::O_RDWR, 0o600);
            assert!(fd >= 0);
            assert_eq!(libc::ftruncate(fd, len as libc::off_t), 0);
            libc::close(fd);
        }
    }

    #[test]
    fn errors_name_the_segment() {
        let prefix = format!("swbe{}_", std::process::id());
        struct Unlink(String);
        impl Drop for Unlink {
            fn drop(&mut self) {
                unlink(&self.0);
            }
        }
        let _unlink = Unlink(prefix.clone());
        let seg = format!("{prefix}tick");
        let e = TickBarrier::open(&prefix).err().expect("no segment yet");
        assert!(matches!(e, BarrierError::Open { .. }), "{e}");
        assert!(e.to_string().contains(&format!("/dev/shm/{seg}")), "{e}");

        let _b = TickBarrier::create(&prefix, 2).unwrap();
        let e = TickBarrier::create(&prefix, 2).err().expect("exists");
        assert!(matches!(e, BarrierError::Create { ref segment, .. } if *segment == seg));
        unlink(&prefix);

        raw_segment(&seg, 8);
        let e = TickBarrier::open(&prefix).err().expect("too small");
        assert!(matches!(e, BarrierError::TooSmall { bytes: 8, .. }), "{e}");
        unlink(&prefix);

        // Big enough, but its magic word was never written.
        raw_segment(&seg, std::mem::size_of::<Header>() + CTL_SLOT_BYTES);
        raw_segment(&ack_segment(&prefix), TickBarrier::ack_len(1));
        let e = TickBarrier::open(&prefix).err().expect("uninitialised");
        assert!(matches!(e, BarrierError::Uninitialised { .. }), "{e}");
        unlink(&prefix);
    }

    /// The layouts docs/protocol.md section 4 gives.
    #[test]
    fn the_protocol_documents_the_barriers_layout() {
        use std::mem::{offset_of, size_of};
        assert_eq!(size_of::<Header>(), 40);
        assert_eq!(
            [
                offset_of!(Header, robots),
                offset_of!(Header, world_pid),
                offset_of!(Header, release),
                offset_of!(Header, shutdown),
                offset_of!(Header, released_tick),
                offset_of!(Header, expected),
            ],
            [8, 12, 16, 20, 24, 32]
        );
        assert_eq!(size_of::<AckHeader>(), 8);
        assert_eq!(offset_of!(AckHeader, ready), 4);
        assert_eq!((CTL_SLOT_BYTES, ACK_SLOT_BYTES), (16, 16));
        assert_eq!(MAGIC.to_be_bytes(), *b"SWARMTK4");
    }

    /// An agent maps the world's segment read-only (its release, shutdown and kill-order
    /// words cannot be written through it) and the agents' segment read-write.
    #[test]
    fn an_agent_maps_the_worlds_words_read_only() {
        let prefix = format!("swbr{}_", std::process::id());
        let _w = TickBarrier::create(&prefix, 2).unwrap();
        let a = TickBarrier::open_agent(&prefix).unwrap();
        a.mark_ready(1);
        assert_eq!(a.attach_count(1), 1);
        let maps = std::fs::read_to_string("/proc/self/maps").unwrap();
        let perms = |name: &str| -> Vec<String> {
            maps.lines()
                .filter(|l| l.ends_with(&format!("/dev/shm/{name}")))
                .map(|l| l.split_whitespace().nth(1).unwrap().to_string())
                .collect()
        };
        // The world's own mapping and the agent's, of each segment.
        let mut ctl = perms(&segment(&prefix));
        ctl.sort();
        assert_eq!(ctl, ["r--s", "rw-s"], "{maps}");
        assert_eq!(perms(&ack_segment(&prefix)), ["rw-s", "rw-s"], "{maps}");
        unlink(&prefix);
    }

    #[test]
    fn release_ack_round_across_threads() {
        let prefix = format!("swtest{}_", std::process::id());
        let w = TickBarrier::create(&prefix, 3).unwrap();
        let agents: Vec<_> = (0..3u32)
            .map(|i| {
                let p = prefix.clone();
                std::thread::spawn(move || {
                    let b = TickBarrier::open(&p).unwrap();
                    b.mark_ready(i);
                    let mut done = 0;
                    let mut seen = vec![];
                    loop {
                        match b.wait_release(done, Duration::from_secs(5)) {
                            Wake::Tick(k) => {
                                seen.push(k);
                                b.ack(i, k);
                                done = k + 1;
                            }
                            Wake::Shutdown => return seen,
                            Wake::Timeout => panic!("timeout"),
                        }
                    }
                })
            })
            .collect();
        while w.ready_count() < 3 {
            std::thread::yield_now();
        }
        for k in 0..50 {
            w.release(k, 3);
            while !(0..3).all(|i| w.acked(i, k)) {
                w.wait_acks(Duration::from_millis(100));
            }
        }
        w.shutdown();
        unlink(&prefix);
        for a in agents {
            assert_eq!(a.join().unwrap(), (0..50).collect::<Vec<u64>>());
        }
    }
}
