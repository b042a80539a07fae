//! Local-vision partial re-planning (thesis sec. 4.2.5, spec 4.8). While hunting:
//! - case 1, a robot sees a new target but cannot know whether another coalition hunts it:
//!   no re-planning;
//! - case 2.1, its coalition meets one that has already encircled its target: no re-planning;
//! - case 2.2, it meets one that has not: the two merge, share their targets and run CBCA
//!   (Algorithms 1 and 2) again; each robot adopts its new path p_i' only if the loyalty test
//!   (4.22) passes, and a robot in its hold time (principle 4) keeps its path. A robot that
//!   leaves pays compensation to the coalitions it abandons (loyalty.rs).
//!
//! [`decide`] takes, per robot of the merged group, its old plan and the plan the new CBCA run
//! proposes, and returns who switches, the thresholds, the payments and the utilities after.

use std::collections::BTreeMap;

use super::loyalty::{compensation, switches, threshold, LoyaltyState, Payment, Threshold};
use super::model::{RobotId, TaskId};
use super::params::LoyaltyParams;

/// What a coalition's robots run into during the hunt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encounter {
    /// Case 1: a target seen by vision.
    NewTarget,
    /// Case 2: another coalition in communication range, which has or has not captured its
    /// target (cases 2.1 and 2.2).
    Coalition { captured: bool },
}

/// Whether the encounter triggers a merged re-plan (only case 2.2).
pub fn replans(e: Encounter) -> bool {
    matches!(e, Encounter::Coalition { captured: false })
}

/// One robot's old plan and the merged run's proposal.
#[derive(Clone, Debug, PartialEq)]
pub struct Proposal {
    pub robot: RobotId,
    /// In a hold period (principle 4): it may not switch.
    pub holding: bool,
    /// p_i with S_ij(p_i) per task.
    pub old: Vec<(TaskId, f64)>,
    /// p_i' and S_i(p_i').
    pub new_path: Vec<TaskId>,
    pub new_score: f64,
    /// The terms of its threshold (4.18).
    pub loyalty: LoyaltyState,
}

impl Proposal {
    pub fn old_score(&self) -> f64 {
        self.old.iter().map(|(_, s)| s).sum()
    }
    fn old_path(&self) -> Vec<TaskId> {
        self.old.iter().map(|(j, _)| *j).collect()
    }
}

/// Why a robot keeps or changes its plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// In its hold period.
    Holding,
    /// The proposal is its current path.
    Unchanged,
    /// (4.22) fails: the gain does not exceed sigma_i.
    Loyal,
    /// (4.22) holds: it adopts p_i'.
    Switches,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub robot: RobotId,
    pub verdict: Verdict,
    /// The path it follows after the decision.
    pub path: Vec<TaskId>,
    pub threshold: Option<Threshold>,
    /// Its utility after the decision: the new score less what it paid, or the old score plus
    /// what it received.
    pub utility: f64,
}

/// The decisions of a merged group, and the compensation paid. `coalitions` are the old
/// coalitions (task -> members) the robots may abandon.
pub fn decide(
    proposals: &[Proposal],
    coalitions: &BTreeMap<TaskId, Vec<RobotId>>,
    params: &LoyaltyParams,
) -> (Vec<Outcome>, Vec<Payment>) {
    let mut outcomes: Vec<Outcome> = proposals
        .iter()
        .map(|p| {
            let old_path = p.old_path();
            let (verdict, th) = if p.holding {
                (Verdict::Holding, None)
            } else if p.new_path == old_path {
                (Verdict::Unchanged, None)
            } else {
                let th = threshold(&p.loyalty, params);
                let v = if switches(p.old_score(), p.new_score, th.sigma) {
                    Verdict::Switches
                } else {
                    Verdict::Loyal
                };
                (v, Some(th))
            };
            let (path, utility) = if verdict == Verdict::Switches {
                (p.new_path.clone(), p.new_score)
            } else {
                (old_path, p.old_score())
            };
            Outcome {
                robot: p.robot,
                verdict,
                path,
                threshold: th,
                utility,
            }
        })
        .collect();
    // Who stays on each old coalition: its members less those who switch away from it.
    let leaves = |m: RobotId, j: TaskId| {
        outcomes
            .iter()
            .any(|o| o.robot == m && o.verdict == Verdict::Switches && !o.path.contains(&j))
    };
    let mut payments = Vec::new();
    for (p, o) in proposals.iter().zip(&outcomes) {
        if o.verdict != Verdict::Switches {
            continue;
        }
        let abandoned: Vec<(TaskId, f64, Vec<RobotId>)> = p
            .old
            .iter()
            .filter(|(j, _)| !o.path.contains(j))
            .map(|&(j, s)| {
                let stay = coalitions
                    .get(&j)
                    .map(|ms| ms.iter().copied().filter(|&m| !leaves(m, j)).collect())
                    .unwrap_or_default();
                (j, s, stay)
            })
            .collect();
        payments.extend(compensation(p.robot, &abandoned, params.compensation_rate));
    }
    for pay in &payments {
        for o in outcomes.iter_mut() {
            if o.robot == pay.from {
                o.utility -= pay.amount;
            }
            if o.robot == pay.to {
                o.utility += pay.amount;
            }
        }
    }
    (outcomes, payments)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loyalty(unexecuted: f64) -> LoyaltyState {
        // Importance 1/3 in every type (three equal members), no travel yet.
        LoyaltyState {
            resources: [1.0; 6],
            coalition_resources: [3.0; 6],
            travelled_time: 0.0,
            gamma: 0.5,
            unexecuted_score: unexecuted,
        }
    }

    #[test]
    fn only_an_uncaptured_coalition_triggers_replanning() {
        assert!(!replans(Encounter::NewTarget));
        assert!(!replans(Encounter::Coalition { captured: true }));
        assert!(replans(Encounter::Coalition { captured: false }));
    }

    #[test]
    fn merged_replan_by_hand() {
        // Old coalition of T2 (index 1): robots 1, 3, 5. Robot 5 is proposed T4 (index 3).
        // sigma_5 = 50 * (1/3) + 0 + 0.1 * 36 = 16.6667 + 3.6 = 20.2667.
        // Robot 5: old 36 on T2, new 60: gain 24 > 20.27 -> switches, pays 36 to robots 1 and 3
        //   (18 each): utility 60 - 36 = 24.
        // Robot 3: old 30 on T2, proposed T4 at 49: gain 19 < sigma_3 = 16.6667 + 0.1 * 30
        //   = 19.6667 -> loyal, keeps T2 (30), receives 18: 48.
        // Robot 1 holds (principle 4): keeps T2 (25), receives 18: 43.
        let proposals = vec![
            Proposal {
                robot: 1,
                holding: true,
                old: vec![(1, 25.0)],
                new_path: vec![3],
                new_score: 90.0,
                loyalty: loyalty(25.0),
            },
            Proposal {
                robot: 3,
                holding: false,
                old: vec![(1, 30.0)],
                new_path: vec![3],
                new_score: 49.0,
                loyalty: loyalty(30.0),
            },
            Proposal {
                robot: 5,
                holding: false,
                old: vec![(1, 36.0)],
                new_path: vec![3],
                new_score: 60.0,
                loyalty: loyalty(36.0),
            },
        ];
        let coalitions: BTreeMap<TaskId, Vec<RobotId>> = [(1, vec![1, 3, 5])].into_iter().collect();
        let (out, pay) = decide(&proposals, &coalitions, &LoyaltyParams::default());
        assert_eq!(
            out.iter().map(|o| o.verdict).collect::<Vec<_>>(),
            vec![Verdict::Holding, Verdict::Loyal, Verdict::Switches]
        );
        assert!((out[1].threshold.as_ref().unwrap().sigma - 19.6667).abs() < 1e-4);
        assert!((out[2].threshold.as_ref().unwrap().sigma - 20.2667).abs() < 1e-4);
        assert_eq!(pay.len(), 2);
        assert!(pay.iter().all(|p| p.from == 5 && p.amount == 18.0));
        assert_eq!(out[0].utility, 43.0);
        assert_eq!(out[1].utility, 48.0);
        assert_eq!(out[1].path, vec![1]);
        assert_eq!(out[2].utility, 24.0);
        assert_eq!(out[2].path, vec![3]);
    }
}
