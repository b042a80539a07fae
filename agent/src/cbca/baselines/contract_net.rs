//! An improved contract net (Li, Liu & Zhang 2016, the thesis's Ref. 71), as the improvements
//! of that family are commonly described: a manager announces each task, capable contractors
//! bid, and the manager awards the task to several contractors at once.
//!
//! Assumptions (none of this is in the thesis or the spec):
//! - the manager of a task is the robot nearest to it; it announces by one broadcast heard by
//!   every robot (the classic contract net's global radio);
//! - capability pre-screening: only robots that can append the task (sec. 4.1's constraints)
//!   and add to its residual need bid;
//! - a bid is the robot's marginal gain (4.15) for appending the task (the score of 4.13),
//!   divided by 1 + its current number of contracts (load balancing);
//! - the manager awards the L_j best bids (ties by id) whose contributions are useful, taking
//!   them in bid order and skipping a bidder that adds nothing to the residual need left by the
//!   better ones; fewer than L_j: no award (shelved);
//! - tasks announced in descending V_a (ties by id), one round each;
//! - messages: one announcement, one bid per bidder, one award per member.

use super::super::model::{Robot, TaskBook, TaskId};
use super::super::params::CbcaParams;
use super::super::score::path_score;
use super::{append_contribution, coverage_gain, recruit, Allocation};

pub fn allocate(robots: &[Robot], book: &TaskBook, params: &CbcaParams) -> Allocation {
    let mut alloc = Allocation::empty(robots.len());
    let mut order: Vec<TaskId> = book.keys().copied().collect();
    order.sort_by(|a, b| book[b].value.total_cmp(&book[a].value).then(a.cmp(b)));
    for j in order {
        let task = &book[&j];
        alloc.messages += 1;
        let mut bids: Vec<(f64, usize)> = Vec::new();
        for r in robots {
            let path = &alloc.paths[r.id];
            let Some(c) = append_contribution(r, path, j, book, params) else {
                continue;
            };
            if coverage_gain(&task.required, &c, &task.required) <= 0.0 {
                continue;
            }
            let mut longer = path.clone();
            longer.push(j);
            let gain = path_score(r, &longer, book, params).total
                - path_score(r, path, book, params).total;
            if gain <= 0.0 {
                continue;
            }
            bids.push((gain / (1.0 + path.len() as f64), r.id));
        }
        alloc.messages += bids.len() as u64;
        bids.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        recruit(
            &mut alloc,
            robots,
            book,
            params,
            j,
            bids.into_iter().map(|(_, i)| i),
        );
    }
    alloc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::model::tests::{robot, task};

    #[test]
    fn best_bids_win_and_load_is_balanced() {
        // T1 (V_a 100) at (0, 0), T2 (V_a 90) at (0, 0.5), both L 1, beta 0.5, hold 1.
        // R1 at (0, 1), R2 at (0, 3), gamma 0.5, speed 1.
        // T1 first: R1 bids 100 e^-0.5 - 0.5 = 60.1531, R2 100 e^-1.5 - 1.5 = 20.8130: R1.
        // T2: R1 appends (T1 at t 1, hold to 2, then 0.5 km: t 2.5): 90 e^-1.25 - 0.25 = 25.5355,
        //   halved for its one contract: 12.7678; R2 alone: 90 e^-1.25 - 1.25 = 24.5355: R2.
        let mut t1 = task(0, [0.0, 0.0], [1.0; 6], 1);
        let mut t2 = task(1, [0.0, 0.5], [1.0; 6], 1);
        t1.value = 100.0;
        t2.value = 90.0;
        let book: TaskBook = [(0, t1), (1, t2)].into_iter().collect();
        let robots = vec![
            robot(0, [0.0, 1.0], [5.0; 6]),
            robot(1, [0.0, 3.0], [5.0; 6]),
        ];
        let a = allocate(&robots, &book, &CbcaParams::default());
        assert_eq!(a.paths, vec![vec![0], vec![1]]);
        // Two announcements, two bids each, two awards.
        assert_eq!(a.messages, 2 + 4 + 2);
    }
}
