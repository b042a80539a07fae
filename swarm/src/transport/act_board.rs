//! The Action frames as one iceoryx2 **blackboard** a robot (`runtime.acts = "blackboard"`,
//! `robot/<i>/board`): the world creates it and holds its one reader, the robot's agent its
//! one writer. A blackboard entry is iceoryx2's `UnrestrictedAtomic`: the writer updates a
//! value, the reader copies the newest complete one out; no loan, no queue, no returned
//! chunks (BENCHMARKS 22b: 518 instructions a robot-tick against 2,093 for a pub-sub act).
//!
//! The board's keys (`docs/protocol.md` section 5b):
//! - [`ATTACH_KEY`]: `u64`, the attach number of the agent that writes the board (0: none
//!   yet). The world counts the robot attached when it reads a new one here.
//! - [`head_key`]`(p)`, p = tick mod 2: an [`ActHead`], the Action of tick t and the first
//!   [`HEAD_AREA`] bytes of its message area. Two slots, so that in real-time mode a late
//!   action of tick k - 1 is still there when tick k's is written.
//! - [`chunk_key`]`(p, c)`: an [`ActChunk`], bytes `HEAD_AREA + c * CHUNK_AREA ..` of slot
//!   p's message area, stamped with its tick; only scenarios whose act area
//!   ([`super::act_slice_len`]) exceeds [`HEAD_AREA`] have chunks. The agent writes a tick's
//!   chunks before its head; the world takes a chunk only when its tick is the head's (a
//!   torn area is cut there, and its messages then fail to parse: malformed, as any bad area).
//!
//! A writer's entries stay taken after its agent dies (iceoryx2 0.10 releases them only when
//! the writer drops them), so a replacement cannot write the dead agent's board: when a robot
//! dies the world drops its side of the board ([`BoardSource::retire`]) and makes it anew
//! once iceoryx2 has removed the old one (the dead agent's node cleaned by the orchestrator);
//! the replacement's [`BoardSink::open`] retries until it finds a board it can write.

use super::act_sink::transmit_area;
use super::{act_slice_len, ServiceId, TransportError, TransportResult};
use crate::frames::Action;
use crate::mailbox::Air;
use crate::scenario::Scenario;
use iceoryx2::port::reader::EntryHandle;
use iceoryx2::port::writer::EntryHandleMut;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::blackboard::PortFactory;
use std::time::{Duration, Instant};

/// Bytes of the message area kept in the act head itself: the whole area of most scenarios
/// (roam's 4 messages of 256 bytes need 1,184), so one entry read a robot a tick.
pub const HEAD_AREA: usize = 2048;
/// Bytes of the message area per chunk beyond the head (a chunk value is one 4 KiB page
/// with its tick stamp).
pub const CHUNK_AREA: usize = 4096 - 8;
/// The key of the attach number.
pub const ATTACH_KEY: u32 = 0;
/// A head value's tick before any action was written: never a tick of a run.
const NO_TICK: u64 = u64::MAX;
/// Nodes a board admits: the world, the agent, a dead agent not cleaned yet, and a tool
/// (`iox2 service details`).
const BOARD_NODES: usize = 4;
/// How long a replacement agent's [`BoardSink::open`] keeps trying before it gives up (the
/// world remakes a dead robot's board once the orchestrator's cleanup removed the old one:
/// well under a second at N = 50; the orchestrator's start-up timeout bounds the attach).
const OPEN_PATIENCE: Duration = Duration::from_secs(30);
/// Pause between two tries of [`BoardSink::open`] (lets the world remake the board).
const OPEN_RETRY: Duration = Duration::from_millis(2);

/// The key of tick slot `p`'s head (p = tick mod 2).
pub fn head_key(p: usize) -> u32 {
    1 + p as u32
}

/// The key of tick slot `p`'s chunk `c`.
pub fn chunk_key(p: usize, c: usize) -> u32 {
    3 + 2 * c as u32 + p as u32
}

/// The chunks a board of this scenario has per tick slot.
pub fn chunks(sc: &Scenario) -> usize {
    act_slice_len(sc)
        .saturating_sub(HEAD_AREA)
        .div_ceil(CHUNK_AREA)
}

/// A tick slot's head: the Action and the first [`HEAD_AREA`] bytes of its message area.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("swarm::ActHead")]
#[repr(C)]
pub struct ActHead {
    pub action: Action,
    pub area: [u8; HEAD_AREA],
}

/// More of a tick slot's message area, stamped with the tick it belongs to.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("swarm::ActChunk")]
#[repr(C)]
pub struct ActChunk {
    pub tick: u64,
    pub bytes: [u8; CHUNK_AREA],
}

impl ActHead {
    fn empty() -> ActHead {
        ActHead {
            action: Action::idle(NO_TICK, 0),
            area: [0; HEAD_AREA],
        }
    }
}

type Board = PortFactory<ipc::Service, u32>;

/// Makes robot `robot`'s board (the world).
fn create_board(node: &Node<ipc::Service>, sc: &Scenario, robot: u32) -> TransportResult<Board> {
    let id = ServiceId::Board(robot);
    let name = super::service_name(&id)?;
    let head = ActHead::empty();
    let chunk = ActChunk {
        tick: NO_TICK,
        bytes: [0; CHUNK_AREA],
    };
    let mut b = node
        .service_builder(&name)
        .blackboard_creator::<u32>()
        .max_readers(1)
        .max_nodes(BOARD_NODES)
        .add::<u64>(ATTACH_KEY, 0)
        .add::<ActHead>(head_key(0), head)
        .add::<ActHead>(head_key(1), head);
    for c in 0..chunks(sc) {
        for p in 0..2 {
            b = b.add::<ActChunk>(chunk_key(p, c), chunk);
        }
    }
    b.create().map_err(|source| TransportError::CreateBoard {
        service: id,
        source,
    })
}

/// The world's side of one robot's board.
struct BoardReader {
    attach: EntryHandle<ipc::Service, u32, u64>,
    heads: [EntryHandle<ipc::Service, u32, ActHead>; 2],
    chunks: [Vec<EntryHandle<ipc::Service, u32, ActChunk>>; 2],
    _reader: iceoryx2::port::reader::Reader<ipc::Service, u32>,
    _board: Board,
}

impl BoardReader {
    fn create(node: &Node<ipc::Service>, sc: &Scenario, robot: u32) -> TransportResult<Self> {
        let board = create_board(node, sc, robot)?;
        let id = || ServiceId::Board(robot);
        let reader = board
            .reader_builder()
            .create()
            .map_err(|source| TransportError::Reader {
                service: id(),
                source,
            })?;
        let entry_err = |source| TransportError::Entry {
            service: id(),
            source,
        };
        let head = |p| reader.entry::<ActHead>(&head_key(p)).map_err(entry_err);
        let chunk_list = |p| {
            (0..chunks(sc))
                .map(|c| {
                    reader
                        .entry::<ActChunk>(&chunk_key(p, c))
                        .map_err(entry_err)
                })
                .collect::<TransportResult<Vec<_>>>()
        };
        Ok(BoardReader {
            attach: reader.entry::<u64>(&ATTACH_KEY).map_err(entry_err)?,
            heads: [head(0)?, head(1)?],
            chunks: [chunk_list(0)?, chunk_list(1)?],
            _reader: reader,
            _board: board,
        })
    }
}

/// The world's side of the Action frames over blackboards: every robot's board, the newest
/// action each robot wrote (held until the tick is applied), its newest late one (real-time
/// mode), and the newest attach number each board showed. The same calls as the pub-sub
/// source (`super::ActSource` dispatches to either).
pub struct BoardSource {
    /// Per robot of the run: its board (None while retired, or not this source's robot).
    boards: Vec<Option<BoardReader>>,
    /// Per robot: whether this source reads its board (a host proxy reads its own robots').
    mine: Vec<bool>,
    held: Vec<Option<Box<ActHead>>>,
    late: Vec<Option<Box<ActHead>>>,
    /// Per robot: the newest tick whose action was taken (never taken again as late).
    taken: Vec<Option<u64>>,
    attached: Vec<u64>,
    /// The message area of the action being taken (head part and chunks, joined).
    area: Vec<u8>,
    /// The run's scenario, to make a retired board anew.
    sc: Scenario,
}

impl BoardSource {
    /// Makes the boards of `robots` of the run (`sc.run.robots` in all).
    pub fn create(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        robots: &[u32],
    ) -> TransportResult<Self> {
        let n = sc.run.robots as usize;
        let mut boards: Vec<Option<BoardReader>> = (0..n).map(|_| None).collect();
        let mut mine = vec![false; n];
        for &i in robots {
            if let Some(b) = boards.get_mut(i as usize) {
                *b = Some(BoardReader::create(node, sc, i)?);
                mine[i as usize] = true;
            }
        }
        let none = |_| None;
        Ok(BoardSource {
            boards,
            mine,
            held: (0..n).map(none).collect(),
            late: (0..n).map(none).collect(),
            taken: vec![None; n],
            attached: vec![0; n],
            area: Vec::with_capacity(act_slice_len(sc)),
            sc: sc.clone(),
        })
    }

    /// Reads slot `p`'s head of robot `r`'s board.
    fn head(&self, r: usize, p: usize) -> Option<ActHead> {
        let b = self.boards.get(r)?.as_ref()?;
        Some(*b.heads[p].get())
    }

    /// The highest attach number robot `robot`'s board showed (0: no agent attached through
    /// it yet). A retired board is remade here first (through the world's `node`), once
    /// iceoryx2 removed the old one.
    pub fn attached(&mut self, node: &Node<ipc::Service>, robot: u32) -> u64 {
        let r = robot as usize;
        if !self.mine.get(r).copied().unwrap_or(false) {
            return 0;
        }
        if self.boards[r].is_none() {
            match BoardReader::create(node, &self.sc, robot) {
                Ok(b) => self.boards[r] = Some(b),
                Err(_) => return self.attached[r],
            }
        }
        if let Some(b) = &self.boards[r] {
            self.attached[r] = self.attached[r].max(*b.attach.get());
        }
        self.attached[r]
    }

    /// Robot `robot` died: the world lets go of its board (its agent's entries stay taken
    /// until iceoryx2 removes the board), to make it anew in [`BoardSource::attached`].
    pub fn retire(&mut self, robot: u32) {
        let r = robot as usize;
        if let Some(b) = self.boards.get_mut(r) {
            *b = None;
            self.held[r] = None;
            self.late[r] = None;
            self.taken[r] = None;
        }
    }

    /// Lock-step: whether robot `robot`'s action of tick `k` has arrived (copied and held
    /// until [`BoardSource::take`]). One head read a robot a tick in the common case.
    pub fn arrived(&mut self, robot: u32, k: u64) -> bool {
        let r = robot as usize;
        if self.holds(robot, k) {
            return true;
        }
        match self.head(r, (k % 2) as usize) {
            // (An action once taken stays on the board: never taken twice.)
            Some(h) if h.action.tick == k && self.taken[r].is_none_or(|t| t < k) => {
                self.held[r] = Some(Box::new(h));
                true
            }
            _ => false,
        }
    }

    /// Whether robot `robot`'s action of tick `k` is held.
    pub fn holds(&self, robot: u32, k: u64) -> bool {
        self.held
            .get(robot as usize)
            .is_some_and(|h| h.as_ref().is_some_and(|h| h.action.tick == k))
    }

    /// Joins head `h`'s message area (its used part, with the chunks of its tick slot) into
    /// `self.area`; a chunk of another tick (a torn write) ends it there.
    fn join_area(&mut self, r: usize, h: &ActHead) {
        self.area.clear();
        let used = h.action.radio_bytes as usize;
        self.area.extend_from_slice(&h.area[..used.min(HEAD_AREA)]);
        let Some(b) = self.boards.get(r).and_then(Option::as_ref) else {
            return;
        };
        let p = (h.action.tick % 2) as usize;
        let mut left = used.saturating_sub(HEAD_AREA);
        for entry in &b.chunks[p] {
            if left == 0 {
                break;
            }
            let c = entry.get();
            if c.tick != h.action.tick {
                break;
            }
            let n = left.min(CHUNK_AREA);
            self.area.extend_from_slice(&c.bytes[..n]);
            left -= n;
        }
    }

    /// Hands head `h`'s messages to `sent` stamped with `robot`, and its Action (its robot
    /// stamped from the board).
    fn deliver(&mut self, robot: u32, h: &ActHead, sent: &mut Air) -> Action {
        let r = robot as usize;
        self.join_area(r, h);
        transmit_area(robot, &self.area, sent);
        self.taken[r] = self.taken[r].max(Some(h.action.tick));
        Action { robot, ..h.action }
    }

    /// Lock-step: robot `robot`'s newest action (see the pub-sub source's `take`).
    pub fn take(&mut self, robot: u32, k: u64, sent: &mut Air) -> Option<Action> {
        self.arrived(robot, k);
        let h = self.held.get_mut(robot as usize)?.take()?;
        Some(self.deliver(robot, &h, sent))
    }

    /// Lock-step, for a host proxy: robot `robot`'s action of tick `k` if it arrived, with
    /// its used message area (head part and chunks joined, cut at a torn chunk).
    pub fn take_area(&mut self, robot: u32, k: u64) -> Option<(Action, Vec<u8>)> {
        if !self.arrived(robot, k) {
            return None;
        }
        let r = robot as usize;
        let h = self.held.get_mut(r)?.take()?;
        self.join_area(r, &h);
        self.taken[r] = self.taken[r].max(Some(k));
        Some((Action { robot, ..h.action }, self.area.clone()))
    }

    /// Real-time mode: reads robot `robot`'s two heads, keeping its action of tick `k` and
    /// its newest late one (of a tick from `since` to k - 1, not taken before). True if an
    /// action not seen before was kept: the robot made progress.
    pub fn poll_realtime(&mut self, robot: u32, k: u64, since: u64) -> bool {
        let r = robot as usize;
        let mut progress = false;
        for p in 0..2 {
            let Some(h) = self.head(r, p) else {
                return false;
            };
            let t = h.action.tick;
            if t == NO_TICK || self.taken[r].is_some_and(|done| t <= done) {
                continue;
            }
            if t == k {
                if !self.holds(robot, k) {
                    self.held[r] = Some(Box::new(h));
                    progress = true;
                }
            } else if t < k && t >= since {
                let newer = self.late[r].as_ref().is_none_or(|l| l.action.tick < t);
                if newer {
                    self.late[r] = Some(Box::new(h));
                    progress = true;
                }
            }
        }
        progress
    }

    /// Real-time mode: robot `robot`'s actions at tick `k`'s deadline (see the pub-sub
    /// source's `take_realtime`).
    pub fn take_realtime(
        &mut self,
        robot: u32,
        k: u64,
        since: u64,
        sent: &mut Air,
    ) -> (Option<Action>, Option<Action>) {
        let r = robot as usize;
        if r >= self.boards.len() {
            return (None, None);
        }
        self.poll_realtime(robot, k, since);
        let cur = self.held[r].take().filter(|h| h.action.tick == k);
        let late = self.late[r]
            .take()
            .filter(|h| h.action.tick < k && h.action.tick >= since);
        let cur = cur.map(|h| self.deliver(robot, &h, sent));
        let late = late.map(|h| self.deliver(robot, &h, sent));
        (cur, late)
    }

    /// Robot `robot` is dead: nothing its agent wrote is taken later (the board itself is
    /// retired once, when the robot dies: [`BoardSource::retire`]).
    pub fn discard(&mut self, robot: u32) {
        let r = robot as usize;
        if r < self.held.len() {
            self.held[r] = None;
            self.late[r] = None;
        }
    }
}

/// An agent's side of its Action frames over its robot's board: the writer's entries, and a
/// buffer of the whole message area (a tick's messages are written there, then into the
/// head and chunks of the tick's slot).
pub struct BoardSink {
    attach: EntryHandleMut<ipc::Service, u32, u64>,
    heads: [EntryHandleMut<ipc::Service, u32, ActHead>; 2],
    chunks: [Vec<EntryHandleMut<ipc::Service, u32, ActChunk>>; 2],
    area: Vec<u8>,
    head: Box<ActHead>,
    _writer: iceoryx2::port::writer::Writer<ipc::Service, u32>,
    _board: Board,
}

impl BoardSink {
    /// One try at robot `robot`'s board: open it, make its writer, take every entry.
    pub fn try_open(node: &Node<ipc::Service>, sc: &Scenario, robot: u32) -> TransportResult<Self> {
        let id = || ServiceId::Board(robot);
        let name = super::service_name(&id())?;
        let board = node
            .service_builder(&name)
            .blackboard_opener::<u32>()
            .open()
            .map_err(|source| TransportError::OpenBoard {
                service: id(),
                source,
            })?;
        let writer = board
            .writer_builder()
            .create()
            .map_err(|source| TransportError::Writer {
                service: id(),
                source,
            })?;
        let entry_err = |source| TransportError::EntryMut {
            service: id(),
            source,
        };
        let head = |p| writer.entry::<ActHead>(&head_key(p)).map_err(entry_err);
        let chunk_list = |p| {
            (0..chunks(sc))
                .map(|c| {
                    writer
                        .entry::<ActChunk>(&chunk_key(p, c))
                        .map_err(entry_err)
                })
                .collect::<TransportResult<Vec<_>>>()
        };
        Ok(BoardSink {
            attach: writer.entry::<u64>(&ATTACH_KEY).map_err(entry_err)?,
            heads: [head(0)?, head(1)?],
            chunks: [chunk_list(0)?, chunk_list(1)?],
            area: vec![0; act_slice_len(sc)],
            head: Box::new(ActHead::empty()),
            _writer: writer,
            _board: board,
        })
    }

    /// Opens robot `robot`'s board for its agent. A replacement may find its dead
    /// predecessor's board, which it cannot write, until the world has made it anew: it tries
    /// again while `keep_trying()` says so (the world is alive and running), for up to
    /// [`OPEN_PATIENCE`].
    pub fn open(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        robot: u32,
        keep_trying: &dyn Fn() -> bool,
    ) -> TransportResult<Self> {
        let t = Instant::now();
        loop {
            match Self::try_open(node, sc, robot) {
                Ok(s) => return Ok(s),
                Err(e) if t.elapsed() > OPEN_PATIENCE || !keep_trying() => return Err(e),
                Err(_) => std::thread::sleep(OPEN_RETRY),
            }
        }
    }

    /// Writes this agent's attach number: the world counts the robot attached when it reads
    /// it.
    pub fn attach(&mut self, attach: u64) {
        self.attach.update_with_copy(attach);
    }

    /// Writes an action of tick t into slot t mod 2: `step` writes the tick's messages
    /// into the message area and returns the Action (its `radio_bytes` the bytes it wrote).
    /// The chunks first, the head last: the world reads a head, then the chunks of its tick.
    pub fn send(&mut self, step: impl FnOnce(&mut [u8]) -> Action) {
        let action = step(&mut self.area);
        let used = (action.radio_bytes as usize).min(self.area.len());
        let p = (action.tick % 2) as usize;
        let mut rest = &self.area[used.min(HEAD_AREA)..used];
        for entry in &self.chunks[p] {
            if rest.is_empty() {
                break;
            }
            let n = rest.len().min(CHUNK_AREA);
            let mut c = ActChunk {
                tick: action.tick,
                bytes: [0; CHUNK_AREA],
            };
            c.bytes[..n].copy_from_slice(&rest[..n]);
            entry.update_with_copy(c);
            rest = &rest[n..];
        }
        self.head.action = action;
        let head_part = used.min(HEAD_AREA);
        self.head.area[..head_part].copy_from_slice(&self.area[..head_part]);
        self.heads[p].update_with_copy(*self.head);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::air::ActTx;
    use crate::frames::RadioHeader;
    use crate::wire::RadioTx;

    /// A head whose chunks are of another tick (a write torn between them, or a writer that
    /// wrote a head alone): the area is cut at the first such chunk, and a message cut short
    /// sends nothing.
    #[test]
    fn a_torn_area_sends_no_message_of_it() {
        super::super::quiet_logs();
        let prefix = format!("swat{}_", std::process::id());
        let mut sc = Scenario::roam();
        sc.run.robots = 1;
        sc.radio.max_messages_per_tick = 3;
        sc.radio.max_message_bytes = 3000;
        let config = super::super::run_config(&prefix).unwrap();
        {
            let world = super::super::node(&config, "world").unwrap();
            let agent = super::super::node(&config, "agent-0").unwrap();
            let mut src = BoardSource::create(&world, &sc, &[0]).unwrap();
            let mut sink = BoardSink::open(&agent, &sc, 0, &|| true).unwrap();
            let step = |tick| {
                move |area: &mut [u8]| {
                    let mut tx = ActTx::new(area);
                    for m in 0..3 {
                        let h = RadioHeader {
                            len: 3000,
                            seq: m,
                            ..RadioHeader::default()
                        };
                        tx.transmit(&h, &mut |b| b.fill(1));
                    }
                    Action {
                        n_sent: 3,
                        radio_bytes: tx.used as u32,
                        ..Action::idle(tick, 0)
                    }
                }
            };
            sink.send(step(2));
            let mut sent = Air::default();
            assert!(src.take(0, 2, &mut sent).is_some());
            assert_eq!(sent.len(), 3);
            sent.clear();
            // Tick 4 (slot 0 again): its head alone; the chunks still say tick 2.
            sink.head.action = Action {
                n_sent: 3,
                radio_bytes: 3 * (40 + 3000),
                ..Action::idle(4, 0)
            };
            sink.heads[0].update_with_copy(*sink.head);
            assert!(src.take(0, 4, &mut sent).is_some());
            assert!(sent.is_empty());
            // Written whole, it goes out whole.
            sink.send(step(6));
            assert!(src.take(0, 6, &mut sent).is_some());
            assert_eq!(sent.len(), 3);
        }
        crate::cleanup::remove_run(&prefix);
    }
}
