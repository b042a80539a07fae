//! Every tunable of the hunting kernels (thesis 003, chapters 2-3) in one struct, so it can become
//! the `[hunt.params]` section of a scenario file. Units throughout: **km** for lengths (the
//! thesis's tables are in km on a 10 km x 10 km arena) and **minutes** for time, so speeds are
//! km/min and turn rates rad/min. Nearly none of these values is printed in the thesis
//! (docs/hunting.md section 6 and 12): each is marked [thesis] or [chosen] with the reason.

use serde::{Deserialize, Serialize};

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
    /// [chosen] 1.5 km. Mirrored by `world::mission::hunt_escape::EscapeParams`.
    pub evader_sensing_radius: f64,
    /// **The parameter that keeps capture possible with robots slower than evaders** (spec 1.3,
    /// 12 item 1). An evader flees at v_j (g / 2 pi)^s, where g is the largest bearing gap among
    /// the pursuers it senses and s is this exponent: alone or chased from one side (g near
    /// 2 pi) it runs at full speed, encircled by L robots (g = 2 pi / L) at v_j / L^s. The thesis
    /// (eq. 2.17) is s = 0, under which slower robots can never close in. [chosen] s = 1.
    /// Mirrored by `world::mission::hunt_escape::EscapeParams::encirclement_slowdown`.
    pub encirclement_slowdown: f64,
    /// On-line re-planning (sec. 3.2.5 (a), step 5): a coalition that has not captured its target
    /// after this long gets assistance, minutes. [chosen] 30 min: the 10 km arena is crossed in
    /// about 12 min at the robots' speeds.
    pub assistance_timeout: f64,
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
    fn weights_sum_to_one_and_alpha_in_open_interval() {
        let p = HuntParams::default();
        assert!(
            (p.m1 + p.m2 + p.m3 - 1.0).abs() < 1e-12,
            "(3.9): m1+m2+m3 = 1"
        );
        assert!(p.alpha > 0.0 && p.alpha < 1.0, "(3.11): alpha in (0,1)");
        // r_s must lie inside every r_e the example uses (L_j up to 5).
        assert!(p.r_s < p.effective_range(5));
    }

    #[test]
    fn escape_defaults_mirror_the_world_side() {
        // The evader's escape lives in the world crate; its defaults must agree with these.
        let p = HuntParams::default();
        let e = world::mission::hunt_escape::EscapeParams::default();
        assert_eq!(p.evader_sensing_radius, e.sensing_radius);
        assert_eq!(p.encirclement_slowdown, e.encirclement_slowdown);
    }

    #[test]
    fn effective_range_shrinks_with_required_robots() {
        let p = HuntParams::default();
        assert!((p.effective_range(3) - 1.0).abs() < 1e-12);
        assert!((p.effective_range(5) - 0.6).abs() < 1e-12);
        assert!(p.effective_range(4) < p.effective_range(3));
    }

    #[test]
    fn empty_section_is_the_default_and_unknown_keys_are_rejected() {
        let p: HuntParams = toml::from_str("").unwrap();
        assert_eq!(p, HuntParams::default());
        let p: HuntParams = toml::from_str("alpha = 0.5").unwrap();
        assert_eq!(p.alpha, 0.5);
        assert!(toml::from_str::<HuntParams>("alfa = 0.5").is_err());
    }
}
