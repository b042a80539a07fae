//! The behaviour API and the agent-side runtime that sits between a behaviour and the radio.
//!
//! A behaviour is a pure state machine: `step_refs(sense, inbox, outbox) -> command`. It can
//! only `broadcast` or `send(to)`; range, loss, delay, ordering and counting happen below it in
//! [`AgentRuntime`], which both executors use: the multi-process agent feeds it the messages
//! it takes off its links (`ingest`), the in-process executor its view of the shared
//! [`Mailbox`] (`ingest_mailbox`), with the same decisions.

use crate::blob::AsBytes;
use crate::frames::{Action, RadioHeader, Sense, BROADCAST, MAX_SENT};
use crate::link::LinkSet;
use crate::mailbox::Mailbox;
use crate::radio::{decide, Verdict};
use crate::scenario::Scenario;
use crate::wire::bincode_config;
#[cfg(test)]
pub(crate) use crate::wire::encode;
pub use crate::wire::{decode, decode_in, RadioTx, Received};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::VecDeque;
use std::sync::Arc;

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

// A decoded message is boxed: held inline it made every Pending as large as the behaviour's
// message, and the in-process executor (which holds only `Posted` indices) moved those ~7 %
// slower; unboxed, the multi-process radio gained ~3 % (bench throughput).
enum Outcome<M> {
    /// Decoded by this runtime (a message taken off a link).
    Delivered(Box<Received<M>>),
    /// The mailbox's message with this index (in-process).
    Posted(u64),
    Lost,
    Malformed,
}

struct Pending<M> {
    due: u64,
    from: u32,
    seq: u32,
    outcome: Outcome<M>,
}

/// Counters the runtime keeps beyond those reported per tick in the Action frame.
#[derive(Debug, Default, Clone, Copy)]
pub struct RuntimeStats {
    pub refused_sends: u64,
    pub oversize_sends: u64,
    pub stale_messages: u64,
    /// Messages left on a link while their sender was out of reach, dropped when it came back.
    pub skipped: u64,
}

/// Everything between one behaviour and the transport, for one robot.
pub struct AgentRuntime<B: Behaviour> {
    pub robot: u32,
    behaviour: B,
    seed: u64,
    radio: crate::scenario::RadioParams,
    links: LinkSet,
    seq: u32,
    /// Own position at recent ticks (for the range test of messages sent at those ticks).
    positions: VecDeque<(u64, [f64; 2])>,
    pending: Vec<Pending<B::Msg>>,
    /// The due messages of the current tick (kept to reuse its allocation).
    due: Vec<Pending<B::Msg>>,
    /// The behaviour's outbox (kept to reuse its allocation).
    out: Vec<(u32, B::Msg)>,
    pub stats: RuntimeStats,
    /// The behaviour's `zero_copy()`.
    zero_copy: bool,
}

impl<B: Behaviour> AgentRuntime<B> {
    pub fn new(sc: &Scenario, robot: u32, behaviour: B) -> Self {
        AgentRuntime {
            robot,
            seed: sc.run.seed,
            radio: sc.radio.clone(),
            links: LinkSet::new(
                sc.radio.max_links as usize,
                sc.radio.lingering_links as usize,
                sc.radio.link_linger_ticks as u64,
            ),
            seq: 0,
            positions: VecDeque::new(),
            pending: Vec::new(),
            due: Vec::new(),
            out: Vec::new(),
            stats: RuntimeStats::default(),
            zero_copy: behaviour.zero_copy(),
            behaviour,
        }
    }

    /// Whether delivered messages are received in place ([`Behaviour::zero_copy`]).
    pub fn zero_copy(&self) -> bool {
        self.zero_copy
    }

    pub fn behaviour(&self) -> &B {
        &self.behaviour
    }

    pub fn links(&self) -> &LinkSet {
        &self.links
    }

    /// Starts tick k: remembers the robot's own position from Sense_k.
    pub fn begin(&mut self, sense: &Sense) {
        if self.positions.back().map(|p| p.0) != Some(sense.tick) {
            self.positions.push_back((sense.tick, sense.pos));
        }
        while self.positions.len() > 2 {
            self.positions.pop_front();
        }
    }

    fn own_pos_at(&self, tick: u64) -> Option<[f64; 2]> {
        self.positions.iter().find(|p| p.0 == tick).map(|p| p.1)
    }

    /// Takes one raw message off a link (straight from shared memory): decides range and loss
    /// now, decodes only if delivered, and holds it until its due tick.
    pub fn ingest(&mut self, h: &RadioHeader, payload: &[u8]) {
        self.take(h, || decode(h, payload));
    }

    /// [`AgentRuntime::ingest`] for a message whose bytes `owner` holds (an iceoryx2 sample):
    /// a delivered message is decoded in place, its [`crate::Blob`] fields are views that keep
    /// `owner` alive; anything else drops `owner` at once.
    pub fn ingest_held<O: AsBytes + 'static>(&mut self, h: &RadioHeader, owner: O) {
        self.take(h, || {
            let owner: Arc<dyn AsBytes> = Arc::new(owner);
            decode_in(h, &owner, 0)
        });
    }

    /// The decisions of `ingest`; `decode` runs only for a delivered message.
    fn take(&mut self, h: &RadioHeader, decode: impl FnOnce() -> Option<B::Msg>) {
        if h.sender == self.robot || !self.links.accepts(h.sender, h.tick) {
            return;
        }
        if let Some(deliver) = self.judge(h, self.own_pos_at(h.tick)) {
            let outcome = if !deliver {
                Outcome::Lost
            } else {
                match decode() {
                    Some(msg) => Outcome::Delivered(Box::new(Received::new(h, msg))),
                    None => Outcome::Malformed,
                }
            };
            self.hold(h, outcome);
        }
    }

    /// In-process: takes the mailbox's latest messages that this robot's links carry, with the
    /// decisions `ingest` makes for each. Links are walked in robot-id order, so the messages
    /// are held in (sender, seq) order, as the multi-process agent takes them off its links.
    pub fn ingest_mailbox(&mut self, mailbox: &Mailbox<B::Msg>) {
        let Some(tick) = mailbox.latest_tick() else {
            return;
        };
        let own = self.own_pos_at(tick);
        for i in 0..self.links.len() {
            // Links whose robot was out of reach at `tick` carry nothing in range (the agent
            // process does not take those messages off its links either).
            let Some(sender) = self.links.reaching(i, tick) else {
                continue;
            };
            for (index, h, decoded) in mailbox.latest_from(sender) {
                if let Some(deliver) = self.judge(h, own) {
                    let outcome = match (deliver, decoded) {
                        (false, _) => Outcome::Lost,
                        (true, true) => Outcome::Posted(index),
                        (true, false) => Outcome::Malformed,
                    };
                    self.hold(h, outcome);
                }
            }
        }
    }

    /// For a message on one of this robot's links, given the robot's own position at the send
    /// tick: None if it is not for this robot or out of range (the world counts range drops
    /// from ground truth; the receiver ignores them), else whether the loss draw delivers it.
    #[inline]
    fn judge(&mut self, h: &RadioHeader, own: Option<[f64; 2]>) -> Option<bool> {
        if h.dest != BROADCAST && h.dest != self.robot {
            return None;
        }
        let Some(own) = own else {
            self.stats.stale_messages += 1;
            return None;
        };
        match decide(
            &self.radio,
            self.seed,
            h.tick,
            h.sender,
            h.sender_pos,
            self.robot,
            own,
            h.seq,
        ) {
            Verdict::OutOfRange => None,
            Verdict::Lost => Some(false),
            Verdict::Deliver => Some(true),
        }
    }

    /// Holds a message's outcome until its due tick.
    fn hold(&mut self, h: &RadioHeader, outcome: Outcome<B::Msg>) {
        self.pending.push(Pending {
            due: h.tick + 1 + self.radio.delay_ticks as u64,
            from: h.sender,
            seq: h.seq,
            outcome,
        });
    }

    /// Finishes tick k: delivers what is due, steps the behaviour, transmits its messages and
    /// returns the Action frame.
    pub fn step(&mut self, sense: &Sense, tx: &mut dyn RadioTx) -> Action {
        self.step_with(sense, None, tx)
    }

    /// `step` in-process: messages held by `ingest_mailbox` are read from the mailbox.
    pub fn step_mailbox(
        &mut self,
        sense: &Sense,
        mailbox: &Mailbox<B::Msg>,
        tx: &mut dyn RadioTx,
    ) -> Action {
        self.step_with(sense, Some(mailbox), tx)
    }

    fn step_with(
        &mut self,
        sense: &Sense,
        mailbox: Option<&Mailbox<B::Msg>>,
        tx: &mut dyn RadioTx,
    ) -> Action {
        let k = sense.tick;
        let mut action = Action::idle(k, self.robot);
        // Due messages in a fixed order: (sender, seq). Scheduling cannot change the inbox.
        // (sender, seq) is unique, so any sort gives the same order; messages usually arrive
        // in it already (links are walked by robot id), and then nothing moves.
        let mut due = std::mem::take(&mut self.due);
        if self.pending.iter().all(|p| p.due <= k) {
            std::mem::swap(&mut due, &mut self.pending);
        } else {
            let mut i = 0;
            while i < self.pending.len() {
                if self.pending[i].due <= k {
                    due.push(self.pending.swap_remove(i));
                } else {
                    i += 1;
                }
            }
        }
        if !due.is_sorted_by_key(|p| (p.from, p.seq)) {
            due.sort_unstable_by_key(|p| (p.from, p.seq));
        }
        let mut inbox: Vec<&Received<B::Msg>> = Vec::with_capacity(due.len());
        for p in &due {
            match &p.outcome {
                Outcome::Delivered(r) => inbox.push(r),
                Outcome::Posted(i) => match mailbox.and_then(|m| m.get(*i)) {
                    Some(r) => inbox.push(r),
                    // Only a runtime stepped again after missing ticks could hold a message
                    // the mailbox has forgotten; the in-process executor never does that.
                    None => {
                        self.stats.stale_messages += 1;
                        continue;
                    }
                },
                Outcome::Lost => action.radio_dropped_loss += 1,
                Outcome::Malformed => action.radio_malformed += 1,
            }
        }
        action.radio_delivered = inbox.len() as u32;
        let mut out = Outbox::reusing(
            std::mem::take(&mut self.out),
            self.radio.max_messages_per_tick as usize,
        );
        let cmd = self.behaviour.step_refs(sense, &inbox, &mut out);
        drop(inbox);
        due.clear();
        self.due = due;
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

    /// Applies Sense_k's neighbour list to the links: (added, removed).
    pub fn update_links(&mut self, sense: &Sense) -> (&[u32], &[u32]) {
        self.links
            .update(sense.tick, sense.neighbours(), self.robot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::Sense;

    /// Broadcasts its tick; remembers what it heard.
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

    /// Receiver 0's links to robots 1..=3, made while handling Sense_0.
    fn linked_receiver(sc: &Scenario) -> AgentRuntime<Echo> {
        let mut rx = AgentRuntime::new(sc, 0, Echo { heard: vec![] });
        let mut s = sense(0, 0, [0.0, 0.0]);
        s.neighbours[..3].copy_from_slice(&[1, 2, 3]);
        s.n_neighbours = 3;
        rx.begin(&s);
        rx.step(&s, &mut Collect(vec![]));
        rx.update_links(&s);
        rx
    }

    #[test]
    fn messages_arrive_next_tick_in_sender_order_and_out_of_range_is_ignored() {
        let sc = Scenario::default();
        let mut rx = linked_receiver(&sc);
        let mut tx = Collect(vec![]);
        let mut senders: Vec<_> = (1..4)
            .map(|i| AgentRuntime::new(&sc, i, Echo { heard: vec![] }))
            .collect();
        // Tick 1: robots 1..3 send; robot 3 is out of range.
        let s1 = sense(0, 1, [0.0, 0.0]);
        rx.begin(&s1);
        for (j, a) in senders.iter_mut().enumerate() {
            let x = if j == 2 { 500.0 } else { 10.0 * (j + 1) as f64 };
            let s = sense(a.robot, 1, [x, 0.0]);
            a.begin(&s);
            a.step(&s, &mut tx);
        }
        // Feed in reverse order: the inbox must still be sorted by sender.
        for (h, p) in tx.0.iter().rev() {
            rx.ingest(h, p);
        }
        let act1 = rx.step(&s1, &mut Collect(vec![]));
        assert_eq!(act1.radio_delivered, 0, "nothing is due at the send tick");
        let s2 = sense(0, 2, [0.0, 0.0]);
        rx.begin(&s2);
        let act2 = rx.step(&s2, &mut Collect(vec![]));
        assert_eq!(act2.radio_delivered, 2);
        assert_eq!(rx.behaviour().heard, vec![(1, 1), (2, 1)]);
    }

    #[test]
    fn messages_on_a_link_made_at_their_send_tick_or_no_link_are_not_received() {
        let sc = Scenario::default();
        let mut rx = linked_receiver(&sc);
        let s1 = sense(0, 1, [0.0, 0.0]);
        rx.begin(&s1);
        let mut tx = Collect(vec![]);
        for (robot, tick) in [(1, 0), (7, 1)] {
            let mut a = AgentRuntime::new(&sc, robot, Echo { heard: vec![] });
            let s = sense(robot, tick, [5.0, 0.0]);
            a.begin(&s);
            a.step(&s, &mut tx);
        }
        for (h, p) in &tx.0 {
            rx.ingest(h, p);
        }
        rx.step(&s1, &mut Collect(vec![]));
        let s2 = sense(0, 2, [0.0, 0.0]);
        rx.begin(&s2);
        assert_eq!(rx.step(&s2, &mut Collect(vec![])).radio_delivered, 0);
    }

    #[test]
    fn garbage_payload_is_counted_as_malformed_not_delivered() {
        let sc = Scenario::default();
        let mut rx = linked_receiver(&sc);
        let s1 = sense(0, 1, [0.0, 0.0]);
        rx.begin(&s1);
        let h = RadioHeader {
            sender: 1,
            len: 9,
            tick: 1,
            ..Default::default()
        };
        rx.ingest(&h, &[0xff; 9]);
        let h2 = RadioHeader {
            sender: 2,
            len: 200,
            tick: 1,
            ..Default::default()
        };
        rx.ingest(&h2, &[1; 4]); // claims more bytes than it carries
        rx.step(&s1, &mut Collect(vec![]));
        let s2 = sense(0, 2, [0.0, 0.0]);
        rx.begin(&s2);
        let a = rx.step(&s2, &mut Collect(vec![]));
        assert_eq!((a.radio_delivered, a.radio_malformed), (0, 2));
    }

    #[test]
    fn delay_holds_messages_for_extra_ticks() {
        let mut sc = Scenario::default();
        sc.radio.delay_ticks = 2;
        let mut rx = linked_receiver(&sc);
        let mut tx = Collect(vec![]);
        let mut a = AgentRuntime::new(&sc, 1, Echo { heard: vec![] });
        let s = sense(1, 1, [5.0, 0.0]);
        a.begin(&s);
        a.step(&s, &mut tx);
        let mut delivered_at = None;
        for k in 1..6 {
            let s = sense(0, k, [0.0, 0.0]);
            rx.begin(&s);
            if k == 1 {
                for (h, p) in &tx.0 {
                    rx.ingest(h, p);
                }
            }
            if rx.step(&s, &mut Collect(vec![])).radio_delivered > 0 {
                delivered_at.get_or_insert(k);
            }
        }
        assert_eq!(delivered_at, Some(4));
    }

    #[test]
    fn outbox_enforces_the_per_tick_limit() {
        let mut o: Outbox<u8> = Outbox::new(2);
        assert!(o.broadcast(1) && o.send(3, 2));
        assert!(!o.broadcast(3));
        assert_eq!(o.refused, 1);
    }
}
