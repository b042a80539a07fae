//! Example 3-A (thesis sec. 3.3, spec 7.1): the improved auction on Tables 3.1-3.2
//! (`configs/hunt-example-3a.toml`), printed beside the thesis's coalitions, reward iterations
//! (Fig. 3.6) and paid rewards (Table 3.3). Run with `--nocapture` to read the comparison. It
//! asserts only what holds for the algorithm whatever the unprinted parameters: every coalition
//! has L_j members covering E_j, no robot is in two, and no reward reaches its cap.

use crate::hunt::auction::{run_auction, AuctionOutcome};
use crate::hunt::model::{coalition_covers, Robot, Task, TaskId};
use crate::hunt::params::HuntParams;
use crate::hunt::scenario::tests::example_3a;
use std::collections::{BTreeMap, BTreeSet};

/// Phi_1..Phi_4 of Fig. 3.3(b).
const THESIS_INITIAL: [(TaskId, &[u32]); 4] = [
    (1, &[1, 2, 15]),
    (2, &[4, 6, 7]),
    (3, &[8, 13, 9, 12]),
    (4, &[3, 10, 14, 11, 5]),
];
/// Table 3.3: reward actually paid.
const THESIS_PAID: [(TaskId, f64); 5] =
    [(1, 490.0), (2, 580.0), (3, 740.0), (4, 970.0), (5, 1450.0)];

fn ids(v: &[u32]) -> String {
    let mut v = v.to_vec();
    v.sort();
    v.iter()
        .map(|i| format!("R{i}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn report(out: &AuctionOutcome, tasks: &[Task]) -> String {
    let mut s = String::new();
    s += &format!(
        "finish: {:?} after {} rounds (thesis: 12), messages {}\n",
        out.finish,
        out.rounds.len(),
        out.messages
    );
    s += "coalitions (ours | thesis Fig. 3.3(b)):\n";
    for (j, thesis) in THESIS_INITIAL {
        let ours = out
            .coalitions
            .get(&j)
            .map(|c| ids(&c.award.members))
            .unwrap_or("-".into());
        s += &format!("  T{j}: {{{ours}}} | {{{}}}\n", ids(thesis));
    }
    s += "rewards per round (Fig. 3.6):\n  round";
    for t in tasks {
        s += &format!(" {:>8}", format!("T{}", t.id));
    }
    s += "\n";
    for r in &out.rounds {
        s += &format!("  {:>5}", r.round);
        for t in tasks {
            match (r.rewards.get(&t.id), r.bids.get(&t.id)) {
                (Some(z), Some(b)) => s += &format!(" {:>5.1}/{b}", z),
                _ => s += &format!(" {:>8}", "done"),
            }
        }
        s += "\n";
    }
    s += "paid reward per task (ours | Table 3.3 | cap):\n";
    for t in tasks {
        let paid = out
            .coalitions
            .get(&t.id)
            .map(|c| format!("{:.1}", c.award.reward))
            .unwrap_or("-".into());
        let thesis = THESIS_PAID
            .iter()
            .find(|(j, _)| *j == t.id)
            .map(|x| x.1)
            .unwrap_or(f64::NAN);
        s += &format!("  T{}: {paid} | {thesis} | {}\n", t.id, t.reward_cap);
    }
    s += &format!(
        "C (3.13) = {:.1}, Y (3.14) = {:.1}\n",
        out.auctioneer_cost, out.total_utility
    );
    s
}

/// What holds whatever the parameters.
fn check(out: &AuctionOutcome, tasks: &[Task], robots: &[Robot]) {
    let by_id: BTreeMap<u32, &Robot> = robots.iter().map(|r| (r.id, r)).collect();
    let mut used = BTreeSet::new();
    for c in out.coalitions.values() {
        let t = tasks.iter().find(|t| t.id == c.award.task).unwrap();
        assert_eq!(
            c.award.members.len(),
            t.required_robots,
            "T{}: L_j members",
            t.id
        );
        assert!(
            coalition_covers(
                c.award.members.iter().map(|i| &by_id[i].resources),
                &t.resources
            ),
            "T{}: (2.6)",
            t.id
        );
        for i in &c.award.members {
            assert!(used.insert(*i), "R{i} in two coalitions");
        }
        assert!(c.utilities.iter().all(|y| *y > 0.0), "(3.7)");
    }
    for r in &out.rounds {
        for t in tasks {
            if let Some(z) = r.rewards.get(&t.id) {
                assert!(
                    *z < t.reward_cap && *z >= 0.0,
                    "T{} round {}: z = {z} (3.4)",
                    t.id,
                    r.round
                );
            }
        }
    }
}

#[test]
fn example_3a_initial_auction() {
    let h = example_3a();
    let p = HuntParams::default();
    let tasks = h.tasks_at(0.0);
    let robots = h.robots();
    let out = run_auction(&tasks, &robots, &p);
    println!(
        "Example 3-A, initial auction (T1-T4, 15 robots):\n{}",
        report(&out, &tasks)
    );
    check(&out, &tasks, &robots);
}
