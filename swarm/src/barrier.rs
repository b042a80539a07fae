//! The lock-step tick barrier in shared memory.
//!
//! One futex word wakes every agent at once (one FUTEX_WAKE for all); each agent writes the tick
//! it finished into its own slot and bumps a counter that wakes the world when it reaches the
//! number of live robots. This replaces one iceoryx2 event per agent (~37 us a wake-up on this
//! VM); the data (Sense, Action, the air) stays on iceoryx2. The same slots tell the world exactly
//! which robots acknowledged a tick, which the fault handling needs.
//!
//! Two segments, anonymous files (memfds, `swarm::sealed`) the orchestrator makes and hands to
//! the world and to every agent as inherited descriptors ([`FDS_ENV`]); nothing of the barrier
//! is in /dev/shm, so no process can open it by name, and its seals hold for any descriptor of
//! it (docs/protocol.md section 4):
//!
//! - the world's segment (`tick`): the release and shutdown words, the world's pid, and per
//!   robot the kill order (world) and dead-up-to mark (orchestrator). Once the world and the
//!   orchestrator mapped it, it is sealed against every new writable mapping and every write()
//!   (`F_SEAL_FUTURE_WRITE`); an agent maps it read-only ([`TickBarrier::open_agent`]): no
//!   agent program can release a tick, stop the run or steer the orchestrator's SIGKILLs.
//! - the agents' segment (`acks`): the ack counter the world sleeps on, the ready counter, and
//!   per robot the acknowledged tick and the attach counter.
//!
//! Both are sealed against shrinking and growing from their creation: no process can truncate
//! them under the world or the orchestrator (which a file in /dev/shm allowed: SIGBUS).

use crate::bell::EventBell;
use crate::sealed::{Mapping, SealError, SIZE_SEALS};
use rustix::fs::SealFlags;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, OwnedFd};
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
    /// The generation of the world's data services (`world/sense`, `radio/air`;
    /// `swarm::transport::Generation`): the world raises it, before a release, when it made
    /// them anew; an agent that finds it changed at a release opens them again.
    data_generation: AtomicU32,
}

/// The head of the agents' segment (`<prefix>acks`).
#[repr(C)]
struct AckHeader {
    /// Futex word the world sleeps on: acknowledgements since the last release.
    acks: AtomicU32,
    /// Agents that attached and are ready for the first tick.
    ready: AtomicU32,
}

/// A mapping of the run's barrier segments.
pub struct TickBarrier {
    /// The world's segment (read-only in an agent).
    ctl: Mapping,
    /// The agents' segment.
    ack: Mapping,
    robots: u32,
}

// SAFETY: the mapping is shared memory accessed only through atomics.
unsafe impl Send for TickBarrier {}
unsafe impl Sync for TickBarrier {}

/// Why the barrier segments could not be made or opened.
#[derive(Debug, thiserror::Error)]
pub enum BarrierError {
    /// Making, sealing, checking or mapping a segment failed (the segment and fd are named).
    #[error("tick barrier: {0}")]
    Seal(#[from] SealError),
    /// The process was not started with the barrier's descriptors.
    #[error(
        "tick barrier: {FDS_ENV} = {value:?} does not name two open descriptors \"<tick fd>,<acks \
         fd>\" (the orchestrator hands them to the world and agents it starts; \
         docs/protocol.md section 4)"
    )]
    NoFds { value: String },
    /// A descriptor [`FDS_ENV`] names is not the run's barrier segment.
    #[error(
        "tick barrier: fd {fd} is {found:?}, not this run's segment (the memfd {expected:?}; \
         {FDS_ENV}, docs/protocol.md section 4)"
    )]
    NotThisRun {
        fd: i32,
        expected: String,
        found: String,
    },
    /// The segment is smaller than its header: not a barrier of this runtime.
    #[error("the tick barrier segment {segment} is too small: {bytes} bytes")]
    TooSmall { segment: String, bytes: usize },
    /// The segment was never initialised (not a barrier of this runtime).
    #[error("the tick barrier segment {segment} is not initialised")]
    Uninitialised { segment: String },
}

/// The environment variable that names the barrier's inherited descriptors, `<tick>,<acks>`
/// (decimal fd numbers), in the world and in every agent (docs/protocol.md section 4).
pub const FDS_ENV: &str = "SWARM_BARRIER_FDS";

/// The world's segment's memfd name (shown as `/memfd:<name>` in /proc/<pid>/fd).
fn segment(prefix: &str) -> String {
    format!("{prefix}tick")
}

/// The agents' segment's memfd name.
fn ack_segment(prefix: &str) -> String {
    format!("{prefix}acks")
}

/// The seals the world's segment carries once the world and the orchestrator mapped it:
/// fixed size, no new writable mapping nor write(), no further seal.
pub const TICK_SEALS: SealFlags = SIZE_SEALS
    .union(SealFlags::FUTURE_WRITE)
    .union(SealFlags::SEAL);
/// The seals of the agents' segment, from its creation: fixed size, no further seal (nobody
/// can seal it against the writable mappings every agent needs).
pub const ACKS_SEALS: SealFlags = SIZE_SEALS.union(SealFlags::SEAL);

/// The run's barrier segments as the orchestrator holds them: the memfds it hands to the
/// world and to every agent it starts (restarted ones too).
pub struct BarrierFds {
    tick: OwnedFd,
    acks: OwnedFd,
    prefix: String,
}

impl BarrierFds {
    /// Makes `cmd`'s child inherit both descriptors, named by [`FDS_ENV`].
    pub fn pass_to(&self, cmd: &mut std::process::Command) {
        let (t, a) = (self.tick.as_raw_fd(), self.acks.as_raw_fd());
        cmd.env(FDS_ENV, format!("{t},{a}"));
        crate::sealed::pass_to(cmd, &[t, a]);
    }

    /// Seals the world's segment against every new writable mapping and write(): called once
    /// the world and the orchestrator mapped it, before any agent starts. From then on no
    /// process can write the release, shutdown or kill-order words but through those two
    /// mappings, whatever descriptor of the segment it gets (even through /proc/<pid>/fd).
    pub fn seal_worlds_segment(&self) -> Result<(), BarrierError> {
        let name = segment(&self.prefix);
        crate::sealed::seal(self.tick.as_fd(), &name, TICK_SEALS)?;
        Ok(())
    }
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

    /// Makes both segments (the orchestrator, the benchmarks' parents): memfds of their fixed
    /// sizes (sealed so), mapped read-write, the world's header initialised (its `world_pid`
    /// this process's until the world writes its own). The descriptors are for
    /// [`BarrierFds::pass_to`].
    pub fn create(prefix: &str, robots: u32) -> Result<(TickBarrier, BarrierFds), BarrierError> {
        let make = |name: String, len: usize| -> Result<(OwnedFd, Mapping), BarrierError> {
            let fd = crate::sealed::create(&name, len)?;
            let map = Mapping::map(fd.as_fd(), &name, len, true)?;
            Ok((fd, map))
        };
        let (tick, ctl) = make(segment(prefix), Self::ctl_len(robots))?;
        let (acks, ack) = make(ack_segment(prefix), Self::ack_len(robots))?;
        crate::sealed::seal(acks.as_fd(), &ack_segment(prefix), ACKS_SEALS)?;
        let b = TickBarrier { ctl, ack, robots };
        let h = b.header();
        // SAFETY: the segment is ours alone until the magic word is written below.
        unsafe { std::ptr::addr_of!(h.robots).cast_mut().write(robots) };
        h.world_pid.store(std::process::id(), Ordering::Relaxed);
        h.magic.store(MAGIC, Ordering::Release);
        let fds = BarrierFds {
            tick,
            acks,
            prefix: prefix.to_string(),
        };
        Ok((b, fds))
    }

    /// Maps the inherited segments read-write (the world, the benchmarks' children), and
    /// records this process as the world.
    pub fn open_world() -> Result<TickBarrier, BarrierError> {
        let b = Self::open_as(SIZE_SEALS, true)?;
        b.header()
            .world_pid
            .store(std::process::id(), Ordering::Release);
        Ok(b)
    }

    /// Maps the inherited segments read-write without claiming the world's part (the
    /// benchmarks' children).
    pub fn open_inherited() -> Result<TickBarrier, BarrierError> {
        Self::open_as(SIZE_SEALS, true)
    }

    /// Opens the segments of the run with the iceoryx2 prefix `prefix` as an agent, from the
    /// descriptors [`FDS_ENV`] names (refused unless they are that run's memfds): the world's
    /// read-only (refused unless sealed [`TICK_SEALS`]: nobody can map it writable any more),
    /// the agents' read-write (refused unless its size is sealed). docs/protocol.md section 4.
    pub fn open_agent(prefix: &str) -> Result<TickBarrier, BarrierError> {
        let (tick, acks) = Self::inherited_fds()?;
        for (fd, name) in [(tick, segment(prefix)), (acks, ack_segment(prefix))] {
            let found = std::fs::read_link(format!("/proc/self/fd/{}", fd.as_raw_fd()))
                .map(|p| p.display().to_string())
                .unwrap_or_default();
            // A memfd's link reads "/memfd:<name> (deleted)".
            if found != format!("/memfd:{name} (deleted)") {
                return Err(BarrierError::NotThisRun {
                    fd: fd.as_raw_fd(),
                    expected: name,
                    found,
                });
            }
        }
        Self::open_fds(tick, acks, TICK_SEALS, false)
    }

    /// The descriptors [`FDS_ENV`] names.
    fn inherited_fds() -> Result<(BorrowedFd<'static>, BorrowedFd<'static>), BarrierError> {
        let value = std::env::var(FDS_ENV).unwrap_or_default();
        let fds = value
            .split_once(',')
            .and_then(|(t, a)| Some((t.parse().ok()?, a.parse().ok()?)))
            .and_then(|(t, a)| Some((crate::sealed::inherited(t)?, crate::sealed::inherited(a)?)));
        fds.ok_or(BarrierError::NoFds { value })
    }

    fn open_as(tick_seals: SealFlags, world_writable: bool) -> Result<TickBarrier, BarrierError> {
        let (tick, acks) = Self::inherited_fds()?;
        Self::open_fds(tick, acks, tick_seals, world_writable)
    }

    /// Checks the seals (`tick_seals` on the world's segment, the size seals on the agents')
    /// and maps both segments.
    fn open_fds(
        tick: BorrowedFd,
        acks: BorrowedFd,
        tick_seals: SealFlags,
        world_writable: bool,
    ) -> Result<TickBarrier, BarrierError> {
        let name = |fd: BorrowedFd, what: &str| format!("{what} (fd {})", fd.as_raw_fd());
        let (tick_name, acks_name) = (name(tick, "tick"), name(acks, "acks"));
        let ctl_len = crate::sealed::check(tick, &tick_name, tick_seals)?;
        if ctl_len < std::mem::size_of::<Header>() {
            return Err(BarrierError::TooSmall {
                segment: tick_name,
                bytes: ctl_len,
            });
        }
        let ack_len = crate::sealed::check(acks, &acks_name, SIZE_SEALS)?;
        let robots = ((ctl_len - std::mem::size_of::<Header>()) / CTL_SLOT_BYTES) as u32;
        if ack_len < Self::ack_len(robots) {
            return Err(BarrierError::TooSmall {
                segment: acks_name,
                bytes: ack_len,
            });
        }
        let ctl = Mapping::map(tick, &tick_name, ctl_len, world_writable)?;
        let ack = Mapping::map(acks, &acks_name, ack_len, true)?;
        let b = TickBarrier { ctl, ack, robots };
        if b.header().magic.load(Ordering::Acquire) != MAGIC || b.header().robots != robots {
            return Err(BarrierError::Uninitialised { segment: tick_name });
        }
        Ok(b)
    }

    fn header(&self) -> &Header {
        // SAFETY: the mapping is at least size_of::<Header>() (checked when opened) and page
        // aligned.
        unsafe { &*(self.ctl.base() as *const Header) }
    }

    fn ack_header(&self) -> &AckHeader {
        // SAFETY: as above, for the agents' segment.
        unsafe { &*(self.ack.base() as *const AckHeader) }
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
        unsafe { &*(self.ctl.base().add(at) as *const AtomicU64) }
    }

    /// Robot `robot`'s words in the agents' segment: 0 = acknowledged tick + 1; 1 = agent
    /// processes that attached.
    fn ack_word(&self, robot: u32, w: usize) -> &AtomicU64 {
        assert!(robot < self.robots, "robot {robot} out of range");
        let at = std::mem::size_of::<AckHeader>() + ACK_SLOT_BYTES * robot as usize + 8 * w;
        // SAFETY: as above, for the agents' segment.
        unsafe { &*(self.ack.base().add(at) as *const AtomicU64) }
    }

    fn slot(&self, robot: u32) -> &AtomicU64 {
        self.ack_word(robot, 0)
    }

    /// The generation of the world's data services (`world/sense`, `radio/air`) as of the
    /// last release.
    pub fn data_generation(&self) -> u32 {
        self.header().data_generation.load(Ordering::Acquire)
    }

    /// The world made its data services anew under generation `g` (before the release that
    /// tells the agents).
    pub fn set_data_generation(&self, g: u32) {
        self.header().data_generation.store(g, Ordering::Release);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Opens `fds` as an agent would.
    fn agent(fds: &BarrierFds) -> Result<TickBarrier, BarrierError> {
        TickBarrier::open_fds(fds.tick.as_fd(), fds.acks.as_fd(), TICK_SEALS, false)
    }

    /// Opens `fds` as the world or a benchmark's child would.
    fn world(fds: &BarrierFds) -> Result<TickBarrier, BarrierError> {
        TickBarrier::open_fds(fds.tick.as_fd(), fds.acks.as_fd(), SIZE_SEALS, true)
    }

    #[test]
    fn errors_name_the_segment_and_what_is_wrong() {
        // No descriptors in the environment (this test process was not started so).
        let e = TickBarrier::open_agent("swbe_").err().expect("no fds");
        assert!(matches!(e, BarrierError::NoFds { .. }), "{e}");
        assert!(e.to_string().contains(FDS_ENV), "{e}");

        let (_w, fds) = TickBarrier::create("swbe_", 2).unwrap();
        // Another run's descriptors (or any other file) are refused by name. (The only test
        // that sets the variable.)
        let value = format!("{},{}", fds.tick.as_raw_fd(), fds.acks.as_raw_fd());
        std::env::set_var(FDS_ENV, &value);
        let e = TickBarrier::open_agent("swother_")
            .err()
            .expect("not this run's");
        assert!(
            matches!(e, BarrierError::NotThisRun { ref expected, .. } if expected == "swother_tick"),
            "{e}"
        );
        fds.seal_worlds_segment().unwrap();
        assert!(TickBarrier::open_agent("swbe_").is_ok());
        std::env::remove_var(FDS_ENV);
        let (_w, fds) = TickBarrier::create("swbe_", 2).unwrap();
        // The world's segment is not sealed against writes yet: an agent refuses it.
        let e = agent(&fds).err().expect("not sealed yet");
        assert!(
            matches!(e, BarrierError::Seal(SealError::Unsealed { ref missing, .. })
                if missing.contains(SealFlags::FUTURE_WRITE)),
            "{e}"
        );
        assert!(e.to_string().contains("tick (fd"), "{e}");

        // A memfd anybody could resize: refused before it is mapped.
        let loose = |len: usize| {
            let fd =
                rustix::fs::memfd_create("loose", rustix::fs::MemfdFlags::ALLOW_SEALING).unwrap();
            rustix::fs::ftruncate(&fd, len as u64).unwrap();
            fd
        };
        let tick = loose(std::mem::size_of::<Header>() + CTL_SLOT_BYTES);
        let e = TickBarrier::open_fds(tick.as_fd(), fds.acks.as_fd(), SIZE_SEALS, true)
            .err()
            .expect("unsealed");
        assert!(
            matches!(e, BarrierError::Seal(SealError::Unsealed { .. })),
            "{e}"
        );

        // Sealed, but too small, or never initialised.
        let small = crate::sealed::create("small", 8).unwrap();
        let e = TickBarrier::open_fds(small.as_fd(), fds.acks.as_fd(), SIZE_SEALS, true)
            .err()
            .expect("too small");
        assert!(matches!(e, BarrierError::TooSmall { bytes: 8, .. }), "{e}");
        let blank = crate::sealed::create("blank", TickBarrier::ctl_len(2)).unwrap();
        let e = TickBarrier::open_fds(blank.as_fd(), fds.acks.as_fd(), SIZE_SEALS, true)
            .err()
            .expect("uninitialised");
        assert!(matches!(e, BarrierError::Uninitialised { .. }), "{e}");
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
                offset_of!(Header, data_generation),
            ],
            [8, 12, 16, 20, 24, 32, 36]
        );
        assert_eq!(size_of::<AckHeader>(), 8);
        assert_eq!(offset_of!(AckHeader, ready), 4);
        assert_eq!((CTL_SLOT_BYTES, ACK_SLOT_BYTES), (16, 16));
        assert_eq!(MAGIC.to_be_bytes(), *b"SWARMTK4");
    }

    /// Once sealed, the world's segment cannot be written but through the mappings made
    /// before the seal: not through a new writable mapping, write(), a descriptor opened again
    /// through /proc/self/fd, nor an agent's read-only mapping made writable. Neither segment
    /// can be resized, nor sealed further.
    #[test]
    fn the_worlds_words_are_out_of_an_agents_reach() {
        use rustix::mm::{MapFlags, MprotectFlags, ProtFlags};
        let (w, fds) = TickBarrier::create("swbr_", 2).unwrap();
        fds.seal_worlds_segment().unwrap();
        let a = agent(&fds).unwrap();
        a.mark_ready(1);
        assert_eq!(w.attach_count(1), 1);
        // The mappings made before the seal still write.
        w.order_kill(1, 7);
        assert_eq!(a.kill_order(1), 7);

        let len = TickBarrier::ctl_len(2);
        let refused = |r: rustix::io::Result<()>, what: &str| {
            assert!(r.is_err(), "{what} was allowed");
        };
        let reopened = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(format!("/proc/self/fd/{}", fds.tick.as_raw_fd()))
            .unwrap();
        for fd in [fds.tick.as_fd(), reopened.as_fd()] {
            refused(rustix::io::write(fd, &[1u8; 8]).map(|_| ()), "write");
            refused(rustix::io::pwrite(fd, &[1u8; 8], 20).map(|_| ()), "pwrite");
            refused(rustix::fs::ftruncate(fd, 0), "shrink");
            refused(rustix::fs::ftruncate(fd, 1 << 20), "grow");
            // SAFETY: a new mapping, unmapped at once if it was made.
            let m = unsafe {
                rustix::mm::mmap(
                    std::ptr::null_mut(),
                    len,
                    ProtFlags::READ | ProtFlags::WRITE,
                    MapFlags::SHARED,
                    fd,
                    0,
                )
            };
            if let Ok(p) = m {
                // SAFETY: our own mapping.
                unsafe { rustix::mm::munmap(p, len).unwrap() };
            }
            refused(m.map(|_| ()), "a writable shared mapping");
        }
        // The agent's read-only mapping cannot be made writable.
        // SAFETY: mprotect of the agent's own mapping; refused, so nothing changes.
        let r = unsafe { rustix::mm::mprotect(a.ctl.base() as *mut _, len, MprotectFlags::WRITE) };
        refused(r, "mprotect(PROT_WRITE) of the agent's mapping");
        // The agents' segment: written by agents, never resized, never sealed further.
        refused(rustix::fs::ftruncate(&fds.acks, 0), "shrink acks");
        refused(rustix::fs::ftruncate(&fds.acks, 1 << 20), "grow acks");
        refused(
            rustix::fs::fcntl_add_seals(&fds.acks, SealFlags::FUTURE_WRITE),
            "seal acks",
        );
        assert_eq!(w.kill_order(1), 7);
        assert!(!w.is_shutdown());
    }

    #[test]
    fn release_ack_round_across_threads() {
        let (w, fds) = TickBarrier::create("swtest_", 3).unwrap();
        let agents: Vec<_> = (0..3u32)
            .map(|i| {
                let b = world(&fds).unwrap();
                std::thread::spawn(move || {
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
        for a in agents {
            assert_eq!(a.join().unwrap(), (0..50).collect::<Vec<u64>>());
        }
    }
}
