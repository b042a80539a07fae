//! The Action frames' two transports (`runtime.acts`), as an agent writes its own and as the
//! world takes every robot's: per-robot cells of one world-made segment
//! (`swarm::air_ring::acts`, the default: no iceoryx2 port operation a tick) or one iceoryx2
//! service per robot. Both hand the world the same Action and the same messages (the
//! message area parsed by `swarm::air::act_messages`), so a run does not depend on the
//! choice.

use super::{act_publisher, act_service, ActService, ServiceId, TransportError, TransportResult};
use crate::air_ring::acts::{ActCellWriter, ActCells};
use crate::frames::Action;
use crate::mailbox::Air;
use crate::scenario::{ActTransport, Scenario};
use crate::wire::RadioTx;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;

/// Hands a message area's messages to `into` (the world's buffer of the tick's messages). An
/// area that does not parse hands none (the world then refuses the action's radio report,
/// counting its messages malformed).
fn transmit_area(area: &[u8], into: &mut Air) {
    crate::air::for_each_act_message(area, |h, p| into.transmit(h, &mut |b| b.copy_from_slice(p)));
}

/// One robot's act service as the world subscribes to it.
pub struct ActPort {
    subscriber: Subscriber<ipc::Service, [u8], Action>,
    _service: ActService,
}

/// The world's side of the Action frames.
pub enum ActSource {
    Cells {
        cells: ActCells,
        /// The message area of the action read last, and of the best late one so far.
        area: Vec<u8>,
        late_area: Vec<u8>,
        /// Real-time mode: each robot's newest tick taken (an action is taken once, as an
        /// iceoryx2 sample is received once).
        taken: Vec<Option<u64>>,
    },
    Iceoryx2(Vec<ActPort>),
}

impl ActSource {
    /// Makes the run's act transport (`runtime.acts`) for `sc.run.robots` robots.
    pub fn create(node: &Node<ipc::Service>, prefix: &str, sc: &Scenario) -> TransportResult<Self> {
        let n = sc.run.robots;
        Ok(match sc.runtime.acts {
            ActTransport::Cells => ActSource::Cells {
                cells: ActCells::create(prefix, n, super::act_slice_len(sc))?,
                area: Vec::new(),
                late_area: Vec::new(),
                taken: vec![None; n as usize],
            },
            ActTransport::Iceoryx2 => ActSource::Iceoryx2(
                (0..n)
                    .map(|i| {
                        let service = act_service(node, i, true)?;
                        Ok(ActPort {
                            subscriber: super::act_subscriber(&service)?,
                            _service: service,
                        })
                    })
                    .collect::<TransportResult<Vec<_>>>()?,
            ),
        })
    }

    /// Lock-step: robot `robot`'s action of tick `k` (every live robot acknowledged it), its
    /// messages appended to `sent` (`World::apply` judges both). None: no action (a torn
    /// cell, or no sample).
    pub fn take(&mut self, robot: u32, k: u64, sent: &mut Air) -> Option<Action> {
        match self {
            ActSource::Cells { cells, area, .. } => {
                let (_, a) = cells.read(robot, k, |t| t == k, area)?;
                transmit_area(area, sent);
                Some(a)
            }
            ActSource::Iceoryx2(ports) => {
                let act = &ports.get(robot as usize)?.subscriber;
                let mut latest = None;
                while let Ok(Some(s)) = act.receive() {
                    latest = Some(s);
                }
                let s = latest?;
                let a = *s.user_header();
                let used = (a.radio_bytes as usize).min(s.payload().len());
                transmit_area(&s.payload()[..used], sent);
                Some(a)
            }
        }
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
        match self {
            ActSource::Cells {
                cells,
                area,
                late_area,
                taken,
            } => {
                let Some(taken) = taken.get_mut(robot as usize) else {
                    return (None, None);
                };
                let last = *taken;
                let fresh = |t: u64| t >= since && last.is_none_or(|x| t > x);
                let cur = cells.read(robot, k, |t| t == k && fresh(t), area);
                if cur.is_some() {
                    transmit_area(area, sent);
                }
                // A late action lies in either buffer (tick k - 1's, or an older one in tick
                // k's buffer that no read found whole yet).
                let mut late: Option<(u64, Action)> = None;
                for parity in [k + 1, k] {
                    let got = cells.read(robot, parity, |t| t < k && fresh(t), area);
                    if let Some((t, a)) = got.filter(|(t, _)| late.is_none_or(|(l, _)| *t > l)) {
                        late = Some((t, a));
                        std::mem::swap(area, late_area);
                    }
                }
                if late.is_some() {
                    transmit_area(late_area, sent);
                }
                *taken = cur.map(|c| c.0).max(late.map(|l| l.0)).max(last);
                (cur.map(|c| c.1), late.map(|l| l.1))
            }
            ActSource::Iceoryx2(ports) => {
                let Some(port) = ports.get(robot as usize) else {
                    return (None, None);
                };
                let (mut cur, mut late) = (None, None);
                late_msgs.clear();
                while let Ok(Some(s)) = port.subscriber.receive() {
                    let a = *s.user_header();
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
                    let used = (a.radio_bytes as usize).min(s.payload().len());
                    transmit_area(&s.payload()[..used], into);
                }
                sent.append(late_msgs);
                (cur, late)
            }
        }
    }

    /// Robot `robot` is dead: nothing its agent sent is taken later (as late).
    pub fn discard(&mut self, robot: u32) {
        match self {
            ActSource::Cells { cells, .. } => cells.clear(robot),
            ActSource::Iceoryx2(ports) => {
                if let Some(p) = ports.get(robot as usize) {
                    while let Ok(Some(_)) = p.subscriber.receive() {}
                }
            }
        }
    }

    /// Cell reads refused because a write overtook them (0 through iceoryx2).
    pub fn torn(&self) -> u64 {
        match self {
            ActSource::Cells { cells, .. } => cells.torn(),
            ActSource::Iceoryx2(_) => 0,
        }
    }
}

/// An agent's side of its Action frames.
pub enum ActSink {
    Cells(ActCellWriter),
    Iceoryx2 {
        publisher: Publisher<ipc::Service, [u8], Action>,
        robot: u32,
        area: usize,
        _service: ActService,
    },
}

impl ActSink {
    /// Opens the run's act transport (`runtime.acts`) for robot `robot`'s agent.
    pub fn open(
        node: &Node<ipc::Service>,
        prefix: &str,
        sc: &Scenario,
        robot: u32,
    ) -> TransportResult<Self> {
        Ok(match sc.runtime.acts {
            ActTransport::Cells => ActSink::Cells(ActCellWriter::open(prefix, robot)?),
            ActTransport::Iceoryx2 => {
                let service = act_service(node, robot, false)?;
                ActSink::Iceoryx2 {
                    publisher: act_publisher(&service, sc)?,
                    robot,
                    area: super::act_slice_len(sc),
                    _service: service,
                }
            }
        })
    }

    /// Sends tick `tick`'s action: `step` writes the tick's messages into the message area
    /// it is given (in place: the cell's, or the loaned sample's) and returns the Action
    /// (its `radio_bytes` the bytes it wrote).
    pub fn send(
        &mut self,
        tick: u64,
        step: impl FnOnce(&mut [u8]) -> Action,
    ) -> TransportResult<()> {
        match self {
            ActSink::Cells(w) => {
                w.write(tick, step);
                Ok(())
            }
            ActSink::Iceoryx2 {
                publisher,
                robot,
                area,
                ..
            } => {
                let sample =
                    publisher
                        .loan_slice_uninit(*area)
                        .map_err(|source| TransportError::Loan {
                            service: ServiceId::Act(*robot),
                            source,
                        })?;
                // SAFETY: the slot is shared memory of the publisher's data segment, mapped
                // from tmpfs: its bytes are always initialised (zero when first mapped, then
                // whatever an earlier tick left), and every u8 value is valid. The world
                // reads only the `radio_bytes` that `step` writes.
                let mut sample = unsafe { sample.assume_init() };
                let action = step(sample.payload_mut());
                *sample.user_header_mut() = action;
                sample.send().map_err(|source| TransportError::Send {
                    service: ServiceId::Act(*robot),
                    source,
                })?;
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::air::ActTx;
    use crate::frames::RadioHeader;

    /// Tick t's action of robot 0 with one message whose payload is `[t as u8; 3]`.
    fn act(t: u64) -> impl FnOnce(&mut [u8]) -> Action {
        move |area: &mut [u8]| {
            let mut tx = ActTx::new(area);
            let h = RadioHeader {
                tick: t,
                len: 3,
                ..RadioHeader::default()
            };
            tx.transmit(&h, &mut |b| b.fill(t as u8));
            let mut a = Action::idle(t, 0);
            a.radio_bytes = tx.used as u32;
            a
        }
    }

    fn ticks_sent(sent: &Air) -> Vec<u64> {
        sent.messages()
            .map(|(h, p)| {
                assert_eq!(p, [h.tick as u8; 3]);
                h.tick
            })
            .collect()
    }

    /// Real-time mode over the cells: an action late for its tick is taken once, at the next
    /// tick the world reads, its messages after that tick's own; actions of an earlier agent
    /// (before `since`) and of ticks not yet released are not taken.
    #[test]
    fn late_actions_in_cells_are_taken_once_after_the_ticks_own() {
        let p = format!("swtest{}_acts-late_", std::process::id());
        let mut src = ActSource::Cells {
            cells: ActCells::create(&p, 1, 256).unwrap(),
            area: Vec::new(),
            late_area: Vec::new(),
            taken: vec![None],
        };
        let mut w = ActCellWriter::open(&p, 0).unwrap();
        let (mut sent, mut scratch) = (Air::default(), Air::default());
        let mut take = |src: &mut ActSource, k: u64, since: u64, sent: &mut Air| {
            sent.clear();
            let (c, l) = src.take_realtime(0, k, since, sent, &mut scratch);
            (c.map(|a| a.tick), l.map(|a| a.tick))
        };
        w.write(0, act(0));
        assert_eq!(take(&mut src, 0, 0, &mut sent), (Some(0), None));
        assert_eq!(ticks_sent(&sent), [0]);
        // Tick 1 missed: written after its deadline, with tick 2's on time.
        assert_eq!(take(&mut src, 1, 0, &mut sent), (None, None));
        w.write(1, act(1));
        w.write(2, act(2));
        assert_eq!(take(&mut src, 2, 0, &mut sent), (Some(2), Some(1)));
        assert_eq!(
            ticks_sent(&sent),
            [2, 1],
            "this tick's messages, then the late"
        );
        // Nothing new: neither is taken again.
        assert_eq!(take(&mut src, 3, 0, &mut sent), (None, None));
        assert!(sent.is_empty());
        // Two late ticks (4 and 5) by tick 6: only the newest counts.
        w.write(4, act(4));
        w.write(5, act(5));
        assert_eq!(take(&mut src, 6, 0, &mut sent), (None, Some(5)));
        assert_eq!(ticks_sent(&sent), [5]);
        // A tick not released yet is not taken; a restarted agent from tick 9 on: the old
        // agent's tick 7 is not late for it.
        w.write(8, act(8));
        assert_eq!(take(&mut src, 7, 0, &mut sent), (None, None));
        w.write(7, act(7));
        assert_eq!(take(&mut src, 9, 9, &mut sent), (None, None));
        w.write(9, act(9));
        assert_eq!(take(&mut src, 9, 9, &mut sent), (Some(9), None));
        // A dead robot's actions are forgotten.
        w.write(10, act(10));
        src.discard(0);
        assert_eq!(take(&mut src, 11, 9, &mut sent), (None, None));
        // Lock-step takes tick k's only.
        w.write(12, act(12));
        assert_eq!(src.take(0, 13, &mut sent).map(|a| a.tick), None);
        sent.clear();
        assert_eq!(src.take(0, 12, &mut sent).map(|a| a.tick), Some(12));
        assert_eq!(ticks_sent(&sent), [12]);
        assert_eq!(src.torn(), 0);
    }
}
