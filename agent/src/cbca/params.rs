//! Every tunable of CBCA (thesis 003 chapter 4), with where it comes from. The thesis gives the
//! radii, l_i and the per-target / per-robot table values (beta_j, gamma_i, ...); everything else
//! is [MISSING] there (docs/hunting.md sections 6 and 12) and the value here is a documented
//! choice. The struct is a `[cbca.params]` section of a scenario file; a missing key takes the
//! default below.

use serde::{Deserialize, Serialize};

/// How much of its resources a robot uses up on a task it joins (4.5); the thesis does not say
/// (spec 12 item 8).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Consumption {
    /// Per type p: min(left^p, E_j^p / L_j), an equal share of the need, capped at what is left.
    /// The default: the thesis's robots carry about a third of a target's need per type, so a
    /// robot can serve up to l_i = 3 targets before running dry in some types.
    FairShare,
    /// Per type p: min(left^p, E_j^p), all it can give up to the whole need.
    FullNeed,
}

/// CBCA's parameters (thesis chapter 4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CbcaParams {
    /// w1 of (4.13), the weight of the time-decaying reward. [MISSING] in the thesis; 1.0 keeps
    /// the reward in the tables' units (V_a 100-600).
    pub w1: f64,
    /// w2 of (4.13), the weight of the path cost xi_ij = gamma_i d_ij (4.14). [MISSING]; 1.0
    /// (neutral). With the tables' gamma 0.4-0.8 and legs of a few km, the cost is a few units
    /// against rewards of tens to hundreds: distance acts mostly through the decay.
    pub w2: f64,
    /// l_i, the most tasks a robot accepts (4.2): 3 for every robot in the thesis (sec. 4.3).
    pub max_tasks: usize,
    /// Robot speed (km per time unit) for t_(p_i) in (4.12) when a robot row gives none.
    /// [MISSING]: the thesis gives no speed and no time unit; 1 km per time unit makes the
    /// tables' beta (0.45-0.71) halve a reward over 1-1.5 km of travel.
    pub robot_speed: f64,
    /// d^c_max of (2.5), the range (km) of a robot whose row gives none. [MISSING]; 20 km, two
    /// arena widths, so it binds only on long multi-task paths.
    pub mileage_budget_km: f64,
    /// The consumption rule of (4.5).
    pub consumption: Consumption,
    /// Principle 4's hold time (time units) of a target whose row gives none. [MISSING]; 1.0.
    pub hold_time: f64,
    /// beta_j of (4.12) for a target whose row gives none (generated scenarios); the tables
    /// give 0.45-0.71, 0.5 is inside that range.
    pub default_beta: f64,
    /// gamma_i of (4.14) for a robot whose row gives none (generated scenarios); the tables
    /// give 0.4-0.8, 0.6 is the middle.
    pub default_gamma: f64,
    /// Robot-robot communication radius (km), sec. 4.3: 1.5.
    pub comm_radius_km: f64,
    /// Detection radius (km), sec. 4.3: 1.2.
    pub detection_radius_km: f64,
    /// Bids are capped by the bids placed earlier in the same bundle (y = min(c, earlier)), the
    /// diminishing-marginal-gain repair of later CBBA work, so a robot never bids more for a
    /// later task than for an earlier one; without it CBBA-style consensus may not converge
    /// when insertion raises a later marginal gain. Not in the thesis; on by default.
    pub cap_bids: bool,
    /// Rule (B) of Algorithm 2 and the displacement of Algorithm 1 require E_m ∩ E_n* != ∅ (the
    /// newcomer carries a type the displaced robot carries). The thesis prints it in
    /// Algorithm 2; we apply it in both places so that both judge a displacement alike.
    pub substitution_check: bool,
    /// Coalition resources (2.6) enforced in Algorithm 1 (bundle.rs): a bid that would complete
    /// a coalition (its L_j-th member) or displace its weakest member is open only if the
    /// members' carried resources E_i' then sum to E_j in every type. Not-completing bids stay
    /// open (a partial coalition may still be completed by a robot that covers the rest). The
    /// thesis states (2.6) but not how a robot would enforce it (spec 12 item 8); on by default.
    pub enforce_coverage: bool,
    /// Round runs (compare.rs) only: after a grouped run converges, temporary groups that
    /// claim a common target merge (they would meet at it) and consensus runs again, until no
    /// target is claimed by two groups. The thesis's groups move and merge (sec. 4.2.5); the
    /// round runs do not move, so this stands in for the meeting. On by default; off gives the
    /// groups-fixed-at-the-start runs (which can deadlock across groups).
    pub merge_on_conflict: bool,
    /// Convergence DETECTOR (consensus.rs): a robot declares convergence when its own state has
    /// not changed for this many of its iterations AND the last message from each current
    /// neighbour carries the same state digest and arrived after its last change. With every
    /// robot declaring it on a connected graph, every edge joins equal states, so all agree.
    /// [MISSING] in the thesis (it iterates "until Z and Y stop changing"); 3.
    pub quiet_iterations: u64,
    /// A driver's safety cap on consensus iterations (an error if reached, never a stopping
    /// rule). 1000.
    pub max_iterations: u64,
    /// Loyalty (4.18)-(4.22) and compensation.
    pub loyalty: LoyaltyParams,
}

/// The loyalty threshold sigma_i = r1 Ē_i + r2 d_ic + r3 mu_i (4.18) and the compensation a
/// defector pays. The thesis gives no r1..r3 and no payment rule (spec 12 item 11).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LoyaltyParams {
    /// r1, on Ē_i in [0, 1] (4.19): a robot supplying all of its coalition's resources needs
    /// 50 more utility units to leave (a quarter of a typical V_a).
    pub r1: f64,
    /// r2, on d_ic = t_ic gamma_i (4.20), the sunk travel cost: 1.0, in the path cost's units.
    pub r2: f64,
    /// r3, on mu_i = S(b_i) (4.21), the utility of its unexecuted tasks: 0.1, so a switch must
    /// beat the old plan by 10 % of it (1.0 would demand doubling it).
    pub r3: f64,
    /// Compensation paid to the coalition a robot leaves: this fraction of the defector's score
    /// S_ij(p_i) on each task it abandons, split equally among that coalition's remaining
    /// members and taken from the defector's utility. [INFERRED from Fig. 4.5: "the defector
    /// bears the loss of its unexecuted task revenue"]; 1.0.
    pub compensation_rate: f64,
}

impl Default for LoyaltyParams {
    fn default() -> Self {
        Self {
            r1: 50.0,
            r2: 1.0,
            r3: 0.1,
            compensation_rate: 1.0,
        }
    }
}

impl Default for CbcaParams {
    fn default() -> Self {
        Self {
            w1: 1.0,
            w2: 1.0,
            max_tasks: 3,
            robot_speed: 1.0,
            mileage_budget_km: 20.0,
            consumption: Consumption::FairShare,
            hold_time: 1.0,
            default_beta: 0.5,
            default_gamma: 0.6,
            comm_radius_km: 1.5,
            detection_radius_km: 1.2,
            cap_bids: true,
            substitution_check: true,
            enforce_coverage: true,
            merge_on_conflict: true,
            quiet_iterations: 3,
            max_iterations: 1000,
            loyalty: LoyaltyParams::default(),
        }
    }
}
