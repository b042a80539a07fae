//! Resource-welfare based allocation (Kim, Baik & Lee 2015, the thesis's Ref. 46), as its idea
//! is commonly described: allocate each task to a coalition that covers its resource need while
//! keeping the team's remaining resources "well off", so that scarce types are not spent where
//! an abundant one would do.
//!
//! Assumptions (none of this is in the thesis or the spec):
//! - the team welfare is W = Σ_p ln(1 + R_p), R_p the team's remaining total of type p (concave:
//!   spending a scarce type costs more welfare than spending an abundant one);
//! - centralised, with global information (the paper's team setting); messages: every robot
//!   reports its state once and every member gets an award;
//! - tasks in descending V_a (ties by id);
//! - a coalition is built greedily: among the robots that can append the task (sec. 4.1's
//!   constraints), add the one with the largest coverage gain (baselines::coverage_gain) per
//!   unit of welfare it consumes, ties by arrival time then id, until L_j members; robots that
//!   add nothing to the residual need are skipped; fewer than L_j: the task is shelved;
//! - with `params.enforce_coverage`, a coalition whose carried E_i' do not cover E_j (2.6) is
//!   shelved too (the same test as CBCA's).

use super::super::model::{Resources, Robot, TaskBook, TaskId, RESOURCE_TYPES};
use super::super::params::CbcaParams;
use super::{append_contribution, coverage_gain, eta, reduce, Allocation};

/// W = Σ_p ln(1 + R_p).
pub fn welfare(team: &Resources) -> f64 {
    team.iter().map(|r| (1.0 + r.max(0.0)).ln()).sum()
}

fn add(a: &Resources, b: &Resources) -> Resources {
    std::array::from_fn(|p| a[p] + b[p])
}

fn sub(a: &Resources, b: &Resources) -> Resources {
    std::array::from_fn(|p| a[p] - b[p])
}

pub fn allocate(robots: &[Robot], book: &TaskBook, params: &CbcaParams) -> Allocation {
    let mut alloc = Allocation::empty(robots.len());
    alloc.messages += robots.len() as u64;
    let mut team = robots
        .iter()
        .fold([0.0; RESOURCE_TYPES], |t, r| add(&t, &r.resources));
    let mut order: Vec<TaskId> = book.keys().copied().collect();
    order.sort_by(|a, b| book[b].value.total_cmp(&book[a].value).then(a.cmp(b)));
    for j in order {
        let task = &book[&j];
        let mut need = task.required;
        let mut members = Vec::new();
        let mut spent = [0.0; RESOURCE_TYPES];
        while members.len() < task.robots_needed {
            let mut best: Option<(f64, f64, usize, Resources)> = None;
            for r in robots.iter().filter(|r| !members.contains(&r.id)) {
                let Some(c) = append_contribution(r, &alloc.paths[r.id], j, book, params) else {
                    continue;
                };
                let gain = coverage_gain(&need, &c, &task.required);
                if gain <= 0.0 {
                    continue;
                }
                let left = sub(&team, &spent);
                let ratio = gain / (welfare(&left) - welfare(&sub(&left, &c)) + 1e-9);
                let t = eta(r, &alloc.paths[r.id], j, book);
                let better = best.as_ref().is_none_or(|b| {
                    ratio > b.0 || (ratio == b.0 && (t < b.1 || (t == b.1 && r.id < b.2)))
                });
                if better {
                    best = Some((ratio, t, r.id, c));
                }
            }
            let Some((_, _, i, c)) = best else { break };
            reduce(&mut need, &c);
            spent = add(&spent, &c);
            members.push(i);
        }
        if members.len() == task.robots_needed
            && super::coalition_covers(robots, &members, task, params)
        {
            team = sub(&team, &spent);
            for &i in &members {
                alloc.paths[i].push(j);
            }
            alloc.messages += members.len() as u64;
        }
    }
    alloc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::model::tests::{robot, task};
    use swarm::geometry::Vec2;

    #[test]
    fn the_robot_spending_an_abundant_type_is_preferred() {
        // T1 needs 2 of type 1 only, L 1. Both robots carry 2 of type 1 and cover the need
        // (gain 1); both spend {2, 0, ...} of the same team total, the same welfare: the tie
        // goes to the arrival time, and R2 (1 km) beats R1 (3 km).
        let book: TaskBook = [(0, task(0, [0.0, 0.0], [2.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1))]
            .into_iter()
            .collect();
        let robots = vec![
            robot(0, [3.0, 0.0], [2.0, 5.0, 0.0, 0.0, 0.0, 0.0]),
            robot(1, [1.0, 0.0], [2.0, 0.0, 9.0, 0.0, 0.0, 0.0]),
        ];
        let a = allocate(&robots, &book, &CbcaParams::default());
        assert_eq!(a.paths, vec![vec![], vec![0]]);
        // Scarcity: a task needing 2 of type 2 (team total 5) and 2 of type 3 (team total 9).
        let b: TaskBook = [(0, task(0, [0.0, 0.0], [0.0, 2.0, 2.0, 0.0, 0.0, 0.0], 1))]
            .into_iter()
            .collect();
        // R1 gives {0,2,0,...} (type 2, scarce: ln 6 - ln 4 = 0.4055), gain 0.5;
        // R2 gives {0,0,2,...} (type 3: ln 10 - ln 8 = 0.2231), gain 0.5: R2 wins on the ratio
        // (0.5 / 0.2231 > 0.5 / 0.4055) although R1 is the one listed first. To check that the
        // ratio, not the distance, decides, R1 is put nearer.
        let mut near = robots.clone();
        near[0].position = Vec2::new(0.5, 0.0);
        // (R2 alone carries no type 2: the ratio test runs with (2.6) off.)
        let off = CbcaParams {
            enforce_coverage: false,
            ..CbcaParams::default()
        };
        let a = allocate(&near, &b, &off);
        assert_eq!(a.paths, vec![vec![], vec![0]]);
        // With (2.6) on, neither robot covers {0, 2, 2} alone (L = 1): shelved.
        let a = allocate(&near, &b, &CbcaParams::default());
        assert_eq!(a.paths, vec![Vec::<usize>::new(), vec![]]);
        assert!(
            (welfare(&[0.0, 5.0, 9.0, 0.0, 0.0, 0.0]) - (6.0f64.ln() + 10.0f64.ln())).abs() < 1e-12
        );
    }
}
