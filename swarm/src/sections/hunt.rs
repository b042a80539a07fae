//! The hunting thesis's scenario section (`[hunt]`, docs/hunting.md; thesis 003 chapters 2-3):
//! the robots (`[[hunt.robots]]`, Table 3.2), the evaders (`[[hunt.evaders]]`, Table 3.1), the
//! auctioneer (`[hunt.auctioneer]`) and the tunables (`[hunt.params]`), and what the world's
//! `hunt` mission and the `hunt` behaviour share: the kind and flags of the evader entities in
//! a Sense frame, the display states, and what a robot's Action `report` holds.
//!
//! Units: **km** and **minutes** (speeds km/min, turn rates rad/min), as the thesis's tables;
//! the world runs in km and ticks of `params.minutes_per_tick` minutes.
//!
//! Agents: robot `k` of the world (0-based) is `hunt.robots[k]`; the auctioneer is the last
//! agent, id `run.robots - 1`, a station (`run.stations` = 1): no body, it only talks.

use serde::{Deserialize, Serialize};

/// Resource types z (every experiment of the thesis uses 6, eq. 2.4).
pub const N_RESOURCES: usize = 6;
/// A resource vector E (2.3)-(2.4), units of each type.
pub type Resources = [f64; N_RESOURCES];

// ---------------------------------------------------------------------------------------
// The entity contract of the Sense frame (what the world tells a robot of the evaders).

/// Sense `entities[..].kind` of an evader (target): `id` is its thesis id (T_j, 1-based),
/// `pos` its position (flag `ENTITY_HAS_POS`), `value` the speed it ran at in the last tick,
/// km/min (0 while silent or captured).
pub const ENTITY_EVADER: u32 = 1;
/// Flag of an evader entity: it is captured (it has stopped for good; sec. 1.4).
pub const EVADER_CAPTURED: u32 = 1 << 4;
/// Most evaders one robot senses in a tick (the nearest when more are within range).
pub const MAX_EVADERS_SENSED: usize = 24;

// ---------------------------------------------------------------------------------------
// What a robot reports (Action `report`) and its display state.

/// The display state (Action events, low byte) of a hunting robot: the thesis id of the
/// task it is hunting, 1..=254, or `STATE_FREE`; the picture colours robots by it (Figs.
/// 3.3-3.5: one colour per coalition).
pub const STATE_FREE: u32 = 0;
/// The display state of the auctioneer.
pub const STATE_AUCTIONEER: u32 = 255;
/// `report[0]`: the task id the robot hunts (0: none). `report[1..3]`: the hunting point it
/// heads for (x, y km; NaN before the hunting-point phase). `report[3]`: `REPORT_LEADER` if
/// it leads its coalition's encirclement, plus `REPORT_AT_POINT` when it stands within the
/// capture tolerance of its point.
pub const REPORT_LEADER: f64 = 1.0;
pub const REPORT_AT_POINT: f64 = 2.0;
// The auctioneer (the station) reports, one row a tick in turn: [task, z_j paid, auction
// rounds so far, 0] for each task it has awarded, then the totals row [0, C, rounds, Y]: the
// auctioneer's cost C (3.13) and the winners' utility Y (3.14) summed over every auction it
// has finished.

// ---------------------------------------------------------------------------------------
// The section.

/// A scenario's `[hunt]` section is malformed.
#[derive(Debug, thiserror::Error)]
pub enum HuntConfigError {
    #[error("hunt section does not parse: {0}")]
    Parse(#[from] toml::de::Error),
    /// A value out of its range (the key path names the row and field).
    #[error("{0}")]
    Invalid(#[from] crate::scenario::ConfigError),
}

/// One `[[hunt.robots]]` row (Table 3.2 plus the columns the thesis does not print).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    pub id: u32,
    /// (x_i, y_i), km.
    pub position: [f64; 2],
    /// Initial heading, rad.
    #[serde(default)]
    pub heading: f64,
    /// g_i for T1..T_n (Table 3.2).
    pub matching: Vec<f64>,
    /// E_i', exactly 6 entries (2.4).
    #[serde(deserialize_with = "six_resources")]
    pub resources: Resources,
    /// v_i, km/min.
    pub speed: f64,
    /// w_max, rad/min.
    pub turn_rate: f64,
    /// d^c_max,i (2.5), km; absent = unlimited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_mileage: Option<f64>,
}

/// One `[[hunt.evaders]]` row (Table 3.1 plus the columns the thesis does not print).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvaderSpec {
    /// T_j, 1..=254.
    pub id: u32,
    /// (x_j, y_j), km.
    pub position: [f64; 2],
    /// L_j.
    pub required_robots: usize,
    /// z_jmax.
    pub reward_cap: f64,
    /// E_j, exactly 6 entries (2.3).
    #[serde(deserialize_with = "six_resources")]
    pub resources: Resources,
    /// v_j, km/min.
    pub speed: f64,
    /// Speed-capability threshold on the robots, km/min.
    #[serde(default)]
    pub min_robot_speed: f64,
    /// When the target appears, minutes (T5 appears mid-run in Example 3-A). 0 = at the
    /// start. It appears at tick round(appears_at / params.minutes_per_tick): [`Self::appear_tick`].
    #[serde(default)]
    pub appears_at: f64,
}

impl EvaderSpec {
    /// The tick the evader appears at.
    pub fn appear_tick(&self, p: &HuntParams) -> u64 {
        (self.appears_at / p.minutes_per_tick).round().max(0.0) as u64
    }
}

/// `[hunt.auctioneer]`: the task initiator's station (sec. 3.1), an agent with no body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AuctioneerSpec {
    /// Where it stands, km. [chosen] The middle of the thesis's 10 km arena.
    pub position: [f64; 2],
    /// Its radio range, km: it hears and is heard only within it, on top of
    /// `radio.comm_radius` (which applies to every message). 0 = global, as the thesis implies
    /// (sec. 1.5: "wireless broadcast", no radius). [chosen] 0.
    pub radio_range: f64,
}

impl Default for AuctioneerSpec {
    fn default() -> Self {
        AuctioneerSpec {
            position: [5.0, 5.0],
            radio_range: 0.0,
        }
    }
}

impl AuctioneerSpec {
    /// Whether a message between the auctioneer and a robot at `robot` is within its range.
    pub fn reaches(&self, robot: [f64; 2]) -> bool {
        let d =
            ((robot[0] - self.position[0]).powi(2) + (robot[1] - self.position[1]).powi(2)).sqrt();
        self.radio_range <= 0.0 || d <= self.radio_range
    }
}

/// The `[hunt]` section (absent: no hunt).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HuntSection {
    #[serde(default)]
    pub params: HuntParams,
    #[serde(default)]
    pub auctioneer: AuctioneerSpec,
    #[serde(default)]
    pub robots: Vec<RobotSpec>,
    #[serde(default)]
    pub evaders: Vec<EvaderSpec>,
}

#[derive(Deserialize)]
struct File {
    hunt: HuntSection,
}

/// Absent: no hunt (left out of a resolved scenario).
impl crate::plugin::Section for HuntSection {
    const NAME: &'static str = "hunt";
    fn absent() -> Option<Self> {
        Some(HuntSection::default())
    }
    fn is_empty(&self) -> bool {
        HuntSection::is_empty(self)
    }
}

impl HuntSection {
    /// No robots and no evaders: the scenario has no hunt (left out of a resolved scenario).
    pub fn is_empty(&self) -> bool {
        self.robots.is_empty() && self.evaders.is_empty()
    }

    /// Parse the `[hunt]` section of a whole scenario file (other sections are ignored) and
    /// validate it.
    pub fn from_scenario_toml(text: &str) -> Result<Self, HuntConfigError> {
        let f: File = toml::from_str(text)?;
        let source = |_: &str| "hunt section".to_string();
        f.hunt.validate(&crate::scenario::Check {
            key_source: &source,
        })?;
        Ok(f.hunt)
    }

    /// Every value of the section in its range, ids unique (errors name the row and the
    /// field: `hunt.robots[3].speed`): crate::sections::hunt_checks.
    pub fn validate(&self, c: &crate::scenario::Check) -> Result<(), crate::scenario::ConfigError> {
        super::hunt_checks::validate(self, c)
    }

    /// The fastest robot's speed in km per tick (robot.v_max must allow it).
    pub fn max_speed_per_tick(&self) -> f64 {
        self.robots.iter().map(|r| r.speed).fold(0.0, f64::max) * self.params.minutes_per_tick
    }

    /// The fastest turn rate in rad per tick (robot.kinematics.w_max must allow it).
    pub fn max_turn_per_tick(&self) -> f64 {
        self.robots.iter().map(|r| r.turn_rate).fold(0.0, f64::max) * self.params.minutes_per_tick
    }
}

/// A resource row must have exactly z = 6 entries (serde's fixed arrays ignore extra ones).
fn six_resources<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Resources, D::Error> {
    let v = Vec::<f64>::deserialize(d)?;
    Resources::try_from(v.as_slice()).map_err(|_| {
        serde::de::Error::invalid_length(v.len(), &"exactly 6 resource entries (eq. 2.4)")
    })
}

/// The live auction (`HuntParams::auction`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AuctionKind {
    /// The thesis's improved auction (sec. 3.1-3.2): single best-task bids, reward feedback.
    #[default]
    Improved,
    /// The parallel auction baseline (Otte, Kuhlman & Sofge 2020; spec 11): one round, fixed
    /// reward, bids on every task, each task awarded independently.
    Parallel,
}

/// Tunables of the hunt: auction (sec. 3.1-3.2), hunting points (sec. 3.2.4), APF (sec. 2.1.4),
/// capture and the evader's escape (eq. 2.17).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HuntParams {
    /// m1, weight of the resource cost E_ij in the robot's cost (3.9). [chosen] The thesis only
    /// says m1 + m2 + m3 = 1; resources get the smallest weight since (2.6) already checks them.
    pub m1: f64,
    /// m2, weight of the encirclement time T'_ij (3.9)-(3.10). [chosen]
    pub m2: f64,
    /// m3, weight of the pursuit time d_ij / (v_j - v_i) (3.9). [chosen] The largest weight: the
    /// thesis's coalitions are geographic, so the distance term must matter.
    pub m3: f64,
    /// alpha in (0, 1): initial reward z_j^1 = alpha z_jmax (3.11). [chosen] 0.8: below every
    /// paid/cap ratio of Table 3.3 except T4's (0.72), leaving room to rise and to fall (spec
    /// 10.1 shows no single alpha fits both Table 3.3 and Fig. 3.6).
    pub alpha: f64,
    /// Multiplier on the reward feedback step of (3.15): 1.0 is the thesis's rule
    /// z^{r+1} = z^r - ((L_bid - L_j) / n_r)(z_max - z^r). [thesis] Kept as a knob for sweeps.
    pub reward_feedback_step: f64,
    /// Lower bound of a reward, as a fraction of z_jmax: (3.15) lowers a reward in proportion to
    /// the headroom, so a low reward with many excess bids could go negative (spec 3.4).
    /// [chosen] 0: the spec's "clamp to >= 0".
    pub reward_floor_fraction: f64,
    /// The auction ends when no reward changes by more than this between two rounds ("until the
    /// rewards stop changing", sec. 3.2.2). [chosen] 0.01 reward units.
    pub reward_tolerance: f64,
    /// Round limit of one auction. [chosen] The thesis converges in 12 rounds; 200 is a safety net
    /// for instances where a task can never be filled (n_r < sum L_j).
    pub max_rounds: u32,
    /// Cap on the combinations of L_j bidders the auctioneer tries when the L_j cheapest do not
    /// cover E_j (2.6). [chosen] Above it the auctioneer repairs the cheapest set greedily.
    pub max_coalition_combinations: usize,
    /// r_e for a target needing L_j = 3 robots, km. The effective hunting range of target j
    /// (3.17) is r_e,j = `r_e_at_three` * 3 / L_j: "the more robots a target needs, the smaller
    /// r_e is set" (text under 3.10). [chosen] 1.0 km: a tenth of the arena side.
    pub r_e_at_three: f64,
    /// r_s, the formation (encirclement) radius of the hunting points, km (3.18)-(3.19).
    /// [chosen] 0.3 km: below the smallest r_e (0.6 km for L_j = 5).
    pub r_s: f64,
    /// A robot "has chased to near its hunting point" within this distance, km (sec. 1.4, spec
    /// 12 item 3). [chosen] 0.05 km = 50 m, a sixth of r_s.
    pub capture_tolerance: f64,
    /// Floor of the speed difference v_j - v_i in (3.9)-(3.10), km/min: the thesis assumes robots
    /// slower than targets; a robot as fast or faster gets the floor (the cheapest time cost)
    /// instead of a negative or infinite one. [chosen] 0.05 km/min.
    pub speed_gap_floor: f64,
    /// How the auctioneer applies (2.6) when it picks winners. [chosen] true: the L_j winners must
    /// cover E_j together; false: the thesis's literal "L_j lowest-cost bidders".
    pub enforce_coalition_resources: bool,
    /// The fixed reward of the parallel-auction baseline as a fraction of z_jmax (spec 11: "alpha
    /// z_jmax or z_jmax [MISSING]"). [chosen] 0.8 = alpha, so both auctions start level.
    pub parallel_reward_fraction: f64,
    /// Parallel auction: may a robot win several tasks in the one round? Otte et al. 2020: yes.
    /// [thesis baseline] true.
    pub parallel_multiple_wins: bool,
    /// Which auction the live auctioneer runs (the `hunt` behaviour; sec. 3.2 vs spec 11):
    /// "improved" (the thesis's, round by round with reward feedback 3.15) or "parallel" (the
    /// baseline: one round at `parallel_reward_fraction` z_jmax, every robot bids on every
    /// task). [thesis] "improved". Re-planning (swaps, assistance, replacement) is the same for
    /// both; a new target is auctioned by the same kind.
    pub auction: AuctionKind,
    /// Hunting points: which of several robots claiming one point gets it (sec. 3.2.4 step 4).
    /// [thesis] true = the farthest, as written ("分配给距离最远的机器人").
    pub contested_point_to_farthest: bool,
    /// APF attractive gain k_a (2.11)-(2.12), (2.16). [chosen] 1 per minute-free unit.
    pub k_a: f64,
    /// APF repulsive gain k_r between robots (2.13)-(2.15). [chosen] 0.002: repulsion equals the
    /// attraction of a goal 1 km away when two robots are 0.1 km apart (d_o = 0.2, n = 2).
    pub k_r: f64,
    /// APF repulsion range d_o, km (2.13). [chosen] 0.2 km, below the hunting-point spacing.
    pub d_o: f64,
    /// APF goal-distance exponent n (2.13)-(2.15). [chosen] 2, the usual Ge-Ni choice.
    pub n: f64,
    /// Use (2.15) as printed (bracket squared) instead of the exact gradient of (2.13) (bracket
    /// to the power 1). [chosen] false: the exact gradient (spec 1.7 recommends it).
    pub printed_fr2: bool,
    /// Force-to-speed gain of the (v, w) mapping, 1/min: v = min(v_max, k_v |F|) cos^+(e).
    /// [chosen] 10: a robot slows down only in the last v_max/10 km (about 80 m) to its goal.
    pub speed_per_force: f64,
    /// Sensing radius of an evader, km: it reacts only to pursuers within it (spec 12 item 2).
    /// [chosen] 1.5 km. The world's escape reads it (`EscapeParams`).
    pub evader_sensing_radius: f64,
    /// **The parameter that keeps capture possible with robots slower than evaders** (spec 1.3,
    /// 12 item 1). An evader flees at v_j (g / 2 pi)^s, where g is the largest bearing gap among
    /// the pursuers it senses and s is this exponent: alone or chased from one side (g near
    /// 2 pi) it runs at full speed, encircled by L robots (g = 2 pi / L) at v_j / L^s. The thesis
    /// (eq. 2.17) is s = 0, under which slower robots can never close in. [chosen] s = 1.
    /// The world's escape reads it (`EscapeParams::encirclement_slowdown`).
    pub encirclement_slowdown: f64,
    /// On-line re-planning (sec. 3.2.5 (a), step 5): a coalition that has not captured its target
    /// after this long gets assistance, minutes. [chosen] 30 min: the 10 km arena is crossed in
    /// about 12 min at the robots' speeds.
    pub assistance_timeout: f64,
    /// The control step dt of eqs. (2.8)-(2.10), minutes per world tick: the world runs in km
    /// and ticks, so robot.v_max is the fastest robot's speed times this. [chosen] 0.05 min
    /// (3 s): a robot at 0.9 km/min moves 45 m a tick, under the capture tolerance.
    pub minutes_per_tick: f64,
    /// A wall closer to an evader than this is a blocked bearing of its escape (eq. 2.17),
    /// km. [chosen] 0.5 km (`world::mission::hunt_escape::EscapeParams::wall_margin`).
    pub evader_wall_margin: f64,
    /// Hunting points by a wall (sec. 3.2.4 says nothing of walls). true: where the r_s circle
    /// (3.18)-(3.19) around the target crosses the arena's edge, the leader spreads the n_j
    /// points evenly over the longest arc of the circle that lies at least
    /// `hunting_point_wall_clearance` inside the arena, and the world's capture rule counts a
    /// wall closer than r_s to the target as a blocked bearing (as the escape does), so a
    /// target pinned to a wall can be captured. false: the printed ring, whose points beyond a
    /// wall no robot can reach. [chosen] true: measured, the replacement run of Example 3-A
    /// (R3 killed at tick 150) never captures T4, pinned to the top wall, with false
    /// (docs/hunting.md section 13).
    pub hunting_points_inside_arena: bool,
    /// How far inside the arena's edge a hunting point must lie, km, when
    /// `hunting_points_inside_arena` moves points off a wall. [chosen] 0.1 km: two robot steps
    /// (0.045 km a tick), so a robot reaching its point is not blocked by the wall.
    pub hunting_point_wall_clearance: f64,
    /// Robots sense the evaders (Sense entities, with positions) within this distance, km.
    /// [chosen] 20 km, more than the 10 km arena's diagonal: chapter 3 gives every robot the
    /// targets' information (the auctioneer "holds information on all targets" and
    /// broadcasts it); chapter 4 would set 1.2 km.
    pub detection_radius: f64,
    /// Ticks the auctioneer waits for bids after announcing a round before it closes it (a
    /// bid is heard two ticks after the announcement at the earliest: one tick to the robot,
    /// one back). [chosen] 3.
    pub bid_window_ticks: u64,
    /// Ticks between a robot's status messages to the auctioneer (position, task, whether it
    /// stands at its hunting point). [chosen] 5 ticks (15 s at 0.05 min a tick).
    pub status_period_ticks: u64,
    /// The auctioneer takes a robot for dead (its agent process died: future work item 4)
    /// when it has heard nothing from it for this many ticks. [chosen] 25 ticks = 5 status
    /// periods: with loss 0.3, five statuses in a row are lost with probability 0.3^5 = 0.002.
    pub silent_dead_ticks: u64,
    /// Ticks between two re-planning passes of the auctioneer (swaps, assistance,
    /// replacement of dead members: sec. 3.2.5). [chosen] 20 ticks (1 min).
    pub replan_period_ticks: u64,
    /// Ticks an award is resent to a member whose status does not name its task yet (the
    /// award was lost on the radio). [chosen] 5.
    pub award_resend_ticks: u64,
}

impl Default for HuntParams {
    fn default() -> Self {
        Self {
            m1: 0.2,
            m2: 0.3,
            m3: 0.5,
            alpha: 0.8,
            reward_feedback_step: 1.0,
            reward_floor_fraction: 0.0,
            reward_tolerance: 0.01,
            max_rounds: 200,
            max_coalition_combinations: 200_000,
            r_e_at_three: 1.0,
            r_s: 0.3,
            capture_tolerance: 0.05,
            speed_gap_floor: 0.05,
            enforce_coalition_resources: true,
            parallel_reward_fraction: 0.8,
            parallel_multiple_wins: true,
            auction: AuctionKind::Improved,
            contested_point_to_farthest: true,
            k_a: 1.0,
            k_r: 0.002,
            d_o: 0.2,
            n: 2.0,
            printed_fr2: false,
            speed_per_force: 10.0,
            evader_sensing_radius: 1.5,
            encirclement_slowdown: 1.0,
            assistance_timeout: 30.0,
            minutes_per_tick: 0.05,
            evader_wall_margin: 0.5,
            hunting_points_inside_arena: true,
            hunting_point_wall_clearance: 0.1,
            detection_radius: 20.0,
            bid_window_ticks: 3,
            status_period_ticks: 5,
            silent_dead_ticks: 25,
            replan_period_ticks: 20,
            award_resend_ticks: 5,
        }
    }
}

impl HuntParams {
    /// r_e,j, the effective hunting range (3.17) of a target needing `required_robots` robots.
    pub fn effective_range(&self, required_robots: usize) -> f64 {
        self.r_e_at_three * 3.0 / required_robots.max(1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn example_3a_parses_with_its_auctioneer_and_t5_tick() {
        let sc = crate::Scenario::parse(
            include_str!("../../../configs/hunt-example-3a.toml"),
            "hunt-example-3a.toml",
        )
        .unwrap();
        let h = &sc.hunt();
        h.validate(&crate::scenario::Check {
            key_source: &|_| "t".to_string(),
        })
        .unwrap();
        assert_eq!((h.robots.len(), h.evaders.len()), (15, 5));
        assert_eq!(h.auctioneer, AuctioneerSpec::default());
        // T5 at 5 min, 0.05 min a tick: tick 100.
        assert_eq!(h.evaders[4].appear_tick(&h.params), 100);
        assert!((h.max_speed_per_tick() - 0.045).abs() < 1e-15);
        assert_eq!((sc.run.robots, sc.run.stations, sc.bodies()), (16, 1, 15));
        assert!(sc.is_station(15) && !sc.is_station(14) && !sc.is_station(16));
        // The resolved scenario keeps the section; a scenario without one leaves it out.
        let again = crate::Scenario::parse(&sc.to_toml(), "resolved").unwrap();
        assert_eq!(again, sc);
        assert!(!crate::Scenario::default().to_toml().contains("[hunt"));
    }

    #[test]
    fn the_auctioneer_range_is_global_at_zero() {
        let mut a = AuctioneerSpec::default();
        assert!(a.reaches([0.0, 0.0]) && a.reaches([100.0, 100.0]));
        a.radio_range = 2.0;
        assert!(a.reaches([6.9, 5.0]) && !a.reaches([7.1, 5.0]));
    }

    #[test]
    fn bad_rows_are_refused() {
        let mut h = HuntSection::default();
        h.evaders.push(EvaderSpec {
            id: 255,
            position: [1.0, 1.0],
            required_robots: 3,
            reward_cap: 100.0,
            resources: [1.0; 6],
            speed: 1.0,
            min_robot_speed: 0.0,
            appears_at: 0.0,
        });
        let source = |_: &str| "t".to_string();
        let c = crate::scenario::Check {
            key_source: &source,
        };
        assert_eq!(h.validate(&c).unwrap_err().key, "hunt.evaders[0].id");
        h.evaders[0].id = 3;
        h.evaders[0].appears_at = -1.0;
        assert_eq!(
            h.validate(&c).unwrap_err().key,
            "hunt.evaders[0].appears_at"
        );
    }
}
