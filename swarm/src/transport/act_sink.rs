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
fn transmit_area(robot: u32, area: &[u8], into: &mut Air) {
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

/// One robot's act service as the world subscribes to it.
pub struct ActPort {
    subscriber: Subscriber<ipc::Service, [u8], Action>,
    _service: ActService,
}

/// The world's side of the Action frames: every robot's act service, and the sample of this
/// tick each robot has sent so far (held until the tick is applied).
pub struct ActSource {
    ports: Vec<ActPort>,
    held: Vec<Option<ActSample>>,
}

impl ActSource {
    /// Makes the run's act services for `sc.run.robots` robots.
    pub fn create(node: &Node<ipc::Service>, sc: &Scenario) -> TransportResult<Self> {
        let ports = (0..sc.run.robots)
            .map(|i| {
                let service = act_service(node, i, true)?;
                Ok(ActPort {
                    subscriber: super::act_subscriber(&service)?,
                    _service: service,
                })
            })
            .collect::<TransportResult<Vec<_>>>()?;
        let held = (0..ports.len()).map(|_| None).collect();
        Ok(ActSource { ports, held })
    }

    /// Lock-step: whether robot `robot`'s action of tick `k` has arrived (received and held
    /// until [`ActSource::take`]). The barrier's ack words only say when to look: a robot
    /// counts as done with tick k when its own act service holds a sample of tick k, so an
    /// ack word written by anyone else cannot make the world go on without the robot.
    pub fn arrived(&mut self, robot: u32, k: u64) -> bool {
        let Some(port) = self.ports.get(robot as usize) else {
            return false;
        };
        let held = &mut self.held[robot as usize];
        while let Ok(Some(s)) = port.subscriber.receive() {
            *held = Some(s);
        }
        held.as_ref().is_some_and(|s| s.user_header().tick == k)
    }

    /// Lock-step: robot `robot`'s newest action (every live robot's action of tick `k`
    /// arrived, or the ack deadline passed), its messages appended to `sent` (`World::apply`
    /// judges both: an action of another tick is refused there). None: no sample.
    pub fn take(&mut self, robot: u32, k: u64, sent: &mut Air) -> Option<Action> {
        // Received already while the world waited (the common case): no second receive.
        let held = self.held.get(robot as usize)?;
        if held.as_ref().is_none_or(|s| s.user_header().tick != k) {
            self.arrived(robot, k);
        }
        let s = self.held.get_mut(robot as usize)?.take()?;
        transmit_area(robot, area_of(&s), sent);
        Some(action_of(robot, &s))
    }

    /// Real-time mode: robot `robot`'s actions at tick `k`'s deadline. The one of tick k (its
    /// messages go to `sent`) is this tick's action; one of an earlier tick arrived after
    /// that tick's deadline: its messages go out now (into `sent`, after this tick's) and its
    /// command is superseded. Only the newest late action counts; actions of a tick before
    /// `since` (an earlier agent's, before a restart) and of ticks not yet released are
    /// dropped. `late_msgs` is scratch.
    pub fn take_realtime(
        &mut self,
        robot: u32,
        k: u64,
        since: u64,
        sent: &mut Air,
        late_msgs: &mut Air,
    ) -> (Option<Action>, Option<Action>) {
        let Some(port) = self.ports.get(robot as usize) else {
            return (None, None);
        };
        let (mut cur, mut late) = (None, None);
        late_msgs.clear();
        while let Ok(Some(s)) = port.subscriber.receive() {
            let a = action_of(robot, &s);
            let into = if a.tick == k {
                cur = Some(a);
                &mut *sent
            } else if a.tick < k && a.tick >= since {
                late = Some(a);
                late_msgs.clear();
                &mut *late_msgs
            } else {
                continue;
            };
            transmit_area(robot, area_of(&s), into);
        }
        sent.append(late_msgs);
        (cur, late)
    }

    /// Robot `robot` is dead: nothing its agent sent is taken later (as late).
    pub fn discard(&mut self, robot: u32) {
        if let Some(p) = self.ports.get(robot as usize) {
            while let Ok(Some(_)) = p.subscriber.receive() {}
            self.held[robot as usize] = None;
        }
    }
}

/// An agent's side of its Action frames: its robot's act service.
pub struct ActSink {
    publisher: Publisher<ipc::Service, [u8], Action>,
    robot: u32,
    area: usize,
    _service: ActService,
}

impl ActSink {
    /// Opens robot `robot`'s act service for its agent.
    pub fn open(node: &Node<ipc::Service>, sc: &Scenario, robot: u32) -> TransportResult<Self> {
        let service = act_service(node, robot, false)?;
        Ok(ActSink {
            publisher: act_publisher(&service, sc)?,
            robot,
            area: super::act_slice_len(sc),
            _service: service,
        })
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
