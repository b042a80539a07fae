//! What hunting robots and the auctioneer say on the radio. Robot ids are the thesis's
//! (`hunt.robots[k].id`), task ids the evaders' (T_j). Every message travels through the
//! behaviour API (`Outbox::broadcast` / `send`), so radio range and loss apply to each.

use crate::hunt::auction::{Announcement, Award, Bid, Closed};
use crate::hunt::model::{RobotId, TaskId};
use serde::{Deserialize, Serialize};

/// One radio message of the hunt.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum HuntMsg {
    /// Auctioneer -> all: round r of auction `auction` (sec. 3.2.2 stage 1). `replan_of`
    /// non-empty: a re-planning auction of a new target (sec. 3.2.5): only free robots and
    /// members of these coalitions bid, a member only if it gains by moving.
    Announce {
        auction: u32,
        replan_of: Vec<TaskId>,
        a: Announcement,
    },
    /// Robot -> auctioneer: its bid of the round (stage 2).
    Bid { auction: u32, bid: Bid },
    /// Auctioneer -> all: a coalition awarded (stage 4), with the epoch of the assignment.
    Award {
        auction: u32,
        epoch: u32,
        award: Award,
    },
    /// Auctioneer -> all: the auction is over; robots without an award are free.
    Closed { auction: u32, closed: Closed },
    /// Auctioneer -> all: the coalition of `task` is now `members` (re-planning: swaps,
    /// assistance, replacement; also resent now and then, so a lost award is made up for).
    /// A robot takes the newest epoch that names it; one hunting `task` that is not named
    /// is free.
    Assign {
        epoch: u32,
        task: TaskId,
        members: Vec<RobotId>,
        reward: f64,
    },
    /// Robot -> all (its coalition and the auctioneer): where it is and what it does.
    Status(Status),
    /// A coalition's leader -> its members: the hunting points (sec. 3.2.4): s_1 at bearing
    /// `anchor` from the target, then clockwise; robot `order[k]` takes point k.
    Points {
        task: TaskId,
        leader: RobotId,
        anchor: f64,
        order: Vec<RobotId>,
    },
}

/// A robot's status.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Status {
    pub robot: RobotId,
    pub pos: [f64; 2],
    /// The task it hunts (0: none) and the epoch of that assignment.
    pub task: TaskId,
    pub epoch: u32,
    /// Where it sees its target (NaN: not seen).
    pub target: [f64; 2],
    /// Its hunting point (NaN before the hunting-point phase).
    pub point: [f64; 2],
    /// Its target is captured (sensed EVADER_CAPTURED).
    pub captured: bool,
}
