//! The runtime parameters of the CBCA behaviour (`[cbca.behaviour]`): what the kernels'
//! `CbcaParams` (`[cbca.params]`) do not cover because it concerns ticks, motion and the radio.
//! The thesis gives none of them (it runs CBCA as rounds in MATLAB); each is a documented
//! choice.

use serde::{Deserialize, Serialize};

/// Which targets a robot knows before it hears anything (grouping's prior information,
/// sec. 4.2.2, `cbca::grouping::PriorInfo`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Prior {
    /// The targets it detects itself (within `cbca.params.detection_radius_km`).
    Detection,
    /// Detection, and each target nobody detects at the start goes to the robot nearest to it
    /// (from the scenario's start rows, which every robot reads): Example 1's T3 is within
    /// 1.2 km of nobody, and the thesis still hunts it.
    DetectionPlusNearest,
    /// Every target (CBCA without grouping: with a radio that reaches everyone).
    All,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BehaviourParams {
    /// Ticks per CBCA time unit (the unit of hold times and of the decay beta_j t). [chosen] 20,
    /// with robots at 0.05 km a tick: one time unit is 1 km of travel, as the kernels assume
    /// (`cbca.params.robot_speed` = 1 km per time unit).
    pub ticks_per_time_unit: f64,
    /// While settled, a beacon (digest and gossip, no state) every this many ticks. [chosen] 5.
    pub beacon_period: u64,
    /// A robot heard within this many ticks is a current neighbour for the convergence
    /// detector. [chosen] 20: four beacon periods, so a neighbour stays one under loss 0.5
    /// with probability 1 - 0.5^4.
    pub neighbour_window: u64,
    /// The convergence detector's quiet period, in ticks (it replaces
    /// `cbca.params.quiet_iterations`, which counts the round drivers' iterations): a robot's
    /// state unchanged this long and every current neighbour's last digest equal to it.
    /// [chosen] 10: a neighbour sending every tick is unheard for 10 ticks with probability
    /// 0.5^10 = 0.1 % under loss 0.5.
    pub quiet_ticks: u64,
    /// Added once to a robot's bids on the tasks it committed to (`CbcaRobot::pin`). [chosen]
    /// 1e6, above any score of the thesis's tables (V_a <= 600).
    pub commit_bonus: f64,
    /// Prior information of the grouping (see [`Prior`]).
    pub prior: Prior,
    /// Joint arrival: a coalition member waits this far from its target (km) until every member
    /// is there. [chosen] 1.6 km, just outside the evaders' 1.5 km sensing radius, so the
    /// target does not flee from a lone early robot.
    pub wait_radius_km: f64,
    /// ... but no longer than this many ticks (a member may never come: lost messages, a
    /// death not yet known). [chosen] 400 (20 time units).
    pub max_wait_ticks: u64,
    /// A goal counts as reached within this distance (km): the go-to slows down near its goal
    /// and would otherwise approach it for ever. [chosen] 0.05 km, the hunt kernels'
    /// capture tolerance.
    pub arrive_tolerance_km: f64,
    /// Radius of the ring the members close on (km). [chosen] 0.3 km, the hunt kernels' r_s.
    pub ring_radius_km: f64,
    /// Loyalty (4.18)-(4.22) on; false is the "no loyalty" ablation (a robot switches whenever
    /// the new plan scores more).
    pub loyalty: bool,
    /// A robot with an empty path (idle from the start, or its targets done) goes to
    /// `seek_radius_km` of the nearest unfinished target it knows of and stays
    /// there, inside the radio range of that target's coalition, so it can replace a member
    /// that dies (sec. 4.2.5 re-planning needs a free robot within reach). [chosen] false, the
    /// thesis's Fig. 4.2(c) (idle robots stay where they are); true lets a coalition that lost
    /// a member after spreading out be completed. Kept off: it is no general win
    /// (configs/cbca-seek-example{1,2}.toml, docs/hunting.md 14.9: at 1.6 km it turns Example
    /// 1's 20 %-killed runs from 7 into 20 of 20 captured, but Example 2's lossless runs from 10
    /// into 0 of 10).
    pub seek_when_idle: bool,
    /// Where a seeking idle robot parks: this far from the target (km). [chosen] 1.0: within
    /// the 1.5 km radio of every member on a capture ring of radius up to 0.5 km (the waiting
    /// ring, 1.6 km, is not: a member across the ring is up to 1.9 km away). Measured (14.9):
    /// 1.6, outside the evaders' 1.5 km sensing radius, does better in every Example 1 variant
    /// and in Example 2 under loss and kills, worse in Example 2 lossless.
    pub seek_radius_km: f64,
    /// A coalition member that has held its capture point this many ticks without the capture
    /// takes every member it has not heard directly in as many ticks for dead (forgotten and
    /// gossiped, as a death the proximity sensor saw): at the capture ring (radius r_s) every
    /// live member is in radio range of every other, so silence there means death, whereas a
    /// member that dies after the coalition spread out leaves nobody's proximity sensor.
    /// [chosen] 100 (5 time units; beacons go every `beacon_period` = 5 ticks). A member still
    /// on its way after that long is taken for dead too: the cost of the rule.
    pub presume_lost_ticks: u64,
    /// The presumed-loss clock of `presume_lost_ticks` starts only once this robot is within
    /// this distance of the target (km). [chosen] 0.6: on the capture ring (radius r_s <= 0.3 km
    /// in the hunt configs) plus the capture tolerance and the target's own motion; members
    /// there are within 1.2 km of each other, inside the 1.5 km radio. Without it a robot
    /// still 3 km away, closing after `max_wait_ticks`, took members it could not hear for
    /// dead (the trace of docs/hunting.md 14.4).
    pub presume_within_km: f64,
    /// Speed / distance gain of the holonomic go-to (1/tick): v = min(v_max, gain d). [chosen]
    /// 0.5: a robot slows down in the last 2 v_max of its goal.
    pub goto_gain: f64,
}

impl Default for BehaviourParams {
    fn default() -> Self {
        Self {
            ticks_per_time_unit: 20.0,
            beacon_period: 5,
            neighbour_window: 20,
            quiet_ticks: 10,
            commit_bonus: 1e6,
            prior: Prior::DetectionPlusNearest,
            wait_radius_km: 1.6,
            max_wait_ticks: 400,
            arrive_tolerance_km: 0.05,
            ring_radius_km: 0.3,
            loyalty: true,
            seek_when_idle: false,
            seek_radius_km: 1.0,
            presume_lost_ticks: 100,
            presume_within_km: 0.6,
            goto_gain: 0.5,
        }
    }
}
