//! The Action frames, as an agent writes its own and as the world takes every robot's: one
//! iceoryx2 publish-subscribe service per robot (`robot/<i>/act`), the agent its publisher,
//! the world its subscriber. The Action is the sample's user header; the tick's messages are
//! its payload (the message area, parsed with bounds checks by
//! `swarm::air::for_each_act_message`). The world knows a sample's robot from the service it
//! came through, never from what the agent wrote (`docs/protocol.md`).

use super::{act_publisher, act_service, ActService, ServiceId, TransportError, TransportResult};
use crate::frames::{Action, RadioHeader};
use crate::mailbox::Air;
use crate::scenario::Scenario;
use crate::wire::RadioTx;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;

/// Hands a message area's messages to `into` (the world's buffer of the tick's messages),
/// each stamped with `robot`, the robot whose act service the area came through: a message's
/// sender is never what its header claims (a robot cannot speak, or be silenced, as another).
/// An area that does not parse hands none (the world then refuses the action's radio report,
/// counting its messages malformed).
pub(super) fn transmit_area(robot: u32, area: &[u8], into: &mut Air) {
    crate::air::for_each_act_message(area, |h, p| {
        let stamped = RadioHeader {
            sender: robot,
            ..*h
        };
        into.transmit(&stamped, &mut |b| b.copy_from_slice(p))
    });
}

/// The Action of a sample of robot `robot`'s act service, its `robot` field stamped from
/// the service (what the agent wrote there is not believed).
fn action_of(robot: u32, s: &ActSample) -> Action {
    Action {
        robot,
        ..*s.user_header()
    }
}

/// The used part of a sample's message area: `radio_bytes`, cut to the area.
fn area_of(s: &ActSample) -> &[u8] {
    let used = (s.user_header().radio_bytes as usize).min(s.payload().len());
    &s.payload()[..used]
}

type ActSample = iceoryx2::sample::Sample<ipc::Service, [u8], Action>;

/// The top bit of an Action's `tick` marks an attach notice: the first sample an agent sends
/// through its robot's act service, before any action, its attach number in the low bits
/// (`docs/protocol.md` section 6). No run reaches 2^63 ticks.
pub const ATTACH_NOTICE: u64 = 1 << 63;

/// The attach number of an attach notice, None for an action.
pub fn attach_of(a: &Action) -> Option<u64> {
    (a.tick & ATTACH_NOTICE != 0).then_some(a.tick & !ATTACH_NOTICE)
}

/// One robot's act service as the world subscribes to it.
pub struct ActPort {
    subscriber: Subscriber<ipc::Service, [u8], Action>,
    _service: ActService,
}

/// The world's side of the Action frames: every robot's act service, the newest action
/// each robot has sent (held until the tick is applied), its newest late one (real-time
/// mode), and the newest attach notice each service delivered. Everything the world decides
/// about a robot (done with a tick, silent, attached) comes from here, never from the
/// barrier's ack and attach words, which every agent can write (issue 37 item 5).
pub struct PubSubSource {
    /// Per robot of the run: its act service, if this source reads it (a host proxy reads
    /// its own robots' only).
    ports: Vec<Option<ActPort>>,
    held: Vec<Option<ActSample>>,
    late: Vec<Option<ActSample>>,
    attached: Vec<u64>,
}

impl PubSubSource {
    /// Makes the act services of `robots` of the run (`sc.run.robots` in all).
    pub fn create(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        robots: &[u32],
    ) -> TransportResult<Self> {
        let mut ports: Vec<Option<ActPort>> = (0..sc.run.robots).map(|_| None).collect();
        for &i in robots {
            let service = act_service(node, i, true)?;
            if let Some(p) = ports.get_mut(i as usize) {
                *p = Some(ActPort {
                    subscriber: super::act_subscriber(&service)?,
                    _service: service,
                });
            }
        }
        let none = |_| None;
        Ok(PubSubSource {
            held: (0..ports.len()).map(none).collect(),
            late: (0..ports.len()).map(none).collect(),
            attached: vec![0; ports.len()],
            ports,
        })
    }

    /// The next sample of robot `robot`'s service that is an action; attach notices met on
    /// the way are noted.
    fn next_action(&mut self, robot: usize) -> Option<ActSample> {
        let port = self.ports.get(robot)?.as_ref()?;
        while let Ok(Some(s)) = port.subscriber.receive() {
            match attach_of(s.user_header()) {
                Some(n) => self.attached[robot] = self.attached[robot].max(n),
                None => return Some(s),
            }
        }
        None
    }

    /// The highest attach number an attach notice of robot `robot`'s own act service carried
    /// (0: no agent attached through it yet). Receives what is pending: call it only while
    /// the robot holds no action the world still needs (at start-up, while it is dead).
    pub fn attached(&mut self, robot: u32) -> u64 {
        let r = robot as usize;
        while self.next_action(r).is_some() {}
        self.attached.get(r).copied().unwrap_or(0)
    }

    /// Lock-step: whether robot `robot`'s action of tick `k` has arrived (received and held
    /// until [`PubSubSource::take`]). A robot counts as done with tick k when its own act
    /// service delivered a sample of tick k: the barrier's ack words only say when to look.
    /// One receive a robot a tick in the common case.
    pub fn arrived(&mut self, robot: u32, k: u64) -> bool {
        let r = robot as usize;
        loop {
            if self
                .held
                .get(r)
                .is_some_and(|h| h.as_ref().is_some_and(|s| s.user_header().tick == k))
            {
                return true;
            }
            match self.next_action(r) {
                Some(s) => self.held[r] = Some(s),
                None => return false,
            }
        }
    }

    /// Lock-step: robot `robot`'s newest action (every live robot's action of tick `k`
    /// arrived, or the ack deadline passed), its messages appended to `sent` (`World::apply`
    /// judges both: an action of another tick is refused there). None: no sample.
    pub fn take(&mut self, robot: u32, k: u64, sent: &mut Air) -> Option<Action> {
        // Received already while the world waited (the common case): no second receive.
        self.arrived(robot, k);
        let s = self.held.get_mut(robot as usize)?.take()?;
        transmit_area(robot, area_of(&s), sent);
        Some(action_of(robot, &s))
    }

    /// Lock-step, for a host proxy: robot `robot`'s action of tick `k` if it arrived, with
    /// its used message area as written (relayed to the world's host as it came).
    pub fn take_area(&mut self, robot: u32, k: u64) -> Option<(Action, Vec<u8>)> {
        if !self.arrived(robot, k) {
            return None;
        }
        let s = self.held.get_mut(robot as usize)?.take()?;
        Some((action_of(robot, &s), area_of(&s).to_vec()))
    }

    /// Real-time mode: receives robot `robot`'s pending samples, keeping its action of tick
    /// `k` and its newest late one (of a tick from `since` to k - 1: an earlier agent's, before
    /// a restart, and ticks not yet released are dropped). True if an action was kept: the
    /// robot made progress, as the world's deadline rule counts it.
    pub fn poll_realtime(&mut self, robot: u32, k: u64, since: u64) -> bool {
        let r = robot as usize;
        let mut progress = false;
        while let Some(s) = self.next_action(r) {
            let t = s.user_header().tick;
            if t == k {
                self.held[r] = Some(s);
            } else if t < k && t >= since {
                self.late[r] = Some(s);
            } else {
                continue;
            }
            progress = true;
        }
        progress
    }

    /// Real-time mode: whether robot `robot`'s action of tick `k` is held.
    pub fn holds(&self, robot: u32, k: u64) -> bool {
        self.held
            .get(robot as usize)
            .is_some_and(|h| h.as_ref().is_some_and(|s| s.user_header().tick == k))
    }

    /// Real-time mode: robot `robot`'s actions at tick `k`'s deadline. The one of tick k (its
    /// messages go to `sent`) is this tick's action; one of an earlier tick arrived after
    /// that tick's deadline: its messages go out now (into `sent`, after this tick's) and its
    /// command is superseded. Only the newest late action counts; actions of a tick before
    /// `since` (an earlier agent's, before a restart) and of ticks not yet released are
    /// dropped.
    pub fn take_realtime(
        &mut self,
        robot: u32,
        k: u64,
        since: u64,
        sent: &mut Air,
    ) -> (Option<Action>, Option<Action>) {
        let r = robot as usize;
        if r >= self.ports.len() {
            return (None, None);
        }
        self.poll_realtime(robot, k, since);
        let take = |slot: &mut Option<ActSample>, ok: &dyn Fn(u64) -> bool, sent: &mut Air| {
            let s = slot.take().filter(|s| ok(s.user_header().tick))?;
            transmit_area(robot, area_of(&s), sent);
            Some(action_of(robot, &s))
        };
        let cur = take(&mut self.held[r], &|t| t == k, sent);
        let late = take(&mut self.late[r], &|t| t < k && t >= since, sent);
        (cur, late)
    }

    /// Robot `robot` is dead: nothing its agent sent is taken later (as late). Attach
    /// notices are kept (a replacement's).
    pub fn discard(&mut self, robot: u32) {
        let r = robot as usize;
        while self.next_action(r).is_some() {}
        if r < self.ports.len() {
            self.held[r] = None;
            self.late[r] = None;
        }
    }
}

/// An agent's side of its Action frames: its robot's act service.
pub struct PubSubSink {
    publisher: Publisher<ipc::Service, [u8], Action>,
    robot: u32,
    area: usize,
    _service: ActService,
}

impl PubSubSink {
    /// Opens robot `robot`'s act service for its agent.
    pub fn open(node: &Node<ipc::Service>, sc: &Scenario, robot: u32) -> TransportResult<Self> {
        let service = act_service(node, robot, false)?;
        Ok(PubSubSink {
            publisher: act_publisher(&service, sc)?,
            robot,
            area: super::act_slice_len(sc),
            _service: service,
        })
    }

    /// Sends the attach notice of this agent, attach number `attach` (the robot's attach
    /// counter after its own increment): the first sample of its act service, before any
    /// action. The world counts the robot attached when it receives it.
    pub fn attach(&mut self, attach: u64) -> TransportResult<()> {
        self.send(|_| Action::idle(ATTACH_NOTICE | attach, 0))
    }

    /// Sends tick `tick`'s action: `step` writes the tick's messages into the loaned
    /// sample's message area and returns the Action (its `radio_bytes` the bytes it wrote).
    pub fn send(&mut self, step: impl FnOnce(&mut [u8]) -> Action) -> TransportResult<()> {
        let sample = self
            .publisher
            .loan_slice_uninit(self.area)
            .map_err(|source| TransportError::Loan {
                service: ServiceId::Act(self.robot),
                source,
            })?;
        // SAFETY: the slot is shared memory of the publisher's data segment, mapped from
        // tmpfs: its bytes are always initialised (zero when first mapped, then whatever an
        // earlier tick left), and every u8 value is valid. The world reads only the
        // `radio_bytes` that `step` writes.
        let mut sample = unsafe { sample.assume_init() };
        let action = step(sample.payload_mut());
        *sample.user_header_mut() = action;
        sample.send().map_err(|source| TransportError::Send {
            service: ServiceId::Act(self.robot),
            source,
        })?;
        Ok(())
    }
}
