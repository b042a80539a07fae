//! Why a robot ends a CBCA run with an empty path (issue 18, Example 1: "which robots stay
//! idle and why"). For every task, Algorithm 1's own verdict on adding it to the robot's
//! empty bundle against the winner lists the robot converged on ([`bundle::evaluate`]), or
//! that the task is not in its book at all (outside its temporary group's prior information,
//! sec. 4.2.2).

use super::bundle::{self, Candidate};
use super::consensus::CbcaRobot;
use super::model::{robot_label, Task, TaskId};

/// One task's verdict for an idle robot.
#[derive(Clone, Debug, PartialEq)]
pub enum IdleReason {
    /// The task is not in the robot's book (its group neither detects nor was given it).
    Unknown,
    /// Algorithm 1's verdict on the task.
    Verdict(Candidate),
}

/// Every task's verdict for robot `r`, in task order.
pub fn why_idle(r: &CbcaRobot, tasks: &[Task]) -> Vec<(TaskId, IdleReason)> {
    tasks
        .iter()
        .map(|t| {
            let reason = if r.book().contains_key(&t.id) {
                IdleReason::Verdict(bundle::evaluate(
                    r.robot(),
                    r.plan(),
                    t.id,
                    r.winners(),
                    r.book(),
                    &r.peers(),
                    r.params(),
                ))
            } else {
                IdleReason::Unknown
            };
            (t.id, reason)
        })
        .collect()
}

/// A short English reading of a verdict, with the equation that decides it; robot ids are the
/// thesis's (R1-based).
pub fn describe(reason: &IdleReason) -> String {
    let c = match reason {
        IdleReason::Unknown => return "not known to its group".into(),
        IdleReason::Verdict(c) => c,
    };
    match c {
        Candidate::InBundle => "in its bundle".into(),
        Candidate::Infeasible(e) => format!("infeasible: {e}"),
        Candidate::Deadlock => "every insertion makes the task graph cyclic (4.6)".into(),
        Candidate::NoGain { bid } => format!("bid {bid:.1} not positive (4.15)"),
        Candidate::Outbid {
            bid,
            weakest,
            weakest_bid,
        } => format!(
            "full: bid {bid:.1} below the weakest winner {}'s {weakest_bid:.1} (4.16)",
            robot_label(*weakest)
        ),
        Candidate::NoSubstitute { bid, weakest } => format!(
            "full: bid {bid:.1} beats {} but carries no type it carries",
            robot_label(*weakest)
        ),
        Candidate::Uncovered { bid, .. } => {
            format!("bid {bid:.1} would leave E_j uncovered (2.6)")
        }
        Candidate::Open { bid, .. } => format!("open with bid {bid:.1}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::compare::run_cbca;
    use crate::cbca::grouping::PriorInfo;
    use crate::cbca::rounds::Radio;
    use crate::cbca::scenario::tests::example;

    /// In Example 1 every idle robot has a reason for every task, and none of them is "open"
    /// (a converged robot with an open task would have bid on it) or "in its bundle".
    #[test]
    fn example1_idle_robots_have_a_closed_reason_for_every_task() {
        let s = example(1);
        let (robots, tasks, params) = (s.robots().unwrap(), s.tasks().unwrap(), s.params.clone());
        let (cbca, stats, _) = run_cbca(
            &robots,
            &tasks,
            PriorInfo::DetectionPlusNearest,
            &Radio::perfect(),
            &params,
        );
        assert!(stats.converged);
        let idle: Vec<&CbcaRobot> = cbca.iter().filter(|r| r.plan().path.is_empty()).collect();
        assert!(!idle.is_empty());
        for r in idle {
            let why = why_idle(r, &tasks);
            assert_eq!(why.len(), tasks.len());
            for (j, reason) in &why {
                let open = matches!(
                    reason,
                    IdleReason::Verdict(Candidate::Open { .. } | Candidate::InBundle)
                );
                assert!(
                    !open,
                    "{} T{}: {}",
                    robot_label(r.id()),
                    j + 1,
                    describe(reason)
                );
            }
        }
    }
}
