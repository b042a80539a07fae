//! Every robot's Action frame and message area of a tick in a cell of its own, all cells in
//! ONE shared-memory segment the world creates (`runtime.acts = "cells"`, the default; issue
//! 15, the tick target).
//!
//! With one iceoryx2 act service per robot the agents make N publishes and the world N
//! receives and releases a tick (BENCHMARKS 17: the tick is bounded by the barrier wake and
//! per-robot port operations). Here an agent writes its action straight into its cell and the
//! world reads every cell after the acks: no port operation at all, one mapping a process.
//!
//! # Layout
//!
//! `/dev/shm/<prefix>acts`: a [`HEAD_BYTES`] head (`magic`, `robots`, `area`, `buffer`
//! bytes), then per robot two buffers of `buffer` bytes (64-byte aligned, no false sharing
//! between robots), buffer `tick & 1` for a tick's action, so that in real-time mode the
//! world can read tick k's while a late agent writes tick k + 1's. A buffer is
//! `[stamp: u64][reserved: u64][Action][message area: area bytes]`.
//!
//! # The stamp (a seqlock)
//!
//! Writer (the robot's agent, the only writer of its cell): (W1) `stamp = 0` (Relaxed), then
//! a Release fence; (W2) the message area and the Action; (W3) `stamp = tick + 1` (Release).
//!
//! Reader (the world): (R1) `s = stamp` (Acquire); not the tick it wants: no action; (R2)
//! copy the Action and the used part of the area out; an Acquire fence; (R3) `stamp` again
//! (Relaxed): changed, the copy may be torn and is refused (no action, as a missing iceoryx2
//! sample was).
//!
//! If R1 reads W3's value, everything W2 wrote before it is visible to R2. If R2 read any
//! byte of a later write (a rewrite of the buffer two ticks on, or a restarted agent), that
//! write's W1 came before the byte (the Release fence) and R3 comes after it (the Acquire
//! fence): R3 sees 0 or a later stamp, never `s`, and the copy is refused. An agent
//! SIGKILLed between W1 and W3 leaves the stamp at 0: its half-written action is never read.
//! A stamp is only ever a tick + 1 written after the whole buffer, so a torn write cannot be
//! mistaken for a whole one by the same tick unless two writers write the same cell at the
//! same tick: a replacement agent is only started after its predecessor was reaped (the
//! supervisor's restart), so there is one writer per cell.
//!
//! Every length read from a cell is bounded by the segment's area (`Action::radio_bytes`
//! beyond it is cut to it; the messages in it are parsed with bounds checks by
//! `swarm::air::act_messages`), so a misbehaving agent cannot make the world read outside
//! its cell.

use super::{map, unlink, Mapping};
use crate::frames::Action;
use std::mem::size_of;
use std::sync::atomic::{fence, AtomicU64, Ordering};

const MAGIC: u64 = 0x5357_4152_4d41_4354; // "SWARMACT"
/// The acts segment's name after the run's prefix (`/dev/shm/<prefix>acts`).
pub const ACTS_SEGMENT: &str = "acts";
/// Bytes of the segment's head, and the alignment of every buffer (a cache line).
const HEAD_BYTES: usize = 64;
const ALIGN: usize = 64;
/// A buffer's bytes before its Action: the stamp and a reserved word.
const STAMP_BYTES: usize = 16;
/// Buffers a robot's cell has (by tick parity).
const BUFFERS: usize = 2;

/// Why the acts segment could not be made or opened.
#[derive(Debug, thiserror::Error)]
pub enum ActCellsError {
    #[error("acts segment /dev/shm/{name}: {source}")]
    Io {
        name: String,
        source: std::io::Error,
    },
    #[error("acts segment /dev/shm/{name} is not initialised or too small")]
    Invalid { name: String },
    #[error("robot {robot} has no act cell (robots 0..{robots})")]
    NoRobot { robot: u32, robots: u32 },
}

impl From<super::AirRingError> for ActCellsError {
    fn from(e: super::AirRingError) -> Self {
        match e {
            super::AirRingError::Io { name, source } => ActCellsError::Io { name, source },
            other => ActCellsError::Invalid {
                name: other.to_string(),
            },
        }
    }
}

#[repr(C)]
struct Head {
    magic: AtomicU64,
    robots: u32,
    area: u32,
    buffer: u64,
}

fn buffer_bytes(area: usize) -> usize {
    (STAMP_BYTES + size_of::<Action>() + area).next_multiple_of(ALIGN)
}

fn segment_bytes(robots: u32, area: usize) -> usize {
    HEAD_BYTES + robots as usize * BUFFERS * buffer_bytes(area)
}

/// The segment as either side maps it.
struct Segment {
    mapping: Mapping,
    robots: u32,
    area: usize,
    buffer: usize,
}

impl Segment {
    /// Robot `robot`'s buffer for ticks of parity `parity`: its stamp and its base.
    fn buffer(&self, robot: u32, parity: u64) -> (&AtomicU64, *mut u8) {
        assert!(robot < self.robots);
        let at = HEAD_BYTES + (robot as usize * BUFFERS + (parity & 1) as usize) * self.buffer;
        // SAFETY: within the mapping (segment_bytes), 64-byte aligned (HEAD_BYTES and buffer
        // are multiples of ALIGN, the mapping is page aligned); the stamp is an AtomicU64.
        unsafe {
            let base = self.mapping.base.add(at);
            (&*(base as *const AtomicU64), base)
        }
    }
    fn action_ptr(base: *mut u8) -> *mut Action {
        // SAFETY: the Action follows the stamp words, 8-byte aligned, within the buffer.
        unsafe { base.add(STAMP_BYTES) as *mut Action }
    }
    fn area_ptr(base: *mut u8) -> *mut u8 {
        // SAFETY: the area follows the Action within the buffer.
        unsafe { base.add(STAMP_BYTES + size_of::<Action>()) }
    }
}

/// The world's side: makes the segment (removed when this is dropped) and reads the cells.
pub struct ActCells {
    name: String,
    seg: Segment,
    /// Reads refused because the stamp changed under them (torn or overtaken writes).
    torn: u64,
}

impl ActCells {
    /// Creates `/dev/shm/<prefix>acts` with a cell for each of `robots` robots, each buffer
    /// with a message area of `area` bytes (`transport::act_slice_len`), every stamp 0.
    pub fn create(prefix: &str, robots: u32, area: usize) -> Result<ActCells, ActCellsError> {
        let name = format!("{prefix}{ACTS_SEGMENT}");
        let mapping = map(&name, Some(segment_bytes(robots, area)))?;
        let seg = Segment {
            mapping,
            robots,
            area,
            buffer: buffer_bytes(area),
        };
        // SAFETY: a new file of zeros nobody else maps before the magic is stored.
        unsafe {
            let h = seg.mapping.base as *mut Head;
            std::ptr::addr_of_mut!((*h).robots).write(robots);
            std::ptr::addr_of_mut!((*h).area).write(area as u32);
            std::ptr::addr_of_mut!((*h).buffer).write(seg.buffer as u64);
            (*h).magic.store(MAGIC, Ordering::Release);
        }
        Ok(ActCells { name, seg, torn: 0 })
    }

    /// Robot `robot`'s action of tick t (buffer `parity`, t's parity) for the first t that
    /// `want` accepts, with its message area's used bytes copied into `area` (cleared first;
    /// `Action::radio_bytes` cut to the area). None: no action stamped that `want` accepts,
    /// being written, or overwritten while read (torn: counted).
    pub fn read(
        &mut self,
        robot: u32,
        parity: u64,
        want: impl Fn(u64) -> bool,
        area: &mut Vec<u8>,
    ) -> Option<(u64, Action)> {
        self.read_with(robot, parity, want, area, || {})
    }

    /// [`ActCells::read`] with `between` run after the copy and before the stamp is checked
    /// again (the tests' window for a write racing the read).
    fn read_with(
        &mut self,
        robot: u32,
        parity: u64,
        want: impl Fn(u64) -> bool,
        area: &mut Vec<u8>,
        between: impl FnOnce(),
    ) -> Option<(u64, Action)> {
        if robot >= self.seg.robots {
            return None;
        }
        let (stamp, base) = self.seg.buffer(robot, parity);
        let s = stamp.load(Ordering::Acquire); // R1
        if s == 0 || !want(s - 1) {
            return None;
        }
        // R2. SAFETY: the Action and the area lie within the buffer; any bytes are a valid
        // Action (integers and floats) and a valid area; a concurrent write is detected below
        // and the copy dropped.
        let a = unsafe { std::ptr::read_volatile(Segment::action_ptr(base)) };
        let used = (a.radio_bytes as usize).min(self.seg.area);
        area.clear();
        area.reserve(used);
        unsafe {
            std::ptr::copy_nonoverlapping(Segment::area_ptr(base), area.as_mut_ptr(), used);
            area.set_len(used);
        }
        between();
        fence(Ordering::Acquire);
        if stamp.load(Ordering::Relaxed) != s {
            // R3: rewritten while read.
            self.torn += 1;
            area.clear();
            return None;
        }
        let mut a = a;
        a.radio_bytes = used as u32;
        Some((s - 1, a))
    }

    /// Forgets robot `robot`'s actions (its agent is dead): both stamps 0.
    pub fn clear(&self, robot: u32) {
        if robot < self.seg.robots {
            for p in 0..BUFFERS as u64 {
                self.seg.buffer(robot, p).0.store(0, Ordering::Release);
            }
        }
    }

    /// Reads refused because a write overtook them.
    pub fn torn(&self) -> u64 {
        self.torn
    }

    /// Bytes of a message area.
    pub fn area(&self) -> usize {
        self.seg.area
    }
}

impl Drop for ActCells {
    fn drop(&mut self) {
        unlink(&self.name);
    }
}

/// A robot's agent's side: writes its own cell.
pub struct ActCellWriter {
    seg: Segment,
    robot: u32,
}

impl ActCellWriter {
    /// Opens the world's segment (`/dev/shm/<prefix>acts`) for robot `robot` (again, after a
    /// restart: the cell is the robot's, whichever agent drives it).
    pub fn open(prefix: &str, robot: u32) -> Result<ActCellWriter, ActCellsError> {
        let name = format!("{prefix}{ACTS_SEGMENT}");
        let mapping = map(&name, None)?;
        let invalid = || ActCellsError::Invalid { name: name.clone() };
        if mapping.len < HEAD_BYTES {
            return Err(invalid());
        }
        // SAFETY: at least a head is mapped; its fields are read after the magic (Acquire).
        let h = unsafe { &*(mapping.base as *const Head) };
        if h.magic.load(Ordering::Acquire) != MAGIC {
            return Err(invalid());
        }
        let (robots, area, buffer) = (h.robots, h.area as usize, h.buffer as usize);
        if buffer != buffer_bytes(area) || mapping.len < segment_bytes(robots, area) {
            return Err(invalid());
        }
        if robot >= robots {
            return Err(ActCellsError::NoRobot { robot, robots });
        }
        Ok(ActCellWriter {
            seg: Segment {
                mapping,
                robots,
                area,
                buffer,
            },
            robot,
        })
    }

    /// Starts writing tick `tick`'s action (W1): the buffer's stamp is 0 until
    /// [`ActWrite::finish`]; dropped unfinished (or the process killed), the buffer holds no
    /// action.
    pub fn begin(&mut self, tick: u64) -> ActWrite<'_> {
        let (stamp, base) = self.seg.buffer(self.robot, tick);
        stamp.store(0, Ordering::Relaxed);
        fence(Ordering::Release);
        ActWrite {
            stamp,
            base,
            area: self.seg.area,
            tick,
        }
    }

    /// Writes tick `tick`'s action: `fill` writes the message area and returns the Action.
    pub fn write(&mut self, tick: u64, fill: impl FnOnce(&mut [u8]) -> Action) {
        let mut w = self.begin(tick);
        let a = fill(w.area_mut());
        w.finish(a);
    }
}

/// A write of one buffer in progress (between W1 and W3).
pub struct ActWrite<'a> {
    stamp: &'a AtomicU64,
    base: *mut u8,
    area: usize,
    tick: u64,
}

impl ActWrite<'_> {
    /// The buffer's message area (W2).
    pub fn area_mut(&mut self) -> &mut [u8] {
        // SAFETY: the area lies within the buffer; only this robot's agent writes it, and
        // `&mut self` keeps one writer in the process. Its bytes are initialised (tmpfs).
        unsafe { std::slice::from_raw_parts_mut(Segment::area_ptr(self.base), self.area) }
    }

    /// Writes the Action (W2) and stamps the buffer (W3): the world may read it from now on.
    pub fn finish(self, a: Action) {
        // SAFETY: the Action's place in the buffer, written by this writer only.
        unsafe { std::ptr::write_volatile(Segment::action_ptr(self.base), a) };
        self.stamp.store(self.tick + 1, Ordering::Release);
    }
}

#[cfg(test)]
mod tests;
