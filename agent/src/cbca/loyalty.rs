//! The loyalty strategy of thesis sec. 4.2.4 (spec 4.7): a robot adopts a new path p_i' only if
//! S_i(p_i') > S_i(p_i) + sigma_i (4.22), with the threshold
//!   sigma_i = r1 Ē_i + r2 d_ic + r3 mu_i                                  (4.18)
//!   Ē_i     = (1/z) Σ_w E_i^w / E_{C_j}^w                                 (4.19)
//!   d_ic    = t_ic gamma_i                                                (4.20)
//!   mu_i    = S(b_i)                                                      (4.21)
//! and, when it leaves, the compensation it pays the coalition it abandons (Fig. 4.5's
//! narrative; the rule is ours, params.rs `LoyaltyParams`).
//!
//! Choices (spec 12 item 11): C_j is the coalition of the robot's current task (the first of
//! its path); types w with E_{C_j}^w = 0 are left out of the mean in (4.19) (the mean is over
//! the types the coalition carries); t_ic is the time the robot has travelled on its plan.

use super::model::{Resources, RobotId, TaskId};
use super::params::LoyaltyParams;

/// Ē_i of (4.19): the mean share robot i supplies of its coalition's resources, over the types
/// the coalition carries (`coalition` includes robot i's own resources).
pub fn importance(mine: &Resources, coalition: &Resources) -> f64 {
    let (sum, n) = mine
        .iter()
        .zip(coalition)
        .filter(|(_, c)| **c > 0.0)
        .fold((0.0, 0usize), |(s, n), (m, c)| (s + m / c, n + 1));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// What robot i's threshold depends on.
#[derive(Clone, Debug, PartialEq)]
pub struct LoyaltyState {
    /// E_i'.
    pub resources: Resources,
    /// Σ over its coalition C_j (itself included) of E'.
    pub coalition_resources: Resources,
    /// t_ic, time already travelled on its current plan.
    pub travelled_time: f64,
    /// gamma_i.
    pub gamma: f64,
    /// S(b_i) of its assigned, unexecuted tasks.
    pub unexecuted_score: f64,
}

/// The terms of (4.18).
#[derive(Clone, Debug, PartialEq)]
pub struct Threshold {
    /// Ē_i (4.19).
    pub importance: f64,
    /// d_ic (4.20).
    pub sunk_cost: f64,
    /// mu_i (4.21).
    pub breach_cost: f64,
    /// sigma_i (4.18).
    pub sigma: f64,
}

/// sigma_i of (4.18).
pub fn threshold(s: &LoyaltyState, p: &LoyaltyParams) -> Threshold {
    let importance = importance(&s.resources, &s.coalition_resources);
    let sunk_cost = s.travelled_time * s.gamma; // (4.20)
    let breach_cost = s.unexecuted_score; // (4.21)
    Threshold {
        importance,
        sunk_cost,
        breach_cost,
        sigma: p.r1 * importance + p.r2 * sunk_cost + p.r3 * breach_cost,
    }
}

/// (4.22): switch only if the new path beats the old by more than sigma_i.
pub fn switches(old_score: f64, new_score: f64, sigma: f64) -> bool {
    new_score > old_score + sigma
}

/// One compensation payment from a defector to a member of a coalition it leaves.
#[derive(Clone, Debug, PartialEq)]
pub struct Payment {
    pub from: RobotId,
    pub to: RobotId,
    pub task: TaskId,
    pub amount: f64,
}

/// The compensation robot `defector` pays when it abandons the tasks in `abandoned`, each given
/// as (task, its score S_ij(p_i) on the old path, the members that stay on that coalition):
/// `rate` times the score, split equally among those who stay. Nobody stays: nothing is paid.
pub fn compensation(
    defector: RobotId,
    abandoned: &[(TaskId, f64, Vec<RobotId>)],
    rate: f64,
) -> Vec<Payment> {
    let mut out = Vec::new();
    for (task, score, stay) in abandoned {
        let stay: Vec<RobotId> = stay.iter().copied().filter(|&m| m != defector).collect();
        if stay.is_empty() {
            continue;
        }
        let each = rate * score.max(0.0) / stay.len() as f64;
        for to in stay {
            out.push(Payment {
                from: defector,
                to,
                task: *task,
                amount: each,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> LoyaltyState {
        // R6 of Example 2 {5,7,8,9,4,5} in {R2, R4, R6} = {3,6,7,8,3,2} + {3,4,7,9,6,5} + R6
        // = {11,17,22,26,13,12}.
        LoyaltyState {
            resources: [5.0, 7.0, 8.0, 9.0, 4.0, 5.0],
            coalition_resources: [11.0, 17.0, 22.0, 26.0, 13.0, 12.0],
            travelled_time: 2.0,
            gamma: 0.6,
            unexecuted_score: 40.0,
        }
    }

    #[test]
    fn threshold_by_hand() {
        let t = threshold(&state(), &LoyaltyParams::default());
        // Ē = (5/11 + 7/17 + 8/22 + 9/26 + 4/13 + 5/12) / 6
        //   = (0.454545 + 0.411765 + 0.363636 + 0.346154 + 0.307692 + 0.416667) / 6 = 0.383410.
        assert!((t.importance - 0.383410).abs() < 1e-6);
        // d_ic = 2 * 0.6 = 1.2; mu = 40.
        assert!((t.sunk_cost - 1.2).abs() < 1e-12);
        // sigma = 50 * 0.383410 + 1 * 1.2 + 0.1 * 40 = 19.1705 + 1.2 + 4 = 24.3705.
        assert!((t.sigma - 24.3705).abs() < 1e-4);
    }

    #[test]
    fn loyalty_blocks_a_switch_below_its_threshold() {
        let sigma = threshold(&state(), &LoyaltyParams::default()).sigma;
        // Old path 40; a new one worth 60 gains 20 < 24.37: blocked. 65 gains 25: switches.
        assert!(!switches(40.0, 60.0, sigma));
        assert!(switches(40.0, 65.0, sigma));
        // Without loyalty (all r = 0) any gain switches.
        let none = LoyaltyParams {
            r1: 0.0,
            r2: 0.0,
            r3: 0.0,
            ..LoyaltyParams::default()
        };
        assert!(switches(40.0, 40.5, threshold(&state(), &none).sigma));
    }

    #[test]
    fn compensation_amounts_by_hand() {
        // R6 (index 5) leaves T2 (index 1), where it scored 36.0, for T4; R2 and R4 (1, 3) stay:
        // rate 1 -> 36 / 2 = 18 each. It also leaves T3 (index 2) scored 10 where nobody stays.
        let p = compensation(5, &[(1, 36.0, vec![1, 3, 5]), (2, 10.0, vec![5])], 1.0);
        assert_eq!(
            p,
            vec![
                Payment {
                    from: 5,
                    to: 1,
                    task: 1,
                    amount: 18.0
                },
                Payment {
                    from: 5,
                    to: 3,
                    task: 1,
                    amount: 18.0
                },
            ]
        );
        // Rate 0.5 on a three-member remainder: 0.5 * 36 / 3 = 6 each.
        let p = compensation(5, &[(1, 36.0, vec![0, 1, 3])], 0.5);
        assert_eq!(p.iter().map(|p| p.amount).collect::<Vec<_>>(), vec![6.0; 3]);
    }
}
