//! The thesis's re-planning of Example 2 (sec. 4.3, Figs. 4.4(d) and 4.5; spec 8.2) as data,
//! and a run's side-by-side comparison with it: for every event the narrative gives, what the
//! run did and why, computed from the run's (4.22) tests, payments and captures
//! (`MovingRun`), not typed in.
//!
//! The narrative's events: R9 T3 -> T5 and R15 T1 -> T3 (utilities 204.39 and 104.53 on the
//! new targets against 110.56 and 36.32 on the old), T1 shelved ("no coalition satisfies T1's
//! resources"), R6 T2 -> T4 with compensation to R2 and R4, R10 left with nothing (utility 0).

use super::loyalty::Payment;
use super::model::{robot_label as r, task_label as t, RobotId, TaskId};
use super::moving_rounds::{Decision, MovingRun};
use super::replan::Verdict;

/// One switch of the narrative: robot, old task, new task, and the utilities it prints
/// (new, old) where it prints them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThesisSwitch {
    pub robot: RobotId,
    pub from: TaskId,
    pub to: TaskId,
    pub printed: Option<(f64, f64)>,
}

/// The narrative's switches (0-based ids): R9 T3 -> T5, R15 T1 -> T3, R6 T2 -> T4.
pub const THESIS_SWITCHES: [ThesisSwitch; 3] = [
    ThesisSwitch {
        robot: 8,
        from: 2,
        to: 4,
        printed: Some((204.39, 110.56)),
    },
    ThesisSwitch {
        robot: 14,
        from: 0,
        to: 2,
        printed: Some((104.53, 36.32)),
    },
    ThesisSwitch {
        robot: 5,
        from: 1,
        to: 3,
        printed: None,
    },
];

/// R6 compensates R2 and R4 (Fig. 4.5's narrative).
pub const THESIS_COMPENSATION: (RobotId, [RobotId; 2]) = (5, [1, 3]);

/// T1 shelved after R15 leaves.
pub const THESIS_SHELVED: TaskId = 0;

/// R10 left with nothing, its utility to 0.
pub const THESIS_LEFT_WITH_NOTHING: RobotId = 9;

/// One row of the side-by-side table.
#[derive(Clone, Debug, PartialEq)]
pub struct SideBySide {
    pub thesis: String,
    pub ours: String,
    pub reason: String,
}

/// `[T1 T5]`, `[]` for no task.
pub fn path_names(p: &[TaskId]) -> String {
    let v: Vec<String> = p.iter().map(|&j| t(j)).collect();
    format!("[{}]", v.join(" "))
}

/// `{R1, R5}`.
pub fn robot_set(v: &[RobotId]) -> String {
    let v: Vec<String> = v.iter().map(|&i| r(i)).collect();
    format!("{{{}}}", v.join(", "))
}

/// A decision's table cells `R1 | [T1] (16.87) | [T5] (67.91)`: robot, old path (S),
/// proposed path (S').
pub fn decision_cells(d: &Decision) -> String {
    format!(
        "{} | {} ({:.2}) | {} ({:.2})",
        r(d.robot),
        path_names(&d.old_path),
        d.old_score,
        path_names(&d.proposed),
        d.new_score
    )
}

/// The (4.22) test of a decision in words: "gain 18.14 < sigma 25.25".
pub fn test_words(d: &Decision) -> String {
    let gain = d.new_score - d.old_score;
    match (d.verdict, d.sigma) {
        (Verdict::Switches, Some(s)) => format!("gain {gain:.2} > sigma {s:.2}"),
        (Verdict::Loyal, Some(s)) => format!("gain {gain:.2} <= sigma {s:.2}"),
        (Verdict::Unchanged, _) => "proposal = old path, no test".into(),
        (Verdict::Holding, _) => "holding (principle 4), no test".into(),
        (v, None) => format!("{v:?}"),
    }
}

/// Every decision of robot `i` in the run, with its re-planning time.
fn decisions_of(run: &MovingRun, i: RobotId) -> Vec<(f64, &Decision)> {
    run.replannings
        .iter()
        .flat_map(|rp| rp.decisions.iter().map(move |d| (rp.time, d)))
        .filter(|(_, d)| d.robot == i)
        .collect()
}

/// Re-plannings at which robot `i` was holding (left out).
fn holding_times(run: &MovingRun, i: RobotId) -> Vec<f64> {
    run.replannings
        .iter()
        .filter(|rp| rp.holding.contains(&i))
        .map(|rp| rp.time)
        .collect()
}

fn switch_row(run: &MovingRun, s: &ThesisSwitch) -> SideBySide {
    let thesis = match s.printed {
        Some((new, old)) => format!(
            "{} {} -> {} ({new:.2} against {old:.2})",
            r(s.robot),
            t(s.from),
            t(s.to)
        ),
        None => format!("{} {} -> {}", r(s.robot), t(s.from), t(s.to)),
    };
    let ds = decisions_of(run, s.robot);
    if ds.is_empty() {
        let held = holding_times(run, s.robot);
        let reason = if held.is_empty() {
            format!("no re-planning included {}", r(s.robot))
        } else {
            format!(
                "holding (principle 4) at every re-planning it met (t = {})",
                held.iter()
                    .map(|x| format!("{x:.2}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        return SideBySide {
            thesis,
            ours: format!(
                "{} {} throughout",
                r(s.robot),
                path_names(&run.initial_paths[s.robot])
            ),
            reason,
        };
    }
    let mut ours = Vec::new();
    let mut reasons = Vec::new();
    for (time, d) in ds {
        ours.push(format!(
            "t {time:.2}: {} {} -> {}",
            r(s.robot),
            path_names(&d.old_path),
            path_names(&d.final_path)
        ));
        let proposed = d.proposed.contains(&s.to);
        let mut why = if proposed {
            let what = match d.verdict {
                Verdict::Switches => "reproduced",
                Verdict::Loyal => "refused by (4.22)",
                _ => "no test",
            };
            format!(
                "{what}: proposed {} (S' {:.2} against S {:.2}), {}",
                path_names(&d.proposed),
                d.new_score,
                d.old_score,
                test_words(d)
            )
        } else {
            let tail = match d.verdict {
                Verdict::Switches => format!(", taken: {}", test_words(d)),
                Verdict::Loyal => format!(", refused by (4.22): {}", test_words(d)),
                _ => format!(" ({})", test_words(d)),
            };
            format!(
                "{} never proposed: the fresh CBCA proposed {} (S' {:.2}, S {:.2}){tail}",
                t(s.to),
                path_names(&d.proposed),
                d.new_score,
                d.old_score
            )
        };
        if d.final_path.contains(&s.to) && !(proposed && d.verdict == Verdict::Switches) {
            why.push_str(&format!("; the consistency pass gave it {}", t(s.to)));
        }
        reasons.push(why);
    }
    SideBySide {
        thesis,
        ours: ours.join("; "),
        reason: reasons.join("; "),
    }
}

/// Every compensation payment of the run with its re-planning time, in order.
pub fn payments(run: &MovingRun) -> impl Iterator<Item = (f64, &Payment)> {
    run.replannings
        .iter()
        .flat_map(|rp| rp.payments.iter().map(move |p| (rp.time, p)))
}

fn compensation_row(run: &MovingRun) -> SideBySide {
    let (payer, to) = THESIS_COMPENSATION;
    let thesis = format!("{} pays {} and {}", r(payer), r(to[0]), r(to[1]));
    let all: Vec<String> = payments(run)
        .map(|(time, p)| {
            format!(
                "t {time:.2}: {} -> {} {:.2} for {}",
                r(p.from),
                r(p.to),
                p.amount,
                t(p.task)
            )
        })
        .collect();
    let ours = if all.is_empty() {
        "no compensation paid".to_string()
    } else {
        all.join("; ")
    };
    let paid: Vec<RobotId> = payments(run)
        .map(|(_, p)| p)
        .filter(|p| p.from == payer)
        .map(|p| p.to)
        .collect();
    let reason = if paid.is_empty() {
        let switched = decisions_of(run, payer)
            .iter()
            .any(|(_, d)| d.verdict == Verdict::Switches && !d.old_path.is_empty());
        if switched {
            format!("{} switched but nobody stayed on what it left", r(payer))
        } else {
            format!("{} paid nothing: it did not switch (row above)", r(payer))
        }
    } else {
        format!("{} paid {}", r(payer), robot_set(&paid))
    };
    SideBySide {
        thesis,
        ours,
        reason,
    }
}

fn shelved_row(run: &MovingRun) -> SideBySide {
    let j = THESIS_SHELVED;
    let thesis = format!(
        "{} shelved ({} left it, no coalition covers it)",
        t(j),
        r(THESIS_SWITCHES[1].robot)
    );
    match run.captures.iter().find(|c| c.task == j) {
        Some(c) => SideBySide {
            thesis,
            ours: format!(
                "{} captured at {:.2} by {}",
                t(j),
                c.time,
                robot_set(&c.members)
            ),
            reason: {
                let leaver = THESIS_SWITCHES[1].robot;
                if c.members.contains(&leaver) {
                    format!(
                        "{} is in {}'s coalition at the capture (row above): the coalition was full",
                        r(leaver),
                        t(j)
                    )
                } else {
                    format!("{} left, others completed the coalition", r(leaver))
                }
            },
        },
        None => SideBySide {
            thesis,
            ours: format!("{} not captured", t(j)),
            reason: "shelved: its coalition short of members at the end".into(),
        },
    }
}

/// Robots that had a task before a re-planning and none after it.
pub fn left_with_nothing(run: &MovingRun) -> Vec<(f64, RobotId)> {
    run.replannings
        .iter()
        .flat_map(|rp| rp.decisions.iter().map(move |d| (rp.time, d)))
        .filter(|(_, d)| !d.old_path.is_empty() && d.final_path.is_empty())
        .map(|(time, d)| (time, d.robot))
        .collect()
}

fn nothing_row(run: &MovingRun) -> SideBySide {
    let i = THESIS_LEFT_WITH_NOTHING;
    let thesis = format!("{} left with nothing (utility to 0)", r(i));
    let left = left_with_nothing(run);
    let ours = if left.is_empty() {
        "nobody".to_string()
    } else {
        left.iter()
            .map(|(time, k)| format!("{} at t {time:.2}", r(*k)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mine: Vec<String> = decisions_of(run, i)
        .iter()
        .map(|(time, d)| {
            format!(
                "{} at t {time:.2}: {} -> {} ({})",
                r(i),
                path_names(&d.old_path),
                path_names(&d.final_path),
                test_words(d)
            )
        })
        .collect();
    let reason = if mine.is_empty() {
        format!("{} took part in no re-planning", r(i))
    } else {
        mine.join("; ")
    };
    SideBySide {
        thesis,
        ours,
        reason,
    }
}

/// The side-by-side table: the narrative's switches, its compensation, T1 shelved, R10 left
/// with nothing; each with what the run did and the reason from the run.
pub fn side_by_side(run: &MovingRun) -> Vec<SideBySide> {
    let mut rows: Vec<SideBySide> = THESIS_SWITCHES.iter().map(|s| switch_row(run, s)).collect();
    rows.push(compensation_row(run));
    rows.push(shelved_row(run));
    rows.push(nothing_row(run));
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::moving_rounds::{run_moving_from, MovingParams};
    use crate::cbca::narrative::thesis_start;
    use crate::cbca::scenario::tests::example;

    /// Example 2 from the thesis's start at 2.0 km: each switch row's reason follows the
    /// robot's own (4.22) test (reproduced only if it was proposed the thesis's target and
    /// switched; "never proposed" when the fresh CBCA did not propose it), and the
    /// compensation row names every payment of the run.
    #[test]
    fn the_side_by_side_rows_follow_the_runs_decisions() {
        let s = example(2);
        let (robots, tasks) = (s.robots().unwrap(), s.tasks().unwrap());
        let mp = MovingParams {
            radius_km: 2.0,
            ..MovingParams::default()
        };
        let run = run_moving_from(&robots, &tasks, &s.params, &mp, &thesis_start(robots.len()));
        let rows = side_by_side(&run);
        assert_eq!(rows.len(), THESIS_SWITCHES.len() + 3);
        for (sw, row) in THESIS_SWITCHES.iter().zip(&rows) {
            let ds = decisions_of(&run, sw.robot);
            assert!(!ds.is_empty(), "R{} re-plans at the meeting", sw.robot + 1);
            let (_, d) = ds[0];
            let proposed = d.proposed.contains(&sw.to);
            assert_eq!(
                row.reason.starts_with("reproduced"),
                proposed && d.verdict == Verdict::Switches,
                "{row:?}"
            );
            assert_eq!(row.reason.contains("never proposed"), !proposed, "{row:?}");
            if d.verdict == Verdict::Loyal {
                assert!(row
                    .reason
                    .contains(&format!("sigma {:.2}", d.sigma.unwrap())));
            }
        }
        let comp = &rows[THESIS_SWITCHES.len()];
        let n = payments(&run).count();
        assert!(n > 0);
        assert_eq!(comp.ours.matches(" -> ").count(), n, "{comp:?}");
    }
}
