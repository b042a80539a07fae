//! The behaviour API and the agent-side runtime that sits between a behaviour and the radio.
//!
//! A behaviour is a pure state machine: `step_refs(sense, inbox, outbox) -> command`. It can
//! only `broadcast` or `send(to)`; range, loss, delay, ordering and counting happen below it:
//! the world's medium decides every (message, receiver) pair and holds the delay
//! (`world::medium`), and [`AgentRuntime`], which both executors use, hands the behaviour the
//! messages the medium delivered at this tick (the multi-process agent decodes them from the
//! tick's air sample, the in-process executor's [`crate::mailbox::Mailbox`] once for all
//! receivers) and encodes what it sends behind its Action.

use crate::frames::{Action, RadioHeader, Sense, BROADCAST, MAX_SENT};
use crate::scenario::Scenario;
use crate::wire::bincode_config;
#[cfg(test)]
pub(crate) use crate::wire::encode;
pub use crate::wire::{decode, decode_in, RadioTx, Received};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// A robot's behaviour.
pub trait Behaviour {
    /// What the robot says on the radio (encoded with bincode into shared memory).
    type Msg: Serialize + DeserializeOwned;
    /// Zero-copy receive: decode delivered messages where they arrived, so that their
    /// [`crate::Blob`] fields are views into the iceoryx2 sample (multi-process) or the tick's
    /// radio bytes (in-process) instead of copies. Costs one reference-counted owner per
    /// delivered message; worth it for large byte payloads. Results are the same either way.
    /// Asked once, when the runtime is built.
    fn zero_copy(&self) -> bool {
        false
    }
    /// One tick: read the Sense frame and the inbox (messages sent at k - 1 - delay that the
    /// radio delivered, ordered by sender and sequence), queue messages, return a command.
    /// The inbox refers to the messages: in-process, all receivers of a message share one
    /// decoded copy (see `mailbox`).
    fn step_refs(
        &mut self,
        sense: &Sense,
        inbox: &[&Received<Self::Msg>],
        out: &mut Outbox<Self::Msg>,
    ) -> Command;

    /// [`Behaviour::step_refs`] over an inbox of owned messages (unit tests).
    fn step(
        &mut self,
        sense: &Sense,
        inbox: &[Received<Self::Msg>],
        out: &mut Outbox<Self::Msg>,
    ) -> Command {
        let refs: Vec<&Received<Self::Msg>> = inbox.iter().collect();
        self.step_refs(sense, &refs, out)
    }
}

/// What a behaviour commands for this tick.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Command {
    /// The motion command, read by the world as the scenario's `robot.kinematics` says: a
    /// velocity (vx, vy) for holonomic robots, (v, w) (speed, turn rate) for unicycles.
    pub cmd: [f64; 2],
    pub events: u32,
    /// What the robot reports to the mission (Action `report`).
    pub report: [f64; 4],
}

/// Messages queued by a behaviour in one tick.
pub struct Outbox<M> {
    msgs: Vec<(u32, M)>,
    limit: usize,
    refused: u32,
}

impl<M> Outbox<M> {
    fn new(limit: usize) -> Self {
        Self::reusing(Vec::new(), limit)
    }
    /// An empty outbox that fills `buf` (cleared), to keep its allocation from tick to tick.
    fn reusing(mut buf: Vec<(u32, M)>, limit: usize) -> Self {
        buf.clear();
        Outbox {
            msgs: buf,
            limit: limit.min(MAX_SENT),
            refused: 0,
        }
    }
    /// An outbox outside a runtime, for behaviour unit tests.
    pub fn new_for_tests(limit: usize) -> Self {
        Self::new(limit)
    }
    /// The messages queued so far: (destination, message), `frames::BROADCAST` for all.
    pub fn queued(&self) -> &[(u32, M)] {
        &self.msgs
    }
    /// Queues a message for every robot in range. Returns false if the per-tick limit is hit.
    pub fn broadcast(&mut self, msg: M) -> bool {
        self.push(BROADCAST, msg)
    }
    /// Queues a message for one robot (still subject to range and loss).
    pub fn send(&mut self, to: u32, msg: M) -> bool {
        self.push(to, msg)
    }
    fn push(&mut self, to: u32, msg: M) -> bool {
        if self.msgs.len() >= self.limit {
            self.refused += 1;
            return false;
        }
        self.msgs.push((to, msg));
        true
    }
}

/// Counters the runtime keeps beyond those reported per tick in the Action frame.
#[derive(Debug, Default, Clone, Copy)]
pub struct RuntimeStats {
    pub refused_sends: u64,
    pub oversize_sends: u64,
}

/// Everything between one behaviour and the transport, for one robot: no links and no
/// pending queue (the world's medium decides delivery and holds the delay).
pub struct AgentRuntime<B: Behaviour> {
    pub robot: u32,
    behaviour: B,
    radio: crate::scenario::RadioParams,
    seq: u32,
    /// The behaviour's outbox (kept to reuse its allocation).
    out: Vec<(u32, B::Msg)>,
    pub stats: RuntimeStats,
    /// The behaviour's `zero_copy()`.
    zero_copy: bool,
    /// The allocation of [`AgentRuntime::step_owned`]'s list of references.
    refs: RefBuf<Received<B::Msg>>,
}

/// An empty `Vec<&T>`'s allocation kept between calls whose references have different
/// lifetimes (each tick's inbox is a new borrow). Only empty vectors go in and come out, so no
/// reference outlives its borrow.
struct RefBuf<T> {
    ptr: *mut *const T,
    cap: usize,
}

impl<T> Default for RefBuf<T> {
    fn default() -> Self {
        RefBuf {
            ptr: std::ptr::null_mut(),
            cap: 0,
        }
    }
}

impl<T> RefBuf<T> {
    /// The kept allocation as an empty vector of references of any lifetime.
    fn take<'a>(&mut self) -> Vec<&'a T> {
        if self.cap == 0 {
            return Vec::new();
        }
        let (ptr, cap) = (
            std::mem::replace(&mut self.ptr, std::ptr::null_mut()),
            self.cap,
        );
        self.cap = 0;
        // SAFETY: `ptr` and `cap` came from a `Vec<&T>` (`keep`), whose element type has the
        // layout of `*const T` whatever its lifetime; the length is 0, so no reference is
        // carried over.
        unsafe { Vec::from_raw_parts(ptr as *mut &'a T, 0, cap) }
    }

    /// Keeps `v`'s allocation (its references are dropped).
    fn keep(&mut self, mut v: Vec<&T>) {
        v.clear();
        let mut v = std::mem::ManuallyDrop::new(v);
        self.free();
        self.cap = v.capacity();
        self.ptr = v.as_mut_ptr() as *mut *const T;
    }

    fn free(&mut self) {
        drop(self.take());
    }
}

impl<T> Drop for RefBuf<T> {
    fn drop(&mut self) {
        self.free();
    }
}

// SAFETY: a RefBuf holds no T, only an empty allocation.
unsafe impl<T> Send for RefBuf<T> {}
unsafe impl<T> Sync for RefBuf<T> {}

impl<B: Behaviour> AgentRuntime<B> {
    pub fn new(sc: &Scenario, robot: u32, behaviour: B) -> Self {
        AgentRuntime {
            robot,
            radio: sc.radio.clone(),
            seq: 0,
            out: Vec::new(),
            stats: RuntimeStats::default(),
            zero_copy: behaviour.zero_copy(),
            behaviour,
            refs: RefBuf::default(),
        }
    }

    /// Whether delivered messages are received in place ([`Behaviour::zero_copy`]).
    pub fn zero_copy(&self) -> bool {
        self.zero_copy
    }

    pub fn behaviour(&self) -> &B {
        &self.behaviour
    }

    /// Tick k: hands the behaviour Sense_k and the messages the medium delivered at k
    /// (`inbox`, in (sender, seq) order; `malformed` more could not be decoded), steps it,
    /// transmits its messages through `tx` and returns the Action frame.
    pub fn step(
        &mut self,
        sense: &Sense,
        inbox: &[&Received<B::Msg>],
        malformed: u32,
        tx: &mut dyn RadioTx,
    ) -> Action {
        let k = sense.tick;
        let mut action = Action::idle(k, self.robot);
        action.radio_delivered = inbox.len() as u32;
        action.radio_malformed = malformed;
        let mut out = Outbox::reusing(
            std::mem::take(&mut self.out),
            self.radio.max_messages_per_tick as usize,
        );
        let cmd = self.behaviour.step_refs(sense, inbox, &mut out);
        self.stats.refused_sends += out.refused as u64;
        action.cmd = cmd.cmd;
        action.report = cmd.report;
        action.events = cmd.events;
        for (dest, msg) in out.msgs.iter() {
            let mut size = bincode::enc::write::SizeWriter::default();
            if bincode::serde::encode_into_writer(msg, &mut size, bincode_config()).is_err()
                || size.bytes_written > self.radio.max_message_bytes as usize
            {
                self.stats.oversize_sends += 1;
                continue;
            }
            self.seq = self.seq.wrapping_add(1);
            let header = RadioHeader {
                sender: self.robot,
                dest: *dest,
                tick: k,
                seq: self.seq,
                len: size.bytes_written as u32,
                sender_pos: sense.pos,
            };
            tx.transmit(&header, &mut |buf: &mut [u8]| {
                bincode::serde::encode_into_slice(msg, buf, bincode_config()).expect("sized above");
            });
            action.sent_to[action.n_sent as usize] = *dest;
            action.n_sent += 1;
        }
        self.out = out.msgs;
        action
    }

    /// [`AgentRuntime::step`] with owned inbox messages (the multi-process agent, tests).
    pub fn step_owned(
        &mut self,
        sense: &Sense,
        inbox: &[Received<B::Msg>],
        malformed: u32,
        tx: &mut dyn RadioTx,
    ) -> Action {
        // The list of references lives in the allocation kept from the last tick (no malloc
        // a tick once warm: the agent calls this every tick).
        let mut refs = self.refs.take();
        refs.extend(inbox.iter());
        let action = self.step(sense, &refs, malformed, tx);
        self.refs.keep(refs);
        action
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::Sense;

    /// Broadcasts its tick, then sends robot 9 a unicast; remembers what it heard.
    struct Echo {
        heard: Vec<(u32, u64)>,
    }
    impl Behaviour for Echo {
        type Msg = u64;
        fn step_refs(
            &mut self,
            s: &Sense,
            inbox: &[&Received<u64>],
            out: &mut Outbox<u64>,
        ) -> Command {
            self.heard.extend(inbox.iter().map(|r| (r.from, r.msg)));
            out.broadcast(s.tick);
            out.send(9, s.tick + 100);
            Command::default()
        }
    }

    struct Collect(Vec<(RadioHeader, Vec<u8>)>);
    impl RadioTx for Collect {
        fn transmit(&mut self, h: &RadioHeader, fill: &mut dyn FnMut(&mut [u8])) {
            let mut v = vec![0u8; h.len as usize];
            fill(&mut v);
            self.0.push((*h, v));
        }
    }

    fn sense(robot: u32, tick: u64, pos: [f64; 2]) -> Box<Sense> {
        let mut s = Sense::zeroed();
        s.robot = robot;
        s.tick = tick;
        s.pos = pos;
        s
    }

    #[test]
    fn a_step_sends_headed_messages_and_reports_its_inbox() {
        let sc = Scenario::default();
        let mut rt = AgentRuntime::new(&sc, 3, Echo { heard: vec![] });
        let mut tx = Collect(vec![]);
        let s = sense(3, 5, [1.0, 2.0]);
        let h = RadioHeader {
            sender: 1,
            tick: 4,
            ..Default::default()
        };
        let inbox = [Received::new(&h, 40u64)];
        let a = rt.step_owned(&s, &inbox, 2, &mut tx);
        assert_eq!(rt.behaviour().heard, vec![(1, 40)]);
        assert_eq!((a.radio_delivered, a.radio_malformed, a.n_sent), (1, 2, 2));
        assert_eq!(&a.sent_to[..2], &[BROADCAST, 9]);
        let (h0, p0) = &tx.0[0];
        assert_eq!(
            (h0.sender, h0.tick, h0.seq, h0.sender_pos),
            (3, 5, 1, [1.0, 2.0])
        );
        assert_eq!(decode::<u64>(h0, p0), Some(5));
        assert_eq!((tx.0[1].0.dest, tx.0[1].0.seq), (9, 2));
        assert_eq!(decode::<u64>(&tx.0[1].0, &tx.0[1].1), Some(105));
    }

    #[test]
    fn oversize_messages_are_not_sent() {
        let mut sc = Scenario::default();
        sc.radio.max_message_bytes = 0;
        let mut rt = AgentRuntime::new(&sc, 0, Echo { heard: vec![] });
        let mut tx = Collect(vec![]);
        let a = rt.step_owned(&sense(0, 1, [0.0; 2]), &[], 0, &mut tx);
        assert_eq!((a.n_sent, tx.0.len(), rt.stats.oversize_sends), (0, 0, 2));
    }

    #[test]
    fn step_owned_keeps_one_allocation_for_its_references_across_ticks() {
        let sc = Scenario::default();
        let mut rt = AgentRuntime::new(&sc, 3, Echo { heard: vec![] });
        let mut tx = Collect(vec![]);
        let h = RadioHeader {
            sender: 1,
            ..Default::default()
        };
        let mut kept = None;
        for tick in 0..4u64 {
            // A new inbox (a new borrow) every tick, as the agent's loop makes it.
            let inbox: Vec<Received<u64>> =
                (0..5).map(|m| Received::new(&h, tick * 10 + m)).collect();
            let a = rt.step_owned(&sense(3, tick, [0.0; 2]), &inbox, 0, &mut tx);
            assert_eq!(a.radio_delivered, 5);
            let v: Vec<&Received<u64>> = rt.refs.take();
            assert!(v.is_empty() && v.capacity() >= 5);
            let p = v.as_ptr() as usize;
            assert_eq!(*kept.get_or_insert(p), p, "tick {tick}: a new allocation");
            rt.refs.keep(v);
        }
        let heard: Vec<u64> = rt.behaviour().heard.iter().map(|x| x.1).collect();
        assert_eq!(heard.len(), 20);
        assert_eq!(&heard[15..], &[30, 31, 32, 33, 34]);
    }

    #[test]
    fn outbox_enforces_the_per_tick_limit() {
        let mut o: Outbox<u8> = Outbox::new(2);
        assert!(o.broadcast(1) && o.send(3, 2));
        assert!(!o.broadcast(3));
        assert_eq!(o.refused, 1);
    }
}
