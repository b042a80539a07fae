//! The air in a world-owned ring of shared-memory slots (issue 15, the /dev/shm item;
//! `radio.air = "ring"`, the default).
//!
//! Through an iceoryx2 publish-subscribe service the air costs subscribers x (buffer +
//! borrowed) slots of the largest air sample, every byte zeroed when the segment is made: at
//! 1,000 robots 2,005 x 256 KiB = 501 MiB of /dev/shm for one ~200 KB sample a tick. Every
//! agent reads the same sample, so the world keeps the air itself:
//!
//! - a control segment `/dev/shm/<prefix>air`: one descriptor per slot (free, ready or
//!   being written, the tick it holds, its [`AirHeader`], its data file's generation and
//!   size), the slot last published, and each robot's **hold cells**;
//! - per slot, a data file `/dev/shm/<prefix>air.<slot>.<generation>`, made when the slot is
//!   first used and made anew (twice the size, the old one unlinked) when an air outgrows it.
//!
//! # Holds that survive SIGKILL
//!
//! Each robot has `radio.zero_copy_held + 1` cells of its own (one for the air it is reading,
//! one per air its zero-copy `Blob` views keep alive). A cell holds `slot + 1` or 0. Only that
//! robot's agent writes its cells, except that the world clears all of a robot's cells while
//! it knows the robot dead (a SIGKILLed agent cannot release its holds; the world learns of
//! the death through the supervisor's report or the ack deadline, and clears them again when
//! a new agent takes the robot over). A hold is therefore never leaked past its agent's life,
//! and a kill cannot exhaust the ring. The ring has `2 + robots x cells` slots: every cell
//! may hold a different slot, one more is the published one, and one is left to write, so the
//! writer always finds a free slot while the cells are honest. Data files exist only for the
//! slots ever used: in lock-step two (the one agents read, the one being written), plus one
//! per distinct air views keep alive.
//!
//! # The reader/writer race (why a writer never rewrites a slot someone reads)
//!
//! Writer, to reuse slot s: (W1) `state[s] = WRITING` (SeqCst store); (W2) load every cell
//! (SeqCst); if one holds s, put the state back and try another slot; else write the data,
//! the header and the tick, then `state[s] = READY` (Release) and `current = s + 1`.
//!
//! Reader, to read the published slot s: (R1) store `s + 1` into a free cell of its own
//! (SeqCst compare-exchange from 0); (R2) load `state[s]` (SeqCst); if it is not READY, clear
//! the cell and start again from `current`; else read the header, tick and data.
//!
//! All four are SeqCst, so they are in one total order S. If R1 comes before W2 in S, the
//! writer's scan sees the hold (the cell keeps s + 1 until the reader is done) and leaves s
//! alone. Otherwise W2, and so W1 before it, precedes R1 and R2, and R2 sees WRITING or a
//! later value: WRITING makes the reader back off; READY (the Release store ending a write
//! that began at W1) means that write is complete and visible to the reader (the load
//! acquires it), and any later rewrite starts with a W1' after R2 in S, whose scan W2' comes
//! after R1 and sees the hold. Either way no reader reads a slot while it is written. Both may
//! see each other (the writer skips, the reader retries): safe, and it can only happen to a
//! reader that loaded `current` before the writer moved on, i.e. one already late. A test
//! below runs the protocol from threads, checking every byte of every air read.
//!
//! An agent the world has declared dead but that still runs (stopped, then woken before the
//! supervisor's kill) may find its cells cleared under it: it reads a slot that may be
//! rewritten. Its output is ignored (the world applies nothing of a dead robot's), and its
//! process is being killed.

use crate::frames::AirHeader;
use std::ffi::CString;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;

const MAGIC: u64 = 0x5357_4152_4d52_4e47; // "SWARMRNG"
/// A slot's states (besides 0, free: never written yet).
const READY: u32 = 1;
const WRITING: u32 = 2;
/// Smallest data file (bytes): small airs share one size, so early ticks do not regrow.
const MIN_SLOT_BYTES: usize = 64 * 1024;
/// Times a reader starts again from the published slot when the writer is reusing the one it
/// found (only a reader that is already late can see that) before it reports no air.
const READ_RETRIES: u32 = 64;

/// Why the ring could not be made, opened or written.
#[derive(Debug, thiserror::Error)]
pub enum AirRingError {
    #[error("air ring /dev/shm/{name}: {source}")]
    Io {
        name: String,
        source: std::io::Error,
    },
    #[error("air ring /dev/shm/{name} is not initialised or too small")]
    Invalid { name: String },
    /// Every slot is held by readers (cannot happen while every cell is honest: the ring has
    /// a slot for every cell, plus two).
    #[error("every one of the air ring's {slots} slots is held by readers")]
    Full { slots: u32 },
    /// A reader has all its hold cells in use (more zero-copy holds than it was given).
    #[error("robot {robot} holds airs in all of its {cells} hold cells")]
    NoCell { robot: u32, cells: u32 },
    #[error("robot {robot} is not in the air ring (robots 0..{robots})")]
    NoRobot { robot: u32, robots: u32 },
}

#[repr(C)]
struct Control {
    magic: AtomicU64,
    slots: u32,
    robots: u32,
    /// Hold cells per robot.
    cells: u32,
    _pad: u32,
    /// The slot last published, + 1 (0: none yet).
    current: AtomicU64,
}

#[repr(C)]
struct Slot {
    /// FREE, READY or WRITING.
    state: AtomicU32,
    /// Generation of its data file (0: no file yet).
    generation: AtomicU32,
    /// Bytes of its data file.
    capacity: AtomicU64,
    /// The tick the air in it is due at.
    tick: AtomicU64,
    /// The air's header, written while WRITING.
    header: AirHeader,
}

/// A shared mapping, unmapped when the last reference goes.
struct Mapping {
    base: *mut u8,
    len: usize,
}

// SAFETY: the mapping is plain shared memory; every access to the control part goes through
// atomics, and data slots are written only while no reader holds them (the ring's protocol).
unsafe impl Send for Mapping {}
unsafe impl Sync for Mapping {}

impl Drop for Mapping {
    fn drop(&mut self) {
        // SAFETY: our own mapping, unmapped once.
        unsafe {
            libc::munmap(self.base as *mut libc::c_void, self.len.max(1));
        }
    }
}

fn shm_name(name: &str) -> CString {
    CString::new(format!("/{name}")).expect("prefix has no NUL")
}

/// The ring of the air (`/dev/shm/<prefix>air`); a sibling ring of the same protocol names
/// itself otherwise (the Sense frames' ring is `sense`, [`sense`]).
pub const AIR_RING: &str = "air";

fn control_name(prefix: &str) -> String {
    prefix.to_string()
}

fn data_name(prefix: &str, slot: u32, generation: u32) -> String {
    format!("{prefix}.{slot}.{generation}")
}

/// Opens (or with `create`, creates exclusively at `len` bytes) a /dev/shm file and maps it.
fn map(name: &str, create: Option<usize>) -> Result<Mapping, AirRingError> {
    let io = |source| AirRingError::Io {
        name: name.to_string(),
        source,
    };
    let c = shm_name(name);
    // SAFETY: plain POSIX calls with checked results; the fd is closed before returning.
    unsafe {
        let flags = match create {
            Some(_) => libc::O_CREAT | libc::O_EXCL | libc::O_RDWR,
            None => libc::O_RDWR,
        };
        let fd = libc::shm_open(c.as_ptr(), flags, 0o600);
        if fd < 0 {
            return Err(io(std::io::Error::last_os_error()));
        }
        let len = match create {
            Some(len) => {
                if libc::ftruncate(fd, len as libc::off_t) != 0 {
                    let e = std::io::Error::last_os_error();
                    libc::close(fd);
                    return Err(io(e));
                }
                len
            }
            None => {
                let mut st: libc::stat = std::mem::zeroed();
                if libc::fstat(fd, &mut st) != 0 {
                    let e = std::io::Error::last_os_error();
                    libc::close(fd);
                    return Err(io(e));
                }
                st.st_size as usize
            }
        };
        let p = libc::mmap(
            std::ptr::null_mut(),
            len.max(1),
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_SHARED,
            fd,
            0,
        );
        libc::close(fd);
        if p == libc::MAP_FAILED {
            return Err(io(std::io::Error::last_os_error()));
        }
        Ok(Mapping {
            base: p as *mut u8,
            len,
        })
    }
}

fn unlink(name: &str) {
    let c = shm_name(name);
    // SAFETY: plain POSIX call.
    unsafe {
        libc::shm_unlink(c.as_ptr());
    }
}

/// The control segment, as either side maps it.
struct Ring {
    control: Mapping,
    slots: u32,
    robots: u32,
    cells: u32,
}

// SAFETY: Ring is a mapping read and written through atomics only (and slot headers under
// the protocol above).
unsafe impl Send for Ring {}
unsafe impl Sync for Ring {}

impl Ring {
    fn slots_at() -> usize {
        std::mem::size_of::<Control>()
    }
    fn cells_at(slots: u32) -> usize {
        Self::slots_at() + slots as usize * std::mem::size_of::<Slot>()
    }
    fn bytes_for(slots: u32, robots: u32, cells: u32) -> usize {
        Self::cells_at(slots) + robots as usize * cells as usize * 4
    }
    fn control(&self) -> &Control {
        // SAFETY: the mapping starts with a Control, page aligned.
        unsafe { &*(self.control.base as *const Control) }
    }
    fn slot(&self, s: u32) -> &Slot {
        assert!(s < self.slots);
        let at = Self::slots_at() + s as usize * std::mem::size_of::<Slot>();
        // SAFETY: the descriptors follow the control block, 8-byte aligned, within the mapping.
        unsafe { &*(self.control.base.add(at) as *const Slot) }
    }
    /// Every robot's hold cells, robot by robot.
    fn all_cells(&self) -> &[AtomicU32] {
        let at = Self::cells_at(self.slots);
        // SAFETY: robots x cells u32 cells follow the descriptors (4-byte aligned: a Slot's
        // size is a multiple of 8), within the mapping.
        unsafe {
            std::slice::from_raw_parts(
                self.control.base.add(at) as *const AtomicU32,
                self.robots as usize * self.cells as usize,
            )
        }
    }
    fn cells_of(&self, robot: u32) -> &[AtomicU32] {
        let c = self.cells as usize;
        &self.all_cells()[robot as usize * c..(robot as usize + 1) * c]
    }
    fn header_ptr(&self, s: u32) -> *mut AirHeader {
        std::ptr::addr_of!(self.slot(s).header).cast_mut()
    }
}

/// The world's side: writes one air a tick into a free slot and publishes it.
pub struct AirWriter {
    prefix: String,
    ring: Ring,
    /// Each slot's data mapping (None: no file yet).
    data: Vec<Option<Mapping>>,
    /// Slots some cell holds (scratch of `claim`).
    held: Vec<bool>,
}

impl AirWriter {
    /// Creates the ring for `robots` agents that may each hold `held` airs through zero-copy
    /// views (and one more while reading).
    pub fn create(prefix: &str, robots: u32, held: u32) -> Result<AirWriter, AirRingError> {
        Self::create_named(prefix, AIR_RING, robots, held)
    }

    /// [`AirWriter::create`] for a ring named `kind` (`/dev/shm/<prefix><kind>` and its data
    /// files): the same protocol for another per-tick publication (the Sense frames).
    pub fn create_named(
        prefix: &str,
        kind: &str,
        robots: u32,
        held: u32,
    ) -> Result<AirWriter, AirRingError> {
        let prefix = format!("{prefix}{kind}");
        let prefix = prefix.as_str();
        let cells = held.saturating_add(1);
        let slots = robots.saturating_mul(cells).saturating_add(2);
        let name = control_name(prefix);
        let control = map(&name, Some(Ring::bytes_for(slots, robots, cells)))?;
        let ring = Ring {
            control,
            slots,
            robots,
            cells,
        };
        let c = ring.control();
        // SAFETY: nobody else maps the segment before the magic is stored (a new file of
        // zeros: every slot FREE, every cell empty).
        unsafe {
            std::ptr::addr_of!(c.slots).cast_mut().write(slots);
            std::ptr::addr_of!(c.robots).cast_mut().write(robots);
            std::ptr::addr_of!(c.cells).cast_mut().write(cells);
        }
        c.magic.store(MAGIC, Ordering::Release);
        Ok(AirWriter {
            prefix: prefix.to_string(),
            ring,
            data: (0..slots).map(|_| None).collect(),
            held: vec![false; slots as usize],
        })
    }

    /// Writes an air of `len` bytes (`fill` writes them and returns the header) due at `tick`
    /// and publishes it: readers from now on see it.
    pub fn publish(
        &mut self,
        tick: u64,
        len: usize,
        fill: impl FnOnce(&mut [u8]) -> AirHeader,
    ) -> Result<(), AirRingError> {
        let s = self.claim()?;
        let slot = self.ring.slot(s);
        let cap = slot.capacity.load(Ordering::Relaxed) as usize;
        if self.data[s as usize].is_none() || cap < len {
            let generation = slot.generation.load(Ordering::Relaxed);
            let bytes = len.max(MIN_SLOT_BYTES).next_power_of_two();
            let m = map(&data_name(&self.prefix, s, generation + 1), Some(bytes))?;
            if generation > 0 {
                unlink(&data_name(&self.prefix, s, generation));
            }
            self.data[s as usize] = Some(m);
            slot.capacity.store(bytes as u64, Ordering::Relaxed);
            slot.generation.store(generation + 1, Ordering::Relaxed);
        }
        let m = self.data[s as usize].as_ref().expect("mapped");
        // SAFETY: the slot is WRITING and no cell holds it (`claim`): no reader reads it until
        // the READY store below; the mapping is at least `len` bytes.
        let out = unsafe { std::slice::from_raw_parts_mut(m.base, len) };
        let h = fill(out);
        // SAFETY: as above, the header is written only while WRITING.
        unsafe { self.ring.header_ptr(s).write(h) };
        slot.tick.store(tick, Ordering::Relaxed);
        slot.state.store(READY, Ordering::Release);
        self.ring
            .control()
            .current
            .store(s as u64 + 1, Ordering::SeqCst);
        Ok(())
    }

    /// The lowest slot no cell holds, other than the published one, marked WRITING (W1, W2 of
    /// the module's argument). Lowest first, so a run touches as few slots (and files) as it
    /// can.
    fn claim(&mut self) -> Result<u32, AirRingError> {
        let current = self.ring.control().current.load(Ordering::Relaxed);
        let n = self.ring.slots;
        // A first look (any ordering will do: it only picks the candidates).
        self.held.iter_mut().for_each(|h| *h = false);
        for c in self.ring.all_cells() {
            let v = c.load(Ordering::Relaxed);
            if v > 0 && v <= n {
                self.held[v as usize - 1] = true;
            }
        }
        for s in 0..n {
            if s as u64 + 1 == current || self.held[s as usize] {
                continue;
            }
            let st = &self.ring.slot(s).state;
            let before = st.load(Ordering::Relaxed);
            st.store(WRITING, Ordering::SeqCst); // W1
            let taken = self
                .ring
                .all_cells()
                .iter()
                .any(|c| c.load(Ordering::SeqCst) == s + 1); // W2
            if !taken {
                return Ok(s);
            }
            // A late reader took it after the first look: leave it to that reader.
            st.store(before, Ordering::SeqCst);
        }
        Err(AirRingError::Full { slots: n })
    }

    /// Clears every hold of `robot` (its agent is dead, or a new one takes the robot over):
    /// whatever the agent held, the world may reuse. Idempotent and cheap (one store a cell).
    pub fn release_robot(&self, robot: u32) {
        if robot < self.ring.robots {
            for c in self.ring.cells_of(robot) {
                c.store(0, Ordering::SeqCst);
            }
        }
    }

    /// The holds in the cells now (for the tests and the e2e checks).
    pub fn holds(&self) -> usize {
        self.ring
            .all_cells()
            .iter()
            .filter(|c| c.load(Ordering::SeqCst) != 0)
            .count()
    }

    /// Slots that have a data file (for the tests and the memory bench).
    pub fn files(&self) -> usize {
        self.data.iter().filter(|d| d.is_some()).count()
    }

    /// The ring's number of slots.
    pub fn slots(&self) -> u32 {
        self.ring.slots
    }
}

impl Drop for AirWriter {
    fn drop(&mut self) {
        for s in 0..self.ring.slots {
            let g = self.ring.slot(s).generation.load(Ordering::Relaxed);
            if g > 0 {
                unlink(&data_name(&self.prefix, s, g));
            }
        }
        unlink(&control_name(&self.prefix));
    }
}

/// A robot's agent's side: reads the published air in place, holding it in one of the
/// robot's cells.
pub struct AirReader {
    prefix: String,
    robot: u32,
    ring: Arc<Ring>,
    /// Each slot's data mapping with its generation, mapped on first use.
    data: Vec<Option<(u32, Arc<Mapping>)>>,
}

impl AirReader {
    pub fn open(prefix: &str, robot: u32) -> Result<AirReader, AirRingError> {
        Self::open_named(prefix, AIR_RING, robot)
    }

    /// [`AirReader::open`] for the ring named `kind` ([`AirWriter::create_named`]).
    pub fn open_named(prefix: &str, kind: &str, robot: u32) -> Result<AirReader, AirRingError> {
        let prefix = format!("{prefix}{kind}");
        let prefix = prefix.as_str();
        let name = control_name(prefix);
        let control = map(&name, None)?;
        if control.len < std::mem::size_of::<Control>() {
            return Err(AirRingError::Invalid { name });
        }
        // SAFETY: at least a Control is mapped.
        let c = unsafe { &*(control.base as *const Control) };
        if c.magic.load(Ordering::Acquire) != MAGIC {
            return Err(AirRingError::Invalid { name });
        }
        let (slots, robots, cells) = (c.slots, c.robots, c.cells);
        if control.len < Ring::bytes_for(slots, robots, cells) {
            return Err(AirRingError::Invalid { name });
        }
        if robot >= robots {
            return Err(AirRingError::NoRobot { robot, robots });
        }
        Ok(AirReader {
            prefix: prefix.to_string(),
            robot,
            ring: Arc::new(Ring {
                control,
                slots,
                robots,
                cells,
            }),
            data: (0..slots).map(|_| None).collect(),
        })
    }

    /// The air published last (None: nothing published yet). The caller compares its tick
    /// with the one it wants. A hold on its slot lasts while the [`AirRead`] (or a clone, a
    /// zero-copy view's) lives.
    pub fn read(&mut self) -> Result<Option<AirRead>, AirRingError> {
        let cells = self.ring.cells_of(self.robot);
        for _ in 0..READ_RETRIES {
            let cur = self.ring.control().current.load(Ordering::SeqCst);
            if cur == 0 || cur > self.ring.slots as u64 {
                return Ok(None);
            }
            let s = (cur - 1) as u32;
            // R1: a free cell of ours takes the hold.
            let Some(cell) = cells.iter().position(|c| {
                c.compare_exchange(0, s + 1, Ordering::SeqCst, Ordering::Relaxed)
                    .is_ok()
            }) else {
                return Err(AirRingError::NoCell {
                    robot: self.robot,
                    cells: self.ring.cells,
                });
            };
            let hold = Hold {
                ring: self.ring.clone(),
                cell: self.robot as usize * self.ring.cells as usize + cell,
            };
            let slot = self.ring.slot(s);
            // R2
            if slot.state.load(Ordering::SeqCst) != READY {
                drop(hold);
                std::hint::spin_loop();
                continue;
            }
            let generation = slot.generation.load(Ordering::Relaxed);
            let fresh = !matches!(&self.data[s as usize], Some((g, _)) if *g == generation);
            if fresh {
                let m = map(&data_name(&self.prefix, s, generation), None)?;
                self.data[s as usize] = Some((generation, Arc::new(m)));
            }
            let (_, m) = self.data[s as usize].as_ref().expect("mapped");
            // SAFETY: written before the READY store our SeqCst load saw; not rewritten while
            // our cell holds the slot (the module's argument).
            let header = unsafe { self.ring.header_ptr(s).read() };
            return Ok(Some(AirRead {
                header,
                tick: slot.tick.load(Ordering::Relaxed),
                mapping: m.clone(),
                _hold: Arc::new(hold),
            }));
        }
        Ok(None)
    }
}

/// A reader's hold on a slot (one of its robot's cells): the world does not rewrite the slot
/// while it exists. Dropping it empties the cell, on whatever thread.
struct Hold {
    ring: Arc<Ring>,
    cell: usize,
}

impl Drop for Hold {
    fn drop(&mut self) {
        self.ring.all_cells()[self.cell].store(0, Ordering::SeqCst);
    }
}

/// One air, read in place: its header and bytes, valid while it (or a clone) lives.
#[derive(Clone)]
pub struct AirRead {
    pub header: AirHeader,
    /// The tick the world published it for (the header's `tick`, as the slot records it).
    pub tick: u64,
    mapping: Arc<Mapping>,
    _hold: Arc<Hold>,
}

impl AirRead {
    /// The air's bytes (the data file's whole mapping; the header says how much is used).
    pub fn bytes(&self) -> &[u8] {
        // SAFETY: the mapping lives as long as self, and the slot is not rewritten while held.
        unsafe { std::slice::from_raw_parts(self.mapping.base, self.mapping.len) }
    }
}

impl crate::blob::AsBytes for AirRead {
    fn as_bytes(&self) -> &[u8] {
        self.bytes()
    }
}

pub mod acts;
pub mod sense;

#[cfg(test)]
mod tests;
