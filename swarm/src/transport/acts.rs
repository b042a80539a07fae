//! The act transport of a run, as the scenario chose it (`runtime.acts`): the world's
//! [`ActSource`] and an agent's [`ActSink`], each either the pub-sub one (`robot/<i>/act`,
//! `act_sink.rs`) or the blackboard one (`robot/<i>/board`, `act_board.rs`), with the same
//! calls. Both are world-created iceoryx2 services, one a robot; the world knows a robot's
//! action from the service it read, never from what the agent wrote.

use super::act_board::{BoardSink, BoardSource};
use super::act_sink::{PubSubSink, PubSubSource};
use super::TransportResult;
use crate::frames::Action;
use crate::mailbox::Air;
use crate::scenario::{ActsKind, Scenario};
use iceoryx2::prelude::*;

/// The world's side of the Action frames (see [`PubSubSource`] and [`BoardSource`] for what
/// each call does).
pub enum ActSource {
    PubSub(PubSubSource),
    Board(Box<BoardSource>),
}

/// Calls the same method on whichever source this is.
macro_rules! either {
    ($self:expr, $s:ident => $call:expr) => {
        match $self {
            ActSource::PubSub($s) => $call,
            ActSource::Board($s) => $call,
        }
    };
}

impl ActSource {
    /// Makes the run's act services (`sc.runtime.acts`) for `sc.run.robots` robots.
    pub fn create(node: &Node<ipc::Service>, sc: &Scenario) -> TransportResult<Self> {
        let all: Vec<u32> = (0..sc.run.robots).collect();
        Self::create_for(node, sc, &all)
    }

    /// Makes the act services of `robots` only (a host proxy's own robots).
    pub fn create_for(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        robots: &[u32],
    ) -> TransportResult<Self> {
        Ok(match sc.runtime.acts {
            ActsKind::PubSub => ActSource::PubSub(PubSubSource::create(node, sc, robots)?),
            ActsKind::Blackboard => {
                ActSource::Board(Box::new(BoardSource::create(node, sc, robots)?))
            }
        })
    }

    /// The highest attach number robot `robot`'s own act service carried (0: none yet).
    /// `node` is the world's: a blackboard retired at the robot's death is made anew through
    /// it.
    pub fn attached(&mut self, node: &Node<ipc::Service>, robot: u32) -> u64 {
        match self {
            ActSource::PubSub(s) => s.attached(robot),
            ActSource::Board(s) => s.attached(node, robot),
        }
    }

    /// Robot `robot` died (once per death): a blackboard is let go, to be made anew for a
    /// replacement; the pub-sub service stays as it is (a replacement opens it beside its
    /// dead predecessor's port).
    pub fn retire(&mut self, robot: u32) {
        if let ActSource::Board(s) = self {
            s.retire(robot)
        }
    }

    pub fn arrived(&mut self, robot: u32, k: u64) -> bool {
        either!(self, s => s.arrived(robot, k))
    }

    pub fn take(&mut self, robot: u32, k: u64, sent: &mut Air) -> Option<Action> {
        either!(self, s => s.take(robot, k, sent))
    }

    /// Lock-step, for a host proxy: robot `robot`'s action of tick `k`, if it arrived, with
    /// its used message area as the agent wrote it (relayed, not parsed here).
    pub fn take_area(&mut self, robot: u32, k: u64) -> Option<(Action, Vec<u8>)> {
        either!(self, s => s.take_area(robot, k))
    }

    pub fn poll_realtime(&mut self, robot: u32, k: u64, since: u64) -> bool {
        either!(self, s => s.poll_realtime(robot, k, since))
    }

    pub fn holds(&self, robot: u32, k: u64) -> bool {
        either!(self, s => s.holds(robot, k))
    }

    pub fn take_realtime(
        &mut self,
        robot: u32,
        k: u64,
        since: u64,
        sent: &mut Air,
    ) -> (Option<Action>, Option<Action>) {
        either!(self, s => s.take_realtime(robot, k, since, sent))
    }

    pub fn discard(&mut self, robot: u32) {
        either!(self, s => s.discard(robot))
    }
}

/// An agent's side of its Action frames, as the scenario chose it.
pub enum ActSink {
    PubSub(PubSubSink),
    Board(Box<BoardSink>),
}

impl ActSink {
    /// Opens robot `robot`'s act service for its agent. A blackboard that is not there yet
    /// or still held by a dead predecessor (being made anew by the world) is tried again
    /// while `keep_trying()` says so.
    pub fn open(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        robot: u32,
        keep_trying: &dyn Fn() -> bool,
    ) -> TransportResult<Self> {
        Ok(match sc.runtime.acts {
            ActsKind::PubSub => ActSink::PubSub(PubSubSink::open(node, sc, robot)?),
            ActsKind::Blackboard => {
                ActSink::Board(Box::new(BoardSink::open(node, sc, robot, keep_trying)?))
            }
        })
    }

    /// One try at opening robot `robot`'s act service (a caller that must not wait: the hosts
    /// gateway tries again at its next turn).
    pub fn try_open(node: &Node<ipc::Service>, sc: &Scenario, robot: u32) -> TransportResult<Self> {
        Ok(match sc.runtime.acts {
            ActsKind::PubSub => ActSink::PubSub(PubSubSink::open(node, sc, robot)?),
            ActsKind::Blackboard => ActSink::Board(Box::new(BoardSink::try_open(node, sc, robot)?)),
        })
    }

    /// Says this agent attached, with attach number `attach` (before any action).
    pub fn attach(&mut self, attach: u64) -> TransportResult<()> {
        match self {
            ActSink::PubSub(s) => s.attach(attach),
            ActSink::Board(s) => {
                s.attach(attach);
                Ok(())
            }
        }
    }

    /// Sends an action: `step` writes the tick's messages into the message area and returns
    /// the Action (its `radio_bytes` the bytes it wrote).
    pub fn send(&mut self, step: impl FnOnce(&mut [u8]) -> Action) -> TransportResult<()> {
        match self {
            ActSink::PubSub(s) => s.send(step),
            ActSink::Board(s) => {
                s.send(step);
                Ok(())
            }
        }
    }
}
